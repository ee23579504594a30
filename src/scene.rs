//! Scene files: the TOML format users write, and its validation into a [`Scene`].
//!
//! Every rejected value is reported as [`Error::Invalid`] with the file, the dotted key and the value.

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// Fixed-length arrays of the scene file, read strictly: serde's own `[T; N]` takes the first N
/// values of a longer TOML array and drops the rest (a quad with 5 node indices, a node
/// `[x, y, z]`, `cells = [2, 2, 0]` were accepted).
mod fixed {
    use serde::de::{Deserialize, Deserializer, Error};

    fn exact<'de, D: Deserializer<'de>, T, const N: usize>(v: Vec<T>) -> Result<[T; N], D::Error> {
        let len = v.len();
        v.try_into().map_err(|_| {
            D::Error::invalid_length(len, &format!("an array of exactly {N} values").as_str())
        })
    }

    /// `[T; N]`.
    pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        exact::<D, T, N>(Vec::deserialize(d)?)
    }

    /// `Option<[T; N]>` (with `#[serde(default)]`).
    pub fn option<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        Option::<Vec<T>>::deserialize(d)?
            .map(exact::<D, T, N>)
            .transpose()
    }

    /// `Option<Vec<[T; N]>>` (with `#[serde(default)]`).
    pub fn list<'de, D, T, const N: usize>(d: D) -> Result<Option<Vec<[T; N]>>, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        Option::<Vec<Vec<T>>>::deserialize(d)?
            .map(|rows| rows.into_iter().map(exact::<D, T, N>).collect())
            .transpose()
    }

    /// `Option<Vec<[i64; 4]>>` of quads `[a, b, c, d]` and triangles `[a, b, c]` (with
    /// `#[serde(default)]`): a triangle becomes the collapsed quad `[a, b, c, c]`.
    pub fn elements<'de, D>(d: D) -> Result<Option<Vec<[i64; 4]>>, D::Error>
    where
        D: Deserializer<'de>,
    {
        Option::<Vec<Vec<i64>>>::deserialize(d)?
            .map(|rows| {
                rows.into_iter()
                    .map(|r| match r[..] {
                        [a, b, c] => Ok([a, b, c, c]),
                        [a, b, c, e] => Ok([a, b, c, e]),
                        _ => Err(D::Error::invalid_length(
                            r.len(),
                            &"exactly 3 node indices (a triangle) or 4 (a quad)",
                        )),
                    })
                    .collect()
            })
            .transpose()
    }

    /// `Option<[[f64; 2]; 2]>` (with `#[serde(default)]`).
    pub fn matrix<'de, D>(d: D) -> Result<Option<[[f64; 2]; 2]>, D::Error>
    where
        D: Deserializer<'de>,
    {
        Option::<Vec<Vec<f64>>>::deserialize(d)?
            .map(|rows| {
                let rows: Vec<[f64; 2]> = rows
                    .into_iter()
                    .map(exact::<D, f64, 2>)
                    .collect::<Result<_, _>>()?;
                exact::<D, [f64; 2], 2>(rows)
            })
            .transpose()
    }
}

use crate::error::{Error, Result};

/// Largest scene file read (bytes).
pub const SCENE_MAX_BYTES: u64 = 64 << 20;

/// Longest body name (bytes).
pub const NAME_MAX: usize = 64;
/// Longest contact or rigid-wall name (characters): it heads four `history.csv` columns.
pub const CONTACT_NAME_MAX: usize = 256;

/// Default safety factor on the stable time step.
pub const DEFAULT_TIME_STEP_SCALE: f64 = 0.9;
/// Default linear bulk-viscosity coefficient (as in common explicit codes).
pub const DEFAULT_BULK_LINEAR: f64 = 0.06;
/// Default quadratic bulk-viscosity coefficient.
pub const DEFAULT_BULK_QUADRATIC: f64 = 1.5;
/// Largest quadratic bulk-viscosity coefficient.
pub const BULK_QUADRATIC_MAX: f64 = 10.0;
/// Default hourglass coefficient.
pub const DEFAULT_HOURGLASS_COEFFICIENT: f64 = 0.1;
/// Default bound on the relative energy-balance error before a run is stopped.
pub const DEFAULT_ENERGY_ERROR_LIMIT: f64 = 0.05;

// ---------------------------------------------------------------------------------------------
// Raw file layout (serde). Unknown keys are errors so that typos are caught.
// ---------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    run: RawRun,
    #[serde(default)]
    material: Vec<RawMaterial>,
    #[serde(default)]
    body: Vec<RawBody>,
    #[serde(default)]
    boundary: Vec<RawBoundary>,
    #[serde(default)]
    contact: Vec<RawContact>,
    #[serde(default)]
    rigid_wall: Vec<RawWall>,
    #[serde(default)]
    pressure: Vec<RawPressure>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPressure {
    body: String,
    region: RawRegion,
    value: RawValue,
    ramp: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    bodies: RawBodies,
    name: Option<String>,
    method: Option<String>,
    two_pass: Option<bool>,
    self_contact: Option<bool>,
    penalty_scale: Option<f64>,
    penalty_stiffness: Option<String>,
    surfaces: Option<Vec<String>>,
    friction: Option<f64>,
    friction_stiffness: Option<f64>,
    augmentation_rate: Option<f64>,
}

/// The penalty and friction keys of a `[[contact]]` or `[[rigid_wall]]` as written.
struct RawSprings<'a> {
    form: Option<&'a str>,
    scale: Option<f64>,
    friction: Option<f64>,
    friction_stiffness: Option<f64>,
    augmentation_rate: Option<f64>,
}

/// The penalty and friction keys of a contact or wall, checked, with their defaults.
struct Springs {
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWall {
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRun {
    end_time: f64,
    time_step_scale: Option<f64>,
    time_step: Option<f64>,
    history_interval: Option<f64>,
    field_interval: Option<f64>,
    field_format: Option<String>,
    checkpoint_interval: Option<f64>,
    energy_error_limit: Option<f64>,
    bulk_viscosity: Option<RawBulk>,
    mass_damping: Option<f64>,
    gravity: Option<toml::Value>,
    gravity_ramp: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBulk {
    linear: Option<f64>,
    quadratic: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: String,
    model: String,
    density: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    yield_stress: Option<f64>,
    hardening_modulus: Option<f64>,
    johnson_cook: Option<toml::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBody {
    name: String,
    material: String,
    formulation: Option<String>,
    thickness: Option<f64>,
    mesh: RawMesh,
    #[serde(default, deserialize_with = "fixed::option")]
    initial_velocity: Option<[f64; 2]>,
    angular_velocity: Option<f64>,
    #[serde(default, deserialize_with = "fixed::matrix")]
    velocity_gradient: Option<[[f64; 2]; 2]>,
    hourglass: Option<RawHourglass>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    rectangle: Option<RawRectangle>,
    disk: Option<RawDisk>,
    #[serde(default, deserialize_with = "fixed::list")]
    nodes: Option<Vec<[f64; 2]>>,
    #[serde(default, deserialize_with = "fixed::elements")]
    quads: Option<Vec<[i64; 4]>>,
    gmsh: Option<String>,
    group: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRectangle {
    #[serde(deserialize_with = "fixed::array")]
    origin: [f64; 2],
    #[serde(deserialize_with = "fixed::array")]
    size: [f64; 2],
    #[serde(deserialize_with = "fixed::array")]
    cells: [i64; 2],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDisk {
    #[serde(deserialize_with = "fixed::array")]
    center: [f64; 2],
    radius: f64,
    cells: i64,
    refine: Option<RawRefine>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRefine {
    #[serde(deserialize_with = "fixed::array")]
    toward: [f64; 2],
    ratio: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHourglass {
    form: Option<String>,
    coefficient: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBoundary {
    body: String,
    region: RawRegion,
    velocity: RawVelocity,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion {
    #[serde(default, deserialize_with = "fixed::option")]
    min: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "fixed::option")]
    max: Option<[f64; 2]>,
    group: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVelocity {
    x: Option<RawValue>,
    y: Option<RawValue>,
}

/// A number, or a load curve: a table of `[time, value]` pairs.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawValue {
    Constant(f64),
    Table(Vec<Vec<f64>>),
}

/// Points of a load curve at most (a bound on what one scene key can allocate).
pub const MAX_CURVE_POINTS: usize = 100_000;

/// A value prescribed in time: piecewise linear through its `[time, value]` points (times
/// strictly increasing), held at the first value before the first time and at the last after
/// the last. A constant is one point.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadCurve {
    /// The `[time (s), value]` points.
    pub points: Vec<[f64; 2]>,
}

impl LoadCurve {
    /// The constant `v`.
    pub fn constant(v: f64) -> Self {
        Self {
            points: vec![[0.0, v]],
        }
    }

    /// The value at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        let p = &self.points;
        let Some(first) = p.first() else {
            return 0.0;
        };
        if t <= first[0] {
            return first[1];
        }
        for w in p.windows(2) {
            let (a, b) = (w[0], w[1]);
            if t <= b[0] {
                return a[1] + (b[1] - a[1]) * ((t - a[0]) / (b[0] - a[0]));
            }
        }
        p[p.len() - 1][1]
    }

    /// Whether it is one value for all time.
    pub fn is_constant(&self) -> bool {
        self.points.windows(2).all(|w| w[0][1] == w[1][1])
    }
}

// ---------------------------------------------------------------------------------------------
// Validated scene.
// ---------------------------------------------------------------------------------------------

/// Constitutive model of a material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaterialModel {
    /// Small-strain linear elasticity (geometrically linear: for the textbook comparisons).
    LinearElastic,
    /// Compressible neo-Hookean hyperelasticity (finite strain, objective).
    NeoHookean,
    /// J2 (von Mises) plasticity with linear isotropic hardening, finite strain: Hencky
    /// elasticity on the elastic left Cauchy-Green tensor of a multiplicative split, radial return
    /// in logarithmic strain ([`crate::element::plastic`]).
    J2Plastic,
}

/// Yield parameters of a [`MaterialModel::J2Plastic`] material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plasticity {
    /// Initial yield stress sigma_y (Pa), > 0.
    pub yield_stress: f64,
    /// Linear isotropic hardening modulus H (Pa), >= 0: sigma_y + H eps_p.
    pub hardening_modulus: f64,
    /// The Johnson-Cook flow stress instead (then `yield_stress` = a, `hardening_modulus` = 0).
    pub johnson_cook: Option<JohnsonCook>,
}

/// Johnson-Cook flow stress without thermal softening:
/// (a + b eps_p^n)(1 + c ln(max(rate / reference_strain_rate, 1))), rate the equivalent plastic
/// strain rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCook {
    /// Initial yield stress A (Pa), > 0.
    pub a: f64,
    /// Hardening coefficient B (Pa), >= 0.
    pub b: f64,
    /// Hardening exponent n, in (0, 10].
    pub n: f64,
    /// Strain-rate coefficient C, >= 0.
    pub c: f64,
    /// Reference strain rate (1/s), > 0.
    pub reference_strain_rate: f64,
}

/// A material, validated.
#[derive(Debug, Clone)]
pub struct Material {
    /// Name used by bodies.
    pub name: String,
    /// Constitutive model.
    pub model: MaterialModel,
    /// Mass density (kg/m^3).
    pub density: f64,
    /// Young's modulus (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Yield parameters (`Some` exactly for [`MaterialModel::J2Plastic`]).
    pub plasticity: Option<Plasticity>,
}

/// 2D kinematic assumption of a body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Formulation {
    /// Plane strain (epsilon_zz = 0).
    PlaneStrain,
    /// Plane stress (sigma_zz = 0).
    PlaneStress,
    /// Axisymmetric about the y axis: x = r >= 0 the radius, y the axis; the out-of-plane
    /// direction is the hoop direction, and masses, forces and energies are per radian.
    Axisymmetric,
}

/// Hourglass control form.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HourglassForm {
    /// No hourglass control.
    None,
    /// Flanagan-Belytschko viscous form (dissipative).
    Viscous,
    /// Flanagan-Belytschko stiffness form (conservative, energy stored).
    Stiffness,
}

/// Hourglass control of a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hourglass {
    /// Which form.
    pub form: HourglassForm,
    /// Dimensionless coefficient (0.1 by default).
    pub coefficient: f64,
}

/// How a body is meshed.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshSpec {
    /// Nodes and counter-clockwise quads and triangles given explicitly (absolute coordinates).
    Explicit {
        /// Node coordinates.
        nodes: Vec<[f64; 2]>,
        /// Quads as 0-based node indices, counter-clockwise; a triangle `[a, b, c]` of the scene
        /// is the collapsed quad `[a, b, c, c]` here (see [`crate::element`]).
        quads: Vec<[u32; 4]>,
    },
    /// A structured grid over an axis-aligned rectangle.
    Rectangle {
        /// Lower-left corner.
        origin: [f64; 2],
        /// Width and height.
        size: [f64; 2],
        /// Cells along x and y.
        cells: [usize; 2],
    },
    /// A structured O-grid disk: a square core and four curved blocks, no degenerate quads.
    Disk {
        /// Centre.
        center: [f64; 2],
        /// Radius.
        radius: f64,
        /// Cells along a quarter of the circumference (and across the core).
        cells: usize,
        /// Grading toward a rim point (a contact point), if any.
        refine: Option<DiskRefinement>,
    },
    /// The quads of one physical surface of a Gmsh MSH 4.1 file (read when the scene is).
    Gmsh {
        /// The mesh file (relative paths resolved against the scene file's folder).
        file: PathBuf,
        /// The physical surface's name.
        group: String,
        /// What was read (counter-clockwise quads, with their Gmsh tags).
        mesh: crate::gmsh::SurfaceMesh,
    },
}

/// Grading of a disk mesh toward a rim point and the point opposite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiskRefinement {
    /// Unit direction from the centre to the refined rim point.
    pub toward: [f64; 2],
    /// Uniform rim spacing over the spacing at that point (>= 1).
    pub ratio: f64,
}

/// A body, validated.
#[derive(Debug, Clone)]
pub struct Body {
    /// Name.
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Plane strain or plane stress.
    pub formulation: Formulation,
    /// Out-of-plane thickness (m).
    pub thickness: f64,
    /// Mesh.
    pub mesh: MeshSpec,
    /// Initial rigid velocity.
    pub initial_velocity: [f64; 2],
    /// Initial angular velocity about the body's centroid (rad/s, counter-clockwise).
    pub angular_velocity: f64,
    /// Initial velocity gradient about the centroid, `[[dvx/dx, dvx/dy], [dvy/dx, dvy/dy]]` (1/s).
    pub velocity_gradient: [[f64; 2]; 2],
    /// Hourglass control.
    pub hourglass: Hourglass,
}

/// A prescribed velocity on the nodes of a body inside a box.
#[derive(Debug, Clone)]
pub struct Boundary {
    /// Index into [`Scene::bodies`].
    pub body: usize,
    /// Box lower corner.
    pub min: [f64; 2],
    /// Box upper corner.
    pub max: [f64; 2],
    /// Prescribed x velocity, if any.
    pub vx: Option<f64>,
    /// Prescribed y velocity, if any.
    pub vy: Option<f64>,
    /// The x velocity's load curve, when it is one (`vx` is then its value at t = 0).
    pub curve_x: Option<LoadCurve>,
    /// The y velocity's load curve, when it is one (`vy` is then its value at t = 0).
    pub curve_y: Option<LoadCurve>,
    /// The physical curve or point of the body's mesh file that selects the nodes instead of
    /// the box (`region = { group = "..." }`).
    pub group: Option<RegionGroup>,
    /// Key prefix used in messages (`boundary[i]`).
    pub key: String,
}

/// A region given by name: a physical curve or point of the body's Gmsh file, as that body's
/// nodes and edges.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionGroup {
    /// The group's name.
    pub name: String,
    /// Node indices within the body (its mesh's numbering), ascending.
    pub nodes: Vec<u32>,
    /// The curve's line elements within the body, as pairs of body node indices.
    pub edges: Vec<[u32; 2]>,
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

/// A pressure (traction) load on the boundary edges of a body inside a box.
#[derive(Debug, Clone)]
pub struct Pressure {
    /// Index into [`Scene::bodies`].
    pub body: usize,
    /// Box lower corner.
    pub min: [f64; 2],
    /// Box upper corner.
    pub max: [f64; 2],
    /// Pressure (Pa), acting against the outward normal (positive: compressive).
    pub value: f64,
    /// Duration of the linear ramp from 0 (s), if any; constant afterwards.
    pub ramp: Option<f64>,
    /// The pressure's load curve, when `value` is a table (`value` is then its value at t = 0).
    pub curve: Option<LoadCurve>,
    /// The physical curve of the body's mesh file whose boundary edges are loaded, instead of
    /// the box (`region = { group = "..." }`).
    pub group: Option<RegionGroup>,
    /// Key prefix used in messages (`pressure[i]`).
    pub key: String,
}

/// Encoding of the VTU field files (`run.field_format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FieldFormat {
    /// Raw appended binary data, zlib-compressed, real numbers in single precision (`"binary"`,
    /// the default).
    #[default]
    Binary,
    /// As [`FieldFormat::Binary`] with real numbers in double precision (`"binary64"`).
    Binary64,
    /// Human-readable text (`"ascii"`), several times larger and slower to write.
    Ascii,
}

/// Run control, validated.
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// Simulated end time (s).
    pub end_time: f64,
    /// Safety factor on the stable step.
    pub time_step_scale: f64,
    /// Fixed step, if given.
    pub time_step: Option<f64>,
    /// Time between history rows.
    pub history_interval: f64,
    /// Time between field snapshots, if any.
    pub field_interval: Option<f64>,
    /// Encoding of the field files.
    pub field_format: FieldFormat,
    /// Simulated time between checkpoints (`checkpoint.bin` in the output folder), if any.
    pub checkpoint_interval: Option<f64>,
    /// Relative energy-balance error that stops the run.
    pub energy_error_limit: f64,
    /// Linear bulk-viscosity coefficient.
    pub bulk_linear: f64,
    /// Quadratic bulk-viscosity coefficient.
    pub bulk_quadratic: f64,
    /// Mass-proportional damping coefficient alpha (1/s): a force -alpha m v on every node
    /// (0: none).
    pub mass_damping: f64,
    /// Gravity (m/s^2): a body force m g on every node ([0, 0]: none).
    pub gravity: [f64; 2],
    /// Duration of a linear ramp of gravity from 0 (s; 0: gravity in full from t = 0).
    pub gravity_ramp: f64,
}

/// A validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Scene name (file stem).
    pub name: String,
    /// Source file.
    pub file: PathBuf,
    /// Run control.
    pub run: RunSettings,
    /// Materials.
    pub materials: Vec<Material>,
    /// Bodies.
    pub bodies: Vec<Body>,
    /// Velocity boundary conditions.
    pub boundaries: Vec<Boundary>,
    /// Contacts between bodies.
    pub contacts: Vec<Contact>,
    /// Rigid walls.
    pub walls: Vec<RigidWall>,
    /// Pressure loads.
    pub pressures: Vec<Pressure>,
}

impl Scene {
    /// Whether the scene has any contact or rigid wall.
    pub fn has_contact(&self) -> bool {
        !self.contacts.is_empty() || !self.walls.is_empty()
    }
}

impl Scene {
    /// Reads and validates a scene file.
    ///
    /// # Errors
    /// [`Error::Read`] when the file cannot be read, [`Error::Parse`] for TOML and shape errors
    /// (unknown keys included), [`Error::Invalid`] for values that are out of range.
    pub fn load(path: &Path) -> Result<Self> {
        use std::io::Read as _;
        let read_err = |source| Error::Read {
            file: path.to_path_buf(),
            source,
        };
        // Bounded: `/dev/zero` or a runaway file is refused, not read until memory runs out.
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(SCENE_MAX_BYTES + 1).read_to_end(&mut bytes))
            .map_err(read_err)?;
        if bytes.len() as u64 > SCENE_MAX_BYTES {
            return Err(Error::Parse {
                file: path.to_path_buf(),
                message: format!(
                    "larger than {} MiB: not a scene file (meshes this large belong in a mesh file)",
                    SCENE_MAX_BYTES >> 20
                ),
            });
        }
        let text = String::from_utf8(bytes).map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        })?;
        Self::parse(&text, path)
    }

    /// Parses and validates scene text; `path` is used for the name and in messages.
    ///
    /// # Errors
    /// As [`Scene::load`], without the read error.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let raw: RawScene = toml::from_str(text).map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: toml_message(text, &e),
        })?;
        let v = Validator { file: path };
        v.scene(raw)
    }
}

/// Characters of the offending line quoted on either side of a TOML error's column.
const QUOTE_CHARS: usize = 60;
/// Longest parser message quoted (characters).
const MESSAGE_CHARS: usize = 1000;

/// A TOML error as the parser renders it (line, column, the line with a caret under the column,
/// the message), with the quoted line cut to [`QUOTE_CHARS`] characters either side of the column
/// and the message to [`MESSAGE_CHARS`]: the parser quotes the whole line and the whole value,
/// and one line can hold a whole mesh (the nodes of `assets/ring_crush.toml` are one line of
/// 16 KB), so a typo there gave a message the size of the file.
pub fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let cut = |s: &str, n: usize| -> String {
        match s.char_indices().nth(n) {
            Some((i, _)) => format!("{}...", &s[..i]),
            None => s.to_string(),
        }
    };
    let message = cut(e.message().trim_end(), MESSAGE_CHARS);
    let Some(span) = e.span() else {
        return cut(e.to_string().trim_end(), MESSAGE_CHARS);
    };
    let mut start = span.start.min(text.len());
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_no = text[..line_start].matches('\n').count() + 1;
    let content = text[line_start..].split('\n').next().unwrap_or("");
    let content = content.strip_suffix('\r').unwrap_or(content);
    let chars: Vec<char> = content.chars().collect();
    let column = text[line_start..start].chars().count();
    let from = column.saturating_sub(QUOTE_CHARS);
    let to = (column + QUOTE_CHARS + 1).min(chars.len());
    let mut quoted: String = if from > 0 {
        "...".into()
    } else {
        String::new()
    };
    let caret_at = column - from + quoted.len();
    quoted.extend(&chars[from.min(to)..to]);
    if to < chars.len() {
        quoted.push_str("...");
    }
    let width = text
        .get(start..span.end.min(text.len()))
        .map_or(1, |s| s.chars().take_while(|&c| c != '\n').count())
        .clamp(1, QUOTE_CHARS);
    let gutter = " ".repeat(line_no.to_string().len() + 1);
    format!(
        "TOML parse error at line {line_no}, column {}\n{gutter}|\n{line_no} | {quoted}\n{gutter}| {}{}\n{message}",
        column + 1,
        " ".repeat(caret_at),
        "^".repeat(width)
    )
}

struct Validator<'a> {
    file: &'a Path,
}

fn fmt_num(x: f64) -> String {
    format!("{x:?}")
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
    fn invalid(&self, key: impl Into<String>, value: impl Into<String>, reason: &str) -> Error {
        Error::Invalid {
            file: self.file.to_path_buf(),
            key: key.into(),
            value: value.into(),
            reason: reason.to_string(),
        }
    }

    fn positive(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_normal() && x > 0.0 {
            Ok(x)
        } else if x > 0.0 && x.is_finite() {
            Err(self.invalid(
                key,
                fmt_num(x),
                &format!(
                    "is below the smallest normal number {:e} (subnormal): use a positive finite \
                     number of normal size",
                    f64::MIN_POSITIVE
                ),
            ))
        } else {
            Err(self.invalid(key, fmt_num(x), "must be a positive finite number"))
        }
    }

    fn non_negative(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(key, fmt_num(x), "must be a finite number >= 0"))
        }
    }

    /// A non-zero finite vector, normalised: `v` over its length, scaled first by its largest component so that no finite vector
    /// overflows (`[-1.5e308, -1.5e308]` is the direction (-1, -1) / sqrt 2).
    fn unit(&self, key: &str, v: [f64; 2]) -> Result<[f64; 2]> {
        let m = v[0].abs().max(v[1].abs());
        if !(m.is_finite() && m > 0.0) {
            return Err(self.invalid(key, format!("{v:?}"), "must be a finite non-zero vector"));
        }
        let w = [v[0] / m, v[1] / m];
        let len = w[0].hypot(w[1]);
        Ok([w[0] / len, w[1] / len])
    }

    fn finite(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(key, fmt_num(x), "must be finite"))
        }
    }

    fn scene(&self, raw: RawScene) -> Result<Scene> {
        let run = self.run(&raw.run)?;
        let mut materials: Vec<Material> = Vec::new();
        for (i, m) in raw.material.iter().enumerate() {
            let key = format!("material[{i}]");
            if materials.iter().any(|o| o.name == m.name) {
                return Err(self.invalid(
                    format!("{key}.name"),
                    format!("{:?}", m.name),
                    "duplicate material name",
                ));
            }
            materials.push(self.material(&key, m)?);
        }
        if raw.body.is_empty() {
            return Err(self.invalid("body", "[]", "a scene needs at least one [[body]]"));
        }
        let mut bodies: Vec<Body> = Vec::new();
        for (i, b) in raw.body.iter().enumerate() {
            let key = format!("body[{i}]");
            self.check_name(&format!("{key}.name"), &b.name)?;
            if bodies.iter().any(|o| o.name == b.name) {
                return Err(self.invalid(
                    format!("{key}.name"),
                    format!("{:?}", b.name),
                    "duplicate body name",
                ));
            }
            bodies.push(self.body(&key, b, &materials)?);
        }
        let mut boundaries = Vec::new();
        for (i, b) in raw.boundary.iter().enumerate() {
            let key = format!("boundary[{i}]");
            boundaries.push(self.boundary(&key, b, &bodies)?);
        }
        let mut contacts: Vec<Contact> = Vec::new();
        for (i, c) in raw.contact.iter().enumerate() {
            let key = format!("contact[{i}]");
            // Two contacts with one default name are the same contact given twice: refused.
            let c = self.contact(&key, c, &bodies, run.mass_damping)?;
            self.unique_name(&key, &c.name, &contacts, &[])?;
            contacts.push(c);
        }
        let mut walls: Vec<RigidWall> = Vec::new();
        for (i, w) in raw.rigid_wall.iter().enumerate() {
            let key = format!("rigid_wall[{i}]");
            // A wall's default name (its bodies joined by `-`) may be a contact's: suffixed.
            let named = w.name.is_some();
            let mut w = self.wall(&key, w, &bodies, run.mass_damping)?;
            if !named {
                w.name = free_name(&w.name, &contacts, &walls);
            }
            self.unique_name(&key, &w.name, &contacts, &walls)?;
            walls.push(w);
        }
        let mut pressures = Vec::new();
        for (i, p) in raw.pressure.iter().enumerate() {
            let key = format!("pressure[{i}]");
            pressures.push(self.pressure(&key, p, &bodies)?);
        }
        let name = self
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".to_string());
        Ok(Scene {
            name,
            file: self.file.to_path_buf(),
            run,
            materials,
            bodies,
            boundaries,
            contacts,
            walls,
            pressures,
        })
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
            let shown: String = name.chars().take(40).collect();
            let more = if name.chars().count() > 40 { "..." } else { "" };
            return Err(self.invalid(
                format!("{key}.name"),
                format!("{shown:?}{more}"),
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
            let shown: String = name.chars().take(40).collect();
            return Err(self.invalid(
                format!("{key}.name"),
                format!("{shown:?}..."),
                &format!(
                    "must be 1 to {CONTACT_NAME_MAX} characters, without commas, quotes or \
                     control characters (it names history columns); this one has {}",
                    name.chars().count()
                ),
            ));
        }
        Ok(())
    }

    /// Body names become file names (`fields/<body>_<k>.vtu`) and `history.csv` headers: 1 to
    /// [`NAME_MAX`] ASCII letters, digits, `_`, `-` and `.`, not starting with `.` or `-`.
    fn check_name(&self, key: &str, name: &str) -> Result<()> {
        let ok = !name.is_empty()
            && name.len() <= NAME_MAX
            && name
                .bytes()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, b'_' | b'-' | b'.'))
            && !name.starts_with(['.', '-']);
        if ok {
            return Ok(());
        }
        let shown: String = name.chars().take(40).collect();
        let more = if name.chars().count() > 40 { "..." } else { "" };
        Err(self.invalid(
            key,
            format!("{shown:?}{more}"),
            &format!(
                "a name must be 1 to {NAME_MAX} ASCII letters, digits, `_`, `-` or `.`, not \
                 starting with `.` or `-` (names become file names and history.csv columns)"
            ),
        ))
    }

    fn body_index(&self, key: &str, name: &str, bodies: &[Body]) -> Result<usize> {
        bodies.iter().position(|b| b.name == name).ok_or_else(|| {
            let known: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
            self.invalid(
                key,
                format!("{name:?}"),
                &format!("no body of that name (defined: {known:?})"),
            )
        })
    }

    fn method(&self, key: &str, m: Option<&str>) -> Result<ContactMethod> {
        match m {
            None | Some("lagrange") => Ok(ContactMethod::Lagrange),
            Some("penalty") => Ok(ContactMethod::Penalty),
            Some("perturbed_lagrange") => Ok(ContactMethod::PerturbedLagrange),
            Some("augmented_lagrange") => Ok(ContactMethod::AugmentedLagrange),
            Some(other) => Err(self.invalid(
                key,
                format!("{other:?}"),
                "expected \"lagrange\", \"penalty\", \"perturbed_lagrange\" or \
                 \"augmented_lagrange\"",
            )),
        }
    }

    /// The penalty and friction keys of contact or wall `key` with `method`.
    fn springs(
        &self,
        key: &str,
        method: ContactMethod,
        raw: RawSprings,
        mass_damping: f64,
    ) -> Result<Springs> {
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
        let f = match form {
            None => return Ok(DEFAULT_PENALTY_FORM),
            Some("modulus") => PenaltyForm::Modulus,
            Some("mass") => PenaltyForm::Mass,
            Some(other) => {
                return Err(self.invalid(
                    key,
                    format!("{other:?}"),
                    "expected \"modulus\" (k = s K t L^2 / A) or \"mass\" (k = s m* / dt^2)",
                ))
            }
        };
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
        let method = self.method(&format!("{key}.method"), c.method.as_deref())?;
        let Springs {
            form: penalty_form,
            scale: penalty_scale,
            friction,
            friction_stiffness,
            augmentation_rate,
        } = self.springs(
            key,
            method,
            RawSprings {
                form: c.penalty_stiffness.as_deref(),
                scale: c.penalty_scale,
                friction: c.friction,
                friction_stiffness: c.friction_stiffness,
                augmentation_rate: c.augmentation_rate,
            },
            mass_damping,
        )?;
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
            Some(names) => {
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
                for (k, (name, &b)) in names.iter().zip(&list).enumerate() {
                    let body = &bodies[b];
                    let MeshSpec::Gmsh { file, mesh, .. } = &body.mesh else {
                        return Err(self.invalid(
                            format!("{sk}[{k}]"),
                            format!("{name:?}"),
                            &format!(
                                "body {:?} is not read from a Gmsh file: a contact surface by \
                                 name is a physical curve of the body's mesh file",
                                body.name
                            ),
                        ));
                    };
                    let Some(g) = mesh.groups.iter().find(|g| g.name == *name && g.dim == 1) else {
                        let known: Vec<&str> = mesh
                            .groups
                            .iter()
                            .filter(|g| g.dim == 1)
                            .map(|g| g.name.as_str())
                            .collect();
                        return Err(self.invalid(
                            format!("{sk}[{k}]"),
                            format!("{name:?}"),
                            &format!(
                                "{} has no physical curve of that name on body {:?} (there: {known:?})",
                                file.display(),
                                body.name
                            ),
                        ));
                    };
                    out.push((name.clone(), g.edges.clone()));
                }
                Some(out)
            }
        };
        Ok(Contact {
            name: c.name.clone().unwrap_or(default),
            bodies: list,
            group,
            self_contact,
            method,
            two_pass: group || c.two_pass.unwrap_or(true),
            penalty_scale,
            penalty_form,
            friction_stiffness,
            surfaces,
            friction,
            augmentation_rate,
        })
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
        let method = self.method(&format!("{key}.method"), w.method.as_deref())?;
        let Springs {
            form: penalty_form,
            scale: penalty_scale,
            friction,
            friction_stiffness,
            augmentation_rate,
        } = self.springs(
            key,
            method,
            RawSprings {
                form: w.penalty_stiffness.as_deref(),
                scale: w.penalty_scale,
                friction: w.friction,
                friction_stiffness: w.friction_stiffness,
                augmentation_rate: w.augmentation_rate,
            },
            mass_damping,
        )?;
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
            method,
            penalty_scale,
            penalty_form,
            friction_stiffness,
            friction,
            augmentation_rate,
        })
    }

    fn run(&self, r: &RawRun) -> Result<RunSettings> {
        let end_time = self.positive("run.end_time", r.end_time)?;
        let time_step_scale = match r.time_step_scale {
            Some(s) => {
                let s = self.positive("run.time_step_scale", s)?;
                // Above 1 the step exceeds the stable step: in a rod (1D, where the estimate is
                // exact) the shortest mode grows within a few steps; in 2D, where the element
                // estimate has some reserve, a run may go on for a while and then diverge.
                if s > 1.0 {
                    return Err(self.invalid(
                        "run.time_step_scale",
                        fmt_num(s),
                        "must not exceed 1.0: it multiplies the stable step, and above 1 the \
                         central-difference step is unstable (1.0 is the stability limit itself, \
                         not a production setting; the default is 0.9)",
                    ));
                }
                s
            }
            None => DEFAULT_TIME_STEP_SCALE,
        };
        let time_step = r
            .time_step
            .map(|s| self.positive("run.time_step", s))
            .transpose()?;
        let history_interval = match r.history_interval {
            Some(h) => self.positive("run.history_interval", h)?,
            None => end_time / 1000.0,
        };
        let field_interval = r
            .field_interval
            .map(|f| self.positive("run.field_interval", f))
            .transpose()?;
        let field_format = match r.field_format.as_deref() {
            None | Some("binary") => FieldFormat::Binary,
            Some("binary64") => FieldFormat::Binary64,
            Some("ascii") => FieldFormat::Ascii,
            Some(other) => {
                return Err(self.invalid(
                    "run.field_format",
                    format!("{other:?}"),
                    "expected \"binary\" (zlib-compressed, single precision, the default), \"binary64\" \
                     (the same in double precision) or \"ascii\"",
                ))
            }
        };
        let checkpoint_interval = r
            .checkpoint_interval
            .map(|c| self.positive("run.checkpoint_interval", c))
            .transpose()?;
        let energy_error_limit = match r.energy_error_limit {
            Some(e) => self.positive("run.energy_error_limit", e)?,
            None => DEFAULT_ENERGY_ERROR_LIMIT,
        };
        let (bulk_linear, bulk_quadratic) = match &r.bulk_viscosity {
            Some(b) => (
                match b.linear {
                    Some(x) => self.non_negative("run.bulk_viscosity.linear", x)?,
                    None => DEFAULT_BULK_LINEAR,
                },
                match b.quadratic {
                    Some(x) => {
                        let x = self.non_negative("run.bulk_viscosity.quadratic", x)?;
                        // The quadratic part shortens the stable step in compression, after
                        // t = 0 (out of reach of the first-step check of `run::check_limits`) and
                        // in proportion to the coefficient: at 9.2e18 the round-off strain rates
                        // of disks in free fall cut the step 350-fold and a run to 1 ms would
                        // take hours.
                        if x > BULK_QUADRATIC_MAX {
                            return Err(self.invalid(
                                "run.bulk_viscosity.quadratic",
                                fmt_num(x),
                                &format!(
                                    "must not exceed {BULK_QUADRATIC_MAX:?} (typical values \
                                     1.0-2.0; it shortens the stable step in compression in \
                                     proportion)"
                                ),
                            ));
                        }
                        x
                    }
                    None => DEFAULT_BULK_QUADRATIC,
                },
            ),
            None => (DEFAULT_BULK_LINEAR, DEFAULT_BULK_QUADRATIC),
        };
        let mass_damping = match r.mass_damping {
            Some(a) => self.non_negative("run.mass_damping", a)?,
            None => 0.0,
        };
        let gravity = match &r.gravity {
            None => [0.0; 2],
            Some(v) => {
                let pair = v.as_array().and_then(|a| match a.as_slice() {
                    [x, y] => Some([
                        x.as_float().or(x.as_integer().map(|i| i as f64))?,
                        y.as_float().or(y.as_integer().map(|i| i as f64))?,
                    ]),
                    _ => None,
                });
                let Some(g) = pair else {
                    return Err(self.invalid(
                        "run.gravity",
                        v.to_string(),
                        "must be a 2-vector [gx, gy] in m/s^2, e.g. [0.0, -9.81]",
                    ));
                };
                if !(g[0].is_finite() && g[1].is_finite()) {
                    return Err(self.invalid("run.gravity", format!("{g:?}"), "must be finite"));
                }
                g
            }
        };
        let gravity_ramp = match r.gravity_ramp {
            None => 0.0,
            Some(t) => {
                if r.gravity.is_none() {
                    return Err(self.invalid(
                        "run.gravity_ramp",
                        fmt_num(t),
                        "ramps gravity, but the scene has no `gravity`",
                    ));
                }
                self.positive("run.gravity_ramp", t)?
            }
        };
        Ok(RunSettings {
            end_time,
            time_step_scale,
            time_step,
            history_interval,
            field_interval,
            field_format,
            checkpoint_interval,
            energy_error_limit,
            bulk_linear,
            bulk_quadratic,
            mass_damping,
            gravity,
            gravity_ramp,
        })
    }

    fn material(&self, key: &str, m: &RawMaterial) -> Result<Material> {
        let model =
            match m.model.as_str() {
                "linear_elastic" => MaterialModel::LinearElastic,
                "neo_hookean" => MaterialModel::NeoHookean,
                "j2_plastic" => MaterialModel::J2Plastic,
                other => return Err(self.invalid(
                    format!("{key}.model"),
                    format!("{other:?}"),
                    "unknown model; expected \"linear_elastic\", \"neo_hookean\" or \"j2_plastic\"",
                )),
            };
        let plasticity = self.plasticity(key, m, model)?;
        let density = self.positive(&format!("{key}.density"), m.density)?;
        let youngs_modulus = self.positive(&format!("{key}.youngs_modulus"), m.youngs_modulus)?;
        let nu = m.poisson_ratio;
        if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
            return Err(self.invalid(
                format!("{key}.poisson_ratio"),
                fmt_num(nu),
                "must lie in (-1, 0.5)",
            ));
        }
        Ok(Material {
            name: m.name.clone(),
            model,
            density,
            youngs_modulus,
            poisson_ratio: nu,
            plasticity,
        })
    }

    /// The yield keys of material `key`: required for `j2_plastic`, refused for the elastic models.
    fn plasticity(
        &self,
        key: &str,
        m: &RawMaterial,
        model: MaterialModel,
    ) -> Result<Option<Plasticity>> {
        if model != MaterialModel::J2Plastic {
            let given = [
                ("yield_stress", m.yield_stress.is_some()),
                ("hardening_modulus", m.hardening_modulus.is_some()),
                ("johnson_cook", m.johnson_cook.is_some()),
            ];
            if let Some((k, _)) = given.iter().find(|(_, g)| *g) {
                return Err(self.invalid(
                    format!("{key}.{k}"),
                    "given",
                    &format!(
                        "only a \"j2_plastic\" material yields (this one is {:?})",
                        m.model
                    ),
                ));
            }
            return Ok(None);
        }
        if let Some(jc) = &m.johnson_cook {
            for (k, given) in [
                ("yield_stress", m.yield_stress.is_some()),
                ("hardening_modulus", m.hardening_modulus.is_some()),
            ] {
                if given {
                    return Err(self.invalid(
                        format!("{key}.{k}"),
                        "given",
                        "with johnson_cook the flow stress is (a + b eps_p^n)(1 + c ln(rate / \
                         reference_strain_rate)): give either johnson_cook or yield_stress and \
                         hardening_modulus",
                    ));
                }
            }
            let jc = self.johnson_cook(&format!("{key}.johnson_cook"), jc)?;
            return Ok(Some(Plasticity {
                yield_stress: jc.a,
                hardening_modulus: 0.0,
                johnson_cook: Some(jc),
            }));
        }
        let Some(y) = m.yield_stress else {
            return Err(self.invalid(
                format!("{key}.yield_stress"),
                "missing",
                "a \"j2_plastic\" material needs yield_stress (Pa, > 0) or johnson_cook",
            ));
        };
        let yield_stress = self.positive(&format!("{key}.yield_stress"), y)?;
        let hardening_modulus = match m.hardening_modulus {
            Some(h) => self.non_negative(&format!("{key}.hardening_modulus"), h)?,
            None => 0.0,
        };
        Ok(Some(Plasticity {
            yield_stress,
            hardening_modulus,
            johnson_cook: None,
        }))
    }

    /// The `johnson_cook = { a, b, n, c, reference_strain_rate }` table at `key`.
    fn johnson_cook(&self, key: &str, v: &toml::Value) -> Result<JohnsonCook> {
        let Some(t) = v.as_table() else {
            return Err(self.invalid(
                key,
                v.to_string(),
                "expected a table { a, b, n, c, reference_strain_rate }",
            ));
        };
        const KEYS: [&str; 5] = ["a", "b", "n", "c", "reference_strain_rate"];
        if let Some(k) = t.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(self.invalid(
                format!("{key}.{k}"),
                t[k].to_string(),
                "unknown key (expected a, b, n, c, reference_strain_rate)",
            ));
        }
        let get = |k: &str| -> Result<f64> {
            match t.get(k) {
                None => Err(self.invalid(
                    format!("{key}.{k}"),
                    "missing",
                    "the Johnson-Cook flow stress needs a, b, n, c and reference_strain_rate",
                )),
                Some(toml::Value::Float(x)) => Ok(*x),
                Some(toml::Value::Integer(i)) => Ok(*i as f64),
                Some(other) => {
                    Err(self.invalid(format!("{key}.{k}"), other.to_string(), "expected a number"))
                }
            }
        };
        let a = self.positive(&format!("{key}.a"), get("a")?)?;
        let b = self.non_negative(&format!("{key}.b"), get("b")?)?;
        let n = get("n")?;
        if !(n.is_finite() && n > 0.0 && n <= 10.0) {
            return Err(self.invalid(format!("{key}.n"), fmt_num(n), "must lie in (0, 10]"));
        }
        let c = self.non_negative(&format!("{key}.c"), get("c")?)?;
        let reference_strain_rate = self.positive(
            &format!("{key}.reference_strain_rate"),
            get("reference_strain_rate")?,
        )?;
        Ok(JohnsonCook {
            a,
            b,
            n,
            c,
            reference_strain_rate,
        })
    }

    fn body(&self, key: &str, b: &RawBody, materials: &[Material]) -> Result<Body> {
        let material = materials
            .iter()
            .position(|m| m.name == b.material)
            .ok_or_else(|| {
                let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                self.invalid(
                    format!("{key}.material"),
                    format!("{:?}", b.material),
                    &format!("no material of that name (defined: {known:?})"),
                )
            })?;
        let formulation = match b.formulation.as_deref() {
            None | Some("plane_strain") => Formulation::PlaneStrain,
            Some("plane_stress") => Formulation::PlaneStress,
            Some("axisymmetric") => Formulation::Axisymmetric,
            Some(other) => {
                return Err(self.invalid(
                    format!("{key}.formulation"),
                    format!("{other:?}"),
                    "expected \"plane_strain\", \"plane_stress\" or \"axisymmetric\"",
                ))
            }
        };
        if formulation == Formulation::PlaneStress
            && materials[material].model == MaterialModel::J2Plastic
        {
            return Err(self.invalid(
                format!("{key}.formulation"),
                "\"plane_stress\"",
                &format!(
                    "material {:?} is \"j2_plastic\", which runs in plane strain and \
                     axisymmetric bodies only so far",
                    materials[material].name
                ),
            ));
        }
        let thickness =
            match b.thickness {
                Some(t) if formulation == Formulation::Axisymmetric => return Err(self.invalid(
                    format!("{key}.thickness"),
                    fmt_num(t),
                    "an axisymmetric body has no thickness: its masses, forces and energies are \
                     per radian",
                )),
                Some(t) => self.positive(&format!("{key}.thickness"), t)?,
                None => 1.0,
            };
        let mesh = self.mesh(&format!("{key}.mesh"), &b.mesh)?;
        let v0 = b.initial_velocity.unwrap_or([0.0, 0.0]);
        self.finite(&format!("{key}.initial_velocity"), v0[0])?;
        self.finite(&format!("{key}.initial_velocity"), v0[1])?;
        let angular_velocity = self.finite(
            &format!("{key}.angular_velocity"),
            b.angular_velocity.unwrap_or(0.0),
        )?;
        let velocity_gradient = b.velocity_gradient.unwrap_or([[0.0; 2]; 2]);
        for row in &velocity_gradient {
            for x in row {
                self.finite(&format!("{key}.velocity_gradient"), *x)?;
            }
        }
        let hourglass = match &b.hourglass {
            None => Hourglass {
                form: HourglassForm::Viscous,
                coefficient: DEFAULT_HOURGLASS_COEFFICIENT,
            },
            Some(h) => {
                let form = match h.form.as_deref() {
                    None | Some("viscous") => HourglassForm::Viscous,
                    Some("stiffness") => HourglassForm::Stiffness,
                    Some("none") => HourglassForm::None,
                    Some(other) => {
                        return Err(self.invalid(
                            format!("{key}.hourglass.form"),
                            format!("{other:?}"),
                            "expected \"viscous\", \"stiffness\" or \"none\"",
                        ))
                    }
                };
                let coefficient = match h.coefficient {
                    Some(c) => self.non_negative(&format!("{key}.hourglass.coefficient"), c)?,
                    None => DEFAULT_HOURGLASS_COEFFICIENT,
                };
                if coefficient > 1.0 {
                    return Err(self.invalid(
                        format!("{key}.hourglass.coefficient"),
                        fmt_num(coefficient),
                        "must not exceed 1.0 (typical values 0.03-0.15)",
                    ));
                }
                let form = if coefficient == 0.0 {
                    HourglassForm::None
                } else {
                    form
                };
                Hourglass { form, coefficient }
            }
        };
        Ok(Body {
            name: b.name.clone(),
            material,
            formulation,
            thickness,
            mesh,
            initial_velocity: v0,
            angular_velocity,
            velocity_gradient,
            hourglass,
        })
    }

    fn mesh(&self, key: &str, m: &RawMesh) -> Result<MeshSpec> {
        let given = [
            m.rectangle.is_some(),
            m.disk.is_some(),
            m.nodes.is_some() || m.quads.is_some(),
            m.gmsh.is_some() || m.group.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(self.invalid(
                key,
                "{...}",
                "give exactly one of `rectangle = {...}`, `disk = {...}`, `nodes = [...], quads = [...]` \
                 or `gmsh = \"file.msh\", group = \"name\"`",
            ));
        }
        if m.gmsh.is_some() || m.group.is_some() {
            let (Some(file), Some(group)) = (&m.gmsh, &m.group) else {
                return Err(self.invalid(
                    key,
                    "{...}",
                    "a Gmsh mesh needs both `gmsh` (the .msh file) and `group` (a physical surface)",
                ));
            };
            let path = self
                .file
                .parent()
                .map_or_else(|| PathBuf::from(file), |d| d.join(file));
            let read = crate::gmsh::read_bytes(&path)
                .and_then(|bytes| crate::gmsh::read_surface(&bytes, group));
            return match read {
                Ok(mesh) => Ok(MeshSpec::Gmsh {
                    file: path,
                    group: group.clone(),
                    mesh,
                }),
                Err(problem) => Err(self.invalid(
                    format!("{key}.gmsh"),
                    format!("{file:?}"),
                    &format!("{}: {problem}", path.display()),
                )),
            };
        }
        if m.nodes.is_some() || m.quads.is_some() {
            let (Some(nodes), Some(quads)) = (&m.nodes, &m.quads) else {
                return Err(self.invalid(
                    key,
                    "{...}",
                    "an explicit mesh needs both `nodes` and `quads`",
                ));
            };
            if quads.is_empty() {
                return Err(self.invalid(format!("{key}.quads"), "[]", "no quads"));
            }
            for (i, p) in nodes.iter().enumerate() {
                if !(p[0].is_finite() && p[1].is_finite()) {
                    return Err(self.invalid(
                        format!("{key}.nodes[{i}]"),
                        format!("{p:?}"),
                        "must be finite",
                    ));
                }
            }
            let mut out = Vec::with_capacity(quads.len());
            for (i, q) in quads.iter().enumerate() {
                if q.iter().any(|&n| n < 0 || n as usize >= nodes.len()) {
                    return Err(self.invalid(
                        format!("{key}.quads[{i}]"),
                        format!("{q:?}"),
                        &format!("node index out of range (0..{})", nodes.len()),
                    ));
                }
                out.push(q.map(|n| n as u32));
            }
            // In a mesh of counter-clockwise quads each directed edge belongs to one quad at most:
            // a second one lies on the same side of it (a duplicate or overlapping quad).
            let mut edges = std::collections::HashMap::with_capacity(4 * out.len());
            for (i, q) in out.iter().enumerate() {
                for k in 0..4 {
                    let e = (q[k], q[(k + 1) % 4]);
                    if e.0 == e.1 {
                        // The collapsed side of a triangle [a, b, c, c] (a repeated node
                        // elsewhere is refused when the model is built).
                        continue;
                    }
                    if let Some(j) = edges.insert(e, i) {
                        return Err(self.invalid(
                            format!("{key}.quads[{i}]"),
                            format!("{:?}", quads[i]),
                            &format!(
                                "overlaps quads[{j}] = {:?}: both have the edge from node {} to \
                                 node {} on the same side (a duplicate or overlapping quad)",
                                quads[j], e.0, e.1
                            ),
                        ));
                    }
                }
            }
            // Quads that overlap without sharing an edge (one laid over others).
            if let Some((i, j)) = crate::geometry::overlapping_quads(nodes, &out) {
                return Err(self.invalid(
                    format!("{key}.quads[{j}]"),
                    format!("{:?}", quads[j]),
                    &format!(
                        "overlaps quads[{i}] = {:?}: their interiors intersect (a quad laid over \
                         others; quads may share edges and corners only)",
                        quads[i]
                    ),
                ));
            }
            return Ok(MeshSpec::Explicit {
                nodes: nodes.clone(),
                quads: out,
            });
        }
        match (&m.rectangle, &m.disk) {
            (Some(r), None) => {
                let k = format!("{key}.rectangle");
                self.finite(&format!("{k}.origin"), r.origin[0])?;
                self.finite(&format!("{k}.origin"), r.origin[1])?;
                for (i, s) in r.size.iter().enumerate() {
                    if !(s.is_finite() && *s > 0.0) {
                        return Err(self.invalid(
                            format!("{k}.size"),
                            format!("{:?}", r.size),
                            &format!("component {i} must be positive"),
                        ));
                    }
                }
                for (i, c) in r.cells.iter().enumerate() {
                    if *c < 1 || *c > 100_000 {
                        return Err(self.invalid(
                            format!("{k}.cells"),
                            format!("{:?}", r.cells),
                            &format!("component {i} must be between 1 and 100000"),
                        ));
                    }
                }
                for i in 0..2 {
                    let far = r.origin[i] + r.size[i];
                    let cell = r.size[i] / r.cells[i] as f64;
                    if !far.is_finite() || !cell.is_normal() || r.origin[i] + cell == r.origin[i] {
                        return Err(self.invalid(
                            format!("{k}.size"),
                            format!("{:?}", r.size),
                            &format!(
                                "component {i}: origin + size = {far:e} and cell size {cell:e} must be \
                                 finite and larger than the spacing of floating-point numbers at \
                                 the origin"
                            ),
                        ));
                    }
                }
                let area = (r.size[0] / r.cells[0] as f64) * (r.size[1] / r.cells[1] as f64);
                if !area.is_normal() {
                    return Err(self.invalid(
                        format!("{k}.size"),
                        format!("{:?}", r.size),
                        &format!(
                            "each cell's area ({area:e} m^2 with cells = {:?}) must be a finite, \
                             normal floating-point number",
                            r.cells
                        ),
                    ));
                }
                Ok(MeshSpec::Rectangle {
                    origin: r.origin,
                    size: r.size,
                    cells: [r.cells[0] as usize, r.cells[1] as usize],
                })
            }
            (None, Some(d)) => {
                let k = format!("{key}.disk");
                self.finite(&format!("{k}.center"), d.center[0])?;
                self.finite(&format!("{k}.center"), d.center[1])?;
                let radius = self.positive(&format!("{k}.radius"), d.radius)?;
                if d.cells < 2 || d.cells > 20_000 {
                    return Err(self.invalid(
                        format!("{k}.cells"),
                        d.cells.to_string(),
                        "must be between 2 and 20000 (cells along a quarter circumference)",
                    ));
                }
                let refine = match &d.refine {
                    None => None,
                    Some(r) => {
                        let rk = format!("{k}.refine");
                        let toward = self.unit(&format!("{rk}.toward"), r.toward)?;
                        if !(r.ratio.is_finite() && (1.0..=1000.0).contains(&r.ratio)) {
                            return Err(self.invalid(
                                format!("{rk}.ratio"),
                                r.ratio.to_string(),
                                "must be between 1 and 1000 (uniform rim spacing over the spacing at the refined point)",
                            ));
                        }
                        Some(DiskRefinement {
                            toward,
                            ratio: r.ratio,
                        })
                    }
                };
                Ok(MeshSpec::Disk {
                    center: d.center,
                    radius,
                    cells: d.cells as usize,
                    refine,
                })
            }
            _ => Err(self.invalid(
                key,
                "{...}",
                "give exactly one of `rectangle = {...}` or `disk = {...}`",
            )),
        }
    }

    fn boundary(&self, key: &str, b: &RawBoundary, bodies: &[Body]) -> Result<Boundary> {
        let body = bodies
            .iter()
            .position(|x| x.name == b.body)
            .ok_or_else(|| {
                let known: Vec<&str> = bodies.iter().map(|m| m.name.as_str()).collect();
                self.invalid(
                    format!("{key}.body"),
                    format!("{:?}", b.body),
                    &format!("no body of that name (defined: {known:?})"),
                )
            })?;
        let (min, max, group) = self.region(key, &b.region, &bodies[body], 0)?;
        if b.velocity.x.is_none() && b.velocity.y.is_none() {
            return Err(self.invalid(
                format!("{key}.velocity"),
                "{}",
                "prescribe at least one of `x` or `y`",
            ));
        }
        let vx = b
            .velocity
            .x
            .as_ref()
            .map(|v| self.value(&format!("{key}.velocity.x"), v))
            .transpose()?;
        let vy = b
            .velocity
            .y
            .as_ref()
            .map(|v| self.value(&format!("{key}.velocity.y"), v))
            .transpose()?;
        let split = |c: Option<LoadCurve>| match c {
            Some(c) if c.points.len() > 1 => (Some(c.at(0.0)), Some(c)),
            Some(c) => (Some(c.at(0.0)), None),
            None => (None, None),
        };
        let ((vx, curve_x), (vy, curve_y)) = (split(vx), split(vy));
        Ok(Boundary {
            body,
            min,
            max,
            vx,
            vy,
            curve_x,
            curve_y,
            group,
            key: key.to_string(),
        })
    }
}

impl Validator<'_> {
    /// A constant or a load curve `[[t0, v0], [t1, v1], ...]`: finite, at least one point of two
    /// numbers, times at least 0 and strictly increasing, at most [`MAX_CURVE_POINTS`] points.
    fn value(&self, key: &str, v: &RawValue) -> Result<LoadCurve> {
        let rows = match v {
            RawValue::Constant(x) => return Ok(LoadCurve::constant(self.finite(key, *x)?)),
            RawValue::Table(rows) => rows,
        };
        let shown = || {
            let s = format!("{rows:?}");
            s.chars().take(80).collect::<String>()
        };
        if rows.is_empty() || rows.len() > MAX_CURVE_POINTS {
            return Err(self.invalid(
                key,
                shown(),
                &format!("a load curve needs 1 to {MAX_CURVE_POINTS} [time, value] points"),
            ));
        }
        let mut points = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let ([t, x], true) = (
                [
                    r.first().copied().unwrap_or(f64::NAN),
                    r.get(1).copied().unwrap_or(f64::NAN),
                ],
                r.len() == 2,
            ) else {
                return Err(self.invalid(
                    format!("{key}[{i}]"),
                    format!("{r:?}"),
                    "each point is [time, value]",
                ));
            };
            if !(t.is_finite() && x.is_finite() && t >= 0.0) {
                return Err(self.invalid(
                    format!("{key}[{i}]"),
                    format!("{r:?}"),
                    "time and value must be finite, the time at least 0",
                ));
            }
            if let Some(prev) = points.last().map(|p: &[f64; 2]| p[0]) {
                if t <= prev {
                    return Err(self.invalid(
                        format!("{key}[{i}]"),
                        format!("{r:?}"),
                        &format!("times must increase (the point before is at {prev:e} s)"),
                    ));
                }
            }
            points.push([t, x]);
        }
        Ok(LoadCurve { points })
    }

    /// A box `{ min, max }` (finite, min <= max component-wise), or `{ group = "name" }`: a
    /// physical curve (or, where `min_dim` is 0, a point) of the Gmsh file `body` was read from,
    /// as that body's nodes and edges. Returns the box (unbounded for a group) and the group.
    fn region(
        &self,
        key: &str,
        r: &RawRegion,
        body: &Body,
        min_dim: i32,
    ) -> Result<([f64; 2], [f64; 2], Option<RegionGroup>)> {
        let rk = format!("{key}.region");
        if let Some(name) = &r.group {
            if r.min.is_some() || r.max.is_some() {
                return Err(self.invalid(
                    rk,
                    format!("{{ group = {name:?}, ... }}"),
                    "give either `group` or `min` and `max`, not both",
                ));
            }
            let gk = format!("{rk}.group");
            let MeshSpec::Gmsh { file, mesh, .. } = &body.mesh else {
                return Err(self.invalid(
                    gk,
                    format!("{name:?}"),
                    &format!(
                        "body {:?} is not read from a Gmsh file: a region by name is a physical \
                         curve or point of the body's mesh file",
                        body.name
                    ),
                ));
            };
            let Some(g) = mesh.groups.iter().find(|g| g.name == *name) else {
                let known: Vec<&str> = mesh.groups.iter().map(|g| g.name.as_str()).collect();
                return Err(self.invalid(
                    gk,
                    format!("{name:?}"),
                    &format!(
                        "{} has no physical curve or point of that name on body {:?} (there: {known:?})",
                        file.display(),
                        body.name
                    ),
                ));
            };
            if g.dim < min_dim {
                return Err(self.invalid(
                    gk,
                    format!("{name:?}"),
                    &format!(
                        "{}: group `{name}` is a physical point; a pressure needs a physical curve",
                        file.display()
                    ),
                ));
            }
            let group = RegionGroup {
                name: name.clone(),
                nodes: g.nodes.clone(),
                edges: g.edges.clone(),
            };
            return Ok(([f64::NEG_INFINITY; 2], [f64::INFINITY; 2], Some(group)));
        }
        let (Some(min), Some(max)) = (r.min, r.max) else {
            return Err(self.invalid(
                rk,
                "{...}",
                "give `min = [x, y]` and `max = [x, y]` (a box), or `group = \"name\"` (a physical \
                 curve or point of the body's Gmsh file)",
            ));
        };
        for i in 0..2 {
            self.finite(&format!("{rk}.min"), min[i])?;
            self.finite(&format!("{rk}.max"), max[i])?;
            if min[i] > max[i] {
                return Err(self.invalid(
                    rk,
                    format!("min = {min:?}, max = {max:?}"),
                    "min must not exceed max",
                ));
            }
        }
        Ok((min, max, None))
    }

    fn pressure(&self, key: &str, p: &RawPressure, bodies: &[Body]) -> Result<Pressure> {
        let body = self.body_index(&format!("{key}.body"), &p.body, bodies)?;
        let (min, max, group) = self.region(key, &p.region, &bodies[body], 1)?;
        let curve = self.value(&format!("{key}.value"), &p.value)?;
        let value = curve.at(0.0);
        let curve = (curve.points.len() > 1).then_some(curve);
        let ramp = p
            .ramp
            .map(|r| self.positive(&format!("{key}.ramp"), r))
            .transpose()?;
        if ramp.is_some() && curve.is_some() {
            return Err(self.invalid(
                format!("{key}.ramp"),
                fmt_num(ramp.unwrap_or(0.0)),
                "a load curve (`value = [[t, p], ...]`) gives its own ramp: drop `ramp`",
            ));
        }
        Ok(Pressure {
            body,
            min,
            max,
            value,
            ramp,
            curve,
            group,
            key: key.to_string(),
        })
    }
}

/// Builds an [`Error::Invalid`] for `scene` (used by later validation stages such as meshing).
pub fn invalid(
    scene: &Scene,
    key: impl Into<String>,
    value: impl Into<String>,
    reason: &str,
) -> Error {
    Error::Invalid {
        file: scene.file.clone(),
        key: key.into(),
        value: value.into(),
        reason: reason.to_string(),
    }
}
