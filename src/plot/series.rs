//! A chart of one quantity against another, one series of points per label: what
//! `ricochet plot DIR --figure F --against P` draws for a study (a collected figure against a
//! parameter, one line per combination of the other parameters). Host-side only.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{bounds, draw_axes, text, PALETTE};

/// One series: its label and its points (x, y), drawn in x order.
pub type Series = (String, Vec<(f64, f64)>);

/// The legend lists at most this many series.
const LEGEND_MAX: usize = 16;

/// Draws `series` on `root`: a line with a marker at each point, x across.
///
/// # Errors
/// The backend's error, as text.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(text)?;
    let xs: Vec<f64> = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.0))
        .collect();
    let ys: Vec<f64> = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .collect();
    let (x0, x1) = bounds(xs.iter());
    let (y0, y1) = bounds(ys.iter());
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(15)
        .margin_right(40)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(text)?;
    draw_axes(&mut chart, x_desc, y_desc, (x0, x1), (y0, y1))?;
    for (i, (label, points)) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()].to_rgba();
        let mut sorted: Vec<(f64, f64)> = points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(sorted.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(text)?;
        let line = chart
            .draw_series(LineSeries::new(
                sorted.iter().copied(),
                color.stroke_width(2),
            ))
            .map_err(text)?;
        if i < LEGEND_MAX && !label.is_empty() {
            line.label(label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
    }
    if series.iter().any(|s| !s.0.is_empty()) {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(text)?;
    }
    root.present().map_err(text)?;
    Ok(())
}
