//! The contact patch test (`REFERENCES.md` section 3) on the GPU: pressure load, mass damping and
//! contact kernels together (the CPU version is `tests/core/patch_contact.rs`). Two-pass Lagrange
//! must carry the pressure exactly (stress error below 1e-4 p, here in f32), with the adapter's
//! own solve, with the one GPUs take (parallel colouring at 256 threads, sweeps in workgroup
//! memory, 2 x 2 blocks of node pairs) and, on the 8/6 mesh, with the adapter's own solve in
//! 2 x 2 blocks and with the per-colour path GPUs take from `solve::MULTI_SLOTS` slots on, which
//! lavapipe does not take by default; one pass reproduces the known failure; the GPU agrees with
//! the CPU run of the same scene.

use ricochet::gpu::contact::ContactOptions;

use ricochet::gpu::GpuSolver;
use ricochet::output::history::EnergyAudit;
use ricochet::plan::Stage;
use ricochet::run::{run, schedule};
use ricochet::step::cpu::CpuSolver;

use crate::{context, load, GPU_LOCK};

#[path = "../shared/patch_scene.rs"]
mod patch_scene;
use patch_scene::*;

/// What a settled run gives (both backends).
struct Settled {
    stress_error: f64,
    contact_force: f64,
    kinetic_ratio: f64,
    energy_error: f64,
    displacement: Vec<[f64; 2]>,
}

/// The one-workgroup solve as GPUs take it by default (`gpu::contact::one_group`,
/// `parallel_colouring`, `local_sweeps`), on any adapter.
const AS_ON_GPUS: ContactOptions = ContactOptions {
    one: Some(false),
    local_sweeps: Some(true),
    group: Some(256),
    parallel_colouring: Some(true),
    pair_blocks: Some(true),
    ..ContactOptions::DEFAULT
};

/// The adapter's own solve with 2 x 2 blocks of node pairs (`gpu::contact::pair_blocks`), which
/// lavapipe does not take by default. The 8/6 mesh has node pairs that coincide, whose blocks
/// are singular: with them it failed the test before 2026-11-29 (stress error 2.2e-4 p here,
/// 4.8e-3 p as on GPUs), while the load jumped between the two constraints of such a pair.
const PAIRS: ContactOptions = ContactOptions {
    pair_blocks: Some(true),
    ..ContactOptions::DEFAULT
};

/// The per-colour solve path (`gpu::contact::solve::MULTI_SLOTS`), on any adapter.
const PER_COLOUR: ContactOptions = ContactOptions {
    multi: Some(true),
    ..ContactOptions::DEFAULT
};

/// Settles the patch scene on the CPU reference (`gpu` None) or on the GPU with these contact
/// options.
fn settle(
    gpu: Option<ContactOptions>,
    lower: usize,
    upper: usize,
    first: &str,
    contact: &str,
) -> Settled {
    let text = scene(lower, upper, first, contact);
    let (scene, model, plan) = load(&text, "patch");
    assert!(plan.has(Stage::Pressure) && plan.has(Stage::MassDamping));
    let sign = if first == "upper" { 1.0 } else { -1.0 };
    let dir = crate::scratch(&format!(
        "gpu-patch-{lower}-{upper}-{first}-{}",
        gpu.map_or("cpu", |o| match o {
            AS_ON_GPUS => "gpus",
            PER_COLOUR => "colour",
            PAIRS => "pairs",
            _ => "gpu",
        })
    ));
    let (r, displacement) = if let Some(options) = gpu {
        let ctx = context().expect("adapter");
        let mut s = GpuSolver::with_options(ctx, &model, &plan, schedule(&scene), None, options)
            .expect("gpu solver");
        let r = run(&scene, &model, &plan, &mut s, &dir, None).expect("gpu run");
        (r, s.nodes().expect("nodes").0)
    } else {
        let mut s = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
        let r = run(&scene, &model, &plan, &mut s, &dir, None).expect("cpu run");
        (r, s.displacement().to_vec())
    };
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let mut audit = EnergyAudit::default();
    let energy_error = r
        .samples
        .iter()
        .map(|(s, _)| audit.error(s))
        .fold(0.0f64, f64::max);
    let last = &r.samples.last().expect("samples").0;
    Settled {
        stress_error: stress_error(&model, &displacement),
        contact_force: sign * last.contacts[0].force[1] / P,
        kinetic_ratio: last.kinetic.abs() / last.internal,
        energy_error,
        displacement,
    }
}

#[test]
fn gpu_two_pass_lagrange_passes_the_contact_patch_test_and_matches_the_cpu() {
    let Some(_) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let keys = "method = \"lagrange\"\ntwo_pass = true";
    for (lower, upper) in MESHES {
        for first in ["upper", "lower"] {
            let c = settle(None, lower, upper, first, keys);
            // The per-colour path and the adapter's solve in blocks on the mesh that failed them
            // (8/6, either body first; CI time).
            let failed = (lower, upper) == (8, 6);
            for (solve, options) in [
                ("the adapter's", ContactOptions::default()),
                ("as on GPUs", AS_ON_GPUS),
                ("the adapter's in blocks", PAIRS),
                ("per-colour", PER_COLOUR),
            ] {
                if (options == PER_COLOUR || options == PAIRS) && !failed {
                    continue;
                }
                let g = settle(Some(options), lower, upper, first, keys);
                let umax = c
                    .displacement
                    .iter()
                    .map(|u| u[0].hypot(u[1]))
                    .fold(0.0f64, f64::max);
                let du = c
                    .displacement
                    .iter()
                    .zip(&g.displacement)
                    .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                    .fold(0.0f64, f64::max);
                eprintln!(
                    "GPU contact patch test, two-pass Lagrange, {lower}/{upper}, first {first}, \
                 {solve} solve: stress error {:.2e} p (CPU {:.2e}), contact force {:.7} p, \
                 kinetic/strain {:.1e}, energy error {:.1e}, displacement vs CPU {:.1e} of max",
                    g.stress_error,
                    c.stress_error,
                    g.contact_force,
                    g.kinetic_ratio,
                    g.energy_error,
                    du / umax
                );
                assert!(g.kinetic_ratio < 1e-6, "not settled: {:e}", g.kinetic_ratio);
                assert!(
                    g.stress_error < 1e-4,
                    "{lower}/{upper}, first {first}, {solve} solve: stress error {:e} p",
                    g.stress_error
                );
                assert!((g.contact_force - 1.0).abs() < 1e-4, "{}", g.contact_force);
                assert!(g.energy_error < 1e-4, "energy error {:e}", g.energy_error);
                assert!(du / umax < 1e-4, "GPU vs CPU displacement {:e}", du / umax);
            }
        }
    }
}

#[test]
fn gpu_one_pass_lagrange_reproduces_the_known_patch_test_failure() {
    let Some(_) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let keys = "method = \"lagrange\"\ntwo_pass = false";
    for (first, side) in [("upper", "coarse"), ("lower", "fine")] {
        let g = settle(Some(ContactOptions::default()), 4, 3, first, keys);
        let c = settle(None, 4, 3, first, keys);
        eprintln!(
            "GPU contact patch test, one-pass Lagrange, 4/3, {side} slave: stress error {:.4} p \
             (CPU {:.4} p), contact force {:.7} p",
            g.stress_error, c.stress_error, g.contact_force
        );
        assert!(
            g.stress_error > 0.03,
            "one pass should fail: {:e}",
            g.stress_error
        );
        assert!(
            (g.stress_error - c.stress_error).abs() < 1e-3,
            "GPU {} vs CPU {}",
            g.stress_error,
            c.stress_error
        );
        assert!((g.contact_force - 1.0).abs() < 1e-4, "{}", g.contact_force);
    }
}
