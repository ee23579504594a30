//! The one-workgroup solve's colouring of its Lagrange constraints (`shaders/contact_colour.wgsl`,
//! `compact`) read back from the device and checked against its CPU reference,
//! `ricochet::gpu::contact::colouring::colours`: in parallel rounds (GPUs) and in one invocation
//! (CPU adapters), each in workgroup memory and through storage.

use super::*;

use ricochet::gpu::contact::colouring::{colours, SERIAL};
use ricochet::gpu::contact::ContactOptions;

/// What [`check_last`] saw over a run.
#[derive(Default)]
struct Seen {
    checked: usize,
    largest: usize,
    colours: usize,
    /// Compactions of at most `bound` constraints on more than 1.5 `bound` nodes: those that the
    /// compaction in workgroup memory gives up to the one through storage.
    beyond_nodes: usize,
}

/// The last compaction of `gpu`: its constraints grouped by the colours the reference gives (the
/// greedy colouring in the hashed order of their slots when `parallel`, else in slot order), in
/// slot order within a colour, no two of a colour sharing a node.
fn check_last(
    gpu: &mut GpuSolver,
    parallel: bool,
    bound: Option<u32>,
    what: &str,
    seen: &mut Seen,
) {
    let last = gpu.contact_last_colouring().expect("colouring");
    let n = last.constraints.len();
    let o = &last.offsets;
    assert_eq!(o.len(), SERIAL as usize + 2);
    assert!(o.windows(2).all(|w| w[0] <= w[1]), "{what}: offsets {o:?}");
    assert_eq!(o[SERIAL as usize + 1] as usize, n);
    let expected = colours(&last.constraints, parallel);
    for c in 0..=SERIAL as usize {
        let group = &last.constraints[o[c] as usize..o[c + 1] as usize];
        assert!(
            group.windows(2).all(|w| w[0].0 < w[1].0),
            "{what}: colour {c} not in slot order"
        );
        let mut nodes: Vec<u32> = group
            .iter()
            .flat_map(|g| g.1)
            .filter(|&x| x != u32::MAX)
            .collect();
        let all = nodes.len();
        nodes.sort_unstable();
        nodes.dedup();
        assert_eq!(nodes.len(), all, "{what}: colour {c} has a node twice");
        for at in o[c] as usize..o[c + 1] as usize {
            assert_eq!(
                expected[at], c as u32,
                "{what}: slot {} has colour {c} on the device, {} in the reference",
                last.constraints[at].0, expected[at]
            );
        }
        if !group.is_empty() {
            seen.colours = seen.colours.max(c + 1);
        }
    }
    let mut nodes: Vec<u32> = last
        .constraints
        .iter()
        .flat_map(|c| c.1)
        .filter(|&x| x != u32::MAX)
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    if let Some(b) = bound.filter(|&b| b > 0).map(|b| b as usize) {
        if n <= b && 2 * nodes.len() > 3 * b {
            seen.beyond_nodes += 1;
        }
    }
    seen.checked += n;
    seen.largest = seen.largest.max(n);
}

fn solver(ctx: &Arc<GpuContext>, text: &str, options: ContactOptions) -> GpuSolver {
    let (scene, model, plan) = load(text, "colouring");
    GpuSolver::with_options(ctx.clone(), &model, &plan, schedule(&scene), None, options)
        .expect("gpu solver")
}

/// The striker into its plate (two-pass Lagrange constraints on two meshes, hundreds a step),
/// with either colouring, its compaction in workgroup memory at the device's bound and at 8
/// constraints (so that its larger steps go through storage), through storage alone, and with
/// the one-workgroup kernels at 64 threads: every 10 steps, [`check_last`].
#[test]
fn gpu_colouring_of_the_one_workgroup_solve_is_its_cpu_reference() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("stress/striker_plate_gpu_energy.toml");
    // (The adapter's workgroup, and 64 threads: on lavapipe a workgroup of 8 runs in lock step,
    // which hides a missing barrier.)
    let sizes = [
        (None, None),
        (Some(8), None),
        (Some(0), None),
        (None, Some(64)),
    ];
    for (parallel, (local, group)) in sizes.into_iter().flat_map(|s| [(true, s), (false, s)]) {
        let options = ContactOptions {
            multi: Some(false),
            compact_local: local,
            group,
            parallel_colouring: Some(parallel),
            ..ContactOptions::default()
        };
        let mut gpu = solver(&ctx, &text, options);
        let what =
            format!("parallel {parallel}, workgroup memory up to {local:?}, group {group:?}");
        let mut seen = Seen::default();
        for _ in 0..12 {
            if gpu.run_steps(10).expect("steps") == 0 {
                break;
            }
            check_last(&mut gpu, parallel, local, &what, &mut seen);
        }
        println!(
            "{what}: {} constraints checked, at most {} in a compaction, {} colours",
            seen.checked, seen.largest, seen.colours
        );
        assert!(
            seen.largest > 8,
            "{what}: the striker's compactions reach more than 8"
        );
        assert!(seen.colours >= 2, "{what}: a colouring with neighbours");
    }
}

/// The pile (disks on a wall and on each other: a few constraints a step, on their own nodes)
/// with the compaction in workgroup memory bounded at 4 constraints and so 6 nodes: compactions
/// of at most 4 constraints on more than 6 nodes go through storage after all, with the same
/// colours; every step from 400 (the disks meet the wall near step 440) to 700, [`check_last`],
/// with either colouring.
#[test]
fn gpu_colouring_falls_back_to_storage_when_the_nodes_exceed_the_bound() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("pile.toml");
    for parallel in [true, false] {
        let options = ContactOptions {
            multi: Some(false),
            compact_local: Some(4),
            parallel_colouring: Some(parallel),
            ..ContactOptions::default()
        };
        let mut gpu = solver(&ctx, &text, options);
        gpu.run_steps(400).expect("steps");
        let what = format!("pile, parallel {parallel}");
        let mut seen = Seen::default();
        for _ in 0..300 {
            if gpu.run_steps(1).expect("steps") == 0 {
                break;
            }
            check_last(&mut gpu, parallel, Some(4), &what, &mut seen);
        }
        println!(
            "{what}: {} constraints checked, {} compactions beyond the bound's nodes",
            seen.checked, seen.beyond_nodes
        );
        assert!(
            seen.beyond_nodes > 0,
            "{what}: a compaction beyond the bound's nodes"
        );
    }
}
