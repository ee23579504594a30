//! `ricochet plot` (and `run --plots`): draws a run's pictures from its output folder with
//! [`ricochet::plot::plot`] and says where they went; or a study's figure against a parameter
//! (`--figure`, `--against`: [`ricochet::study::plot::plot`]).

use std::path::Path;
use std::process::ExitCode;

use ricochet::plot::PlotOptions;

use super::args::{PlotArgs, PlotFormat};

/// `ricochet plot OUT`.
pub fn plot(args: PlotArgs) -> anyhow::Result<ExitCode> {
    let PlotArgs {
        out,
        figure,
        against,
        field,
        times,
        range,
        animate,
        format,
    } = args;
    let picture_format = match format {
        PlotFormat::Png => ricochet::plot::Format::Png,
        PlotFormat::Svg => ricochet::plot::Format::Svg,
    };
    if let (Some(figure), Some(against)) = (figure, against) {
        let path = ricochet::study::plot::plot(&out, &figure, &against, picture_format)?;
        println!("plot: {}", path.display());
        return Ok(ExitCode::SUCCESS);
    }
    let opts = PlotOptions {
        field: field
            .as_deref()
            .and_then(ricochet::plot::field::Field::parse),
        times,
        range: range.map(|r| (r[0], r[1])),
        animate,
        format: picture_format,
    };
    draw(&out, &opts)?;
    Ok(ExitCode::SUCCESS)
}

/// Draws the pictures of the run in `out` and says where they went.
pub fn draw(out: &Path, opts: &PlotOptions) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let report = ricochet::plot::plot(out, opts)?;
    for note in &report.notes {
        eprintln!("note: {note}");
    }
    let field = match (report.field, report.range) {
        (Some(f), Some((lo, hi))) => format!(
            ", {} {} pictures on [{lo:.4e}, {hi:.4e}]{}",
            report.pictures.len(),
            f.name(),
            if report.gif_frames > 0 {
                format!(" and a GIF of {} frames", report.gif_frames)
            } else {
                String::new()
            }
        ),
        _ => String::new(),
    };
    println!(
        "plots: {} files in {}{field} ({:.2} s)",
        report.files.len(),
        report.dir.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
