//! Helpers shared by the core tests: scenes from text, temporary folders, force assembly,
//! a one-step-at-a-time driver of the CPU solver, the CSV reader and the binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use ricochet::element::{evaluate, Dissipation, ElementParams};
use ricochet::model::Model;
use ricochet::plan::Plan;
use ricochet::run::RunResult;
use ricochet::scene::{Formulation, HourglassForm, Material, MaterialModel, Scene};
use ricochet::step::cpu::CpuSolver;
use ricochet::step::{Event, Failure, Sample, Schedule, Solver};

/// Steel: Young's modulus (Pa).
pub const E_STEEL: f64 = 210e9;
/// Steel: density (kg/m^3).
pub const RHO_STEEL: f64 = 7850.0;

/// A material.
pub fn material(model: MaterialModel, youngs_modulus: f64, nu: f64, density: f64) -> Material {
    Material {
        name: "m".into(),
        model,
        density,
        youngs_modulus,
        poisson_ratio: nu,
        plasticity: None,
        failure: None,
    }
}

/// Element parameters of steel with Poisson's ratio `nu`, thickness `t`, bulk viscosity off.
pub fn steel_params(
    model: MaterialModel,
    nu: f64,
    form: Formulation,
    hourglass: HourglassForm,
    coefficient: f64,
    t: f64,
) -> ElementParams {
    ElementParams::new(
        &material(model, E_STEEL, nu, RHO_STEEL),
        form,
        t,
        hourglass,
        coefficient,
        (0.0, 0.0),
    )
}

/// Parses scene text as if it were the file `test_scene.toml`.
pub fn parse(text: &str) -> Scene {
    Scene::parse(text, Path::new("test_scene.toml"))
        .unwrap_or_else(|e| panic!("scene does not parse: {e}\n{text}"))
}

/// Scene, model and plan of scene text.
pub fn build(text: &str) -> (Scene, Model, Plan) {
    let scene = parse(text);
    let model =
        ricochet::run::model(&scene).unwrap_or_else(|e| panic!("model does not build: {e}"));
    let plan = Plan::new(&scene, &model);
    (scene, model, plan)
}

/// Runs scene text on the CPU reference in a temporary folder (removed after) and asserts that
/// the run completed; the result, the model and the final displacements.
pub fn run_cpu_text(text: &str, name: &str) -> (RunResult, Model, Vec<[f64; 2]>) {
    let (scene, model, plan) = build(text);
    let dir = tmp_dir(name);
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), ricochet::run::schedule(&scene));
    let r = ricochet::run::run(&scene, &model, &plan, &mut solver, &dir, None).expect("run");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let u = solver.displacement().to_vec();
    (r, model, u)
}

/// A fresh, empty temporary folder for this test process.
pub fn tmp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ricochet-core-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temporary folder");
    dir
}

/// Nodal forces (external minus internal) of the whole model for displacements `u` and
/// velocities `v` (no dissipative history), assembled element by element.
pub fn assemble(model: &Model, u: &[[f64; 2]], v: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut f = vec![[0.0; 2]; model.node_count()];
    for e in 0..model.element_count() {
        let q = model.quads[e];
        let out = evaluate(
            model.params(e),
            &model.corners[e],
            &q.map(|i| u[i as usize]),
            &q.map(|i| v[i as usize]),
            &Dissipation::default(),
            0.0,
        );
        for a in 0..4 {
            f[q[a] as usize][0] += out.force[a][0];
            f[q[a] as usize][1] += out.force[a][1];
        }
    }
    f
}

/// A schedule that samples every step, no fields. `interval` must be below the smallest step
/// (the clock then finds a sample due at every t_n).
pub fn every_step(end_time: f64, time_step: Option<f64>, scale: f64, interval: f64) -> Schedule {
    Schedule {
        end_time,
        history_interval: interval,
        field_interval: None,
        time_step_scale: scale,
        time_step,
    }
}

/// Drives a [`CpuSolver`] one step at a time (with a schedule from [`every_step`]).
pub struct Stepper {
    /// The solver.
    pub solver: CpuSolver,
    /// The samples so far.
    pub samples: Vec<Sample>,
    /// Set when the run failed.
    pub failure: Option<Failure>,
    /// Set when the run reached its end.
    pub done: bool,
}

impl Stepper {
    /// A stepper on a fresh solver.
    pub fn new(model: Model, plan: Plan, schedule: Schedule) -> Self {
        Self {
            solver: CpuSolver::new(model, plan, schedule),
            samples: Vec::new(),
            failure: None,
            done: false,
        }
    }

    /// Advances to the next event(s); returns false once the run ended or failed.
    pub fn advance(&mut self) -> bool {
        if self.done || self.failure.is_some() {
            return false;
        }
        let mut events = Vec::new();
        self.solver.advance(&mut events).expect("CPU solver error");
        for ev in events {
            match ev {
                Event::Sample(s) => self.samples.push(s),
                Event::Snapshot(_) => {}
                Event::Done => self.done = true,
                Event::Failed(f) => self.failure = Some(f),
            }
        }
        !(self.done || self.failure.is_some())
    }

    /// Builds the scene `text` and runs it to its end on the CPU; panics naming `what` if the
    /// run fails. Returns the model and the finished stepper.
    pub fn finish(text: &str, what: &str) -> (Model, Stepper) {
        let (scene, model, plan) = build(text);
        let mut run = Stepper::new(model.clone(), plan, ricochet::run::schedule(&scene));
        while run.advance() {}
        if let Some(f) = &run.failure {
            panic!("{what}: the run failed: {}", f.message);
        }
        (model, run)
    }
}

/// Reads a CSV file of numbers with a header line.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    // Comment lines (`#`: the axisymmetric note) before the header.
    let mut lines = text.lines().skip_while(|l| l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .expect("header line")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows: Vec<Vec<f64>> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|x| {
                    x.parse::<f64>()
                        .unwrap_or_else(|e| panic!("bad number {x:?} in {l:?}: {e}"))
                })
                .collect()
        })
        .collect();
    for r in &rows {
        assert_eq!(r.len(), header.len(), "row length differs from the header");
    }
    (header, rows)
}

/// Index of `name` in a CSV header.
pub fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name:?} in {header:?}"))
}

/// The `ricochet` binary built for this test run.
pub fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_ricochet")
}

/// Runs the binary with `args`.
pub fn run_bin(args: &[&str]) -> Output {
    Command::new(bin())
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("cannot start the ricochet binary")
}

/// Runs `ricochet run SCENE --backend cpu --out OUT` with `extra` arguments.
pub fn run_cpu(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let (scene, out) = (scene.to_string_lossy(), out.to_string_lossy());
    let mut args = vec!["run", &scene, "--backend", "cpu", "--out", &out];
    args.extend_from_slice(extra);
    run_bin(&args)
}

/// Relative difference |a - b| / scale.
pub fn rel(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / scale
}

/// 2x2 matrix (row-major xx, xy, yx, yy) times a point.
pub fn mat_vec(m: [[f64; 2]; 2], x: [f64; 2]) -> [f64; 2] {
    [
        m[0][0] * x[0] + m[0][1] * x[1],
        m[1][0] * x[0] + m[1][1] * x[1],
    ]
}

/// Rotation matrix by `theta`.
pub fn rotation(theta: f64) -> [[f64; 2]; 2] {
    let (s, c) = theta.sin_cos();
    [[c, -s], [s, c]]
}

/// Von Mises stress of (xx, yy, xy, zz).
pub fn von_mises(s: [f64; 4]) -> f64 {
    let [sxx, syy, sxy, szz] = s;
    (0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2) + 6.0 * sxy * sxy))
        .sqrt()
}

/// Runs the binary with `args` under a 4 GiB address-space limit (`ulimit -v`: a read that
/// grows without bound fails there instead of exhausting the machine), killed after `secs`
/// seconds; returns its output and whether it had to be killed.
pub fn run_bin_bounded(args: &[&str], secs: u64) -> (Output, bool) {
    use std::process::Stdio;
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 4194304; exec \"$0\" \"$@\"")
        .arg(bin())
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cannot start the ricochet binary");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(secs);
    let mut killed = false;
    while child.try_wait().expect("wait").is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            killed = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    (child.wait_with_output().expect("output"), killed)
}
