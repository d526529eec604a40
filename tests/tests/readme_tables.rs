//! The figures of README.md and docs/ come from committed results, never typed by hand: each
//! table between a `<!-- table KIND FILE... key=value... -->` marker and the `<!-- /table -->`
//! after it is what this file writes from those files (report.json files of `oit bench` under
//! `bench/results/`, and `bench/results/cpu/builds/builds.json`), and the test fails where a
//! README or doc differs. To regenerate after a new run or a new marker:
//!
//! ```sh
//! OIT_WRITE_README=1 cargo test --release -p oit-tests --test readme_tables
//! ```
//!
//! Kinds ([`table`]):
//! - `trade REPORT scene=S [backend=B] [raster=R] [techniques=a,b] [time=readback|gpu]`: one
//!   backend's trade on one scene: passes, lost, storage, time, EPR, PSNR.
//! - `paths REPORT scene=S [backend=wgpu]`: the hardware and compute raster paths side by side,
//!   GPU and steady wall time, and which is faster where the ranges do not overlap.
//! - `scenes REPORT`: each scene's triangles, fragments and deepest pixel.
//! - `picks REPORT [backend=B] [raster=R] [time=readback|gpu]`: per scene, the fastest exact
//!   technique (EPR 0, nothing lost) and the fastest within 1 % EPR, by median time.
//! - `model REPORT...`: the cost model's error on the scenes it was not calibrated on.
//! - `overflow DROP_REPORT TAIL_REPORT [raster=R]`: `--overflow drop` against `--overflow tail`.
//! - `builds BUILDS_JSON`: each feature set's cold build time and binary size.
//!
//! A scene `S` matches a report's scene of that name, or a mesh path whose file is `S.obj` (the
//! older runs named the meshes by path).
//!
//! Beside the tables, [`no_hand_typed_measurements`] scans the prose of the README and docs for
//! a figure with a unit of measurement (`ms`, `%`, `MiB`, `dB`, a factor `1.5×`) outside a
//! generated table, a code block or inline code.
//!
//! Mutations that make it fail: edit any figure of a generated table by hand; commit a new
//! report.json without regenerating; type "12.4 ms" into the README's prose.

use std::path::{Path, PathBuf};

use serde_json::Value;

const OPEN: &str = "<!-- table ";
const CLOSE: &str = "<!-- /table -->";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ is in the workspace").to_path_buf()
}

/// README.md and every Markdown file under docs/, relative to the root.
fn documents() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> =
            std::fs::read_dir(dir).expect("docs/ is readable").map(|e| e.expect("entry").path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "md") {
                out.push(p);
            }
        }
    }
    let mut out = vec![root().join("README.md")];
    walk(&root().join("docs"), &mut out);
    out
}

fn read_json(path: &str) -> Value {
    let text = std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// A figure to three significant digits at most (`341`, `26.1`, `2.26`, `0.507`).
fn sig(x: f64) -> String {
    let a = x.abs();
    if a >= 100.0 {
        format!("{x:.0}")
    } else if a >= 10.0 {
        format!("{x:.1}")
    } else if a >= 1.0 || a == 0.0 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    }
}

/// An integer with thousands separators: `156,812`.
fn count(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A timing as `median (min–max)`, or "n/a" where the report has none.
fn spread(v: &Value) -> String {
    let f = |k: &str| v[k].as_f64();
    match (f("median"), f("min"), f("max")) {
        (Some(m), Some(lo), Some(hi)) => format!("{} ({}–{})", sig(m), sig(lo), sig(hi)),
        _ => "n/a".into(),
    }
}

/// EPR in per cent as the tables print it: `0`, `0.003`, `0.507`, `51.3`.
fn epr(r: &Value) -> String {
    match r["epr"].as_f64() {
        None => "n/a".into(),
        Some(e) => {
            let pct = e * 100.0;
            if pct == 0.0 {
                "0".into()
            } else if pct < 0.01 {
                // two significant digits, however small
                let decimals = (-pct.log10()).ceil() as usize + 1;
                let s = format!("{pct:.decimals$}");
                s.trim_end_matches('0').to_string()
            } else if pct < 1.0 {
                format!("{pct:.3}").trim_end_matches('0').to_string()
            } else {
                format!("{pct:.1}")
            }
        }
    }
}

fn psnr(r: &Value) -> String {
    match (r["epr"].as_f64(), r["psnr"].as_f64()) {
        (None, _) => "n/a".into(),
        (Some(e), Some(p)) if e > 0.0 && p.is_finite() => format!("{p:.1}"),
        _ => "exact".into(),
    }
}

fn mib(bytes: f64) -> String {
    format!("{:.1} MiB", bytes / (1u64 << 20) as f64)
}

/// `bunny` for `bunny`, and for a mesh path ending in `/bunny.obj`.
fn scene_matches(name: &str, want: &str) -> bool {
    name == want || scene_name(name) == want
}

/// A scene's name as the tables print it: a mesh path as its file stem, inside a scene
/// expression too (`grid:4x4:` before a path keeps its prefix).
fn scene_name(name: &str) -> String {
    match name.strip_suffix(".obj") {
        Some(s) => {
            let (prefix, path) = match s.rfind(':') {
                Some(at) => s.split_at(at + 1),
                None => ("", s),
            };
            format!("{prefix}{}", path.rsplit('/').next().unwrap_or(path))
        }
        None => name.to_string(),
    }
}

/// A marker's arguments: the files, then `key=value` options.
struct Spec<'a> {
    kind: &'a str,
    files: Vec<&'a str>,
    opts: Vec<(&'a str, &'a str)>,
}

impl<'a> Spec<'a> {
    fn parse(head: &'a str) -> Self {
        let mut words = head.split_whitespace();
        let kind = words.next().expect("a marker names its kind");
        let (mut files, mut opts) = (Vec::new(), Vec::new());
        for w in words {
            match w.split_once('=') {
                Some(kv) => opts.push(kv),
                None => files.push(w),
            }
        }
        Spec { kind, files, opts }
    }
    fn opt(&self, key: &str) -> Option<&'a str> {
        self.opts.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }
    fn file(&self, i: usize) -> &'a str {
        self.files.get(i).copied().unwrap_or_else(|| panic!("table {} wants a file #{}", self.kind, i + 1))
    }
}

fn rows(report: &Value) -> &Vec<Value> {
    report["rows"].as_array().expect("report.json has rows")
}

/// One backend's trade on one scene.
fn trade(spec: &Spec<'_>) -> String {
    let report = read_json(spec.file(0));
    let scene = spec.opt("scene").expect("trade: scene=");
    let backend = spec.opt("backend").unwrap_or("cpu");
    let raster = spec.opt("raster");
    let only: Option<Vec<&str>> = spec.opt("techniques").map(|t| t.split(',').collect());
    let gpu = spec.opt("time") == Some("gpu");
    let mut out = vec![
        if gpu {
            "| technique | passes | lost | storage | GPU ms, median (min–max) | steady wall ms | EPR (%) | PSNR (dB) |"
        } else {
            "| technique | passes | lost | storage | wall ms + readback, median (min–max) | EPR (%) | PSNR (dB) |"
        }
        .to_string(),
        if gpu { "|---|---|---|---|---|---|---|---|" } else { "|---|---|---|---|---|---|---|" }.to_string(),
    ];
    let mut picked: Vec<&Value> = rows(&report)
        .iter()
        .filter(|r| scene_matches(r["scene"].as_str().unwrap_or(""), scene) && r["backend"] == backend)
        .filter(|r| raster.is_none_or(|p| r["raster"] == p))
        .filter(|r| only.as_ref().is_none_or(|o| o.contains(&r["technique"].as_str().unwrap_or(""))))
        .collect();
    if let Some(o) = &only {
        picked.sort_by_key(|r| o.iter().position(|t| r["technique"] == *t));
    }
    assert!(!picked.is_empty(), "trade: no {backend} rows for {scene} in {}", spec.file(0));
    for r in picked {
        let time = if gpu {
            format!("{} | {}", spread(&r["gpu_ms"]), spread(&r["steady_wall_ms"]))
        } else {
            spread(&r["readback_wall_ms"])
        };
        out.push(format!(
            "| {} | {} | {} | {} | {time} | {} | {} |",
            r["technique"].as_str().unwrap_or("?"),
            r["passes"],
            count(r["lost"].as_u64().unwrap_or(0)),
            mib(r["storage_bytes"].as_f64().unwrap_or(0.0)),
            epr(r),
            psnr(r),
        ));
    }
    out.join("\n")
}

/// The hardware and compute raster paths of one GPU backend side by side.
fn paths(spec: &Spec<'_>) -> String {
    let report = read_json(spec.file(0));
    let scene = spec.opt("scene").expect("paths: scene=");
    let backend = spec.opt("backend").unwrap_or("wgpu");
    let of = |raster: &str| -> Vec<&Value> {
        rows(&report)
            .iter()
            .filter(|r| scene_matches(r["scene"].as_str().unwrap_or(""), scene))
            .filter(|r| r["backend"] == backend && r["raster"] == raster)
            .collect()
    };
    let (hw, cs) = (of("hardware"), of("compute"));
    assert!(!hw.is_empty() && !cs.is_empty(), "paths: {scene} lacks a path in {}", spec.file(0));
    let mut out = vec![
        "| technique | lost | EPR (%) | GPU ms, hardware | GPU ms, compute | steady wall ms, hardware | steady wall ms, compute | faster (GPU) |".to_string(),
        "|---|---|---|---|---|---|---|---|".to_string(),
    ];
    for h in hw {
        let Some(c) = cs.iter().find(|c| c["technique"] == h["technique"]) else { continue };
        let range = |r: &Value| (r["gpu_ms"]["min"].as_f64(), r["gpu_ms"]["max"].as_f64());
        let faster = match (range(h), range(c)) {
            ((Some(hlo), Some(hhi)), (Some(clo), Some(chi))) => {
                if chi < hlo {
                    "compute"
                } else if hhi < clo {
                    "hardware"
                } else {
                    "overlap"
                }
            }
            _ => "n/a",
        };
        out.push(format!(
            "| {} | {} | {} | {} | {} | {} | {} | {faster} |",
            h["technique"].as_str().unwrap_or("?"),
            count(h["lost"].as_u64().unwrap_or(0)),
            epr(h),
            spread(&h["gpu_ms"]),
            spread(&c["gpu_ms"]),
            spread(&h["steady_wall_ms"]),
            spread(&c["steady_wall_ms"]),
        ));
    }
    out.join("\n")
}

/// Per scene of a report, in its order: the fastest technique that is exact there (EPR 0 and
/// nothing lost) and the fastest whose EPR is at most 1 %, by median time (readback wall time, or
/// GPU time with `time=gpu`), on one backend (and raster path).
fn picks(spec: &Spec<'_>) -> String {
    let report = read_json(spec.file(0));
    let backend = spec.opt("backend").unwrap_or("cpu");
    let raster = spec.opt("raster");
    let (key, label) = if spec.opt("time") == Some("gpu") {
        ("gpu_ms", "GPU ms")
    } else {
        ("readback_wall_ms", "wall ms + readback")
    };
    let mut out = vec![
        format!("| scene | fastest exact | {label} | fastest within 1 % EPR | {label} | its EPR (%) |"),
        "|---|---|---|---|---|---|".to_string(),
    ];
    for s in report["scenes"].as_array().expect("report.json has scenes") {
        let name = s["name"].as_str().unwrap_or("?");
        let of: Vec<&Value> = rows(&report)
            .iter()
            .filter(|r| r["scene"] == name && r["backend"] == backend)
            .filter(|r| raster.is_none_or(|p| r["raster"] == p))
            .filter(|r| r[key]["median"].as_f64().is_some())
            .collect();
        let fastest = |ok: &dyn Fn(&Value) -> bool| {
            of.iter().copied().filter(|r| ok(r)).min_by(|a, b| {
                a[key]["median"].as_f64().unwrap().total_cmp(&b[key]["median"].as_f64().unwrap())
            })
        };
        let exact = fastest(&|r| r["epr"].as_f64() == Some(0.0) && r["lost"].as_u64() == Some(0));
        let close = fastest(&|r| r["epr"].as_f64().is_some_and(|e| e <= 0.01));
        let cell = |r: Option<&Value>| match r {
            Some(r) => (r["technique"].as_str().unwrap_or("?").to_string(), spread(&r[key])),
            None => ("none".to_string(), "n/a".to_string()),
        };
        let ((et, etime), (ct, ctime)) = (cell(exact), cell(close));
        out.push(format!(
            "| {} | {et} | {etime} | {ct} | {ctime} | {} |",
            scene_name(name),
            close.map_or_else(|| "n/a".to_string(), epr)
        ));
    }
    out.join("\n")
}

/// Each scene of a report: triangles, fragments, deepest pixel, and the run's frame size.
fn scenes(spec: &Spec<'_>) -> String {
    let report = read_json(spec.file(0));
    let size = format!("{}×{}", report["width"], report["height"]);
    let mut out = vec![
        "| scene | size | triangles | fragments | deepest pixel (layers) |".to_string(),
        "|---|---|---|---|---|".to_string(),
    ];
    for s in report["scenes"].as_array().expect("report.json has scenes") {
        out.push(format!(
            "| {} | {size} | {} | {} | {} |",
            scene_name(s["name"].as_str().unwrap_or("?")),
            count(s["triangles"].as_u64().unwrap_or(0)),
            count(s["fragments"].as_u64().unwrap_or(0)),
            s["max_depth"],
        ));
    }
    out.join("\n")
}

/// The cost model's error on unseen scenes, one row per backend/path of each report.
fn model(spec: &Spec<'_>) -> String {
    let mut out = vec![
        "| device | backend/path | unseen scenes | predictions | median error | worst | both targets met |"
            .to_string(),
        "|---|---|---|---|---|---|---|".to_string(),
    ];
    for file in &spec.files {
        let report = read_json(file);
        let device = report["backends"][0]["device"].as_str().unwrap_or("?");
        let host = report["host"].as_str().unwrap_or("?");
        let device = if device.starts_with("CPU") { host.to_string() } else { device.to_string() };
        let unseen: Vec<String> = report["scenes"]
            .as_array()
            .expect("scenes")
            .iter()
            .map(|s| scene_name(s["name"].as_str().unwrap_or("?")))
            .collect();
        let size = format!("{}×{}", report["width"], report["height"]);
        for m in report["model_summary"].as_array().expect("report.json has a model summary") {
            out.push(format!(
                "| {device} | {} | {} at {size} | {} | {:.1} % | {}, {:.2}× | {} |",
                m["backend"].as_str().unwrap_or("?"),
                unseen.join(", "),
                m["predictions"],
                m["median_error"].as_f64().unwrap_or(f64::NAN) * 100.0,
                m["worst_technique"].as_str().unwrap_or("?"),
                m["worst_factor"].as_f64().unwrap_or(f64::NAN),
                if m["within_targets"] == true { "yes" } else { "no" },
            ));
        }
    }
    out.join("\n")
}

/// `--overflow drop` against `--overflow tail`, the same techniques, scenes and path.
fn overflow(spec: &Spec<'_>) -> String {
    let (drop, tail) = (read_json(spec.file(0)), read_json(spec.file(1)));
    let raster = spec.opt("raster").unwrap_or("compute");
    let mut out = vec![
        "| scene | technique | lost (drop) | EPR (%), drop | merged (tail) | lost (tail) | EPR (%), tail | GPU ms, drop | GPU ms, tail |"
            .to_string(),
        "|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    for t in rows(&tail).iter().filter(|r| r["raster"] == raster) {
        let Some(d) = rows(&drop).iter().find(|d| {
            d["raster"] == raster
                && d["scene"] == t["scene"]
                && d["technique"] == t["technique"]
                && d["backend"] == t["backend"]
        }) else {
            continue;
        };
        out.push(format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            scene_name(t["scene"].as_str().unwrap_or("?")),
            t["technique"].as_str().unwrap_or("?"),
            count(d["lost"].as_u64().unwrap_or(0)),
            epr(d),
            t["merged"].as_u64().map_or("n/a".to_string(), count),
            count(t["lost"].as_u64().unwrap_or(0)),
            epr(t),
            spread(&d["gpu_ms"]),
            spread(&t["gpu_ms"]),
        ));
    }
    out.join("\n")
}

/// Each measured build: its command, cold build time and binary size.
fn builds(spec: &Spec<'_>) -> String {
    let builds = read_json(spec.file(0));
    let mut out = vec![
        "| build | command | cold build (s) | binary | measured on |".to_string(),
        "|---|---|---|---|---|".to_string(),
    ];
    for b in builds.as_array().expect("builds.json is a list") {
        out.push(format!(
            "| {} | `{}` | {:.0} | {} | {}, {} cores, {}, {} |",
            b["name"].as_str().unwrap_or("?"),
            b["command"].as_str().unwrap_or("?"),
            b["wall_s"].as_f64().unwrap_or(f64::NAN),
            mib(b["binary_bytes"].as_f64().unwrap_or(f64::NAN)),
            b["cpu"].as_str().unwrap_or("?"),
            b["cores"],
            match b["load_after"].as_f64() {
                Some(after) => format!("load average {} before, {after} after", b["load_before"]),
                None => format!("load average {} at the start", b["load_before"]),
            },
            b["date"].as_str().unwrap_or("?"),
        ));
    }
    out.join("\n")
}

/// Multisampling on one scene (issue 40): three runs of the same techniques, at one sample, at
/// `--samples N` and at `--samples N --coverage pixel` (files in that order): the fragments the
/// samples add, bytes a captured fragment, steady wall time, and the error pixel rate against the
/// per-sample reference per sample and per pixel.
fn msaa(spec: &Spec<'_>) -> String {
    let (one, many, pixel) = (read_json(spec.file(0)), read_json(spec.file(1)), read_json(spec.file(2)));
    // a column naming the backend and raster path where the reports hold several
    let path = |r: &Value| {
        format!("{}/{}", r["backend"].as_str().unwrap_or("?"), r["raster"].as_str().unwrap_or("?"))
    };
    let several = rows(&many).iter().map(path).collect::<std::collections::BTreeSet<_>>().len() > 1;
    let mut out = vec![
        format!(
            "| {}technique | fragments, 1 sample | fragments, N samples | bytes a captured fragment, 1 → N | steady wall ms, 1 → N | EPR (%), per sample | EPR (%), per pixel |",
            if several { "backend/path | " } else { "" }
        ),
        format!("|{}---|---|---|---|---|---|---|", if several { "---|" } else { "" }),
    ];
    let find = |report: &Value, r: &Value| {
        rows(report)
            .iter()
            .find(|o| {
                o["technique"] == r["technique"]
                    && o["scene"] == r["scene"]
                    && o["backend"] == r["backend"]
                    && o["raster"] == r["raster"]
            })
            .cloned()
    };
    let per = |r: &Value| {
        r["storage_bytes"].as_f64().unwrap_or(f64::NAN) / r["captured"].as_f64().unwrap_or(f64::NAN)
    };
    let median = |r: &Value| r["steady_wall_ms"]["median"].as_f64().unwrap_or(f64::NAN);
    for r in rows(&many) {
        let (Some(o), Some(p)) = (find(&one, r), find(&pixel, r)) else {
            continue;
        };
        out.push(format!(
            "| {}{} | {} | {} | {} → {} | {} → {} | {} | {} |",
            if several { format!("{} | ", path(r)) } else { String::new() },
            r["technique"].as_str().unwrap_or("?"),
            count(o["fragments"].as_u64().unwrap_or(0)),
            count(r["fragments"].as_u64().unwrap_or(0)),
            sig(per(&o)),
            sig(per(r)),
            sig(median(&o)),
            sig(median(r)),
            epr(r),
            epr(&p),
        ));
    }
    assert!(out.len() > 2, "msaa: no technique in all three of {:?}", spec.files);
    out.join("\n")
}

/// The table a marker's head (the text after `<!-- table `) asks for.
fn table(head: &str) -> String {
    let spec = Spec::parse(head);
    match spec.kind {
        "trade" => trade(&spec),
        "paths" => paths(&spec),
        "scenes" => scenes(&spec),
        "picks" => picks(&spec),
        "model" => model(&spec),
        "overflow" => overflow(&spec),
        "builds" => builds(&spec),
        "msaa" => msaa(&spec),
        other => panic!("unknown table kind {other:?} in marker {head:?}"),
    }
}

/// Every marked table of `text` with the text its results give.
fn regenerate(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find(OPEN) {
        let head_end = at + rest[at..].find("-->").expect("the marker closes") + 3;
        let head = rest[at + OPEN.len()..head_end - 3].trim();
        let end = head_end + rest[head_end..].find(CLOSE).unwrap_or_else(|| panic!("{head}: no {CLOSE}"));
        out.push_str(&rest[..head_end]);
        out.push('\n');
        out.push_str(&table(head));
        out.push('\n');
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

#[test]
fn tables_are_the_committed_results() {
    let write = std::env::var("OIT_WRITE_README").is_ok_and(|v| v == "1");
    let mut stale = Vec::new();
    let mut marked = 0;
    for path in documents() {
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        marked += text.matches(OPEN).count();
        let fresh = regenerate(&text);
        if fresh != text {
            if write {
                std::fs::write(&path, &fresh).expect("written");
            } else {
                stale.push(path.strip_prefix(root()).unwrap_or(&path).display().to_string());
            }
        }
    }
    assert!(marked >= 5, "README.md and docs/ have their generated tables ({marked} markers)");
    assert!(
        stale.is_empty(),
        "{} differ from the committed results they cite; run \
         OIT_WRITE_README=1 cargo test --release -p oit-tests --test readme_tables",
        stale.join(", ")
    );
}

/// The writer fails on a figure typed by hand: a table with one cell changed is not what the
/// report gives.
#[test]
fn a_hand_edited_figure_is_caught() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let fresh = regenerate(&readme);
    let edited = fresh.replacen("| bunny | 512×512 | 69,666 |", "| bunny | 512×512 | 69,667 |", 1);
    assert_ne!(edited, fresh, "the README's scenes table has a bunny row to edit");
    assert_ne!(regenerate(&edited), edited, "a hand edit is regenerated away");
}

/// Text of `line` outside inline code spans.
fn outside_code(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join(" ")
}

/// The figures with a unit of measurement in `prose`: a number followed by `ms`, `%`, `MiB`,
/// `GiB`, `KiB`, `dB`, `fps`, or directly by `×` (a factor; `8 × R32` is a count).
fn measurements(prose: &str) -> Vec<String> {
    const UNITS: &[&str] = &["ms", "%", "MiB", "GiB", "KiB", "dB", "fps"];
    let chars: Vec<char> = prose.chars().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts = chars[i].is_ascii_digit() && (i == 0 || !chars[i - 1].is_alphanumeric());
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < chars.len() && (chars[j].is_ascii_digit() || chars[j] == '.' || chars[j] == ',') {
            j += 1;
        }
        let number: String = chars[i..j].iter().collect();
        let number = number.trim_end_matches(['.', ',']);
        if j < chars.len() && chars[j] == '×' {
            found.push(format!("{number}×"));
        }
        let mut k = j;
        if k < chars.len() && chars[k] == ' ' {
            k += 1;
        }
        let after: String = chars[k..chars.len().min(k + 4)].iter().collect();
        for unit in UNITS {
            let ends = after
                .strip_prefix(unit)
                .is_some_and(|r| r.chars().next().is_none_or(|c| !c.is_alphanumeric()));
            if ends {
                found.push(format!("{number} {unit}"));
            }
        }
        i = j.max(i + 1);
    }
    found
}

/// No figure with a unit in the prose of the README and docs (the design record,
/// docs/architecture.md, included): measurements live in generated tables.
#[test]
fn no_hand_typed_measurements() {
    let mut found = Vec::new();
    for path in documents() {
        let text = std::fs::read_to_string(&path).expect("readable");
        let (mut fence, mut table) = (false, false);
        for (n, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("```") {
                fence = !fence;
                continue;
            }
            if line.contains(OPEN) {
                table = true;
            }
            if line.contains(CLOSE) {
                table = false;
            }
            if fence || table {
                continue;
            }
            for m in measurements(&outside_code(line)) {
                found.push(format!(
                    "{}:{}: {m}",
                    path.strip_prefix(root()).unwrap_or(&path).display(),
                    n + 1
                ));
            }
        }
    }
    assert!(
        found.is_empty(),
        "figures typed by hand (put them in a generated table from a committed result, or drop them):\n{}",
        found.join("\n")
    );
}

#[test]
fn scene_names_and_small_rates() {
    assert_eq!(scene_name("grid:4x4:../models/bunny.obj"), "grid:4x4:bunny");
    assert_eq!(scene_name("planes:64"), "planes:64");
    assert!(scene_matches("models/bunny.obj", "bunny") && !scene_matches("grid:4x4:bunny", "bunny"));
    assert!(!scene_matches("grid:4x4:models/bunny.obj", "bunny"));
    assert_eq!(epr(&serde_json::json!({"epr": 0.0000133})), "0.0013");
    assert_eq!(epr(&serde_json::json!({"epr": 0.00003})), "0.003");
}

#[test]
fn measurements_are_recognised() {
    assert_eq!(
        measurements("it took 12.4 ms, 1.5× and 0.5 % of 25.0 MiB"),
        ["12.4 ms", "1.5×", "0.5 %", "25.0 MiB"]
    );
    assert!(measurements("8 × R32, 32 buckets, grid:4x4, mdts:8, 2⁻²⁰, 1024 bins").is_empty());
    assert_eq!(outside_code("see `--max-epr 0.5%` and 3 ms"), "see   and 3 ms");
}
