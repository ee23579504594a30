//! The one-workgroup solve's colouring of its Lagrange constraints (`shaders/contact_solve.wgsl`,
//! `compact`) read back from the device and checked against its CPU reference,
//! `ricochet::gpu::contact::colouring::colours`: in parallel rounds (GPUs) and in one invocation
//! (CPU adapters), each in workgroup memory and through storage.

use super::*;

use ricochet::gpu::contact::colouring::{colours, SERIAL};
use ricochet::gpu::contact::ContactOptions;

/// The striker into its plate (two-pass Lagrange constraints on two meshes, hundreds a step),
/// with either colouring, its compaction in workgroup memory at the device's bound and at 8
/// constraints (so that its larger steps go through storage), through storage alone, and with
/// the one-workgroup kernels at 64 threads: every 10
/// steps the last compaction's constraints are grouped by the colours the reference gives (the
/// greedy colouring in the hashed order of their slots, or in slot order), in slot order within
/// a colour, and no two of a colour share a node.
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
        let (scene, model, plan) = load(&text, "colouring");
        let options = ContactOptions {
            multi: Some(false),
            compact_local: local,
            group,
            parallel_colouring: Some(parallel),
            ..ContactOptions::default()
        };
        let mut gpu =
            GpuSolver::with_options(ctx.clone(), &model, &plan, schedule(&scene), None, options)
                .expect("gpu solver");
        let (mut checked, mut largest, mut most_colours) = (0usize, 0usize, 0usize);
        for _ in 0..12 {
            if gpu.run_steps(10).expect("steps") == 0 {
                break;
            }
            let last = gpu.contact_last_colouring().expect("colouring");
            let n = last.constraints.len();
            let o = &last.offsets;
            assert_eq!(o.len(), SERIAL as usize + 2);
            assert!(
                o.windows(2).all(|w| w[0] <= w[1]),
                "{local:?}: offsets {o:?}"
            );
            assert_eq!(o[SERIAL as usize + 1] as usize, n);
            let expected = colours(&last.constraints, parallel);
            for c in 0..=SERIAL as usize {
                let group = &last.constraints[o[c] as usize..o[c + 1] as usize];
                assert!(
                    group.windows(2).all(|w| w[0].0 < w[1].0),
                    "{local:?}: colour {c} not in slot order"
                );
                let mut nodes: Vec<u32> = group
                    .iter()
                    .flat_map(|g| g.1)
                    .filter(|&x| x != u32::MAX)
                    .collect();
                let all = nodes.len();
                nodes.sort_unstable();
                nodes.dedup();
                assert_eq!(nodes.len(), all, "{local:?}: colour {c} has a node twice");
                for (i, _) in group.iter().enumerate() {
                    let at = o[c] as usize + i;
                    assert_eq!(
                        expected[at], c as u32,
                        "{local:?}: slot {} has colour {c} on the device, {} in the reference",
                        last.constraints[at].0, expected[at]
                    );
                }
                if !group.is_empty() {
                    most_colours = most_colours.max(c + 1);
                }
            }
            checked += n;
            largest = largest.max(n);
        }
        println!(
            "parallel {parallel}, compaction in workgroup memory up to {local:?}, group \
             {group:?}: {checked} constraints checked, at most {largest} in a compaction, \
             {most_colours} colours"
        );
        assert!(
            largest > 8,
            "{local:?}: the striker's compactions reach more than 8"
        );
        assert!(most_colours >= 2, "{local:?}: a colouring with neighbours");
    }
}
