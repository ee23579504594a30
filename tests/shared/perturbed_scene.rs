//! The perturbed Lagrangian's defining property (Belytschko X.5.8), shared by the core and GPU
//! suites: one steel quad resting on a rigid wall under gravity (ramped in, mass damping), its
//! two base nodes the only contact nodes, so that their reactions follow from statics alone
//! (R0 + R1 = W, R1 l = sum m_i g x_i). The node-by-node penalty gives each base node
//! p_i = R_i / k; the perturbed Lagrangian the consistent nodal forces of the linear penetration,
//! R = (k / 3) [[2, 1], [1, 2]] p, so p = (1 / k) [[2, -1], [-1, 2]] R: the same sum, three times
//! the difference. A trapezoid (top edge from x = 0 to 0.6) puts its weight off the base's centre;
//! a rectangle does not (both methods then give the same uniform penetration).

use crate::scene_text::STEEL;

/// Gravity (m/s^2, along -y).
pub const G: f64 = 981.0;

/// Base width (m): the base nodes are at x = 0 and x = L, y = 0.
pub const L: f64 = 1.0;

/// The quad (top edge from x = 0 to `top`, height 0.5 m) on a wall at y = 0 with `method` at
/// penalty scale 1 (stiffness hourglass control, since the one-point quad carries its weight
/// off-centre), run for 50 ms: 2 ms of gravity ramp, then mass damping settles it.
pub fn quad_on_wall(method: &str, top: f64) -> String {
    format!(
        r#"
[run]
end_time = 5.0e-2
history_interval = 5.0e-3
mass_damping = 3.0e3
gravity = [0.0, {g:e}]
gravity_ramp = 2.0e-3

{STEEL}

[[body]]
name = "block"
material = "steel"
formulation = "plane_strain"
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
mesh = {{ nodes = [[0.0, 0.0], [{l:?}, 0.0], [{top:?}, 0.5], [0.0, 0.5]], quads = [[0, 1, 2, 3]] }}

[[rigid_wall]]
name = "floor"
point = [0.0, 0.0]
normal = [0.0, 1.0]
method = "{method}"
penalty_scale = 1.0
"#,
        g = -G,
        l = L,
    )
}

/// The same quad on a steel base instead of the wall (one pass: the quad's nodes against the
/// base's segments, the node-to-segment path), the base 2 m x 0.5 m in 4 x 1 quads from
/// x = -0.25 (so that the quad's base nodes fall mid-segment), its bottom edge held.
pub fn quad_on_base(method: &str, top: f64) -> String {
    let wall = quad_on_wall(method, top);
    let cut = wall.find("[[rigid_wall]]").expect("wall table");
    format!(
        r#"{}
[[body]]
name = "base"
material = "steel"
formulation = "plane_strain"
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
mesh = {{ rectangle = {{ origin = [-0.25, -0.5], size = [2.0, 0.5], cells = [4, 1] }} }}

[[boundary]]
body = "base"
region = {{ min = [-1.0, -0.51], max = [2.0, -0.49] }}
velocity = {{ x = 0.0, y = 0.0 }}

[[contact]]
bodies = ["block", "base"]
two_pass = false
method = "{method}"
penalty_scale = 1.0
"#,
        &wall[..cut]
    )
}

/// The reactions of the wall on base nodes 0 and 1 from statics: the nodes' weights m_i g at
/// their positions `x` (the model's nodes, in mesh order).
pub fn reactions(mass: &[f64], x: &[[f64; 2]]) -> [f64; 2] {
    let w: f64 = mass.iter().map(|m| m * G).sum();
    let moment: f64 = mass.iter().zip(x).map(|(m, p)| m * G * p[0]).sum();
    let r1 = moment / L;
    [w - r1, r1]
}

/// The penetrations of base nodes 0 and 1 from the displacements: below y = 0 (the wall), or,
/// with a base (nodes after the quad's four), below the base's top edge, interpolated between
/// its nodes at the reference positions `x`.
pub fn penetrations(x: &[[f64; 2]], u: &[[f64; 2]]) -> [f64; 2] {
    let top: Vec<usize> = (4..x.len()).filter(|&i| x[i][1] == 0.0).collect();
    [0, 1].map(|i| {
        let xi = x[i][0];
        let surface = top
            .iter()
            .flat_map(|&a| top.iter().map(move |&b| (a, b)))
            .find(|&(a, b)| x[a][0] <= xi && xi < x[b][0] && x[b][0] - x[a][0] <= 0.5 + 1e-12)
            .map_or(0.0, |(a, b)| {
                let t = (xi - x[a][0]) / (x[b][0] - x[a][0]);
                (1.0 - t) * u[a][1] + t * u[b][1]
            });
        surface - u[i][1]
    })
}

/// (p0 - p1) / (p0 + p1): the tilt of the base over its mean penetration.
pub fn tilt(p: [f64; 2]) -> f64 {
    (p[0] - p[1]) / (p[0] + p[1])
}
