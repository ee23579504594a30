//! Line charts of `history.csv` against time: energies (with the balance error on its own axis),
//! contact and wall forces, and the bodies' rigid-body velocities.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::read::History;
use super::style::{bounds, draw_axes, text, PALETTE};

/// Width and height of a chart in pixels.
pub const SIZE: (u32, u32) = (1000, 600);

/// The legend lists at most this many series (a pile of disks has hundreds of velocity columns).
const LEGEND_MAX: usize = 16;

/// One line: its label and values (one per history row).
pub type Line = (String, Vec<f64>);

/// The energy columns of the energy chart, with their labels.
pub const ENERGIES: [(&str, &str); 6] = [
    ("kinetic_energy", "kinetic"),
    ("internal_energy", "internal"),
    ("hourglass_energy", "hourglass"),
    ("contact_energy", "contact"),
    ("viscous_work", "viscous work"),
    ("external_work", "external work"),
];

/// The energy lines of `h` (columns it has).
pub fn energy_lines(h: &History) -> Vec<Line> {
    ENERGIES
        .iter()
        .filter_map(|(col, label)| h.column(col).map(|k| (label.to_string(), h.values(k))))
        .collect()
}

/// The contact and wall force lines of `h`: `<name>.fx` and `<name>.fy` of every contact block
/// (recognised by its `max_penetration` column).
pub fn force_lines(h: &History) -> Vec<Line> {
    let mut out = Vec::new();
    for c in &h.columns {
        if let Some(name) = c.strip_suffix(".max_penetration") {
            for comp in ["fx", "fy"] {
                if let Some(k) = h.column(&format!("{name}.{comp}")) {
                    out.push((format!("{name} {comp}"), h.values(k)));
                }
            }
        }
    }
    out
}

/// The rigid-body velocity lines of `h`: `<body>.vx`, `<body>.vy`.
pub fn velocity_lines(h: &History) -> Vec<Line> {
    h.columns
        .iter()
        .enumerate()
        .filter(|(_, c)| c.ends_with(".vx") || c.ends_with(".vy"))
        .map(|(k, c)| {
            let (body, comp) = c.rsplit_once('.').unwrap_or((c, ""));
            (format!("{body} {comp}"), h.values(k))
        })
        .collect()
}

/// Draws `lines` against `time` on `root`, with `error` (label, values) on a second axis at the
/// right when given.
///
/// # Errors
/// The backend's error, as text.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    y_desc: &str,
    time: &[f64],
    lines: &[Line],
    error: Option<&Line>,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(text)?;
    let (t0, t1) = match (time.first(), time.last()) {
        (Some(&a), Some(&b)) if b > a => (a, b),
        (Some(&a), _) => (a, a + 1.0),
        _ => (0.0, 1.0),
    };
    let (y0, y1) = bounds(lines.iter().flat_map(|l| l.1.iter()));
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(title, ("sans-serif", 22))
        .margin(15)
        .margin_right(if error.is_some() { 15 } else { 40 })
        .x_label_area_size(50)
        .y_label_area_size(90);
    if error.is_some() {
        builder.right_y_label_area_size(90);
    }
    let mut chart = builder
        .build_cartesian_2d(t0..t1, y0..y1)
        .map_err(text)?
        .set_secondary_coord(
            t0..t1,
            match error {
                Some(e) => {
                    let (_, hi) = bounds(e.1.iter());
                    0.0..hi.max(1e-16)
                }
                None => 0.0..1.0,
            },
        );
    draw_axes(&mut chart, "time [s]", y_desc, (t0, t1), (y0, y1))?;
    for (i, (label, values)) in lines.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()].to_rgba();
        let series = chart
            .draw_series(LineSeries::new(
                time.iter()
                    .zip(values)
                    .filter(|(t, v)| t.is_finite() && v.is_finite())
                    .map(|(&t, &v)| (t, v)),
                color.stroke_width(2),
            ))
            .map_err(text)?;
        if i < LEGEND_MAX {
            series.label(label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
    }
    if let Some((label, values)) = error {
        chart
            .configure_secondary_axes()
            .y_desc(label.as_str())
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .draw()
            .map_err(text)?;
        let color = BLACK.mix(0.7);
        chart
            .draw_secondary_series(LineSeries::new(
                time.iter()
                    .zip(values)
                    .filter(|(t, v)| t.is_finite() && v.is_finite())
                    .map(|(&t, &v)| (t, v)),
                ShapeStyle::from(color).stroke_width(1),
            ))
            .map_err(text)?
            .label(format!("{label} (right axis)"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    if !lines.is_empty() || error.is_some() {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(text)?;
    }
    if lines.len() > LEGEND_MAX {
        root.draw(&Text::new(
            format!("legend: first {LEGEND_MAX} of {} lines", lines.len()),
            (110, SIZE.1 as i32 - 20),
            ("sans-serif", 13).into_font().color(&BLACK),
        ))
        .map_err(text)?;
    }
    root.present().map_err(text)?;
    Ok(())
}
