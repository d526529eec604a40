//! `oit sweep`: the camera once around the scene, every technique against the reference at each
//! view.

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use oit_bench::experiment::{Experiment, Step};
use oit_core::{OitError, Technique, View};

use crate::Outcome;
use crate::options::{Prepared, SceneArgs, check_output};
use crate::output::{self, Table};
use crate::plot::{self, Record};

/// Most views a sweep takes (one per 0.01°).
const MAX_VIEWS: u32 = 36_000;

/// Arguments of `oit sweep`.
#[derive(Args, Debug)]
#[command(
    about = "Orbit the camera around the scene and measure techniques at every view",
    long_about = "Orbit the camera around the scene and measure techniques at every view.\n\n\
        Takes N views at evenly spaced azimuths from 0 to 360 degrees (the elevation stays at \
        --elevation; --azimuth is not used). At each view renders the reference and every \
        technique on every backend (and raster path), and records the error pixel rate (EPR: the \
        share of covered pixels off by more than 1 in 8 bits), PSNR, fragments lost and time. \
        Prints a summary per technique, backend and raster path (mean and max EPR in per cent, \
        mean lost, mean time), or with --json a JSON array of every record ({azimuth, technique, \
        backend, raster, geometry_passes, fragments, captured, merged, lost, tied, storage_bytes, \
        tiles, wall_ms, gpu_ms, epr, psnr, max_error}; epr is a fraction in [0, 1], not per cent) and \
        nothing else. A progress bar goes to stderr. A technique that fails is reported once \
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

    /// Also draw EPR per view (in per cent, log axis) for each technique, as an SVG, or a PNG
    /// when FILE ends in .png [default: none].
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    pub plot: Option<PathBuf>,

    #[command(flatten)]
    pub scene: SceneArgs,
}

/// Every check `oit sweep` makes before it renders: the technique list, the view count, the
/// plot's path, then the scene options ([`SceneArgs::prepare`]). Reads, writes nothing.
pub fn check(args: &SweepArgs) -> Result<(Vec<Technique>, Prepared), OitError> {
    let techniques = Technique::parse_list(&args.techniques)?;
    if !(1..=MAX_VIEWS).contains(&args.views) {
        return Err(OitError::InvalidSettings(format!(
            "--views {} is out of range: use 1 to {MAX_VIEWS}",
            args.views
        )));
    }
    if let Some(path) = &args.plot {
        // an SVG, or a PNG when the name says so
        let is = |ext: &str| path.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext));
        if !is("svg") && !is("png") {
            return Err(OitError::Write {
                path: path.clone(),
                message: "--plot must name a .svg or .png file".into(),
            });
        }
        check_output(path, if is("png") { "png" } else { "svg" }, "--plot")?;
    }
    Ok((techniques, args.scene.prepare()?))
}

/// Runs `oit sweep`.
pub fn run(args: &SweepArgs) -> Result<Outcome, OitError> {
    let (techniques, prepared) = check(args)?;
    let views: Vec<View> = (0..args.views)
        .map(|i| View { azimuth: (f64::from(i) * 360.0 / f64::from(args.views)) as f32, ..prepared.view })
        .collect();
    let experiment = Experiment {
        backends: &prepared.backends,
        settings: &prepared.settings,
        techniques: &techniques,
        warmup: 0,
        warmup_ms: 0,
        frames: 1,
        keep_images: false,
    };

    let bar = ProgressBar::new(experiment.renders_per_view() * u64::from(args.views));
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} sweep [{bar:30}] {pos}/{len} renders, {elapsed} (eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    // (technique, backend/path) pairs that have failed, reported once each.
    let mut failed: Vec<(String, String)> = Vec::new();
    let measurements = experiment.run(&args.scene.scene, &prepared.scene, &views, &mut |step| match step {
        Step::Rendering(what) => bar.set_message(what.to_string()),
        Step::Measured(m) => {
            bar.inc(1);
            let Err(e) = &m.result else { return };
            if m.baseline {
                // the techniques of this view and backend are not rendered
                bar.inc(techniques.len() as u64);
            }
            let technique = if m.baseline { "reference".to_string() } else { m.technique.to_string() };
            let label = m.label();
            if !failed.iter().any(|(t, b)| *t == technique && *b == label) {
                bar.suspend(|| output::error_line(&format!("{technique} on {label}: {e}")));
                failed.push((technique, label));
            }
        }
    });
    bar.finish_and_clear();
    let records: Vec<Record> = measurements?
        .into_iter()
        .filter(|m| !m.baseline)
        .filter_map(|m| {
            let r = m.result.ok()?;
            let acc = r.accuracy?;
            Some(Record {
                azimuth: m.view.azimuth,
                technique: m.technique.to_string(),
                backend: m.backend,
                raster: m.raster.to_string(),
                stats: r.stats,
                epr: acc.epr,
                psnr: acc.psnr.is_finite().then_some(acc.psnr),
                max_error: acc.max_error,
            })
        })
        .collect();

    if let Some(path) = &args.plot {
        plot::epr_plot(path, &records, &args.scene.scene, prepared.view.elevation)?;
    }
    if args.json {
        output::print_json(&records)?;
    } else {
        output::print(&summary(&records, &techniques))?;
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

/// The summary table: one row per technique and backend/raster path that has records, in the
/// order of `techniques`, then of the backends and paths as first measured.
fn summary(records: &[Record], techniques: &[Technique]) -> String {
    let (table, mut text) = Table::new(
        &[
            ("technique", 10),
            ("backend", 7),
            ("raster", 8),
            ("views", 5),
            ("mean EPR (%)", 8),
            ("max EPR (%)", 8),
            ("mean lost", 9),
            ("mean ms", 8),
        ],
        3,
    );
    let mut seen: Vec<(String, String, String)> = Vec::new();
    for technique in techniques.iter().map(ToString::to_string) {
        for r in records.iter().filter(|r| r.technique == technique) {
            let key = (technique.clone(), r.backend.clone(), r.raster.clone());
            if seen.contains(&key) {
                continue;
            }
            let rows: Vec<&Record> = records
                .iter()
                .filter(|o| o.technique == key.0 && o.backend == key.1 && o.raster == key.2)
                .collect();
            let n = rows.len() as f64;
            let mean = |f: fn(&Record) -> f64| rows.iter().map(|r| f(r)).sum::<f64>() / n;
            // EPR over the views that covered a pixel (NaN: none covered); n/a when none did
            let eprs: Vec<f64> = rows.iter().map(|r| r.epr).filter(|e| !e.is_nan()).collect();
            let (mean_epr, max_epr) = if eprs.is_empty() {
                (f64::NAN, f64::NAN)
            } else {
                (eprs.iter().sum::<f64>() / eprs.len() as f64, eprs.iter().copied().fold(0.0, f64::max))
            };
            text.push_str(&table.row(&[
                key.0.clone(),
                key.1.clone(),
                key.2.clone(),
                rows.len().to_string(),
                output::percent(mean_epr),
                output::percent(max_epr),
                format!("{:.1}", mean(|r| r.stats.lost as f64)),
                format!("{:.2}", mean(|r| r.stats.wall_ms)),
            ]));
            seen.push(key);
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use oit_core::Stats;

    use super::*;

    fn record(azimuth: f32, epr: f64) -> Record {
        Record {
            azimuth,
            technique: "dp".into(),
            backend: "cpu".into(),
            raster: "cpu".into(),
            stats: Stats::default(),
            epr,
            psnr: None,
            max_error: 0.0,
        }
    }

    #[test]
    fn views_that_cover_nothing_are_not_available_not_scores() {
        // Issue 41.4: a view that covers no pixel has a NaN EPR; the summary printed mean EPR
        // `NaN` and, when every view was empty, max EPR 0.000 (a perfect score). Mutations caught:
        // averaging over every view (NaN in the mean), folding the max from 0 over every view
        // (0.000 when all are empty), `output::percent` without its NaN arm.
        let techniques = Technique::parse_list("dp").unwrap();
        let all_empty = summary(&[record(0.0, f64::NAN), record(90.0, f64::NAN)], &techniques);
        let row = all_empty.lines().last().unwrap();
        assert!(row.contains("n/a") && !row.contains("NaN") && !row.contains("0.000"), "{row}");
        let some_empty = summary(&[record(0.0, f64::NAN), record(90.0, 0.5)], &techniques);
        let row = some_empty.lines().last().unwrap();
        // mean and max over the one view that covered pixels: 50 %
        assert_eq!(row.matches("50.000").count(), 2, "{row}");
        assert!(!row.contains("NaN") && !row.contains("n/a"), "{row}");
    }
}
