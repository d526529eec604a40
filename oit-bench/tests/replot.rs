//! `oit bench --replot` on reports that hold absurd numbers: drawing one ends (the plots clamp
//! their ranges), and reading one back is a clear error naming the number.

use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

use oit_bench::{Report, read_report, write_report};

/// A small report (one scene, two rows, two curve points) with `epr`, `time_ms` and `x` put in.
fn report(epr: f64, time_ms: f64, x: f64) -> Report {
    let row = |technique: &str, epr: f64, time_ms: f64| {
        serde_json::json!({
            "scene": "planes:4", "backend": "cpu", "raster": "cpu", "technique": technique,
            "passes": 5, "fragments": 1000, "captured": 1000, "lost": 0, "storage_bytes": 4096,
            "wall_ms": {"median": 1.0, "min": 1.0, "max": 1.0, "q1": 1.0, "q3": 1.0, "samples": 1},
            "gpu_ms": null, "time_ms": time_ms, "time_source": "wall", "gfrag_per_s": 1.0,
            "epr": epr, "psnr": null, "max_diff": 0
        })
    };
    let point = |x: f64, time_ms: f64| {
        serde_json::json!({
            "curve": "depth", "scene": "planes:1", "backend": "cpu", "technique": "dp",
            "x": x, "time_ms": time_ms, "passes": 2, "fragments": 10
        })
    };
    serde_json::from_value(serde_json::json!({
        "command_line": "replot test", "host": "test", "width": 32, "height": 32,
        "view": {"azimuth": 30.0, "elevation": 20.0, "fov": 45.0}, "warmup": 0, "frames": 1,
        "backends": [{"label": "cpu", "device": "test"}],
        "scenes": [{"name": "planes:4", "triangles": 8, "fragments": 1000, "max_depth": 4}],
        "rows": [row("dp", 0.0, 1.0), row("wavg", epr, time_ms)],
        "model": [], "matrix": [],
        "curves": [point(1.0, 1.0), point(x, time_ms)],
        "curve_mesh": "knot", "curve_size": [32, 32], "failures": [], "files": []
    }))
    .expect("a report")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("oit-replot-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn absurd_numbers_still_draw_and_end() {
    // each of these once made a plot's axis span hundreds of decades, and the drawing never ended
    for (epr, time_ms, x) in [(1e308, 1.0, 2.0), (0.1, 1e308, 2.0), (0.1, 1.0, 1e-308), (0.1, 1e-308, 1e308)]
    {
        let dir = scratch("draw");
        let (tx, rx) = mpsc::channel();
        let d = dir.clone();
        std::thread::spawn(move || {
            let mut r = report(epr, time_ms, x);
            tx.send(write_report(&mut r, &d).map(|()| r.files.len())).ok();
        });
        // lavapipe-free and tiny: a second is plenty; a minute means it hangs
        let files = rx
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|_| panic!("drawing epr {epr:e}, time {time_ms:e}, x {x:e} did not end"))
            .unwrap();
        assert!(files >= 6, "trade and depth plots, report.json and .md");
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn absurd_numbers_are_refused_when_read_back() {
    let dir = scratch("read");
    let mut good = report(0.1, 1.0, 2.0);
    write_report(&mut good, &dir).unwrap();
    assert_eq!(read_report(&dir).unwrap().rows.len(), 2);

    for (epr, time_ms, x, named) in [
        (1e308, 1.0, 2.0, "rows[1].epr"),
        (-0.5, 1.0, 2.0, "rows[1].epr"),
        (0.1, 1e308, 2.0, "rows[1].time_ms"),
        (0.1, 1.0, 1e300, "curves[1].x"),
        (0.1, 1.0, 0.0, "curves[1].x"),
    ] {
        let text = serde_json::to_string(&report(epr, time_ms, x)).unwrap();
        std::fs::write(dir.join("report.json"), text).unwrap();
        let message = read_report(&dir).expect_err(named).to_string();
        assert!(message.contains(named) && message.contains("report.json"), "{named}: {message}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_row_that_covered_nothing_round_trips_as_not_available() {
    // Issue 41.4: a frame that covers no pixel has no EPR (NaN, written `null`); the replot once
    // refused its own report ("invalid type: null, expected f64") and report.md printed PSNR
    // `inf`, a perfect score. Mutations caught: dropping `nan_if_null` from `Row::epr` (the read
    // fails), `check_numbers` checking a NaN EPR's range (the read fails), `psnr_cell` without
    // its NaN arm (`inf` in the row), `percent` without its NaN arm (`NaN` in the row).
    let dir = scratch("empty");
    let mut empty = report(f64::NAN, 1.0, 2.0);
    write_report(&mut empty, &dir).unwrap();
    let json = std::fs::read_to_string(dir.join("report.json")).unwrap();
    assert!(json.contains("\"epr\": null"), "the empty row's EPR is written as null");
    let again = read_report(&dir).expect("a report with an empty row reads back");
    assert!(again.rows[1].epr.is_nan() && again.rows[0].epr == 0.0);
    // and draws again (`--replot`), the empty row shown as n/a, never as a number
    let mut again = again;
    again.files.clear();
    write_report(&mut again, &dir).unwrap();
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let line = md.lines().find(|l| l.starts_with("| wavg | cpu |")).expect("the empty row's line");
    assert!(line.ends_with("| n/a | n/a |"), "{line}");
    assert!(!md.contains("NaN"), "{md}");
    read_report(&dir).expect("the redrawn report reads back too");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn every_timing_field_is_checked_when_read_back() {
    // Issue 41.4: ±1e308 in the steady, latency and readback wall times was accepted and printed
    // as 309-digit numbers. Mutation caught: leaving any of the three (or gpu_ms) out of
    // `check_numbers`' list of spreads; `check_spread` without its order check (the last case).
    let dir = scratch("timing");
    std::fs::create_dir_all(&dir).unwrap();
    let spread = |median: f64, min: f64, max: f64| serde_json::json!({"median": median, "min": min, "max": max, "q1": median, "q3": median, "samples": 3});
    for (field, value, named) in [
        ("steady_wall_ms", spread(1e308, 1e308, 1e308), "rows[1].steady_wall_ms.median"),
        ("latency_wall_ms", spread(-1e308, -1e308, -1e308), "rows[1].latency_wall_ms.median"),
        ("readback_wall_ms", spread(1.0, 1.0, 1e308), "rows[1].readback_wall_ms.max"),
        ("gpu_ms", spread(1.0, -1.0, 1.0), "rows[1].gpu_ms.min"),
        ("steady_wall_ms", spread(5.0, 1.0, 2.0), "rows[1].steady_wall_ms is out of order"),
    ] {
        let mut value_report = serde_json::to_value(report(0.1, 1.0, 2.0)).unwrap();
        value_report["rows"][1][field] = value;
        std::fs::write(dir.join("report.json"), value_report.to_string()).unwrap();
        let message = read_report(&dir).expect_err(named).to_string();
        assert!(message.contains(named) && message.contains("report.json"), "{named}: {message}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
