//! Writing a [`Report`]: the plots, `report.json` (everything) and `report.md` (tables, plots,
//! the model, the matrix, and what each number means).

use std::fmt::Write as _;
use std::path::Path;

use oit_core::OitError;

use crate::model::Prediction;
use crate::plot::{Chart, Series};
use crate::{CurvePoint, Report, Row, Spread, pareto_front};

/// Where an EPR of 0 is drawn on the trade plot's log axis at most, in per cent (lower when a
/// real EPR is lower): a log axis has no 0.
const EPR_FLOOR_PERCENT: f64 = 1e-3;

/// A file-name-safe form of a scene name: path folders and `.obj` dropped, the rest
/// alphanumerics and `-`.
fn slug(name: &str) -> String {
    let parts: Vec<String> = name
        .split(':')
        .map(|p| {
            let last = p.rsplit(['/', '\\']).next().unwrap_or(p);
            let last = last.strip_suffix(".obj").unwrap_or(last);
            last.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect()
        })
        .collect();
    parts.join("-")
}

fn bytes(n: u64) -> String {
    const UNITS: [&str; 4] = ["B", "KiB", "MiB", "GiB"];
    let mut v = n as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 { format!("{n} B") } else { format!("{v:.1} {}", UNITS[unit]) }
}

/// A fraction in per cent, without the sign: the columns' headers say `(%)`; `n/a` for the NaN
/// of a frame that covered no pixel (an EPR of nothing is no score, least of all 0).
fn percent(f: f64) -> String {
    if f.is_nan() {
        "n/a".into()
    } else if f == 0.0 {
        "0".into()
    } else {
        format!("{:.3}", f * 100.0)
    }
}

/// A row's PSNR cell: `n/a` where nothing was covered (its EPR is NaN), `inf` where identical.
fn psnr_cell(r: &Row) -> String {
    match r.psnr {
        _ if r.epr.is_nan() => "n/a".into(),
        None => "inf".into(),
        Some(p) => format!("{p:.1}"),
    }
}

fn ms(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

fn row_label(r: &Row) -> String {
    if r.raster == r.backend { r.backend.clone() } else { format!("{}/{}", r.backend, r.raster) }
}

/// Which of `spreads` (label, spread) is faster with the spread supporting it: the one whose slowest
/// frame beats every other's fastest frame; `None` where the ranges overlap (no ordering claimed).
pub fn separated_fastest<'a>(spreads: &[(&'a str, &Spread)]) -> Option<&'a str> {
    let (best, s) = spreads.iter().min_by(|a, b| a.1.median.total_cmp(&b.1.median))?;
    let clear = spreads.iter().filter(|(l, _)| l != best).all(|(_, o)| s.max < o.min);
    (clear && spreads.len() > 1).then_some(*best)
}

/// Per technique, its time on each backend/path side by side (median, then min–max of the timed
/// frames: GPU time where measured, wall time otherwise, and wall time beside it), and which is
/// faster only where the ranges do not overlap.
fn side_by_side(w: &mut String, report: &Report, scene: &str) {
    let rows: Vec<&Row> = report.rows.iter().filter(|r| r.scene == scene).collect();
    let mut labels: Vec<String> = Vec::new();
    for r in &rows {
        let l = row_label(r);
        if !labels.contains(&l) {
            labels.push(l);
        }
    }
    if labels.len() < 2 {
        return;
    }
    let range = |s: &Spread| format!("{} ({}–{})", ms(s.median), ms(s.min), ms(s.max));
    let _ = writeln!(
        w,
        "\nSide by side: per backend/path, GPU ms where measured and steady-state wall ms (no image \
         readback; wall ms with the readback where the steady state was not measured), median of \
         the timed frames, then min–max. *faster* names a backend/path only where its slowest frame beats \
         every other's fastest (GPU time where all have it, else wall): overlapping ranges support \
         no ordering.\n"
    );
    let mut head = "| technique | lost | EPR (%) |".to_string();
    for l in &labels {
        let _ = write!(head, " {l} GPU ms | {l} steady wall ms |");
    }
    let _ = writeln!(w, "{head} faster |");
    let _ = writeln!(w, "|---|---|---|{}---|", "---|---|".repeat(labels.len()));
    let mut techniques: Vec<&str> = Vec::new();
    for r in &rows {
        if !techniques.contains(&r.technique.as_str()) {
            techniques.push(&r.technique);
        }
    }
    for t in techniques {
        let mine: Vec<&&Row> = rows.iter().filter(|r| r.technique == t).collect();
        let first = mine[0];
        let mut line = format!("| {t} | {} | {} |", first.lost, percent(first.epr));
        for l in &labels {
            match mine.iter().find(|r| row_label(r) == *l) {
                Some(r) => {
                    let gpu = r.gpu_ms.as_ref().map_or("-".into(), range);
                    let _ =
                        write!(line, " {gpu} | {} |", range(r.steady_wall_ms.as_ref().unwrap_or(&r.wall_ms)));
                }
                None => line.push_str(" - | - |"),
            }
        }
        let all_gpu = mine.iter().all(|r| r.gpu_ms.is_some());
        let labelled: Vec<(String, &Spread)> = mine
            .iter()
            .map(|r| {
                (row_label(r), if all_gpu { r.gpu_ms.as_ref().unwrap_or(&r.wall_ms) } else { &r.wall_ms })
            })
            .collect();
        let spreads: Vec<(&str, &Spread)> = labelled.iter().map(|(l, s)| (l.as_str(), *s)).collect();
        let verdict = separated_fastest(&spreads).unwrap_or("overlap");
        let _ = writeln!(line, " {verdict} |");
        w.push_str(&line);
    }
}

/// Reads the `report.json` that [`write_report`] wrote into `dir`, to draw it again (`oit bench
/// --replot DIR`) without measuring again.
pub fn read_report(dir: &Path) -> Result<Report, OitError> {
    let path = dir.join("report.json");
    let io = |source| OitError::Io { path: path.clone(), source };
    // a FIFO or device in its place is refused before it is opened for reading (it would block)
    let Some((file, _)) = oit_core::open_regular(&path).map_err(io)? else {
        return Err(OitError::InvalidSettings(format!(
            "{} is not a regular file (a pipe, device or folder): --replot reads the report.json `oit bench` wrote",
            path.display()
        )));
    };
    let mut text = String::new();
    std::io::Read::read_to_string(&mut std::io::Read::take(file, MAX_REPORT_BYTES + 1), &mut text)
        .map_err(io)?;
    if text.len() as u64 > MAX_REPORT_BYTES {
        return Err(OitError::InvalidSettings(format!(
            "{} is over {MAX_REPORT_BYTES} bytes: not a report oit bench writes",
            path.display()
        )));
    }
    let report: Report = serde_json::from_str(&text).map_err(|e| {
        OitError::InvalidSettings(format!("{} is not an oit bench report: {e}", path.display()))
    })?;
    check_numbers(&report).map_err(|e| {
        OitError::InvalidSettings(format!(
            "{}: {e}; the file is damaged or was not written by oit bench (run the bench again)",
            path.display()
        ))
    })?;
    Ok(report)
}

/// The largest report.json `--replot` reads: 1 GiB (a report of every technique on a hundred
/// scenes is a few MiB).
const MAX_REPORT_BYTES: u64 = 1 << 30;

/// Longest time any report holds, in milliseconds: a day per frame is absurd already.
const MAX_MS: f64 = 86_400_000.0;

/// Largest count, rate or ratio a report holds (speedups, Gfrag/s, triangles).
const MAX_VALUE: f64 = 1e12;

/// Checks that `value` (at `at`) is finite and within `lo..=hi`, saying what it should be.
fn check(at: &str, value: f64, lo: f64, hi: f64, meaning: &str) -> Result<(), String> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(format!("{at} is {value:e}: {meaning} from {lo} to {hi:e}"))
    }
}

fn check_ms(at: &str, value: f64) -> Result<(), String> {
    check(at, value, 0.0, MAX_MS, "a time is milliseconds")
}

fn check_spread(at: &str, s: &Spread) -> Result<(), String> {
    for (name, v) in [("median", s.median), ("min", s.min), ("max", s.max), ("q1", s.q1), ("q3", s.q3)] {
        check_ms(&format!("{at}.{name}"), v)?;
    }
    // the quartiles are interpolated: allow their rounding, not a median outside the frames
    let slack = 1e-9 * s.max;
    let within = |v: f64| s.min - slack <= v && v <= s.max + slack;
    if s.min > s.max || ![s.q1, s.median, s.q3].into_iter().all(within) {
        return Err(format!(
            "{at} is out of order (min {:e}, q1 {:e}, median {:e}, q3 {:e}, max {:e}): a spread's values lie from its min up to its max",
            s.min, s.q1, s.median, s.q3, s.max
        ));
    }
    Ok(())
}

/// Every number of a report read back, checked: finite and within what a measurement can give,
/// so that a damaged file is a clear error instead of a plot with no end.
fn check_numbers(report: &Report) -> Result<(), String> {
    let size = f64::from(oit_core::MAX_SIZE);
    check("width", f64::from(report.width), 1.0, size, "an image side is pixels")?;
    check("height", f64::from(report.height), 1.0, size, "an image side is pixels")?;
    if let Some((w, h)) = report.curve_size {
        check("curve_size", f64::from(w.min(h)), 1.0, size, "an image side is pixels")?;
        check("curve_size", f64::from(w.max(h)), 1.0, size, "an image side is pixels")?;
    }
    let v = report.view;
    for (at, value) in [("view.azimuth", v.azimuth), ("view.elevation", v.elevation), ("view.fov", v.fov)] {
        check(at, f64::from(value), -1e6, 1e6, "an angle is degrees")?;
    }
    for (i, r) in report.rows.iter().enumerate() {
        let at = |field: &str| format!("rows[{i}].{field}");
        check_spread(&at("wall_ms"), &r.wall_ms)?;
        for (name, spread) in [
            ("gpu_ms", &r.gpu_ms),
            ("steady_wall_ms", &r.steady_wall_ms),
            ("latency_wall_ms", &r.latency_wall_ms),
            ("readback_wall_ms", &r.readback_wall_ms),
        ] {
            if let Some(s) = spread {
                check_spread(&at(name), s)?;
            }
        }
        check_ms(&at("time_ms"), r.time_ms)?;
        check(&at("gfrag_per_s"), r.gfrag_per_s, 0.0, MAX_VALUE, "a rate is")?;
        // NaN (null in the file): the frame covered no pixel, shown as n/a
        if !r.epr.is_nan() {
            check(&at("epr"), r.epr, 0.0, 1.0, "an error pixel rate is a fraction")?;
        }
        if let Some(p) = r.psnr {
            check(&at("psnr"), p, -1000.0, 1000.0, "a PSNR is decibels")?;
        }
        check(&at("max_diff"), f64::from(r.max_diff), 0.0, 255.0, "a difference is 8-bit steps")?;
        for (k, (_, ms)) in r.gpu_pass_ms.iter().enumerate() {
            check_ms(&at(&format!("gpu_pass_ms[{k}]")), *ms)?;
        }
    }
    for (i, p) in report.predictions.iter().enumerate() {
        let at = |field: &str| format!("predictions[{i}].{field}");
        check_ms(&at("predicted_ms"), p.predicted_ms)?;
        check_ms(&at("measured_ms"), p.measured_ms)?;
        check(&at("ratio"), p.ratio, 0.0, MAX_VALUE, "a ratio of times is")?;
        for (name, value) in
            [("predicted_speedup", p.predicted_speedup), ("measured_speedup", p.measured_speedup)]
        {
            if let Some(value) = value {
                check(&at(name), value, 0.0, MAX_VALUE, "a speedup is")?;
            }
        }
    }
    for (i, m) in report.model_summary.iter().enumerate() {
        let at = |field: &str| format!("model_summary[{i}].{field}");
        check(&at("median_error"), m.median_error, 0.0, MAX_VALUE, "a relative error is")?;
        check(&at("worst_error"), m.worst_error, 0.0, MAX_VALUE, "a relative error is")?;
        check(&at("worst_factor"), m.worst_factor, 1.0, MAX_VALUE, "a factor is")?;
    }
    for (i, st) in report.scene_stats.iter().enumerate() {
        let s = &st.stats;
        for (name, v) in [("triangles", s.triangles), ("pixels", s.pixels), ("fragments", s.fragments)] {
            check(&format!("scene_stats[{i}].{name}"), v as f64, 0.0, MAX_VALUE, "a count is")?;
        }
        if s.histogram.len() > 1 << 20 {
            return Err(format!(
                "scene_stats[{i}].histogram has {} bins: more layers than oit renders",
                s.histogram.len()
            ));
        }
    }
    for (i, m) in report.matrix.iter().enumerate() {
        if !m.epr.is_nan() {
            check(&format!("matrix[{i}].epr"), m.epr, 0.0, 1.0, "an error pixel rate is a fraction")?;
        }
        check(
            &format!("matrix[{i}].max_diff"),
            f64::from(m.max_diff),
            0.0,
            255.0,
            "a difference is 8-bit steps",
        )?;
        check(
            &format!("matrix[{i}].max_diff_off_edges"),
            f64::from(m.max_diff_off_edges),
            0.0,
            255.0,
            "a difference is 8-bit steps",
        )?;
    }
    for (i, p) in report.curves.iter().enumerate() {
        check(&format!("curves[{i}].x"), p.x, 1.0, MAX_VALUE, "a depth or triangle count is")?;
        check_ms(&format!("curves[{i}].time_ms"), p.time_ms)?;
    }
    Ok(())
}

/// Writes `report.json`, `report.md` and the plots into `dir` (made if missing), and records the
/// files written in `report.files`.
pub fn write_report(report: &mut Report, dir: &Path) -> Result<(), OitError> {
    let err = |path: &Path, e: &dyn std::fmt::Display| OitError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| err(dir, &e))?;
    let mut files = Vec::new();
    let mut draw = |chart: &Chart, stem: &str| -> Result<(), OitError> {
        for ext in ["svg", "png"] {
            let name = format!("{stem}.{ext}");
            let path = dir.join(&name);
            if ext == "svg" {
                chart.svg(&path)?
            } else {
                chart.png(&path)?
            }
            files.push(name);
        }
        Ok(())
    };

    // trade plots, one per scene
    let mut trade_plots = Vec::new();
    for (i, scene) in report.scenes.iter().enumerate() {
        // rows that covered no pixel have no EPR to draw (NaN): left out, not drawn as 0
        let rows: Vec<&Row> =
            report.rows.iter().filter(|r| r.scene == scene.name && !r.epr.is_nan()).collect();
        if rows.is_empty() {
            continue;
        }
        // EPR in per cent on the plot, as in the tables
        let pct = |r: &Row| r.epr * 100.0;
        let min_epr = rows.iter().map(|r| pct(r)).filter(|e| *e > 0.0).fold(f64::INFINITY, f64::min);
        let floor = if min_epr.is_finite() {
            EPR_FLOOR_PERCENT.min(10f64.powf((min_epr / 3.0).log10().floor()))
        } else {
            EPR_FLOOR_PERCENT
        };
        let mut labels: Vec<String> = Vec::new();
        for r in &rows {
            if !labels.contains(&row_label(r)) {
                labels.push(row_label(r));
            }
        }
        let mut series: Vec<Series> = labels
            .iter()
            .map(|l| {
                let mine: Vec<&&Row> = rows.iter().filter(|r| row_label(r) == *l).collect();
                Series {
                    name: l.clone(),
                    points: mine.iter().map(|r| (r.time_ms.max(1e-6), pct(r).max(floor))).collect(),
                    labels: mine.iter().map(|r| r.technique.clone()).collect(),
                    line: false,
                    markers: true,
                    color: None,
                }
            })
            .collect();
        let all: Vec<(f64, f64)> = rows.iter().map(|r| (r.time_ms.max(1e-6), pct(r).max(floor))).collect();
        let front: Vec<(f64, f64)> = pareto_front(&all).into_iter().map(|k| all[k]).collect();
        // a staircase: each front point holds its error until the next, faster-to-slower
        let mut stairs = Vec::new();
        for (k, p) in front.iter().enumerate() {
            if k > 0 {
                stairs.push((p.0, front[k - 1].1));
            }
            stairs.push(*p);
        }
        series.push(Series {
            name: "Pareto front".into(),
            points: stairs,
            labels: Vec::new(),
            line: true,
            markers: false,
            color: Some((0, 0, 0)),
        });
        let chart = Chart {
            title: format!("time vs error on {} ({}x{})", scene.name, report.width, report.height),
            x_desc: "time per frame (ms, log)".into(),
            y_desc: format!("EPR, % of covered pixels (log; EPR 0 drawn at {floor:e} %)"),
            x_log: true,
            y_log: true,
            series,
        };
        let stem = format!("trade-{i}-{}", slug(&scene.name));
        draw(&chart, &stem)?;
        trade_plots.push((scene.name.clone(), stem, floor));
    }

    // the curves
    let mut curve_plots = Vec::new();
    for (curve, x_desc) in
        [("depth", "depth complexity N of planes:N (log)"), ("triangles", "triangles (log)")]
    {
        let points: Vec<&CurvePoint> = report.curves.iter().filter(|p| p.curve == curve).collect();
        if points.is_empty() {
            continue;
        }
        let mut keys: Vec<(String, String)> = Vec::new();
        for p in &points {
            let k = (p.technique.clone(), p.backend.clone());
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        let several = keys.iter().any(|(_, b)| *b != keys[0].1);
        let series = keys
            .iter()
            .map(|(t, b)| {
                let mut pts: Vec<(f64, f64)> = points
                    .iter()
                    .filter(|p| p.technique == *t && p.backend == *b)
                    .map(|p| (p.x, p.time_ms.max(1e-6)))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Series {
                    name: if several { format!("{t} ({b})") } else { t.clone() },
                    labels: Vec::new(),
                    points: pts,
                    line: true,
                    markers: true,
                    color: None,
                }
            })
            .collect();
        let size = report.curve_size.unwrap_or((report.width, report.height));
        let title = match curve {
            "depth" => format!("time vs depth complexity (planes:N, {}x{})", size.0, size.1),
            _ => format!(
                "time vs triangles (grid:RxC:{}, {}x{})",
                report.curve_mesh.as_deref().unwrap_or("?"),
                size.0,
                size.1
            ),
        };
        let chart = Chart {
            title,
            x_desc: x_desc.into(),
            y_desc: "time per frame (ms, log)".into(),
            x_log: true,
            y_log: true,
            series,
        };
        let stem = format!("curve-{curve}");
        draw(&chart, &stem)?;
        curve_plots.push((curve, stem));
    }
    // the model: predicted against measured, log–log, the diagonal drawn
    let mut model_plot = None;
    if !report.predictions.is_empty() {
        draw(&model_chart(report), "model")?;
        model_plot = Some("model".to_string());
    }
    report.files = files;
    report.files.push("report.json".into());
    report.files.push("report.md".into());

    let json = serde_json::to_string_pretty(&report).map_err(|e| err(&dir.join("report.json"), &e))?;
    std::fs::write(dir.join("report.json"), json + "\n").map_err(|e| err(&dir.join("report.json"), &e))?;
    let md = markdown(report, &trade_plots, &curve_plots, model_plot.as_deref());
    std::fs::write(dir.join("report.md"), md).map_err(|e| err(&dir.join("report.md"), &e))?;
    Ok(())
}

fn markdown(
    report: &Report,
    trade: &[(String, String, f64)],
    curves: &[(&str, String)],
    model_plot: Option<&str>,
) -> String {
    let mut md = String::new();
    let w = &mut md;
    let _ = writeln!(w, "# oit bench\n");
    let _ = writeln!(w, "```sh\n{}\n```\n", report.command_line);
    let _ = writeln!(w, "- host: {}", report.host);
    for b in &report.backends {
        let _ = writeln!(w, "- backend `{}`: {}", b.label, b.device);
    }
    let _ = writeln!(
        w,
        "- {}×{} pixels, camera azimuth {}°, elevation {}°, field of view {}°",
        report.width, report.height, report.view.azimuth, report.view.elevation, report.view.fov
    );
    let _ = writeln!(
        w,
        "- per run: {} untimed warm-up frames{}, then {} timed frames",
        report.warmup,
        if report.warmup_ms > 0 {
            format!(" and {} ms of untimed frame loops", report.warmup_ms)
        } else {
            String::new()
        },
        report.frames
    );
    if report.frames < 10 {
        let _ = writeln!(w, "- **fewer than 10 timed frames: medians and spreads are rough**");
    }
    let _ = writeln!(w, "\n## What the numbers mean\n");
    let _ = writeln!(
        w,
        "- **passes**: geometry passes per frame (bounds, histogram, sizing and peel passes all count; \
         a frame run in screen tiles under `--memory` counts every tile's, and says how many tiles).\n\
         - **fragments**: fragments one geometry pass generates for the scene; **lost**: those that \
         did not reach the composite (collisions, overflow, coplanar ties); **tied**: those that \
         did, but tie in depth with another colour that the technique ordered by colour, not by \
         primitive as the reference; **storage**: per-pixel storage the technique allocated.\n\
         - **steady wall ms**: wall time per steady-state frame: the same prepared scene after the \
         warm-up in a frame loop, each frame's counters read back, not its image, the time between \
         one frame's completion and the next's (`Prepared::frame_loop`, which keeps two frames in \
         flight on wgpu: the host records one while the device runs the other; median of the \
         timed frames, then min–max): what a frame loop that presents on the device waits per \
         frame. **latency ms**: the same frame rendered on its own and waited for before the next \
         starts (`Prepared::frame_stats`; `latency_wall_ms` in report.json). **wall ms + readback**: the same frame with its image \
         read back to the host (`Prepared::frame`; `readback_wall_ms`, and `wall_ms`, in \
         report.json). **GPU ms**: the sum of the frame's GPU timestamp intervals (device time, no \
         readbacks or pipeline creation), where the backend has timestamps.\n\
         - **time**: GPU ms where measured, else wall ms. It is what the plots, Gfrag/s and the model use.\n\
         - **Gfrag/s**: scene fragments resolved per second, `fragments / time` (one pass's \
         fragments, whatever the passes: the rate at which the technique turns the scene into a picture).\n\
         - **EPR**: error pixel rate, the share of covered pixels whose 8-bit colour differs from \
         the same backend/path's `reference` by more than 1 in any channel, in per cent in these \
         tables and plots (`report.json`'s `epr` holds the fraction, 0 to 1); **PSNR** over covered \
         pixels (`inf` when identical); both `n/a` for a frame that covered no pixel (`null` in \
         report.json; left out of the trade plot); **max diff**: the largest channel difference in 8-bit steps."
    );

    for scene in &report.scenes {
        let _ = writeln!(w, "\n## {}\n", scene.name);
        let _ = writeln!(
            w,
            "{} triangles, {} fragments per pass, deepest pixel {} layers.\n",
            scene.triangles,
            scene.fragments.map_or("?".into(), |f| f.to_string()),
            scene.max_depth.map_or("?".into(), |f| f.to_string())
        );
        // the depth complexity, compactly: the first reference's layers per pixel
        if let Some(row) = report.scene_stats.iter().find(|r| r.scene == scene.name) {
            let depth = oit_core::metrics::DepthComplexity {
                histogram: row.stats.histogram.clone(),
                max_depth: row.stats.deepest(),
            };
            let _ = writeln!(w, "Depth complexity ({}): {}.\n", row.backend, depth.summary());
        }
        let _ = writeln!(
            w,
            "| technique | backend | raster | passes | fragments | lost | tied | storage | GPU ms (min–max) | steady wall ms (min–max) | latency ms (min–max) | wall ms + readback (min–max) | Gfrag/s | EPR (%) | PSNR (dB) |"
        );
        let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for r in report.rows.iter().filter(|r| r.scene == scene.name) {
            let gpu = r
                .gpu_ms
                .as_ref()
                .map_or("-".into(), |g| format!("{} ({}–{})", ms(g.median), ms(g.min), ms(g.max)));
            let spread = |s: &Spread| format!("{} ({}–{})", ms(s.median), ms(s.min), ms(s.max));
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.3} | {} | {} |",
                r.technique,
                r.backend,
                r.raster,
                if r.tiles > 1 { format!("{} ({} tiles)", r.passes, r.tiles) } else { r.passes.to_string() },
                r.fragments,
                r.lost,
                r.tied,
                bytes(r.storage_bytes),
                gpu,
                r.steady_wall_ms.as_ref().map_or("-".into(), spread),
                r.latency_wall_ms.as_ref().map_or("-".into(), spread),
                spread(r.readback_wall_ms.as_ref().unwrap_or(&r.wall_ms)),
                r.gfrag_per_s,
                percent(r.epr),
                psnr_cell(r),
            );
        }
        side_by_side(w, report, &scene.name);
        if let Some((_, stem, floor)) = trade.iter().find(|(s, _, _)| *s == scene.name) {
            let _ = writeln!(
                w,
                "\nTime against error, both log axes, one point per technique and backend/path; the \
                 black staircase is the Pareto front (no other point is both faster and more \
                 accurate). EPR 0 is drawn at {floor:e} %. ([SVG]({stem}.svg), [PNG]({stem}.png))\n\n![trade plot]({stem}.svg)"
            );
        }
    }

    model_section(w, report, model_plot);

    let _ = writeln!(w, "\n## Cross-backend matrix\n");
    let _ = writeln!(
        w,
        "Per technique, every pair of backend/paths on the same scene and view: the largest 8-bit \
         channel difference between their images, the same off projected triangle edges, and the \
         share of pixels (covered by the first's reference) that differ by more than 1. Each pair \
         is held to the conformance bounds: at most 1 step anywhere between paths that share oit's \
         fixed-point rules (cpu, compute), at most 1 off the edges where a hardware rasterizer is \
         one side; a pair that breaks its bound is a failure of the run.\n"
    );
    if report.matrix.is_empty() {
        let _ = writeln!(w, "(one backend/path only: nothing to compare)");
    } else {
        let _ = writeln!(w, "| scene | technique | a | b | max diff | off edges | EPR (%) | held |");
        let _ = writeln!(w, "|---|---|---|---|---|---|---|---|");
        for m in &report.matrix {
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} | {} | {} | {} | {} |",
                m.scene,
                m.technique,
                m.a,
                m.b,
                m.max_diff,
                m.max_diff_off_edges,
                percent(m.epr),
                match (&m.note, m.failed) {
                    (_, true) => "**FAILED**".to_string(),
                    (Some(note), false) => note.clone(),
                    (None, false) => "yes".to_string(),
                }
            );
        }
    }

    if !curves.is_empty() {
        let (cw, ch) = report.curve_size.unwrap_or((report.width, report.height));
        let _ = writeln!(w, "\n## Curves\n");
        let _ = writeln!(
            w,
            "Time per frame ({cw}×{ch}, median of the timed frames after one untimed) against depth \
             complexity (`planes:N`: N overlapping quads, N layers everywhere) and against triangle \
             count (`grid:RxC:{}`: R×C overlapping copies of the mesh).\n",
            report.curve_mesh.as_deref().unwrap_or("?")
        );
        for (curve, stem) in curves {
            let _ = writeln!(w, "![{curve} curve]({stem}.svg) ([SVG]({stem}.svg), [PNG]({stem}.png))\n");
            let _ = writeln!(w, "| scene | x | technique | backend | passes | fragments | time ms |");
            let _ = writeln!(w, "|---|---|---|---|---|---|---|");
            for p in report.curves.iter().filter(|p| p.curve == *curve) {
                let _ = writeln!(
                    w,
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    p.scene,
                    p.x,
                    p.technique,
                    p.backend,
                    p.passes,
                    p.fragments,
                    ms(p.time_ms)
                );
            }
            let _ = writeln!(w);
        }
    }

    if !report.failures.is_empty() {
        let _ = writeln!(w, "\n## Failures\n");
        let _ = writeln!(w, "| stage | scene | backend | technique | error |");
        let _ = writeln!(w, "|---|---|---|---|---|");
        for f in &report.failures {
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} | {} |",
                f.stage,
                f.scene,
                f.backend,
                f.technique,
                f.error.replace('|', "\\|").replace('\n', " ")
            );
        }
    }
    let _ = writeln!(
        w,
        "\nEverything above, and more (quartiles, captured counts), is in [report.json](report.json)."
    );
    md
}

/// Predicted against measured time, both log axes: per backend/path the unseen scenes (labelled
/// by technique) and the calibration scenes, the diagonal, and the 2× band around it.
fn model_chart(report: &Report) -> Chart {
    let mut backends: Vec<&str> = Vec::new();
    for p in &report.predictions {
        if !backends.contains(&p.backend.as_str()) {
            backends.push(&p.backend);
        }
    }
    let mut series = Vec::new();
    for b in backends {
        for calibration in [false, true] {
            let mine: Vec<&Prediction> = report
                .predictions
                .iter()
                .filter(|p| p.backend == b && p.calibration_scene == calibration)
                .collect();
            if mine.is_empty() {
                continue;
            }
            series.push(Series {
                name: format!(
                    "{b}{}",
                    if calibration { " (calibration scenes)" } else { " (unseen scenes)" }
                ),
                points: mine.iter().map(|p| (p.measured_ms.max(1e-6), p.predicted_ms.max(1e-6))).collect(),
                labels: if calibration {
                    Vec::new()
                } else {
                    mine.iter().map(|p| p.technique.clone()).collect()
                },
                line: false,
                markers: true,
                color: None,
            });
        }
    }
    let all = report.predictions.iter().flat_map(|p| [p.measured_ms, p.predicted_ms]).filter(|v| *v > 0.0);
    let (lo, hi) = all.fold((f64::INFINITY, 0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (lo, hi) = if lo.is_finite() { (lo / 2.0, hi * 2.0) } else { (0.1, 10.0) };
    for (name, factor, color) in [
        ("predicted = measured", 1.0, (0, 0, 0)),
        ("2× off", 2.0, (170, 170, 170)),
        ("", 0.5, (170, 170, 170)),
    ] {
        series.push(Series {
            name: name.into(),
            points: vec![(lo, lo * factor), (hi, hi * factor)],
            labels: Vec::new(),
            line: true,
            markers: false,
            color: Some(color),
        });
    }
    Chart {
        title: format!("the cost model: predicted vs measured time ({}x{})", report.width, report.height),
        x_desc: "measured time per frame (ms, log)".into(),
        y_desc: "predicted time per frame (ms, log)".into(),
        x_log: true,
        y_log: true,
        series,
    }
}

/// The model's section of report.md: the check per backend/path, then every prediction.
fn model_section(w: &mut String, report: &Report, plot: Option<&str>) {
    let _ = writeln!(w, "\n## The cost model\n");
    let _ = writeln!(
        w,
        "Each technique's time predicted before it runs, from a per backend/path calibration \
         (`oit bench --calibrate`, procedural scenes only) and the scene's statistics (triangles, \
         pixels, fragments per pass, the depth histogram of the reference's layers per pixel): \
         `time ≈ a·passes·triangles + b·passes·fragments + c·passes·pixels + d·Σ f(layers) + e` \
         (oit-bench's `model` module documents the terms and units). **passes**: the plan's \
         prediction from the deepest pixel N (the run's count in brackets where it differs); \
         **ratio** = measured / predicted; **K** = dp's predicted time / the technique's (the depth-peeling \
         speedup model's `N·Tv/(Tv+Tf)`, where dp is N+1 passes of Tv), beside dp's measured time / the technique's. \
         The check counts only the scenes the model was not calibrated on.\n"
    );
    if report.predictions.is_empty() {
        let _ = writeln!(
            w,
            "(no calibration loaded for these backend/paths: run `oit bench --calibrate`, then `oit \
             bench --model FILE`; the cpu backend loads `bench/results/cpu/calibration.json` by default)"
        );
        return;
    }
    if let Some(source) = &report.model_source {
        let _ = writeln!(w, "Model: {source}.\n");
    }
    if !report.model_summary.is_empty() {
        let _ = writeln!(
            w,
            "| backend | predictions (unseen scenes) | median \\|pred − meas\\| / meas | worst technique | its error | worst factor off | targets (median ≤ 20 %, none > 2×) |"
        );
        let _ = writeln!(w, "|---|---|---|---|---|---|---|");
        for m in &report.model_summary {
            let _ = writeln!(
                w,
                "| {} | {} | {:.1} % | {} | {:.1} % | {:.2}× | {} |",
                m.backend,
                m.predictions,
                m.median_error * 100.0,
                m.worst_technique,
                m.worst_error * 100.0,
                m.worst_factor,
                if m.within_targets { "met" } else { "**missed**" }
            );
        }
        let _ = writeln!(w);
    } else {
        let _ = writeln!(w, "(every scene here was a calibration scene: nothing to check)\n");
    }
    if let Some(stem) = plot {
        let _ = writeln!(
            w,
            "Predicted against measured, log–log: the black line is a perfect prediction, the grey ones \
             2× off. ([SVG]({stem}.svg), [PNG]({stem}.png))\n\n![the cost model]({stem}.svg)\n"
        );
    }
    let _ = writeln!(
        w,
        "| scene | backend | technique | N | passes | predicted ms | measured ms | ratio | K predicted | K measured |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|---|");
    for p in &report.predictions {
        let passes = if p.measured_passes == p.passes || p.measured_passes == 0 {
            p.passes.to_string()
        } else {
            format!("{} ({})", p.passes, p.measured_passes)
        };
        let _ = writeln!(
            w,
            "| {}{} | {} | {} | {} | {} | {} | {} | {:.2} | {} | {} |",
            p.scene,
            if p.calibration_scene { " (calibration)" } else { "" },
            p.backend,
            p.technique,
            p.n,
            passes,
            ms(p.predicted_ms),
            ms(p.measured_ms),
            p.ratio,
            p.predicted_speedup.map_or("-".into(), |v| format!("{v:.2}")),
            p.measured_speedup.map_or("-".into(), |v| format!("{v:.2}")),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::{Spread, separated_fastest, slug};

    #[test]
    fn an_ordering_only_where_the_spreads_separate() {
        let s = |min, median, max| Spread { median, min, max, q1: median, q3: median, samples: 10 };
        let (a, b, c) = (s(1.0, 1.1, 1.2), s(1.3, 1.4, 1.5), s(1.15, 1.3, 1.6));
        assert_eq!(separated_fastest(&[("a", &a), ("b", &b)]), Some("a"));
        assert_eq!(separated_fastest(&[("b", &b), ("a", &a)]), Some("a"));
        assert_eq!(
            separated_fastest(&[("a", &a), ("c", &c)]),
            None,
            "a's slowest is slower than c's fastest"
        );
        assert_eq!(separated_fastest(&[("a", &a)]), None, "one alone is no ordering");
    }

    #[test]
    fn slugs() {
        assert_eq!(slug("grid:4x4:bunny"), "grid-4x4-bunny");
        assert_eq!(slug("meshes/scans/bunny.obj"), "bunny");
        assert_eq!(slug("grid:2x2:../m/armadillo.obj"), "grid-2x2-armadillo");
    }
}
