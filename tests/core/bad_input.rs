//! Bad input: every rejected scene makes the binary exit with status 2 and an error on stderr
//! that names the file, the key and the offending value -- never a panic. Both `check` and
//! `run` are exercised on each case.

use std::path::PathBuf;
use std::process::Output;
use std::time::{Duration, Instant};

use crate::common::*;

const MATERIAL: &str = concat!("\n", steel!(), "\n");

const BODY: &str = r#"
[[body]]
name = "block"
material = "steel"
mesh = { rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }
"#;

const RUN: &str = "[run]\nend_time = 1.0e-5\n";

/// The valid base scene.
fn valid() -> String {
    format!("{RUN}{MATERIAL}{BODY}")
}

/// A valid scene with `from` replaced by `to` (which must occur).
fn variant(from: &str, to: &str) -> String {
    let base = valid();
    assert!(base.contains(from), "{from:?} not in the base scene");
    base.replacen(from, to, 1)
}

/// Writes `text` to a fresh folder as `<case>.toml`.
fn write_scene(case: &str, text: &str) -> (PathBuf, PathBuf) {
    let dir = tmp_dir(&format!("bad-{case}"));
    let file = dir.join(format!("{case}.toml"));
    std::fs::write(&file, text).unwrap();
    (dir, file)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `check` and `run` on the scene; both must exit with 2 and name the file and every
/// string of `needles` on stderr.
fn expect_rejected(case: &str, text: &str, needles: &[&str]) -> String {
    let (dir, file) = write_scene(case, text);
    let f = file.to_str().unwrap();
    let out = dir.join("out");
    let mut last = String::new();
    for args in [
        vec!["check", f],
        vec!["run", f, "--backend", "cpu", "--out", out.to_str().unwrap()],
    ] {
        let o = run_bin(&args);
        let err = stderr(&o);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{case}: `ricochet {}` exited with {:?}; stderr:\n{err}",
            args[0],
            o.status.code()
        );
        assert!(!err.contains("panicked"), "{case}: panic:\n{err}");
        assert!(
            err.contains(f),
            "{case}: stderr does not name the file:\n{err}"
        );
        for n in needles {
            assert!(
                err.contains(n),
                "{case}: stderr does not contain {n:?}:\n{err}"
            );
        }
        last = err;
    }
    assert!(
        !out.join("summary.json").exists(),
        "{case}: a rejected scene must not produce outputs"
    );
    let _ = std::fs::remove_dir_all(&dir);
    last
}

/// `check` (and, with `run`, a CPU run) accepts the scene.
fn expect_accepted(case: &str, text: &str, run: bool) {
    let (dir, file) = write_scene(case, text);
    let o = if run {
        run_cpu(&file, &dir.join("out"), &[])
    } else {
        run_bin(&["check", file.to_str().unwrap()])
    };
    assert_eq!(o.status.code(), Some(0), "{case}: {}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn negative_density() {
    expect_rejected(
        "negative_density",
        &variant("density = 7850.0", "density = -7850.0"),
        &["material[0].density", "-7850.0"],
    );
}

#[test]
fn non_positive_youngs_modulus() {
    expect_rejected(
        "zero_modulus",
        &variant("youngs_modulus = 2.1e11", "youngs_modulus = 0.0"),
        &["material[0].youngs_modulus", "0.0"],
    );
}

/// The base scene's material made `j2_plastic` with `keys` (TOML lines) added.
fn plastic(keys: &str) -> String {
    variant(
        "model = \"linear_elastic\"",
        &format!("model = \"j2_plastic\"\n{keys}"),
    )
}

#[test]
fn bad_plastic_materials() {
    expect_accepted(
        "plastic_ok",
        &plastic("yield_stress = 2.5e8\nhardening_modulus = 1.0e9"),
        true,
    );
    expect_rejected(
        "plastic_zero_yield",
        &plastic("yield_stress = 0.0"),
        &["material[0].yield_stress", "0.0"],
    );
    expect_rejected(
        "plastic_negative_yield",
        &plastic("yield_stress = -2.5e8"),
        &["material[0].yield_stress", "-250000000"],
    );
    expect_rejected(
        "plastic_no_yield",
        &plastic("hardening_modulus = 1.0e9"),
        &["material[0].yield_stress", "missing"],
    );
    expect_rejected(
        "plastic_negative_hardening",
        &plastic("yield_stress = 2.5e8\nhardening_modulus = -1.0e9"),
        &["material[0].hardening_modulus", "-1000000000"],
    );
    expect_accepted(
        "johnson_cook_ok",
        &plastic(
            "johnson_cook = { a = 9.0e7, b = 2.92e8, n = 0.31, c = 0.025, reference_strain_rate = 1.0 }",
        ),
        true,
    );
    expect_rejected(
        "johnson_cook_missing_key",
        &plastic("johnson_cook = { a = 9.0e7, n = 0.31, c = 0.025, reference_strain_rate = 1.0 }"),
        &["material[0].johnson_cook.b", "missing"],
    );
    expect_rejected(
        "johnson_cook_with_yield_stress",
        &plastic(
            "yield_stress = 2.5e8\njohnson_cook = { a = 9.0e7, b = 2.92e8, n = 0.31, c = 0.025, reference_strain_rate = 1.0 }",
        ),
        &["material[0].yield_stress", "johnson_cook"],
    );
    expect_rejected(
        "johnson_cook_zero_exponent",
        &plastic(
            "johnson_cook = { a = 9.0e7, b = 2.92e8, n = 0.0, c = 0.025, reference_strain_rate = 1.0 }",
        ),
        &["material[0].johnson_cook.n", "0.0"],
    );
    expect_rejected(
        "johnson_cook_unknown_key",
        &plastic(
            "johnson_cook = { a = 9.0e7, b = 2.92e8, n = 0.31, c = 0.025, reference_strain_rate = 1.0, d = 1.09 }",
        ),
        &["material[0].johnson_cook.d", "unknown key"],
    );
    bad_failure_keys();
    bad_thermal_keys();
    expect_rejected(
        "elastic_with_yield",
        &variant(
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.3\nyield_stress = 2.5e8",
        ),
        &["material[0].yield_stress", "j2_plastic"],
    );
    expect_rejected(
        "plastic_plane_stress",
        &plastic("yield_stress = 2.5e8").replace(
            "material = \"steel\"",
            "material = \"steel\"\nformulation = \"plane_stress\"",
        ),
        &["body[0].formulation", "plane_stress", "j2_plastic"],
    );
}

#[test]
fn poisson_ratio_of_one_half() {
    expect_rejected(
        "poisson_half",
        &variant("poisson_ratio = 0.3", "poisson_ratio = 0.5"),
        &["material[0].poisson_ratio", "0.5"],
    );
}

#[test]
fn poisson_ratio_above_one_half() {
    expect_rejected(
        "poisson_high",
        &variant("poisson_ratio = 0.3", "poisson_ratio = 0.7"),
        &["material[0].poisson_ratio", "0.7"],
    );
}

#[test]
fn unknown_material_model() {
    expect_rejected(
        "unknown_model",
        &variant("model = \"linear_elastic\"", "model = \"elastic\""),
        &["material[0].model", "\"elastic\""],
    );
}

#[test]
fn unknown_material_name() {
    expect_rejected(
        "unknown_material",
        &variant("material = \"steel\"", "material = \"stel\""),
        &["body[0].material", "\"stel\""],
    );
}

#[test]
fn body_names_that_would_escape_the_output_folder_or_break_the_history_header() {
    // Body names become `fields/<name>_<k>.vtu` and `history.csv` columns.
    let long = "b".repeat(300);
    for (case, name) in [
        ("name_parent", "../../escaped"),
        ("name_absolute", "/tmp/escaped"),
        ("name_comma", "a,b"),
        ("name_slash", "a/b"),
        ("name_nul", "a\\u0000b"),
        ("name_space", "a b"),
        ("name_dot", ".hidden"),
        ("name_empty", ""),
        ("name_long", long.as_str()),
    ] {
        let text = variant("name = \"block\"", &format!("name = \"{name}\""));
        let err = expect_rejected(case, &text, &["body[0].name", "a name must be 1 to 64"]);
        assert!(err.len() < 1000, "{case}: message of {} bytes", err.len());
    }
    // Allowed: letters, digits, `_`, `-`, `.` inside.
    let text = variant("name = \"block\"", "name = \"Part_2-a.v1\"");
    expect_accepted("name_ok", &text, true);
}

#[test]
fn runs_that_would_never_end_are_refused_naming_the_key_and_the_limit() {
    let cases: [(&str, String, &[&str]); 6] = [
        (
            "history_1e-300",
            variant("end_time = 1.0e-5\n", "end_time = 1.0e-5\nhistory_interval = 1e-300\n"),
            &["run.history_interval", "1e-300", "more than the limit of 1e7"],
        ),
        (
            "fields_1e-300",
            variant("end_time = 1.0e-5\n", "end_time = 1.0e-5\nfield_interval = 1e-300\n"),
            &["run.field_interval", "1e-300", "more than the limit of 1e5"],
        ),
        (
            "scale_1e-300",
            variant(
                "end_time = 1.0e-5\n",
                "end_time = 1.0e-5\ntime_step_scale = 1e-300\n",
            ),
            &["run.time_step_scale", "1e-300", "more than the limit of 1e9"],
        ),
        (
            "scale_5e-324",
            variant(
                "end_time = 1.0e-5\n",
                "end_time = 1.0e-5\ntime_step_scale = 5e-324\n",
            ),
            &["run.time_step_scale", "5e-324", "subnormal"],
        ),
        (
            "penalty_1e300",
            format!(
                "{}\n[[rigid_wall]]\npoint = [0.0, -1.0e-3]\nnormal = [0.0, 1.0]\nmethod = \"penalty\"\npenalty_scale = 1e300\n",
                valid()
            ),
            &["rigid_wall[0].penalty_scale", "1e300", "more than the limit of 1e9"],
        ),
        (
            "end_1e9_steps",
            variant("end_time = 1.0e-5\n", "end_time = 1.0e5\n"),
            &["run.end_time", "1e5", "more than the limit of 1e9"],
        ),
    ];
    for (case, text, needles) in &cases {
        expect_rejected(case, text, needles);
    }
}

#[test]
fn spinning_rubber_disk_against_a_penalty_wall_through_its_rim_ends() {
    // Issue 16 case 2: a 10 MPa rubber disk spinning at 200 rad/s against a penalty wall placed
    // 5 mm inside its rim used to hang. The overlap is moved onto the wall at t = 0 and the run
    // ends in about 10^4 steps with its energy balance.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/spinning_disk.toml"),
    )
    .unwrap()
        + "\n[[rigid_wall]]\npoint = [0.0, -0.045]\nnormal = [0.0, 1.0]\nmethod = \"penalty\"\n";
    let (dir, file) = write_scene("spinning_rim", &text);
    let out = dir.join("out");
    let o = run_cpu(&file, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["status"], "completed");
    let steps = s["steps"].as_u64().unwrap();
    assert!(steps > 1000 && steps < 100_000, "{steps} steps");
    assert!(s["max_energy_error"].as_f64().unwrap() < 1e-4, "{s}");
    assert!(s["contact_searches"].as_u64().unwrap() < steps / 10, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn contact_names_longer_than_256_characters_are_refused() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/disk_wall.toml"),
    )
    .unwrap();
    let long = "w".repeat(300);
    let named = text.replacen(
        "[[rigid_wall]]\nname = \"wall\"",
        &format!("[[rigid_wall]]\nname = \"{long}\""),
        1,
    );
    assert_ne!(named, text);
    expect_rejected(
        "long_wall_name",
        &named,
        &["rigid_wall[0].name", "1 to 256 characters"],
    );
}

#[test]
fn duplicate_body_name() {
    let text = format!("{}{BODY}", valid());
    expect_rejected("duplicate_body", &text, &["body[1].name", "\"block\""]);
}

#[test]
fn zero_rectangle_cells() {
    expect_rejected(
        "zero_cells",
        &variant("cells = [4, 2]", "cells = [0, 2]"),
        &["body[0].mesh.rectangle.cells", "[0, 2]"],
    );
}

#[test]
fn zero_disk_cells() {
    expect_rejected(
        "zero_disk_cells",
        &variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            "{ disk = { center = [0.0, 0.0], radius = 0.05, cells = 0 } }",
        ),
        &["body[0].mesh.disk.cells", "0"],
    );
}

#[test]
fn negative_rectangle_size() {
    expect_rejected(
        "negative_size",
        &variant("size = [0.1, 0.05]", "size = [0.1, -0.05]"),
        &["body[0].mesh.rectangle.size", "[0.1, -0.05]"],
    );
}

#[test]
fn rectangle_whose_cell_area_overflows_names_the_size_not_convexity() {
    let msg = expect_rejected(
        "overflowing_size",
        &variant("size = [0.1, 0.05]", "size = [1e300, 1e300]"),
        &["body[0].mesh.rectangle.size", "[1e300, 1e300]", "area"],
    );
    assert!(!msg.contains("convex"), "{msg}");
}

#[test]
fn non_positive_thickness() {
    expect_rejected(
        "zero_thickness",
        &variant(
            "material = \"steel\"\n",
            "material = \"steel\"\nthickness = -0.01\n",
        ),
        &["body[0].thickness", "-0.01"],
    );
}

#[test]
fn inverted_explicit_mesh() {
    // A clockwise quad: negative area.
    expect_rejected(
        "inverted_mesh",
        &variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            "{ nodes = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], quads = [[0, 3, 2, 1]] }",
        ),
        &["body[0].mesh", "quad 0 = [0, 3, 2, 1]", "area -1"],
    );
}

#[test]
fn zero_area_explicit_mesh() {
    // Four collinear nodes.
    expect_rejected(
        "zero_area_mesh",
        &variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            "{ nodes = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]], quads = [[0, 1, 2, 3]] }",
        ),
        &["body[0].mesh", "quad 0 = [0, 1, 2, 3]", "area 0"],
    );
}

#[test]
fn non_convex_explicit_mesh() {
    // A dart: positive area but a re-entrant corner.
    expect_rejected(
        "dart_mesh",
        &variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            "{ nodes = [[0.0, 0.0], [1.0, 0.0], [0.3, 0.3], [0.0, 1.0]], quads = [[0, 1, 2, 3]] }",
        ),
        &["body[0].mesh", "quad 0 = [0, 1, 2, 3]"],
    );
}

#[test]
fn bad_gravity_names_the_key_and_value() {
    let with = |g: &str| {
        variant(
            "end_time = 1.0e-5\n",
            &format!("end_time = 1.0e-5\ngravity = {g}\n"),
        )
    };
    expect_accepted("gravity_ok", &with("[0.0, -9.81]"), true);
    expect_accepted("gravity_integers", &with("[0, -10]"), false);
    for (case, g, why) in [
        ("gravity_scalar", "9.81", "must be a 2-vector"),
        ("gravity_three", "[0.0, -9.81, 0.0]", "must be a 2-vector"),
        ("gravity_text", "[\"0\", \"-9.81\"]", "must be a 2-vector"),
        ("gravity_infinite", "[0.0, -inf]", "must be finite"),
        ("gravity_nan", "[nan, 0.0]", "must be finite"),
    ] {
        expect_rejected(case, &with(g), &["run.gravity", why]);
    }
}

#[test]
fn explicit_triangles_are_read_and_bad_ones_named() {
    let mesh = |quads: &str| {
        variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            &format!(
                "{{ nodes = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.5]], quads = {quads} }}"
            ),
        )
    };
    // A quad and a triangle, the triangle written with three nodes or collapsed.
    expect_accepted(
        "explicit_triangle",
        &mesh("[[0, 1, 2, 3], [1, 4, 2]]"),
        true,
    );
    expect_accepted(
        "explicit_collapsed_triangle",
        &mesh("[[0, 1, 2, 3], [1, 4, 2, 2]]"),
        false,
    );
    expect_rejected(
        "clockwise_triangle",
        &variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            "{ nodes = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], quads = [[0, 2, 1]] }",
        ),
        &["body[0].mesh", "triangle 0 = [0, 2, 1, 1]", "area -5e-1"],
    );
    expect_rejected(
        "triangle_repeated_node",
        &mesh("[[0, 1, 2, 3], [1, 1, 4]]"),
        &["body[0].mesh", "element 1 = [1, 1, 4, 4]", "same node"],
    );
    expect_rejected(
        "element_of_five_nodes",
        &mesh("[[0, 1, 2, 3, 4]]"),
        &[
            "quads = [[0, 1, 2, 3, 4]]",
            "3 node indices (a triangle) or 4 (a quad)",
        ],
    );
}

#[test]
fn explicit_mesh_index_out_of_range() {
    expect_rejected(
        "index_mesh",
        &variant(
            "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            "{ nodes = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], quads = [[0, 1, 2, 4]] }",
        ),
        &["body[0].mesh.quads[0]", "[0, 1, 2, 4]"],
    );
}

#[test]
fn boundary_box_selects_no_node() {
    let text = format!(
        "{}\n[[boundary]]\nbody = \"block\"\nregion = {{ min = [5.0, 5.0], max = [6.0, 6.0] }}\nvelocity = {{ x = 0.0 }}\n",
        valid()
    );
    expect_rejected(
        "empty_boundary",
        &text,
        &["boundary[0].region", "min = [5.0, 5.0]", "max = [6.0, 6.0]"],
    );
}

#[test]
fn boundary_on_unknown_body() {
    let text = format!(
        "{}\n[[boundary]]\nbody = \"blok\"\nregion = {{ min = [-1.0, -1.0], max = [1.0, 1.0] }}\nvelocity = {{ x = 0.0 }}\n",
        valid()
    );
    expect_rejected("unknown_body", &text, &["boundary[0].body", "\"blok\""]);
}

#[test]
fn non_positive_time_step_scale() {
    expect_rejected(
        "zero_scale",
        &variant(
            "end_time = 1.0e-5\n",
            "end_time = 1.0e-5\ntime_step_scale = 0.0\n",
        ),
        &["run.time_step_scale", "0.0"],
    );
}

#[test]
fn fixed_length_arrays_with_extra_values_are_refused() {
    // serde's own [T; N] took the first N values and dropped the rest.
    let explicit = |nodes: &str, quads: &str| {
        variant(
            "mesh = { rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            &format!("mesh = {{ nodes = {nodes}, quads = {quads} }}"),
        )
    };
    let cases: [(&str, String); 6] = [
        ("cells_3", variant("cells = [4, 2]", "cells = [4, 2, 0]")),
        (
            "origin_3",
            variant("origin = [0.0, 0.0]", "origin = [0.0, 0.0, 1.0]"),
        ),
        (
            "node_xyz",
            explicit(
                "[[0.0, 0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]",
                "[[0, 1, 2, 3]]",
            ),
        ),
        (
            "quad_5",
            explicit(
                "[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]",
                "[[0, 1, 2, 3, 0]]",
            ),
        ),
        (
            "velocity_3",
            format!("{}initial_velocity = [1.0, 0.0, 0.0]\n", valid()),
        ),
        (
            "wall_point_1",
            format!(
                "{}\n[[rigid_wall]]\npoint = [0.0]\nnormal = [0.0, 1.0]\n",
                valid()
            ),
        ),
    ];
    for (case, text) in &cases {
        expect_rejected(case, text, &["TOML parse error at line", "exactly"]);
    }
    // The explicit mesh with the right lengths runs.
    let ok = explicit(
        "[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]",
        "[[0, 1, 2, 3]]",
    );
    expect_accepted("explicit_ok", &ok, false);
}

#[test]
fn a_wall_normal_whose_length_overflows_keeps_its_direction() {
    // [-1.5e308, -1.5e308] has a length above f64::MAX: it used to become the zero vector and
    // the wall did nothing. It is the direction (-1, -1) / sqrt 2.
    let text = format!(
        "{}\n[[rigid_wall]]\nname = \"w\"\npoint = [1.0, 1.0]\nnormal = [-1.5e308, -1.5e308]\n",
        valid()
    );
    let scene =
        ricochet::scene::Scene::parse(&text, std::path::Path::new("wall.toml")).expect("parses");
    let n = scene.walls[0].normal;
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        (n[0] + h).abs() < 1e-15 && (n[1] + h).abs() < 1e-15,
        "{n:?}"
    );
}

#[test]
fn scenes_beyond_the_machines_memory_are_refused_before_meshing() {
    // 10^10 elements (inside the documented cell range) used to abort on allocation; a disk of
    // cells = 20000 (1.2e9 elements) meshed toward the out-of-memory killer.
    expect_rejected(
        "cells_1e5",
        &variant("cells = [4, 2]", "cells = [100000, 100000]"),
        &[
            "body[0].mesh.rectangle.cells",
            "[100000, 100000]",
            "10000000000 elements",
            "GiB this machine has available",
        ],
    );
    expect_rejected(
        "disk_20000",
        &variant(
            "rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] }",
            "disk = { center = [0.0, 0.0], radius = 0.1, cells = 20000 }",
        ),
        &["body[0].mesh.disk.cells", "20000", "1200000000 elements"],
    );
    // `bench` sizes likewise, naming the option.
    let o = run_bin(&["bench", "--backend", "cpu", "--cells", "100000"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("key `--cells` = 100000")
            && stderr(&o).contains("GiB this machine has available"),
        "{}",
        stderr(&o)
    );
    // A scene file that never ends is not read until memory runs out.
    let o = run_bin(&["check", "/dev/zero"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("/dev/zero: larger than 64 MiB"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn duplicate_or_overlapping_quads_of_an_explicit_mesh_are_refused() {
    let mesh = |quads: &str| {
        // Nodes 0-5: a 2 x 1 grid of unit squares; node 6 at (0.5, 0) only for the folded quad.
        let extra = if quads.contains('6') {
            ", [0.5, 0.0]"
        } else {
            ""
        };
        variant(
            "mesh = { rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            &format!(
                "mesh = {{ nodes = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], \
                 [2.0, 1.0]{extra}], quads = {quads} }}"
            ),
        )
    };
    // The same quad twice, and one starting at another node.
    expect_rejected(
        "quad_duplicate",
        &mesh("[[0, 1, 4, 3], [1, 2, 5, 4], [0, 1, 4, 3]]"),
        &["quads[2]", "overlaps quads[0]", "same side"],
    );
    expect_rejected(
        "quad_rotated",
        &mesh("[[0, 1, 4, 3], [4, 3, 0, 1]]"),
        &["quads[1]", "overlaps quads[0]"],
    );
    // A quad folded over its neighbour across their shared edge 1-4.
    expect_rejected(
        "quad_folded",
        &mesh("[[0, 1, 4, 3], [6, 1, 4, 3]]"),
        &["quads[1]", "overlaps quads[0]"],
    );
    // Two quads sharing the edge 1-4 in opposite directions are fine.
    expect_accepted("quads_ok", &mesh("[[0, 1, 4, 3], [1, 2, 5, 4]]"), false);
    // A quad laid over two others, sharing no edge with either (own nodes 6-9), and a small one
    // inside a large one; a quad touching others at a corner only is fine.
    let over = |nodes: &str, quads: &str| {
        variant(
            "mesh = { rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [4, 2] } }",
            &format!(
                "mesh = {{ nodes = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], \
                 [2.0, 1.0], {nodes}], quads = {quads} }}"
            ),
        )
    };
    expect_rejected(
        "quad_laid_over",
        &over(
            "[0.5, 0.2], [1.5, 0.2], [1.5, 0.8], [0.5, 0.8]",
            "[[0, 1, 4, 3], [1, 2, 5, 4], [6, 7, 8, 9]]",
        ),
        &["quads[2]", "overlaps quads[0]", "interiors intersect"],
    );
    expect_rejected(
        "quad_inside",
        &over(
            "[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]",
            "[[6, 7, 8, 9], [0, 1, 4, 3], [1, 2, 5, 4]]",
        ),
        &["quads[1]", "overlaps quads[0]", "interiors intersect"],
    );
    expect_accepted(
        "quad_corner_touch",
        &over(
            "[3.0, 1.0], [3.0, 2.0], [2.0, 2.0]",
            "[[0, 1, 4, 3], [1, 2, 5, 4], [5, 6, 7, 8]]",
        ),
        false,
    );
}

#[test]
fn overlap_check_finds_one_overlap_among_many_quads_by_its_grid() {
    // 200 x 200 quads of a generated grid (40 000): none overlap; then one quad moved over its
    // diagonal neighbour is found, and the check takes about one pass.
    let mesh = ricochet::mesh::rectangle([0.0, 0.0], [1.0, 1.0], [200, 200]);
    assert_eq!(
        ricochet::geometry::overlapping_quads(&mesh.nodes, &mesh.quads),
        None
    );
    let mut nodes = mesh.nodes.clone();
    let mut quads = mesh.quads.clone();
    let base = nodes.len() as u32;
    let h = 1.0 / 200.0;
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        nodes.push([0.5 + 0.5 * h + dx * h, 0.5 + 0.5 * h + dy * h]);
    }
    quads.push([base, base + 1, base + 2, base + 3]);
    let found =
        ricochet::geometry::overlapping_quads(&nodes, &quads).expect("the overlap is found");
    assert_eq!(found.1, quads.len() - 1);
    // The four quads it covers in part: (100, 100), (101, 100), (100, 101), (101, 101).
    assert!(
        [100 * 200 + 100, 100 * 200 + 101].contains(&found.0),
        "{found:?}"
    );
}

#[test]
fn messages_name_the_real_cause() {
    // A subnormal density used to be reported as "node belongs to no element".
    expect_rejected(
        "density_subnormal",
        &variant("density = 7850.0", "density = 1e-310"),
        &["material[0].density", "1e-310", "subnormal"],
    );
    // A normal density whose nodal masses underflow on tiny elements.
    expect_rejected(
        "mass_underflow",
        &variant("density = 7850.0", "density = 1e-300")
            .replace("size = [0.1, 0.05]", "size = [1.0e-5, 1.0e-5]"),
        &["material[0].density", "underflows"],
    );
    // A rectangle whose far corner overflows used to be "not convex and counter-clockwise".
    expect_rejected(
        "rectangle_overflow",
        &variant("origin = [0.0, 0.0]", "origin = [1.0e308, 0.0]")
            .replace("size = [0.1, 0.05]", "size = [1.5e308, 0.05]"),
        &["body[0].mesh.rectangle.size", "origin + size = inf"],
    );
}

#[test]
fn unknown_key_names_the_line() {
    // A typo: `densty`. The parser names the line, the column and the unknown key.
    expect_rejected(
        "typo",
        &variant("density = 7850.0", "densty = 7850.0"),
        &["line 7", "densty", "unknown field"],
    );
}

#[test]
fn missing_end_time_names_the_line() {
    expect_rejected(
        "no_end_time",
        &variant("end_time = 1.0e-5\n", "history_interval = 1.0e-6\n"),
        &["line 1", "end_time", "missing field"],
    );
}

#[test]
fn not_toml_at_all() {
    expect_rejected("garbage", "[run\nend_time = = 1\n", &["line 1"]);
}

#[test]
fn missing_file() {
    let dir = tmp_dir("bad-missing");
    let file = dir.join("does_not_exist.toml");
    let f = file.to_str().unwrap();
    for args in [vec!["check", f], vec!["run", f, "--backend", "cpu"]] {
        let o = run_bin(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(f) && err.contains("cannot read"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn negative_end_time_on_the_command_line() {
    let (dir, file) = write_scene("cli_end_time", &valid());
    let o = run_bin(&[
        "run",
        file.to_str().unwrap(),
        "--backend",
        "cpu",
        "--end-time=-1",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--end-time") && err.contains("-1.0"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fixed_time_step_above_the_stable_step() {
    // The block's stable step is about 3.5e-6 s (h = 0.025 m, c = 7170 m/s).
    let text = variant(
        "end_time = 1.0e-5\n",
        "end_time = 1.0e-5\ntime_step = 1.0e-5\n",
    );
    let (dir, file) = write_scene("big_step", &text);
    let f = file.to_str().unwrap();
    // `check` rejects it as bad input.
    let o = run_bin(&["check", f]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(f) && err.contains("run.time_step") && err.contains("1e-5"),
        "{err}"
    );
    // `run` refuses to integrate with it and names the element that limits the step. (It
    // reports this as a run that failed at step 0, exit status 3, not as bad input.)
    let o = run_bin(&[
        "run",
        f,
        "--backend",
        "cpu",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("time_step") && err.contains("element"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_base_scene_is_valid() {
    // Guards the cases above: they differ from a scene that passes.
    let (dir, file) = write_scene("valid", &valid());
    let o = run_bin(&["check", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

fn with_contact(extra: &str) -> String {
    format!(
        "{}\n[[body]]\nname = \"other\"\nmaterial = \"steel\"\nmesh = {{ rectangle = {{ origin = [0.2, 0.0], size = [0.1, 0.05], cells = [2, 2] }} }}\n{extra}",
        valid()
    )
}

#[test]
fn contact_keys_are_checked() {
    expect_rejected(
        "contact_unknown_body",
        &with_contact("[[contact]]\nbodies = [\"block\", \"nothing\"]\n"),
        &["contact[0].bodies", "\"nothing\"", "no body of that name"],
    );
    expect_rejected(
        "contact_one_body",
        &with_contact("[[contact]]\nbodies = [\"block\"]\n"),
        &["contact[0].bodies", "exactly two"],
    );
    expect_rejected(
        "contact_self",
        &with_contact("[[contact]]\nbodies = [\"block\", \"block\"]\n"),
        &["contact[0].bodies", "must differ"],
    );
    expect_rejected(
        "contact_method",
        &with_contact("[[contact]]\nbodies = [\"block\", \"other\"]\nmethod = \"glue\"\n"),
        &["contact[0].method", "\"glue\"", "lagrange"],
    );
    expect_rejected(
        "contact_scale_without_penalty",
        &with_contact("[[contact]]\nbodies = [\"block\", \"other\"]\npenalty_scale = 0.5\n"),
        &["contact[0].penalty_scale", "0.5", "penalty"],
    );
    expect_rejected(
        "contact_negative_scale",
        &with_contact(
            "[[contact]]\nbodies = [\"block\", \"other\"]\nmethod = \"penalty\"\npenalty_scale = -1.0\n",
        ),
        &["contact[0].penalty_scale", "-1.0", "positive"],
    );
    expect_rejected(
        "contact_group_one_body",
        &with_contact("[[contact]]\nbodies = [\"other\"]\n"),
        &["contact[0].bodies", "[\"other\"]", "self_contact = true"],
    );
    expect_rejected(
        "contact_group_duplicate",
        &with_contact(
            "[[contact]]\nbodies = [\"block\", \"other\", \"block\"]\nself_contact = true\n",
        ),
        &["contact[0].bodies", "\"block\" is named twice"],
    );
    expect_rejected(
        "contact_group_empty",
        &with_contact("[[contact]]\nbodies = []\n"),
        &["contact[0].bodies", "[]", "at least one body"],
    );
    expect_rejected(
        "contact_group_word",
        &with_contact("[[contact]]\nbodies = \"everything\"\n"),
        &["contact[0].bodies", "\"everything\"", "\"all\""],
    );
    expect_rejected(
        "contact_group_one_pass",
        &with_contact("[[contact]]\nbodies = \"all\"\ntwo_pass = false\n"),
        &["contact[0].two_pass", "false", "group"],
    );
    expect_rejected(
        "contact_duplicate_name",
        &with_contact(
            "[[contact]]\nbodies = [\"block\", \"other\"]\n[[contact]]\nbodies = [\"block\", \"other\"]\n",
        ),
        &["contact[1].name", "\"block-other\"", "distinct"],
    );
    expect_rejected(
        "wall_zero_normal",
        &with_contact("[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 0.0]\n"),
        &["rigid_wall[0].normal", "[0.0, 0.0]", "non-zero"],
    );
    expect_rejected(
        "wall_unknown_key",
        &with_contact("[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\nfricton = 0.3\n"),
        &["fricton"],
    );
}

#[test]
fn bad_friction_names_the_key_and_value() {
    let wall = |rest: &str| {
        with_contact(&format!(
            "[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n{rest}\n"
        ))
    };
    expect_accepted("wall_friction_ok", &wall("friction = 0.3"), false);
    expect_accepted("wall_friction_zero", &wall("friction = 0.0"), false);
    expect_accepted(
        "wall_friction_penalty",
        &wall("method = \"penalty\"\nfriction = 0.3"),
        true,
    );
    for (case, rest, needles) in [
        (
            "wall_friction_negative",
            "friction = -0.3",
            ["rigid_wall[0].friction", "-0.3", ">= 0"],
        ),
        (
            "wall_friction_nan",
            "friction = nan",
            ["rigid_wall[0].friction", "NaN", ">= 0"],
        ),
        (
            "wall_friction_infinite",
            "friction = inf",
            ["rigid_wall[0].friction", "inf", ">= 0"],
        ),
    ] {
        expect_rejected(case, &wall(rest), &needles);
    }
    let text = with_contact("[[contact]]\nbodies = [\"block\", \"other\"]\nfriction = -1.0\n");
    expect_rejected(
        "contact_friction_negative",
        &text,
        &["contact[0].friction", "-1", ">= 0"],
    );
    // The perturbed Lagrangian carries normal multipliers only.
    expect_rejected(
        "wall_friction_perturbed",
        &wall("method = \"perturbed_lagrange\"\nfriction = 0.3"),
        &["rigid_wall[0].friction", "0.3", "perturbed Lagrangian"],
    );
    expect_accepted(
        "wall_perturbed",
        &wall("method = \"perturbed_lagrange\"\npenalty_scale = 0.5"),
        false,
    );
    expect_rejected(
        "wall_method_unknown",
        &wall("method = \"augmented\""),
        &[
            "rigid_wall[0].method",
            "\"augmented\"",
            "perturbed_lagrange",
            "augmented_lagrange",
        ],
    );
}

#[test]
fn bad_augmented_lagrange_names_the_key_and_value() {
    let wall = |damping: &str, rest: &str| {
        with_contact(&format!(
            "[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\nmethod = \"augmented_lagrange\"\n{rest}\n"
        ))
        .replacen(RUN, &format!("{RUN}{damping}"), 1)
    };
    let damped = "mass_damping = 1.0e3\n";
    expect_accepted("wall_augmented", &wall(damped, ""), true);
    expect_accepted(
        "wall_augmented_rate",
        &wall(damped, "augmentation_rate = 800.0\npenalty_scale = 0.5"),
        false,
    );
    for (case, damping, rest, needles) in [
        // Its multipliers' update needs mass damping, and a rate below it.
        (
            "wall_augmented_undamped",
            "",
            "",
            &[
                "rigid_wall[0].method",
                "augmented_lagrange",
                "run.mass_damping",
            ][..],
        ),
        (
            "wall_augmented_rate_too_high",
            damped,
            "augmentation_rate = 1000.0",
            &[
                "rigid_wall[0].augmentation_rate",
                "1000",
                "below run.mass_damping",
            ][..],
        ),
        (
            "wall_augmented_rate_negative",
            damped,
            "augmentation_rate = -5.0",
            &["rigid_wall[0].augmentation_rate", "-5"][..],
        ),
        (
            "wall_augmented_rate_nan",
            damped,
            "augmentation_rate = nan",
            &["rigid_wall[0].augmentation_rate", "NaN"][..],
        ),
        // Normal multipliers only.
        (
            "wall_augmented_friction",
            damped,
            "friction = 0.3",
            &["rigid_wall[0].friction", "0.3", "augmented Lagrangian"][..],
        ),
    ] {
        expect_rejected(case, &wall(damping, rest), needles);
    }
    // The rate belongs to the augmented Lagrangian only.
    expect_rejected(
        "contact_rate_penalty",
        &with_contact(
            "[[contact]]\nbodies = [\"block\", \"other\"]\nmethod = \"penalty\"\naugmentation_rate = 10.0\n",
        ),
        &["contact[0].augmentation_rate", "10", "augmented_lagrange"],
    );
}

#[test]
fn bad_penalty_stiffness_names_the_key_and_value() {
    let wall = |rest: &str| {
        with_contact(&format!(
            "[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n{rest}\n"
        ))
    };
    expect_accepted(
        "wall_mass_form",
        &wall("method = \"penalty\"\npenalty_stiffness = \"mass\"\npenalty_scale = 0.2"),
        true,
    );
    expect_accepted(
        "wall_friction_stiffness",
        &wall("method = \"penalty\"\nfriction = 0.3\nfriction_stiffness = 0.5"),
        true,
    );
    for (case, rest, needles) in [
        (
            "wall_form_unknown",
            "method = \"penalty\"\npenalty_stiffness = \"springy\"",
            ["rigid_wall[0].penalty_stiffness", "\"springy\"", "\"mass\""],
        ),
        (
            "wall_form_lagrange",
            "penalty_stiffness = \"mass\"",
            ["rigid_wall[0].penalty_stiffness", "\"mass\"", "penalty"],
        ),
        (
            "wall_friction_stiffness_frictionless",
            "method = \"penalty\"\nfriction_stiffness = 0.5",
            ["rigid_wall[0].friction_stiffness", "0.5", "friction > 0"],
        ),
        (
            "wall_friction_stiffness_lagrange",
            "friction = 0.3\nfriction_stiffness = 0.5",
            ["rigid_wall[0].friction_stiffness", "0.5", "penalty"],
        ),
        (
            "wall_friction_stiffness_negative",
            "method = \"penalty\"\nfriction = 0.3\nfriction_stiffness = -2.0",
            ["rigid_wall[0].friction_stiffness", "-2", "positive"],
        ),
        (
            "wall_friction_stiffness_nan",
            "method = \"penalty\"\nfriction = 0.3\nfriction_stiffness = nan",
            ["rigid_wall[0].friction_stiffness", "NaN", "positive"],
        ),
    ] {
        expect_rejected(case, &wall(rest), &needles);
    }
    expect_rejected(
        "contact_form_number",
        &with_contact(
            "[[contact]]\nbodies = [\"block\", \"other\"]\nmethod = \"penalty\"\npenalty_stiffness = \"modulus \"\n",
        ),
        &["contact[0].penalty_stiffness", "\"modulus \"", "\"modulus\""],
    );
}

fn with_pressure(keys: &str) -> String {
    format!("{}\n[[pressure]]\n{keys}\n", valid())
}

#[test]
fn pressure_keys_are_checked() {
    let top = "region = { min = [-0.01, 0.049], max = [0.11, 0.051] }";
    expect_rejected(
        "pressure_unknown_body",
        &with_pressure(&format!("body = \"blok\"\n{top}\nvalue = 1.0e6")),
        &["pressure[0].body", "\"blok\"", "no body of that name"],
    );
    expect_rejected(
        "pressure_no_edge",
        &with_pressure(
            "body = \"block\"\nregion = { min = [5.0, 5.0], max = [6.0, 6.0] }\nvalue = 1.0e6",
        ),
        &["pressure[0].region", "min = [5.0, 5.0]", "no boundary edge"],
    );
    // One boundary node only (the corner): no edge has both its nodes in the box.
    expect_rejected(
        "pressure_one_node",
        &with_pressure(
            "body = \"block\"\nregion = { min = [-0.001, -0.001], max = [0.001, 0.001] }\nvalue = 1.0e6",
        ),
        &["pressure[0].region", "no boundary edge"],
    );
    // Interior edges (the middle row of nodes) are not loaded.
    expect_rejected(
        "pressure_interior_edges",
        &with_pressure(
            "body = \"block\"\nregion = { min = [0.02, 0.024], max = [0.08, 0.026] }\nvalue = 1.0e6",
        ),
        &["pressure[0].region", "no boundary edge"],
    );
    expect_rejected(
        "pressure_inverted_box",
        &with_pressure(
            "body = \"block\"\nregion = { min = [0.2, 0.0], max = [0.1, 0.05] }\nvalue = 1.0e6",
        ),
        &["pressure[0].region", "min must not exceed max"],
    );
    expect_rejected(
        "pressure_nan_value",
        &with_pressure(&format!("body = \"block\"\n{top}\nvalue = nan")),
        &["pressure[0].value", "NaN", "finite"],
    );
    expect_rejected(
        "pressure_zero_ramp",
        &with_pressure(&format!(
            "body = \"block\"\n{top}\nvalue = 1.0e6\nramp = 0.0"
        )),
        &["pressure[0].ramp", "0.0", "positive"],
    );
    expect_rejected(
        "pressure_negative_ramp",
        &with_pressure(&format!(
            "body = \"block\"\n{top}\nvalue = 1.0e6\nramp = -1.0e-3"
        )),
        &["pressure[0].ramp", "-0.001", "positive"],
    );
    expect_rejected(
        "pressure_missing_value",
        &with_pressure(&format!("body = \"block\"\n{top}")),
        &["value"],
    );
    expect_rejected(
        "pressure_unknown_key",
        &with_pressure(&format!(
            "body = \"block\"\n{top}\nvalue = 1.0e6\nfollower = true"
        )),
        &["follower"],
    );
}

#[test]
fn mass_damping_is_checked() {
    expect_rejected(
        "mass_damping_negative",
        &variant(
            "end_time = 1.0e-5\n",
            "end_time = 1.0e-5\nmass_damping = -1.0\n",
        ),
        &["run.mass_damping", "-1.0", ">= 0"],
    );
    expect_rejected(
        "mass_damping_infinite",
        &variant(
            "end_time = 1.0e-5\n",
            "end_time = 1.0e-5\nmass_damping = inf\n",
        ),
        &["run.mass_damping", "inf", ">= 0"],
    );
}

/// `ricochet run SCENE --backend cpu --out OUT`, killed (and the test failed) after `limit`.
fn run_cpu_within(scene: &std::path::Path, out: &std::path::Path, limit: Duration) -> Output {
    use std::process::{Command, Stdio};
    let mut child = Command::new(bin())
        .args(["run", scene.to_str().unwrap(), "--backend", "cpu", "--out"])
        .arg(out)
        .env_remove("RUST_BACKTRACE")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cannot start the ricochet binary");
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "`ricochet run {}` still running after {limit:?}",
                scene.display()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn a_first_step_far_beyond_the_end_time_ends_the_run_at_once() {
    // Found by the fuzz test. A density of 1e300 makes the stable step about 1e141 s: the first
    // step passes end_time, and the clock walked the 1e147 history (and snapshot) times that
    // step passed one by one: the run never ended.
    let text = variant("density = 7850.0", "density = 1e300")
        .replace(
            "cells = [4, 2] } }\n",
            "cells = [4, 2] } }\nhourglass = { form = \"stiffness\" }\n",
        )
        .replace(
            "end_time = 1.0e-5\n",
            "end_time = 1.0e-5\nhistory_interval = 1.0e-6\nfield_interval = 1.0e-6\n\
         bulk_viscosity = { linear = 0.0, quadratic = 0.0 }\n",
        );
    let (dir, file) = write_scene("huge_first_step", &text);
    let out = dir.join("out");
    let o = run_cpu_within(&file, &out, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed", "{summary}");
    assert_eq!(summary["steps"], 1, "{summary}");
    assert_eq!(summary["history_rows"], 2, "{summary}");
    assert_eq!(summary["snapshots"], 2, "{summary}");
    let _ = std::fs::remove_dir_all(&dir);

    // The clock's jump finds the index a walk finds.
    use ricochet::step::{Clock, Schedule, TIME_SLACK};
    for (t, dt, interval) in [
        (0.0, 0.0, 1e-6),
        (1e-6, 1e-6, 1e-6),
        (3.3e-6, 4.35e-6, 1e-7),
        (7.0e-4, 1.1e-7, 1e-5),
        (1.0, 0.25, 0.1),
        (5e-3, 5e-3, 1e-9),
    ] {
        let s = Schedule {
            end_time: 1e9,
            history_interval: interval,
            field_interval: Some(interval),
            time_step_scale: 0.9,
            time_step: None,
        };
        for from in [0, 3] {
            let mut walk = from;
            while t + TIME_SLACK * dt >= walk as f64 * interval {
                walk += 1;
            }
            let mut c = Clock {
                next_sample: from,
                next_snapshot: from,
            };
            c.took_sample(&s, t, dt);
            c.took_snapshot(&s, t, dt);
            assert_eq!(
                c.next_sample, walk,
                "t {t:e}, dt {dt:e}, interval {interval:e}"
            );
            assert_eq!(c.next_snapshot, walk);
        }
    }
    // Beyond u64: saturates.
    let s = Schedule {
        end_time: 1e-5,
        history_interval: 1e-6,
        field_interval: None,
        time_step_scale: 0.9,
        time_step: None,
    };
    let mut c = Clock::new();
    c.took_sample(&s, 3.5e141, 3.5e141);
    assert_eq!(c.next_sample, u64::MAX);
}

#[test]
fn parse_errors_quote_a_window_of_a_long_line() {
    // Found by the fuzz test. The nodes of an explicit mesh on one line (as in
    // assets/ring_crush.toml, 16 KB) with a typo far into it: the parser's message quoted the
    // whole line, and its caret line had as many spaces as the column.
    let nodes: Vec<String> = (0..2000).map(|i| format!("[{i}.0, 0.0]")).collect();
    let line = nodes.join(", ").replace("[1000.0, 0.0]", "[1000.0, 0.0x]");
    let text = format!(
        "{}\n[[body]]\nname = \"mesh\"\nmaterial = \"steel\"\nmesh = {{ nodes = [{line}], quads = [[0, 1, 2, 3]] }}\n",
        valid()
    );
    let line_no = text.lines().position(|l| l.contains("nodes = ")).unwrap() + 1;
    let err = expect_rejected(
        "long_line",
        &text,
        &[
            &format!("TOML parse error at line {line_no}, column "),
            "0.0x]",
            "^",
        ],
    );
    assert!(err.len() < 1000, "message of {} bytes:\n{err}", err.len());
}

#[test]
fn long_values_are_cut_in_messages() {
    // Found by the fuzz test. A rejected string value was quoted whole: a `model` of 100 000
    // characters gave a message of 100 KB.
    let long = "x".repeat(100_000);
    let err = expect_rejected(
        "long_model",
        &variant("model = \"linear_elastic\"", &format!("model = \"{long}\"")),
        &[
            "material[0].model",
            "\"xxxx",
            "100002 characters in all",
            "unknown model",
        ],
    );
    assert!(err.len() < 1000, "message of {} bytes", err.len());
}

#[test]
fn bulk_viscosity_quadratic_is_bounded() {
    // Found by the fuzz test. A quadratic coefficient of 9.2e18 was accepted: the step it allows
    // in compression (even at the round-off strain rates of rigid motion) fell 350-fold after
    // t = 0, where the first-step limits do not look, and a run to 1 ms took hours.
    expect_rejected(
        "bulk_quadratic_huge",
        &variant(
            "end_time = 1.0e-5\n",
            "end_time = 1.0e-5\nbulk_viscosity = { quadratic = 9223372036854775807 }\n",
        ),
        &[
            "run.bulk_viscosity.quadratic",
            "9.223372036854776e18",
            "must not exceed 10",
        ],
    );
    let text = variant(
        "end_time = 1.0e-5\n",
        "end_time = 1.0e-5\nbulk_viscosity = { quadratic = 10.0 }\n",
    );
    expect_accepted("bulk_quadratic_10", &text, true);
}

/// A scene whose body `part` is group `group` of the mesh file `mesh` (absolute path).
fn gmsh_scene(mesh: &std::path::Path, group: &str) -> String {
    format!(
        "{RUN}{MATERIAL}\n[[body]]\nname = \"part\"\nmaterial = \"steel\"\n\
         mesh = {{ gmsh = {:?}, group = {group:?} }}\n",
        mesh.to_string_lossy()
    )
}

#[test]
fn bad_gmsh_meshes_name_the_file_the_group_and_the_problem() {
    use crate::gmsh::{edit_quads, test_mesh};
    let square = test_mesh("square.msh");
    expect_accepted("gmsh_ok", &gmsh_scene(&square, "square"), true);
    let key = "body[0].mesh.gmsh";
    let missing = test_mesh("no_such_file.msh");
    expect_rejected(
        "gmsh_missing_file",
        &gmsh_scene(&missing, "square"),
        &[key, "no_such_file.msh", "cannot read the mesh file"],
    );
    expect_rejected(
        "gmsh_msh2",
        &gmsh_scene(&test_mesh("square_v22.msh"), "square"),
        &[key, "square_v22.msh", "MSH format version 2.2", "4.1"],
    );
    expect_rejected(
        "gmsh_no_group",
        &gmsh_scene(&square, "bracket"),
        &[
            key,
            "square.msh",
            "no physical surface named `bracket`",
            "square",
        ],
    );
    expect_rejected(
        "gmsh_curve_group",
        &gmsh_scene(&square, "left"),
        &[key, "group `left` is a physical curve, not a surface"],
    );
    expect_rejected(
        "gmsh_point_group",
        &gmsh_scene(&square, "corner"),
        &[key, "group `corner` is a physical point"],
    );
    expect_rejected(
        "gmsh_second_order",
        &gmsh_scene(&test_mesh("square_order2.msh"), "square"),
        &[
            key,
            "square_order2.msh",
            "group `square`",
            "64 x Qua9 (Gmsh type 10)",
        ],
    );
    // Triangles are read (as collapsed quads), alone or among quads.
    expect_accepted(
        "gmsh_triangles",
        &gmsh_scene(&test_mesh("square_triangles.msh"), "square"),
        true,
    );
    expect_accepted(
        "gmsh_mixed",
        &gmsh_scene(&test_mesh("mixed.msh"), "square"),
        true,
    );
    // An inverted (bow-tie) element: the first quad's second and third nodes swapped.
    let text = std::fs::read_to_string(&square).expect("square.msh");
    let mut first = true;
    let bowtie = edit_quads(&text, |n| {
        let out = if first {
            vec![n[0], n[2], n[1], n[3]]
        } else {
            n.to_vec()
        };
        first = false;
        out.iter().map(|s| s.to_string()).collect()
    });
    let dir = tmp_dir("bad-gmsh-inverted-mesh");
    let inverted = dir.join("inverted.msh");
    std::fs::write(&inverted, bowtie).expect("write");
    let err = expect_rejected(
        "gmsh_inverted",
        &gmsh_scene(&inverted, "square"),
        &[
            key,
            "inverted.msh",
            "element",
            "is inverted or has zero area",
        ],
    );
    // It names the Gmsh tag and the nodes of the first quad as the file gives them.
    let line = text
        .lines()
        .skip_while(|l| l.trim() != "2 1 3 64")
        .nth(1)
        .expect("first quad");
    let t: Vec<&str> = line.split_whitespace().collect();
    let named = format!(
        "element {} of group `square` (nodes {} {} {} {})",
        t[0], t[1], t[3], t[2], t[4]
    );
    assert!(err.contains(&named), "{err}\ndoes not contain {named}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_regions_by_group_name_the_key_and_the_group() {
    use crate::gmsh::test_mesh;
    let square = gmsh_scene(&test_mesh("square.msh"), "square");
    let table = |t: &str, region: &str, rest: &str| {
        format!("{square}\n[[{t}]]\nbody = \"part\"\nregion = {region}\n{rest}\n")
    };
    let v = "velocity = { y = 0.0 }";
    expect_rejected(
        "group_missing",
        &table("boundary", "{ group = \"clamp\" }", v),
        &[
            "boundary[0].region.group",
            "\"clamp\"",
            "no physical curve or point of that name",
            "bottom",
        ],
    );
    expect_rejected(
        "group_and_box",
        &table(
            "boundary",
            "{ group = \"left\", min = [0.0, 0.0], max = [1.0, 1.0] }",
            v,
        ),
        &["boundary[0].region", "either `group` or `min` and `max`"],
    );
    expect_rejected(
        "region_empty",
        &table("boundary", "{}", v),
        &[
            "boundary[0].region",
            "give `min = [x, y]` and `max = [x, y]`",
        ],
    );
    expect_rejected(
        "pressure_on_a_point",
        &table("pressure", "{ group = \"corner\" }", "value = 1.0e6"),
        &[
            "pressure[0].region.group",
            "is a physical point; a pressure needs a physical curve",
        ],
    );
    expect_rejected(
        "group_on_a_generated_body",
        &format!(
            "{}\n[[boundary]]\nbody = \"block\"\nregion = {{ group = \"left\" }}\n{v}\n",
            valid()
        ),
        &["boundary[0].region.group", "is not read from a Gmsh file"],
    );
}

#[test]
fn bad_load_curves_name_the_key_and_the_point() {
    let boundary = |v: &str| {
        format!(
            "{}\n[[boundary]]\nbody = \"block\"\nregion = {{ min = [-0.01, -0.01], max = [0.01, 0.06] }}\nvelocity = {{ x = {v} }}\n",
            valid()
        )
    };
    expect_rejected(
        "curve_decreasing",
        &boundary("[[0.0, 0.0], [1.0e-4, 1.0], [5.0e-5, 2.0]]"),
        &["boundary[0].velocity.x[2]", "times must increase"],
    );
    expect_rejected(
        "curve_negative_time",
        &boundary("[[-1.0e-4, 0.0], [1.0e-4, 1.0]]"),
        &["boundary[0].velocity.x[0]", "the time at least 0"],
    );
    expect_rejected(
        "curve_three_numbers",
        &boundary("[[0.0, 0.0, 1.0]]"),
        &["boundary[0].velocity.x[0]", "each point is [time, value]"],
    );
    expect_rejected(
        "curve_empty",
        &boundary("[]"),
        &["boundary[0].velocity.x", "needs 1 to 100000"],
    );
    expect_rejected(
        "curve_not_finite",
        &boundary("[[0.0, 0.0], [1.0e-4, nan]]"),
        &["boundary[0].velocity.x"],
    );
    let pressure = format!(
        "{}\n[[pressure]]\nbody = \"block\"\nregion = {{ min = [-0.01, 0.049], max = [0.11, 0.051] }}\nvalue = [[0.0, 0.0], [1.0e-5, 1.0e6]]\nramp = 1.0e-5\n",
        valid()
    );
    expect_rejected(
        "curve_with_ramp",
        &pressure,
        &["pressure[0].ramp", "a load curve"],
    );
    expect_accepted("curve_ok", &boundary("[[0.0, 0.0], [1.0e-6, 1.0]]"), true);
}

#[test]
fn bad_contact_surfaces_name_the_key_and_the_curve() {
    let plate =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/gmsh/notched_plate.msh");
    let scene = |surfaces: &str| {
        format!(
            "{RUN}{MATERIAL}\n[[body]]\nname = \"plate\"\nmaterial = \"steel\"\n\
             mesh = {{ gmsh = {p:?}, group = \"plate\" }}\n\
             [[body]]\nname = \"striker\"\nmaterial = \"steel\"\n\
             mesh = {{ gmsh = {p:?}, group = \"striker\" }}\n\
             [[contact]]\nbodies = [\"striker\", \"plate\"]\nmethod = \"lagrange\"\nsurfaces = {surfaces}\n",
            p = plate.to_string_lossy()
        )
    };
    expect_rejected(
        "surfaces_unknown",
        &scene("[\"striker_face\", \"top\"]"),
        &[
            "contact[0].surfaces[1]",
            "\"top\"",
            "no physical curve of that name",
            "plate_top",
        ],
    );
    expect_rejected(
        "surfaces_one",
        &scene("[\"striker_face\"]"),
        &["contact[0].surfaces", "one physical curve per body"],
    );
    expect_rejected(
        "surfaces_wrong_body",
        &scene("[\"plate_top\", \"striker_face\"]"),
        &[
            "contact[0].surfaces[0]",
            "\"plate_top\"",
            "on body \"striker\"",
        ],
    );
    expect_rejected(
        "surfaces_on_a_generated_body",
        &format!(
            "{}\n[[body]]\nname = \"other\"\nmaterial = \"steel\"\n\
             mesh = {{ rectangle = {{ origin = [0.0, 0.1], size = [0.1, 0.05], cells = [4, 2] }} }}\n\
             [[contact]]\nbodies = [\"block\", \"other\"]\nsurfaces = [\"a\", \"b\"]\n",
            valid()
        ),
        &["contact[0].surfaces[0]", "is not read from a Gmsh file"],
    );
}

#[test]
fn a_node_at_1e300_in_an_explicit_mesh_is_refused_at_once() {
    // Found by the fuzz test (case 791 once assets were added): the overlap check's grid keys
    // saturated and the cell count of the far quad overflowed, and `check` looped for minutes.
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/stress/corner_to_corner.toml"),
    )
    .expect("corner_to_corner.toml");
    let node = "[7.0710678119e-03, 7.0710678119e-03]";
    assert!(base.contains(node));
    let text = base.replacen(node, "[7.0710678119e-03, -1e300]", 1);
    let t0 = Instant::now();
    expect_rejected("node_at_1e300", &text, &["body[0].mesh", "non-convex"]);
    assert!(
        t0.elapsed() < Duration::from_secs(20),
        "took {:?}",
        t0.elapsed()
    );
}

/// The `failure` table of a material: every bad value exits 2 naming the key and the value.
/// Johnson-Cook thermal softening (`m`, `melt_temperature`, `room_temperature` in the table) and
/// adiabatic heating (`specific_heat`, `taylor_quinney` beside it).
fn bad_thermal_keys() {
    let jc = |thermal: &str, keys: &str| {
        plastic(&format!(
            "johnson_cook = {{ a = 9.0e7, b = 2.92e8, n = 0.31, c = 0.025, reference_strain_rate = 1.0{thermal} }}\n{keys}"
        ))
    };
    let full = ", m = 1.09, melt_temperature = 1356.0, room_temperature = 293.0";
    expect_accepted(
        "thermal_ok",
        &jc(full, "specific_heat = 383.0\ntaylor_quinney = 0.9"),
        true,
    );
    expect_accepted(
        "thermal_default_beta_ok",
        &jc(full, "specific_heat = 383.0"),
        false,
    );
    let cases: [(&str, String, &[&str]); 11] = [
        (
            "thermal_zero_m",
            jc(
                ", m = 0.0, melt_temperature = 1356.0, room_temperature = 293.0",
                "specific_heat = 383.0",
            ),
            &["material[0].johnson_cook.m", "0.0"],
        ),
        (
            "thermal_negative_m",
            jc(
                ", m = -1.0, melt_temperature = 1356.0, room_temperature = 293.0",
                "specific_heat = 383.0",
            ),
            &["material[0].johnson_cook.m", "-1.0"],
        ),
        (
            "thermal_melt_below_room",
            jc(
                ", m = 1.09, melt_temperature = 250.0, room_temperature = 293.0",
                "specific_heat = 383.0",
            ),
            &[
                "material[0].johnson_cook.melt_temperature",
                "250.0",
                "room_temperature",
            ],
        ),
        (
            "thermal_melt_at_room",
            jc(
                ", m = 1.09, melt_temperature = 293.0, room_temperature = 293.0",
                "specific_heat = 383.0",
            ),
            &["material[0].johnson_cook.melt_temperature", "293.0"],
        ),
        (
            "thermal_m_alone",
            jc(", m = 1.09", "specific_heat = 383.0"),
            &["material[0].johnson_cook.melt_temperature", "missing"],
        ),
        (
            "thermal_no_specific_heat",
            jc(full, ""),
            &["material[0].specific_heat", "missing"],
        ),
        (
            "thermal_zero_specific_heat",
            jc(full, "specific_heat = 0.0"),
            &["material[0].specific_heat", "0.0"],
        ),
        (
            "thermal_beta_above_one",
            jc(full, "specific_heat = 383.0\ntaylor_quinney = 1.5"),
            &["material[0].taylor_quinney", "1.5"],
        ),
        (
            "thermal_beta_negative",
            jc(full, "specific_heat = 383.0\ntaylor_quinney = -0.1"),
            &["material[0].taylor_quinney", "-0.1"],
        ),
        (
            "heating_without_thermal_softening",
            jc("", "specific_heat = 383.0"),
            &["material[0].specific_heat", "383.0", "m, melt_temperature"],
        ),
        (
            "heating_without_johnson_cook",
            plastic("yield_stress = 2.5e8\ntaylor_quinney = 0.9"),
            &["material[0].taylor_quinney", "0.9", "johnson_cook"],
        ),
    ];
    for (case, text, needles) in &cases {
        expect_rejected(case, text, needles);
    }
    expect_rejected(
        "heating_on_an_elastic_material",
        &variant(
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.3\nspecific_heat = 383.0",
        ),
        &["material[0].specific_heat", "j2_plastic"],
    );
}

#[test]
fn bad_erosion_options_name_the_key_and_value() {
    let with = |erosion: &str| {
        variant(
            "end_time = 1.0e-5",
            &format!("end_time = 1.0e-5\n{erosion}"),
        )
    };
    expect_accepted(
        "erosion_inverted_ok",
        &with("erosion = { inverted = true }"),
        true,
    );
    expect_accepted(
        "erosion_inverted_off_ok",
        &with("erosion = { inverted = false }"),
        false,
    );
    expect_rejected(
        "erosion_not_a_table",
        &with("erosion = true"),
        &["run.erosion", "true"],
    );
    expect_rejected(
        "erosion_empty",
        &with("erosion = {}"),
        &["run.erosion", "{}"],
    );
    expect_rejected(
        "erosion_inverted_not_a_boolean",
        &with("erosion = { inverted = 1 }"),
        &["run.erosion.inverted", "1", "true or false"],
    );
    expect_rejected(
        "erosion_unknown_key",
        &with("erosion = { inverted = true, dt_min = 1.0e-9 }"),
        &["run.erosion.dt_min", "unknown key"],
    );
    expect_accepted(
        "erosion_min_time_step_ok",
        &with("erosion = { inverted = true, min_time_step = 1.0e-9 }"),
        true,
    );
    expect_rejected(
        "erosion_min_time_step_negative",
        &with("erosion = { min_time_step = -1.0e-9 }"),
        &["run.erosion.min_time_step", "-1e-9"],
    );
    expect_rejected(
        "erosion_min_time_step_not_a_number",
        &with("erosion = { min_time_step = \"small\" }"),
        &["run.erosion.min_time_step", "small", "seconds"],
    );
}

fn bad_failure_keys() {
    let yielding = |failure: &str| plastic(&format!("yield_stress = 2.5e8\nfailure = {failure}"));
    let jc = "johnson_cook = { d1 = 0.54, d2 = 4.89, d3 = -3.03, d4 = 0.014, d5 = 1.12 }";
    expect_accepted(
        "failure_ok",
        &yielding(&format!(
            "{{ plastic_strain = 0.8, {jc}, principal_strain = 0.5, tensile_pressure = 1.0e9 }}"
        )),
        true,
    );
    expect_accepted(
        "failure_elastic_principal_ok",
        &variant(
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.3\nfailure = { principal_strain = 0.2, tensile_pressure = 1.0e9 }",
        ),
        false,
    );
    let cases: [(&str, String, &[&str]); 10] = [
        (
            "failure_not_a_table",
            yielding("0.8"),
            &["material[0].failure", "0.8"],
        ),
        (
            "failure_empty",
            yielding("{}"),
            &["material[0].failure", "{}"],
        ),
        (
            "failure_unknown_key",
            yielding("{ plastic_strian = 0.8 }"),
            &["material[0].failure.plastic_strian", "unknown key"],
        ),
        (
            "failure_negative_plastic_strain",
            yielding("{ plastic_strain = -0.8 }"),
            &["material[0].failure.plastic_strain", "-0.8"],
        ),
        (
            "failure_elastic_plastic_strain",
            variant(
                "poisson_ratio = 0.3",
                "poisson_ratio = 0.3\nfailure = { plastic_strain = 0.8 }",
            ),
            &["material[0].failure.plastic_strain", "j2_plastic"],
        ),
        (
            "failure_jc_missing_key",
            yielding("{ johnson_cook = { d1 = 0.54, d2 = 4.89, d3 = -3.03, d4 = 0.014 } }"),
            &["material[0].failure.johnson_cook.d5", "missing"],
        ),
        (
            "failure_jc_nan",
            yielding(
                "{ johnson_cook = { d1 = 0.54, d2 = 4.89, d3 = nan, d4 = 0.014, d5 = 1.12 } }",
            ),
            &["material[0].failure.johnson_cook.d3", "NaN"],
        ),
        (
            "failure_jc_negative_reference_strain",
            yielding(
                "{ johnson_cook = { d1 = -2.0, d2 = 1.0, d3 = -3.03, d4 = 0.014, d5 = 1.12 } }",
            ),
            &["material[0].failure.johnson_cook.d1", "-2.0", "d1 + d2"],
        ),
        (
            "failure_zero_tensile_pressure",
            yielding("{ tensile_pressure = 0.0 }"),
            &["material[0].failure.tensile_pressure", "0.0"],
        ),
        (
            "failure_principal_strain_string",
            yielding("{ principal_strain = \"big\" }"),
            &[
                "material[0].failure.principal_strain",
                "\"big\"",
                "expected a number",
            ],
        ),
    ];
    for (case, text, needles) in cases {
        expect_rejected(case, &text, needles);
    }
}
