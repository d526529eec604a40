//! The chart of `oit sweep --plot`: error pixel rate per view, one line per technique, log axis,
//! drawn by oit-bench's [`Chart`] (SVG or PNG, the legend beside the plot area, never over the
//! data), and the per-view [`Record`] it draws (which `oit sweep` makes and prints: here, so that
//! the chart does not import its command).

use std::path::Path;

use oit_bench::plot::{Chart, Series};
use oit_core::{OitError, Stats};
use serde::Serialize;

/// One technique at one view: a row of `oit sweep --json`.
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    /// Camera azimuth in degrees.
    pub azimuth: f32,
    /// The technique, parameters included.
    pub technique: String,
    /// The backend.
    pub backend: String,
    /// The raster path it took.
    pub raster: String,
    /// The frame's counters (`geometry_passes`, `fragments`, `captured`, `lost`, `tied`,
    /// `storage_bytes`, `tiles`, `wall_ms`, `gpu_ms`, and `gpu_pass_ms` where measured).
    #[serde(flatten)]
    pub stats: Stats,
    /// Error pixel rate: the share of covered pixels off by more than 1 in 8 bits, a fraction in
    /// [0, 1] (the summary table prints it in per cent).
    pub epr: f64,
    /// PSNR in dB against the reference; null when identical.
    pub psnr: Option<f64>,
    /// The largest channel difference from the reference, in [0, 1].
    pub max_error: f64,
}

impl Record {
    /// `backend` or `backend/path`.
    pub fn label(&self) -> String {
        if self.raster == self.backend {
            self.raster.clone()
        } else {
            format!("{}/{}", self.backend, self.raster)
        }
    }
}

/// Where an EPR of 0 is drawn, in per cent: a log axis has no 0, and no real image has 1 error
/// pixel in 10⁵.
const FLOOR_PERCENT: f64 = 1e-3;

/// One line of the plot: technique, backend/raster path, (azimuth, EPR %) points.
type Line = (String, String, Vec<(f64, f64)>);

/// Draws `records` as one line per technique (and backend/raster path, when there are several)
/// against the azimuth, EPR in per cent on a log axis, into `path`: an SVG or, for a `.png` path,
/// a PNG.
pub fn epr_plot(path: &Path, records: &[Record], scene: &str, elevation: f32) -> Result<(), OitError> {
    // Series in first-seen order: the order of --techniques.
    let mut series: Vec<Line> = Vec::new();
    // a view that covered no pixel has no EPR (NaN): left out, not drawn at the floor as a perfect
    // score
    for r in records.iter().filter(|r| !r.epr.is_nan()) {
        let point = (f64::from(r.azimuth), (r.epr * 100.0).max(FLOOR_PERCENT));
        let label = r.label();
        match series.iter_mut().find(|(t, b, _)| *t == r.technique && *b == label) {
            Some((_, _, points)) => points.push(point),
            None => series.push((r.technique.clone(), label, vec![point])),
        }
    }
    let several_backends = series.iter().any(|(_, b, _)| series.first().is_some_and(|(_, b0, _)| b0 != b));
    let chart = Chart {
        title: format!("error pixel rate around {scene} (elevation {elevation}°)"),
        x_desc: "camera azimuth (degrees)".into(),
        y_desc: format!("EPR, % of covered pixels (log; EPR 0 drawn at {FLOOR_PERCENT:e} %)"),
        x_log: false,
        y_log: true,
        series: series
            .into_iter()
            .map(|(technique, backend, points)| Series {
                name: if several_backends { format!("{technique} ({backend})") } else { technique },
                // a line of one point draws nothing: mark the points of a single view
                markers: points.len() == 1,
                points,
                labels: Vec::new(),
                line: true,
                color: None,
            })
            .collect(),
    };
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        chart.png(path)
    } else {
        chart.svg(path)
    }
}
