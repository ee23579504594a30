//! The contact patch test scene of `REFERENCES.md` section 3 (Taylor & Papadopoulos 1991), shared
//! by the CPU (`tests/core/patch_contact.rs`) and GPU (`tests/gpu/patch.rs`) tests: two plane-strain
//! steel blocks touching along y = 0.5 with non-matching meshes, a uniform pressure p = 1e-3 E on the
//! top edge ramped slowly, mass damping, u_y = 0 at y = 0 and u_x = 0 on x = 0.
#![allow(dead_code)]

use ricochet::model::Model;
use ricochet::output::fields::element_fields;

/// Young's modulus of the steel blocks (Pa).
const E_STEEL: f64 = 210e9;
/// Density of the steel blocks (kg/m^3).
const RHO_STEEL: f64 = 7850.0;

/// The meshes (lower, upper elements along x) of the reference.
pub const MESHES: [(usize, usize); 3] = [(4, 3), (5, 4), (8, 6)];

/// The applied pressure, 1e-3 E.
pub const P: f64 = 1e-3 * E_STEEL;

/// Dilatational wave speed of plane-strain steel with nu = 0.3 (m/s).
fn dilatational_speed() -> f64 {
    let nu: f64 = 0.3;
    (E_STEEL * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu) * RHO_STEEL)).sqrt()
}

/// The two-block scene: `lower` and `upper` elements along x; `first` is the contact's first body
/// (the slave nodes of the first pass); `contact` holds the method keys.
pub fn scene(lower: usize, upper: usize, first: &str, contact: &str) -> String {
    let second = if first == "upper" { "lower" } else { "upper" };
    // Ramp over about 12 transits of the 1 m column, then hold; the mass damping alpha = 1.2e4 1/s
    // is about critical for the lowest (quarter-wave) modes (omega ~ pi c / 2 ~ 8.5e3 rad/s), and
    // every underdamped mode decays at alpha / 2 at least. 10 ms: the velocities have died out
    // (kinetic energy below 1e-9 of the strain energy).
    let transit = 1.0 / dilatational_speed();
    let ramp = 12.0 * transit;
    format!(
        r#"
[run]
end_time = 1.0e-2
history_interval = 1.0e-3
mass_damping = 1.2e4

[[material]]
name = "steel"
model = "linear_elastic"
density = {RHO_STEEL}
youngs_modulus = {E_STEEL:e}
poisson_ratio = 0.3

[[body]]
name = "upper"
material = "steel"
formulation = "plane_strain"
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
mesh = {{ rectangle = {{ origin = [0.0, 0.5], size = [1.0, 0.5], cells = [{upper}, 2] }} }}

[[body]]
name = "lower"
material = "steel"
formulation = "plane_strain"
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [1.0, 0.5], cells = [{lower}, 2] }} }}

[[contact]]
bodies = ["{first}", "{second}"]
name = "interface"
{contact}

[[pressure]]
body = "upper"
region = {{ min = [-0.01, 0.99], max = [1.01, 1.01] }}
value = {P:e}
ramp = {ramp:e}

[[boundary]]
body = "lower"
region = {{ min = [-0.01, -0.01], max = [1.01, 0.01] }}
velocity = {{ y = 0.0 }}

[[boundary]]
body = "lower"
region = {{ min = [-0.01, -0.01], max = [0.01, 0.51] }}
velocity = {{ x = 0.0 }}

[[boundary]]
body = "upper"
region = {{ min = [-0.01, 0.49], max = [0.01, 1.01] }}
velocity = {{ x = 0.0 }}
"#
    )
}

/// Largest |sigma_yy + p|, |sigma_xx|, |sigma_xy| over all elements, over p, for displacement `u`.
pub fn stress_error(model: &Model, u: &[[f64; 2]]) -> f64 {
    let mut err = 0.0f64;
    for e in 0..model.element_count() {
        let [sxx, syy, sxy, _] = element_fields(model, u, e).stress;
        err = err
            .max((syy + P).abs() / P)
            .max(sxx.abs() / P)
            .max(sxy.abs() / P);
    }
    err
}
