//! Scenes with Coulomb friction, shared by the core and GPU suites (REFERENCES.md section 7):
//! the steel block (20 x 10 mm, plane strain) sliding at 1 m/s under g = 981 m/s^2, on a rigid
//! floor or on a second, clamped block (node-to-segment contact), mu = 0.3, with Lagrange or
//! penalty contact (penalty friction: the Curnier-Mroz spring): it decelerates at
//! mu g = 294.3 m/s^2.

use crate::scene_text::STEEL;

/// Gravity (m/s^2).
pub const G: f64 = 981.0;
/// Coulomb coefficient.
pub const MU: f64 = 0.3;

/// The block sliding at 1 m/s for `end_time` on a rigid floor with friction, by `method`.
pub fn block_on_floor(end_time: f64, method: &str) -> String {
    format!(
        "{}\n[[rigid_wall]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n\
         method = \"{method}\"\nfriction = {MU}\n",
        header(end_time)
    )
}

/// The block sliding at 1 m/s for `end_time` on a 60 x 5 mm base block (10 x 2 quads) whose
/// lower edge is clamped: two-pass contact with friction between them, by `method`.
pub fn block_on_block(end_time: f64, method: &str) -> String {
    format!(
        "{}\n[[body]]\nname = \"base\"\nmaterial = \"steel\"\nformulation = \"plane_strain\"\n\
         mesh = {{ rectangle = {{ origin = [-0.02, -0.005], size = [0.06, 0.005], cells = [10, 2] }} }}\n\
         hourglass = {{ form = \"stiffness\", coefficient = 0.1 }}\n\n\
         [[boundary]]\nbody = \"base\"\nregion = {{ min = [-1.0, -0.0051], max = [1.0, -0.0049] }}\n\
         velocity = {{ x = 0.0, y = 0.0 }}\n\n\
         [[contact]]\nname = \"sliding\"\nbodies = [\"block\", \"base\"]\nmethod = \"{method}\"\n\
         friction = {MU}\n",
        header(end_time)
    )
}

/// The five sliding cases both backends run for `end_time`, named: on the floor and on the
/// clamped block, each by Lagrange and by penalty contact, and on the floor by penalty with a
/// tangent spring a quarter as stiff (`friction_stiffness = 0.25`).
pub fn sliding_cases(end_time: f64) -> [(&'static str, String); 5] {
    [
        ("floor", block_on_floor(end_time, "lagrange")),
        ("block", block_on_block(end_time, "lagrange")),
        ("floor, penalty", block_on_floor(end_time, "penalty")),
        ("block, penalty", block_on_block(end_time, "penalty")),
        (
            "floor, penalty, softer tangent",
            block_on_floor(end_time, "penalty") + "friction_stiffness = 0.25\n",
        ),
    ]
}

fn header(end_time: f64) -> String {
    format!(
        r#"[run]
end_time = {end_time:e}
history_interval = 2.0e-5
gravity = [0.0, {g:e}]

{STEEL}

[[body]]
name = "block"
material = "steel"
formulation = "plane_strain"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [0.02, 0.01], cells = [8, 4] }} }}
initial_velocity = [1.0, 0.0]
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
"#,
        g = -G
    )
}
