//! General contact and self-contact on the GPU, the energy regression of the old one-workgroup
//! kernel, and the device search checked against parry's (the CPU reference); the helpers that
//! `paths.rs` (the contact stage's paths against each other) shares.

use super::*;

use ricochet::gpu::contact::ContactOptions;
use ricochet::run::RunResult;

use super::stress::penetration::interpenetration;
use crate::scene_text::STEEL;

#[path = "../shared/general_checks.rs"]
pub(super) mod general_checks;
use general_checks::{check_pile, check_ring, most_active, PILE_H};

fn tmp_dir(name: &str) -> std::path::PathBuf {
    crate::scratch(&format!("gpu-general-{name}"))
}

/// Runs scene text on the GPU (the solve path chosen by `multi`, or by size); the result, the
/// model and the final displacements.
pub(super) fn run_gpu(
    ctx: &Arc<GpuContext>,
    text: &str,
    name: &str,
    multi: Option<bool>,
) -> (RunResult, Model, Vec<[f64; 2]>) {
    let options = ContactOptions {
        multi,
        ..ContactOptions::default()
    };
    let (r, model, u, _) = run_gpu_with(ctx, text, name, options);
    (r, model, u)
}

/// As [`run_gpu`] with any contact options; also the grow events of the run.
pub(super) fn run_gpu_with(
    ctx: &Arc<GpuContext>,
    text: &str,
    name: &str,
    options: ContactOptions,
) -> (RunResult, Model, Vec<[f64; 2]>, u32) {
    let (r, model, u, gpu) = run_gpu_solver(ctx, text, name, options);
    (r, model, u, gpu.contact_grows())
}

/// [`run_gpu_with`], giving the solver back (for its counts).
pub(super) fn run_gpu_solver(
    ctx: &Arc<GpuContext>,
    text: &str,
    name: &str,
    options: ContactOptions,
) -> (RunResult, Model, Vec<[f64; 2]>, GpuSolver) {
    let (scene, model, plan) = load(text, name);
    let mut gpu =
        GpuSolver::with_options(ctx.clone(), &model, &plan, schedule(&scene), None, options)
            .expect("gpu solver");
    // Each batch recorded while the device runs the one before, as on GPUs (not lavapipe's
    // default): the grows and resumed steps of these runs drop the batch recorded ahead.
    gpu.set_record_ahead(true);
    let dir = tmp_dir(name);
    let r = run(&scene, &model, &plan, &mut gpu, &dir, None).expect("run");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(
        r.summary.status, "completed",
        "{name}: {}",
        r.summary.message
    );
    let u = gpu.displacement_now().expect("displacement");
    (r, model, u, gpu)
}

/// Runs scene text on the CPU reference: the result and the final displacements.
pub(super) fn run_cpu(text: &str, name: &str) -> (RunResult, Vec<[f64; 2]>) {
    let (scene, model, plan) = load(text, name);
    let mut cpu = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
    let dir = tmp_dir(name);
    let r = run(&scene, &model, &plan, &mut cpu, &dir, None).expect("cpu run");
    let _ = std::fs::remove_dir_all(&dir);
    (r, cpu.displacement().to_vec())
}

/// The bits of every node's displacement, for comparing two runs bit for bit.
pub(super) fn displacement_bits(u: &[[f64; 2]]) -> Vec<[u64; 2]> {
    u.iter().map(|x| x.map(f64::to_bits)).collect()
}

/// The bits of every history row's energies and contact reports, for comparing two runs bit for
/// bit.
pub(super) fn history_bits(r: &RunResult) -> Vec<u64> {
    r.samples
        .iter()
        .flat_map(|(s, _)| {
            let mut v = vec![
                s.kinetic.to_bits(),
                s.internal.to_bits(),
                s.contact.to_bits(),
            ];
            for c in &s.contacts {
                v.extend([c.force[0].to_bits(), c.force[1].to_bits()]);
                v.push(c.max_penetration.to_bits());
            }
            v
        })
        .collect()
}

/// Asserts that two runs (each its result and final displacements) gave the same history and
/// displacement bits; `what` says which runs.
pub(super) fn assert_same_bits(
    a: (&RunResult, &[[f64; 2]]),
    b: (&RunResult, &[[f64; 2]]),
    what: &str,
) {
    assert_eq!(history_bits(a.0), history_bits(b.0), "{what}");
    assert_eq!(displacement_bits(a.1), displacement_bits(b.1), "{what}");
}

#[test]
fn gpu_pile_in_one_general_contact_keeps_the_energy_no_node_inside_and_the_same_bits() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("pile.toml");
    let (r, model, u) = run_gpu(&ctx, &text, "pile-a", None);
    let (r2, _, u2) = run_gpu(&ctx, &text, "pile-b", None);
    // f32: a node may sit within round-off of the other surface.
    let p = check_pile(&r, &model, &u, 1e-4);
    println!(
        "gpu pile: {} steps, energy error {:.2e}, deepest node inside another disk {:.2e} m \
         ({:.1e} h), most nodes in disk contact {}, {} searches, sweeps mean {:.1} max {}, \
         {} bytes read back",
        r.summary.steps,
        p.err,
        p.deepest,
        p.deepest / PILE_H,
        p.active,
        r.summary.contact_searches,
        r.summary.contact_sweeps_mean,
        r.summary.contact_sweeps_max,
        r.summary.bytes_read_back
    );
    assert_same_bits((&r, &u), (&r2, &u2), "two GPU runs differ");
}

#[test]
fn gpu_ring_with_self_contact_stays_out_of_its_own_surface() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (r, model, u) = run_gpu(&ctx, &asset("ring_crush.toml"), "ring", None);
    let ring = check_ring(&r, &model, &u, 1e-4);
    println!(
        "gpu ring: energy error {:.2e}, inside its own ring {:.2e} m, inside the punch {:.2e} m, \
         most self-contact nodes {}",
        ring.err, ring.inside, ring.other, ring.active
    );
}

/// The old one-workgroup kernel lost a step's impulses on this scene (contact_energy +154 J ->
/// -764 J at step 170, energy error 2.1e-2): the GPU now follows the CPU row by row.
#[test]
fn gpu_striker_into_plate_follows_the_cpu_contact_energy_row_by_row() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("stress/striker_plate_gpu_energy.toml");
    let (rc, _) = run_cpu(&text, "striker-cpu");
    let (rg, _, _) = run_gpu(&ctx, &text, "striker-gpu", None);
    let ke0 = rc.samples[0].0.kinetic;
    let mut worst: f64 = 0.0;
    for ((c, _), (g, _)) in rc.samples.iter().zip(&rg.samples) {
        worst = worst.max((c.contact - g.contact).abs());
        let active = c.contacts[0].active_nodes;
        if active > 10 {
            assert!(
                g.contacts[0].active_nodes * 2 > active,
                "t = {:e}: {} active nodes on the GPU, {active} on the CPU",
                c.time,
                g.contacts[0].active_nodes
            );
        }
    }
    println!(
        "striker: largest |contact_energy GPU - CPU| {worst:.3e} J of {ke0:.3e} J; GPU energy \
         error {:.2e}, sweeps mean {:.1} max {}",
        rg.summary.max_energy_error, rg.summary.contact_sweeps_mean, rg.summary.contact_sweeps_max
    );
    assert_eq!(rc.samples.len(), rg.samples.len());
    assert!(worst < 1e-3 * ke0, "contact energy differs by {worst:e} J");
    assert!(rg.summary.max_energy_error < 1e-3);
}

/// Every (slot, segment) pair that parry's broad phase yields and the CPU narrow phase activates
/// at the GPU's current positions is among the candidates of the GPU's last search, and its slot,
/// like every wall slot the CPU activates, among the search's active slots (the only ones the
/// narrow phase, the solve and the reports visit).
#[test]
fn gpu_search_candidates_contain_every_pair_parry_and_the_narrow_phase_activate() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let mut scenes: Vec<(String, String)> = vec![
        ("pile".into(), asset("pile.toml")),
        ("ring".into(), asset("ring_crush.toml")),
        ("disk_wall".into(), asset("disk_wall.toml")),
        ("rods".into(), asset("rods_impact.toml")),
    ];
    for s in [
        "corner_first",
        "corner_to_corner",
        "high_velocity",
        "mesh_ratio",
        "thin_plate",
        "striker_plate_gpu_energy",
    ] {
        scenes.push((s.into(), asset(&format!("stress/{s}.toml"))));
    }
    // Random pairs: two blocks at random offsets and angles of approach.
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..3 {
        let (x, vx, n) = (
            0.02 * rnd() - 0.01,
            40.0 * rnd() - 20.0,
            4 + (8.0 * rnd()) as usize,
        );
        scenes.push((
            format!("random{k}"),
            format!(
                r#"
[run]
end_time = 2.0e-5
history_interval = 1.0e-5

{STEEL}

[[body]]
name = "top"
material = "steel"
mesh = {{ rectangle = {{ origin = [{x}, 0.0101], size = [0.02, 0.01], cells = [{n}, {n}] }} }}
initial_velocity = [{vx}, -150.0]

[[body]]
name = "base"
material = "steel"
mesh = {{ rectangle = {{ origin = [-0.02, 0.0], size = [0.06, 0.01], cells = [{m}, 5] }} }}

[[contact]]
bodies = "all"
"#,
                m = 3 * n + 1
            ),
        ));
    }
    let mut total = 0usize;
    for (name, text) in scenes {
        // The pile and the ring meet late: check them further apart.
        let every = if name == "pile" || name == "ring" {
            400
        } else {
            25
        };
        let (scene, model, plan) = load(&text, &name);
        let mut gpu =
            GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu solver");
        let mut set = ricochet::contact::ContactSet::new(&model).expect("contact");
        let mut checked = 0usize;
        let mut pairs = 0usize;
        let mut walls = 0usize;
        let mut inactive_walls = 0usize;
        let tables = set.tables();
        for _ in 0..6 {
            if gpu.run_steps(every).expect("steps") == 0 {
                break;
            }
            let cand = gpu.contact_candidates().expect("candidates");
            let active = gpu.contact_active_slots().expect("active slots");
            assert!(
                active.windows(2).all(|w| w[0] < w[1]),
                "{name}: active slots not in slot order"
            );
            let (u, v) = gpu.nodes().expect("nodes");
            let mut v = v;
            // Positions now (dt -> 0): pairs in contact at the GPU's current configuration.
            set.apply(&model, &u, &mut v, 1e-30, 1e-30, 1.0);
            for (slot, seg) in set.active_pairs() {
                assert!(
                    cand[slot as usize].contains(&seg),
                    "{name}: slot {slot} is active against segment {seg}, not a GPU candidate \
                     ({:?})",
                    cand[slot as usize]
                );
                assert!(
                    active.binary_search(&slot).is_ok(),
                    "{name}: slot {slot} is in contact, not an active GPU slot"
                );
                pairs += 1;
            }
            for slot in set.active_wall_slots() {
                assert!(
                    active.binary_search(&slot).is_ok(),
                    "{name}: wall slot {slot} is in contact, not an active GPU slot"
                );
                walls += 1;
            }
            // A pass slot is active exactly when it has candidates.
            for (k, c) in cand
                .iter()
                .enumerate()
                .filter(|(k, _)| !tables.slots[*k].wall)
            {
                assert_eq!(
                    !c.is_empty(),
                    active.binary_search(&(k as u32)).is_ok(),
                    "{name}: slot {k} with {} candidates",
                    c.len()
                );
            }
            inactive_walls += tables
                .slots
                .iter()
                .enumerate()
                .filter(|(k, s)| s.wall && active.binary_search(&(*k as u32)).is_err())
                .count();
            checked += 1;
        }
        println!(
            "{name}: {pairs} active pairs in {checked} checks, all GPU candidates; {walls} wall \
             contacts, all active GPU slots ({inactive_walls} wall slots inactive in all)"
        );
        assert!(checked > 0, "{name}");
        // The wall scenes touch their walls in the checks, and skip their far wall slots.
        if name == "pile" || name == "disk_wall" {
            assert!(walls > 0, "{name}: no wall contact checked");
            assert!(inactive_walls > 0, "{name}: every wall slot active");
        }
        total += pairs;
    }
    assert!(total > 100, "only {total} active pairs checked");
}

/// The 1e4-element pile of the bench (100 disks of 108 elements, one `bodies = "all"` table and
/// a wall) through its first collisions, on both backends: to 0.13 ms, in which the lowest row
/// meets the wall (from 30 us) and the disks one another (from 60 us; at 60, 90, 100 and 130 us
/// in the history rows of the CPU reference, 2026-11-28). To 0.25 ms the test took 207 s of
/// lavapipe and CPU time, and ran the same kinds of collision again.
#[test]
fn gpu_and_cpu_pile_of_a_hundred_disks_collide_without_penetration_and_with_the_same_bits() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("bench/pile_1e4.toml").replace("end_time = 1e-3", "end_time = 1.3e-4");
    assert!(text.contains("end_time = 1.3e-4"), "the pile's end time");
    let (r, model, u) = run_gpu(&ctx, &text, "pile100-a", None);
    let (r2, _, u2) = run_gpu(&ctx, &text, "pile100-b", None);
    let (rc, uc) = run_cpu(&text, "pile100-cpu");
    let h = 0.01 / 6.0;
    let gpu_in = interpenetration(&model, &u);
    let cpu_in = interpenetration(&model, &uc);
    let active = most_active(&r, 0);
    println!(
        "pile of 100, 0.13 ms: {} steps; energy error gpu {:.2e} cpu {:.2e}; deepest node inside \
         another disk gpu {gpu_in:.2e} m cpu {cpu_in:.2e} m; most nodes in disk contact {active}; \
         {} searches; sweeps mean {:.2} max {}",
        r.summary.steps,
        r.summary.max_energy_error,
        rc.summary.max_energy_error,
        r.summary.contact_searches,
        r.summary.contact_sweeps_mean,
        r.summary.contact_sweeps_max
    );
    assert!(active > 0, "the disks met");
    assert!(most_active(&r, 1) > 0, "the lowest disks met the wall");
    assert!(
        most_active(&rc, 0) > 0 && most_active(&rc, 1) > 0,
        "the same on the CPU"
    );
    assert!(r.summary.max_energy_error < 1e-3);
    assert!(rc.summary.max_energy_error < 1e-3);
    assert!(gpu_in < 1e-4 * h, "{gpu_in:e} m inside");
    assert!(cpu_in < 1e-6 * h, "{cpu_in:e} m inside");
    assert_same_bits((&r, &u), (&r2, &u2), "two GPU runs differ");
}

/// A candidate buffer far too small at first grows (the step stops, the host enlarges the
/// buffer and resumes it), and the run is the same, bit for bit, as one that never had to grow.
#[test]
fn gpu_candidate_buffer_grows_and_the_run_is_unchanged() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("stress/striker_plate_gpu_energy.toml")
        .replace("end_time = 3.2e-6", "end_time = 1.0e-6");
    assert!(text.contains("end_time = 1.0e-6"));
    let (r, _, u, grows) = run_gpu_with(&ctx, &text, "grow-default", ContactOptions::default());
    let small = ContactOptions {
        candidate_capacity: Some(8),
        ..ContactOptions::default()
    };
    let (rs, _, us, grows_small) = run_gpu_with(&ctx, &text, "grow-small", small);
    println!("candidate buffer: {grows} grows from the default, {grows_small} from 8 words");
    assert_eq!(grows, 0);
    assert!(grows_small > 0, "a buffer of 8 candidates must grow");
    assert_same_bits((&r, &u), (&rs, &us), "the grown run differs");
}
