//! Error-against-wall-time plots of the verification suite (plotters; SVG and PNG), one per case:
//! every method and backend in one picture, log-log, with reference slopes for convergence orders
//! 1 and 2 given the case's cost exponent (wall time ~ size^k: error ~ time^(-p/k)).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::case::Case;
use super::Row;
use crate::error::{Error, Result};
use crate::plot::style::PALETTE;

fn register_font() -> Result<()> {
    if crate::plot::style::register_font() {
        Ok(())
    } else {
        Err(Error::Verify("the embedded plot font is invalid".into()))
    }
}

/// One series: a label and its (wall seconds, error) points by level.
type Series = (String, Vec<(f64, f64)>);

/// Writes `<case>.svg` and `<case>.png` into `dir`: the error of the case's plotted metric against
/// wall time, one series per (method, backend).
///
/// # Errors
/// [`Error::Verify`] when drawing or writing fails.
pub fn error_vs_time(dir: &Path, case: &Case, rows: &[Row]) -> Result<()> {
    register_font()?;
    let metric = case
        .case
        .plot
        .clone()
        .unwrap_or_else(|| case.metric[0].name.clone());
    let mut series: Vec<Series> = Vec::new();
    for r in rows
        .iter()
        .filter(|r| r.case == case.case.name && r.metric == metric)
    {
        let label = format!("{}, {}", r.method, r.backend);
        let point = (r.wall_seconds.max(1e-6), r.relative_error.max(1e-16));
        if !(point.0.is_finite() && point.1.is_finite()) {
            continue;
        }
        match series.iter_mut().find(|s| s.0 == label) {
            Some(s) => s.1.push(point),
            None => series.push((label, vec![point])),
        }
    }
    let title = format!("{}: error of {metric} against wall time", case.case.name);
    let k = case.case.cost_exponent;
    let draw_err = |e: String| Error::Verify(format!("plot {}: {e}", case.case.name));
    let svg = dir.join(format!("{}.svg", case.case.name));
    let png = dir.join(format!("{}.png", case.case.name));
    draw(
        &SVGBackend::new(&svg, SIZE).into_drawing_area(),
        &title,
        &metric,
        &series,
        k,
    )
    .map_err(draw_err)?;
    let rgb = crate::plot::raster(SIZE, &png, |root| draw(root, &title, &metric, &series, k))?;
    crate::plot::write_png(&png, SIZE, &rgb)
}

/// Pixels of each plot.
const SIZE: (u32, u32) = (900, 600);

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    metric: &str,
    series: &[Series],
    k: f64,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let pts = series.iter().flat_map(|s| s.1.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (1e-3, 1.0, 1e-6, 1.0);
    }
    let (x0, x1) = (x0 / 2.0, x1 * 2.0);
    let (y0, y1) = (y0 / 5.0, y1 * 5.0);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("wall time of the run (s)")
        .y_desc(format!("relative error of {metric}"))
        .label_style(("sans-serif", 14))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .draw()
        .map_err(e)?;
    // Reference slopes through the first point of the first series.
    if let Some(&(t0, e0)) = series.first().and_then(|s| s.1.first()) {
        for (p, style) in [(1.0, BLACK.mix(0.35)), (2.0, BLACK.mix(0.6))] {
            let slope = -p / k;
            let line: Vec<(f64, f64)> = [x0, x1]
                .iter()
                .map(|&t| (t, e0 * (t / t0).powf(slope)))
                .collect();
            chart
                .draw_series(LineSeries::new(line, style.stroke_width(1)))
                .map_err(e)?
                .label(format!("order {p} in size: slope -{p}/{k}"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
    }
    for (i, (label, points)) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()].to_rgba();
        chart
            .draw_series(LineSeries::new(
                points.iter().copied(),
                color.stroke_width(2),
            ))
            .map_err(e)?
            .label(label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}
