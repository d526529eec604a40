//! `run_bench` end to end at 32×32 with 2 frames on planes:4, on every backend compiled in (wgpu
//! when an adapter is found): report.json parses and holds every technique, the plots exist.

use oit_bench::{Config, CurveConfig, available_backends, read_report, run_bench, write_report};
use oit_core::{Settings, Technique, View};

#[test]
fn report_holds_every_technique() {
    let backends = available_backends();
    let labels: Vec<String> =
        backends.iter().map(|b| oit_bench::label(b.as_ref(), &Settings::default())).collect();
    let techniques = Technique::all();
    let mut curves = CurveConfig::new("knot");
    curves.depths = vec![1, 2];
    curves.grids = vec![(1, 1)];
    curves.techniques = vec![Technique::Dp, Technique::Fabs { k: None }];
    curves.width = 32;
    curves.height = 32;
    curves.frames = 1;
    let config = Config {
        scenes: vec!["planes:4".into()],
        gltf_scene: None,
        backends,
        settings: Settings { width: 32, height: 32, ..Settings::default() },
        view: View::default(),
        techniques: techniques.clone(),
        warmup: 1,
        warmup_ms: 0,
        frames: 2,
        curves: Some(curves),
        command_line: "report test".into(),
        model: None,
        model_source: None,
        blend_targets: vec![oit_core::BlendTarget::F16, oit_core::BlendTarget::Unorm8],
    };
    let mut report = run_bench(&config).unwrap();
    assert!(report.failures.is_empty(), "{:?}", report.failures);
    // the cost model: the plan's passes are the run's, and a model fitted on this run predicts it
    // as its fit did (each prediction is the fitted value the model recorded for that run, beside
    // that run's time; fails where `predict` takes another technique's model, another scene's
    // statistics or another run's passes)
    assert_eq!(report.scene_stats.len(), labels.len());
    for r in report.rows.iter().filter(|r| r.backend == "cpu") {
        assert_eq!(r.model_passes, r.passes, "{}", r.technique);
    }
    let samples = oit_bench::samples(&report);
    assert_eq!(samples.len(), report.rows.len());
    let model = oit_bench::ModelFile {
        host: String::new(),
        commit: None,
        command_line: String::new(),
        scenes: vec!["planes:4".into()],
        frames: 2,
        note: None,
        calibrations: oit_bench::model::calibrate(&samples, &Default::default(), (32, 32)),
    };
    report.predictions = oit_bench::model::predict(&model, &samples);
    assert_eq!(report.predictions.len(), samples.len());
    for p in &report.predictions {
        assert!(p.calibration_scene, "{p:?}");
        let calibration = model.backend(&p.backend).expect("the backend was calibrated");
        let fitted = calibration.technique(&p.technique).expect("the technique was calibrated");
        let &(_, measured, fitted_ms) =
            fitted.residuals.iter().find(|(scene, _, _)| *scene == p.scene).expect("the scene was fitted");
        assert!(p.predicted_ms > 0.0 && p.predicted_ms == fitted_ms, "{p:?} against the fit's {fitted_ms}");
        assert_eq!(p.measured_ms, measured, "{p:?}");
    }
    let dir = std::env::temp_dir().join(format!("oit-bench-test-{}", std::process::id()));
    write_report(&mut report, &dir).unwrap();

    // `oit bench --replot` reads back what was written
    let again = read_report(&dir).unwrap();
    assert_eq!(again.rows.len(), report.rows.len());
    assert_eq!(again.curves.len(), report.curves.len());
    // serde_json's float parsing is not exactly round-trip (it can come back an ulp or so off)
    let (a, b) = (&again.rows[0].wall_ms, &report.rows[0].wall_ms);
    for (x, y) in [(a.median, b.median), (a.min, b.min), (a.max, b.max)] {
        assert!((x - y).abs() <= 1e-12 * y.abs().max(1.0), "{a:?} read back as {b:?}");
    }
    assert_eq!(a.samples, b.samples);

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    for label in &labels {
        for t in &techniques {
            let name = t.to_string();
            assert!(
                rows.iter().any(|r| r["technique"] == name.as_str()
                    && label.starts_with(r["backend"].as_str().unwrap())
                    && r["time_ms"].as_f64().unwrap() > 0.0),
                "no row for {name} on {label}"
            );
        }
    }
    // issue 10.6: every row has its steady-state wall time (a frame loop, no image readback), its
    // latency (one frame at a time) and its wall time with the readback
    for r in rows {
        for key in ["steady_wall_ms", "latency_wall_ms", "readback_wall_ms"] {
            assert!(r[key]["median"].as_f64().is_some_and(|ms| ms > 0.0), "{key} of {}", r["technique"]);
        }
    }
    // issue 10.5: where wavg ran on wgpu's hardware path, its blend capture ran beside it, with
    // the same error (the sums are equal below 2^24)
    let on = |backend: &str| {
        rows.iter().find(|r| r["technique"] == "wavg" && r["backend"] == backend && r["raster"] == "hardware")
    };
    if let Some(atomics) = on("wgpu") {
        let blend = on("wgpu+blend").expect("a wgpu+blend row for wavg");
        assert_eq!(blend["epr"], atomics["epr"]);
        assert_eq!(blend["fragments"], atomics["fragments"]);
    }
    // --blend-targets: the blender's techniques into RGBA16F and RGBA8 beside the default, the
    // same fragments, their error measured; wavg has no RGBA8 row (its sums leave [0, 1])
    let row = |technique: &str, backend: &str| {
        rows.iter()
            .find(|r| r["technique"] == technique && r["backend"] == backend && r["raster"] == "hardware")
    };
    if let Some(plain) = row("plain", "wgpu") {
        for (technique, backend) in [("plain", "wgpu+f16"), ("plain", "wgpu+unorm8"), ("wavg", "wgpu+f16")] {
            let r = row(technique, backend).unwrap_or_else(|| panic!("a {backend} row for {technique}"));
            assert_eq!(r["fragments"], plain["fragments"], "{backend} {technique}");
            assert!(r["epr"].as_f64().is_some_and(f64::is_finite), "{backend} {technique}");
        }
        assert!(row("wavg", "wgpu+unorm8").is_none());
    }
    // planes:4 is 4 layers deep: dp peels 4 and finds none left
    let dp = rows.iter().find(|r| r["technique"] == "dp").unwrap();
    assert_eq!(dp["passes"], 5);
    assert_eq!(dp["epr"], 0.0);
    assert!(!json["predictions"].as_array().unwrap().is_empty());
    assert_eq!(json["curves"].as_array().unwrap().len(), 3 * labels.len() * 2);
    for file in [
        "report.md",
        "trade-0-planes-4.svg",
        "trade-0-planes-4.png",
        "curve-depth.png",
        "curve-triangles.svg",
        "model.svg",
        "model.png",
    ] {
        assert!(dir.join(file).is_file(), "{file} missing");
    }
    std::fs::remove_dir_all(&dir).ok();
}
