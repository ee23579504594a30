//! Fuzz of scenes on the GPU (issue 40): [`GPU_MUTANTS`] mutants (or `RICOCHET_FUZZ_GPU_MUTANTS`,
//! seed [`SEED`] or `RICOCHET_FUZZ_SEED`) of small shipped scenes, each changed by one or two
//! operators aimed at what the GPU does differently from the CPU reference (its `f32` numbers and
//! tick-based time): an end time of 1e-24 s down to 1e-35 s, a tiny or overlong sample or
//! snapshot interval, a time step scale from 0.1 to 2, velocities of 0 to 1e8 m/s, a density or
//! stiffness scaled by 1e-6 or 1e6. Each is loaded, cut to its first [`STEPS`] steps (a tiny end
//! time stays as it is) and run on the GPU in process. Rules: no panic; no case longer than
//! [`CASE_LIMIT`] (the watchdog aborts the process, printing it); a refusal is bad input or a
//! GPU error with a message; a run ends "completed" or "failed" with a message, and a completed
//! run ends at its end time (as the CPU's clock rules place it: at most 1 % of a step before it,
//! 1 % of the run past it) with finite numbers in its history and summary.

use super::*;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use toml::Value;

/// Seed of the generator.
const SEED: u64 = 0x0040_6A0F_5EED_2026;
/// Mutants run in CI (the first bases below: no contact stage, whose kernels take lavapipe
/// seconds to build).
const GPU_MUTANTS: usize = 3;
/// Steps of a run at most (its end time cut to them).
const STEPS: f64 = 150.0;
/// Longest time one case may take.
const CASE_LIMIT: Duration = Duration::from_secs(60);
/// Small shipped scenes the mutants start from, in turn.
const BASES: [&str; 7] = [
    "vibrating_block.toml",
    "spinning_disk.toml",
    "rods.toml",
    "disk_wall.toml",
    "rod_wall.toml",
    "plastic_bar_wall.toml",
    "pile.toml",
];

/// splitmix64.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[(self.next() % xs.len() as u64) as usize]
    }
}

/// One change to the scene `v`: what it was.
fn mutate(rng: &mut Rng, v: &mut Value) -> String {
    let run = v.get_mut("run").and_then(Value::as_table_mut).unwrap();
    match rng.next() % 7 {
        0 => {
            let t = rng.pick(&[1e-24, 1e-27, 1e-28, 1e-29, 1e-30, 1e-33, 1e-35]);
            run.insert("end_time".into(), Value::Float(t));
            format!("run.end_time = {t:e}")
        }
        1 => {
            let key = rng.pick(&["history_interval", "field_interval"]);
            let t = rng.pick(&[1e-30, 1e-12, 1.0]);
            run.insert(key.into(), Value::Float(t));
            format!("run.{key} = {t:e}")
        }
        2 => {
            let s = rng.pick(&[0.1, 1.0, 1.2, 2.0]);
            run.remove("time_step");
            run.insert("time_step_scale".into(), Value::Float(s));
            format!("run.time_step_scale = {s}")
        }
        3 => {
            let body = v
                .get_mut("body")
                .and_then(Value::as_array_mut)
                .and_then(|b| b.first_mut())
                .and_then(Value::as_table_mut)
                .unwrap();
            let s = rng.pick(&[0.0, 1e3, -1e3, 1e8]);
            body.remove("velocity_gradient");
            body.insert(
                "initial_velocity".into(),
                Value::Array(vec![Value::Float(s), Value::Float(-0.5 * s)]),
            );
            format!("body[0].initial_velocity = [{s:e}, {:e}]", -0.5 * s)
        }
        k => {
            let m = v
                .get_mut("material")
                .and_then(Value::as_array_mut)
                .and_then(|b| b.first_mut())
                .and_then(Value::as_table_mut)
                .unwrap();
            let key = if k == 4 { "density" } else { "youngs_modulus" };
            let f = rng.pick(&[1e-6, 1e6]);
            let old = m.get(key).and_then(Value::as_float).unwrap_or(1.0);
            m.insert(key.into(), Value::Float(old * f));
            format!("material[0].{key} *= {f:e}")
        }
    }
}

/// A case: Ok(outcome) or the rule it broke.
fn gpu_case(ctx: &Arc<GpuContext>, text: &str, out: &Path) -> Result<&'static str, String> {
    let path = Path::new("fuzz.toml");
    let mut scene = match Scene::parse(text, path) {
        Ok(s) => s,
        Err(e) => return message(e, "refused"),
    };
    let model = match ricochet::run::model(&scene) {
        Ok(m) => m,
        Err(e) => return message(e, "refused"),
    };
    if let Err(e) = ricochet::run::check_limits(&scene, &model) {
        return message(e, "refused");
    }
    let dt = ricochet::run::first_step(&scene, &model).0;
    if dt.is_finite() && dt > 0.0 {
        scene.run.end_time = scene.run.end_time.min(STEPS * dt);
    }
    let plan = Plan::new(&scene, &model);
    let mut gpu = match GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)) {
        Ok(g) => g,
        Err(e) => return message(e, "refused by the GPU"),
    };
    let r = match run(&scene, &model, &plan, &mut gpu, out, None) {
        Ok(r) => r,
        Err(e) => return message(e, "refused at the run"),
    };
    match r.summary.status.as_str() {
        "failed" if !r.summary.message.trim().is_empty() => Ok("failed"),
        "completed" => {
            let last = r.samples.last().ok_or("completed without a history row")?;
            // At its end time as the CPU's clock rules place it: within 1 % of a step before it
            // (the end is due at t + 0.01 dt >= T) or at most 1 % of the run past it (a last
            // step that would go further lands on it: step::clip_to_end, control.wgsl).
            let (t, end) = (last.0.time, scene.run.end_time);
            let before = 0.011 * r.summary.dt_max + 1e-6 * end;
            if !(t >= end - before && t <= end * (1.0 + 0.01 + 1e-6)) {
                return Err(format!(
                    "completed at t = {t:e} s, its end time is {end:e} s"
                ));
            }
            let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
            if text.contains("null") {
                return Err(format!("completed with a non-finite number: {text}"));
            }
            let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
            for line in history.lines().skip_while(|l| l.starts_with('#')).skip(1) {
                if !line
                    .split(',')
                    .all(|x| x.parse::<f64>().is_ok_and(f64::is_finite))
                {
                    return Err(format!("completed with {line:?} in history.csv"));
                }
            }
            Ok("completed")
        }
        s => Err(format!("ended {s:?} with {:?}", r.summary.message)),
    }
}

/// A refusal: bad input or a GPU error, with a message.
fn message(e: ricochet::Error, what: &'static str) -> Result<&'static str, String> {
    match e {
        ricochet::Error::Parse { .. }
        | ricochet::Error::Invalid { .. }
        | ricochet::Error::Gpu(_)
            if !e.to_string().trim().is_empty() =>
        {
            Ok(what)
        }
        e => Err(format!("{what} with {e}")),
    }
}

#[test]
fn mutated_scenes_on_the_gpu_end_or_are_refused_and_never_hang() {
    let Some(ctx) = context() else { return };
    let _guard = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let seed = env("RICOCHET_FUZZ_SEED").unwrap_or(SEED);
    let n = env("RICOCHET_FUZZ_GPU_MUTANTS").map_or(GPU_MUTANTS, |n| n as usize);
    let mut rng = Rng(seed ^ 0x0067_7075);
    let base_dir = std::env::temp_dir().join(format!("ricochet-gpu-fuzz-{}", std::process::id()));
    let t_start = Instant::now();
    // The watchdog: a case running past CASE_LIMIT aborts the process, printing it.
    let current: Arc<Mutex<Option<(Instant, String)>>> = Arc::new(Mutex::new(None));
    let stop = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let (c, s) = (Arc::clone(&current), Arc::clone(&stop));
        std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(100));
                let g = c.lock().unwrap_or_else(|e| e.into_inner());
                if let Some((t0, what)) = g.as_ref() {
                    if t0.elapsed() > CASE_LIMIT {
                        use std::io::Write as _;
                        let _ = writeln!(
                            std::io::stderr(),
                            "gpu fuzz: HANG: more than {CASE_LIMIT:?}; aborting.\n{what}"
                        );
                        std::process::abort();
                    }
                }
            }
        })
    };
    let mut counts = std::collections::BTreeMap::<&str, usize>::new();
    let mut violations = Vec::new();
    for case in 0..n {
        let base = BASES[case % BASES.len()];
        let file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets")
            .join(base);
        let mut v: Value = toml::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        let mut ops = vec![mutate(&mut rng, &mut v)];
        if rng.next().is_multiple_of(3) {
            ops.push(mutate(&mut rng, &mut v));
        }
        let text = toml::to_string(&v).unwrap();
        let what = format!("gpu case {case} (base {base}): {}", ops.join("; "));
        let out = base_dir.join(format!("{case:03}"));
        *current.lock().unwrap_or_else(|e| e.into_inner()) = Some((Instant::now(), what.clone()));
        let t0 = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| gpu_case(&ctx, &text, &out)))
            .unwrap_or_else(|_| Err("PANIC".into()));
        eprintln!("{what}: {r:?} in {:.2} s", t0.elapsed().as_secs_f64());
        *current.lock().unwrap_or_else(|e| e.into_inner()) = None;
        match r {
            Ok(o) => *counts.entry(o).or_default() += 1,
            Err(why) => violations.push(format!("{what}: {why}\n{text}")),
        }
        let _ = std::fs::remove_dir_all(&out);
    }
    stop.store(true, Ordering::Relaxed);
    let _ = watchdog.join();
    let _ = std::fs::remove_dir_all(&base_dir);
    eprintln!(
        "gpu fuzz: seed {seed:#x}: {n} mutants: {counts:?}; {} rule violations; {:.1} s",
        violations.len(),
        t_start.elapsed().as_secs_f64()
    );
    for v in violations.iter().take(5) {
        eprintln!("gpu fuzz: VIOLATION: {v}\n");
    }
    assert!(
        violations.is_empty(),
        "{} GPU cases broke a rule",
        violations.len()
    );
}
