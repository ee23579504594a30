//! The pulled bar of the load-curve tests (`tests/core/load_curve.rs`, and on the GPU in
//! `tests/gpu.rs`): REFERENCES.md section 1's steel strip, left end held, right end pulled at a
//! velocity written as `velocity` (a number or a load curve).
#![allow(dead_code)]

pub const E: f64 = 2.1e11;
pub const RHO: f64 = 7850.0;
pub const L: f64 = 1.0;
pub const H: f64 = 0.025;
pub const T: f64 = 0.004;
pub const V: f64 = 1.0;
pub const RAMP: f64 = 2.0e-5;
pub const CELLS: usize = 200;

/// The bar scene with the right end's x velocity `velocity`.
pub fn bar_scene(velocity: &str) -> String {
    format!(
        r#"[run]
end_time = 3.5e-4
time_step = 8.0e-7
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

[[material]]
name = "steel"
model = "linear_elastic"
density = {RHO}
youngs_modulus = {E:e}
poisson_ratio = 0.0

[[body]]
name = "bar"
material = "steel"
formulation = "plane_stress"
thickness = {T}
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{L}, {H}], cells = [{CELLS}, 1] }} }}
hourglass = {{ form = "stiffness", coefficient = 0.1 }}

[[boundary]]
body = "bar"
region = {{ min = [-1e-9, -1.0], max = [1e-9, 1.0] }}
velocity = {{ x = 0.0 }}

[[boundary]]
body = "bar"
region = {{ min = [{L0}, -1.0], max = [{L1}, 1.0] }}
velocity = {{ x = {velocity} }}
"#,
        L0 = L - 1e-9,
        L1 = L + 1e-9,
    )
}
