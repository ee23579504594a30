//! Stress cases of `assets/stress/` (REFERENCES.md section 6) on the GPU, against the same bounds
//! as the CPU tests (`tests/core/stress.rs`): the penalty 1000 x stiffer than the default (step
//! reduced to the formula, no energy gained) and the projectile crossing a thin plate within one
//! step (caught by the swept contact test); the thin plate and the 0.3 c impact also on the
//! per-colour solve path that GPUs take from `gpu::contact::solve::MULTI_SLOTS` slots on.

use std::path::Path;

use ricochet::gpu::contact::ContactOptions;
use ricochet::gpu::GpuSolver;
use ricochet::run::{run, schedule, RunResult};

use ricochet::step::Solver;

use crate::{context, load, GPU_LOCK};

#[path = "../shared/penetration.rs"]
pub(crate) mod penetration;
use penetration::interpenetration;

fn stress_asset(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/stress")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn run_gpu(text: &str, name: &str) -> Option<(RunResult, ricochet::model::Model)> {
    run_gpu_u(text, name).map(|(r, m, _)| (r, m))
}

/// As `run_gpu`, with the displacement at the end.
fn run_gpu_u(text: &str, name: &str) -> Option<(RunResult, ricochet::model::Model, Vec<[f64; 2]>)> {
    run_gpu_with(text, name, ContactOptions::default())
}

/// The solve paths the impacts below run on: the adapter's (by size) and the per-colour one.
const PATHS: [(&str, ContactOptions); 2] = [
    ("default", ContactOptions::DEFAULT),
    (
        "per-colour",
        ContactOptions {
            multi: Some(true),
            ..ContactOptions::DEFAULT
        },
    ),
];

/// As `run_gpu_u`, with these contact options.
fn run_gpu_with(
    text: &str,
    name: &str,
    options: ContactOptions,
) -> Option<(RunResult, ricochet::model::Model, Vec<[f64; 2]>)> {
    let ctx = context()?;
    let (scene, model, plan) = load(text, name);
    let dir = crate::scratch(&format!("gpu-stress-{name}"));
    let mut gpu = GpuSolver::with_options(ctx, &model, &plan, schedule(&scene), None, options)
        .expect("gpu solver");
    let r = run(&scene, &model, &plan, &mut gpu, &dir, None).expect("gpu run");
    let u = gpu.displacement_now().expect("displacement");
    let _ = std::fs::remove_dir_all(&dir);
    Some((r, model, u))
}

#[test]
fn gpu_stiff_penalty_reduces_the_step_and_gains_no_energy() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text =
        stress_asset("penalty_stiff.toml").replace("penalty_scale = 1.0", "penalty_scale = 100.0");
    let Some((r, model)) = run_gpu(&text, "penalty") else {
        return;
    };
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let e0 = 0.5 * model.bodies[0].mass * 100.0;
    let e_max = r
        .samples
        .iter()
        .map(|(s, _)| (s.kinetic + s.internal + s.hourglass) / e0)
        .fold(0.0f64, f64::max);
    let last = &r.samples.last().expect("rows").0;
    let e_end = (last.kinetic + last.internal + last.hourglass) / e0;
    let dt = 0.9 * 0.05 / (5172.19 * 101f64.sqrt());
    let dev = (r.summary.dt_max / dt - 1.0)
        .abs()
        .max((r.summary.dt_min / dt - 1.0).abs());
    println!(
        "gpu penalty 1000 x default: E_end/E0 {e_end:.5}, max E/E0 {e_max:.5}, dt {:.4e} (formula {dt:.4e}), \
         v1/v0 {:.4}, v2/v0 {:.4}, energy error {:.1e}",
        r.summary.dt_max,
        last.body_velocity[0][0] / 10.0,
        last.body_velocity[1][0] / 10.0,
        r.summary.max_energy_error
    );
    assert!(e_end <= 1.01 && e_max <= 1.01);
    assert!(dev < 5e-3, "step {dev}");
    assert!(last.body_velocity[0][0].abs() < 0.5 && last.body_velocity[1][0] > 9.5);
}

#[test]
fn gpu_projectile_crossing_a_thin_plate_within_one_step_is_caught() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (path, options) in PATHS {
        let Some((r, _, _)) = run_gpu_with(&stress_asset("thin_plate.toml"), "plate", options)
        else {
            return;
        };
        thin_plate(&r, path);
    }
}

/// The thin plate's checks of run `r` on solve path `path`.
fn thin_plate(r: &RunResult, path: &str) {
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let thickness = 5.0e-5;
    let crossing = 600.0 * r.summary.dt_min / thickness;
    let pen = r
        .samples
        .iter()
        .map(|(s, _)| s.contacts[0].max_penetration)
        .fold(0.0f64, f64::max);
    let last = &r.samples.last().expect("rows").0;
    println!(
        "gpu thin plate, {path} solve: {crossing:.2} thicknesses per step, reported penetration \
         {pen:.2e} m, energy error {:.2e}, projectile {:.1} m/s, plate {:.1} m/s, {} unconverged \
         steps",
        r.summary.max_energy_error,
        last.body_velocity[0][0],
        last.body_velocity[1][0],
        r.summary.contact_unconverged
    );
    assert!(crossing > 1.0);
    assert!(pen < 1e-2 * thickness, "{path}: penetration {pen}");
    assert!(r.summary.max_energy_error < 0.02);
    assert!(last.body_velocity[0][0] < 0.0, "the projectile rebounds");
    assert!(last.body_velocity[1][0] > 0.0, "the plate is pushed");
}

#[test]
fn gpu_corner_impacts_keep_the_mirror_symmetry() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let h = 0.02 / 6.0;
    for name in ["corner_first.toml", "corner_to_corner.toml"] {
        let Some((r, model, u)) = run_gpu_u(&stress_asset(name), "corner") else {
            return;
        };
        assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
        let m0v0 = model.bodies[0].mass * 5.0;
        let masses = [model.bodies[0].mass, model.bodies[1].mass];
        let side = r
            .samples
            .iter()
            .flat_map(|(s, _)| (0..2).map(move |b| (masses[b] * s.body_velocity[b][0]).abs()))
            .fold(0.0f64, f64::max)
            / m0v0;
        let last = &r.samples.last().expect("rows").0;
        let deepest = interpenetration(&model, &u);
        println!(
            "gpu {name}: sideways momentum of a body / M v0 {side:.2e}, final vy {:.3} m/s, \
             node inside the other body at the end {deepest:.1e} m, energy error {:.1e}",
            last.body_velocity[0][1], r.summary.max_energy_error
        );
        // f32: the mirror images differ by round-off only (4e-4 and 0.41 before the corner rule).
        assert!(side < 1e-4, "{name}: sideways momentum {side:e} of M v0");
        assert!(last.body_velocity[0][1] > 0.0, "{name}: no rebound");
        assert!(deepest < 1e-4 * h, "{name}: {deepest:e} m inside");
        assert!(r.summary.max_energy_error < 1e-3);
    }
}

#[test]
fn gpu_impact_at_0_3_c_leaves_no_node_inside_the_other_block() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let h = 0.01 / 8.0;
    let text = stress_asset("high_velocity.toml")
        .replace(
            "initial_velocity = [5.172, 0.0]",
            &format!("initial_velocity = [{:e}, 0.0]", 0.3 * 5172.19),
        )
        .replace("linear_elastic", "neo_hookean");
    for (path, options) in PATHS {
        let Some((r, model, u)) = run_gpu_with(&text, "fast", options) else {
            return;
        };
        fast_impact(&r, &model, &u, h, path);
    }
}

/// The 0.3 c impact's checks of run `r` (`model`, final displacements `u`, element size `h`) on
/// solve path `path`.
fn fast_impact(r: &RunResult, model: &ricochet::model::Model, u: &[[f64; 2]], h: f64, path: &str) {
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let deepest = interpenetration(model, u);
    let pen = r
        .samples
        .iter()
        .map(|(s, _)| s.contacts[0].max_penetration)
        .fold(0.0f64, f64::max);
    println!(
        "gpu v0/c = 0.3, {path} solve: node inside the other block at the end {deepest:.2e} m \
         ({:.1e} h), reported penetration {pen:.2e} m, energy error {:.2e}, {} unconverged steps",
        deepest / h,
        r.summary.max_energy_error,
        r.summary.contact_unconverged
    );
    assert!(deepest < 1e-2 * h, "{path}: {deepest:e} m inside");
    assert!(pen < 1e-3 * h, "{path}: reported penetration {pen:e} m");
    assert!(r.summary.max_energy_error < 0.05);
}
