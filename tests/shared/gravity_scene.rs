//! Scenes with gravity, shared by the core and GPU suites: a steel block 20 x 10 mm (plane
//! strain) under g = 981 m/s^2 (REFERENCES.md section 7's block), falling freely or resting on
//! a rigid wall at y = 0.

use crate::scene_text::STEEL;

/// Gravity (m/s^2, along -y).
pub const G: f64 = 981.0;

/// The block of 8 x 4 quads with its lower edge at `y0`, under gravity `[0, -G]`, run to
/// `end_time` with the fixed step `dt` (0: the stable step) and `rows` history rows, a rigid
/// Lagrange wall at y = 0 when `wall`.
pub fn block_scene(y0: f64, end_time: f64, dt: f64, rows: usize, wall: bool) -> String {
    let step = if dt > 0.0 {
        format!("time_step = {dt:e}\n")
    } else {
        String::new()
    };
    let wall = if wall {
        "\n[[rigid_wall]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\nmethod = \"lagrange\"\n"
    } else {
        ""
    };
    format!(
        r#"
[run]
end_time = {end_time:e}
{step}history_interval = {h:e}
gravity = [0.0, {g:e}]
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

{STEEL}

[[body]]
name = "block"
material = "steel"
formulation = "plane_strain"
mesh = {{ rectangle = {{ origin = [0.0, {y0:e}], size = [0.02, 0.01], cells = [8, 4] }} }}
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
{wall}"#,
        h = end_time / rows as f64,
        g = -G
    )
}
