//! A scene pays only for what it uses, on the GPU: for the scenes of the CPU plan tests, the
//! buffers allocated are exactly those [`expected_buffers`] derives from the plan (the
//! specification), and each optional kernel exists exactly when the plan has its stage; the bench's
//! ratios are reported at a tiny size.

use std::collections::BTreeSet;

use ricochet::gpu::GpuSolver;
use ricochet::plan::Plan;
use ricochet::plan::Stage::*;
use ricochet::run::schedule;

use crate::{context, load, GPU_LOCK};

#[path = "../shared/plan_scenes.rs"]
mod scenes;
use scenes::cases;

/// The contact kernel's buffers (`src/gpu/contact.rs`).
const CONTACT: [&str; 11] = [
    "contact_state",
    "contact_nodes",
    "contact_reference",
    "contact_slots",
    "contact_segments",
    "contact_nodal",
    "contact_constraints",
    "contact_workspace",
    "contact_candidates",
    "contact_workspace_f32",
    "contact_history",
];
const CONTACT_INDEX: [&str; 2] = ["contact_indirect", "contact_index"];

/// The buffers a plan needs on the device, by name, right after the solver is built.
fn expected_buffers(plan: &Plan) -> BTreeSet<&'static str> {
    // Every scene: parameters and the control block; elements, bodies, nodal state, inverse
    // masses and the force gather (adjacency, element force slots); each element's stable step
    // (checked against a fixed step too); v^{n-1/2} and the per-node, per-element sample sources
    // of the history rows; the reductions (partials and instances; the partials at the minimum
    // size when the control workgroup reduces directly, see `reduction_scratch_is_minimal...`);
    // the history ring, its times, the indirect size of the sum dispatch; the readback.
    let mut b: BTreeSet<&'static str> = [
        "params",
        "control",
        "elements",
        "bodies",
        "nodes",
        "inv_mass",
        "adjacency_offsets",
        "adjacency_slots",
        "element_forces",
        "element_dt",
        "v_prev",
        "sample_sources",
        "dt_partials",
        "instances",
        "sum_partials",
        "history",
        "times",
        "indirect",
        "readback",
        "rows_readback",
        "instance_sums",
    ]
    .into();
    if plan.has(HourglassViscous) || plan.has(BulkViscosity) {
        b.insert("element_dissipation");
    }
    if plan.has(Fields) {
        b.extend(["u_snapshot", "snapshot_readback"]);
    }
    if plan.has(VelocityBoundaries) {
        b.insert("constraints");
    }
    if plan.has(Pressure) {
        b.insert("pressure_entries");
    }
    if plan.has(VelocityBoundaries) || plan.has(Pressure) {
        b.insert("load_curves");
    }
    if plan.has(Pressure) || plan.has(MassDamping) {
        b.insert("v_old");
    }
    if plan.has(Contact) {
        b.extend(CONTACT);
        b.extend(CONTACT_INDEX);
    }
    if plan.has(Failure) {
        b.extend(["body_failure", "element_erosion", "element_eroded_list"]);
    }
    b
}

/// Sizes (bytes) of the plan-dependent buffers that scale with the model.
fn expected_sizes(plan: &Plan) -> Vec<(&'static str, u64)> {
    let (nn, ne, nc) = (
        plan.nodes as u64,
        plan.elements as u64,
        plan.constrained_nodes as u64,
    );
    let mut s = Vec::new();
    if plan.has_dissipation() {
        s.push(("element_dissipation", 32 * ne));
    }
    if plan.has(Fields) {
        s.extend([("u_snapshot", 8 * nn), ("snapshot_readback", 32 * nn)]);
    }
    if plan.has(VelocityBoundaries) {
        s.push(("constraints", (32 * nc).max(16)));
    }
    if plan.has(Pressure) || plan.has(MassDamping) {
        s.push(("v_old", 8 * nn));
    }
    if plan.has(Failure) {
        s.push(("element_erosion", 16 * ne));
        // The list of the elements eroded since the contact surfaces last followed: one entry
        // in a scene without contact.
        let listed = if plan.has(Contact) { ne } else { 1 };
        s.push(("element_eroded_list", 4 * listed));
    }
    s
}

#[test]
fn gpu_allocates_exactly_the_buffers_and_kernels_the_plan_uses() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (name, text, _) in cases() {
        let (scene, model, plan) = load(&text, name);
        for fused in [None, Some(false)] {
            let gpu =
                GpuSolver::with_reductions(ctx.clone(), &model, &plan, schedule(&scene), fused)
                    .expect("gpu solver");
            let state = gpu.state();
            let list: Vec<&str> = state.allocated.iter().map(|(n, _)| *n).collect();
            let names: BTreeSet<&str> = list.iter().copied().collect();
            assert_eq!(names.len(), list.len(), "{name}: a name twice in {list:?}");
            let expected = expected_buffers(&plan);
            assert_eq!(
                names,
                expected,
                "{name} ({plan}): allocated but not expected {:?}, expected but not allocated {:?}",
                names.difference(&expected).collect::<Vec<_>>(),
                expected.difference(&names).collect::<Vec<_>>()
            );
            let size = |n: &str| {
                state
                    .allocated
                    .iter()
                    .find(|(m, _)| *m == n)
                    .map(|(_, b)| *b)
            };
            for (n, bytes) in expected_sizes(&plan) {
                assert_eq!(size(n), Some(bytes), "{name}: size of {n}");
            }
            if state.params.dt_groups == 0 && state.params.sum_groups == 0 {
                // The control workgroup reduces directly: the partials are never used.
                assert_eq!(size("dt_partials"), Some(16), "{name}");
                assert_eq!(size("sum_partials"), Some(16), "{name}");
            }
            let k = gpu.kernels();
            assert_eq!(k.boundary.is_some(), plan.has(VelocityBoundaries), "{name}");
            assert_eq!(k.contact.is_some(), plan.has(Contact), "{name}");
            assert_eq!(state.contact.is_some(), plan.has(Contact), "{name}");
            assert_eq!(k.pressure.is_some(), plan.has(Pressure), "{name}");
            let loads = plan.has(Pressure) || plan.has(MassDamping);
            assert_eq!(k.load_work.is_some(), loads, "{name}");
            assert_eq!(k.features.loads, loads, "{name}");
            assert_eq!(k.features.dissipation, plan.has_dissipation(), "{name}");
            assert_eq!(k.features.fields, plan.has(Fields), "{name}");
            assert_eq!(k.features.failure, plan.has(Failure), "{name}");
            let thermal = model.bodies.iter().any(|b| b.params.has_thermal());
            assert_eq!(k.features.thermal, thermal, "{name}");
        }
    }
}

#[test]
fn gpu_contact_searches_read_back_only_counters_and_rows() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (name, text, _) in cases() {
        if !["no_contact", "contact_pair", "wall_only"].contains(&name) {
            continue;
        }
        let (scene, model, plan) = load(&text, name);
        let mut gpu =
            GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu solver");
        let steps = gpu.run_steps(3).expect("steps");
        assert!(steps >= 3, "{name}");
        let c = ricochet::step::Solver::counters(&gpu);
        assert_eq!(c.contact_searches > 0, plan.has(Contact), "{name}");
        // No staging buffer for node state: the search runs on the device.
        assert!(
            !gpu.state()
                .allocated
                .iter()
                .any(|(n, _)| n.contains("search")),
            "{name}"
        );
        // Per batch: the control block (256 bytes) and the contact counters (64), plus the
        // history rows written (at most one per step, and the first).
        let per_batch = 256 + if plan.has(Contact) { 64 } else { 0 };
        let row_bytes = 4 * gpu.state().params.row_stride as u64
            + gpu
                .state()
                .contact
                .as_ref()
                .map_or(0, |k| 4 * k.params.hist_stride as u64);
        assert!(
            c.bytes_read_back <= c.submissions * per_batch + (steps + 1) * row_bytes,
            "{name}: {} bytes read back in {} submissions",
            c.bytes_read_back,
            c.submissions
        );
        assert!(c.bytes_read_back > 0, "{name}");
    }
}

#[test]
fn gpu_bench_reports_the_full_over_bare_ratio_and_the_contact_share_at_a_tiny_size() {
    // Reported, finite and of the right sign: how large they are is for BENCHMARKS.md.
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let r = ricochet::bench::gpu(ctx, 6, 30, 3).expect("bench");
    eprintln!("{}", ricochet::bench::summary(std::slice::from_ref(&r)));
    assert_eq!((r.elements, r.steps, r.rounds), (36, 30, 3));
    assert_eq!(r.contact_elements, 36 + 6);
    for (key, x) in [
        ("wall_seconds", r.wall_seconds),
        ("bare_seconds", r.bare_seconds),
        ("full_over_bare", r.full_over_bare),
    ] {
        assert!(x.is_finite() && x > 0.0, "{key} = {x}");
    }
    assert!(r.contact_share.is_finite() && r.contact_share < 1.0);
    assert!(r.contact_seconds_per_step.is_finite());
    assert!(r.contact_searches >= 1);
}

#[test]
fn bench_times_the_cpu_and_the_gpu_in_the_same_rounds_and_gives_their_ratio() {
    // `--backend both`: the two backends' variants (with and without contact, with friction and
    // with failure) alternate in one set of rounds; the GPU row carries its speed over the CPU's, the CPU row
    // none. How large the ratio is belongs in BENCHMARKS.md.
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let timing = ricochet::bench::ContactTiming {
        steps: 8,
        rounds: 2,
        warmup: ricochet::bench::DEFAULT_WARMUP,
        pile: ricochet::bench::PileContact::All,
        friction: Some(0.3),
        failure: Some(ricochet::bench::FAILURE_STRAIN),
        plain_sweeps: false,
        // (Constraints one by one, lavapipe's default: the blocks are in tests/gpu/patch.rs and
        // tests/gpu/paths.rs.)
        pair_blocks: None,
        // (The GPUs' colouring, which lavapipe does not take by default.)
        parallel_colouring: Some(true),
        // (The GPUs' sweeps in workgroup memory, which lavapipe does not take by default.)
        local_sweeps: Some(true),
        search_one: None,
        group: None,
        one: None,
        // (Each batch recorded ahead, which lavapipe does not do by default.)
        record_ahead: Some(true),
    };
    let rows =
        ricochet::bench::both_contact(ctx, ricochet::bench::ContactScene::Striker, 4, &timing)
            .expect("bench rows");
    let table = ricochet::bench::contact_table(&rows);
    eprint!("{table}");
    assert_eq!(rows.len(), 2);
    assert_eq!(
        (rows[0].backend.as_str(), rows[1].backend.as_str()),
        ("cpu", "gpu")
    );
    for r in &rows {
        assert_eq!((r.steps, r.rounds, r.elements, r.bodies), (8, 2, 96, 2));
        assert!(r.steps_per_second > 0.0 && r.free_seconds > 0.0);
        assert!(r.friction_steps_per_second.is_some_and(|f| f > 0.0));
        assert!(r.failure_steps_per_second.is_some_and(|f| f > 0.0));
        assert!(r.failure_eroded.is_some());
        // Every erosion in the timed steps is one follow of the contact surfaces at most.
        let (eroded, follows) = (r.failure_eroded, r.failure_follows.expect("follows"));
        assert!(
            eroded.is_some_and(|n| follows <= n),
            "{follows} follows, {eroded:?} eroded"
        );
        assert!(r
            .failure_follow_us
            .is_some_and(|us| us >= 0.0 && us.is_finite()));
    }
    assert_eq!(rows[0].vs_cpu, None);
    let v = rows[1].vs_cpu.expect("the GPU row's ratio to the CPU");
    assert!(v.is_finite() && v > 0.0, "vs_cpu = {v}");
    assert_eq!(rows[0].bytes_read_back_per_step, 0.0);
    assert!(rows[1].bytes_read_back_per_step > 0.0);
    assert!(table.contains("vs CPU"));
}

#[test]
fn a_model_beyond_the_adapters_largest_buffer_is_refused_up_front_naming_its_mesh() {
    // A block just large enough that its element buffer (64 bytes per element) exceeds this
    // adapter's largest storage binding: `run --backend gpu` exits 2 naming the mesh key and the
    // limit, before meshing onto the device. (Where the CPU memory check refuses such a size
    // first, the message names the memory instead: still exit 2 and the key.)
    let Some(ctx) = context() else { return };
    let limits = ctx.device.limits();
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let n = ((limit / ricochet::run::GPU_BYTES_PER_ELEMENT + 1) as f64)
        .sqrt()
        .ceil() as u64;
    let dir = std::env::temp_dir().join(format!("ricochet-gpu-limit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("big.toml");
    std::fs::write(
        &scene,
        format!(
            "[run]\nend_time = 1.0e-9\n[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
             density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n[[body]]\nname = \"b\"\n\
             material = \"steel\"\nmesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [1.0, 1.0], \
             cells = [{n}, {n}] }} }}\n"
        ),
    )
    .unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .args(["run", scene.to_str().unwrap(), "--backend", "gpu", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("body[0].mesh.rectangle.cells") && err.contains(&format!("[{n}, {n}]")),
        "{err}"
    );
    assert!(
        (err.contains("largest buffer binding") && err.contains(&limit.to_string()))
            || err.contains("available"),
        "{err}"
    );

    // The check itself, against a limit one byte short and one exactly met.
    let text =
        "[run]\nend_time = 1.0e-9\n[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
         density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n[[body]]\nname = \"b\"\n\
         material = \"steel\"\nmesh = { rectangle = { origin = [0.0, 0.0], size = [1.0, 1.0], \
         cells = [10, 10] } }\n";
    let (scene, model, _) = load(text, "small.toml");
    let need = ricochet::run::GPU_BYTES_PER_ELEMENT * 100;
    assert!(ricochet::run::check_gpu_limits(&scene, &model, "x", need, need).is_ok());
    let e = ricochet::run::check_gpu_limits(&scene, &model, "x", need - 1, need).unwrap_err();
    assert!(
        e.to_string().contains("body[0].mesh.rectangle.cells"),
        "{e}"
    );
}
