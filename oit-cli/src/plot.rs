//! The SVG of `oit sweep --plot`: error pixel rate per view, one line per technique, log axis.

use std::path::Path;

use oit_core::OitError;
use plotters::prelude::*;

use crate::sweep::Record;

/// One line of the plot: (technique, backend/raster path, (azimuth, EPR) points).
type Series = (String, String, Vec<(f64, f64)>);

/// Where an EPR of 0 is drawn: a log axis has no 0, and no real image has 1 error pixel in 10⁵.
const FLOOR: f64 = 1e-5;

/// Draws `records` as one line per technique (and backend/raster path, when there are several)
/// against the azimuth, into `path`.
pub fn epr_plot(path: &Path, records: &[Record], scene: &str, elevation: f32) -> Result<(), OitError> {
    let err =
        |e: &dyn std::fmt::Display| OitError::Write { path: path.to_path_buf(), message: e.to_string() };

    // Series in first-seen order: the order of --techniques.
    let mut series: Vec<Series> = Vec::new();
    for r in records {
        let point = (f64::from(r.azimuth), r.epr.max(FLOOR));
        let label = r.label();
        match series.iter_mut().find(|(t, b, _)| *t == r.technique && *b == label) {
            Some((_, _, points)) => points.push(point),
            None => series.push((r.technique.clone(), label, vec![point])),
        }
    }
    let several_backends = series.iter().any(|(_, b, _)| series.first().is_some_and(|(_, b0, _)| b0 != b));
    let top = (records.iter().map(|r| r.epr).fold(0.0, f64::max) * 2.0).clamp(1e-2, 1.0);

    let root = SVGBackend::new(path, (1000, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("error pixel rate around {scene} (elevation {elevation}°)"), ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(0f64..360f64, (FLOOR..top).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("camera azimuth (degrees)")
        .y_desc(format!("error pixel rate (log; EPR 0 drawn at {FLOOR:e})"))
        .y_label_formatter(&|v| format!("{v:e}"))
        .draw()
        .map_err(|e| err(&e))?;
    for (i, (technique, backend, points)) in series.into_iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let label = if several_backends { format!("{technique} ({backend})") } else { technique };
        let single = points.len() == 1;
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        if single {
            // A line of one point draws nothing; mark it.
            chart
                .draw_series(points.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                .map_err(|e| err(&e))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
