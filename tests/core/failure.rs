//! Material failure and erosion (CPU reference): a single element pulled in uniaxial plane
//! strain erodes at the step where its plastic strain reaches the limit (closed form); Johnson-
//! Cook damage at zero triaxiality (simple shear) is d(eps_p) / (d1 + d2) summed and erodes the
//! element at the closed form's time; a freely stretching block whose elements erode keeps its
//! energy balance with the `eroded_energy` column, its eroded elements carry no force and leave
//! the stable step, and its nodes fly on as free masses; the plan has the failure stage only with
//! failure; the history, summary, VTU `eroded` and `damage` cell fields and the plot. Johnson-
//! Cook thermal softening with adiabatic heating: a sheared element's temperature against the
//! exact coupled solution for m = 1, its `temperature` cell field, summary and `check` lines, the
//! damage's d5 term at the heated T*, and a restart through a checkpoint.

use ricochet::plan::Stage;
use ricochet::step::cpu::CpuSolver;
use ricochet::step::{Event, Sample, Solver};

use crate::common::*;

#[path = "../shared/failure_scene.rs"]
mod failure_scene;
use failure_scene::*;

/// Steps `solver` one at a time until element 0 erodes or the run ends; the displacements u_n
/// and plastic strain of the step that eroded it, and of the step before (None if it never did).
#[allow(clippy::type_complexity)]
fn step_until_eroded(
    solver: &mut CpuSolver,
) -> Option<((f64, Vec<[f64; 2]>, f64), (f64, Vec<[f64; 2]>, f64))> {
    let mut before = (0.0, solver.displacement().to_vec(), 0.0);
    while !solver.finished() {
        let now = (solver.time(), solver.displacement().to_vec());
        solver.run_steps(1);
        let alpha = solver
            .plastic_now()
            .unwrap()
            .first()
            .map_or(0.0, |p| p.alpha);
        if solver.eroded()[0] {
            return Some((before, (now.0, now.1, alpha)));
        }
        before = (now.0, now.1, alpha);
    }
    None
}

/// The numbers the Python `script` prints when run on the output folder `out` (meshio reads its
/// VTU files), and what it printed, with its standard error.
fn python_numbers(script: &str, out: &std::path::Path) -> (Vec<f64>, String) {
    let py = std::process::Command::new("python3")
        .args(["-c", script, out.to_str().unwrap()])
        .output()
        .unwrap();
    let line = String::from_utf8_lossy(&py.stdout).into_owned();
    let v = line
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let printed = format!("{line} {}", String::from_utf8_lossy(&py.stderr));
    (v, printed)
}

/// The stretch of the single element from its displacements (top node minus bottom node).
fn stretch(u: &[[f64; 2]], model: &ricochet::model::Model) -> f64 {
    let top = model
        .position
        .iter()
        .position(|p| (p[1] - SIDE).abs() < 1e-12)
        .unwrap();
    let bottom = model.position.iter().position(|p| p[1] == 0.0).unwrap();
    1.0 + (u[top][1] - u[bottom][1]) / SIDE
}

#[test]
fn a_single_element_erodes_at_the_step_its_plastic_strain_reaches_the_limit() {
    let limit = 0.004;
    let text = tension_scene(100.0, 1.0e-4, &format!("{{ plastic_strain = {limit} }}"));
    let (scene, model, plan) = build(&text);
    assert!(plan.has(Stage::Failure));
    let mut solver = CpuSolver::new(model.clone(), plan, ricochet::run::schedule(&scene));
    let (before, at) = step_until_eroded(&mut solver).expect("the element erodes");
    let (l0, l1) = (stretch(&before.1, &model), stretch(&at.1, &model));
    // The plastic strain is the closed form's at every step, below the limit the step before and
    // at or past it on the step that eroded the element.
    for (l, alpha) in [(l0, before.2), (l1, at.2)] {
        let closed = tension_plastic_strain(l);
        assert!(
            (alpha - closed).abs() < 1e-9 * limit,
            "alpha {alpha} vs closed form {closed} at stretch {l}"
        );
    }
    assert!(before.2 < limit && at.2 >= limit, "{before:?} {at:?}");
    // The closed form's failure stretch lies between the two steps.
    assert!(tension_plastic_strain(l0) < limit && tension_plastic_strain(l1) >= limit);
    println!(
        "eroded at t = {:e} s, stretch {l1} (closed form's stretch between {l0} and {l1})",
        at.0
    );
    // Eroded at once: the element gives no force; the run goes on to its end.
    let mut events = Vec::new();
    while !solver.finished() {
        solver.advance(&mut events).unwrap();
    }
    assert!(
        events.iter().any(|e| matches!(e, Event::Done)),
        "{events:?}"
    );
    assert_eq!(solver.eroded_count(), 1);
}

#[test]
fn johnson_cook_damage_at_zero_triaxiality_erodes_at_the_closed_form_time() {
    // Simple shear: sigma* = 0, so eps_f = d1 + d2 whatever d3; d4's rate term is off.
    let (d1, d2) = (0.1, 0.2);
    let eps_f = d1 + d2;
    let rate = 1000.0;
    let failure =
        format!("{{ johnson_cook = {{ d1 = {d1}, d2 = {d2}, d3 = -1.5, d4 = 0.0, d5 = 0.0 }} }}");
    let (scene, model, plan) = build(&shear_scene(rate, 1.0e-3, &failure));
    let mut solver = CpuSolver::new(model, plan, ricochet::run::schedule(&scene));
    let mut t_fail = None;
    let mut last_alpha = 0.0;
    while !solver.finished() {
        let t = solver.time();
        solver.run_steps(1);
        let alpha = solver.plastic_now().unwrap()[0].alpha;
        let d = solver.damage()[0];
        // D = sum d(eps_p) / eps_f = eps_p / eps_f at constant triaxiality.
        assert!(
            (d - alpha / eps_f).abs() < 1e-10 * d.max(1e-3),
            "t {t:e}: D {d} vs {}",
            alpha / eps_f
        );
        if solver.eroded()[0] {
            assert!(
                d >= 1.0 && last_alpha < eps_f,
                "D {d}, alpha before {last_alpha}"
            );
            t_fail = Some(t);
            break;
        }
        last_alpha = alpha;
    }
    let t_fail = t_fail.expect("the element erodes");
    let closed = shear_strain_at(eps_f) / rate;
    let err = (t_fail - closed).abs() / closed;
    println!("failure at t = {t_fail:e} s, closed form {closed:e} s: {err:.2e} relative");
    assert!(err < 3e-3, "{t_fail:e} vs {closed:e}");
}

/// The history samples and snapshots of a run of `text` to its end.
fn run_events(text: &str) -> (CpuSolver, Vec<Sample>, Vec<ricochet::step::Snapshot>) {
    let (scene, model, plan) = build(text);
    let mut solver = CpuSolver::new(model, plan, ricochet::run::schedule(&scene));
    let (mut samples, mut snaps) = (Vec::new(), Vec::new());
    let mut events = Vec::new();
    while !solver.finished() {
        solver.advance(&mut events).unwrap();
        for e in events.drain(..) {
            match e {
                Event::Sample(s) => samples.push(s),
                Event::Snapshot(s) => snaps.push(s),
                Event::Failed(f) => panic!("run failed: {f:?}"),
                Event::Done => {}
            }
        }
    }
    (solver, samples, snaps)
}

#[test]
fn eroded_elements_leave_the_energy_balanced_and_their_nodes_fly_free() {
    let text = stretching_block(2000.0, 2.0e-5, 0.01);
    let (solver, samples, snaps) = run_events(&text);
    let last = samples.last().unwrap();
    let ne = solver.model().element_count();
    assert!(
        last.eroded_elements > 0 && last.eroded_elements as usize <= ne,
        "{} of {ne} eroded",
        last.eroded_elements
    );
    assert_eq!(
        solver.eroded().iter().filter(|&&e| e).count() as u64,
        last.eroded_elements
    );
    assert!(last.eroded_energy > 0.0);
    // The energy audit with the eroded energy: as tight as without erosion.
    let mut audit = ricochet::output::history::EnergyAudit::default();
    for s in &samples {
        audit.error(s);
    }
    println!(
        "{} of {ne} eroded, eroded energy {:e} J, max energy error {:e}",
        last.eroded_elements, last.eroded_energy, audit.max_error
    );
    assert!(audit.max_error < 1e-3, "{}", audit.max_error);
    // The eroded count never falls, and the snapshots carry the eroded flags.
    assert!(samples
        .windows(2)
        .all(|w| w[1].eroded_elements >= w[0].eroded_elements));
    assert!(snaps.iter().all(|s| s.eroded.len() == ne));
    // The stable step ignores eroded elements: it is that of the elements left.
    let (dt, e) = solver.stable_step();
    assert!(!solver.eroded()[e] || dt == f64::INFINITY);
}

#[test]
fn a_node_of_eroded_elements_only_moves_on_at_constant_velocity() {
    // Every element erodes in the stretched block (a low limit): every node is a free mass.
    let text = stretching_block(2000.0, 2.0e-5, 1.0e-4);
    let (mut solver, samples, _) = run_events(&text);
    assert!(solver.eroded().iter().all(|&e| e), "{:?}", solver.eroded());
    let t = samples
        .iter()
        .position(|s| s.eroded_elements as usize == solver.eroded().len());
    let t = t.expect("all eroded before the end");
    // From then on the kinetic energy is constant and the momentum of the block too.
    let k0 = samples[t + 1].kinetic;
    for s in &samples[t + 1..] {
        assert!(
            (s.kinetic - k0).abs() <= 1e-12 * k0,
            "{} vs {k0}",
            s.kinetic
        );
    }
    let v = solver.velocity().to_vec();
    solver.run_steps(10);
    assert_eq!(v, solver.velocity());
}

#[test]
fn a_scene_without_failure_has_no_failure_stage_or_state() {
    let text = tension_scene(100.0, 1.0e-5, "{ plastic_strain = 0.5 }");
    let plain = text.replace("failure = { plastic_strain = 0.5 }\n", "");
    let (scene, model, plan) = build(&plain);
    assert!(!plan.has(Stage::Failure));
    assert!(!model.has_failure());
    let mut solver = CpuSolver::new(model, plan, ricochet::run::schedule(&scene));
    solver.run_steps(5);
    assert!(solver.eroded().is_empty() && solver.damage().is_empty());
    // With plastic_strain only, no damage state either.
    let (scene, model, plan) = build(&text);
    assert!(plan.has(Stage::Failure));
    let solver = CpuSolver::new(model, plan, ricochet::run::schedule(&scene));
    assert_eq!(solver.eroded().len(), 1);
    assert!(solver.damage().is_empty());
    let _ = scene;
}

#[test]
fn outputs_carry_the_eroded_columns_fields_and_summary() {
    let text = stretching_block(2000.0, 2.0e-5, 0.01)
        .replace("plastic_strain = 0.01", "plastic_strain = 0.01, johnson_cook = { d1 = 5.0, d2 = 1.0, d3 = -1.5, d4 = 0.0, d5 = 0.0 }");
    let dir = tmp_dir("failure-outputs");
    let file = dir.join("block.toml");
    std::fs::write(&file, &text).unwrap();
    let out = dir.join("out");
    let o = run_cpu(&file, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let (header, rows) = read_csv(&out.join("history.csv"));
    let (n, w) = (
        column(&header, "eroded_elements"),
        column(&header, "eroded_energy"),
    );
    assert_eq!(
        &header[n - 2..=w + 1],
        &[
            "viscous_work",
            "plastic_work",
            "eroded_elements",
            "eroded_energy",
            "contact_energy"
        ]
    );
    let last = rows.last().unwrap();
    assert!(last[n] > 0.0 && last[w] > 0.0, "{last:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["eroded_elements"].as_f64(), Some(last[n]));
    let failure = summary["failure"][0].as_str().unwrap();
    assert!(
        failure.starts_with("aluminium: plastic_strain 0.01, johnson_cook (d1 5"),
        "{failure}"
    );
    // `check` says what fails.
    let c = run_bin(&["check", file.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&c.stdout);
    assert!(stdout.contains("failure: plastic_strain 0.01"), "{stdout}");
    assert!(stdout.contains("failure"), "{stdout}");
    // The last snapshot's VTU: an `eroded` cell field (1 on the eroded cells, whose stress is 0)
    // and the damage.
    let script = r#"
import sys, meshio, glob
m = meshio.read(sorted(glob.glob(sys.argv[1] + "/fields/*.vtu"))[-1])
e = m.cell_data["eroded"][0]
vm = m.cell_data["von_mises"][0]
d = m.cell_data["damage"][0]
print(int(e.sum()), len(e), float(abs(vm[e == 1]).max()) if e.sum() else 0.0, float(d.max()))
"#;
    let (v, line) = python_numbers(script, &out);
    assert_eq!(v.len(), 4, "{line}");
    assert_eq!(v[0], last[n], "{line}");
    assert_eq!(v[1], 32.0);
    assert_eq!(v[2], 0.0);
    assert!(v[3] > 0.0 && v[3] < 1.0, "{line}");
    // The plot leaves the eroded cells out (their values are NaN for the colour range).
    let p = run_bin(&["plot", out.to_str().unwrap(), "--field", "von_mises"]);
    assert_eq!(p.status.code(), Some(0), "{p:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

use crate::restart::shared_restart;

/// Runs the scene `text` straight through with the binary into `base/a`, and on the CPU solver
/// interrupted halfway into `base/b` (a checkpoint to restart from); returns `base`, `a`, `b`,
/// the model and the interrupted solver.
fn straight_and_interrupted(
    text: &str,
    name: &str,
) -> (
    std::path::PathBuf,
    std::path::PathBuf,
    std::path::PathBuf,
    ricochet::model::Model,
    CpuSolver,
) {
    let base = tmp_dir(name);
    let path = base.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let a = base.join("a");
    let o = run_cpu(&path, &a, &[]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let (scene, model, plan) = build(text);
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), ricochet::run::schedule(&scene));
    let b = base.join("b");
    shared_restart::run_interrupted_halfway(
        &scene,
        &model,
        &plan,
        &mut solver,
        &b,
        &path,
        text,
        None,
    );
    (base, a, b, model, solver)
}

#[test]
fn a_run_with_erosion_restarts_to_the_same_outputs() {
    // Interrupted halfway, after some elements eroded: the eroded flags and damage are part of
    // the checkpoint, and the restart ends with the outputs of the run never stopped.
    let text = stretching_block(2000.0, 2.0e-5, 0.01).replace(
        "plastic_strain = 0.01",
        "plastic_strain = 0.01, johnson_cook = { d1 = 0.05, d2 = 0.01, d3 = -1.5, d4 = 0.0, d5 = 0.0 }",
    );
    let (base, a, b, model, solver) = straight_and_interrupted(&text, "failure-restart");
    assert!(
        solver.eroded_count() > 0,
        "nothing eroded by the interruption"
    );
    assert!(solver.eroded_count() < model.element_count() as u64);
    let o = run_bin(&["run", "--restart", b.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    shared_restart::assert_same_outputs(&a, &b);
    let (header, rows) = read_csv(&b.join("history.csv"));
    let n = column(&header, "eroded_elements");
    assert!(rows.last().unwrap()[n] >= solver.eroded_count() as f64);
    let _ = std::fs::remove_dir_all(&base);
}

/// The thermal softening verification case (`assets/verification/thermal_softening.toml`) at
/// `n` = 1: one Weldox element (m = 1, no rate term) sheared to eps_p ~ 1, every node held.
fn thermal_scene() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/verification/thermal_softening.toml");
    let case = ricochet::verify::case::Case::read(&path).unwrap();
    let level = [("n".to_string(), 1.0)].into_iter().collect();
    case.expand(&level, "none").unwrap()
}

/// Its constants: A, B, n (Pa, Pa, -) and k = beta / (rho c_p (T_m - T_r)) (1/Pa), T_r, T_m (K).
const THERMAL_A: f64 = 4.9e8;
const THERMAL_B: f64 = 8.07e8;
const THERMAL_N: f64 = 0.73;
const THERMAL_ROOM: f64 = 293.0;
const THERMAL_MELT: f64 = 1800.0;

fn thermal_k() -> f64 {
    0.9 / (7850.0 * 452.0 * (THERMAL_MELT - THERMAL_ROOM))
}

/// The exact adiabatic T* at the plastic strain `eps` (m = 1, no rate term): 1 - exp(-k W0).
fn thermal_closed_form(eps: f64) -> f64 {
    let w0 = THERMAL_A * eps + THERMAL_B * eps.powf(THERMAL_N + 1.0) / (THERMAL_N + 1.0);
    1.0 - (-thermal_k() * w0).exp()
}

#[test]
fn thermal_softening_heats_to_the_closed_form_and_writes_the_temperature() {
    let text = thermal_scene().replace(
        "history_interval = 2.5e-6",
        "history_interval = 2.5e-6\nfield_interval = 2.5e-5\nfield_format = \"ascii\"",
    );
    let dir = tmp_dir("thermal-softening");
    let file = dir.join("thermal.toml");
    std::fs::write(&file, &text).unwrap();
    let out = dir.join("out");
    let o = run_cpu(&file, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("highest element temperature"), "{stdout}");
    // The last snapshot: the temperature cell field, T_r + (T_m - T_r) T*, against the closed
    // form at the element's plastic strain (within the case's bound at n = 1).
    let script = r#"
import sys, meshio, glob
m = meshio.read(sorted(glob.glob(sys.argv[1] + "/fields/*.vtu"))[-1])
print(float(m.cell_data["plastic_strain"][0][0]), float(m.cell_data["temperature"][0][0]))
"#;
    let (v, line) = python_numbers(script, &out);
    assert_eq!(v.len(), 2, "{line}");
    let (eps, temperature) = (v[0], v[1]);
    assert!(eps > 0.95 && eps < 1.05, "{eps}");
    let t_star = (temperature - THERMAL_ROOM) / (THERMAL_MELT - THERMAL_ROOM);
    let closed = thermal_closed_form(eps);
    println!("eps_p {eps}: T = {temperature} K, T* {t_star} against the closed form's {closed}");
    assert!((t_star - closed).abs() < 4.1e-4, "T* {t_star} vs {closed}");
    assert!(closed > 0.14 && closed < 0.16, "{closed}");
    // summary.json states the heating and the highest temperature, `check` the softening.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let thermal = summary["thermal"][0].as_str().unwrap();
    assert!(
        thermal.starts_with("weldox: thermal softening m 1, melt temperature 1800 K"),
        "{thermal}"
    );
    assert!(thermal.contains("specific heat 452 J/(kg K), taylor_quinney 0.9"));
    let max = summary["max_temperature"].as_f64().unwrap();
    assert!(
        (max - temperature).abs() < 1e-9 * max,
        "{max} vs {temperature}"
    );
    let c = run_bin(&["check", file.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&c.stdout);
    assert!(stdout.contains("thermal softening m 1"), "{stdout}");
    // A scene without thermal softening has neither key nor field.
    let plain = thermal_scene()
        .replace(
            ", m = 1.0, melt_temperature = 1800.0, room_temperature = 293.0",
            "",
        )
        .replace("specific_heat = 452.0\ntaylor_quinney = 0.9\n", "");
    assert!(!plain.contains("specific_heat") && !plain.contains("melt_temperature"));
    let (r, _, _) = run_cpu_text(&plain, "thermal-plain");
    assert!(r.summary.thermal.is_empty() && r.summary.max_temperature.is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn johnson_cook_damage_uses_the_heated_t_star_in_its_d5_term() {
    // The heated element with Johnson-Cook damage at zero triaxiality: eps_f = (d1 + d2)
    // (1 + d5 T*), so D = integral of d(eps_p) / (0.5 (1 + d5 T*(eps_p))) reaches 1 later than
    // at eps_p = 0.5 when d5 > 0, where T* is the closed form's.
    let eroded_at = |d5: f64| {
        let text = thermal_scene().replace(
            "taylor_quinney = 0.9\n",
            &format!(
                "taylor_quinney = 0.9\nfailure = {{ johnson_cook = {{ d1 = 0.3, d2 = 0.2, d3 = 0.0, d4 = 0.0, d5 = {d5} }} }}\n"
            ),
        );
        let (scene, model, plan) = build(&text);
        let mut solver = CpuSolver::new(model, plan, ricochet::run::schedule(&scene));
        let (_, at) = step_until_eroded(&mut solver).expect("the element erodes");
        at.2
    };
    let plain = eroded_at(0.0);
    let heated = eroded_at(2.0);
    // The closed form: D(eps) = integral_0^eps d e / (0.5 (1 + 2 T*(e))) = 1 (midpoint rule).
    let (mut d, mut eps, h) = (0.0, 0.0, 1e-5);
    while d < 1.0 {
        d += h / (0.5 * (1.0 + 2.0 * thermal_closed_form(eps + 0.5 * h)));
        eps += h;
    }
    println!("eroded at eps_p {plain} (d5 = 0), {heated} (d5 = 2; closed form {eps})");
    // Within a step's plastic strain (2.5e-3) of the limit.
    assert!(plain > 0.5 - 1e-9 && plain < 0.5 + 2.5e-3, "{plain}");
    assert!(
        heated >= eps - 1e-3 && heated < eps + 2.5e-3,
        "{heated} vs {eps}"
    );
    // The d5 term moves the failure by 6 % (T* ~ 0.07 there), over ten steps' plastic strain.
    assert!(eps > 0.525, "{eps}");
}

#[test]
fn a_run_with_thermal_softening_restarts_to_the_same_outputs() {
    // Interrupted halfway, heated: the temperature is part of the plastic state in the
    // checkpoint, and the restart ends with the outputs of the run never stopped.
    let text = thermal_scene().replace(
        "history_interval = 2.5e-6",
        "history_interval = 2.5e-6\nfield_interval = 1.0e-5",
    );
    let (base, a, b, _, mut solver) = straight_and_interrupted(&text, "thermal-restart");
    assert!(solver.plastic_now().unwrap()[0].heat > 10.0);
    let o = run_bin(&["run", "--restart", b.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    shared_restart::assert_same_outputs(&a, &b);
    let _ = std::fs::remove_dir_all(&base);
}

/// Runs `file` (a scene in which one element erodes, by `run.erosion`) through the binary into
/// `out`: it completes, `run` says "1 elements eroded, 1 of them {why}", and `summary.json`
/// counts the one element under `key` (`eroded_inverted` or `eroded_small_step`) and not under
/// the other. The summary's largest energy error, the last row's, and its eroded energy.
fn run_eroding_one(
    file: &std::path::Path,
    out: &std::path::Path,
    why: &str,
    key: &str,
) -> (f64, f64, f64) {
    let o = run_cpu(file, out, &[]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains(&format!("1 elements eroded, 1 of them {why}")),
        "{stdout}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    assert_eq!(summary["eroded_elements"].as_u64(), Some(1));
    for k in ["eroded_inverted", "eroded_small_step"] {
        let want = (k == key).then_some(1);
        assert_eq!(summary.get(k).and_then(|v| v.as_u64()), want, "{k}");
    }
    let max_error = summary["max_energy_error"].as_f64().unwrap();
    let (header, rows) = read_csv(&out.join("history.csv"));
    let last = rows.last().unwrap();
    (
        max_error,
        last[column(&header, "energy_error")],
        last[column(&header, "eroded_energy")],
    )
}

#[test]
fn an_element_whose_stable_step_falls_below_min_time_step_erodes_at_the_closed_forms_time() {
    let text = collapsing_element();
    let (scene, model, plan) = build(&text);
    assert!(plan.has(Stage::Failure) && !model.has_failure() && model.has_erosion());
    let scale = scene.run.time_step_scale;
    let limit = scene.run.erode_min_time_step.expect("min_time_step");
    let mut solver = CpuSolver::new(model.clone(), plan, ricochet::run::schedule(&scene));
    let dt0 = solver.stable_step().0;
    let t_star = collapse_time(dt0, scale, limit);
    let t_cross = SIDE / (2.0 * COLLAPSE_SPEED);
    assert!(t_star > 0.0 && t_star < t_cross, "{t_star:e} {t_cross:e}");
    // It erodes in the first step whose u_n (at t_n) puts its stable step below the limit: t_n
    // past t*, the step before at or before it.
    let (before, at) = step_until_eroded(&mut solver).expect("the element erodes");
    println!(
        "stable step at rest {dt0:e} s, limit {limit:e} s: eroded in the step from t = {:e} s \
         (closed form t* = {t_star:e} s, the step before from {:e} s)",
        at.0, before.0
    );
    assert!(before.0 <= t_star && at.0 > t_star, "{before:?} {at:?}");
    assert_eq!(solver.eroded_count(), 1);
    assert_eq!(solver.eroded_small_step_now().unwrap(), 1);
    assert_eq!(solver.eroded_inverted_now().unwrap(), 0);
    // The run's step never went below the limit (after the erosion it keeps its last step).
    solver.run_steps(u64::MAX);
    let (dt_min, _) = solver.dt_range();
    assert!(
        dt_min >= limit,
        "smallest step {dt_min:e} s under the limit {limit:e} s"
    );
    // Through the binary: completed, counted apart, the energy balanced with the eroded energy.
    let dir = tmp_dir("erosion-min-step");
    let file = dir.join("collapse.toml");
    std::fs::write(&file, &text).unwrap();
    let (max_error, last_error, eroded_energy) = run_eroding_one(
        &file,
        &dir.join("out"),
        "for a stable step below",
        "eroded_small_step",
    );
    println!("energy error {max_error:e} (start-up), {last_error:e} at the end");
    assert!(eroded_energy > 0.0);
    assert!(max_error < 2e-3, "{max_error}");
    assert!(last_error < 1e-9, "{last_error}");
    let c = run_bin(&["check", file.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&c.stdout).contains("run.erosion.min_time_step"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_element_about_to_invert_erodes_with_erosion_inverted_and_the_run_goes_on() {
    // Its corner crosses the diagonal at t = SIDE / (2 x 100 m/s) = 50 us.
    let (speed, end) = (100.0, 8.0e-5);
    let dir = tmp_dir("erosion-inverted");
    // Without the option the run stops naming the element.
    let file = dir.join("stop.toml");
    std::fs::write(&file, crushed_corner(speed, end, "")).unwrap();
    let o = run_cpu(&file, &dir.join("stop"), &[]);
    let err = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_ne!(o.status.code(), Some(0), "{o:?}");
    assert!(
        err.contains("inverted") && err.contains("element 0"),
        "{err}"
    );
    // With it the element erodes in the step where its corner reaches the diagonal, and the run
    // completes with its energy balanced, the eroded energy counted.
    let text = crushed_corner(speed, end, "erosion = { inverted = true }");
    let (scene, model, plan) = build(&text);
    assert!(plan.has(Stage::Failure) && !model.has_failure() && model.has_erosion());
    let mut solver = CpuSolver::new(model.clone(), plan, ricochet::run::schedule(&scene));
    let (before, at) = step_until_eroded(&mut solver).expect("the element erodes");
    let t_cross = SIDE / (2.0 * speed);
    println!(
        "eroded in the step from t = {:e} s (crossing at {t_cross:e} s)",
        at.0
    );
    assert!(before.0 < t_cross && at.0 >= before.0, "{before:?} {at:?}");
    // u_n of the step that eroded it: the pushed corner on or past the diagonal.
    let c = model
        .position
        .iter()
        .position(|p| p[0] > 0.5 * SIDE && p[1] > 0.5 * SIDE)
        .unwrap();
    let x = |u: &[[f64; 2]]| model.position[c][0] + u[c][0] + model.position[c][1] + u[c][1];
    assert!(
        x(&before.1) > SIDE && x(&at.1) <= SIDE + 1e-12,
        "{before:?} {at:?}"
    );
    assert_eq!(solver.eroded_count(), 1);
    assert_eq!(solver.eroded_inverted_now().unwrap(), 1);
    let file = dir.join("erode.toml");
    std::fs::write(&file, &text).unwrap();
    let (max_error, last_error, eroded_energy) = run_eroding_one(
        &file,
        &dir.join("erode"),
        "about to invert",
        "eroded_inverted",
    );
    println!(
        "energy error {max_error:e} (start-up), {last_error:e} at the end, eroded energy \
         {eroded_energy:e} J"
    );
    assert!(eroded_energy > 0.0);
    // The largest error is the first step's (the corner starts at 100 m/s against the tiny
    // energy of one step; 1.3e-3, decaying), and with the eroded energy counted the balance
    // after the erosion closes to round-off.
    assert!(max_error < 2e-3, "{max_error}");
    assert!(last_error < 1e-9, "{last_error}");
    // `check` says so; a scene without the option has no eroded_inverted key.
    let c = run_bin(&["check", file.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&c.stdout).contains("run.erosion.inverted"));
    let (r, _, _) = run_cpu_text(&stretching_block(2000.0, 2.0e-6, 0.01), "no-inverted");
    assert!(r.summary.eroded_inverted.is_none());
    let _ = std::fs::remove_dir_all(&dir);
}
