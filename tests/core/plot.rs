//! `ricochet plot` and `run --plots`: the pictures of a run from its output folder. Every file
//! exists at its stated size, the same run plotted twice gives the same bytes, a GIF has one frame
//! per chosen snapshot, the colours of a uniform field are the colour map's value of the exact
//! stress (contact patch test), the window frames the cells drawn (not the free nodes of eroded
//! ones), and folders that are not a run's output, or fields a run did not write, are refused
//! with exit status 2.

use std::fs::File;
use std::path::{Path, PathBuf};

use ricochet::plot::field::Field;
use ricochet::plot::read::vtu;
use ricochet::plot::{charts, field, plot, PlotOptions};

use crate::common::*;

use crate::erosion_contact::perforation::stretched_block;
use crate::patch_contact::patch_scene;

/// Decodes a PNG: (width, height, RGB bytes).
fn png_rgb(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("PNG header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("PNG data");
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Frames of a GIF.
fn gif_frames(path: &Path) -> (u16, u16, usize) {
    let file = File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut dec = opts.read_info(file).expect("GIF header");
    let (w, h) = (dec.width(), dec.height());
    let mut n = 0;
    while dec.read_next_frame().expect("GIF frame").is_some() {
        n += 1;
    }
    (w, h, n)
}

fn run_scene(scene: &str, out: &Path, extra: &[&str]) {
    let o = run_cpu(Path::new(scene), out, extra);
    assert!(
        o.status.success(),
        "ricochet run {scene}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn snapshots_written(out: &Path) -> usize {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("summary JSON");
    v["snapshots"].as_u64().expect("snapshots") as usize
}

fn assert_size(path: &Path, size: (u32, u32)) {
    let (w, h, rgb) = png_rgb(path);
    assert_eq!((w, h), size, "{}", path.display());
    // Not blank: more than the white background and the text.
    let distinct: std::collections::BTreeSet<&[u8]> = rgb.chunks_exact(3).collect();
    assert!(
        distinct.len() > 8,
        "{}: {} colours",
        path.display(),
        distinct.len()
    );
}

#[test]
fn run_plots_draws_every_picture_of_the_vibrating_block() {
    let out = tmp_dir("plot-block");
    run_scene("assets/vibrating_block.toml", &out, &["--plots"]);
    let plots = out.join("plots");
    assert_size(&plots.join("energies.png"), charts::SIZE);
    assert_size(&plots.join("velocities.png"), charts::SIZE);
    assert!(
        !plots.join("contact_forces.png").exists(),
        "no contact, no contact force chart"
    );
    let snapshots = snapshots_written(&out);
    let chosen = snapshots.min(ricochet::plot::DEFAULT_SNAPSHOTS);
    assert!(snapshots >= 2);
    let pictures: Vec<PathBuf> = (0..snapshots)
        .map(|k| plots.join(format!("field_von_mises_{k:05}.png")))
        .filter(|p| p.exists())
        .collect();
    assert_eq!(pictures.len(), chosen, "default: every snapshot up to 12");
    for p in &pictures {
        assert_size(p, field::SIZE);
    }
    // The animation, through the library: one frame per chosen snapshot.
    let report = plot(
        &out,
        &PlotOptions {
            field: Some(Field::Velocity),
            animate: true,
            ..PlotOptions::default()
        },
    )
    .expect("plot");
    let gif = plots.join("field_velocity.gif");
    let (w, h, frames) = gif_frames(&gif);
    assert_eq!((w as u32, h as u32), field::SIZE);
    assert_eq!(frames, report.pictures.len());
    assert_eq!(frames, report.gif_frames);
    assert_eq!(frames, chosen);
    // SVG: the same pictures as vector files of the stated size.
    plot(
        &out,
        &PlotOptions {
            format: ricochet::plot::Format::Svg,
            ..PlotOptions::default()
        },
    )
    .expect("plot svg");
    for name in [
        "energies.svg",
        "velocities.svg",
        "field_von_mises_00000.svg",
    ] {
        let text = std::fs::read_to_string(plots.join(name)).expect(name);
        let (w, h) = if name.starts_with("field") {
            field::SIZE
        } else {
            charts::SIZE
        };
        assert!(
            text.starts_with(&format!("<svg width=\"{w}\" height=\"{h}\"")),
            "{name}: {:.80}",
            text
        );
    }
}

#[test]
fn disk_on_wall_plots_are_identical_twice_and_follow_the_chosen_times() {
    let out = tmp_dir("plot-disk");
    run_scene("assets/disk_wall.toml", &out, &[]);
    let args = |o: &Path| {
        vec![
            "plot".to_string(),
            o.to_string_lossy().to_string(),
            "--times".into(),
            "0".into(),
            "8e-5".into(),
            "1.6e-4".into(),
            "--animate".into(),
        ]
    };
    let a: Vec<String> = args(&out);
    let o = run_bin(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let plots = out.join("plots");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&plots)
        .expect("plots folder")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    let names: Vec<String> = files
        .iter()
        .map(|f| f.file_name().expect("name").to_string_lossy().to_string())
        .collect();
    // 9 snapshots (every 20 us to 160 us): the nearest to 0, 80 and 160 us.
    assert_eq!(
        names,
        [
            "contact_forces.png",
            "energies.png",
            "field_von_mises.gif",
            "field_von_mises_00000.png",
            "field_von_mises_00004.png",
            "field_von_mises_00008.png",
            "velocities.png"
        ]
    );
    assert_size(&plots.join("contact_forces.png"), charts::SIZE);
    for k in [0, 4, 8] {
        assert_size(
            &plots.join(format!("field_von_mises_{k:05}.png")),
            field::SIZE,
        );
    }
    assert_eq!(gif_frames(&plots.join("field_von_mises.gif")).2, 3);
    let first: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(f).expect("read"))
        .collect();
    let o = run_bin(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success());
    for (f, bytes) in files.iter().zip(&first) {
        assert!(
            &std::fs::read(f).expect("read") == bytes,
            "{}: different bytes on the second plot",
            f.display()
        );
    }
}

/// Runs `text` on the CPU reference to the end, its outputs in a fresh folder named after
/// `name`: the folder, the run's result and the solver at the end.
fn run_on_cpu(
    text: &str,
    name: &str,
) -> (
    std::path::PathBuf,
    ricochet::run::RunResult,
    ricochet::step::cpu::CpuSolver,
) {
    let (scene, model, plan) = build(text);
    let out = tmp_dir(name);
    let mut solver = ricochet::step::cpu::CpuSolver::new(
        model.clone(),
        plan.clone(),
        ricochet::run::schedule(&scene),
    );
    let r = ricochet::run::run(&scene, &model, &plan, &mut solver, &out, None).expect("run");
    assert_eq!(r.summary.status, "completed");
    (out, r, solver)
}

#[test]
fn uniform_stress_of_the_contact_patch_test_is_drawn_in_its_colour() {
    // Two-pass Lagrange settles to sigma_yy = -p, sigma_xx = sigma_xy = 0 in every element
    // (tests/core/patch_contact.rs, error below 1e-4 p), so sigma_zz = -nu p in plane strain and
    // the pressure -(s_xx + s_yy + s_zz) / 3 = (1 + nu) p / 3 everywhere.
    let text = patch_scene::scene(4, 3, "upper", "method = \"lagrange\"\ntwo_pass = true").replace(
        "history_interval = 1.0e-3",
        "history_interval = 1.0e-3\nfield_interval = 1.0e-3",
    );
    let (out, r, _) = run_on_cpu(&text, "plot-patch");
    let report = plot(
        &out,
        &PlotOptions {
            field: Some(Field::Pressure),
            ..PlotOptions::default()
        },
    )
    .expect("plot");
    let (lo, hi) = report.range.expect("range");
    let window = report.window.expect("window");
    let last = report.pictures.last().expect("pictures");
    assert_eq!(
        last.snapshot,
        r.summary.snapshots - 1,
        "the final snapshot is drawn"
    );
    let exact = (1.0 + 0.3) * patch_scene::P / 3.0;
    assert!(lo < exact && exact < hi, "[{lo}, {hi}] around {exact}");
    let want = ricochet::plot::style::colour(exact, lo, hi);
    // The check tells values 2 % apart.
    assert_ne!(ricochet::plot::style::colour(0.98 * exact, lo, hi), want);
    let (w, _, rgb) = png_rgb(&last.path);
    let snaps = ricochet::plot::read::snapshots(&out).expect("fields.pvd");
    let mut checked = 0;
    for (_, file) in &snaps.last().expect("snapshot").parts {
        let piece = vtu(file).expect("VTU");
        let values = Field::Pressure.values(&piece);
        for (c, value) in values.iter().enumerate() {
            let cell = piece.cell(c);
            let n = cell.len() as f64;
            let (cx, cy) = cell.iter().fold((0.0, 0.0), |(x, y), &i| {
                let p = piece.points[i as usize];
                (x + p[0] / n, y + p[1] / n)
            });
            let (px, py) = window.pixel(cx, cy);
            let at = 3 * (py as usize * w as usize + px as usize);
            let got = [rgb[at], rgb[at + 1], rgb[at + 2]];
            assert!(
                ((value - exact) / patch_scene::P).abs() < 1e-4,
                "element {c}: pressure {value} against {exact}"
            );
            assert_eq!(
                got, want,
                "element {c} at pixel ({px}, {py}): pressure {value} drawn as {got:?}, the colour \
                 map gives {want:?} for the exact {exact} on [{lo}, {hi}]"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 7 * 2, "4 + 3 elements along x, two layers");
}

#[test]
fn plastic_strain_draws_a_body_whose_material_does_not_write_it_in_grey() {
    // The plate perforation's first microsecond: a plastic plate and an elastic projectile,
    // whose cells have no plastic_strain (the plot once indexed past their empty values).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("assets/plate_perforation.toml"))
        .expect("asset")
        .replace("end_time = 4.0e-5", "end_time = 1.0e-6")
        .replace("field_interval = 5.0e-6", "field_interval = 5.0e-7");
    let dir = tmp_dir("plot-mixed");
    let scene = dir.join("mixed.toml");
    std::fs::write(&scene, text).expect("scene");
    let out = dir.join("out");
    run_scene(&scene.to_string_lossy(), &out, &[]);
    let o = run_bin(&["plot", &out.to_string_lossy(), "--field", "plastic_strain"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let last = out.join("plots/field_plastic_strain_00002.png");
    assert_size(&last, field::SIZE);
    // The projectile (10 x 20 mm of the picture's 60 x 24 mm) in the no-value grey.
    let (_, _, rgb) = png_rgb(&last);
    let grey = rgb
        .chunks_exact(3)
        .filter(|p| *p == [200, 200, 200])
        .count();
    println!("{grey} grey pixels");
    assert!(grey > 10_000, "{grey} grey pixels");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_window_frames_the_cells_drawn_not_the_free_nodes_of_eroded_ones() {
    // A block stretched until every element erodes: its nodes fly on as free masses beside an
    // elastic witness block 80 mm away, the only cells left to draw at the end.
    let text = &stretched_block(
        3.0e-5,
        0.0,
        "field_interval = 1.0e-5\n",
        "",
        "[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\n\
         youngs_modulus = 2.0e11\npoisson_ratio = 0.3\n\n\
         [[body]]\nname = \"witness\"\nmaterial = \"steel\"\n\
         mesh = { rectangle = { origin = [0.1, 0.0], size = [0.01, 0.01], cells = [2, 2] } }\n",
    );
    let (out, _, solver) = run_on_cpu(text, "plot-free-nodes");
    assert!(solver.eroded()[..32].iter().all(|&e| e), "the block eroded");
    let report = plot(
        &out,
        &PlotOptions {
            times: vec![3.0e-5],
            ..PlotOptions::default()
        },
    )
    .expect("plot");
    let window = report.window.expect("window");
    // The witness's 10 mm and a border, not the block's free nodes at x <= 20 mm.
    println!("window x {:?}, y {:?}", window.x, window.y);
    assert!(window.x.0 > 0.09 && window.x.1 < 0.12, "{:?}", window.x);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn plot_refuses_folders_that_are_not_a_run_and_fields_it_did_not_write() {
    let empty = tmp_dir("plot-empty");
    let o = run_bin(&["plot", &empty.to_string_lossy()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("missing history.csv, summary.json, fields.pvd"),
        "{err}"
    );

    let out = tmp_dir("plot-fields");
    run_scene("assets/vibrating_block.toml", &out, &[]);
    let o = run_bin(&["plot", &out.to_string_lossy(), "--field", "plastic_strain"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("`--field` = plastic_strain")
            && err.contains("von_mises, pressure, velocity, displacement"),
        "{err}"
    );

    // History and summary but no fields.
    let no_fields = tmp_dir("plot-no-fields");
    for f in ["history.csv", "summary.json"] {
        std::fs::copy(out.join(f), no_fields.join(f)).expect("copy");
    }
    let o = run_bin(&["plot", &no_fields.to_string_lossy(), "--field", "von_mises"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("missing fields.pvd"), "{err}");
    // Without --field the history charts are still drawn, with a note.
    let o = run_bin(&["plot", &no_fields.to_string_lossy()]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no field pictures"));
    assert!(no_fields.join("plots/energies.png").exists());
}

#[test]
fn plot_reads_are_bounded_before_they_happen() {
    // An output file replaced by an endless stream (issue 40: every file the program reads is
    // read within a cap decided before the read): refused naming it, never read until memory
    // runs out.
    let out = tmp_dir("plot-streams");
    run_scene("assets/vibrating_block.toml", &out, &["--end-time", "4e-5"]);
    let mut vtus: Vec<String> = std::fs::read_dir(out.join("fields"))
        .expect("fields/")
        .map(|e| format!("fields/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    vtus.sort();
    for f in ["history.csv", vtus[0].as_str()] {
        let saved = std::fs::read(out.join(f)).expect("output file");
        std::fs::remove_file(out.join(f)).unwrap();
        std::os::unix::fs::symlink("/dev/zero", out.join(f)).unwrap();
        let (o, killed) = run_bin_bounded(&["plot", &out.to_string_lossy()], 60);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!killed, "plot read {f} without bound");
        assert_eq!(o.status.code(), Some(2), "{f}: {err}");
        // Named as missing (plot looks for regular files) or as not a regular file.
        assert!(
            err.contains(f) && (err.contains("not a regular file") || err.contains("missing")),
            "{err}"
        );
        std::fs::remove_file(out.join(f)).unwrap();
        std::fs::write(out.join(f), saved).unwrap();
    }
}
