//! `ricochet plot`: pictures of a run drawn from its own output folder, headless (plotters with an
//! embedded font; no display, no system fonts).
//!
//! Into `<out>/plots/`:
//! - `energies.png`: the energy columns of `history.csv` against time, the balance error on its own
//!   (right) axis;
//! - `contact_forces.png`: each contact's and wall's `fx`, `fy` against time (scenes with contact);
//! - `velocities.png`: each body's rigid-body velocity against time;
//! - `field_<name>_<k>.png` for each chosen snapshot `k` of `fields.pvd`: the deformed mesh of every
//!   body filled by the field (one value per element, viridis on one range for all the chosen
//!   snapshots), equal aspect, axes in metres;
//! - with `animate`, `field_<name>.gif`: those pictures as frames.
//!
//! The readers are in [`read`], the charts in [`charts`], the field pictures in [`field`]; a
//! study's figure against a parameter ([`xy_chart`]) in [`series`].

pub mod charts;
pub mod field;
pub mod read;
pub mod series;
pub mod style;

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::error::{Error, Result};
use field::{Field, Frame, Layer, Window};
use read::{History, Piece, SnapshotFiles};

/// Picture file format of the charts and field pictures (animations are always GIF).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// PNG (8-bit RGB).
    #[default]
    Png,
    /// SVG.
    Svg,
}

impl Format {
    fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }
}

/// Snapshots drawn when none are asked for: all of them up to this many, else this many evenly
/// spaced (first and last included).
pub const DEFAULT_SNAPSHOTS: usize = 12;

/// Delay between GIF frames (hundredths of a second).
pub const GIF_DELAY: u16 = 50;

/// What to draw.
#[derive(Debug, Clone, Default)]
pub struct PlotOptions {
    /// The field of the field pictures; `None`: von Mises stress, and no field pictures (only a
    /// note) when the run wrote no fields.
    pub field: Option<Field>,
    /// Snapshot times: for each, the snapshot nearest to it; empty: the default choice
    /// ([`DEFAULT_SNAPSHOTS`]).
    pub times: Vec<f64>,
    /// Colour range of the field pictures (lo < hi); `None`: the smallest and largest value over
    /// the chosen snapshots.
    pub range: Option<(f64, f64)>,
    /// Also write `field_<name>.gif`.
    pub animate: bool,
    /// Picture format.
    pub format: Format,
}

/// One field picture written.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// The file.
    pub path: PathBuf,
    /// Index of the snapshot in `fields.pvd`.
    pub snapshot: usize,
    /// Its time (s).
    pub time: f64,
}

/// What [`plot`] wrote.
#[derive(Debug, Clone, Default)]
pub struct PlotReport {
    /// `<out>/plots`.
    pub dir: PathBuf,
    /// Every file written, in order.
    pub files: Vec<PathBuf>,
    /// The field drawn (none without field pictures).
    pub field: Option<Field>,
    /// The colour range of the field pictures.
    pub range: Option<(f64, f64)>,
    /// Where the data lands in the field pictures.
    pub window: Option<Window>,
    /// The field pictures.
    pub pictures: Vec<Picture>,
    /// Frames of the GIF (0 without one).
    pub gif_frames: usize,
    /// Notes for the user (e.g. no fields to draw).
    pub notes: Vec<String>,
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Plot(format!("{}: {e}", path.display()))
}

/// The snapshot indices to draw out of `snaps`: the nearest to each of `times` (sorted, without
/// repeats), or the default choice.
///
/// # Errors
/// [`Error::Invalid`] for a time that is not finite.
pub fn choose(snaps: &[SnapshotFiles], times: &[f64], dir: &Path) -> Result<Vec<usize>> {
    let n = snaps.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let mut out: Vec<usize> = if times.is_empty() {
        if n <= DEFAULT_SNAPSHOTS {
            (0..n).collect()
        } else {
            (0..DEFAULT_SNAPSHOTS)
                .map(|k| ((k * (n - 1)) as f64 / (DEFAULT_SNAPSHOTS - 1) as f64).round() as usize)
                .collect()
        }
    } else {
        let mut v = Vec::with_capacity(times.len());
        for &t in times {
            if !t.is_finite() {
                return Err(Error::Invalid {
                    file: dir.to_path_buf(),
                    key: "--times".into(),
                    value: format!("{t}"),
                    reason: "must be a finite time in seconds".into(),
                });
            }
            let best = (0..n)
                .min_by(|&a, &b| {
                    (snaps[a].time - t)
                        .abs()
                        .total_cmp(&(snaps[b].time - t).abs())
                })
                .unwrap_or(0);
            v.push(best);
        }
        v
    };
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// Checks that `dir` is a run's output folder (it has `history.csv`).
///
/// # Errors
/// [`Error::Read`] when `dir` is not a folder; [`Error::Parse`] naming what is missing.
pub fn check_folder(dir: &Path) -> Result<()> {
    if !dir.is_dir() {
        return Err(Error::Read {
            file: dir.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "not a folder"),
        });
    }
    if !dir.join("history.csv").is_file() {
        let missing: Vec<&str> = ["history.csv", "summary.json", "fields.pvd"]
            .into_iter()
            .filter(|f| !dir.join(f).is_file())
            .collect();
        return Err(Error::Parse {
            file: dir.to_path_buf(),
            message: format!(
                "not the output folder of a run: missing {} (written by `ricochet run`)",
                missing.join(", ")
            ),
        });
    }
    Ok(())
}

/// The scene name and status of `summary.json` when there is one ("interrupted" when not).
fn run_label(dir: &Path) -> String {
    let text = crate::input::read_capped(&dir.join("summary.json"), 1 << 20)
        .ok()
        .and_then(|b| String::from_utf8(b).ok());
    let Some(text) = text else {
        return "no summary.json: interrupted run".into();
    };
    let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    let scene = v["scene"].as_str().unwrap_or("?");
    let status = v["status"].as_str().unwrap_or("?");
    format!("{scene}, {status}")
}

/// Encodes an RGB buffer of `size` as a PNG file.
/// Writes `rgb` (8-bit RGB rows of `size`) as a PNG file at `path` (also the verification
/// suite's plots: plotters draws into a buffer and this encodes it, so no image codec is built).
pub(crate) fn write_png(path: &Path, size: (u32, u32), rgb: &[u8]) -> Result<()> {
    let file = File::create(path).map_err(|source| Error::Write {
        path: path.to_path_buf(),
        source,
    })?;
    let mut enc = png::Encoder::new(BufWriter::new(file), size.0, size.1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| plot_error(path, e))?;
    w.write_image_data(rgb).map_err(|e| plot_error(path, e))?;
    w.finish().map_err(|e| plot_error(path, e))
}

/// Draws with `f` into an RGB buffer of `size` (white first).
pub(crate) fn raster(
    size: (u32, u32),
    path: &Path,
    f: impl FnOnce(
        &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    ) -> std::result::Result<(), String>,
) -> Result<Vec<u8>> {
    let mut buf = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        f(&root).map_err(|e| plot_error(path, e))?;
    }
    Ok(buf)
}

/// Draws `frame` as a PNG file at `path` ([`field::SIZE`]).
///
/// # Errors
/// [`Error::Write`] / [`Error::Plot`] when it cannot be drawn or written.
pub fn write_field_png(path: &Path, frame: &Frame<'_>) -> Result<()> {
    let rgb = raster(field::SIZE, path, |root| field::draw(root, frame))?;
    write_png(path, field::SIZE, &rgb)
}

/// Writes one chart in `format`.
fn chart(
    path: &Path,
    format: Format,
    title: &str,
    y_desc: &str,
    time: &[f64],
    lines: &[charts::Line],
    error: Option<&charts::Line>,
) -> Result<()> {
    match format {
        Format::Png => {
            let rgb = raster(charts::SIZE, path, |root| {
                charts::draw(root, title, y_desc, time, lines, error)
            })?;
            write_png(path, charts::SIZE, &rgb)
        }
        Format::Svg => {
            let root = SVGBackend::new(path, charts::SIZE).into_drawing_area();
            charts::draw(&root, title, y_desc, time, lines, error).map_err(|e| plot_error(path, e))
        }
    }
}

/// Draws `series` (y against x, one line per label) as one chart at `path` in `format`.
///
/// # Errors
/// [`Error::Write`] / [`Error::Plot`] when the chart cannot be drawn or written.
pub fn xy_chart(
    path: &Path,
    format: Format,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[series::Series],
) -> Result<()> {
    if !style::register_font() {
        return Err(Error::Plot("the embedded font is invalid".into()));
    }
    match format {
        Format::Png => {
            let rgb = raster(charts::SIZE, path, |root| {
                series::draw(root, title, x_desc, y_desc, series)
            })?;
            write_png(path, charts::SIZE, &rgb)
        }
        Format::Svg => {
            let root = SVGBackend::new(path, charts::SIZE).into_drawing_area();
            series::draw(&root, title, x_desc, y_desc, series).map_err(|e| plot_error(path, e))
        }
    }
}

/// Draws the pictures of the run in `dir` into `dir/plots/`.
///
/// # Errors
/// [`Error::Read`] / [`Error::Parse`] when `dir` is not a run's output folder or a file in it is
/// malformed; [`Error::Invalid`] for a field the run did not write (naming those it did) or a
/// bad time; [`Error::Write`] / [`Error::Plot`] when a picture cannot be written.
pub fn plot(dir: &Path, opts: &PlotOptions) -> Result<PlotReport> {
    if !style::register_font() {
        return Err(Error::Plot("the embedded font is invalid".into()));
    }
    check_folder(dir)?;
    let history = History::read(&dir.join("history.csv"))?;
    let out = dir.join("plots");
    crate::output::create_dir(&out)?;
    let mut report = PlotReport {
        dir: out.clone(),
        ..PlotReport::default()
    };
    let label = run_label(dir);
    let ext = opts.format.extension();
    let time = history.values(0);

    let error = history
        .column("energy_error")
        .map(|k| ("balance error".to_string(), history.values(k)));
    let charts_drawn = [
        (
            "energies",
            "energies",
            "energy [J; J/m in plane strain]",
            charts::energy_lines(&history),
            error.as_ref(),
        ),
        (
            "contact_forces",
            "contact and wall forces",
            "force [N; N/m in plane strain]",
            charts::force_lines(&history),
            None,
        ),
        (
            "velocities",
            "rigid-body velocities",
            "velocity [m/s]",
            charts::velocity_lines(&history),
            None,
        ),
    ];
    for (name, title, y_desc, lines, error) in &charts_drawn {
        // The energy chart always; the others when the run has their columns.
        if lines.is_empty() && *name != "energies" {
            continue;
        }
        let path = out.join(format!("{name}.{ext}"));
        let title = format!("{title} ({label})");
        chart(&path, opts.format, &title, y_desc, &time, lines, *error)?;
        report.files.push(path);
    }

    if !dir.join("fields.pvd").is_file() {
        if let Some(f) = opts.field {
            return Err(Error::Parse {
                file: dir.to_path_buf(),
                message: format!(
                    "no field snapshots to draw `{}` from: missing fields.pvd (the scene has no \
                     run.field_interval)",
                    f.name()
                ),
            });
        }
        report
            .notes
            .push("no fields.pvd: no field pictures (the scene has no run.field_interval)".into());
        return Ok(report);
    }
    let snaps = read::snapshots(dir)?;
    let chosen = choose(&snaps, &opts.times, dir)?;
    let field = opts.field.unwrap_or(Field::VonMises);
    let mut pieces: Vec<Vec<Piece>> = Vec::with_capacity(chosen.len());
    for &k in &chosen {
        let mut v = Vec::with_capacity(snaps[k].parts.len());
        for (_, file) in &snaps[k].parts {
            v.push(read::vtu(file)?);
        }
        pieces.push(v);
    }
    if let Some(first) = pieces.iter().flatten().next() {
        if !field.available(first) {
            let wrote: Vec<&str> = Field::ALL
                .iter()
                .filter(|f| f.available(first))
                .map(|f| f.name())
                .collect();
            return Err(Error::Invalid {
                file: dir.to_path_buf(),
                key: "--field".into(),
                value: field.name().into(),
                reason: format!("this run wrote only the fields {}", wrote.join(", ")),
            });
        }
    }
    let values: Vec<Vec<Vec<f64>>> = pieces
        .iter()
        .map(|s| s.iter().map(|p| field.values(p)).collect())
        .collect();
    let range = match opts.range {
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() && lo < hi => (lo, hi),
        Some((lo, hi)) => {
            return Err(Error::Invalid {
                file: dir.to_path_buf(),
                key: "--range".into(),
                value: format!("{lo} {hi}"),
                reason: "must be two finite values, the first below the second".into(),
            })
        }
        None => field::range(values.iter().flatten().flatten()),
    };
    let mut bbox = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    // The window frames the cells drawn: not the free nodes of eroded cells, which fly on as
    // masses with no element (assets/long_rod_penetration.toml's flew 0.54 m off, 2026-11-28);
    // every point where no cell is left to draw.
    let drawn = |p: &Piece| -> Vec<usize> {
        let gone = field::eroded_cells(p);
        let mut points: Vec<usize> = (0..p.cells())
            .filter(|&c| gone.get(c) != Some(&true))
            .flat_map(|c| p.cell(c).iter().map(|&i| i as usize))
            .collect();
        points.sort_unstable();
        points.dedup();
        points
    };
    let mut framed: Vec<Vec<usize>> = pieces.iter().flatten().map(drawn).collect();
    if framed.iter().all(|f| f.is_empty()) {
        framed = pieces
            .iter()
            .flatten()
            .map(|p| (0..p.points.len()).collect())
            .collect();
    }
    for (p, f) in pieces.iter().flatten().zip(&framed) {
        for q in f.iter().filter_map(|&i| p.points.get(i)) {
            if q[0].is_finite() && q[1].is_finite() {
                bbox = (
                    bbox.0.min(q[0]),
                    bbox.1.max(q[0]),
                    bbox.2.min(q[1]),
                    bbox.3.max(q[1]),
                );
            }
        }
    }
    let window = Window::around(bbox);
    report.field = Some(field);
    report.range = Some(range);
    report.window = Some(window);
    let gif_path = out.join(format!("field_{}.gif", field.name()));
    let mut gif = if opts.animate {
        let file = File::create(&gif_path).map_err(|source| Error::Write {
            path: gif_path.clone(),
            source,
        })?;
        let (w, h) = field::SIZE;
        let mut enc = gif::Encoder::new(BufWriter::new(file), w as u16, h as u16, &[])
            .map_err(|e| plot_error(&gif_path, e))?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(|e| plot_error(&gif_path, e))?;
        Some(enc)
    } else {
        None
    };
    let mut edges = None;
    for (j, &k) in chosen.iter().enumerate() {
        let layers: Vec<Layer<'_>> = pieces[j]
            .iter()
            .zip(&values[j])
            .map(|(piece, v)| Layer { piece, values: v })
            .collect();
        let edges = *edges.get_or_insert_with(|| field::edges_readable(&layers, &window));
        let frame = Frame {
            layers,
            range,
            window,
            field,
            time: snaps[k].time,
            edges,
        };
        let path = out.join(format!("field_{}_{:05}.{ext}", field.name(), k));
        let rgb = if opts.format == Format::Png || gif.is_some() {
            Some(raster(field::SIZE, &path, |root| {
                field::draw(root, &frame)
            })?)
        } else {
            None
        };
        match (opts.format, &rgb) {
            (Format::Png, Some(rgb)) => write_png(&path, field::SIZE, rgb)?,
            _ => {
                let root = SVGBackend::new(&path, field::SIZE).into_drawing_area();
                field::draw(&root, &frame).map_err(|e| plot_error(&path, e))?;
            }
        }
        if let (Some(enc), Some(rgb)) = (gif.as_mut(), &rgb) {
            let (w, h) = field::SIZE;
            let mut f = gif::Frame::from_rgb_speed(w as u16, h as u16, rgb, 10);
            f.delay = GIF_DELAY;
            enc.write_frame(&f).map_err(|e| plot_error(&gif_path, e))?;
            report.gif_frames += 1;
        }
        report.files.push(path.clone());
        report.pictures.push(Picture {
            path,
            snapshot: k,
            time: snaps[k].time,
        });
    }
    if let Some(enc) = gif {
        enc.into_inner().map_err(|e| plot_error(&gif_path, e))?;
        report.files.push(gif_path);
    }
    Ok(report)
}
