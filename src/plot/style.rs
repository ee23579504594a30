//! What every picture ricochet draws shares: the embedded font, the series colours and the colour
//! map of the field pictures.

use std::sync::OnceLock;

use plotters::drawing::DrawingAreaErrorKind;
use plotters::style::{FontStyle, RGBColor};

/// The font of the plots' text (DejaVu Sans, see `assets/fonts/DejaVuSans-LICENSE.txt`), embedded
/// so that plots need no system fonts.
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font as plotters' `sans-serif` (once per process); false when the
/// embedded font is invalid.
pub fn register_font() -> bool {
    static OK: OnceLock<bool> = OnceLock::new();
    *OK.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    })
}

/// Series colours (distinct on white, colour-blind friendly order, Okabe-Ito).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(230, 159, 0),
    RGBColor(120, 120, 120),
    RGBColor(0, 0, 0),
];

/// Entries of the field colour map: values are binned into this many colours (the colour bar shows
/// the same bins).
pub const LEVELS: usize = 256;

/// The colour of bin `k` (0 ..= [`LEVELS`] - 1) of the field colour map: viridis (perceptually
/// uniform, readable in grey and by colour-blind readers), from `colorous`.
pub fn level_colour(k: usize) -> [u8; 3] {
    let c = colorous::VIRIDIS.eval_rational(k.min(LEVELS - 1), LEVELS);
    [c.r, c.g, c.b]
}

/// The bin of value `v` on the range `lo..hi` (`lo < hi`): values outside clamp to the ends, NaN
/// to the first bin.
pub fn level(v: f64, lo: f64, hi: f64) -> usize {
    let t = (v - lo) / (hi - lo);
    if t.is_nan() || t <= 0.0 {
        0
    } else {
        ((t * LEVELS as f64) as usize).min(LEVELS - 1)
    }
}

/// The colour map's colour for `v` on `lo..hi`: `level_colour(level(v, lo, hi))`.
pub fn colour(v: f64, lo: f64, hi: f64) -> [u8; 3] {
    level_colour(level(v, lo, hi))
}

/// A plotters drawing error as text.
pub(crate) fn text<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> String {
    e.to_string()
}

/// Axis tick labels: `v` with a few significant digits, in exponent form outside `plain`, and 0
/// for values within round-off of zero on an axis spanning `span`.
pub(crate) fn tick(v: f64, span: f64, plain: std::ops::Range<f64>) -> String {
    let a = v.abs();
    if a <= 1e-9 * span {
        "0".into()
    } else if !plain.contains(&a) {
        format!("{v:.2e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').into()
    }
}

/// The smallest and largest finite values, or `None` when there are none.
pub(crate) fn finite_extent<'a>(values: impl Iterator<Item = &'a f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| v.is_finite())
        .fold(None, |acc, &v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((f64::min(lo, v), f64::max(hi, v))),
        })
}

/// The axis range of `values`: their finite extent with 5 % of room on each side.
pub(crate) fn bounds<'a>(values: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    let Some((lo, hi)) = finite_extent(values) else {
        return (0.0, 1.0);
    };
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else if hi != 0.0 {
        0.05 * hi.abs()
    } else {
        1.0
    };
    (lo - pad, hi + pad)
}

/// Draws the grid, ticks and axis titles of a chart over `x` and `y` (the time charts' and the
/// study's series' common look: light grid, tick labels by [`tick`]).
pub(crate) fn draw_axes<DB: plotters::prelude::DrawingBackend>(
    chart: &mut plotters::prelude::ChartContext<
        '_,
        DB,
        plotters::prelude::Cartesian2d<
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
        >,
    >,
    x_desc: &str,
    y_desc: &str,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> std::result::Result<(), String> {
    use plotters::style::{Color, BLACK, WHITE};
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_label_formatter(&|v| tick(*v, x1 - x0, 1e-2..1e4))
        .y_label_formatter(&|v| tick(*v, y1 - y0, 1e-2..1e4))
        .light_line_style(WHITE)
        .bold_line_style(BLACK.mix(0.08))
        .draw()
        .map_err(text)
}
