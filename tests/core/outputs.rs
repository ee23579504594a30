//! Outputs and the command line: `history.csv` with the documented columns, `summary.json` with
//! the documented keys, VTU fields and their PVD collection (read back with a real VTK reader,
//! meshio, through `tests/read_vtu.py`), `check`, the plan's stages, the example scenes, and
//! unstable runs that end with status "failed", exit code 3 and a message naming the step and
//! the element or node.

use std::path::{Path, PathBuf};
use std::process::Command;

use ricochet::plan::{Plan, Stage};
use ricochet::scene::Scene;
use serde_json::Value;

use crate::common::*;
use crate::scene_text::steel_of;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn summary(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

const HISTORY_COLUMNS: &str = "time,step,dt,kinetic_energy,internal_energy,hourglass_energy,viscous_work,contact_energy,external_work,energy_error";

#[test]
fn run_writes_history_summary_and_fields() {
    let dir = tmp_dir("outputs-block");
    let o = run_bin(&[
        "run",
        asset("vibrating_block.toml").to_str().unwrap(),
        "--backend",
        "cpu",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("completed"), "{stdout}");

    // history.csv: the documented header, one row per history_interval (2e-6 s over 2e-4 s).
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    assert_eq!(
        text.lines().next().unwrap(),
        format!("{HISTORY_COLUMNS},block.vx,block.vy")
    );
    let (header, rows) = read_csv(&dir.join("history.csv"));
    assert_eq!(rows.len(), 101);
    let (t, step, dt, err) = (
        column(&header, "time"),
        column(&header, "step"),
        column(&header, "dt"),
        column(&header, "energy_error"),
    );
    for (k, r) in rows.iter().enumerate() {
        assert!(
            (r[t] - 2e-6 * k as f64).abs() < 1e-9 * 2e-6,
            "row {k}: time {}",
            r[t]
        );
        assert_eq!(r[step], 10.0 * k as f64, "row {k}");
        assert_eq!(r[dt], 2e-7);
        assert!(r[err] < 1e-12, "row {k}: energy error {}", r[err]);
    }
    // The velocity field is about the centroid: the block's momentum is zero.
    let (vx, vy) = (column(&header, "block.vx"), column(&header, "block.vy"));
    for r in &rows {
        assert!(r[vx].abs() < 1e-9 && r[vy].abs() < 1e-9, "{r:?}");
    }

    // summary.json: the documented keys.
    let s = summary(&dir);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["message"], "");
    assert_eq!(s["backend"], "cpu");
    assert!(!s["adapter"].as_str().unwrap().is_empty());
    assert_eq!(s["steps"], 1000);
    assert!(s["wall_seconds"].as_f64().unwrap() > 0.0);
    assert!(s["element_cycles_per_second"].as_f64().unwrap() > 0.0);
    assert_eq!(s["dt_min"].as_f64().unwrap(), 2e-7);
    assert_eq!(s["dt_max"].as_f64().unwrap(), 2e-7);
    let max_err = rows.iter().fold(0.0f64, |m, r| m.max(r[err]));
    // (serde_json's default float parser may be 1 ulp off, hence the relative comparison.)
    assert!(rel(s["max_energy_error"].as_f64().unwrap(), max_err, max_err) < 1e-15);

    // Fields: a VTU per snapshot (every 2e-5 s, with t = 0 and the end) and the PVD.
    for k in 0..=10 {
        assert!(
            dir.join(format!("fields/block_{k:05}.vtu")).is_file(),
            "snapshot {k}"
        );
    }
    assert!(!dir.join("fields/block_00011.vtu").exists());
    assert_eq!(s["snapshots"], 11);
    let pvd = std::fs::read_to_string(dir.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet ").count(), 11);
    check_vtu_with_meshio(&dir, 11, 231, 200, [0.0, 0.0, 0.1, 0.05], F32_ROUNDING);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn triangles_are_written_as_vtk_triangle_cells() {
    // tests/data/gmsh/mixed.msh: 20 quads and 35 triangles on 51 nodes, stretched; each
    // encoding read back by meshio with its quads and triangles.
    let base = tmp_dir("triangle-fields");
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gmsh/mixed.msh");
    for format in ["binary", "ascii"] {
        let scene = base.join(format!("{format}.toml"));
        std::fs::write(
            &scene,
            format!(
                "[run]\nend_time = 1.0e-4\nfield_interval = 5.0e-5\nfield_format = \"{format}\"\n\
                 [[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\n\
                 youngs_modulus = 2.1e11\npoisson_ratio = 0.3\n[[body]]\nname = \"square\"\n\
                 material = \"steel\"\nmesh = {{ gmsh = {:?}, group = \"square\" }}\n\
                 velocity_gradient = [[100.0, 20.0], [0.0, -60.0]]\n",
                mesh.to_string_lossy()
            ),
        )
        .unwrap();
        let (out, precision) = run_in_format(&base, &scene, format);
        check_vtu_cells_with_meshio(
            &out,
            3,
            51,
            55,
            &["quad", "triangle"],
            [0.0, 0.0, 1.0, 1.0],
            precision,
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// Runs `scene` into `base/<format>` (the run must succeed); that folder, and the rounding the
/// fields' `format` keeps (single precision for `binary`, else double).
fn run_in_format(base: &Path, scene: &Path, format: &str) -> (PathBuf, f64) {
    let out = base.join(format);
    let o = run_cpu(scene, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let precision = if format == "binary" {
        F32_ROUNDING
    } else {
        F64_ROUNDING
    };
    (out, precision)
}

#[test]
fn binary_fields_hold_the_ascii_values_in_a_quarter_of_the_bytes() {
    // The same run written in the three encodings: `binary64` holds every ASCII value bit for bit
    // (the ASCII numbers are shortest round-trip forms), `binary` every value rounded to single
    // precision; all three are read by meshio, and the default `binary` snapshot takes at most a
    // quarter of the ASCII one's bytes.
    let base = tmp_dir("field-formats");
    let mut pieces = Vec::new();
    let mut sizes = Vec::new();
    let formats = ["binary", "binary64", "ascii"];
    for format in formats {
        let scene = base.join(format!("{format}.toml"));
        std::fs::write(
            &scene,
            block_scene(
                &format!("field_interval = 1.0e-4\nfield_format = \"{format}\""),
                "linear_elastic",
                "velocity_gradient = [[100.0, 20.0], [0.0, -60.0]]",
            )
            .replace("cells = [20, 10]", "cells = [100, 50]"),
        )
        .unwrap();
        let (out, precision) = run_in_format(&base, &scene, format);
        check_vtu_with_meshio(&out, 3, 101 * 51, 5000, [0.0, 0.0, 0.1, 0.05], precision);
        let last = out.join("fields/block_00002.vtu");
        let head = std::fs::read(&last).unwrap();
        let head = String::from_utf8_lossy(&head[..600]);
        assert_eq!(
            head.contains("compressor=\"vtkZLibDataCompressor\""),
            format != "ascii",
            "{head}"
        );
        assert_eq!(head.contains("Float32"), format == "binary", "{head}");
        sizes.push(std::fs::metadata(&last).unwrap().len());
        pieces.push(ricochet::plot::read::vtu(&last).expect("read back"));
    }
    let a = &pieces[2];
    assert_eq!(a.points.len(), 101 * 51);
    assert_eq!(a.point_data.len(), 2);
    assert_eq!(a.cell_data.len(), 3);
    for (k, b) in pieces[..2].iter().enumerate() {
        let round = |x: f64| if k == 0 { x as f32 as f64 } else { x };
        let points: Vec<[f64; 2]> = a.points.iter().map(|p| p.map(round)).collect();
        assert_eq!(b.points, points, "{}", formats[k]);
        assert_eq!(b.connectivity, a.connectivity);
        assert_eq!(b.offsets, a.offsets);
        for (x, y) in b
            .point_data
            .iter()
            .zip(&a.point_data)
            .chain(b.cell_data.iter().zip(&a.cell_data))
        {
            assert_eq!((&x.name, x.components), (&y.name, y.components));
            let want: Vec<f64> = y.values.iter().map(|&v| round(v)).collect();
            assert_eq!(x.values, want, "{} {}", formats[k], x.name);
            assert!(x.values.iter().any(|v| *v != 0.0), "{}", x.name);
        }
    }
    assert!(
        4 * sizes[0] <= sizes[2],
        "binary {} bytes against ascii {}",
        sizes[0],
        sizes[2]
    );

    // A binary file cut short, or with a corrupted block, is an error naming the file, not a
    // panic or a silent partial read.
    let bytes = std::fs::read(base.join("binary/fields/block_00002.vtu")).unwrap();
    let cut = base.join("cut.vtu");
    for broken in [
        bytes[..bytes.len() / 2].to_vec(),
        bytes
            .iter()
            .enumerate()
            .map(|(k, &x)| if k > bytes.len() - 3000 { !x } else { x })
            .collect::<Vec<u8>>(),
    ] {
        std::fs::write(&cut, &broken).unwrap();
        let err = ricochet::plot::read::vtu(&cut).expect_err("a broken file is refused");
        assert!(err.to_string().contains("cut.vtu"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_step_longer_than_the_run_or_a_short_run_ends_on_the_end_time() {
    // A soft 1 x 1 m block in free flight: one stable step (6.1 s) is longer than the run
    // (0.05 s); 2.5 steps and 40.5 steps; and a long run, which keeps its steps and ends less
    // than one step (and less than 1 % of the run) past the end. (Free flight: a deforming block
    // at the stability limit would also show the energy audit's sensitivity to a shortened step
    // in a run of three steps, see `step::clip_to_end`.)
    let text = |end: f64| {
        format!(
            "[run]\nend_time = {end:e}\nhistory_interval = {end:e}\n\n[[material]]\nname = \"rubber\"\n\
             model = \"neo_hookean\"\ndensity = 1000.0\nyoungs_modulus = 10.0\npoisson_ratio = 0.3\n\n\
             [[body]]\nname = \"b\"\nmaterial = \"rubber\"\ninitial_velocity = [2.0, -1.0]\n\
             mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [1.0, 1.0], cells = [1, 1] }} }}\n"
        )
    };
    let base = tmp_dir("end-clip");
    let dt = 0.9 * 6.7914; // time_step_scale x the stable step `check` prints
    for (end, steps) in [
        (0.05, 1u64),
        (2.5 * dt, 3),
        (40.5 * dt, 41),
        (1000.3 * dt, 1001),
    ] {
        let scene = base.join("s.toml");
        std::fs::write(&scene, text(end)).unwrap();
        let out = base.join("o");
        let o = run_cpu(&scene, &out, &[]);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        let s = summary(&out);
        let t = s["end_time"].as_f64().unwrap();
        assert_eq!(s["status"], "completed");
        assert_eq!(s["steps"].as_u64().unwrap(), steps, "end {end}");
        if steps < 1000 {
            assert!((t - end).abs() <= 1e-12 * end, "end {end}: t = {t}");
        } else {
            assert!(
                t >= end && t - end < 0.01 * end && t - end < dt,
                "end {end}: t = {t}"
            );
        }
        let (header, rows) = read_csv(&out.join("history.csv"));
        assert_eq!(rows.last().unwrap()[column(&header, "time")], t);
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// Relative rounding of single and double precision.
const F32_ROUNDING: f64 = 5.96e-8;
const F64_ROUNDING: f64 = 1.12e-16;

/// Runs `tests/read_vtu.py` on `dir`. Without meshio (or python3), the check is skipped with a
/// notice, except under CI (env var `CI` set), where it fails.
///
/// `precision`: the relative rounding of the real numbers in the files (2^-24 for the default
/// single-precision binary, 2^-53 for `binary64` and ASCII).
fn check_vtu_with_meshio(
    dir: &Path,
    files: usize,
    points: u64,
    cells: u64,
    bbox: [f64; 4],
    precision: f64,
) {
    check_vtu_cells_with_meshio(dir, files, points, cells, &["quad"], bbox, precision);
}

/// [`check_vtu_with_meshio`] with the VTK cell types expected (meshio's names, sorted).
fn check_vtu_cells_with_meshio(
    dir: &Path,
    files: usize,
    points: u64,
    cells: u64,
    types: &[&str],
    bbox: [f64; 4],
    precision: f64,
) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/read_vtu.py");
    let out = Command::new("python3").arg(&script).arg(dir).output();
    let skip = |why: String| {
        if std::env::var_os("CI").is_some() {
            panic!("CI is set, so the VTU files must be read with meshio: {why}");
        }
        eprintln!(
            "SKIPPED: VTU check with meshio: {why} (install it: python3 -m pip install meshio)"
        );
    };
    let out = match out {
        Ok(o) => o,
        Err(e) => return skip(format!("cannot run python3: {e}")),
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(77) {
        return skip(stderr.trim().to_string());
    }
    assert_eq!(out.status.code(), Some(0), "read_vtu.py failed:\n{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    let pvd = &lines[0];
    assert_eq!(pvd["pvd"], files as u64, "{pvd}");
    assert_eq!(pvd["missing"].as_array().unwrap().len(), 0, "{pvd}");
    let times: Vec<f64> = pvd["times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert!(times.windows(2).all(|w| w[1] > w[0]), "times {times:?}");
    assert_eq!(lines.len(), files + 1, "{stdout}");
    for v in &lines[1..] {
        assert_eq!(v["points"], points, "{v}");
        assert_eq!(v["cells"], cells, "{v}");
        assert_eq!(v["cell_types"], serde_json::json!(types), "{v}");
        for (name, n) in [("displacement", 3), ("velocity", 3)] {
            assert_eq!(v["point_data"][name], n, "{v}");
        }
        for (name, n) in [("stress", 4), ("von_mises", 1), ("equivalent_strain", 1)] {
            assert_eq!(v["cell_data"][name], n, "{v}");
        }
        // Deformed points minus displacement give back the reference mesh.
        let b: Vec<f64> = v["reference_bbox"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        // (Points and displacements are each rounded, so their difference by up to about 2
        // roundings of the largest coordinate.)
        let scale = bbox.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for k in 0..4 {
            assert!((b[k] - bbox[k]).abs() <= 4.0 * precision * scale, "{v}");
        }
        assert!(
            v["von_mises_mismatch"].as_f64().unwrap() <= 16.0 * precision,
            "{v}"
        );
        assert_eq!(v["max_abs_z"].as_f64().unwrap(), 0.0, "{v}");
    }
    println!("meshio read {files} VTU files ({points} points, {cells} cells of {types:?} each)");
}

#[test]
fn auto_backend_prefers_the_cpu_reference_over_a_software_adapter() {
    // What auto should pick on this machine: the GPU only when the most capable adapter is
    // hardware; with a software one (lavapipe in CI) or none, the CPU reference with a notice.
    let best = ricochet::gpu::GpuContext::new(None);
    let hardware = best.as_ref().is_ok_and(|c| !c.is_software());
    let dir = tmp_dir("outputs-auto");
    let scene = asset("vibrating_block.toml");
    let run = |extra: &[&str]| {
        let mut cmd = std::process::Command::new(bin());
        cmd.args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ])
        .args(extra)
        .env_remove("WGPU_ADAPTER_NAME");
        cmd.output().expect("run the binary")
    };
    let o = run(&[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let backend = summary(&dir)["backend"].as_str().unwrap().to_string();
    if hardware {
        assert_eq!(backend, "gpu", "{err}");
    } else {
        assert_eq!(backend, "cpu", "{err}");
        let said = match &best {
            Ok(_) => "the only GPU adapter is a software one",
            Err(_) => "no GPU adapter",
        };
        assert!(err.contains(said) && err.lines().count() == 1, "{err}");
    }
    // Naming the software adapter takes it.
    if let Ok(ctx) = &best {
        if ctx.is_software() {
            let name = ctx.info.name.clone();
            let o = run(&["--adapter", &name]);
            assert_eq!(o.status.code(), Some(0));
            assert_eq!(summary(&dir)["backend"], "gpu");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn end_time_override_and_check() {
    let dir = tmp_dir("outputs-override");
    let scene = asset("vibrating_block.toml");
    let o = run_bin(&[
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--end-time",
        "2e-5",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(summary(&dir)["steps"], 100);
    let _ = std::fs::remove_dir_all(&dir);

    let o = run_bin(&["check", scene.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}");
    for needle in [
        "231 nodes",
        "200 elements",
        "1 bodies",
        "stable 6.97",
        "step 2.0000e-7 s",
        "element_forces -> hourglass_stiffness -> node_update -> history -> fields",
        "history every 2e-6 s (about 101 rows), fields every 2e-5 s (about 11 snapshots, \
         binary VTU, Float32, zlib)",
    ] {
        assert!(
            stdout.contains(needle),
            "`check` output lacks {needle:?}:\n{stdout}"
        );
    }
    // The estimated step count: 2e-4 / 2e-7 = 1000 (the floating-point quotient rounds up,
    // so accept 1001 too).
    let steps: u64 = stdout
        .split("about ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no step estimate in:\n{stdout}"));
    assert!((1000..=1001).contains(&steps), "{steps} steps estimated");
}

#[test]
fn plan_has_only_the_stages_a_scene_needs() {
    let plan = |name: &str| {
        let scene = Scene::load(&asset(name)).unwrap();
        let model = ricochet::run::model(&scene).unwrap();
        Plan::new(&scene, &model).stages
    };
    use Stage::*;
    // Fixed step, stiffness hourglass, no bulk viscosity, no boundaries.
    assert_eq!(
        plan("vibrating_block.toml"),
        vec![
            ElementForces,
            HourglassStiffness,
            NodeUpdate,
            History,
            Fields
        ]
    );
    // Default viscous hourglass and bulk viscosity, variable step.
    assert_eq!(
        plan("spinning_disk.toml"),
        vec![
            ElementForces,
            HourglassViscous,
            BulkViscosity,
            StableStep,
            NodeUpdate,
            History,
            Fields
        ]
    );
    // A boundary adds its pass; no hourglass control adds none.
    let (_, _, p) = build(concat!(
        r#"
[run]
end_time = 1.0e-5
bulk_viscosity = { linear = 0.0, quadratic = 0.0 }
"#,
        steel!(),
        r#"
[[body]]
name = "b"
material = "steel"
mesh = { rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }
hourglass = { form = "none" }
[[boundary]]
body = "b"
region = { min = [-1.0, -1.0], max = [1.0e-9, 1.0] }
velocity = { x = 0.0, y = 0.0 }
"#
    ));
    assert_eq!(
        p.stages,
        vec![
            ElementForces,
            StableStep,
            NodeUpdate,
            VelocityBoundaries,
            History
        ]
    );
    assert_eq!(p.constrained_nodes, 3);
}

#[test]
fn every_example_scene_runs() {
    for name in ["vibrating_block.toml", "spinning_disk.toml", "rods.toml"] {
        let dir = tmp_dir(&format!("asset-{name}"));
        let o = run_bin(&[
            "run",
            asset(name).to_str().unwrap(),
            "--backend",
            "cpu",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let s = summary(&dir);
        assert_eq!(s["status"], "completed", "{name}");
        println!(
            "{name}: {} steps, max energy error {:.2e}",
            s["steps"],
            s["max_energy_error"].as_f64().unwrap()
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn overflowing_velocity_fails_instead_of_completing_with_non_finite_energies() {
    // 1e300 m/s is finite, its kinetic energy is not: the run used to say "completed" with a
    // max_energy_error of 0 over inf and NaN rows.
    for v in ["[1.0e300, 0.0]", "[0.0, -3.0e200]"] {
        let text = block_scene("", "linear_elastic", &format!("initial_velocity = {v}"));
        let (message, _) = expect_failed_run("overflow", &text);
        assert!(
            message.contains("the energies are not finite") && message.contains("overflows"),
            "{v}: {message}"
        );
    }
}

#[test]
fn sigint_stops_a_run_between_sparse_history_rows_within_a_second() {
    // The disk on a wall for 2 ms (about 10 s on the CPU) with one history row at the start and
    // one at the end: the signal is seen between rows (the solver returns to the driver at least
    // every 0.25 s), so the run stops soon after it, not at the end.
    let dir = tmp_dir("outputs-signal-sparse");
    let scene = dir.join("sparse.toml");
    let text = std::fs::read_to_string(asset("disk_wall.toml"))
        .unwrap()
        .replace("history_interval = 2.0e-7", "history_interval = 2.0e-3")
        .replace("field_interval = 2.0e-5\n", "");
    assert!(text.contains("history_interval = 2.0e-3"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let child = std::process::Command::new(bin())
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--end-time",
            "2e-3",
        ])
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start the run");
    let start = std::time::Instant::now();
    while !out.join("summary.json").exists() {
        assert!(start.elapsed().as_secs() < 60, "no summary after 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let sent = std::time::Instant::now();
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(kill.success());
    let o = child.wait_with_output().expect("wait");
    let waited = sent.elapsed().as_secs_f64();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["status"], "interrupted");
    let t = s["end_time"].as_f64().unwrap();
    assert!(t > 0.0 && t < 1.5e-3, "stopped at {t:e}");
    // The process ended well before the run would have (a loaded CI machine may be slow).
    assert!(waited < 5.0, "{waited} s after the signal");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sigint_and_sigterm_end_a_run_with_its_summary_and_complete_history() {
    for (signal, code) in [("INT", 130), ("TERM", 143)] {
        let dir = tmp_dir(&format!("outputs-signal-{signal}"));
        // The disk on a wall for 2 ms (about 10 s on the CPU): interrupted once two snapshots
        // are written.
        let child = std::process::Command::new(bin())
            .args([
                "run",
                asset("disk_wall.toml").to_str().unwrap(),
                "--backend",
                "cpu",
                "--end-time",
                "2e-3",
                "--out",
                dir.to_str().unwrap(),
            ])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("start the run");
        let start = std::time::Instant::now();
        while !dir.join("fields/disk_00001.vtu").exists() {
            assert!(start.elapsed().as_secs() < 60, "no snapshot after 60 s");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        // The summary exists from the first step on (an unwritable folder fails at once).
        assert_eq!(summary(&dir)["status"], "running", "SIG{signal}");
        let kill = std::process::Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .expect("kill");
        assert!(kill.success());
        let out = child.wait_with_output().expect("wait");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "SIG{signal}: {err}");
        let s = summary(&dir);
        assert_eq!(s["status"], "interrupted", "SIG{signal}");
        let message = s["message"].as_str().unwrap();
        assert!(
            message.starts_with(&format!("interrupted by SIG{signal} at step ")),
            "{message}"
        );
        assert!(err.contains(message), "{err}");
        // The history names every row the summary counts, each whole.
        let (header, rows) = read_csv(&dir.join("history.csv"));
        assert_eq!(rows.len() as u64, s["history_rows"].as_u64().unwrap());
        assert!(rows.len() > 1);
        assert!(rows.iter().all(|r| r.len() == header.len()));
        let t_end = s["end_time"].as_f64().unwrap();
        assert!(t_end > 0.0 && t_end < 2e-3, "stopped at {t_end:e}");
        // fields.pvd lists every snapshot written, whole.
        let pvd = std::fs::read_to_string(dir.join("fields.pvd")).expect("fields.pvd");
        assert!(pvd.trim_end().ends_with("</VTKFile>"));
        assert_eq!(
            pvd.matches("<DataSet").count() as u64,
            s["snapshots"].as_u64().unwrap()
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// A block scene with extra `[run]` lines and body lines.
fn block_scene(run_extra: &str, model: &str, body_extra: &str) -> String {
    format!(
        r#"
[run]
end_time = 2.0e-4
{run_extra}

{steel}

[[body]]
name = "block"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [0.1, 0.05], cells = [20, 10] }} }}
{body_extra}
"#,
        steel = steel_of(model),
    )
}

/// Runs a scene that must fail; returns (summary message, stderr).
fn expect_failed_run(case: &str, text: &str) -> (String, String) {
    let dir = tmp_dir(&format!("unstable-{case}"));
    let file = dir.join(format!("{case}.toml"));
    std::fs::write(&file, text).unwrap();
    let out = dir.join("out");
    let o = run_cpu(&file, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(3), "{case}: {stderr}");
    assert!(!stderr.contains("panicked"), "{case}: {stderr}");
    let message = failure_message(case, &out);
    assert!(
        stderr.contains(&message),
        "{case}: stderr lacks the message: {stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
    (message, stderr)
}

/// The message of the failed run whose outputs are in `out`: its summary says "failed", the
/// history written up to the failure is kept, with its header, and the message names the step
/// and the time.
fn failure_message(case: &str, out: &Path) -> String {
    let s = summary(out);
    assert_eq!(s["status"], "failed", "{case}");
    let message = s["message"].as_str().unwrap().to_string();
    let (header, rows) = read_csv(&out.join("history.csv"));
    assert_eq!(header[0], "time");
    assert!(!rows.is_empty());
    assert!(
        message.starts_with("step ") && message.contains(", t = "),
        "{case}: {message}"
    );
    message
}

/// Runs a scene through the library with `time_step_scale` forced to `scale` (a scene file
/// above 1.0 is refused up front, see `tests/core/stress.rs`; the solver's own checks are the
/// safety net behind that); the run must fail. Returns the summary message.
fn expect_failed_scaled_run(case: &str, text: &str, scale: f64) -> String {
    let (scene, model, plan) = build(text);
    let dir = tmp_dir(&format!("unstable-{case}"));
    let mut sched = ricochet::run::schedule(&scene);
    sched.time_step_scale = scale;
    let mut solver = ricochet::step::cpu::CpuSolver::new(model.clone(), plan.clone(), sched);
    let r = ricochet::run::run(&scene, &model, &plan, &mut solver, &dir, None).expect("run");
    let message = failure_message(case, &dir);
    assert_eq!(message, r.summary.message);
    let _ = std::fs::remove_dir_all(&dir);
    message
}

#[test]
fn unstable_time_step_fails_naming_the_element() {
    // 1.5 x the stable step: the highest modes grow exponentially until an element inverts
    // (the energy-error stop is disabled so that the element check speaks).
    let m = expect_failed_scaled_run(
        "scale",
        &block_scene(
            "energy_error_limit = 1e30",
            "linear_elastic",
            "velocity_gradient = [[100.0, 20.0], [0.0, -60.0]]",
        ),
        1.5,
    );
    assert!(
        (m.contains("element ") && m.contains("body \"block\"")) || m.contains("node "),
        "{m}"
    );
    println!("unstable time step: {m}");
}

#[test]
fn unstable_time_step_is_caught_by_the_energy_bound_by_default() {
    let m = expect_failed_scaled_run(
        "scale-energy",
        &block_scene(
            "",
            "linear_elastic",
            "velocity_gradient = [[100.0, 20.0], [0.0, -60.0]]",
        ),
        1.5,
    );
    assert!(
        m.contains("energy balance error") && m.contains("run.energy_error_limit = 0.05"),
        "{m}"
    );
    println!("energy bound: {m}");
}

#[test]
fn crushing_velocity_inverts_an_element_and_fails_naming_it() {
    // A velocity field that crushes the block by 20 % of its size per microsecond.
    let (m, _) = expect_failed_run(
        "crush",
        &block_scene(
            "energy_error_limit = 1e30",
            "linear_elastic",
            "velocity_gradient = [[-2.0e5, 0.0], [0.0, -2.0e5]]",
        ),
    );
    assert!(m.contains("inverted") && m.contains("element "), "{m}");
    println!("crushed: {m}");
}
