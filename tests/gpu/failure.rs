//! Material failure and erosion on the GPU against the CPU reference (lavapipe in CI): a freely
//! stretching block whose elements erode at a plastic-strain limit, and one whose elements erode
//! by Johnson-Cook damage: the same elements erode, each count reached within one step of the
//! CPU's, the energy balances with the eroded energy counted, two GPU runs give the same bits
//! (and the reductions over many workgroups the same erosion),
//! and a restart from a checkpoint taken after some elements eroded ends with the outputs of the
//! run never stopped; in neo-Hookean and linear elastic blocks the principal-strain and spall
//! limits erode the CPU's elements. A scene without failure compiles neither the check nor its
//! buffers. With Johnson-Cook thermal softening a sheared element heats as on the CPU and its
//! damage's d5 term erodes it in the CPU's step, the same bits twice.

use super::*;

use std::process::Command;

use ricochet::checkpoint::Checkpoint;
use ricochet::output::history::EnergyAudit;
use ricochet::step::{Event, Sample, Snapshot};

#[path = "../shared/failure_scene.rs"]
mod failure_scene;
use failure_scene::stretching_block;

use crate::restart::shared_restart;

/// The stretching block (4 x 8 elements at 2000 /s to 20 us, history every 0.1 us) with its
/// failure table replaced by `failure`.
fn block(failure: &str) -> String {
    stretching_block(2000.0, 2.0e-5, 0.01).replace("{ plastic_strain = 0.01 }", failure)
}

/// The plastic-strain limit of the CPU's stretched block, and Johnson-Cook damage alone
/// (eps_f about 0.01 at the triaxiality of uniaxial plane strain).
const CRITERIA: [&str; 2] = [
    "{ plastic_strain = 0.01 }",
    "{ johnson_cook = { d1 = 0.005, d2 = 0.01, d3 = -1.5, d4 = 0.0, d5 = 0.0 } }",
];

/// The samples and snapshots of a run of `solver` to its end.
pub(crate) fn run_to_end(solver: &mut dyn Solver) -> (Vec<Sample>, Vec<Snapshot>) {
    let (mut samples, mut snaps, mut events) = (Vec::new(), Vec::new(), Vec::new());
    while !solver.finished() {
        solver.advance(&mut events).expect("advance");
        for e in events.drain(..) {
            match e {
                Event::Sample(s) => samples.push(s),
                Event::Snapshot(s) => snaps.push(s),
                Event::Failed(f) => panic!("run failed: {f:?}"),
                Event::Done => {}
            }
        }
    }
    (samples, snaps)
}

#[test]
fn gpu_erosion_matches_the_cpu_reference_and_repeats_bit_for_bit() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for failure in CRITERIA {
        let text = block(failure);
        let (scene, model, plan) = load(&text, "block.toml");
        let ne = model.element_count();
        let mut cpu = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
        let (cs, csnap) = run_to_end(&mut cpu);
        let mut gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
        let (gs, gsnap) = run_to_end(&mut gpu);
        assert_eq!(cs.len(), gs.len(), "{failure}: history rows");
        let (cl, gl) = (cs.last().unwrap(), gs.last().unwrap());
        assert!(
            cl.eroded_elements > 0 && (cl.eroded_elements as usize) < ne,
            "{failure}: {} of {ne} eroded on the CPU",
            cl.eroded_elements
        );
        // The same elements eroded by the end.
        let (ce, ge) = (&csnap.last().unwrap().eroded, &gsnap.last().unwrap().eroded);
        assert_eq!(ce.len(), ne);
        assert_eq!(ce, ge, "{failure}: eroded elements, CPU then GPU");
        // A row every step: each count the GPU reaches, it reaches within one step of the CPU.
        for j in 0..cs.len() {
            let lo = cs[j.saturating_sub(1)].eroded_elements;
            let hi = cs[(j + 1).min(cs.len() - 1)].eroded_elements;
            assert_eq!(cs[j].step, gs[j].step);
            assert!(
                (lo..=hi).contains(&gs[j].eroded_elements),
                "{failure}: step {}: {} eroded on the GPU, {lo}..{hi} on the CPU",
                gs[j].step,
                gs[j].eroded_elements
            );
        }
        // The eroded energy agrees, and the balance holds with it as on the CPU.
        let rel = (gl.eroded_energy - cl.eroded_energy).abs() / cl.eroded_energy;
        assert!(rel < 1e-3, "{failure}: eroded energy {rel:e} apart");
        let (mut ca, mut ga) = (EnergyAudit::default(), EnergyAudit::default());
        for (c, g) in cs.iter().zip(&gs) {
            ca.error(c);
            ga.error(g);
        }
        println!(
            "{failure}: {} of {ne} eroded, eroded energy {:e} (CPU {:e}) J, energy error GPU {:e}, CPU {:e}",
            gl.eroded_elements, gl.eroded_energy, cl.eroded_energy, ga.max_error, ca.max_error
        );
        assert!(ga.max_error < 1e-3, "{failure}: {}", ga.max_error);
        // The Johnson-Cook damage in the snapshots (empty without it).
        let damage = &gsnap.last().unwrap().damage;
        if failure.contains("johnson_cook") {
            assert_eq!(damage.len(), ne);
            for (e, (&g, &c)) in damage.iter().zip(&csnap.last().unwrap().damage).enumerate() {
                assert!(
                    (g - c).abs() < 1e-2 * c.max(0.1),
                    "element {e}: damage {g} vs {c}"
                );
            }
        } else {
            assert!(damage.is_empty());
        }
        // A second GPU run: the same bits.
        let mut again = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
        let (gs2, gsnap2) = run_to_end(&mut again);
        assert_eq!(gs, gs2, "{failure}: two GPU runs differ");
        assert_eq!(gsnap, gsnap2, "{failure}: two GPU runs' snapshots differ");
        // The reductions over many workgroups (the path of GPUs and of large models): the same
        // elements erode at the same steps, the eroded energy summed in another fixed order.
        let mut multi =
            GpuSolver::with_reductions(ctx.clone(), &model, &plan, schedule(&scene), Some(false))
                .expect("gpu");
        assert!(multi.state().params.sum_groups > 0);
        let (ms, msnap) = run_to_end(&mut multi);
        assert_eq!(
            msnap.last().unwrap().eroded,
            *ge,
            "{failure}: multi-level reductions"
        );
        for (m, g) in ms.iter().zip(&gs) {
            assert_eq!(
                m.eroded_elements, g.eroded_elements,
                "{failure}: step {}",
                g.step
            );
            assert!((m.eroded_energy - g.eroded_energy).abs() <= 1e-5 * cl.eroded_energy);
        }
    }
}

/// The stretching block of an elastic material `model` (its yield keys removed) with `failure`.
fn elastic_block(model: &str, failure: &str) -> String {
    block(failure)
        .replace("model = \"j2_plastic\"", &format!("model = \"{model}\""))
        .lines()
        .filter(|l| !l.starts_with("yield_stress") && !l.starts_with("hardening_modulus"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn gpu_principal_strain_and_spall_limits_erode_the_cpus_elements_in_elastic_bodies() {
    // The elastic models' Cauchy stress and the principal strain (element.wgsl's linear elastic
    // and neo-Hookean branches), which the plastic cases above do not reach.
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (model, failure) in [
        ("neo_hookean", "{ principal_strain = 0.004 }"),
        ("linear_elastic", "{ tensile_pressure = 2.0e8 }"),
        ("neo_hookean", "{ tensile_pressure = 2.0e8 }"),
    ] {
        let text = elastic_block(model, failure);
        let (scene, m, plan) = load(&text, "block.toml");
        let ne = m.element_count();
        let mut cpu = CpuSolver::new(m.clone(), plan.clone(), schedule(&scene));
        let (cs, csnap) = run_to_end(&mut cpu);
        let mut gpu = GpuSolver::new(ctx.clone(), &m, &plan, schedule(&scene)).expect("gpu");
        let (gs, gsnap) = run_to_end(&mut gpu);
        let what = format!("{model} {failure}");
        let (cl, gl) = (cs.last().unwrap(), gs.last().unwrap());
        println!(
            "{what}: {} of {ne} eroded on the CPU, {} on the GPU",
            cl.eroded_elements, gl.eroded_elements
        );
        assert!(
            cl.eroded_elements > 0 && (cl.eroded_elements as usize) < ne,
            "{what}: {} of {ne} eroded on the CPU",
            cl.eroded_elements
        );
        assert_eq!(
            csnap.last().unwrap().eroded,
            gsnap.last().unwrap().eroded,
            "{what}: eroded elements, CPU then GPU"
        );
        for j in 0..cs.len() {
            let lo = cs[j.saturating_sub(1)].eroded_elements;
            let hi = cs[(j + 1).min(cs.len() - 1)].eroded_elements;
            assert!(
                (lo..=hi).contains(&gs[j].eroded_elements),
                "{what}: step {}: {} eroded on the GPU, {lo}..{hi} on the CPU",
                gs[j].step,
                gs[j].eroded_elements
            );
        }
    }
}

#[test]
fn a_gpu_run_with_erosion_restarts_to_the_same_outputs() {
    let Some(_) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // Both criteria at once: the checkpoint carries the flags and the damage.
    let text = block(
        "{ plastic_strain = 0.01, johnson_cook = { d1 = 0.05, d2 = 0.01, d3 = -1.5, d4 = 0.0, d5 = 0.0 } }",
    );
    let base = std::env::temp_dir().join(format!("ricochet-gpu-failure-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let path = base.join("block.toml");
    std::fs::write(&path, &text).unwrap();
    let bin = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_ricochet"))
            .args(args)
            .output()
            .expect("run the binary")
    };
    let a = base.join("a");
    let o = bin(&[
        "run",
        path.to_str().unwrap(),
        "--backend",
        "gpu",
        "--checkpoint-interval",
        "1.2e-5",
        "--out",
        a.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let c = Checkpoint::read(&a).expect("the run left a checkpoint");
    assert_eq!(c.backend, "gpu");
    // Some elements, not all, had eroded when the checkpoint was taken.
    let history = std::fs::read_to_string(a.join("history.csv")).unwrap();
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (tc, ec) = (col("time"), col("eroded_elements"));
    let at_checkpoint = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[tc].parse::<f64>().unwrap() <= c.time)
        .map(|r| r[ec].parse::<u64>().unwrap())
        .next_back()
        .unwrap();
    assert!(
        at_checkpoint > 0 && at_checkpoint < 32,
        "{at_checkpoint} eroded at the checkpoint (t = {:e})",
        c.time
    );
    // A crash after the checkpoint: its folder, restarted.
    let b = base.join("b");
    shared_restart::copy_dir(&a, &b);
    let o = bin(&["run", "--restart", b.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    shared_restart::assert_same_outputs(&a, &b);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_scene_without_failure_compiles_no_failure_check_or_buffers() {
    let plain = shader::source(ricochet::gpu::element::SOURCE, Features::default());
    assert!(
        !plain.contains("fn failure_check") && !plain.contains("var<storage, read_write> erosion"),
        "no failure check nor erosion state without failure"
    );
    let failing = shader::source(
        ricochet::gpu::element::SOURCE,
        Features {
            failure: true,
            plastic: true,
            ..Features::default()
        },
    );
    assert!(
        failing.contains("fn failure_check")
            && failing.contains("var<storage, read_write> erosion")
    );
    shader::validate("element with failure", &failing).expect("valid WGSL");
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (text, with) in [
        (block(CRITERIA[0]), true),
        (
            block(CRITERIA[0]).replace(&format!("failure = {}\n", CRITERIA[0]), ""),
            false,
        ),
    ] {
        let (scene, model, plan) = load(&text, "block.toml");
        assert_eq!(model.has_failure(), with);
        let gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
        let names: Vec<&str> = gpu.state().allocated.iter().map(|(n, _)| *n).collect();
        assert_eq!(names.contains(&"element_erosion"), with, "{names:?}");
        assert_eq!(names.contains(&"body_failure"), with, "{names:?}");
        assert_eq!(gpu.kernels().features.failure, with);
    }
}

/// The thermal softening verification case (`assets/verification/thermal_softening.toml`) at
/// `n` = 1, with Johnson-Cook damage whose d5 term reads the heated T*, a history row every step
/// and a snapshot at the end.
fn thermal_scene() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/verification/thermal_softening.toml");
    let case = ricochet::verify::case::Case::read(&path).unwrap();
    let level = [("n".to_string(), 1.0)].into_iter().collect();
    case.expand(&level, "none")
        .unwrap()
        .replace(
            "history_interval = 2.5e-6",
            "history_interval = 1.0e-8\nfield_interval = 2.5e-5",
        )
        .replace(
            "taylor_quinney = 0.9\n",
            "taylor_quinney = 0.9\nfailure = { johnson_cook = { d1 = 0.3, d2 = 0.2, d3 = 0.0, d4 = 0.0, d5 = 2.0 } }\n",
        )
}

/// The first history row with an eroded element in the CPU's and the GPU's samples (printing
/// their steps).
fn first_eroded_rows(cs: &[Sample], gs: &[Sample]) -> (usize, usize) {
    let first = |s: &[Sample]| {
        s.iter()
            .position(|r| r.eroded_elements > 0)
            .expect("eroded")
    };
    let (c, g) = (first(cs), first(gs));
    println!(
        "eroded at step {} on the CPU, {} on the GPU",
        cs[c].step, gs[g].step
    );
    (c, g)
}

#[test]
fn gpu_thermal_softening_matches_the_cpu_reference_and_repeats_bit_for_bit() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = thermal_scene();
    let (scene, model, plan) = load(&text, "thermal.toml");
    let mut cpu = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
    let (cs, csnap) = run_to_end(&mut cpu);
    let mut gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
    let (gs, gsnap) = run_to_end(&mut gpu);
    assert_eq!(cs.len(), gs.len(), "history rows");
    // The heated element erodes (its d5 term at T* ~ 0.1) in the CPU's step, within one.
    let (c, g) = first_eroded_rows(&cs, &gs);
    assert!(c.abs_diff(g) <= 1, "CPU row {c}, GPU row {g}");
    // The temperature it eroded at: its T* the CPU's to f32 round-off of the heating sum.
    let (cp, gp) = (
        &csnap.last().unwrap().plastic,
        &gsnap.last().unwrap().plastic,
    );
    assert!(cp[0].heat > 50.0, "{:?}", cp[0]);
    let rel = (gp[0].heat - cp[0].heat).abs() / cp[0].heat;
    println!(
        "temperature rise {} K (CPU {} K), {rel:e} apart",
        gp[0].heat, cp[0].heat
    );
    assert!(rel < 1e-2, "{:?} vs {:?}", gp[0], cp[0]);
    // A second GPU run: the same bits.
    let mut again = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
    let (gs2, gsnap2) = run_to_end(&mut again);
    assert_eq!(gs, gs2, "two GPU runs differ");
    assert_eq!(gsnap, gsnap2, "two GPU runs' snapshots differ");
}

#[test]
fn gpu_erodes_an_element_about_to_invert_in_the_cpus_step_and_repeats_bit_for_bit() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = failure_scene::crushed_corner(100.0, 8.0e-5, "erosion = { inverted = true }");
    erodes_once_in_the_cpus_step(&ctx, &text, (1, 0));
}

#[test]
fn gpu_erodes_an_element_whose_step_collapses_in_the_cpus_step_and_repeats_bit_for_bit() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    erodes_once_in_the_cpus_step(&ctx, &failure_scene::collapsing_element(), (0, 1));
}

/// One element of `text` erodes in the same step on both backends (a history row every step),
/// counted apart as `(inverted, small_step)` say (`run.erosion.inverted`, `min_time_step`); the
/// energy balances with the eroded energy counted, as on the CPU; a second GPU run gives the
/// same bits.
fn erodes_once_in_the_cpus_step(ctx: &Arc<GpuContext>, text: &str, apart: (u64, u64)) {
    let (scene, model, plan) = load(text, "crushed.toml");
    let mut cpu = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
    let (cs, _) = run_to_end(&mut cpu);
    let mut gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
    let (gs, gsnap) = run_to_end(&mut gpu);
    assert_eq!(cs.len(), gs.len(), "history rows");
    let (c, g) = first_eroded_rows(&cs, &gs);
    assert_eq!(cs[c].step, gs[g].step);
    assert_eq!(gs.last().unwrap().eroded_elements, 1);
    for solver in [&mut cpu as &mut dyn Solver, &mut gpu] {
        let counted = (
            solver.eroded_inverted_now().unwrap(),
            solver.eroded_small_step_now().unwrap(),
        );
        assert_eq!(counted, apart, "{}", solver.backend());
    }
    // The energy balances with the eroded energy counted, as on the CPU.
    let (mut ca, mut ga) = (EnergyAudit::default(), EnergyAudit::default());
    let (mut c_end, mut g_end) = (0.0, 0.0);
    for (c, g) in cs.iter().zip(&gs) {
        c_end = ca.error(c);
        g_end = ga.error(g);
    }
    let (cl, gl) = (cs.last().unwrap(), gs.last().unwrap());
    println!(
        "eroded in step {}: eroded energy {:e} J (CPU {:e}), energy error GPU {:e} ({g_end:e} at \
         the end), CPU {:e} ({c_end:e})",
        gs[g].step, gl.eroded_energy, cl.eroded_energy, ga.max_error, ca.max_error
    );
    // The largest error is the start-up's (the first step's, 1.3e-3 on the CPU); after the
    // erosion the balance closes with the eroded energy counted.
    assert!(ga.max_error < 2e-3 && ca.max_error < 2e-3);
    assert!(g_end < 1e-5 && c_end < 1e-9, "{g_end:e} {c_end:e}");
    assert!((gl.eroded_energy - cl.eroded_energy).abs() < 1e-3 * cl.eroded_energy);
    // A second GPU run: the same bits.
    let mut again = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
    let (gs2, gsnap2) = run_to_end(&mut again);
    assert_eq!(gs, gs2, "two GPU runs differ");
    assert_eq!(gsnap, gsnap2, "two GPU runs' snapshots differ");
}
