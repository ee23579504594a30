//! GPU backend tests: shader validation (no GPU needed), kernel-level comparison with the CPU
//! reference, parity of whole runs, bit-reproducibility, and submission/readback counts.
//!
//! On a machine without an adapter these tests print that they were skipped; with `CI` set they
//! fail instead, so a CI machine without lavapipe cannot pass silently.
#![allow(clippy::needless_range_loop)]

#[macro_use]
#[path = "shared/scene_text.rs"]
mod scene_text;

use std::path::Path;
use std::sync::{Arc, Mutex};

use ricochet::element::plastic::PlasticState;
use ricochet::element::{evaluate_state, Dissipation};
use ricochet::gpu::kernels::Kernels;
use ricochet::gpu::shader::{self, Features};
use ricochet::gpu::{GpuContext, GpuSolver};
use ricochet::model::Model;
use ricochet::plan::Plan;
use ricochet::run::{run, schedule};
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;
use ricochet::step::Solver;

/// GPU tests at a time: two (lavapipe shares the machine's two cores), or `RICOCHET_GPU_TESTS`,
/// each on a device no other running test holds ([`context`]).
static GPU_LOCK: GpuLock = GpuLock::new();

/// GPU tests at a time when `RICOCHET_GPU_TESTS` does not say: two. With two the whole suite
/// passed in 677 s against 813 s one at a time on the 2-core CI machine (lavapipe, 2026-11-27,
/// 4842683); a test at a time leaves a core idle in each test's serial parts (setup, the CPU
/// reference's run, readbacks).
const DEFAULT_GPU_TESTS: usize = 2;

/// GPU tests at a time: `RICOCHET_GPU_TESTS`, or [`DEFAULT_GPU_TESTS`].
fn gpu_tests() -> usize {
    std::env::var("RICOCHET_GPU_TESTS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(DEFAULT_GPU_TESTS)
        .max(1)
}

/// A counting lock over the GPU tests ([`GPU_LOCK`]): `lock()` (with `Mutex::lock`'s shape) takes
/// one of `RICOCHET_GPU_TESTS` turns.
struct GpuLock {
    /// Turns held.
    busy: Mutex<usize>,
    free: std::sync::Condvar,
}

/// A GPU test's turn, given back when dropped.
struct GpuPermit<'a> {
    lock: &'a GpuLock,
}

impl GpuLock {
    /// Free: no turn held.
    const fn new() -> Self {
        GpuLock {
            busy: Mutex::new(0),
            free: std::sync::Condvar::new(),
        }
    }

    /// One turn, once fewer than `RICOCHET_GPU_TESTS` (default [`DEFAULT_GPU_TESTS`]) are held.
    fn lock(&self) -> Result<GpuPermit<'_>, std::sync::PoisonError<GpuPermit<'_>>> {
        Ok(self.shared(gpu_tests()))
    }

    /// One of `most` (at least one) turns, as [`GpuLock::lock`].
    fn shared(&self, most: usize) -> GpuPermit<'_> {
        let most = most.max(1);
        let mut busy = self.busy.lock().unwrap_or_else(|e| e.into_inner());
        while *busy >= most {
            busy = self.free.wait(busy).unwrap_or_else(|e| e.into_inner());
        }
        *busy += 1;
        GpuPermit { lock: self }
    }
}

impl Drop for GpuPermit<'_> {
    fn drop(&mut self) {
        let mut busy = self.lock.busy.lock().unwrap_or_else(|e| e.into_inner());
        *busy -= 1;
        self.lock.free.notify_all();
    }
}

/// The GPU lock's turns under contention (no GPU needed): never more than `most` at once, and
/// `most` do overlap.
#[test]
fn gpu_lock_gives_at_most_n_turns_at_once() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::Duration;
    let lock = GpuLock::new();
    let held = AtomicUsize::new(0);
    let most_held = AtomicUsize::new(0);
    let turns = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                for _ in 0..60 {
                    let _p = lock.shared(2);
                    let now = held.fetch_add(1, Ordering::SeqCst) + 1;
                    most_held.fetch_max(now, Ordering::SeqCst);
                    assert!(now <= 2, "{now} turns at once");
                    std::thread::sleep(Duration::from_micros(300));
                    held.fetch_sub(1, Ordering::SeqCst);
                    turns.fetch_add(1, Ordering::SeqCst);
                }
            });
        }
    });
    assert_eq!(turns.load(Ordering::SeqCst), 240);
    assert_eq!(most_held.load(Ordering::SeqCst), 2, "two turns overlapped");
    assert_eq!(*lock.busy.lock().unwrap(), 0);
}

/// A device of the default adapter for a GPU test, from a pool of as many as GPU tests run at
/// once ([`gpu_tests`]): one that no running test holds (a test holds its clone until it ends),
/// opened while the pool is not full, or else the one the fewest hold. lavapipe runs each
/// device's queue in one thread, and with `LP_NUM_THREADS=0` (as `.ci/run` sets) every dispatch
/// in it: two tests sharing one process-wide device took turns on one core for their GPU work.
/// A device reused by the next test keeps the kernels its scenes compiled (its `KernelCache`).
fn context() -> Option<Arc<GpuContext>> {
    static POOL: Mutex<Vec<Arc<GpuContext>>> = Mutex::new(Vec::new());
    let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(free) = pool.iter().find(|c| Arc::strong_count(c) == 1) {
        return Some(free.clone());
    }
    if pool.len() < gpu_tests() || pool.is_empty() {
        match GpuContext::new(None) {
            Ok(ctx) => {
                pool.push(Arc::new(ctx));
                return pool.last().cloned();
            }
            Err(e) if pool.is_empty() => {
                if std::env::var_os("CI").is_some() {
                    panic!("CI is set but no GPU adapter is available: {e}");
                }
                eprintln!("skipped: no GPU adapter ({e})");
                return None;
            }
            Err(_) => {}
        }
    }
    pool.iter().min_by_key(|c| Arc::strong_count(c)).cloned()
}

/// A folder under the temporary folder for one run's outputs, `ricochet-{what}-{pid}-{n}` with `n`
/// counting up in this process: two GPU tests run at once, and two helpers called with the same
/// name (`both(.., "rods", ..)` in two tests) would otherwise write into one folder, which the
/// output lock refuses to the second (`InUse`).
fn scratch(what: &str) -> std::path::PathBuf {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    std::env::temp_dir().join(format!("ricochet-{what}-{}-{n}", std::process::id()))
}

fn load(text: &str, name: &str) -> (Scene, Model, Plan) {
    let scene = Scene::parse(text, Path::new(name)).expect("scene parses");
    let model = ricochet::run::model(&scene).expect("model builds");
    let plan = Plan::new(&scene, &model);
    (scene, model, plan)
}

/// The largest difference of a force component of an element's corners between the GPU
/// (`gpu`) and the CPU reference (`cpu`), relative to the largest CPU component (at least
/// 1e-30).
fn force_difference(gpu: &[[f64; 2]; 4], cpu: &[[f64; 2]; 4]) -> f64 {
    let scale = cpu
        .iter()
        .map(|f| f[0].abs().max(f[1].abs()))
        .fold(0.0f64, f64::max)
        .max(1e-30);
    let mut worst: f64 = 0.0;
    for a in 0..4 {
        for c in 0..2 {
            worst = worst.max((gpu[a][c] - cpu[a][c]).abs() / scale);
        }
    }
    worst
}

fn asset(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets")
            .join(name),
    )
    .expect("asset exists")
}

#[test]
fn every_shader_variant_validates_with_naga() {
    for features in Features::all() {
        for (name, src) in Kernels::sources() {
            let wgsl = shader::source(&src, features);
            shader::validate(name, &wgsl).unwrap_or_else(|e| panic!("{features:?}: {e}"));
        }
    }
}

#[test]
fn variants_compile_only_what_the_scene_needs() {
    let plain = shader::source(ricochet::gpu::element::SOURCE, Features::default());
    assert!(
        !plain.contains("elem_state"),
        "no dissipation buffer without dissipation"
    );
    let diss = shader::source(
        ricochet::gpu::element::SOURCE,
        Features {
            dissipation: true,
            ..Features::default()
        },
    );
    assert!(diss.contains("elem_state"));
    // Only the material models, formulations and hourglass forms of the scene's bodies.
    let linear = shader::source(
        ricochet::gpu::element::SOURCE,
        Features {
            neo_hookean: false,
            plane_stress: false,
            hourglass_stiffness: false,
            ..Features::default()
        },
    );
    assert!(linear.contains("b.lambda_plane * tr"));
    assert!(
        !linear.contains("jf_cof") && !linear.contains("let stiffness = b.hourglass"),
        "no neo-Hookean branch nor stiffness hourglass in a linear elastic scene"
    );
    assert!(!linear.contains("let axi = b.formulation"));
    let rubber = shader::source(
        ricochet::gpu::element::SOURCE,
        Features {
            linear_elastic: false,
            plane_stress: false,
            ..Features::default()
        },
    );
    assert!(rubber.contains("jf_cof") && !rubber.contains("b.lambda_plane * tr"));
    assert!(
        !rubber.contains("for (var it = 0; it < 6; it++)"),
        "no plane stress iteration in a plane strain scene"
    );
    // Only the contact methods of the scene's contacts and walls.
    let contact = |springs: bool, friction: bool| {
        ricochet::gpu::contact::stage_source(
            &[ricochet::gpu::contact::narrow::SOURCE],
            Features {
                contact_springs: springs,
                contact_friction: friction,
                ..Features::default()
            },
        )
    };
    let lagrange = contact(false, false);
    assert!(
        lagrange.contains("const SPRINGS: bool = false;")
            && lagrange.contains("const FRICTION: bool = false;")
    );
    let rough = contact(true, true);
    assert!(
        rough.contains("const SPRINGS: bool = true;")
            && rough.contains("const FRICTION: bool = true;")
    );
    let node = shader::source(ricochet::gpu::node::SOURCE, Features::default());
    assert!(
        !node.contains("u_snap"),
        "no snapshot buffer without fields"
    );
    assert!(
        !node.contains("v_old") && !node.contains("damp_c *"),
        "no load variant"
    );
    let loaded = shader::source(
        ricochet::gpu::node::SOURCE,
        Features {
            loads: true,
            ..Features::default()
        },
    );
    assert!(loaded.contains("v_old") && loaded.contains("ctrl.damp_c"));
    assert_eq!(
        loaded.matches("let vp =").count(),
        1,
        "exactly one branch of //#if loads ... //#else ... //#endif"
    );
}

/// A scene of `n` x `m` distorted elements with all material and hourglass variants.
fn mixed_scene() -> String {
    let mut s = String::from(
        "[run]\nend_time = 1.0e-4\n\n\
         [[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n\n\
         [[material]]\nname = \"rubber\"\nmodel = \"neo_hookean\"\ndensity = 1100.0\nyoungs_modulus = 1.0e7\npoisson_ratio = 0.45\n\n\
         [[material]]\nname = \"copper\"\nmodel = \"j2_plastic\"\ndensity = 8930.0\nyoungs_modulus = 1.17e11\npoisson_ratio = 0.35\nyield_stress = 4.0e8\nhardening_modulus = 1.0e8\n",
    );
    let combos = [
        ("steel", "plane_strain", "viscous"),
        ("steel", "plane_stress", "stiffness"),
        ("rubber", "plane_strain", "stiffness"),
        ("rubber", "plane_stress", "viscous"),
        ("steel", "plane_strain", "none"),
        ("steel", "axisymmetric", "viscous"),
        ("rubber", "axisymmetric", "stiffness"),
        ("copper", "plane_strain", "viscous"),
        ("copper", "axisymmetric", "none"),
    ];
    for (k, (mat, form, hg)) in combos.iter().enumerate() {
        // An axisymmetric body has no thickness (per radian).
        let thickness = if *form == "axisymmetric" {
            ""
        } else {
            "thickness = 0.02\n"
        };
        // Odd sizes: not multiples of the workgroup size.
        s.push_str(&format!(
            "\n[[body]]\nname = \"b{k}\"\nmaterial = \"{mat}\"\nformulation = \"{form}\"\n{thickness}\
             mesh = {{ rectangle = {{ origin = [{x}, 0.0], size = [0.03, 0.02], cells = [{nx}, 3] }} }}\n\
             hourglass = {{ form = \"{hg}\", coefficient = 0.1 }}\n",
            x = 0.1 * k as f64,
            nx = 5 + 2 * k
        ));
    }
    s
}

/// Deterministic pseudo-random numbers in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[test]
fn element_kernel_matches_cpu_reference_on_random_states() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (scene, model, plan) = load(&mixed_scene(), "mixed.toml");
    let mut gpu = GpuSolver::new(ctx, &model, &plan, schedule(&scene)).expect("gpu solver");
    let mut rng = Lcg(7);
    // Cases: zero state, small random strains (1e-3 of the element size), random velocities
    // (bulk viscosity and viscous hourglass active), and larger strains (3e-2). The J2 bodies
    // yield; the kernel keeps the state it returns to, and so does the CPU side here.
    let mut plastic = vec![PlasticState::VIRGIN; model.element_count()];
    let h = 0.006;
    for (amp_u, amp_v) in [
        (0.0, 0.0),
        (1e-3 * h, 0.0),
        (1e-3 * h, 5.0),
        (3e-2 * h, 0.0),
    ] {
        let u: Vec<[f64; 2]> = (0..model.node_count())
            .map(|_| [amp_u * rng.next(), amp_u * rng.next()])
            .collect();
        let v: Vec<[f64; 2]> = (0..model.node_count())
            .map(|_| [amp_v * rng.next(), amp_v * rng.next()])
            .collect();
        let (forces, dts) = gpu.element_stage(&u, &v).expect("element stage");
        let mut worst: f64 = 0.0;
        for e in 0..model.element_count() {
            let q = model.quads[e];
            let ue = q.map(|i| u[i as usize]);
            let ve = q.map(|i| v[i as usize]);
            let cpu = evaluate_state(
                model.params(e),
                &model.geometry(e),
                &model.corners[e],
                &ue,
                &ve,
                &Dissipation::default(),
                0.0,
                &plastic[e],
            );
            plastic[e] = cpu.plastic;
            worst = worst.max(force_difference(&forces[e], &cpu.force));
            let ddt = (dts[e] - cpu.dt).abs() / cpu.dt;
            assert!(ddt < 1e-5, "element {e}: dt {} vs {}", dts[e], cpu.dt);
        }
        // f32 against f64: relative to the element's largest force component.
        eprintln!("amp_u {amp_u:e} amp_v {amp_v}: worst relative force difference {worst:.2e}");
        assert!(worst < 2e-3, "worst relative force difference {worst:e}");
    }
}

/// A scene of the mixed quad/triangle square of `tests/data/gmsh/mixed.msh` (20 quads, 35
/// triangles), with `body` lines added to its body.
fn mixed_mesh_scene(model: &str, formulation: &str, run: &str, body: &str) -> String {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gmsh/mixed.msh");
    format!(
        "[run]\nend_time = 2.0e-4\n{run}\n[[material]]\nname = \"steel\"\nmodel = \"{model}\"\n\
         density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n[[body]]\nname = \"square\"\n\
         material = \"steel\"\nformulation = \"{formulation}\"\n{}\
         mesh = {{ gmsh = {:?}, group = \"square\" }}\n{body}\n",
        if formulation == "axisymmetric" {
            ""
        } else {
            "thickness = 0.02\n"
        },
        mesh.to_string_lossy()
    )
}

/// The constant-strain patch test on the GPU element kernel, on the mixed quad/triangle mesh
/// that Gmsh made: u = A X + shift uploaded, the element stage run once. Each element's stress
/// recovered from its nodal forces (sum_a f_a X_a^T = -A0 t P, since the gradients reproduce
/// linear fields), the interior nodes' force and the boundary nodes' consistent traction, all
/// to 1e-5 of the stress (f32); and the stable step as on the CPU.
#[test]
fn element_kernel_passes_the_patch_test_on_the_mixed_gmsh_mesh() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let grad = [[1.0e-3, 4.0e-4], [-2.0e-4, -5.0e-4]];
    let shift = [3.0e-4, -7.0e-4];
    let (e_mod, nu, t) = (2.1e11f64, 0.3f64, 0.02);
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for (formulation, hourglass) in [
        ("plane_strain", "stiffness"),
        ("plane_stress", "viscous"),
        ("plane_strain", "none"),
    ] {
        let text = mixed_mesh_scene(
            "linear_elastic",
            formulation,
            "",
            &format!("hourglass = {{ form = \"{hourglass}\", coefficient = 0.1 }}"),
        );
        let (scene, model, plan) = load(&text, "mixed_patch.toml");
        let tris = model
            .quads
            .iter()
            .filter(|q| ricochet::geometry::is_triangle(q))
            .count();
        assert_eq!((model.element_count(), tris), (55, 35));
        let mut gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
        let u: Vec<[f64; 2]> = model
            .position
            .iter()
            .map(|x| {
                [
                    grad[0][0] * x[0] + grad[0][1] * x[1] + shift[0],
                    grad[1][0] * x[0] + grad[1][1] * x[1] + shift[1],
                ]
            })
            .collect();
        let (forces, dts) = gpu
            .element_stage(&u, &vec![[0.0; 2]; model.node_count()])
            .expect("element stage");
        // Hooke's stress of the field (plane strain or plane stress).
        let (exx, eyy, exy) = (grad[0][0], grad[1][1], 0.5 * (grad[0][1] + grad[1][0]));
        let (sxx, syy) = if formulation == "plane_strain" {
            let k = e_mod / ((1.0 + nu) * (1.0 - 2.0 * nu));
            (
                k * ((1.0 - nu) * exx + nu * eyy),
                k * (nu * exx + (1.0 - nu) * eyy),
            )
        } else {
            let k = e_mod / (1.0 - nu * nu);
            (k * (exx + nu * eyy), k * (nu * exx + eyy))
        };
        let sxy = e_mod / (1.0 + nu) * exy;
        let sigma = [[sxx, sxy], [sxy, syy]];
        let scale = sxx.abs().max(syy.abs()).max(sxy.abs());
        let mut node_force = vec![[0.0f64; 2]; model.node_count()];
        for e in 0..model.element_count() {
            let q = model.quads[e];
            let x = q.map(|i| model.position[i as usize]);
            let g = model.geometry(e);
            let mut p = [[0.0f64; 2]; 2];
            for a in 0..4 {
                for i in 0..2 {
                    for j in 0..2 {
                        p[i][j] -= forces[e][a][i] * x[a][j] / (g.area * t);
                    }
                    node_force[q[a] as usize][i] += forces[e][a][i];
                }
            }
            for i in 0..2 {
                for j in 0..2 {
                    worst.0 = worst.0.max((p[i][j] - sigma[i][j]).abs() / scale);
                }
            }
            let cpu = evaluate_state(
                model.params(e),
                &g,
                &model.corners[e],
                &q.map(|i| u[i as usize]),
                &[[0.0; 2]; 4],
                &Dissipation::default(),
                0.0,
                &PlasticState::VIRGIN,
            );
            assert!(
                ((dts[e] - cpu.dt) / cpu.dt).abs() < 1e-6,
                "element {e} ({q:?}): dt {} against {}",
                dts[e],
                cpu.dt
            );
        }
        // The consistent traction t sigma n on the boundary edges, half to each end; interior
        // nodes get nothing.
        let expected = traction::traction_forces(&model, sigma, t);
        let f_scale = scale * t * 1.0;
        for (i, (f, w)) in node_force.iter().zip(&expected).enumerate() {
            let d = (f[0] - w[0]).hypot(f[1] - w[1]) / f_scale;
            if w == &[0.0, 0.0] {
                worst.2 = worst.2.max(d);
            } else {
                worst.1 = worst.1.max(d);
            }
            assert!(
                d < 1e-5,
                "{formulation}, {hourglass}: node {i} force {f:?} against {w:?}"
            );
        }
        assert!(
            worst.0 < 1e-5,
            "{formulation}, {hourglass}: stress error {:e}",
            worst.0
        );
    }
    eprintln!(
        "GPU patch test on mixed.msh: stress error {:.2e}, boundary force error {:.2e}, interior force {:.2e} of sigma t L",
        worst.0, worst.1, worst.2
    );
}

/// The element kernel against the CPU reference on the quads and triangles of the mixed mesh,
/// from random states, in plane strain with bulk viscosity and viscous hourglass control and in
/// the axisymmetric formulation (a triangle's centroid weights), neo-Hookean.
#[test]
fn element_kernel_matches_cpu_reference_on_triangles() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let mut rng = Lcg(11);
    for (formulation, x0) in [("plane_strain", 0.0), ("axisymmetric", 0.0)] {
        let text = mixed_mesh_scene(
            "neo_hookean",
            formulation,
            "bulk_viscosity = { linear = 0.06, quadratic = 1.5 }",
            "hourglass = { form = \"viscous\", coefficient = 0.1 }",
        );
        let (scene, model, plan) = load(&text, "mixed_kernel.toml");
        let mut gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
        let h = 0.2;
        let mut worst = 0.0f64;
        for (amp_u, amp_v) in [(1e-3 * h, 0.0), (1e-3 * h, 5.0), (3e-2 * h, 2.0)] {
            let u: Vec<[f64; 2]> = (0..model.node_count())
                .map(|i| {
                    // No radial displacement on the axis (x = 0) of the axisymmetric body.
                    let r = if model.position[i][0] > x0 { 1.0 } else { 0.0 };
                    [r * amp_u * rng.next(), amp_u * rng.next()]
                })
                .collect();
            let v: Vec<[f64; 2]> = (0..model.node_count())
                .map(|i| {
                    let r = if model.position[i][0] > x0 { 1.0 } else { 0.0 };
                    [r * amp_v * rng.next(), amp_v * rng.next()]
                })
                .collect();
            let (forces, dts) = gpu.element_stage(&u, &v).expect("element stage");
            for e in 0..model.element_count() {
                let q = model.quads[e];
                let cpu = evaluate_state(
                    model.params(e),
                    &model.geometry(e),
                    &model.corners[e],
                    &q.map(|i| u[i as usize]),
                    &q.map(|i| v[i as usize]),
                    &Dissipation::default(),
                    0.0,
                    &PlasticState::VIRGIN,
                );
                worst = worst.max(force_difference(&forces[e], &cpu.force));
                assert!(
                    ((dts[e] - cpu.dt) / cpu.dt).abs() < 1e-5,
                    "{formulation}, element {e}: dt {} vs {}",
                    dts[e],
                    cpu.dt
                );
            }
        }
        eprintln!("{formulation} mixed mesh: worst relative force difference {worst:.2e}");
        assert!(
            worst < 2e-3,
            "{formulation}: worst relative force difference {worst:e}"
        );
    }
}

/// A whole run on the mixed quad/triangle mesh, as on the CPU: the stretched and sheared square
/// with bulk viscosity and stiffness hourglass control on its quads.
#[test]
fn parity_mixed_quad_triangle_mesh() {
    parity(
        "mixed_mesh",
        &mixed_mesh_scene(
            "neo_hookean",
            "plane_strain",
            "bulk_viscosity = { linear = 0.06, quadratic = 1.5 }",
            "velocity_gradient = [[100.0, 20.0], [0.0, -60.0]]\nhourglass = { form = \"stiffness\", coefficient = 0.1 }",
        )
        .replace("end_time = 2.0e-4", "end_time = 2.0e-3"),
    );
}

/// Runs `text` on both backends and returns (cpu samples, gpu samples, cpu u, gpu u).
#[allow(clippy::type_complexity)]
fn both(
    ctx: Arc<GpuContext>,
    text: &str,
    name: &str,
    fused: Option<bool>,
) -> (
    Vec<ricochet::step::Sample>,
    Vec<ricochet::step::Sample>,
    Vec<[f64; 2]>,
    Vec<[f64; 2]>,
    u64,
    u64,
) {
    let (scene, model, plan) = load(text, name);
    let dir = scratch(&format!("gpu-{name}"));
    let mut cpu = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
    let rc = run(&scene, &model, &plan, &mut cpu, &dir.join("cpu"), None).expect("cpu run");
    assert_eq!(rc.summary.status, "completed", "{}", rc.summary.message);
    let mut gpu = GpuSolver::with_reductions(ctx, &model, &plan, schedule(&scene), fused)
        .expect("gpu solver");
    let rg = run(&scene, &model, &plan, &mut gpu, &dir.join("gpu"), None).expect("gpu run");
    assert_eq!(rg.summary.status, "completed", "{}", rg.summary.message);
    let (ug, _) = gpu.nodes().expect("nodes");
    let _ = std::fs::remove_dir_all(&dir);
    (
        rc.samples.into_iter().map(|s| s.0).collect(),
        rg.samples.into_iter().map(|s| s.0).collect(),
        cpu.displacement().to_vec(),
        ug,
        cpu.steps(),
        gpu.steps(),
    )
}

/// The GPU half of [`both`]: the history rows of a GPU run alone (for a second run whose bits are
/// compared with the first).
fn gpu_samples(ctx: Arc<GpuContext>, text: &str, name: &str) -> Vec<ricochet::step::Sample> {
    let (scene, model, plan) = load(text, name);
    let dir = scratch(&format!("gpu-{name}-2"));
    let mut gpu =
        GpuSolver::with_reductions(ctx, &model, &plan, schedule(&scene), None).expect("gpu solver");
    let rg = run(&scene, &model, &plan, &mut gpu, &dir, None).expect("gpu run");
    assert_eq!(rg.summary.status, "completed", "{}", rg.summary.message);
    let _ = std::fs::remove_dir_all(&dir);
    rg.samples.into_iter().map(|s| s.0).collect()
}

fn parity(name: &str, text: &str) {
    parity_with(name, text, None);
}

fn parity_with(name: &str, text: &str, fused: Option<bool>) {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (sc, sg, uc, ug, nc, ng) = both(ctx, text, name, fused);
    assert!(nc.abs_diff(ng) <= 1, "{name}: {nc} and {ng} steps");
    assert_eq!(sc.len(), sg.len(), "{name}: same number of history rows");
    let umax = uc.iter().map(|u| u[0].hypot(u[1])).fold(0.0f64, f64::max);
    let du = uc
        .iter()
        .zip(&ug)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0f64, f64::max);
    let emax = sc
        .iter()
        .map(|s| {
            s.kinetic.abs()
                + s.internal.abs()
                + s.hourglass.abs()
                + s.viscous.abs()
                + s.external.abs()
        })
        .fold(0.0f64, f64::max);
    let mut de: f64 = 0.0;
    let mut shifted = 0;
    for (a, b) in sc.iter().zip(&sg) {
        // With a variable step, f32 and f64 may put a row time on either side of a step boundary.
        assert!(
            a.step.abs_diff(b.step) <= 1,
            "{name}: rows at steps {} and {}",
            a.step,
            b.step
        );
        shifted += usize::from(a.step != b.step);
        for (x, y) in [
            (a.kinetic, b.kinetic),
            (a.internal, b.internal),
            (a.hourglass, b.hourglass),
            (a.viscous, b.viscous),
            (a.external, b.external),
        ] {
            de = de.max((x - y).abs() / emax);
        }
    }
    eprintln!(
        "{name}: {nc} steps, displacement difference {:.2e} of max {umax:.3e}, energy difference {de:.2e}, {shifted} of {} rows one step apart",
        du / umax,
        sc.len()
    );
    assert!(
        du / umax < 1e-4,
        "{name}: displacement difference {:e} relative",
        du / umax
    );
    assert!(de < 1e-4, "{name}: energy difference {de:e} relative");
}

#[test]
fn parity_vibrating_block() {
    parity("vibrating_block", &asset("vibrating_block.toml"));
}

#[test]
fn parity_spinning_disk() {
    parity("spinning_disk", &asset("spinning_disk.toml"));
}

#[test]
fn parity_rods() {
    parity("rods", &asset("rods.toml"));
}

#[test]
fn parity_mixed_materials_with_boundaries() {
    let mut s = mixed_scene();
    s = s.replace(
        "end_time = 1.0e-4",
        "end_time = 2.0e-5\nhistory_interval = 1.0e-6",
    );
    s.push_str("\n[[boundary]]\nbody = \"b0\"\nregion = { min = [-1.0, -1.0], max = [0.0001, 1.0] }\nvelocity = { x = 2.0, y = 0.0 }\n");
    s.push_str("\n[[boundary]]\nbody = \"b3\"\nregion = { min = [-1.0, -1.0], max = [1.0, 0.0001] }\nvelocity = { y = -1.0 }\n");
    parity("mixed", &s);
}

#[test]
fn parity_step_pulse_rod_of_the_wave_tests() {
    // The core step-pulse test's scene (tests/core/wave.rs): a plane-stress rod of 200 cells
    // moving at 5 m/s, stopped at x = 0 by a velocity boundary, fixed step at Courant 0.9, no bulk
    // viscosity, viscous hourglass control.
    let (h, cells, c_number) = (1.0e-3, 200usize, 0.9);
    let dt = c_number * h / (2.1e11f64 / 7850.0).sqrt();
    let s = format!(
        "[run]\nend_time = {end:e}\ntime_step = {dt:e}\nhistory_interval = {hi:e}\n\
         bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}\n\n\
         [[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\n\
         youngs_modulus = 2.1e11\npoisson_ratio = 0.0\n\n\
         [[body]]\nname = \"rod\"\nmaterial = \"steel\"\nformulation = \"plane_stress\"\nthickness = 0.01\n\
         mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{len}, {h}], cells = [{cells}, 1] }} }}\n\
         hourglass = {{ form = \"viscous\", coefficient = 0.1 }}\ninitial_velocity = [5.0, 0.0]\n\n\
         [[boundary]]\nbody = \"rod\"\nregion = {{ min = [-1.0e-9, -1.0], max = [1.0e-9, 1.0] }}\n\
         velocity = {{ x = 0.0 }}\n",
        end = dt * 150.0,
        hi = dt * 10.0,
        len = h * cells as f64,
    );
    parity("step_pulse", &s);
}

#[test]
fn parity_dissipative_block_with_variable_step_of_the_energy_tests() {
    // The core energy test's dissipative case (tests/core/energy.rs): the vibrating block with
    // viscous hourglass control, default bulk viscosity and the variable stable step.
    let s = asset("vibrating_block.toml")
        .replace("time_step = 2.0e-7\n", "")
        .replace("bulk_viscosity = { linear = 0.0, quadratic = 0.0 }\n", "")
        .replace("form = \"stiffness\"", "form = \"viscous\"");
    let scene = ricochet::scene::Scene::parse(&s, std::path::Path::new("vibrating_block.toml"))
        .expect("edited asset parses");
    assert!(scene.run.time_step.is_none(), "variable step");
    assert!(scene.run.bulk_linear > 0.0, "default bulk viscosity");
    assert_eq!(
        scene.bodies[0].hourglass.form,
        ricochet::scene::HourglassForm::Viscous
    );
    parity("dissipative_variable_step", &s);
}

#[test]
fn parity_with_the_multi_level_reductions() {
    // The path GPUs take (and CPU adapters for large models): first-level reduction kernels, then
    // the control workgroup; with boundaries, so that every sum instance is exercised.
    let mut s = mixed_scene();
    s = s.replace(
        "end_time = 1.0e-4",
        "end_time = 2.0e-5\nhistory_interval = 1.0e-6",
    );
    s.push_str("\n[[boundary]]\nbody = \"b0\"\nregion = { min = [-1.0, -1.0], max = [0.0001, 1.0] }\nvelocity = { x = 2.0, y = 0.0 }\n");
    parity_with("mixed_multi_level", &s, Some(false));
    parity_with(
        "vibrating_block_multi_level",
        &asset("vibrating_block.toml"),
        Some(false),
    );
}

/// Coulomb friction on the device (the tangential update in the Lagrange sweeps, its work and
/// force in the reports): the block sliding on a rigid floor and on a clamped block
/// (node-to-segment, both passes), as on the CPU. The floor nodes chatter under the suddenly
/// applied weight, and f32 and f64 chatter differently (the rows' velocities differ by up to
/// 1.3e-3 v0 in that vibration), so what is compared is the motion: the deceleration (least
/// squares over the rows) within 0.2 % of the CPU's and of mu g within 1 %, the friction work
/// within 0.5 %, the friction force mu times the normal one; and the same bits twice.
#[test]
fn friction_as_on_the_cpu_and_the_same_bits_twice() {
    use friction_scenes::*;
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let decel = |rows: &[ricochet::step::Sample]| {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|s| (s.time, s.body_velocity[0][0]))
            .collect();
        -ricochet::verify::metric::line_fit(&points).expect("rows").0
    };
    let ratio = |rows: &[ricochet::step::Sample]| {
        let (ft, fy) = rows[1..].iter().fold((0.0, 0.0), |(a, b), s| {
            (a + s.contacts[0].ft.abs(), b + s.contacts[0].force[1].abs())
        });
        ft / fy
    };
    let bits = |rows: &[ricochet::step::Sample]| -> Vec<u64> {
        rows.iter()
            .flat_map(|s| {
                [
                    s.kinetic,
                    s.friction,
                    s.contact,
                    s.contacts[0].ft,
                    s.contacts[0].force[1],
                ]
            })
            .map(f64::to_bits)
            .collect()
    };
    for (name, text) in sliding_cases(1.0e-3) {
        let (sc, sg, _, _, _, _) = both(ctx.clone(), &text, name, None);
        let sg2 = gpu_samples(ctx.clone(), &text, name);
        assert_eq!(sc.len(), sg.len(), "{name}: rows");
        let (ac, ag) = (decel(&sc), decel(&sg));
        let (wc, wg) = (sc.last().unwrap().friction, sg.last().unwrap().friction);
        eprintln!(
            "{name}: deceleration {ag:.3} m/s^2 (CPU {ac:.3}), friction work {wg:.6} (CPU {wc:.6}), ft / fy {:.4} (CPU {:.4})",
            ratio(&sg),
            ratio(&sc)
        );
        assert!(wc > 0.1, "{name}: friction work {wc}");
        assert!(
            (ag / ac - 1.0).abs() < 2e-3,
            "{name}: deceleration {ag} against {ac}"
        );
        assert!(
            (ag / (MU * G) - 1.0).abs() < 0.01,
            "{name}: deceleration {ag}"
        );
        assert!(
            (wg / wc - 1.0).abs() < 5e-3,
            "{name}: friction work {wg} against {wc}"
        );
        assert!(
            (ratio(&sg) / MU - 1.0).abs() < 0.01,
            "{name}: ft / fy {}",
            ratio(&sg)
        );
        assert!(bits(&sg) == bits(&sg2), "{name}: two GPU runs differ");
    }
}

/// A free fall of 27 000 steps on the device: the node update adds about 1e-4 of the velocity a
/// step, and plain f32 sums drifted 2.2e-4 (vx) and 1.9e-4 (vy) from g t, with an energy error of
/// 2.2e-4 (the incline's block, 32 x 16 quads); node.wgsl's compensated sum keeps both near f32
/// round-off.
#[test]
fn gpu_long_free_fall_keeps_g_t_and_its_energy() {
    use gravity_scene::*;
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (end, dt) = (2.0e-3, 7.4e-8);
    let text = block_scene(0.05, end, dt, 10, false);
    let (scene, model, plan) = load(&text, "long_fall.toml");
    let dir = std::env::temp_dir().join(format!("ricochet-gpu-{}-long-fall", std::process::id()));
    let mut gpu = GpuSolver::new(ctx, &model, &plan, schedule(&scene)).expect("gpu solver");
    let r = run(&scene, &model, &plan, &mut gpu, &dir, None).expect("gpu run");
    let _ = std::fs::remove_dir_all(&dir);
    let last = &r.samples.last().expect("rows").0;
    let v = last.body_velocity[0][1];
    let exact = -G * last.time;
    eprintln!(
        "gpu free fall, {} steps: v = {v:.7} m/s against g t = {exact:.7} ({:.1e}), energy error \
         {:.1e}",
        gpu.steps(),
        v / exact - 1.0,
        r.summary.max_energy_error
    );
    assert!(gpu.steps() > 25_000);
    assert!(
        (v / exact - 1.0).abs() < 1e-5,
        "velocity {v} against {exact}"
    );
    assert!(
        r.summary.max_energy_error < 1e-5,
        "{}",
        r.summary.max_energy_error
    );
}

/// Gravity on the device (the `loads` variant of the node stage, its work with the pressure's):
/// the free fall as on the CPU; the block resting on a rigid wall held by its weight (its
/// displacements, a few nm, are too small for the parity's relative bound in f32).
#[test]
fn gravity_on_the_device() {
    use gravity_scene::*;
    parity("free_fall", &block_scene(0.05, 9.0e-4, 3.0e-7, 50, false));
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (sc, sg, _, ug, _, _) = both(
        ctx,
        &block_scene(0.0, 2.0e-3, 0.0, 2000, true),
        "resting",
        None,
    );
    let (_, model, _) = load(&block_scene(0.0, 2.0e-3, 0.0, 2000, true), "resting.toml");
    let weight = model.bodies[0].mass * G;
    for (name, rows) in [("cpu", &sc), ("gpu", &sg)] {
        let mean = rows.iter().map(|s| s.contacts[0].force[1]).sum::<f64>() / rows.len() as f64;
        let moving = rows
            .iter()
            .map(|s| s.body_velocity[0][1].abs())
            .fold(0.0f64, f64::max);
        eprintln!(
            "resting block ({name}): mean wall force {:.5} of m g, largest |v| {moving:.2e} m/s",
            mean / weight
        );
        assert!(
            (mean / weight - 1.0).abs() < 0.01,
            "{name}: {mean} against {weight}"
        );
        assert!(moving < 1e-3 * G * 2.0e-3, "{name}: {moving}");
    }
    let sink = ug
        .iter()
        .zip(&model.position)
        .filter(|(_, p)| p[1] == 0.0)
        .map(|(u, _)| u[1])
        .fold(0.0f64, f64::min);
    assert!(sink > -1e-9, "gpu: bottom node at {sink:e}");
}

/// Load curves on the device: the pulled bar (a ramped-then-held velocity) and the same bar under
/// a pressure curve, as on the CPU.
#[test]
fn load_curves_as_on_the_cpu() {
    use load_curve_scene::*;
    let pulled = bar_scene(&format!("[[0.0, 0.0], [{RAMP:e}, {V}]]"));
    parity_with("pulled_bar_curve", &pulled, None);
    let pressed = bar_scene("0.0").replace(
        &format!(
            "region = {{ min = [{}, -1.0], max = [{}, 1.0] }}\nvelocity = {{ x = 0.0 }}\n",
            L - 1e-9,
            L + 1e-9
        ),
        &format!(
            "region = {{ min = [{}, -1.0], max = [{}, 1.0] }}\nvelocity = {{ y = 0.0 }}\n\n\
             [[pressure]]\nbody = \"bar\"\nregion = {{ min = [{}, -1.0], max = [{}, 1.0] }}\n\
             value = [[0.0, 0.0], [{RAMP:e}, -1.0e6], [1.0e-4, -2.0e6]]\n",
            L - 1e-9,
            L + 1e-9,
            L - 1e-9,
            L + 1e-9
        ),
    );
    assert!(pressed.contains("[[pressure]]"), "{pressed}");
    parity_with("pressure_curve", &pressed, None);
}

/// 300 one-element bodies, each moving at its own velocity: more sum instances than a reduction
/// workgroup has lanes, so that the second level of the sums (`sum_instances`) and the
/// history's body columns (spread over the control workgroup's lanes) are exercised, fused and
/// not. Each body's velocity and the kinetic energy in every history row as on the CPU.
#[test]
fn many_bodies_sum_their_velocities_and_kinetic_energy_as_on_the_cpu() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let n = 300;
    let mut s = String::from(
        "[run]\nend_time = 3.0e-5\nhistory_interval = 3.0e-6\n\n\
         [[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\n\
         youngs_modulus = 2.1e11\npoisson_ratio = 0.3\n",
    );
    for b in 0..n {
        let (x, y) = ((b % 20) as f64 * 0.02, (b / 20) as f64 * 0.02);
        let (vx, vy) = (1.0 + 0.1 * b as f64, -2.0 + 0.05 * (b % 7) as f64);
        s.push_str(&format!(
            "\n[[body]]\nname = \"b{b}\"\nmaterial = \"steel\"\n\
             mesh = {{ rectangle = {{ origin = [{x:?}, {y:?}], size = [0.01, 0.01], cells = [1, 1] }} }}\n\
             initial_velocity = [{vx:?}, {vy:?}]\n"
        ));
    }
    for fused in [Some(true), Some(false)] {
        let (sc, sg, _, _, _, _) = both(ctx.clone(), &s, "many_bodies", fused);
        assert_eq!(sc.len(), sg.len(), "{fused:?}: same number of history rows");
        assert!(sc.len() >= 4, "{fused:?}: {} rows", sc.len());
        let mut dv: f64 = 0.0;
        let mut de: f64 = 0.0;
        for (a, b) in sc.iter().zip(&sg) {
            assert_eq!(a.body_velocity.len(), n);
            assert_eq!(b.body_velocity.len(), n);
            for (p, q) in a.body_velocity.iter().zip(&b.body_velocity) {
                dv = dv.max((p[0] - q[0]).hypot(p[1] - q[1]) / p[0].hypot(p[1]));
            }
            de = de.max((a.kinetic - b.kinetic).abs() / a.kinetic);
        }
        eprintln!("many bodies {fused:?}: velocity difference {dv:.2e}, kinetic {de:.2e} relative");
        assert!(
            dv < 1e-5,
            "{fused:?}: body velocity difference {dv:e} relative"
        );
        assert!(
            de < 1e-5,
            "{fused:?}: kinetic energy difference {de:e} relative"
        );
    }
}

#[test]
fn same_scene_twice_gives_identical_bits() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = asset("spinning_disk.toml").replace("end_time = 0.05", "end_time = 0.01");
    let (scene, model, plan) = load(&text, "disk.toml");
    let dir = std::env::temp_dir().join(format!("ricochet-det-{}", std::process::id()));
    let mut outs = Vec::new();
    for k in 0..2 {
        let mut gpu =
            GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu solver");
        let out = dir.join(format!("run{k}"));
        let r = run(&scene, &model, &plan, &mut gpu, &out, None).expect("gpu run");
        assert_eq!(r.summary.status, "completed");
        let (u, v) = gpu.nodes().expect("nodes");
        let history = std::fs::read(out.join("history.csv")).expect("history");
        let mut fields = Vec::new();
        for entry in std::fs::read_dir(out.join("fields")).expect("fields") {
            let p = entry.expect("entry").path();
            fields.push((
                p.file_name().map(|s| s.to_owned()),
                std::fs::read(&p).expect("field"),
            ));
        }
        fields.sort();
        outs.push((u, v, history, fields));
    }
    let _ = std::fs::remove_dir_all(&dir);
    let bits = |x: &Vec<[f64; 2]>| {
        x.iter()
            .map(|p| (p[0].to_bits(), p[1].to_bits()))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        bits(&outs[0].0),
        bits(&outs[1].0),
        "displacements differ between runs"
    );
    assert_eq!(
        bits(&outs[0].1),
        bits(&outs[1].1),
        "velocities differ between runs"
    );
    assert_eq!(outs[0].2, outs[1].2, "history.csv differs between runs");
    assert!(!outs[0].3.is_empty());
    assert_eq!(outs[0].3, outs[1].3, "field files differ between runs");
}

#[test]
fn batches_steps_and_reads_back_about_once_per_history_row() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // 10^4 steps with 100 history rows on a small block with a fixed step.
    let text = "[run]\nend_time = 1.0e-3\ntime_step = 1.0e-7\nhistory_interval = 1.0e-5\n\n\
        [[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n\n\
        [[body]]\nname = \"block\"\nmaterial = \"steel\"\nmesh = { rectangle = { origin = [0.0, 0.0], size = [0.05, 0.05], cells = [8, 8] } }\n\
        velocity_gradient = [[10.0, 0.0], [0.0, -10.0]]\n";
    let (scene, model, plan) = load(text, "counts.toml");
    let dir = std::env::temp_dir().join(format!("ricochet-counts-{}", std::process::id()));
    let mut gpu = GpuSolver::new(ctx, &model, &plan, schedule(&scene)).expect("gpu solver");
    let r = run(&scene, &model, &plan, &mut gpu, &dir, None).expect("run");
    let _ = std::fs::remove_dir_all(&dir);
    let s = &r.summary;
    assert_eq!(s.status, "completed", "{}", s.message);
    assert_eq!(s.steps, 10_000);
    assert_eq!(s.history_rows, 101);
    eprintln!(
        "{} steps, {} rows: {} submissions, {} readbacks",
        s.steps, s.history_rows, s.gpu_submissions, s.gpu_readbacks
    );
    assert!(
        s.gpu_readbacks <= s.history_rows as u64 + 5,
        "{} readbacks for {} rows",
        s.gpu_readbacks,
        s.history_rows
    );
    assert!(
        s.gpu_submissions * 32 <= s.steps + 32,
        "{} submissions for {} steps",
        s.gpu_submissions,
        s.steps
    );
}

#[test]
fn unstable_gpu_run_stops_with_a_diagnostic() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // A step far above the stable limit (a scene file above 1.0 is refused up front; the
    // solver's checks are the safety net behind that).
    let text = asset("vibrating_block.toml").replace("time_step = 2.0e-7", "");
    let (scene, model, plan) = load(&text, "unstable.toml");
    let dir = std::env::temp_dir().join(format!("ricochet-unstable-{}", std::process::id()));
    let mut sched = schedule(&scene);
    sched.time_step_scale = 1.8;
    let mut gpu = GpuSolver::new(ctx, &model, &plan, sched).expect("gpu solver");
    let r = run(&scene, &model, &plan, &mut gpu, &dir, None).expect("run");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(r.summary.status, "failed");
    let m = &r.summary.message;
    assert!(
        m.contains("step ")
            && (m.contains("element") || m.contains("node") || m.contains("energy")),
        "{m}"
    );
}

#[test]
fn a_step_longer_than_the_run_or_a_short_run_ends_on_the_end_time_on_both_backends() {
    // A soft block in free flight whose stable step (6.1 s) is longer than the run, and a run of
    // 2.5 steps: both backends land on the end time (the GPU to its f32 tick resolution), with the
    // same number of steps.
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for end in [0.05, 2.5 * 0.9 * 6.7914] {
        let text = format!(
            "[run]\nend_time = {end:e}\n[[material]]\nname = \"r\"\nmodel = \"neo_hookean\"\n\
             density = 1000.0\nyoungs_modulus = 10.0\npoisson_ratio = 0.3\n[[body]]\nname = \"b\"\n\
             material = \"r\"\ninitial_velocity = [2.0, -1.0]\n\
             mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [1.0, 1.0], cells = [1, 1] }} }}\n"
        );
        let (c, g, uc, ug, nc, ng) = both(ctx.clone(), &text, "end_clip.toml", None);
        assert_eq!(nc, ng, "end {end}");
        let (tc, tg) = (c.last().unwrap().time, g.last().unwrap().time);
        assert!((tc - end).abs() <= 1e-12 * end, "cpu: {tc} for {end}");
        assert!((tg - end).abs() <= 1e-6 * end, "gpu: {tg} for {end}");
        // Free flight: u = v T at the end.
        for u in uc.iter().chain(&ug) {
            assert!((u[0] - 2.0 * end).abs() <= 1e-5 * end, "{u:?} for {end}");
        }
    }
}

/// The vibrating block with a pressure load on its top edge (ramped over 1 ms), mass damping, or both.
fn loaded_block(pressure: bool, damping: bool) -> String {
    let mut text = asset("vibrating_block.toml");
    if damping {
        let damped = text.replacen("[run]\n", "[run]\nmass_damping = 2000.0\n", 1);
        assert_ne!(damped, text);
        text = damped;
    }
    if pressure {
        text.push_str(
            "\n[[pressure]]\nbody = \"block\"\nregion = { min = [-0.01, 0.049], max = [0.11, 0.051] }\n\
             value = 1.0e8\nramp = 1.0e-3\n",
        );
    }
    text
}

#[test]
fn parity_pressure_load() {
    // The external column carries the pressure work on both backends (the energy comparison).
    parity("pressure", &loaded_block(true, false));
}

#[test]
fn parity_mass_damping() {
    // The viscous column carries the damping work on both backends.
    parity("damping", &loaded_block(false, true));
}

#[test]
fn parity_pressure_load_with_mass_damping() {
    parity("pressure+damping", &loaded_block(true, true));
}

#[test]
fn pressure_and_damping_compile_their_kernels_only_when_used() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (pressure, damping) in [(false, false), (true, false), (false, true), (true, true)] {
        let (scene, model, plan) = load(&loaded_block(pressure, damping), "loads");
        let gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu solver");
        let names: Vec<&str> = gpu.state().allocated.iter().map(|(n, _)| *n).collect();
        let k = gpu.kernels();
        assert_eq!(k.pressure.is_some(), pressure, "{names:?}");
        assert_eq!(k.load_work.is_some(), pressure || damping);
        assert_eq!(k.features.loads, pressure || damping);
        assert_eq!(names.contains(&"pressure_entries"), pressure, "{names:?}");
        assert_eq!(names.contains(&"v_old"), pressure || damping, "{names:?}");
    }
}

#[path = "shared/friction_scenes.rs"]
mod friction_scenes;
#[path = "shared/gravity_scene.rs"]
mod gravity_scene;
#[path = "shared/load_curve_scene.rs"]
mod load_curve_scene;
#[path = "shared/traction.rs"]
mod traction;

#[path = "gpu/colouring.rs"]
mod colouring;
#[path = "gpu/contact.rs"]
mod contact;
#[path = "gpu/device.rs"]
mod device;
#[path = "gpu/end_time.rs"]
mod end_time;
#[path = "gpu/erosion_contact.rs"]
mod erosion_contact;
#[path = "gpu/failure.rs"]
mod failure;
#[path = "gpu/fuzz.rs"]
mod fuzz;
#[path = "gpu/general.rs"]
mod general;
#[path = "gpu/patch.rs"]
mod patch;
#[path = "gpu/paths.rs"]
mod paths;
#[path = "gpu/plan.rs"]
mod plan;
#[path = "gpu/plastic.rs"]
mod plastic;
#[path = "gpu/restart.rs"]
mod restart;
#[path = "gpu/stress.rs"]
mod stress;
#[path = "gpu/verify.rs"]
mod verify;

/// `GpuSolver::profile_steps` records each part of a step in its own pass between timestamps:
/// the same kernels in the same order, so the state after it is bit for bit that of
/// `run_steps` (contact searches included), and every part of a contact scene takes time.
#[test]
fn profiled_steps_give_the_same_bits_and_time_every_part() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let text = ricochet::bench::striker_text(6, true);
    let (scene, model, plan) = load(&text, "striker.toml");
    let steps = 120;
    let mut plain =
        GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu solver");
    let taken = plain.run_steps(steps).expect("run");
    let mut profiled =
        GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu solver");
    let profile = profiled.profile_steps(steps).expect("profile");
    assert_eq!(plain.steps(), profiled.steps(), "steps taken");
    assert!(
        plain.counters().contact_searches > 1,
        "searches in the profiled steps"
    );
    let bits = |x: Vec<[f64; 2]>| {
        x.iter()
            .map(|p| (p[0].to_bits(), p[1].to_bits()))
            .collect::<Vec<_>>()
    };
    let (u0, v0) = plain.nodes().expect("nodes");
    let (u1, v1) = profiled.nodes().expect("nodes");
    assert_eq!(bits(u0), bits(u1), "displacements differ when profiled");
    assert_eq!(bits(v0), bits(v1), "velocities differ when profiled");
    match profile {
        Some((k, parts)) => {
            assert_eq!(k, taken);
            assert_eq!(parts.len(), ricochet::gpu::solver::PROFILE_PARTS.len());
            for (name, t) in ricochet::gpu::solver::PROFILE_PARTS.iter().zip(&parts) {
                eprintln!("{name}: {:.1} us per step", t * 1e6);
                assert!(*t > 0.0 && t.is_finite(), "{name}: {t} s per step");
            }
        }
        None => assert!(
            !ctx.timestamps,
            "no profile although the adapter has timestamps"
        ),
    }
}
