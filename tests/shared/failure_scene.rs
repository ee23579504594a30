//! Scenes with material failure and their closed forms, shared by the core
//! (`tests/core/failure.rs`) and GPU tests: a single element in uniaxial plane strain pulled
//! until its plastic strain reaches a limit, a single element in simple shear accumulating
//! Johnson-Cook damage at zero triaxiality, and a freely stretching block whose elements erode.
#![allow(dead_code)]

/// The plastic patch test's aluminium (tests/shared/plastic_scene.rs).
pub const E: f64 = 70e9;
pub const NU: f64 = 0.33;
pub const YIELD: f64 = 20e6;
pub const HARDENING: f64 = 200e6;
/// Side of the element (m).
pub const SIDE: f64 = 0.01;

/// Shear modulus.
pub fn mu() -> f64 {
    E / (2.0 * (1.0 + NU))
}

/// One element of side [`SIDE`] in uniaxial plane strain, pulled along y at the strain rate
/// `rate` (v_y = rate (y - SIDE / 2), held on the top and bottom edges, v_x = 0) until
/// `end_time`, its material with `failure`.
pub fn tension_scene(rate: f64, end_time: f64, failure: &str) -> String {
    one_element(
        end_time,
        &format!("hardening_modulus = {HARDENING:e}\n"),
        failure,
        &format!("[[0.0, 0.0], [0.0, {rate:e}]]"),
        ("x", "y", 0.5 * SIDE * rate),
    )
}

/// The one-element scene of [`tension_scene`] and [`shear_scene`]: the J2 aluminium (`hardening`:
/// its hardening line, or none) with `failure`, the initial velocity gradient `gradient`, every
/// node held at `held` = 0 and the bottom and top edges moved along `moved` at -v and +v
/// (`(held, moved, v)`).
fn one_element(
    end_time: f64,
    hardening: &str,
    failure: &str,
    gradient: &str,
    (held, moved, v): (&str, &str, f64),
) -> String {
    format!(
        r#"
[run]
end_time = {end_time:e}
history_interval = {hi:e}
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

[[material]]
name = "aluminium"
model = "j2_plastic"
density = 2700.0
youngs_modulus = {E:e}
poisson_ratio = {NU}
yield_stress = {YIELD:e}
{hardening}failure = {failure}

[[body]]
name = "block"
material = "aluminium"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{SIDE:e}, {SIDE:e}], cells = [1, 1] }} }}
velocity_gradient = {gradient}

[[boundary]]
body = "block"
region = {{ min = [-1.0, -1.0], max = [1.0, 1.0] }}
velocity = {{ {held} = 0.0 }}

[[boundary]]
body = "block"
region = {{ min = [-1.0, -1e-9], max = [1.0, 1e-9] }}
velocity = {{ {moved} = {:e} }}

[[boundary]]
body = "block"
region = {{ min = [-1.0, {top_lo:e}], max = [1.0, {top_hi:e}] }}
velocity = {{ {moved} = {v:e} }}
"#,
        -v,
        hi = end_time / 20.0,
        top_lo = SIDE - 1e-9,
        top_hi = SIDE + 1e-9,
    )
}

/// The equivalent plastic strain of [`tension_scene`] at the stretch `lambda` (the model's
/// closed form: the return in logarithmic strain is exact for this proportional, coaxial path,
/// yield on the Cauchy stress): alpha = (2 mu ln lambda - lambda sigma_y) / (3 mu + lambda H).
pub fn tension_plastic_strain(lambda: f64) -> f64 {
    let mu = mu();
    ((2.0 * mu * lambda.ln() - lambda * YIELD) / (3.0 * mu + lambda * HARDENING)).max(0.0)
}

/// One element in simple shear at the shear rate `rate` (v_x = rate (y - SIDE / 2), held on
/// every node, v_y = 0): J = 1 exactly, so the mean stress and the triaxiality are 0. Perfect
/// plasticity (no hardening); its material with `failure`.
pub fn shear_scene(rate: f64, end_time: f64, failure: &str) -> String {
    one_element(
        end_time,
        "",
        failure,
        &format!("[[0.0, {rate:e}], [0.0, 0.0]]"),
        ("y", "x", 0.5 * SIDE * rate),
    )
}

/// The shear strain gamma at which [`shear_scene`]'s equivalent plastic strain reaches `eps`,
/// to first order in the elastic strain: the rate of deformation of simple shear has the
/// equivalent rate gamma_dot / sqrt 3, constant in time whatever the rotation; once yielded, the
/// elastic strain stays at sigma_y / (3 mu) (perfect plasticity) and all the rest flows
/// plastically, so eps_p = gamma / sqrt 3 - sigma_y / (3 mu).
pub fn shear_strain_at(eps: f64) -> f64 {
    3f64.sqrt() * (eps + YIELD / (3.0 * mu()))
}

/// A block of 4 x 8 elements stretching freely along y (v_y = rate (y - 2 SIDE), no boundary
/// conditions) until `end_time`: the free ends unload, the middle keeps stretching, and the
/// elements erode at `plastic_strain`; history every step.
pub fn stretching_block(rate: f64, end_time: f64, plastic_strain: f64) -> String {
    format!(
        r#"
[run]
end_time = {end_time:e}
history_interval = {hi:e}
field_interval = {fi:e}

[[material]]
name = "aluminium"
model = "j2_plastic"
density = 2700.0
youngs_modulus = {E:e}
poisson_ratio = {NU}
yield_stress = {YIELD:e}
hardening_modulus = {HARDENING:e}
failure = {{ plastic_strain = {plastic_strain} }}

[[body]]
name = "block"
material = "aluminium"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{w:e}, {l:e}], cells = [4, 8] }} }}
velocity_gradient = [[0.0, 0.0], [0.0, {rate:e}]]
"#,
        hi = end_time / 200.0,
        fi = end_time / 4.0,
        w = 2.0 * SIDE,
        l = 4.0 * SIDE,
    )
}

/// One element of side [`SIDE`] of the aluminium (linear elastic, so that its energies stay
/// finite past inversion) whose top-right corner is pushed at `speed` (m/s) along the diagonal
/// towards the fixed bottom-left one, the other two held: the corner crosses the diagonal
/// between its neighbours, where the element inverts (a corner Jacobian of 0) while its area is
/// still half the square, at t = SIDE / (2 speed). `erosion`: the `[run]` line of the option
/// (or none). A history row every step until `end_time`.
pub fn crushed_corner(speed: f64, end_time: f64, erosion: &str) -> String {
    format!(
        r#"
[run]
end_time = {end_time:e}
history_interval = 1e-9
{erosion}

[[material]]
name = "aluminium"
model = "linear_elastic"
density = 2700.0
youngs_modulus = {E:e}
poisson_ratio = {NU}

[[body]]
name = "block"
material = "aluminium"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{SIDE:e}, {SIDE:e}], cells = [1, 1] }} }}

[[boundary]]
body = "block"
region = {{ min = [-1.0, -1.0], max = [1.0, 1.0e-9] }}
velocity = {{ x = 0.0, y = 0.0 }}

[[boundary]]
body = "block"
region = {{ min = [-1.0, {lo:e}], max = [1.0e-9, 1.0] }}
velocity = {{ x = 0.0, y = 0.0 }}

[[boundary]]
body = "block"
region = {{ min = [{lo:e}, {lo:e}], max = [1.0, 1.0] }}
velocity = {{ x = {v:e}, y = {v:e} }}
"#,
        lo = SIDE - 1e-9,
        v = -speed,
    )
}

/// The stress case `assets/stress/collapsing_element.toml`: the element of [`crushed_corner`] at
/// [`COLLAPSE_SPEED`], bulk viscosity off, with `run.erosion.min_time_step`.
pub fn collapsing_element() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/stress/collapsing_element.toml");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The corner's speed in [`collapsing_element`] (m/s).
pub const COLLAPSE_SPEED: f64 = 100.0;

/// When [`collapsing_element`]'s element erodes, in closed form: its characteristic length is
/// SIDE - v t (its area SIDE (SIDE - v t) over its longest side SIDE) and its wave speed
/// c0 sqrt(A / A0) = c0 sqrt(1 - v t / SIDE) (at the current density), so its stable step is
/// `dt0` sqrt(1 - v t / SIDE), `dt0` = SIDE / c0 its stable step at rest, and it falls below
/// `min_time_step / scale` after t* = (SIDE / v) (1 - (min_time_step / (scale dt0))^2).
pub fn collapse_time(dt0: f64, scale: f64, min_time_step: f64) -> f64 {
    SIDE / COLLAPSE_SPEED * (1.0 - (min_time_step / (scale * dt0)).powi(2))
}
