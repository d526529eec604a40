//! `oit sweep`: the camera once around the scene, every technique against the reference at each
//! view.

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use oit_core::metrics::accuracy;
use oit_core::{OitError, Technique, View};
use serde::Serialize;

use crate::Outcome;
use crate::options::{SceneArgs, check_output};
use crate::output::{self, Table};
use crate::plot;

/// Most views a sweep takes (one per 0.01°).
const MAX_VIEWS: u32 = 36_000;

/// Arguments of `oit sweep`.
#[derive(Args, Debug)]
#[command(
    about = "Orbit the camera around the scene and measure techniques at every view",
    long_about = "Orbit the camera around the scene and measure techniques at every view.\n\n\
        Takes N views at evenly spaced azimuths from 0 to 360 degrees (the elevation stays at \
        --elevation; --azimuth is not used). At each view renders the reference and every \
        technique on every backend, and records the error pixel rate (EPR), fragments lost and \
        time. Prints a summary per technique (mean and max EPR, mean lost, mean time), or with \
        --json a JSON array of every record ({azimuth, technique, backend, epr, lost, wall_ms}) \
        and nothing else. A progress bar goes to stderr. A technique that fails is reported once \
        on stderr and left out of the results; the exit code is then 1."
)]
pub struct SweepArgs {
    /// Comma-separated techniques (e.g. dp,bdp2,fabs:16), or all (every technique but the
    /// reference, in catalogue order).
    #[arg(short, long, value_name = "LIST|all", default_value = "all")]
    pub techniques: String,

    /// Views around the orbit, at azimuths 0, 360/N, 2·360/N, ... (1 to 36000).
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub views: u32,

    /// Print every per-view record as one JSON array instead of the summary.
    #[arg(long)]
    pub json: bool,

    /// Also draw EPR per view for each technique, on a log axis, as an SVG [default: none].
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,

    #[command(flatten)]
    pub scene: SceneArgs,
}

/// One technique at one view.
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    /// Camera azimuth in degrees.
    pub azimuth: f32,
    /// The technique, parameters included.
    pub technique: String,
    /// The backend.
    pub backend: String,
    /// Error pixel rate, a fraction.
    pub epr: f64,
    /// Fragments lost.
    pub lost: u64,
    /// Wall-clock milliseconds.
    pub wall_ms: f64,
}

/// Runs `oit sweep`.
pub fn run(args: &SweepArgs) -> Result<Outcome, OitError> {
    let techniques = Technique::parse_list(&args.techniques)?;
    if !(1..=MAX_VIEWS).contains(&args.views) {
        return Err(OitError::InvalidSettings(format!(
            "--views {} is out of range: use 1 to {MAX_VIEWS}",
            args.views
        )));
    }
    if let Some(path) = &args.plot {
        check_output(path, "svg", "--plot")?;
    }
    let prepared = args.scene.prepare()?;
    let views: Vec<f32> =
        (0..args.views).map(|i| (f64::from(i) * 360.0 / f64::from(args.views)) as f32).collect();
    // Every camera first, so a view that cannot be framed fails before any work.
    let cameras = views
        .iter()
        .map(|&azimuth| prepared.camera(View { azimuth, ..prepared.view }))
        .collect::<Result<Vec<_>, _>>()?;

    let per_view = (techniques.len() as u64 + 1) * prepared.backends.len() as u64;
    let bar = ProgressBar::new(per_view * u64::from(args.views));
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} sweep [{bar:30}] {pos}/{len} renders, {elapsed} (eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );

    let mut records = Vec::new();
    // (technique, backend) pairs that have failed, reported once each.
    let mut failed: Vec<(String, String)> = Vec::new();
    let mut report = |bar: &ProgressBar, technique: &str, backend: &str, e: &OitError| {
        if !failed.iter().any(|(t, b)| t == technique && b == backend) {
            failed.push((technique.to_string(), backend.to_string()));
            bar.suspend(|| output::error_line(&format!("{technique} on {backend}: {e}")));
        }
    };
    for (&azimuth, camera) in views.iter().zip(&cameras) {
        for backend in &prepared.backends {
            let name = backend.name();
            bar.set_message(format!("{azimuth:.1}° reference on {name}"));
            let reference =
                match backend.render(&prepared.scene, camera, &prepared.with_technique(Technique::Reference))
                {
                    Ok(frame) => frame,
                    Err(e) => {
                        report(&bar, "reference", name, &e);
                        bar.inc(per_view / prepared.backends.len() as u64);
                        continue;
                    }
                };
            bar.inc(1);
            for &technique in &techniques {
                let label = technique.to_string();
                bar.set_message(format!("{azimuth:.1}° {label} on {name}"));
                let result = backend
                    .render(&prepared.scene, camera, &prepared.with_technique(technique))
                    .and_then(|frame| Ok((accuracy(&reference, &frame.image)?, frame)));
                bar.inc(1);
                match result {
                    Ok((acc, frame)) => records.push(Record {
                        azimuth,
                        technique: label,
                        backend: name.to_string(),
                        epr: acc.epr,
                        lost: frame.stats.lost,
                        wall_ms: frame.stats.wall_ms,
                    }),
                    Err(e) => report(&bar, &label, name, &e),
                }
            }
        }
    }
    bar.finish_and_clear();

    if let Some(path) = &args.plot {
        plot::epr_plot(path, &records, &args.scene.scene, prepared.view.elevation)?;
    }
    if args.json {
        output::print_json(&records)?;
    } else {
        output::print(&summary(
            &records,
            &techniques,
            &prepared.backends.iter().map(|b| b.name()).collect::<Vec<_>>(),
        ))?;
        if let Some(path) = &args.plot {
            output::print(&format!("wrote {}\n", path.display()))?;
        }
    }
    if !failed.is_empty() {
        output::error_line(&format!("{} technique(s) failed and are left out of the results", failed.len()));
        return Ok(Outcome::Failed);
    }
    Ok(Outcome::Success)
}

/// The summary table: one row per technique and backend that has records.
fn summary(records: &[Record], techniques: &[Technique], backends: &[&str]) -> String {
    let (table, mut text) = Table::new(
        &[
            ("technique", 10),
            ("backend", 7),
            ("views", 5),
            ("mean EPR (%)", 8),
            ("max EPR (%)", 8),
            ("mean lost", 9),
            ("mean ms", 8),
        ],
        2,
    );
    let mut seen = Vec::new();
    for technique in techniques.iter().map(ToString::to_string) {
        for &backend in backends {
            if seen.contains(&(technique.clone(), backend)) {
                continue;
            }
            seen.push((technique.clone(), backend));
            let rows: Vec<&Record> =
                records.iter().filter(|r| r.technique == technique && r.backend == backend).collect();
            if rows.is_empty() {
                continue;
            }
            let n = rows.len() as f64;
            let mean = |f: fn(&Record) -> f64| rows.iter().map(|r| f(r)).sum::<f64>() / n;
            let max_epr = rows.iter().map(|r| r.epr).fold(0.0, f64::max);
            text.push_str(&table.row(&[
                technique.clone(),
                backend.to_string(),
                rows.len().to_string(),
                output::percent(mean(|r| r.epr)),
                output::percent(max_epr),
                format!("{:.1}", mean(|r| r.lost as f64)),
                format!("{:.2}", mean(|r| r.wall_ms)),
            ]));
        }
    }
    text
}
