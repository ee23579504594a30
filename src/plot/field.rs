//! Field pictures: the deformed mesh of every body filled by an element field, on a fixed colour
//! range, with a labelled colour bar, equal aspect and axes in metres.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::read::Piece;
use super::style::{finite_extent, level, level_colour, text, tick, LEVELS};

/// Fields a picture can show, each one value per element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// Von Mises stress (cell data `von_mises`).
    VonMises,
    /// Pressure -(s_xx + s_yy + s_zz) / 3, positive in compression (from cell data `stress`).
    Pressure,
    /// Speed |v|, the mean over the element's nodes (point data `velocity`).
    Velocity,
    /// Displacement magnitude |u|, the mean over the element's nodes (point data `displacement`).
    Displacement,
    /// Equivalent plastic strain (cell data `plastic_strain`).
    PlasticStrain,
}

impl Field {
    /// Every field, in the order of the command line's list.
    pub const ALL: [Field; 5] = [
        Field::VonMises,
        Field::Pressure,
        Field::Velocity,
        Field::Displacement,
        Field::PlasticStrain,
    ];

    /// The name on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Field::VonMises => "von_mises",
            Field::Pressure => "pressure",
            Field::Velocity => "velocity",
            Field::Displacement => "displacement",
            Field::PlasticStrain => "plastic_strain",
        }
    }

    /// The field called `name`.
    pub fn parse(name: &str) -> Option<Field> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Title and colour-bar label, with the unit.
    pub fn label(self) -> &'static str {
        match self {
            Field::VonMises => "von Mises stress [Pa]",
            Field::Pressure => "pressure [Pa]",
            Field::Velocity => "speed [m/s]",
            Field::Displacement => "displacement [m]",
            Field::PlasticStrain => "equivalent plastic strain",
        }
    }

    /// Whether a VTU piece carries what this field is computed from.
    pub fn available(self, piece: &Piece) -> bool {
        match self {
            Field::VonMises => piece.cell_array("von_mises").is_some(),
            Field::Pressure => piece.cell_array("stress").is_some(),
            Field::Velocity => piece.point_array("velocity").is_some(),
            Field::Displacement => piece.point_array("displacement").is_some(),
            Field::PlasticStrain => piece.cell_array("plastic_strain").is_some(),
        }
    }

    /// The value of every cell of `piece` (empty when the piece lacks the field; NaN on an
    /// eroded cell, which the colour range leaves out: see [`eroded_cells`]).
    pub fn values(self, piece: &Piece) -> Vec<f64> {
        let mut v = self.values_of_all(piece);
        for (x, gone) in v.iter_mut().zip(eroded_cells(piece)) {
            if gone {
                *x = f64::NAN;
            }
        }
        v
    }

    /// [`Field::values`] of every cell, eroded or not.
    fn values_of_all(self, piece: &Piece) -> Vec<f64> {
        let nodal_mean = |name: &str| -> Vec<f64> {
            let Some(a) = piece.point_array(name) else {
                return Vec::new();
            };
            let n = a.components;
            let norm = |i: u32| {
                let v = &a.values[i as usize * n..(i as usize + 1) * n];
                v.iter().map(|x| x * x).sum::<f64>().sqrt()
            };
            (0..piece.cells())
                .map(|c| {
                    let cell = piece.cell(c);
                    cell.iter().map(|&i| norm(i)).sum::<f64>() / cell.len().max(1) as f64
                })
                .collect()
        };
        let scalar = |name: &str| -> Vec<f64> {
            piece
                .cell_array(name)
                .map(|a| a.values.iter().step_by(a.components).copied().collect())
                .unwrap_or_default()
        };
        match self {
            Field::VonMises => scalar("von_mises"),
            Field::PlasticStrain => scalar("plastic_strain"),
            Field::Pressure => piece
                .cell_array("stress")
                .map(|a| {
                    a.values
                        .chunks_exact(a.components)
                        .map(|s| {
                            // (xx, yy, xy, zz)
                            let zz = if s.len() > 3 { s[3] } else { 0.0 };
                            -(s[0] + s[1] + zz) / 3.0
                        })
                        .collect()
                })
                .unwrap_or_default(),
            Field::Velocity => nodal_mean("velocity"),
            Field::Displacement => nodal_mean("displacement"),
        }
    }
}

/// Per cell of `piece`, whether it eroded (its cell data `eroded` is not 0): pictures leave it
/// out, so that a perforation looks like one. All false without that array.
pub fn eroded_cells(piece: &Piece) -> Vec<bool> {
    match piece.cell_array("eroded") {
        Some(a) => a
            .values
            .iter()
            .step_by(a.components.max(1))
            .map(|&x| x != 0.0)
            .collect(),
        None => vec![false; piece.cells()],
    }
}

/// Width and height of a field picture in pixels.
pub const SIZE: (u32, u32) = (1000, 720);

/// Title strip, margin, label areas and colour-bar strip of a field picture (pixels).
const TITLE: u32 = 50;
const MARGIN: u32 = 15;
const X_LABELS: u32 = 50;
const Y_LABELS: u32 = 95;
const BAR: u32 = 170;
/// The colour of a cell without a value: a body whose material does not write the field
/// (`plastic_strain` of an elastic body) is drawn in light grey.
const NO_VALUE: [u8; 3] = [200, 200, 200];

/// One body's cells and their values in one snapshot.
#[derive(Debug, Clone)]
pub struct Layer<'a> {
    /// The body's deformed mesh.
    pub piece: &'a Piece,
    /// One value per cell (empty for a body whose material does not write the field: drawn in
    /// light grey).
    pub values: &'a [f64],
}

/// The data window and the pixel window of a field picture's plotting area, the same for every
/// snapshot of a run: a point (x, y) lands at pixel
/// (px0 + (x - x0) / (x1 - x0) * (px1 - px0), py0 + (y1 - y) / (y1 - y0) * (py1 - py0)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Data x range (m).
    pub x: (f64, f64),
    /// Data y range (m).
    pub y: (f64, f64),
    /// Pixel x range of the plotting area.
    pub px: (i32, i32),
    /// Pixel y range of the plotting area (top, bottom).
    pub py: (i32, i32),
}

impl Window {
    /// The plotting area's pixel ranges (from the fixed layout) and the data window around `bbox`
    /// (x0, x1, y0, y1) with a 4 % border, widened along one axis so that a metre is as long in
    /// x as in y.
    pub fn around(bbox: (f64, f64, f64, f64)) -> Self {
        let (w, h) = SIZE;
        let px = ((MARGIN + Y_LABELS) as i32, (w - BAR - MARGIN) as i32);
        let py = ((TITLE + MARGIN) as i32, (h - MARGIN - X_LABELS) as i32);
        let (pw, ph) = ((px.1 - px.0) as f64, (py.1 - py.0) as f64);
        let (mut x0, mut x1, mut y0, mut y1) = bbox;
        if !(x0 <= x1 && y0 <= y1) {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        let size = (x1 - x0).max(y1 - y0).max(f64::MIN_POSITIVE * 1e10);
        let pad = 0.04 * size;
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        // Metres per pixel: the larger of the two axes' needs.
        let scale = ((x1 - x0 + 2.0 * pad) / pw).max((y1 - y0 + 2.0 * pad) / ph);
        Self {
            x: (cx - 0.5 * scale * pw, cx + 0.5 * scale * pw),
            y: (cy - 0.5 * scale * ph, cy + 0.5 * scale * ph),
            px,
            py,
        }
    }

    /// The pixel of point (x, y) (rounded down, as the rasterizer's sample).
    pub fn pixel(&self, x: f64, y: f64) -> (i32, i32) {
        let fx = (x - self.x.0) / (self.x.1 - self.x.0) * (self.px.1 - self.px.0) as f64;
        let fy = (self.y.1 - y) / (self.y.1 - self.y.0) * (self.py.1 - self.py.0) as f64;
        (self.px.0 + fx.floor() as i32, self.py.0 + fy.floor() as i32)
    }
}

/// The colour range of `values`: the smallest and largest finite value, widened when they
/// coincide; (0, 1) when there is none.
pub fn range<'a>(values: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    let Some((lo, hi)) = finite_extent(values) else {
        return (0.0, 1.0);
    };
    let span = hi - lo;
    if span <= 1e-9 * hi.abs().max(lo.abs()) || span == 0.0 {
        let d = if hi.abs().max(lo.abs()) > 0.0 {
            1e-3 * hi.abs().max(lo.abs())
        } else {
            1.0
        };
        return (lo - d, hi + d);
    }
    (lo, hi)
}

/// What one field picture shows.
#[derive(Debug, Clone)]
pub struct Frame<'a> {
    /// The bodies.
    pub layers: Vec<Layer<'a>>,
    /// Colour range (lo < hi).
    pub range: (f64, f64),
    /// Data and pixel window.
    pub window: Window,
    /// The field.
    pub field: Field,
    /// Simulated time (s).
    pub time: f64,
    /// Draw element edges.
    pub edges: bool,
}

/// The corner coordinates of cell `c` of `piece`, in order.
fn corners(piece: &Piece, c: usize) -> Vec<(f64, f64)> {
    piece
        .cell(c)
        .iter()
        .map(|&i| {
            let p = piece.points[i as usize];
            (p[0], p[1])
        })
        .collect()
}

/// Whether the mesh is coarse enough on screen for element edges to be read: at least 10 x 10
/// pixels per cell on average.
pub fn edges_readable(layers: &[Layer<'_>], window: &Window) -> bool {
    let cells: usize = layers.iter().map(|l| l.piece.cells()).sum();
    if cells == 0 {
        return false;
    }
    let mut area = 0.0;
    for l in layers {
        for c in 0..l.piece.cells() {
            let p = corners(l.piece, c);
            let n = p.len();
            let mut a = 0.0;
            for k in 0..n {
                let (q, r) = (p[k], p[(k + 1) % n]);
                a += q.0 * r.1 - r.0 * q.1;
            }
            area += 0.5 * a.abs();
        }
    }
    let per_px = (window.x.1 - window.x.0) / (window.px.1 - window.px.0) as f64;
    area / (per_px * per_px) / cells as f64 >= 100.0
}

/// Draws the frame onto `root` ([`SIZE`]): title, axes, the cells filled by the colour map, edges
/// when asked, and the colour bar. Fills rasterize each cell once (plotters' polygon scan fill).
///
/// # Errors
/// The backend's error, as text.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    frame: &Frame<'_>,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(text)?;
    let w = SIZE.0;
    let w_ = &frame.window;
    let title = format!("{}, t = {:.4e} s", frame.field.label(), frame.time);
    root.draw(&Text::new(
        title,
        ((MARGIN + Y_LABELS) as i32, (MARGIN + 5) as i32),
        ("sans-serif", 22).into_font().color(&BLACK),
    ))
    .map_err(text)?;
    let body = root.margin(TITLE, 0, 0, 0);
    let (main, bar) = body.split_horizontally(w - BAR);
    let mut chart = ChartBuilder::on(&main)
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(w_.x.0..w_.x.1, w_.y.0..w_.y.1)
        .map_err(text)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&|v| tick(*v, w_.x.1 - w_.x.0, 1e-3..1e4))
        .y_label_formatter(&|v| tick(*v, w_.y.1 - w_.y.0, 1e-3..1e4))
        .draw()
        .map_err(text)?;
    let (lo, hi) = frame.range;
    let area = chart.plotting_area();
    for layer in &frame.layers {
        let piece = layer.piece;
        let gone = eroded_cells(piece);
        for c in 0..piece.cells() {
            if gone[c] {
                continue;
            }
            let [r, g, b] = match layer.values.get(c) {
                Some(&v) => level_colour(level(v, lo, hi)),
                None => NO_VALUE,
            };
            area.draw(&Polygon::new(corners(piece, c), RGBColor(r, g, b).filled()))
                .map_err(text)?;
        }
    }
    if frame.edges {
        let edge = RGBColor(40, 40, 40);
        for layer in &frame.layers {
            let piece = layer.piece;
            let gone = eroded_cells(piece);
            for c in 0..piece.cells() {
                if gone[c] {
                    continue;
                }
                let mut pts = corners(piece, c);
                if let Some(&first) = pts.first() {
                    pts.push(first);
                }
                area.draw(&PathElement::new(pts, edge)).map_err(text)?;
            }
        }
    }
    // The colour bar: one band per level, labelled with the values.
    let mut bar_chart = ChartBuilder::on(&bar)
        .margin_top(MARGIN)
        .margin_bottom(MARGIN + X_LABELS)
        .margin_left(10)
        .margin_right(10)
        .right_y_label_area_size(BAR - 60)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(text)?;
    bar_chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(9)
        .y_label_formatter(&|v| format!("{v:.3e}"))
        .label_style(("sans-serif", 13))
        .y_desc(frame.field.label())
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(text)?;
    let bands = (0..LEVELS).map(|k| {
        let a = lo + (hi - lo) * k as f64 / LEVELS as f64;
        let b = lo + (hi - lo) * (k + 1) as f64 / LEVELS as f64;
        let [r, g, bl] = level_colour(k);
        Rectangle::new([(0.0, a), (1.0, b)], RGBColor(r, g, bl).filled())
    });
    bar_chart.draw_series(bands).map_err(text)?;
    root.present().map_err(text)?;
    Ok(())
}
