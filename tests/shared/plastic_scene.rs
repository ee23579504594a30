//! The plastic patch test's scene (REFERENCES.md section 10) and its closed form, shared by the
//! core (`tests/core/plastic.rs`) and GPU (`tests/gpu/plastic.rs`) tests.
#![allow(dead_code)]

/// Annealed pure aluminium (sigma_y / E = 2.9e-4, so that the finite-strain terms of the elastic
/// range, 1.5 |eps| relative, stay below 1e-3 sigma_y at first yield).
pub const E: f64 = 70e9;
pub const NU: f64 = 0.33;
pub const YIELD: f64 = 20e6;
pub const HARDENING: f64 = 200e6;
/// Side of the block (m) and the final compressive strain |eps| = RATE * END.
pub const SIDE: f64 = 0.01;
pub const RATE: f64 = 100.0;
pub const END: f64 = 1e-4;

/// The block in uniaxial plane strain: v_y = -RATE (y - SIDE / 2) everywhere, held on the top and
/// bottom edges, v_x = 0 on every node. The stress is uniform, so the inner nodes feel no net
/// force and keep the linear field: a homogeneous state, exactly.
pub fn scene(format: &str) -> String {
    let h = 0.5 * SIDE * RATE;
    format!(
        r#"
[run]
end_time = {END:e}
history_interval = {:e}
field_interval = {:e}
field_format = "{format}"
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

[[material]]
name = "aluminium"
model = "j2_plastic"
density = 2700.0
youngs_modulus = {E:e}
poisson_ratio = {NU}
yield_stress = {YIELD:e}
hardening_modulus = {HARDENING:e}

[[body]]
name = "block"
material = "aluminium"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{SIDE:e}, {SIDE:e}], cells = [4, 4] }} }}
velocity_gradient = [[0.0, 0.0], [0.0, -{RATE:e}]]

[[boundary]]
body = "block"
region = {{ min = [-1.0, -1.0], max = [1.0, 1.0] }}
velocity = {{ x = 0.0 }}

[[boundary]]
body = "block"
region = {{ min = [-1.0, -1e-9], max = [1.0, 1e-9] }}
velocity = {{ y = {h:e} }}

[[boundary]]
body = "block"
region = {{ min = [-1.0, {top_lo:e}], max = [1.0, {top_hi:e}] }}
velocity = {{ y = {:e} }}
"#,
        END / 50.0,
        END / 40.0,
        -h,
        top_lo = SIDE - 1e-9,
        top_hi = SIDE + 1e-9,
    )
}

/// The closed form (small strain): von Mises stress at compressive strain x = |eps|.
/// The scene with the Johnson-Cook flow stress A (1 + C ln(max(rate, 1))) (B = 0, reference
/// rate 1/s) instead of linear hardening.
pub fn rate_scene(format: &str, c: f64) -> String {
    scene(format).replace(
        &format!("yield_stress = {YIELD:e}\nhardening_modulus = {HARDENING:e}"),
        &format!(
            "johnson_cook = {{ a = {YIELD:e}, b = 0.0, n = 1.0, c = {c}, reference_strain_rate = 1.0 }}"
        ),
    )
}

/// The steady flow stress of [`rate_scene`] at compressive strain `x`: A (1 + C ln(alpha rate)),
/// with the plastic strain rate (2/3) of the logarithmic strain rate RATE / (1 - x) (the trial's
/// von Mises stress grows by 2 mu d|eps|, each return takes 3 mu d alpha off it).
pub fn rate_flow(x: f64, c: f64) -> f64 {
    YIELD * (1.0 + c * (2.0 / 3.0 * RATE / (1.0 - x)).ln())
}

pub fn von_mises_closed(x: f64) -> f64 {
    let mu = E / (2.0 * (1.0 + NU));
    let first = YIELD / (2.0 * mu);
    if x <= first {
        2.0 * mu * x
    } else {
        YIELD + 2.0 * mu * HARDENING / (3.0 * mu + HARDENING) * (x - first)
    }
}

pub fn bulk_modulus() -> f64 {
    E / (3.0 * (1.0 - 2.0 * NU))
}
