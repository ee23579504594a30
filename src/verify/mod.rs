//! `ricochet verify`: runs the verification cases of `assets/verification/` (REFERENCES.md
//! sections 1-5) over a refinement ladder, per contact method and backend, and records for each
//! run the error of each metric against its reference, the wall time, the steps and element-cycles
//! and the energy-balance error. Writes `results.csv`, `report.md` (tables, observed convergence
//! orders, pass/fail against each case's bounds) and a log-log plot of error against wall time
//! per case (`<case>.svg` and `.png`).

pub mod case;
pub mod metric;
pub mod plot;
pub mod report;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, GpuSolver};
use crate::plan::Plan;
use crate::run::{run, schedule};
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;
use crate::step::Solver;

pub use case::Case;

/// What to run.
#[derive(Debug, Clone)]
pub struct Options {
    /// The short ladders instead of the full ones.
    pub quick: bool,
    /// Run on the CPU reference.
    pub cpu: bool,
    /// Run on the GPU (an adapter is required).
    pub gpu: bool,
    /// Folder of the case files; `None`: the cases built into the binary ([`EMBEDDED`]).
    pub cases: Option<PathBuf>,
    /// Only the cases with these names (all when empty).
    pub only: Vec<String>,
    /// Output folder.
    pub out: PathBuf,
    /// GPU adapter name substring.
    pub adapter: Option<String>,
    /// Runs at a time: 1 runs them one after another (the default: wall times undisturbed); more
    /// runs the GPU's runs one after another beside `jobs - 1` workers taking the CPU's, each
    /// worker taking the other backend's runs once its own are done (with one backend, `jobs`
    /// workers; each worker after the first runs the GPU's runs on a device of its own). Rows, `results.csv` and the report come out in the same order either way; only
    /// the wall times (each run's own, measured while others ran) change.
    pub jobs: usize,
}

/// One metric of one run.
#[derive(Debug, Clone)]
pub struct Row {
    /// Case name.
    pub case: String,
    /// Contact method.
    pub method: String,
    /// "cpu" or "gpu".
    pub backend: String,
    /// Level index in the ladder (0 = coarsest).
    pub level: usize,
    /// The level's refinement (the case's `size` variable).
    pub size: f64,
    /// Elements.
    pub elements: usize,
    /// Steps taken.
    pub steps: u64,
    /// Wall seconds of the time loop.
    pub wall_seconds: f64,
    /// Largest energy-balance error of the run.
    pub energy_error: f64,
    /// Metric name.
    pub metric: String,
    /// Reference value.
    pub reference: f64,
    /// Measured value (NaN when the run failed or the metric could not be measured).
    pub value: f64,
    /// |value - reference| / scale.
    pub relative_error: f64,
    /// The pass bound, when this row is judged.
    pub bound: Option<f64>,
    /// Whether the judged row passed.
    pub pass: Option<bool>,
    /// Why the value is missing, if it is.
    pub note: String,
}

/// The suite's results.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// Every metric of every run.
    pub rows: Vec<Row>,
    /// The cases in the order run.
    pub cases: Vec<Case>,
    /// The adapters used ("cpu" / "gpu" -> name).
    pub adapters: Vec<(String, String)>,
    /// Failures: the case, method, backend, metric, value and bound.
    pub failures: Vec<String>,
    /// The cases left out of a `--quick` run: those with no quick ladder (`quick = []`, a case
    /// too costly for the test suite), with their titles.
    pub full_only: Vec<(String, String)>,
}

/// The case files of `assets/verification/`, built into the binary so that `ricochet verify` runs
/// from any folder: (file name, text), sorted by file name.
pub const EMBEDDED: [(&str, &str); 19] = [
    (
        "disk_wall_10ms.toml",
        include_str!("../../assets/verification/disk_wall_10ms.toml"),
    ),
    (
        "disk_wall_1ms.toml",
        include_str!("../../assets/verification/disk_wall_1ms.toml"),
    ),
    (
        "failure_element.toml",
        include_str!("../../assets/verification/failure_element.toml"),
    ),
    (
        "failure_johnson_cook.toml",
        include_str!("../../assets/verification/failure_johnson_cook.toml"),
    ),
    (
        "hertz_rigid.toml",
        include_str!("../../assets/verification/hertz_rigid.toml"),
    ),
    (
        "impedance_1e4.toml",
        include_str!("../../assets/verification/impedance_1e4.toml"),
    ),
    (
        "incline_slide.toml",
        include_str!("../../assets/verification/incline_slide.toml"),
    ),
    (
        "incline_stick.toml",
        include_str!("../../assets/verification/incline_stick.toml"),
    ),
    (
        "lame_cylinder.toml",
        include_str!("../../assets/verification/lame_cylinder.toml"),
    ),
    (
        "patch_augmented.toml",
        include_str!("../../assets/verification/patch_augmented.toml"),
    ),
    (
        "patch_test.toml",
        include_str!("../../assets/verification/patch_test.toml"),
    ),
    (
        "perforation_blunt.toml",
        include_str!("../../assets/verification/perforation_blunt.toml"),
    ),
    (
        "plastic_patch.toml",
        include_str!("../../assets/verification/plastic_patch.toml"),
    ),
    (
        "rod_wall.toml",
        include_str!("../../assets/verification/rod_wall.toml"),
    ),
    (
        "rods.toml",
        include_str!("../../assets/verification/rods.toml"),
    ),
    (
        "rolling_disk.toml",
        include_str!("../../assets/verification/rolling_disk.toml"),
    ),
    (
        "sliding_block.toml",
        include_str!("../../assets/verification/sliding_block.toml"),
    ),
    (
        "taylor_bar.toml",
        include_str!("../../assets/verification/taylor_bar.toml"),
    ),
    (
        "thermal_softening.toml",
        include_str!("../../assets/verification/thermal_softening.toml"),
    ),
];

/// The built-in cases ([`EMBEDDED`]), named as their files in `assets/verification/`.
///
/// # Errors
/// The error of the first bad case (none in a tested build).
pub fn embedded_cases() -> Result<Vec<Case>> {
    EMBEDDED
        .iter()
        .map(|(name, text)| Case::parse(text, &Path::new("assets/verification").join(name)))
        .collect()
}

/// Reads the case files of `dir` (sorted by file name).
///
/// # Errors
/// [`Error::Read`] for an unreadable folder, or the error of the first bad case file.
pub fn read_cases(dir: &Path) -> Result<Vec<Case>> {
    let entries = std::fs::read_dir(dir).map_err(|source| Error::Read {
        file: dir.to_path_buf(),
        source,
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files.iter().map(|f| Case::read(f)).collect()
}

/// Runs the suite and writes its outputs into `opts.out`; `log` gets one line per run.
///
/// # Errors
/// Bad case files, a missing adapter with `gpu`, or outputs that cannot be written. Runs that fail
/// or miss their bounds are not errors: they are in [`Outcome::failures`].
pub fn verify(opts: &Options, mut log: impl FnMut(&str)) -> Result<Outcome> {
    let mut cases = match &opts.cases {
        Some(dir) => read_cases(dir)?,
        None => embedded_cases()?,
    };
    if !opts.only.is_empty() {
        for name in &opts.only {
            if !cases.iter().any(|c| &c.case.name == name) {
                let known: Vec<&str> = cases.iter().map(|c| c.case.name.as_str()).collect();
                return Err(Error::Verify(format!(
                    "no case named {name:?} in {} (cases: {known:?})",
                    match &opts.cases {
                        Some(d) => d.display().to_string(),
                        None => "the built-in cases".into(),
                    }
                )));
            }
        }
        cases.retain(|c| opts.only.contains(&c.case.name));
    }
    let mut full_only = Vec::new();
    if opts.quick {
        for c in cases.iter().filter(|c| c.levels.quick.is_empty()) {
            log(&format!(
                "{}: not run (no quick ladder: the full ladder only, `ricochet verify --case {}`)",
                c.case.name, c.case.name
            ));
            full_only.push((c.case.name.clone(), c.case.title.clone()));
        }
        cases.retain(|c| !c.levels.quick.is_empty());
    }
    let ctx = if opts.gpu {
        Some(Arc::new(GpuContext::new(opts.adapter.as_deref())?))
    } else {
        None
    };
    std::fs::create_dir_all(&opts.out).map_err(|source| Error::Write {
        path: opts.out.clone(),
        source,
    })?;
    let mut out = Outcome {
        full_only,
        ..Outcome::default()
    };
    if opts.cpu {
        out.adapters
            .push(("cpu".into(), "CPU reference (f64, 1 thread)".into()));
    }
    if let Some(c) = &ctx {
        out.adapters.push(("gpu".into(), c.adapter_name()));
    }
    let scratch = opts.out.join("runs");
    let mut jobs = Vec::new();
    for case in &cases {
        let levels = if opts.quick {
            &case.levels.quick
        } else {
            &case.levels.full
        };
        for method in &case.case.methods {
            let mut backends: Vec<Option<Arc<GpuContext>>> = Vec::new();
            if opts.cpu {
                backends.push(None);
            }
            if let Some(c) = &ctx {
                backends.push(Some(c.clone()));
            }
            for backend in backends {
                let bname = if backend.is_some() { "gpu" } else { "cpu" };
                if !case.case.runs_on(bname) {
                    log(&format!(
                        "{} {method} {bname}: not run (the case runs on {:?} only: a model the \
                         {bname} backend does not run yet)",
                        case.case.name,
                        case.case.backends.as_deref().unwrap_or_default()
                    ));
                    continue;
                }
                for (i, level) in levels.iter().enumerate() {
                    jobs.push(Job {
                        case,
                        method,
                        ctx: backend.clone(),
                        index: i,
                        level,
                    });
                }
            }
        }
    }
    let rows = run_jobs(
        &jobs,
        opts.jobs.max(1),
        opts.adapter.as_deref(),
        &scratch,
        &mut log,
    );
    let _ = std::fs::remove_dir_all(&scratch);
    for r in rows {
        out.rows.extend(r?);
    }
    judge(&cases, &mut out, levels_count(&cases, opts.quick));
    out.cases = cases;
    report::write_csv(&opts.out.join("results.csv"), &out.rows)?;
    for case in &out.cases {
        plot::error_vs_time(&opts.out, case, &out.rows)?;
    }
    report::write_markdown(&opts.out.join("report.md"), &out, opts)?;
    Ok(out)
}

type Ladder = Vec<std::collections::BTreeMap<String, f64>>;

/// One run of the suite: a case's level with one method on one backend (`ctx`: the GPU's).
struct Job<'a> {
    case: &'a Case,
    method: &'a str,
    ctx: Option<Arc<GpuContext>>,
    index: usize,
    level: &'a std::collections::BTreeMap<String, f64>,
}

impl Job<'_> {
    fn run(&self, scratch: &Path) -> Result<Vec<Row>> {
        self.run_on(self.ctx.clone(), scratch)
    }

    /// Runs on `ctx` in place of the job's own device (another device on the same adapter gives
    /// the same bits).
    fn run_on(&self, ctx: Option<Arc<GpuContext>>, scratch: &Path) -> Result<Vec<Row>> {
        run_one(self.case, self.method, ctx, self.index, self.level, scratch)
    }

    /// The progress line of a finished run.
    fn line(&self, rows: &Result<Vec<Row>>) -> String {
        let (case, method, i) = (&self.case.case, self.method, self.index);
        let bname = if self.ctx.is_some() { "gpu" } else { "cpu" };
        let Ok(rows) = rows else {
            return format!("{} {method} {bname} level {i}: failed", case.name);
        };
        let first = rows.first();
        format!(
            "{} {method} {bname} level {i} ({} = {}): {} elements, {} steps, {:.3} s{}",
            case.name,
            case.size,
            self.level.get(&case.size).copied().unwrap_or(0.0),
            first.map_or(0, |r| r.elements),
            first.map_or(0, |r| r.steps),
            first.map_or(0.0, |r| r.wall_seconds),
            first
                .filter(|r| !r.note.is_empty())
                .map_or(String::new(), |r| format!(": {}", r.note))
        )
    }
}

/// Runs the jobs, `jobs` at a time (see [`Options::jobs`]), logging each as it ends; their rows
/// in the jobs' order. One at a time, the suite stops at the first run that errs.
fn run_jobs(
    list: &[Job],
    jobs: usize,
    adapter: Option<&str>,
    scratch: &Path,
    log: &mut impl FnMut(&str),
) -> Vec<Result<Vec<Row>>> {
    if jobs <= 1 {
        let mut out = Vec::new();
        for job in list {
            let rows = job.run(scratch);
            log(&job.line(&rows));
            let failed = rows.is_err();
            out.push(rows);
            if failed {
                break;
            }
        }
        return out;
    }
    use std::sync::atomic::{AtomicUsize, Ordering};
    let gpu: Vec<usize> = (0..list.len()).filter(|&i| list[i].ctx.is_some()).collect();
    let cpu: Vec<usize> = (0..list.len()).filter(|&i| list[i].ctx.is_none()).collect();
    let (next_cpu, next_gpu) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let (tx, rx) = std::sync::mpsc::channel::<(usize, Result<Vec<Row>>)>();
    let mut results: Vec<Option<Result<Vec<Row>>>> = (0..list.len()).map(|_| None).collect();
    std::thread::scope(|scope| {
        // Each worker takes its own queue's runs, then the other's: the device's runs go one
        // after another in one worker beside `jobs - 1` taking the CPU's, and a worker whose
        // queue is empty helps with the other (on a CPU adapter the device's runs are the long
        // ones, and they would otherwise end the suite on one core).
        // The first worker runs the device's runs on the suite's device, any other on a device
        // of its own, opened at its first such run (the suite's if that fails): a device's queue
        // runs its work in turn, and on lavapipe in one thread, so that two workers on one
        // device took turns on one core.
        let worker = |queues: [(&'_ [usize], &'_ AtomicUsize); 2],
                      own_device: bool,
                      tx: std::sync::mpsc::Sender<_>| {
            let mut own: Option<Arc<GpuContext>> = None;
            for (queue, next) in queues {
                while let Some(&i) = queue.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let job = &list[i];
                    let ctx = match &job.ctx {
                        Some(suite) if own_device => Some(
                            own.get_or_insert_with(|| {
                                GpuContext::new(adapter)
                                    .map(Arc::new)
                                    .unwrap_or_else(|_| suite.clone())
                            })
                            .clone(),
                        ),
                        ctx => ctx.clone(),
                    };
                    if tx.send((i, job.run_on(ctx, scratch))).is_err() {
                        return;
                    }
                }
            }
        };
        let gpu_first = [(&gpu[..], &next_gpu), (&cpu[..], &next_cpu)];
        let cpu_first = [(&cpu[..], &next_cpu), (&gpu[..], &next_gpu)];
        let gpu_workers = usize::from(!gpu.is_empty());
        for w in 0..jobs.min(list.len()) {
            let tx = tx.clone();
            let queues = if w < gpu_workers {
                gpu_first
            } else {
                cpu_first
            };
            scope.spawn(move || worker(queues, w > 0, tx));
        }
        drop(tx);
        for (i, rows) in rx {
            log(&list[i].line(&rows));
            results[i] = Some(rows);
        }
    });
    results.into_iter().flatten().collect()
}

fn levels_count(cases: &[Case], quick: bool) -> Vec<(usize, Ladder)> {
    cases
        .iter()
        .map(|c| {
            let l = if quick {
                c.levels.quick.clone()
            } else {
                c.levels.full.clone()
            };
            (l.len(), l)
        })
        .collect()
}

/// Marks the judged rows (the finest level, or every level) and collects the failures.
fn judge(cases: &[Case], out: &mut Outcome, counts: Vec<(usize, Ladder)>) {
    for (case, (count, ladder)) in cases.iter().zip(counts) {
        for m in &case.metric {
            for row in out
                .rows
                .iter_mut()
                .filter(|r| r.case == case.case.name && r.metric == m.name)
            {
                let vars = case.variables(&ladder[row.level]);
                let Some(Ok(bound)) = m
                    .bound
                    .as_ref()
                    .and_then(|b| b.get(&row.method, &row.backend, &vars))
                else {
                    continue;
                };
                if !(m.every_level || row.level + 1 == count) {
                    continue;
                }
                let pass = row.relative_error <= bound;
                row.bound = Some(bound);
                row.pass = Some(pass);
                if !pass {
                    out.failures.push(format!(
                        "{} / {} / {} / level {} ({} = {}): {} = {:.6e}, error {:.3e} > bound {:.1e}{}",
                        row.case,
                        row.method,
                        row.backend,
                        row.level,
                        case.case.size,
                        row.size,
                        row.metric,
                        row.value,
                        row.relative_error,
                        bound,
                        if row.note.is_empty() {
                            String::new()
                        } else {
                            format!(" ({})", row.note)
                        }
                    ));
                }
            }
        }
    }
}

/// Runs one level of one case with one method on one backend; one row per applicable metric.
fn run_one(
    case: &Case,
    method: &str,
    ctx: Option<Arc<GpuContext>>,
    level_index: usize,
    level: &std::collections::BTreeMap<String, f64>,
    scratch: &Path,
) -> Result<Vec<Row>> {
    let backend = if ctx.is_some() { "gpu" } else { "cpu" };
    let text = case
        .expand(level, method)
        .map_err(|e| Error::Verify(format!("{}: {e}", case.file.display())))?;
    let label = PathBuf::from(format!(
        "{} [{method}, level {level_index}]",
        case.file.display()
    ));
    let scene = Scene::parse(&text, &label)?;
    let model = crate::run::model(&scene)?;
    let plan = Plan::new(&scene, &model);
    let mut solver: Box<dyn Solver> = match ctx {
        Some(c) => Box::new(GpuSolver::new(c, &model, &plan, schedule(&scene))?),
        None => Box::new(CpuSolver::new(
            model.clone(),
            plan.clone(),
            schedule(&scene),
        )),
    };
    let dir = scratch.join(format!(
        "{}-{method}-{backend}-{level_index}",
        case.case.name
    ));
    let r = run(&scene, &model, &plan, solver.as_mut(), &dir, None)?;
    let _ = std::fs::remove_dir_all(&dir);
    let displacement = solver.displacement_now()?;
    let plastic = solver.plastic_now()?;
    let contacts = model.interface_names();
    let vars = case.variables(level);
    let data = metric::RunData {
        model: &model,
        samples: &r.samples,
        displacement: &displacement,
        contacts: &contacts,
        vars: &vars,
        plastic: &plastic,
    };
    let failed = (r.summary.status != "completed").then(|| r.summary.message.clone());
    let mut rows = Vec::new();
    for m in case.metric.iter().filter(|m| m.applies(method)) {
        let (value, mut note) = match &failed {
            Some(msg) => (f64::NAN, format!("run failed: {msg}")),
            None => match metric::measure(m, &data) {
                Ok(v) => (v, String::new()),
                Err(e) => (f64::NAN, e),
            },
        };
        let (reference, err) = match metric::relative_error(m, value, &vars) {
            Ok(x) => x,
            Err(e) => {
                note = e;
                (f64::NAN, f64::NAN)
            }
        };
        rows.push(Row {
            case: case.case.name.clone(),
            method: method.to_string(),
            backend: backend.to_string(),
            level: level_index,
            size: level.get(&case.case.size).copied().unwrap_or(f64::NAN),
            elements: model.element_count(),
            steps: r.summary.steps,
            wall_seconds: r.summary.wall_seconds,
            energy_error: r.summary.max_energy_error,
            metric: m.name.clone(),
            reference,
            value,
            relative_error: if err.is_nan() { f64::INFINITY } else { err },
            bound: None,
            pass: None,
            note,
        });
    }
    Ok(rows)
}
