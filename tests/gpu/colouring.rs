//! The one-workgroup solve's colouring of its Lagrange constraints (`shaders/contact_colour.wgsl`,
//! `compact`) read back from the device and checked against its CPU reference,
//! `ricochet::gpu::contact::colouring::colours`: in parallel rounds (GPUs) and in one invocation
//! (CPU adapters), each in workgroup memory and through storage.

use super::*;

use ricochet::gpu::contact::colouring::{colours_paired, PARTNER, SERIAL};
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
    /// Pairs solved as 2 x 2 blocks.
    pairs: usize,
}

/// The last compaction of `gpu`: its constraints grouped by the colours the reference gives (the
/// greedy colouring in the hashed order of their slots when `parallel`, else in slot order, each
/// pair's leader on the nodes of both, its partner listed last), in slot order within a colour,
/// no two of a colour sharing a node (a leader's with its partner's). Each pair: the leader the
/// lower slot, each one's slave an end of the other's segment, each slot in one pair at most.
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
    assert_eq!(o.len(), PARTNER as usize + 2);
    assert!(o.windows(2).all(|w| w[0] <= w[1]), "{what}: offsets {o:?}");
    assert_eq!(o[PARTNER as usize + 1] as usize, n);
    let nodes_of = |k: u32| {
        last.constraints
            .iter()
            .find(|c| c.0 == k)
            .map(|c| c.1)
            .expect("a paired slot is compacted")
    };
    let mut in_pair = std::collections::HashSet::new();
    for &(a, b) in &last.pairs {
        assert!(a < b, "{what}: pair ({a}, {b}) led by the higher slot");
        assert!(
            in_pair.insert(a) && in_pair.insert(b),
            "{what}: slot in two pairs"
        );
        let (na, nb) = (nodes_of(a), nodes_of(b));
        assert!(
            nb[1..].contains(&na[0]) && na[1..].contains(&nb[0]),
            "{what}: pair ({a}, {b}) is not a node pair met from both passes: {na:?} {nb:?}"
        );
    }
    let partners: std::collections::HashSet<u32> = last.pairs.iter().map(|p| p.1).collect();
    let partner_range = &last.constraints[o[PARTNER as usize] as usize..n];
    assert_eq!(
        partner_range.len(),
        partners.len(),
        "{what}: partners listed"
    );
    assert!(partner_range.iter().all(|c| partners.contains(&c.0)));
    let expected = colours_paired(&last.constraints, &last.pairs, parallel);
    for c in 0..=SERIAL as usize {
        let group = &last.constraints[o[c] as usize..o[c + 1] as usize];
        assert!(
            group.windows(2).all(|w| w[0].0 < w[1].0),
            "{what}: colour {c} not in slot order"
        );
        // Each unit's distinct nodes (a leader's with its partner's, which share two).
        let mut nodes: Vec<u32> = group
            .iter()
            .flat_map(|g| {
                let partner = last
                    .pairs
                    .iter()
                    .find(|p| p.0 == g.0)
                    .map(|p| nodes_of(p.1));
                let mut unit: Vec<u32> =
                    g.1.into_iter()
                        .chain(partner.unwrap_or([u32::MAX; 3]))
                        .collect();
                unit.sort_unstable();
                unit.dedup();
                unit
            })
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
    seen.pairs += last.pairs.len();
}

fn solver(ctx: &Arc<GpuContext>, text: &str, options: ContactOptions) -> GpuSolver {
    let (scene, model, plan) = load(text, "colouring");
    GpuSolver::with_options(ctx.clone(), &model, &plan, schedule(&scene), None, options)
        .expect("gpu solver")
}

/// The striker into its plate (two-pass Lagrange constraints on two meshes, hundreds a step,
/// most of them in node pairs met from both passes), with either colouring, its compaction in
/// workgroup memory at the device's bound and at 8 constraints (so that its larger steps go
/// through storage), through storage alone, with the one-workgroup kernels at 64 threads, and
/// without the 2 x 2 blocks (the default: no pair): every 10 steps, [`check_last`].
#[test]
fn gpu_colouring_of_the_one_workgroup_solve_is_its_cpu_reference() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("stress/striker_plate_gpu_energy.toml");
    // (The adapter's workgroup, and 64 threads: on lavapipe a workgroup of 8 runs in lock step,
    // which hides a missing barrier.)
    let sizes = [
        (None, None, true),
        (Some(8), None, true),
        (Some(0), None, true),
        (None, Some(64), true),
        (None, None, false),
    ];
    for (parallel, (local, group, pair_blocks)) in
        sizes.into_iter().flat_map(|s| [(true, s), (false, s)])
    {
        let options = ContactOptions {
            multi: Some(false),
            compact_local: local,
            group,
            parallel_colouring: Some(parallel),
            pair_blocks: Some(pair_blocks),
            ..ContactOptions::default()
        };
        let mut gpu = solver(&ctx, &text, options);
        let what = format!(
            "parallel {parallel}, workgroup memory up to {local:?}, group {group:?}, 2 x 2 \
             blocks {pair_blocks}"
        );
        let mut seen = Seen::default();
        for _ in 0..12 {
            if gpu.run_steps(10).expect("steps") == 0 {
                break;
            }
            check_last(&mut gpu, parallel, local, &what, &mut seen);
        }
        println!(
            "{what}: {} constraints checked, at most {} in a compaction, {} colours, {} pairs",
            seen.checked, seen.largest, seen.colours, seen.pairs
        );
        if pair_blocks {
            assert!(
                4 * seen.pairs > seen.checked,
                "{what}: most constraints paired"
            );
        } else {
            assert_eq!(seen.pairs, 0, "{what}: no pair without the blocks");
        }
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
