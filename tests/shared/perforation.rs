//! A projectile perforating a plate (plane strain, eroding contact) and the check that no node
//! ends inside a remaining element, shared by the CPU reference's tests
//! (`tests/core/erosion_contact.rs`) and the GPU's (`tests/gpu/erosion_contact.rs`).
#![allow(dead_code)]

use ricochet::model::Model;

/// A steel with a plastic-strain limit, and one without.
pub const MATERIALS: &str = r#"
[[material]]
name = "soft"
model = "j2_plastic"
density = 7850.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3
yield_stress = 3.0e8
hardening_modulus = 1.0e9
failure = { plastic_strain = 0.3 }

[[material]]
name = "hard"
model = "linear_elastic"
density = 7850.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3
"#;

/// A plane-strain projectile (hard, 10 x 10 mm, 0.5 mm elements) at `speed` m/s onto a plate
/// (40 x 4 mm, 0.5 mm elements, a 0.3 plastic-strain limit, stiffness hourglass control: with
/// the viscous default an element at the projectile's corner inverts before it erodes) held at
/// both ends, with `contact`. At 400 m/s the plug leaves after about 6 us (48 elements eroded,
/// 256 m/s left, 2026-11-27).
pub fn perforation(speed: f64, contact: &str) -> String {
    format!(
        r#"
[run]
end_time = 6.0e-5
history_interval = 5.0e-7
time_step_scale = 0.5
{MATERIALS}
[[body]]
name = "plate"
material = "soft"
mesh = {{ rectangle = {{ origin = [-0.02, 0.0], size = [0.04, 0.004], cells = [80, 8] }} }}
hourglass = {{ form = "stiffness", coefficient = 0.1 }}

[[body]]
name = "projectile"
material = "hard"
mesh = {{ rectangle = {{ origin = [-0.005, 0.00401], size = [0.01, 0.01], cells = [10, 10] }} }}
initial_velocity = [0.0, {v:e}]

[[boundary]]
body = "plate"
region = {{ min = [-1.0, -1.0], max = [-0.0199, 1.0] }}
velocity = {{ x = 0.0, y = 0.0 }}

[[boundary]]
body = "plate"
region = {{ min = [0.0199, -1.0], max = [1.0, 1.0] }}
velocity = {{ x = 0.0, y = 0.0 }}

{contact}
"#,
        v = -speed
    )
}

/// How far `p` lies inside the convex quad or triangle `x` (counter-clockwise): the smallest
/// distance to the lines of its sides (<= 0 outside).
fn inside_depth(x: &[[f64; 2]; 4], p: [f64; 2]) -> f64 {
    // Outside the element's bounding box: outside it (a quick rejection; the scans below test
    // every node against every element).
    let (lo, hi) = x.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), c| {
            (
                [lo[0].min(c[0]), lo[1].min(c[1])],
                [hi[0].max(c[0]), hi[1].max(c[1])],
            )
        },
    );
    if p[0] <= lo[0] || p[0] >= hi[0] || p[1] <= lo[1] || p[1] >= hi[1] {
        return 0.0;
    }
    (0..4)
        .filter(|&a| x[a] != x[(a + 1) % 4])
        .map(|a| {
            let (s, t) = (x[a], x[(a + 1) % 4]);
            let d = [t[0] - s[0], t[1] - s[1]];
            (d[0] * (p[1] - s[1]) - d[1] * (p[0] - s[0])) / d[0].hypot(d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// Whether node `n` of body `b` has only eroded elements (a free node).
fn is_free(model: &Model, b: usize, n: usize, eroded: &[bool]) -> bool {
    model.bodies[b]
        .elements
        .clone()
        .filter(|&f| model.quads[f].contains(&(n as u32)))
        .all(|f| eroded[f])
}

/// The deepest any node of one body lies inside a remaining (not eroded) element of another;
/// and of a body's own remaining elements that do not hold them, the deepest of its nodes that
/// are not free and the deepest of its free nodes.
pub fn deepest_in_remaining(model: &Model, u: &[[f64; 2]], eroded: &[bool]) -> [f64; 3] {
    let x = |n: usize| {
        [
            model.position[n][0] + u[n][0],
            model.position[n][1] + u[n][1],
        ]
    };
    let mut worst = [0.0f64; 3];
    for (i, a) in model.bodies.iter().enumerate() {
        for (j, b) in model.bodies.iter().enumerate() {
            for e in b.elements.clone().filter(|&e| !eroded[e]) {
                let c = model.quads[e].map(|n| x(n as usize));
                for n in a.nodes.clone() {
                    if model.quads[e].contains(&(n as u32)) {
                        continue;
                    }
                    let depth = inside_depth(&c, x(n));
                    if depth <= 0.0 {
                        continue;
                    }
                    let k = if i != j {
                        0
                    } else if is_free(model, i, n, eroded) {
                        2
                    } else {
                        1
                    };
                    worst[k] = worst[k].max(depth);
                }
            }
        }
    }
    worst
}

/// The deepest any node of body `a` lies inside a remaining (not eroded) element of body `b`
/// (`a` != `b`): the cross-body part of [`deepest_in_remaining`], without its scan of each
/// body's own elements, for larger meshes.
pub fn deepest_of_in(model: &Model, u: &[[f64; 2]], eroded: &[bool], a: usize, b: usize) -> f64 {
    let x = |n: usize| {
        [
            model.position[n][0] + u[n][0],
            model.position[n][1] + u[n][1],
        ]
    };
    let mut worst = 0.0f64;
    for e in model.bodies[b].elements.clone().filter(|&e| !eroded[e]) {
        let c = model.quads[e].map(|n| x(n as usize));
        for n in model.bodies[a].nodes.clone() {
            worst = worst.max(inside_depth(&c, x(n)));
        }
    }
    worst
}

/// The stretched block of `tests/core/failure.rs` (4 x 8 aluminium elements, 20 x 40 mm, from
/// y = `y0`, stretched along y at 2000 /s) whose every element erodes within about 2e-5 s, run to
/// `end_time`: `run` adds lines to `[run]`, `body` to the block's table, and `tail` follows it.
pub fn stretched_block(end_time: f64, y0: f64, run: &str, body: &str, tail: &str) -> String {
    format!(
        r#"
[run]
end_time = {end_time:e}
history_interval = 1.0e-6
{run}
[[material]]
name = "aluminium"
model = "j2_plastic"
density = 2700.0
youngs_modulus = 7.0e10
poisson_ratio = 0.33
yield_stress = 2.0e7
hardening_modulus = 2.0e8
failure = {{ plastic_strain = 1.0e-4 }}

[[body]]
name = "block"
material = "aluminium"
mesh = {{ rectangle = {{ origin = [0.0, {y0:e}], size = [0.02, 0.04], cells = [4, 8] }} }}
velocity_gradient = [[0.0, 0.0], [0.0, 2000.0]]
{body}
{tail}"#
    )
}

/// [`stretched_block`] falling onto a floor (a Lagrange rigid wall) at 100 m/s to 1e-4 s: every
/// node falls on as a free mass until the wall stops it (without the wall the lowest nodes would
/// end millimetres below it); `run` adds lines to `[run]`.
pub fn falling_block(run: &str) -> String {
    stretched_block(
        1.0e-4,
        0.001,
        run,
        "initial_velocity = [0.0, -100.0]\n",
        "[[rigid_wall]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\nmethod = \"lagrange\"\n",
    )
}
