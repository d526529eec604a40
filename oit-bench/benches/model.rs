//! The cost model's check (issue 15, item 3), run by the bench crate: calibrate every backend /
//! raster path compiled in on the procedural calibration scenes only, then predict every
//! technique on scenes the calibration never saw (the built-in bunny and armadillo and
//! `grid:4x4:bunny`, and the procedural `knot`) and state the error: per
//! backend/path the median |predicted − measured| / measured, the worst technique and the largest
//! factor off, against the targets (median ≤ 20 %, none off by more than 2×).
//!
//! `cargo bench -p oit-bench --bench model` runs it at 256×256 with 3 timed frames a run (several
//! minutes on 2 cores); `cargo test` runs it in its small form (64×64, one frame, two calibration
//! scenes), which checks that the evaluation runs and produces a prediction for every unseen
//! technique, not that the small model is good: timing one frame of 64×64 is mostly noise.
//!
//! The same evaluation is in `oit bench` (`--model FILE`, or the shipped CPU calibration) and its
//! report; this bench is the one-command form that needs no calibration file.

use std::collections::BTreeMap;

use oit_bench::model::{self, ModelFile};
use oit_core::{Settings, Technique, View};

fn config(scenes: Vec<String>, size: u32, frames: u32, model: Option<ModelFile>) -> oit_bench::Config {
    oit_bench::Config {
        scenes,
        gltf_scene: None,
        backends: oit_bench::available_backends(),
        settings: Settings { width: size, height: size, ..Settings::default() },
        view: View::default(),
        techniques: Technique::all(),
        warmup: 1,
        warmup_ms: 0,
        frames,
        curves: None,
        command_line: "cargo bench -p oit-bench --bench model".into(),
        model,
        model_source: Some("calibrated by this bench on the procedural scenes".into()),
        blend_targets: Vec::new(),
    }
}

fn main() {
    // criterion's convention: `cargo bench` passes --bench, `cargo test` does not
    let full = std::env::args().any(|a| a == "--bench");
    let (size, frames, calibration, mut unseen): (u32, u32, Vec<String>, Vec<String>) = if full {
        let scenes = model::CALIBRATION_SCENES.split(',').map(str::to_string).collect();
        (256, 3, scenes, vec!["knot".into()])
    } else {
        (64, 1, vec!["planes:4".into(), "spheres:3".into()], vec!["knot".into()])
    };
    if full {
        unseen.extend(["bunny", "armadillo", "grid:4x4:bunny"].map(String::from));
    }

    let calibration_report = oit_bench::run_bench(&config(calibration.clone(), size, frames, None))
        .unwrap_or_else(|e| panic!("calibration runs: {e}"));
    let samples = oit_bench::samples(&calibration_report);
    let fitted = ModelFile {
        host: calibration_report.host.clone(),
        commit: model::commit(),
        command_line: calibration_report.command_line.clone(),
        scenes: calibration,
        frames,
        note: None,
        calibrations: model::calibrate(&samples, &BTreeMap::new(), (size, size)),
    };
    assert!(!fitted.calibrations.is_empty(), "the calibration fitted nothing");

    let report = oit_bench::run_bench(&config(unseen.clone(), size, frames, Some(fitted)))
        .unwrap_or_else(|e| panic!("unseen runs: {e}"));
    let predictions = &report.predictions;
    let summary = model::summarize(predictions);
    println!("cost model on scenes it was not calibrated on ({}), {size}x{size}:", unseen.join(", "));
    println!(
        "{:<18} {:>11} {:>13} {:>22} {:>12}",
        "backend/path", "predictions", "median error", "worst (technique)", "worst factor"
    );
    for s in &summary {
        println!(
            "{:<18} {:>11} {:>12.1}% {:>13.1}% ({:<6}) {:>11.2}x{}",
            s.backend,
            s.predictions,
            100.0 * s.median_error,
            100.0 * s.worst_error,
            s.worst_technique,
            s.worst_factor,
            if s.within_targets { "" } else { "  (targets missed: median <= 20 %, none over 2x)" }
        );
    }
    // every unseen technique on every backend/path that ran it got a prediction
    let runs = report.rows.iter().filter(|r| !r.technique.starts_with("reference")).count();
    assert_eq!(
        predictions.iter().filter(|p| !p.calibration_scene).count(),
        runs,
        "a run without a prediction: the model does not cover every technique it was calibrated for"
    );
    assert!(summary.iter().all(|s| s.median_error.is_finite() && s.worst_factor >= 1.0), "{summary:?}");
}
