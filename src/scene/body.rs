//! `[[body]]`: bodies (README, "Scene format", `[[body]]`): the raw table, [`Body`] with its
//! [`Formulation`] and hourglass control ([`Hourglass`], [`HourglassForm`]), body names, and
//! their validation; the `mesh` key is in `mesh.rs`. Host-side only, no GPU twin.

use serde::Deserialize;

use super::fixed;
use super::material::{Material, MaterialModel};
use super::mesh::{MeshSpec, RawMesh};
use super::validate::{fmt_num, shown_name, Validator};
use crate::error::Result;

/// Longest body name (bytes).
pub const NAME_MAX: usize = 64;

/// Default hourglass coefficient.
pub const DEFAULT_HOURGLASS_COEFFICIENT: f64 = 0.1;

/// A `[[body]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBody {
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

/// The `hourglass` table of a body.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHourglass {
    form: Option<String>,
    coefficient: Option<f64>,
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

/// A body, validated.
#[derive(Debug, Clone)]
pub struct Body {
    /// Name.
    pub name: String,
    /// Index into [`Scene::materials`](super::Scene::materials).
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

impl Validator<'_> {
    /// The `[[body]]` tables, in order: at least one; names valid ([`NAME_MAX`]) and distinct.
    pub(super) fn bodies(&self, raw: &[RawBody], materials: &[Material]) -> Result<Vec<Body>> {
        if raw.is_empty() {
            return Err(self.invalid("body", "[]", "a scene needs at least one [[body]]"));
        }
        let mut bodies: Vec<Body> = Vec::new();
        for (i, b) in raw.iter().enumerate() {
            let key = format!("body[{i}]");
            self.check_name(&format!("{key}.name"), &b.name)?;
            if bodies.iter().any(|o| o.name == b.name) {
                return Err(self.invalid(
                    format!("{key}.name"),
                    format!("{:?}", b.name),
                    "duplicate body name",
                ));
            }
            bodies.push(self.body(&key, b, materials)?);
        }
        Ok(bodies)
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
        Err(self.invalid(
            key,
            shown_name(name),
            &format!(
                "a name must be 1 to {NAME_MAX} ASCII letters, digits, `_`, `-` or `.`, not \
                 starting with `.` or `-` (names become file names and history.csv columns)"
            ),
        ))
    }

    fn body(&self, key: &str, b: &RawBody, materials: &[Material]) -> Result<Body> {
        let material = self.index_of(
            &format!("{key}.material"),
            &b.material,
            "material",
            materials.iter().map(|m| m.name.as_str()),
        )?;
        let formulation = self.keyword(
            &format!("{key}.formulation"),
            b.formulation.as_deref(),
            &[
                ("plane_strain", Formulation::PlaneStrain),
                ("plane_stress", Formulation::PlaneStress),
                ("axisymmetric", Formulation::Axisymmetric),
            ],
            "expected \"plane_strain\", \"plane_stress\" or \"axisymmetric\"",
        )?;
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
        self.finite_all(&format!("{key}.initial_velocity"), &v0)?;
        let angular_velocity = self.finite(
            &format!("{key}.angular_velocity"),
            b.angular_velocity.unwrap_or(0.0),
        )?;
        let velocity_gradient = b.velocity_gradient.unwrap_or([[0.0; 2]; 2]);
        self.finite_all(
            &format!("{key}.velocity_gradient"),
            velocity_gradient.as_flattened(),
        )?;
        let hourglass = match &b.hourglass {
            None => Hourglass {
                form: HourglassForm::Viscous,
                coefficient: DEFAULT_HOURGLASS_COEFFICIENT,
            },
            Some(h) => {
                let form = self.keyword(
                    &format!("{key}.hourglass.form"),
                    h.form.as_deref(),
                    &[
                        ("viscous", HourglassForm::Viscous),
                        ("stiffness", HourglassForm::Stiffness),
                        ("none", HourglassForm::None),
                    ],
                    "expected \"viscous\", \"stiffness\" or \"none\"",
                )?;
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
}
