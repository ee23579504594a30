//! A study's figure against one of its parameters, drawn into `DIR/plots/<figure>_vs_<param>.png`
//! (or `.svg`) by [`crate::plot::xy_chart`]: one line per combination of the other parameters'
//! values, through the completed cases. Host-side only, no GPU twin.

use std::path::{Path, PathBuf};

use super::collect::collect;
use crate::error::{Error, Result};
use crate::plot::series::Series;
use crate::plot::Format;

/// Draws the figure `figure` of the study in `root` against its parameter `against` and returns
/// the picture's path.
///
/// # Errors
/// As [`collect`]; [`Error::Invalid`] naming `root/study.json` when the study has no such figure
/// or parameter (listing those it has) or no completed case has both; [`Error::Write`] /
/// [`Error::Plot`] when the picture cannot be written.
pub fn plot(root: &Path, figure: &str, against: &str, format: Format) -> Result<PathBuf> {
    let results = collect(root)?;
    let record = &results.record;
    let file = root.join("study.json");
    let invalid = |key: &str, value: &str, reason: String| Error::Invalid {
        file: file.clone(),
        key: key.into(),
        value: format!("{value:?}"),
        reason,
    };
    let Some(points) = results.series(figure, against) else {
        let figures: Vec<&str> = record.figures.iter().map(|f| f.name.as_str()).collect();
        let parameters: Vec<&str> = record.parameters.iter().map(|p| p.0.as_str()).collect();
        return Err(if !figures.contains(&figure) {
            invalid(
                "--figure",
                figure,
                format!("not a figure of the study (those: {figures:?})"),
            )
        } else {
            invalid(
                "--against",
                against,
                format!("not a parameter of the study (those: {parameters:?})"),
            )
        });
    };
    if points.is_empty() {
        return Err(invalid(
            "--figure",
            figure,
            format!("no completed case has a number for it and for {against:?}"),
        ));
    }
    let mut series: Vec<Series> = Vec::new();
    for (label, x, y) in points {
        match series.iter_mut().find(|s| s.0 == label) {
            Some(s) => s.1.push((x, y)),
            None => series.push((label, vec![(x, y)])),
        }
    }
    let dir = root.join("plots");
    crate::output::create_dir(&dir)?;
    let ext = match format {
        Format::Png => "png",
        Format::Svg => "svg",
    };
    let path = dir.join(format!("{figure}_vs_{against}.{ext}"));
    crate::plot::xy_chart(
        &path,
        format,
        &format!("{}: {figure} against {against}", record.name),
        against,
        figure,
        &series,
    )?;
    Ok(path)
}
