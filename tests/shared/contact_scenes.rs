//! Contact scenes and measurements shared by the CPU (`tests/core/contact.rs`) and GPU
//! (`tests/gpu/contact.rs`) contact tests: REFERENCES.md sections 1 and 5 and the corner-first square.
#![allow(dead_code)]

use ricochet::model::Model;
use ricochet::output::summary::Summary;
use ricochet::step::Sample;

use crate::scene_text::{fixed_step_run, STEEL, STEEL_NU0};

/// Steel: Young's modulus (Pa) and density (kg/m^3).
const E_STEEL: f64 = 210e9;
const RHO_STEEL: f64 = 7850.0;

pub const A: f64 = 1e-4; // rod cross-section (m^2): height h (one square element) x thickness A / h
pub const L: f64 = 1.0; // rod length (m)
pub const V0: f64 = 10.0;

pub fn bar_speed() -> f64 {
    (E_STEEL / RHO_STEEL).sqrt()
}

/// Two rods (or one rod and a wall) of n square plane-stress elements at 1D Courant number 0.9,
/// touching at t = 0, one history row per step. `target` is the target's area relative to the
/// striker's (None: a rigid wall at x = 0 instead).
pub fn rod_scene(
    n: usize,
    target: Option<f64>,
    method: &str,
    extra: &str,
    end_factor: f64,
) -> String {
    let h = L / n as f64;
    let t = A / h;
    let dt = 0.9 * h / bar_speed();
    let run = fixed_step_run(end_factor * 2.0 * L / bar_speed(), dt);
    let mut s = format!(
        r#"
{run}

{STEEL_NU0}

[[body]]
name = "striker"
material = "steel"
formulation = "plane_stress"
thickness = {t:e}
mesh = {{ rectangle = {{ origin = [-{L}, 0.0], size = [{L}, {h:e}], cells = [{n}, 1] }} }}
initial_velocity = [{V0}, 0.0]
hourglass = {{ form = "stiffness", coefficient = 0.1 }}
"#
    );
    match target {
        Some(ratio) => s.push_str(&format!(
            r#"
[[body]]
name = "target"
material = "steel"
formulation = "plane_stress"
thickness = {t2:e}
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{L}, {h:e}], cells = [{n}, 1] }} }}
hourglass = {{ form = "stiffness", coefficient = 0.1 }}

[[contact]]
bodies = ["striker", "target"]
method = "{method}"
{extra}
"#,
            t2 = ratio * t
        )),
        None => s.push_str(&format!(
            r#"
[[rigid_wall]]
point = [0.0, 0.0]
normal = [-1.0, 0.0]
method = "{method}"
{extra}
"#
        )),
    }
    s
}

/// Contact duration in steps (first to last step with a force, inclusive), the steps without
/// force inside it (chatter) and the median force over it.
pub fn contact_window(samples: &[(Sample, f64)]) -> (usize, usize, f64) {
    let f: Vec<f64> = samples
        .iter()
        .map(|(s, _)| s.contacts[0].force[0])
        .collect();
    let first = f.iter().position(|x| *x != 0.0).expect("a contact force");
    let last = f.iter().rposition(|x| *x != 0.0).expect("a contact force");
    let chatter = f[first..=last].iter().filter(|x| **x == 0.0).count();
    let mut inside: Vec<f64> = f[first..=last].iter().map(|x| x.abs()).collect();
    inside.sort_by(f64::total_cmp);
    (last - first + 1, chatter, inside[inside.len() / 2])
}

pub fn momentum(model: &Model, s: &Sample) -> f64 {
    model
        .bodies
        .iter()
        .zip(&s.body_velocity)
        .map(|(b, v)| b.mass * v[0])
        .sum()
}

/// A square of `cells` x `cells` elements and side `side`, turned by 45 degrees, its lowest corner
/// at (0, gap), falling at `v` onto a wall y = 0.
pub fn diamond_scene(cells: usize, side: f64, gap: f64, v: f64, method: &str) -> String {
    let c = std::f64::consts::FRAC_1_SQRT_2;
    let mut nodes = Vec::new();
    for j in 0..=cells {
        for i in 0..=cells {
            let (x, y) = (
                side * i as f64 / cells as f64,
                side * j as f64 / cells as f64,
            );
            // Rotate by 45 degrees about the origin: corner (0, 0) stays the lowest.
            nodes.push(format!("[{:e}, {:e}]", c * (x - y), c * (x + y) + gap));
        }
    }
    let mut quads = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            let a = j * (cells + 1) + i;
            quads.push(format!(
                "[{}, {}, {}, {}]",
                a,
                a + 1,
                a + cells + 2,
                a + cells + 1
            ));
        }
    }
    let dt = 0.5 * side / cells as f64 / 6000.0;
    format!(
        r#"
[run]
end_time = {end:e}
history_interval = {dt:e}
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

{STEEL}

[[body]]
name = "square"
material = "steel"
mesh = {{ nodes = [{nodes}], quads = [{quads}] }}
initial_velocity = [0.0, {v}]
hourglass = {{ form = "stiffness", coefficient = 0.1 }}

[[rigid_wall]]
point = [0.0, 0.0]
normal = [0.0, 1.0]
method = "{method}"
"#,
        end = 8.0 * side / 5000.0,
        nodes = nodes.join(", "),
        quads = quads.join(", "),
    )
}

/// The disk-on-a-wall asset at speed `v0`.
pub fn disk_text(v0: f64) -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/disk_wall.toml"
    ))
    .expect("read assets/disk_wall.toml")
    .replace(
        "initial_velocity = [1.0, 0.0]",
        &format!("initial_velocity = [{v0:e}, 0.0]"),
    )
}

/// The disk on the wall of [`disk_text`] meshed by Gmsh (`assets/disk_wall_gmsh.toml`, its mesh
/// file given by absolute path so that the text parses from anywhere).
pub fn disk_gmsh_text(v0: f64) -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/disk_wall_gmsh.toml"
    ))
    .expect("read assets/disk_wall_gmsh.toml")
    .replace(
        "initial_velocity = [1.0, 0.0]",
        &format!("initial_velocity = [{v0:e}, 0.0]"),
    )
    .replace(
        "gmsh = \"gmsh/disk.msh\"",
        &format!(
            "gmsh = {:?}",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/gmsh/disk.msh")
        ),
    )
}

/// The disk on the wall of [`disk_gmsh_text`] meshed by Gmsh into triangles only
/// (`tests/data/gmsh/disk_triangles.msh`, from its `.geo` beside it).
pub fn disk_triangles_text(v0: f64) -> String {
    disk_gmsh_text(v0).replace(
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/gmsh/disk.msh"),
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/gmsh/disk_triangles.msh"
        ),
    )
}

/// Contact time, peak force (N/m), centre-of-mass restitution and the largest total-energy drift
/// relative to E0 = M v0^2 / 2 of a disk-on-wall run's samples.
pub fn disk_metrics(samples: &[Sample], mass: f64, v0: f64) -> (f64, f64, f64, f64) {
    let e0 = 0.5 * mass * v0 * v0;
    let f: Vec<f64> = samples.iter().map(|s| s.contacts[0].force[0]).collect();
    let first = f.iter().position(|x| *x != 0.0).expect("contact");
    let last = f.iter().rposition(|x| *x != 0.0).expect("contact");
    // Rows are history intervals ending at their time: the contact spans from the start of the
    // first row with a force to the end of the last.
    let interval = samples[1].time - samples[0].time;
    let duration = samples[last].time - samples[first].time + interval;
    let peak = f.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let e = -samples.last().expect("rows").body_velocity[0][0] / v0;
    let drift = samples
        .iter()
        .map(|s| ((s.kinetic + s.internal + s.hourglass) / e0 - 1.0).abs())
        .fold(0.0, f64::max);
    (duration, peak, e, drift)
}

/// REFERENCES.md section 5: (v0, contact time, peak force, restitution).
pub const DISK_CASES: [(f64, f64, f64, f64); 2] = [
    (1.0, 89.5e-6, 2.25e6, 0.992),
    (10.0, 77.1e-6, 26.5e6, 0.980),
];

/// The `penalty_scale` that gives omega dt = `omega_dt` for the rods of `rod_scene(n, Some(1.0), ..)`.
/// Interface stiffness k = s K t L^2 / A_e with K = E/2 (plane stress, nu = 0) and square elements:
/// k = s E t / 2 (two passes, half each), per face node k/2 against its partner:
/// omega^2 = (k/2) (2 / m_node), m_node = rho h^2 t / 4.
pub fn penalty_scale_for(n: usize, omega_dt: f64) -> f64 {
    let h = L / n as f64;
    let t = A / h;
    let dt = 0.9 * h / bar_speed();
    let m_node = RHO_STEEL * h * h * t / 4.0;
    let omega = omega_dt / dt;
    omega * omega * m_node / (E_STEEL * t / 2.0)
}

/// The identical rods of [`rod_scene`] (`n` cells each, run for twice the wave's round trip)
/// with penalty contact at omega dt = 0.3: the penalty scale and the scene.
pub fn penalty_rods(n: usize) -> (f64, String) {
    let s = penalty_scale_for(n, 0.3);
    let text = rod_scene(
        n,
        Some(1.0),
        "penalty",
        &format!("penalty_scale = {s:e}"),
        2.0,
    );
    (s, text)
}

/// The restitution of two rods' impact at the history row `row`: (v2 - v1) / V0.
pub fn restitution(row: &Sample) -> f64 {
    (row.body_velocity[1][0] - row.body_velocity[0][0]) / V0
}

/// Identical rods at n = 20 with penalty contact at omega dt = 0.3 (s = 1/18, as the rods
/// verification case), run to 1.5 x 2L/c: well after separation.
pub fn penalty_release_scene() -> String {
    rod_scene(
        20,
        Some(1.0),
        "penalty",
        &format!("penalty_scale = {:e}", 1.0 / 18.0),
        1.5,
    )
}

/// The short striker of REFERENCES.md section 1 as the issue measured it: aluminium (E = 70 GPa,
/// rho = 2700, c = 5091.75 m/s), plane stress, nu = 0, one row of square cells of 1.25 mm,
/// L1 = 0.05 m (40 cells) at 7 m/s onto L2 = 0.1 m (80 cells); contact with `keys` (method
/// included) at the default step. Exact: contact for 2 L1 / c = 19.640 us, then the striker at
/// rest and the target at v0 L1 / L2 = 3.5 m/s.
pub fn short_striker_scene(keys: &str) -> String {
    format!(
        r#"
[run]
end_time = 6.0e-5
history_interval = 1.0e-7
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

[[material]]
name = "aluminium"
model = "linear_elastic"
density = 2700.0
youngs_modulus = 7.0e10
poisson_ratio = 0.0

[[body]]
name = "striker"
material = "aluminium"
formulation = "plane_stress"
thickness = 0.01
mesh = {{ rectangle = {{ origin = [-0.05, 0.0], size = [0.05, 0.00125], cells = [40, 1] }} }}
initial_velocity = [7.0, 0.0]
hourglass = {{ form = "stiffness", coefficient = 0.1 }}

[[body]]
name = "target"
material = "aluminium"
formulation = "plane_stress"
thickness = 0.01
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [0.1, 0.00125], cells = [80, 1] }} }}
hourglass = {{ form = "stiffness", coefficient = 0.1 }}

[[contact]]
bodies = ["striker", "target"]
{keys}
"#
    )
}

/// The short striker's exact contact time 2 L1 / c (s) and target velocity (m/s).
pub const SHORT_STRIKER: (f64, f64) = (19.640e-6, 3.5);

/// (contact time from the first to the last row whose force exceeds 1 % of the peak, plus one
/// row; striker and target velocities at the end) of a short-striker run.
pub fn short_striker_figures(samples: &[Sample]) -> (f64, f64, f64) {
    let f: Vec<f64> = samples
        .iter()
        .map(|s| s.contacts[0].force[0].abs())
        .collect();
    let peak = f.iter().fold(0.0f64, |m, &x| m.max(x));
    let on: Vec<f64> = samples
        .iter()
        .zip(&f)
        .filter(|(_, &x)| x > 0.01 * peak)
        .map(|(s, _)| s.time)
        .collect();
    let interval = samples[1].time - samples[0].time;
    let last = samples.last().expect("rows");
    (
        on[on.len() - 1] - on[0] + interval,
        last.body_velocity[0][0],
        last.body_velocity[1][0],
    )
}

/// The run of a fixed step above the rods' penalty limit failed with the diagnostic naming it.
pub fn assert_penalty_step_refused(summary: &Summary) {
    assert_eq!(summary.status, "failed");
    assert!(
        summary.message.contains("exceeds the stable step")
            && summary
                .message
                .contains("penalty springs of contact \"striker-target\""),
        "{}",
        summary.message
    );
}

/// The `[run]` (8 us, a history row every 0.1 us) and steel `[[material]]` tables of
/// [`DIMPLE`] and [`CORNER_PASS`].
macro_rules! small_steel_run {
    () => {
        r#"
[run]
end_time = 8.0e-6
history_interval = 1.0e-7

[[material]]
name = "steel"
model = "linear_elastic"
density = 7850.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3
"#
    };
}

/// A cone `tip` (axisymmetric, its apex on the axis) strikes at 200 m/s the held `rod`, whose nose
/// rises from its rim (r = 1 mm) to its axis node 0.5 mm above it (a dimple); one pass, the tip's
/// nodes the slaves. The tip's apex meets the rod's axis node 1 mm before the rims could meet, and
/// must stop there ([`apex_inside`]). Past the end of the nose's segment it meets the vertex that
/// the segment makes with its mirror image across the axis (`ricochet::contact::rules::project`);
/// without it the apex went on into the rod and ended 0.68 mm inside it (2026-11-28).
pub const DIMPLE: &str = concat!(
    small_steel_run!(),
    r#"
[[body]]
name = "rod"
material = "steel"
formulation = "axisymmetric"
mesh = { nodes = [[0.0, 5.0e-4], [1.0e-3, 0.0], [1.0e-3, 2.0e-3], [0.0, 2.0e-3]], quads = [[0, 1, 2, 3]] }

[[body]]
name = "tip"
material = "steel"
formulation = "axisymmetric"
mesh = { nodes = [[0.0, -2.5e-3], [1.0e-3, -2.5e-3], [1.0e-3, -1.05e-3], [0.0, -5.0e-5]], quads = [[0, 1, 2, 3]] }
initial_velocity = [0.0, 200.0]

[[boundary]]
body = "rod"
region = { min = [-1.0, -1.0], max = [1.0, 1.0] }
velocity = { x = 0.0, y = 0.0 }

[[contact]]
bodies = ["tip", "rod"]
method = "lagrange"
two_pass = false
"#
);

/// How far [`DIMPLE`]'s tip apex (node 7) ended above the rod's axis node (node 0) at the
/// displacements `u` (m; positive: inside the rod).
pub fn apex_inside(model: &Model, u: &[[f64; 2]]) -> f64 {
    let y = |n: usize| model.position[n][1] + u[n][1];
    assert!(model.position[0][0] == 0.0 && model.position[7][0] == 0.0);
    y(7) - y(0)
}

/// A block falls at 10 m/s past the apex of a held wedge (one pass, the block's nodes the slaves):
/// its middle bottom node starts 20 um above the apex and 50 um to the right of it, inside the
/// wedge's left side's line (the side leans out, down to the left) but above its top face, which
/// falls away to the right at 1 in 2. The node passes the apex's level outside the wedge and
/// lands on the top face at 4.5 us. Taken as penetrating the side (behind its line by 50 um,
/// projecting onto it once it is below the apex), it was thrown to the left: the block's mean
/// x velocity -492 m/s, and the run stopped on its energy balance (2026-11-28). The convex
/// corner's rule (`ricochet::contact::rules::outside_convex_corner`) leaves it alone.
pub const CORNER_PASS: &str = concat!(
    small_steel_run!(),
    r#"
[[body]]
name = "wedge"
material = "steel"
mesh = { nodes = [[-1.0e-4, -2.0e-3], [1.0e-3, -2.0e-3], [1.0e-3, -5.0e-4], [0.0, 0.0]], quads = [[0, 1, 2, 3]] }

[[body]]
name = "block"
material = "steel"
mesh = { nodes = [[-9.5e-4, 2.0e-5], [5.0e-5, 2.0e-5], [1.05e-3, 2.0e-5], [-9.5e-4, 1.02e-3], [5.0e-5, 1.02e-3], [1.05e-3, 1.02e-3]], quads = [[0, 1, 4, 3], [1, 2, 5, 4]] }
initial_velocity = [0.0, -10.0]

[[boundary]]
body = "wedge"
region = { min = [-1.0, -1.0], max = [1.0, 1.0] }
velocity = { x = 0.0, y = 0.0 }

[[contact]]
bodies = ["block", "wedge"]
method = "lagrange"
two_pass = false
"#
);

/// [`CORNER_PASS`]'s run: the block's smallest mean x velocity over the rows (m/s; negative: thrown
/// to the left) and whether it met the wedge's top face (a contact force along the face's normal,
/// (1, 2) / sqrt 5, in some row).
pub fn corner_pass(samples: &[Sample]) -> (f64, bool) {
    let left = samples
        .iter()
        .map(|s| s.body_velocity[1][0])
        .fold(f64::INFINITY, f64::min);
    let landed = samples.iter().any(|s| {
        let f = s.contacts[0].force;
        f[1] > 0.0 && (f[1] - 2.0 * f[0]).abs() < 1e-3 * f[1]
    });
    (left, landed)
}
