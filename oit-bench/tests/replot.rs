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
