//! `[[contact]]` and `[[rigid_wall]]`: contacts between bodies and rigid walls (README, "Scene
//! format", `[[contact]]` and `[[rigid_wall]]`): the raw tables, [`Contact`], [`RigidWall`], the
//! enforcement ([`ContactMethod`], [`PenaltyForm`], the penalty springs and friction) with its
//! defaults, contact names, and their validation. The contact itself is in [`crate::contact`]
//! (CPU reference) and `shaders/contact_*.wgsl` (GPU). Host-side only.

use serde::Deserialize;

use super::body::Body;
use super::fixed;
use super::validate::{fmt_num, shown_name, Validator};
use crate::error::Result;

/// Longest contact or rigid-wall name (characters): it heads four `history.csv` columns.
pub const CONTACT_NAME_MAX: usize = 256;

/// A `[[contact]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawContact {
    bodies: RawBodies,
    name: Option<String>,
    method: Option<String>,
    two_pass: Option<bool>,
    self_contact: Option<bool>,
    penalty_scale: Option<f64>,
    penalty_stiffness: Option<String>,
    #[serde(default, deserialize_with = "fixed::groups")]
    surfaces: Option<Vec<String>>,
    friction: Option<f64>,
    friction_stiffness: Option<f64>,
    augmentation_rate: Option<f64>,
}

/// The enforcement keys of a raw `[[contact]]` or `[[rigid_wall]]` table `$t` (the two spell
/// them alike) as [`RawSprings`].
macro_rules! raw_springs {
    ($t:expr) => {
        RawSprings {
            method: $t.method.as_deref(),
            form: $t.penalty_stiffness.as_deref(),
            scale: $t.penalty_scale,
            friction: $t.friction,
            friction_stiffness: $t.friction_stiffness,
            augmentation_rate: $t.augmentation_rate,
        }
    };
}

/// The enforcement keys of a `[[contact]]` or `[[rigid_wall]]` as written: the method, the
/// penalty and the friction.
struct RawSprings<'a> {
    method: Option<&'a str>,
    form: Option<&'a str>,
    scale: Option<f64>,
    friction: Option<f64>,
    friction_stiffness: Option<f64>,
    augmentation_rate: Option<f64>,
}

/// The enforcement of a contact or wall, checked, with its defaults.
struct Springs {
    method: ContactMethod,
    form: PenaltyForm,
    scale: f64,
    friction: f64,
    friction_stiffness: f64,
    augmentation_rate: f64,
}

/// `bodies` of a `[[contact]]`: the string "all" or a list of names.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawBodies {
    Word(String),
    List(Vec<String>),
}

/// A `[[rigid_wall]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWall {
    #[serde(deserialize_with = "fixed::array")]
    point: [f64; 2],
    #[serde(deserialize_with = "fixed::array")]
    normal: [f64; 2],
    name: Option<String>,
    bodies: Option<Vec<String>>,
    method: Option<String>,
    penalty_scale: Option<f64>,
    penalty_stiffness: Option<String>,
    friction: Option<f64>,
    friction_stiffness: Option<f64>,
    augmentation_rate: Option<f64>,
}

/// How a contact constraint is enforced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ContactMethod {
    /// Lagrange multipliers with the diagonal mass: the gap is closed exactly in the step
    /// (perfectly plastic impact of the contacting nodes, momentum conserved).
    Lagrange,
    /// Penalty springs p = k g, bounded by the perfectly plastic impulse; they shorten the stable step.
    Penalty,
    /// Perturbed Lagrangian (Belytschko X.5.8): multipliers interpolated along the slave
    /// surface with H = (1/beta) int Lambda^T Lambda (Eq. X.5.44), eliminated as in Eq. X.5.45:
    /// the penalty distributed by the consistent H, each node's force the consistent nodal force
    /// beta int N_I g of the penetration field, instead of k g node by node.
    PerturbedLagrange,
    /// Augmented Lagrangian (Belytschko X.5.7): the penalty spring plus a multiplier per contact
    /// node, carried from step to step and augmented by the spring's force (Uzawa's update
    /// lambda <- lambda + k g, at the rate `augmentation_rate`), so that a persistent contact
    /// ends with no penetration while the stable step is the (soft) spring's.
    AugmentedLagrange,
}

impl ContactMethod {
    /// Whether the method acts through penalty springs (penalty, perturbed and augmented
    /// Lagrangian): the penalty keys apply, and the springs count in the stable step.
    pub fn has_springs(self) -> bool {
        matches!(
            self,
            ContactMethod::Penalty
                | ContactMethod::PerturbedLagrange
                | ContactMethod::AugmentedLagrange
        )
    }

    /// The word of the scene's `method` key.
    pub fn word(self) -> &'static str {
        match self {
            ContactMethod::Lagrange => "lagrange",
            ContactMethod::Penalty => "penalty",
            ContactMethod::PerturbedLagrange => "perturbed_lagrange",
            ContactMethod::AugmentedLagrange => "augmented_lagrange",
        }
    }
}

/// How a penalty spring's stiffness is derived (`penalty_stiffness`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum PenaltyForm {
    /// From the modulus: k = s K t L^2 / A per master segment (K the 2D bulk modulus, t the
    /// thickness, L the segment, A its element's area); the springs shorten the stable step.
    Modulus,
    /// From the mass and the step: k = s m* / dt^2 (m* the reduced mass of the pair, dt the run's
    /// step at t = 0), so that omega dt = sqrt(s) whatever the mesh and material; the stable step
    /// is not reduced.
    Mass,
}

impl PenaltyForm {
    /// The word of the scene key.
    pub fn word(self) -> &'static str {
        match self {
            PenaltyForm::Modulus => "modulus",
            PenaltyForm::Mass => "mass",
        }
    }
}

/// Default form of the penalty stiffness.
pub const DEFAULT_PENALTY_FORM: PenaltyForm = PenaltyForm::Modulus;

/// Default penalty scale `s` of the modulus form, k = s K t L^2 / A.
pub const DEFAULT_PENALTY_SCALE: f64 = 2.0;

/// Default `augmentation_rate` of the augmented Lagrangian as a fraction of `run.mass_damping`
/// alpha: half the stability limit r < alpha (see [`ContactMethod::AugmentedLagrange`]).
pub const DEFAULT_AUGMENTATION: f64 = 0.5;

/// Default penalty scale `s` of the mass form, k = s m* / dt^2.
pub const DEFAULT_MASS_PENALTY_SCALE: f64 = 0.1;

/// Node-to-segment contact: a pair of bodies, or a group (every pair among its bodies, and each
/// body against itself with self-contact).
#[derive(Debug, Clone)]
pub struct Contact {
    /// Name used in history columns (`<a>-<b>` for a pair, `all` or the names joined by `+` for
    /// a group, unless given).
    pub name: String,
    /// A pair: the first body (slave nodes of the first pass) and the second (its master
    /// segments). A group: its bodies, ascending.
    pub bodies: Vec<usize>,
    /// A group: one symmetric pass over all its bodies' surfaces (every unordered pair in both
    /// directions, the history's force the sum over the pairs of the force on the lower-indexed
    /// body). Otherwise a pair as above.
    pub group: bool,
    /// A group whose bodies also contact their own surfaces.
    pub self_contact: bool,
    /// Enforcement.
    pub method: ContactMethod,
    /// Also the reverse pass (second body's nodes against the first body's segments); always
    /// true for a group (it is symmetric).
    pub two_pass: bool,
    /// Penalty scale `s` (penalty only).
    pub penalty_scale: f64,
    /// Form of the penalty stiffness (penalty only).
    pub penalty_form: PenaltyForm,
    /// Tangential (friction) spring stiffness of penalty friction over the normal one
    /// (`friction_stiffness`, default 1).
    pub friction_stiffness: f64,
    /// A pair limited to named faces (`surfaces = ["a", "b"]`): per body, the name of the
    /// physical curve of its Gmsh file and its line elements as pairs of body node indices;
    /// only the boundary segments among them (and their nodes) take part. `None`: the whole
    /// boundary of each body.
    pub surfaces: Option<Vec<(String, Vec<[u32; 2]>)>>,
    /// Coulomb friction coefficient mu (0: frictionless).
    pub friction: f64,
    /// Augmented Lagrangian: the rate r (1/s) of the multipliers' update, lambda <- lambda +
    /// r dt k (-g) each step (`augmentation_rate`, default half of `run.mass_damping`; below it,
    /// see [`DEFAULT_AUGMENTATION`]); 0 for the other methods.
    pub augmentation_rate: f64,
}

/// A fixed planar rigid wall.
#[derive(Debug, Clone)]
pub struct RigidWall {
    /// Name used in history columns.
    pub name: String,
    /// A point of the wall.
    pub point: [f64; 2],
    /// Unit normal pointing to the side the bodies stay on.
    pub normal: [f64; 2],
    /// Bodies the wall acts on.
    pub bodies: Vec<usize>,
    /// Enforcement.
    pub method: ContactMethod,
    /// Penalty scale `s` (penalty only).
    pub penalty_scale: f64,
    /// Form of the penalty stiffness (penalty only).
    pub penalty_form: PenaltyForm,
    /// Tangential (friction) spring stiffness of penalty friction over the normal one
    /// (`friction_stiffness`, default 1).
    pub friction_stiffness: f64,
    /// Coulomb friction coefficient mu (0: frictionless).
    pub friction: f64,
    /// Augmented Lagrangian: the rate r (1/s) of the multipliers' update, lambda <- lambda +
    /// r dt k (-g) each step (`augmentation_rate`, default half of `run.mass_damping`; below it,
    /// see [`DEFAULT_AUGMENTATION`]); 0 for the other methods.
    pub augmentation_rate: f64,
}

/// `name`, or, when another contact or wall has it already, `name` with the first free suffix
/// `_2`, `_3`, ... (default names only: a name given in the scene must be unique).
fn free_name(name: &str, contacts: &[Contact], walls: &[RigidWall]) -> String {
    let taken = |n: &str| contacts.iter().any(|c| c.name == n) || walls.iter().any(|w| w.name == n);
    if !taken(name) {
        return name.to_string();
    }
    (2..)
        .map(|k| format!("{name}_{k}"))
        .find(|n| !taken(n))
        .unwrap_or_else(|| name.to_string())
}

impl Validator<'_> {
    /// The `[[contact]]` tables, in order; names must differ.
    pub(super) fn contacts(
        &self,
        raw: &[RawContact],
        bodies: &[Body],
        mass_damping: f64,
    ) -> Result<Vec<Contact>> {
        let mut contacts: Vec<Contact> = Vec::new();
        for (i, c) in raw.iter().enumerate() {
            let key = format!("contact[{i}]");
            // Two contacts with one default name are the same contact given twice: refused.
            let c = self.contact(&key, c, bodies, mass_damping)?;
            self.unique_name(&key, &c.name, &contacts, &[])?;
            contacts.push(c);
        }
        Ok(contacts)
    }

    /// The `[[rigid_wall]]` tables, in order; names must differ from each other and from the
    /// `contacts`' (a default name is suffixed instead).
    pub(super) fn walls(
        &self,
        raw: &[RawWall],
        bodies: &[Body],
        contacts: &[Contact],
        mass_damping: f64,
    ) -> Result<Vec<RigidWall>> {
        let mut walls: Vec<RigidWall> = Vec::new();
        for (i, w) in raw.iter().enumerate() {
            let key = format!("rigid_wall[{i}]");
            // A wall's default name (its bodies joined by `-`) may be a contact's: suffixed.
            let named = w.name.is_some();
            let mut w = self.wall(&key, w, bodies, mass_damping)?;
            if !named {
                w.name = free_name(&w.name, contacts, &walls);
            }
            self.unique_name(&key, &w.name, contacts, &walls)?;
            walls.push(w);
        }
        Ok(walls)
    }

    fn unique_name(
        &self,
        key: &str,
        name: &str,
        contacts: &[Contact],
        walls: &[RigidWall],
    ) -> Result<()> {
        let taken = contacts.iter().any(|c| c.name == name) || walls.iter().any(|w| w.name == name);
        if taken {
            return Err(self.invalid(
                format!("{key}.name"),
                format!("{name:?}"),
                "another contact or rigid wall has this name (give each a distinct `name`)",
            ));
        }
        if name.is_empty() || name.contains([',', '"']) || name.chars().any(char::is_control) {
            return Err(self.invalid(
                format!("{key}.name"),
                shown_name(name),
                &format!(
                    "must be 1 to {CONTACT_NAME_MAX} characters, without commas, quotes or \
                     control characters (it names history columns)"
                ),
            ));
        }
        Ok(())
    }

    /// A `name` given to a contact or wall (default names, made of body names, may be longer).
    fn given_name_length(&self, key: &str, name: Option<&String>) -> Result<()> {
        if let Some(name) = name.filter(|n| n.chars().count() > CONTACT_NAME_MAX) {
            return Err(self.invalid(
                format!("{key}.name"),
                shown_name(name),
                &format!(
                    "must be 1 to {CONTACT_NAME_MAX} characters, without commas, quotes or \
                     control characters (it names history columns); this one has {}",
                    name.chars().count()
                ),
            ));
        }
        Ok(())
    }

    /// The enforcement keys of contact or wall `key`: the method, then the penalty and friction
    /// keys that go with it.
    fn springs(&self, key: &str, raw: RawSprings, mass_damping: f64) -> Result<Springs> {
        let method = self.keyword(
            &format!("{key}.method"),
            raw.method,
            &[
                ("lagrange", ContactMethod::Lagrange),
                ("penalty", ContactMethod::Penalty),
                ("perturbed_lagrange", ContactMethod::PerturbedLagrange),
                ("augmented_lagrange", ContactMethod::AugmentedLagrange),
            ],
            "expected \"lagrange\", \"penalty\", \"perturbed_lagrange\" or \
             \"augmented_lagrange\"",
        )?;
        let form = self.penalty_form(&format!("{key}.penalty_stiffness"), raw.form, method)?;
        let scale = self.penalty_scale(&format!("{key}.penalty_scale"), raw.scale, method, form)?;
        let friction = self.friction(&format!("{key}.friction"), raw.friction, method)?;
        let friction_stiffness = self.friction_stiffness(
            &format!("{key}.friction_stiffness"),
            raw.friction_stiffness,
            method,
            friction,
        )?;
        let augmentation_rate =
            self.augmentation_rate(key, raw.augmentation_rate, method, mass_damping)?;
        Ok(Springs {
            method,
            form,
            scale,
            friction,
            friction_stiffness,
            augmentation_rate,
        })
    }

    /// `augmentation_rate` of an augmented Lagrangian contact or wall `key`: in (0,
    /// run.mass_damping), default [`DEFAULT_AUGMENTATION`] times it. The update
    /// lambda' = r k (-g) integrates the penetration: on a body m x'' + alpha m x' + k x + lambda
    /// = 0 it is stable only while r < alpha (Routh-Hurwitz on m s^3 + alpha m s^2 + k s + r k);
    /// without mass damping its oscillations grow at r / 2.
    fn augmentation_rate(
        &self,
        key: &str,
        r: Option<f64>,
        method: ContactMethod,
        mass_damping: f64,
    ) -> Result<f64> {
        if method != ContactMethod::AugmentedLagrange {
            return match r {
                None => Ok(0.0),
                Some(x) => Err(self.invalid(
                    format!("{key}.augmentation_rate"),
                    fmt_num(x),
                    "applies to method = \"augmented_lagrange\" only",
                )),
            };
        }
        if mass_damping <= 0.0 {
            return Err(self.invalid(
                format!("{key}.method"),
                "\"augmented_lagrange\"",
                "needs run.mass_damping > 0: the multipliers' update integrates the \
                 penetration, which is stable only under mass damping (augmentation_rate < \
                 run.mass_damping)",
            ));
        }
        match r {
            None => Ok(DEFAULT_AUGMENTATION * mass_damping),
            Some(x) => {
                let x = self.positive(&format!("{key}.augmentation_rate"), x)?;
                if x >= mass_damping {
                    return Err(self.invalid(
                        format!("{key}.augmentation_rate"),
                        fmt_num(x),
                        &format!(
                            "must be below run.mass_damping = {}: the multipliers' update is \
                             unstable at or above it",
                            fmt_num(mass_damping)
                        ),
                    ));
                }
                Ok(x)
            }
        }
    }

    /// The form of the penalty stiffness (`penalty_stiffness`), penalty only.
    fn penalty_form(
        &self,
        key: &str,
        form: Option<&str>,
        method: ContactMethod,
    ) -> Result<PenaltyForm> {
        if form.is_none() {
            return Ok(DEFAULT_PENALTY_FORM);
        }
        let f = self.keyword(
            key,
            form,
            &[
                ("modulus", PenaltyForm::Modulus),
                ("mass", PenaltyForm::Mass),
            ],
            "expected \"modulus\" (k = s K t L^2 / A) or \"mass\" (k = s m* / dt^2)",
        )?;
        if !method.has_springs() {
            return Err(self.invalid(
                key,
                format!("{:?}", f.word()),
                "applies to the spring methods only (\"penalty\", \"perturbed_lagrange\", \"augmented_lagrange\")",
            ));
        }
        Ok(f)
    }

    /// `friction_stiffness`: the tangential spring over the normal one, penalty with friction only.
    fn friction_stiffness(
        &self,
        key: &str,
        r: Option<f64>,
        method: ContactMethod,
        mu: f64,
    ) -> Result<f64> {
        match r {
            None => Ok(1.0),
            Some(x) if method != ContactMethod::Penalty || mu == 0.0 => Err(self.invalid(
                key,
                fmt_num(x),
                "applies to method = \"penalty\" with friction > 0 only (the tangential spring \
                 of penalty friction, as a multiple of the normal one)",
            )),
            Some(x) => self.positive(key, x),
        }
    }

    fn penalty_scale(
        &self,
        key: &str,
        s: Option<f64>,
        method: ContactMethod,
        form: PenaltyForm,
    ) -> Result<f64> {
        match s {
            None if form == PenaltyForm::Mass => Ok(DEFAULT_MASS_PENALTY_SCALE),
            None => Ok(DEFAULT_PENALTY_SCALE),
            Some(_) if !method.has_springs() => Err(self.invalid(
                key,
                format!("{:?}", s.unwrap_or_default()),
                "applies to the spring methods only (\"penalty\", \"perturbed_lagrange\", \"augmented_lagrange\")",
            )),
            Some(x) => self.positive(key, x),
        }
    }

    /// The Coulomb coefficient `friction` of a contact or wall: finite and >= 0, and with a
    /// method that carries it (not the perturbed Lagrangian, whose multipliers are normal only).
    fn friction(&self, key: &str, mu: Option<f64>, method: ContactMethod) -> Result<f64> {
        let mu = mu.map_or(Ok(0.0), |mu| self.non_negative(key, mu))?;
        if mu > 0.0
            && matches!(
                method,
                ContactMethod::PerturbedLagrange | ContactMethod::AugmentedLagrange
            )
        {
            return Err(self.invalid(
                key,
                fmt_num(mu),
                &format!(
                    "friction needs method = \"lagrange\" or \"penalty\": the {} carries \
                     normal multipliers only",
                    if method == ContactMethod::PerturbedLagrange {
                        "perturbed Lagrangian"
                    } else {
                        "augmented Lagrangian"
                    }
                ),
            ));
        }
        Ok(mu)
    }

    fn contact(
        &self,
        key: &str,
        c: &RawContact,
        bodies: &[Body],
        mass_damping: f64,
    ) -> Result<Contact> {
        let bkey = format!("{key}.bodies");
        let self_contact = c.self_contact.unwrap_or(false);
        let (list, all) = match &c.bodies {
            RawBodies::Word(w) if w == "all" => ((0..bodies.len()).collect::<Vec<_>>(), true),
            RawBodies::Word(w) => {
                return Err(self.invalid(
                    bkey,
                    format!("{w:?}"),
                    "expected \"all\" or a list of body names",
                ))
            }
            RawBodies::List(names) => {
                let mut list = Vec::new();
                for n in names {
                    let i = self.body_index(&bkey, n, bodies)?;
                    if list.contains(&i) {
                        return Err(self.invalid(
                            bkey,
                            format!("{names:?}"),
                            &format!("body {n:?} is named twice: the bodies must differ"),
                        ));
                    }
                    list.push(i);
                }
                (list, false)
            }
        };
        let shown = match &c.bodies {
            RawBodies::Word(w) => format!("{w:?}"),
            RawBodies::List(names) => format!("{names:?}"),
        };
        if list.is_empty() {
            return Err(self.invalid(bkey, shown, "name at least one body"));
        }
        if list.len() == 1 && !self_contact {
            return Err(self.invalid(
                bkey,
                shown,
                "a single body needs self_contact = true (give exactly two bodies for a contact \
                 pair, or more, or \"all\", for a group)",
            ));
        }
        let group = all || list.len() > 2 || self_contact;
        if group && c.two_pass == Some(false) {
            return Err(self.invalid(
                format!("{key}.two_pass"),
                "false",
                &format!(
                    "a contact group (bodies = {shown}{}) is symmetric: every pair in both \
                     directions; two_pass = false applies to a pair of bodies only",
                    if self_contact { ", self_contact" } else { "" }
                ),
            ));
        }
        self.given_name_length(key, c.name.as_ref())?;
        let springs = self.springs(key, raw_springs!(c), mass_damping)?;
        let names: Vec<&str> = list.iter().map(|&i| bodies[i].name.as_str()).collect();
        let default = if !group {
            names.join("-")
        } else if all {
            "all".to_string()
        } else if names.len() == 1 {
            format!("{}-self", names[0])
        } else {
            names.join("+")
        };
        let mut list = list;
        if group {
            list.sort_unstable();
        }
        let surfaces = match &c.surfaces {
            None => None,
            Some(names) => Some(self.surfaces(key, names, group, &list, bodies)?),
        };
        Ok(Contact {
            name: c.name.clone().unwrap_or(default),
            bodies: list,
            group,
            self_contact,
            method: springs.method,
            two_pass: group || c.two_pass.unwrap_or(true),
            penalty_scale: springs.scale,
            penalty_form: springs.form,
            friction_stiffness: springs.friction_stiffness,
            surfaces,
            friction: springs.friction,
            augmentation_rate: springs.augmentation_rate,
        })
    }

    /// `surfaces` of contact `key` between `bodies` `list` (not a `group`): one physical curve of
    /// each body's Gmsh file, as its name and line elements.
    fn surfaces(
        &self,
        key: &str,
        names: &[String],
        group: bool,
        list: &[usize],
        bodies: &[Body],
    ) -> Result<Vec<(String, Vec<[u32; 2]>)>> {
        let sk = format!("{key}.surfaces");
        if group || names.len() != 2 {
            return Err(self.invalid(
                sk,
                format!("{names:?}"),
                "name one physical curve per body of a contact pair (two bodies, in \
                 the order of `bodies`)",
            ));
        }
        let mut out = Vec::new();
        for (k, (name, &b)) in names.iter().zip(list).enumerate() {
            let (_, g) = self.mesh_group(
                &format!("{sk}[{k}]"),
                name,
                &bodies[b],
                "a contact surface by name",
                "physical curve",
                |dim| dim == 1,
            )?;
            out.push((name.clone(), g.edges.clone()));
        }
        Ok(out)
    }

    fn wall(
        &self,
        key: &str,
        w: &RawWall,
        bodies: &[Body],
        mass_damping: f64,
    ) -> Result<RigidWall> {
        self.given_name_length(key, w.name.as_ref())?;
        for i in 0..2 {
            self.finite(&format!("{key}.point"), w.point[i])?;
            self.finite(&format!("{key}.normal"), w.normal[i])?;
        }
        // Normalised without overflow: a normal of [-1.5e308, -1.5e308] is (-1, -1) / sqrt 2,
        // not the zero vector.
        let normal = self.unit(&format!("{key}.normal"), w.normal).map_err(|_| {
            self.invalid(
                format!("{key}.normal"),
                format!("{:?}", w.normal),
                "must be a non-zero vector (pointing to the side the bodies stay on)",
            )
        })?;
        let list = match &w.bodies {
            Some(names) => {
                if names.is_empty() {
                    return Err(self.invalid(
                        format!("{key}.bodies"),
                        "[]",
                        "name at least one body",
                    ));
                }
                let mut out = Vec::new();
                for n in names {
                    let i = self.body_index(&format!("{key}.bodies"), n, bodies)?;
                    if !out.contains(&i) {
                        out.push(i);
                    }
                }
                out
            }
            None => (0..bodies.len()).collect(),
        };
        let springs = self.springs(key, raw_springs!(w), mass_damping)?;
        let name = match &w.name {
            Some(n) => n.clone(),
            None => {
                let names: Vec<&str> = list.iter().map(|&i| bodies[i].name.as_str()).collect();
                names.join("-")
            }
        };
        Ok(RigidWall {
            name,
            point: w.point,
            normal,
            bodies: list,
            method: springs.method,
            penalty_scale: springs.scale,
            penalty_form: springs.form,
            friction_stiffness: springs.friction_stiffness,
            friction: springs.friction,
            augmentation_rate: springs.augmentation_rate,
        })
    }
}
