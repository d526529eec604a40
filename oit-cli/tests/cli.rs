//! The `oit` binary as a user runs it: outputs written, JSON shapes, and one `error:` line with
//! exit code 1 for every bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

/// Small enough that every test renders in well under a second.
const SIZE: &str = "64x64";

fn oit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_oit")).args(args).output().expect("the oit binary runs")
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A fresh folder of this test's own under cargo's scratch space.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("oit-cli").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Asserts the failure contract: non-zero exit, exactly one `error:` line on stderr, no panic.
fn assert_one_error(out: &Output, what: &str) {
    let err = stderr(out);
    assert!(!out.status.success(), "{what}: should fail, stdout: {}", stdout(out));
    assert_eq!(out.status.code(), Some(1), "{what}: exit code, stderr: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{what}: one line on stderr, got {err:?}");
    assert!(lines[0].starts_with("error: "), "{what}: {err:?}");
    assert!(!err.contains("panicked") && !err.contains("backtrace"), "{what}: {err:?}");
}

fn parse_json(out: &Output, what: &str) -> Value {
    assert!(out.status.success(), "{what}: {}", stderr(out));
    serde_json::from_str(&stdout(out))
        .unwrap_or_else(|e| panic!("{what}: stdout is not JSON ({e}): {}", stdout(out)))
}

#[test]
fn render_writes_a_png() {
    let dir = scratch("render_png");
    let png = dir.join("out.png");
    let out = oit(&["render", "--size", SIZE, "--technique", "dp", "-o", png.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let bytes = std::fs::read(&png).expect("the PNG was written");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let text = stdout(&out);
    for word in ["technique", "backend", "passes", "fragments", "captured", "lost", "storage", "time"] {
        assert!(text.contains(word), "summary lacks {word}: {text}");
    }
}

#[test]
fn render_json_has_the_camera() {
    let dir = scratch("render_json");
    let png = dir.join("out.png");
    let out = oit(&["render", "--size", SIZE, "--json", "-t", "fabs:16", "-o", png.to_str().unwrap()]);
    let v = parse_json(&out, "render --json");
    assert_eq!(v["technique"], "fabs:16");
    assert_eq!(v["backend"], "cpu");
    assert_eq!(v["raster"], "cpu");
    assert_eq!(v["width"], 64);
    assert_eq!(v["height"], 64);
    for key in ["geometry_passes", "fragments", "captured", "lost", "storage_bytes", "wall_ms"] {
        assert!(v[key].is_number(), "{key}: {v}");
    }
    assert!(v["gpu_ms"].is_null(), "the cpu backend has no device timer");
    let camera = &v["camera"];
    for key in ["view", "proj"] {
        let m = camera[key].as_array().unwrap_or_else(|| panic!("{key} is an array"));
        assert_eq!(m.len(), 16, "{key}");
        assert!(m.iter().all(Value::is_f64), "{key}");
    }
    assert_eq!(camera["eye"].as_array().map(Vec::len), Some(3));
    assert_eq!(camera["forward"].as_array().map(Vec::len), Some(3));
    assert!(camera["near"].as_f64().unwrap() < camera["far"].as_f64().unwrap());
    assert_eq!(camera["azimuth"], 30.0);
    assert_eq!(camera["elevation"], 20.0);
    assert_eq!(camera["fov"], 45.0);
    assert!(png.exists());
}

/// `--shading vertex` on meshes without vertex colours says so, once, naming the meshes and that
/// they are drawn as `flat`; on a mesh with colours, and with other shadings, nothing is said.
#[test]
fn vertex_shading_without_colours_warns() {
    let dir = scratch("vertex_shading");
    let png = dir.join("v.png");
    let out_path = png.to_str().unwrap();
    let out = oit(&["render", "--size", SIZE, "--shading", "vertex", "-o", out_path]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(warnings.len(), 1, "one warning: {err}");
    // the default scene draws two meshes, the knot and the sphere (twice): each named once
    let w = warnings[0];
    assert!(w.contains("--shading vertex") && w.contains("flat"), "{w}");
    assert!(w.contains("'knot'") && w.matches("'sphere'").count() == 1, "{w}");
    assert!(w.contains("scene 'default'"), "{w}");

    let quiet = oit(&["render", "--size", SIZE, "--shading", "flat", "-o", out_path]);
    assert!(quiet.status.success() && !stderr(&quiet).contains("warning"), "{}", stderr(&quiet));
    let coloured = dir.join("coloured.obj");
    std::fs::write(&coloured, "v -1 -1 0 1 0 0\nv 1 -1 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
    let scene = coloured.to_str().unwrap();
    let quiet = oit(&["render", "--size", SIZE, "--shading", "vertex", "--scene", scene, "-o", out_path]);
    assert!(quiet.status.success() && !stderr(&quiet).contains("warning"), "{}", stderr(&quiet));
    // compare and sweep share the check
    let sweep = oit(&["sweep", "--size", "16x16", "--views", "1", "-t", "wavg", "--shading", "vertex"]);
    assert!(sweep.status.success(), "{}", stderr(&sweep));
    assert_eq!(
        stderr(&sweep).lines().filter(|l| l.starts_with("warning: ")).count(),
        1,
        "{}",
        stderr(&sweep)
    );
}

/// `oit render --effect complexity` writes the backend's heat map with the legend drawn over its
/// bottom-right corner, scaled to the frame's `max_layers`, and every other pixel as rendered.
#[cfg(feature = "cpu")]
/// Issue 11.2 and 11.6: `--memory` tiles the frame, with the same image and counts, and says so
/// (`tiles`); `--json` gives the depth histogram and its maximum, from the reference's counts.
#[test]
fn render_memory_tiles_and_depth_complexity() {
    let dir = scratch("render_memory");
    let (whole_png, tiled_png) = (dir.join("whole.png"), dir.join("tiled.png"));
    let run = |png: &Path, memory: &[&str]| {
        let mut args = vec!["render", "--size", SIZE, "--json", "-t", "fabs", "-o", png.to_str().unwrap()];
        args.extend_from_slice(memory);
        parse_json(&oit(&args), "render --json")
    };
    let whole = run(&whole_png, &[]);
    let tiled = run(&tiled_png, &["--memory", "100K"]);
    assert_eq!(whole["tiles"], 1);
    assert!(tiled["tiles"].as_u64().unwrap() >= 4, "{tiled}");
    assert!(tiled["storage_bytes"].as_u64().unwrap() <= 100 << 10, "{tiled}");
    for key in ["fragments", "captured", "lost", "max_layers", "max_depth", "depth_histogram"] {
        assert_eq!(whole[key], tiled[key], "{key}");
    }
    assert_eq!(std::fs::read(&whole_png).unwrap(), std::fs::read(&tiled_png).unwrap(), "the same image");
    let histogram: Vec<u64> =
        whole["depth_histogram"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    let max_depth = whole["max_depth"].as_u64().unwrap();
    assert_eq!(histogram.len() as u64, max_depth + 1);
    assert_eq!(histogram.iter().sum::<u64>(), 64 * 64);
    let fragments: u64 = histogram.iter().enumerate().map(|(n, c)| n as u64 * c).sum();
    assert_eq!(fragments, whole["fragments"].as_u64().unwrap(), "the histogram counts every fragment");
    for (memory, says) in [("12Q", "not a byte count"), ("10", "one pixel")] {
        let out = oit(&["render", "--size", SIZE, "--memory", memory, "-o", whole_png.to_str().unwrap()]);
        assert_one_error(&out, memory);
        assert!(stderr(&out).contains(says), "--memory {memory}: {}", stderr(&out));
    }
}

#[test]
fn render_complexity_draws_the_legend_on_the_heat_map() {
    use oit_bench::present::heat_legend_rect;
    use oit_core::{Backend, Camera, Effect, Settings, View, load_scene, parse_rgb};

    let dir = scratch("render_complexity");
    let png = dir.join("c.png");
    let (scene_name, background) = ("spheres:6", "0.2,0.2,0.25");
    let args = ["--scene", scene_name, "-t", "fabs", "--effect", "complexity", "--size", "256x256"];
    let args = [&args[..], &["--background", background, "--json", "-o", png.to_str().unwrap()]].concat();
    let v = parse_json(&oit(&["render"].into_iter().chain(args).collect::<Vec<_>>()), "render complexity");
    let max = u32::try_from(v["max_layers"].as_u64().expect("max_layers in the JSON")).unwrap();
    let written = image::open(&png).expect("a PNG").to_rgba8();

    // The same frame from the library, without a legend.
    let scene = load_scene(scene_name).unwrap();
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let settings = Settings {
        width: 256,
        height: 256,
        technique: "fabs".parse().unwrap(),
        effect: Effect::Complexity,
        background: parse_rgb(background).unwrap(),
        ..Settings::default()
    };
    let frame = oit_cpu::CpuBackend::default().render(&scene, &camera, &settings).unwrap();
    assert_eq!(frame.stats.max_layers, max);
    assert_eq!(max, 12, "six nested spheres: 12 surfaces through the middle");

    let rect = heat_legend_rect(256, 256, max).expect("room for the legend");
    let mut legend_pixels = 0;
    for (x, y, p) in written.enumerate_pixels() {
        if rect.contains(x, y) {
            legend_pixels += usize::from(p.0 != frame.image.get(x, y));
        } else {
            assert_eq!(p.0, frame.image.get(x, y), "({x}, {y}) outside the legend {rect:?}");
        }
    }
    assert!(legend_pixels * 2 > (rect.width * rect.height) as usize, "no legend in {rect:?}");
}

const COMPARE_KEYS: [&str; 23] = [
    "technique",
    "backend",
    "raster",
    "width",
    "height",
    "geometry_passes",
    "fragments",
    "captured",
    "lost",
    "occluded",
    "opaque_fragments",
    "masked",
    "merged",
    "tied",
    "quantized",
    "storage_bytes",
    "wall_ms",
    "gpu_ms",
    "epr",
    "psnr",
    "max_error",
    "max_layers",
    "tiles",
];

#[test]
fn compare_json_has_exactly_the_keys() {
    let dir = scratch("compare_json");
    let sheet = dir.join("sheet.png");
    let out = oit(&[
        "compare",
        "--size",
        SIZE,
        "--techniques",
        "dp,wavg,fabs:16",
        "--json",
        "--sheet",
        sheet.to_str().unwrap(),
    ]);
    let v = parse_json(&out, "compare --json");
    let rows = v.as_array().expect("an array");
    assert_eq!(rows.len(), 3);
    let names: Vec<&str> = rows.iter().map(|r| r["technique"].as_str().unwrap()).collect();
    assert_eq!(names, ["dp", "wavg", "fabs:16"]);
    for row in rows {
        let obj = row.as_object().expect("an object");
        let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
        let mut expected = COMPARE_KEYS.to_vec();
        keys.sort_unstable();
        expected.sort_unstable();
        assert_eq!(keys, expected);
        assert_eq!(row["raster"], "cpu");
        assert!(row["gpu_ms"].is_null());
    }
    // dp is exact on the default scene: identical images have an infinite PSNR, written as null.
    assert_eq!(rows[0]["epr"], 0.0);
    assert!(rows[0]["psnr"].is_null());
    // The weighted average ignores order: it cannot match everywhere.
    assert!(rows[1]["epr"].as_f64().unwrap() > 0.0);
    assert!(rows[1]["psnr"].is_f64());
    // The sheet is a grid: the reference and three techniques, two cells (each 64 + gap + 64
    // pixels of image and error at least) side by side, no taller than wide.
    let sheet = image::open(&sheet).expect("the sheet was written as a PNG");
    assert!(
        sheet.width() > 2 * (64 + 8 + 64) && sheet.width() >= sheet.height(),
        "{:?}",
        (sheet.width(), sheet.height())
    );
    assert!(
        sheet.height() > 2 * 64 && sheet.height() < 3 * 64 + 3 * 60,
        "two rows: {:?}",
        (sheet.width(), sheet.height())
    );
}

#[test]
fn compare_table_shows_every_technique() {
    let out = oit(&["compare", "--size", "32x32", "--techniques", "dp,bdp"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    for word in ["technique", "backend", "EPR (%)", "PSNR (dB)", "inf", "dp", "bdp"] {
        assert!(text.contains(word), "{word}: {text}");
    }
}

/// Issue 40 item 3: with `--supersample` one table gives each technique's error against the
/// per-sample reference (MSAA's target: 0 for the exact dfb) beside its error against the
/// supersampled one, and the per-sample reference's own error against supersampling (its row,
/// `msaa-ref`, equal to dfb's, which is its image). Mutation tried: `epr_msaa` measured against
/// the supersampled baseline (dfb's `epr_msaa` then is not 0).
#[test]
fn compare_supersampled_reports_both_references() {
    let args = [
        "compare",
        "--scene",
        "bunny",
        "--size",
        "64x64",
        "--samples",
        "4",
        "--supersample",
        "--techniques",
        "dfb,fabs:2",
    ];
    let out = oit(&[&args[..], &["--json"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).expect("JSON rows");
    let field = |t: &str, f: &str| {
        rows.iter()
            .find(|r| r["technique"] == t)
            .and_then(|r| r[f].as_f64())
            .unwrap_or_else(|| panic!("{t} {f}: {rows:?}"))
    };
    assert_eq!(field("dfb", "epr_msaa"), 0.0, "dfb is the per-sample reference's image");
    assert!(field("dfb", "epr") > 0.01, "MSAA errs against supersampling along the edges");
    assert!(field("fabs:2", "epr_msaa") > 0.0 && field("fabs:2", "epr_msaa") < 1.0);
    let text = stdout(&oit(&args));
    let msaa = text.lines().find(|l| l.starts_with("msaa-ref")).unwrap_or_else(|| panic!("{text}"));
    let dfb = text.lines().find(|l| l.starts_with("dfb")).unwrap_or_else(|| panic!("{text}"));
    let last3 = |l: &str| l.split_whitespace().rev().take(3).map(str::to_string).collect::<Vec<_>>();
    assert_eq!(last3(msaa), last3(dfb), "the per-sample reference's errors are dfb's\n{text}");
    assert!(text.contains("EPR MSAA (%)"), "{text}");
    // without --supersample the table has no second reference
    let without: Vec<&str> = args.iter().copied().filter(|a| *a != "--supersample").collect();
    let plain = stdout(&oit(&without));
    assert!(!plain.contains("msaa-ref") && !plain.contains("EPR MSAA"), "{plain}");
}

#[test]
fn compare_goes_on_past_a_failing_technique() {
    // The weighted techniques never order fragments, so they cannot absorb through a thickness.
    let out = oit(&["compare", "--size", "32x32", "--techniques", "wavg,dp", "--effect", "translucency"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.lines().any(|l| l.starts_with("wavg") && l.contains("error")), "{text}");
    assert!(text.lines().any(|l| l.starts_with("dp ") && l.contains("inf")), "{text}");
    assert!(stderr(&out).starts_with("error: "));
    assert!(!stderr(&out).contains("panicked"));
}

#[test]
fn bad_inputs_fail_with_one_error_line() {
    let dir = scratch("bad_inputs");
    let malformed = dir.join("malformed.obj");
    std::fs::write(&malformed, "v 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let nan = dir.join("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let not_numbers = dir.join("words.obj");
    std::fs::write(&not_numbers, "v zero 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let missing = dir.join("missing.obj");
    let png = dir.join("out.png");
    let (png, malformed, nan, not_numbers, missing) = (
        png.to_str().unwrap(),
        malformed.to_str().unwrap(),
        nan.to_str().unwrap(),
        not_numbers.to_str().unwrap(),
        missing.to_str().unwrap(),
    );
    let unwritable = dir.join("no-such-folder").join("out.png");
    let cases: Vec<(&str, Vec<&str>)> = vec![
        ("missing file", vec!["render", "--scene", missing]),
        ("malformed obj", vec!["render", "--scene", malformed]),
        ("nan vertex", vec!["render", "--scene", nan]),
        ("words for numbers", vec!["render", "--scene", not_numbers]),
        ("0x0 size", vec!["render", "--size", "0x0"]),
        ("malformed size", vec!["render", "--size", "64by64"]),
        ("unknown technique", vec!["render", "--technique", "nope"]),
        ("bad parameter", vec!["render", "--technique", "fabs:0"]),
        ("unknown scene", vec!["render", "--scene", "no-such-scene"]),
        ("nan azimuth", vec!["render", "--azimuth", "nan"]),
        ("bad fov", vec!["render", "--fov", "0"]),
        ("alpha out of range", vec!["render", "--alpha", "1.5"]),
        ("bad background", vec!["render", "--background", "1,1"]),
        ("unknown shading", vec!["render", "--shading", "phong"]),
        ("unknown effect", vec!["render", "--effect", "glow"]),
        ("unknown backend", vec!["render", "--backend", "metal"]),
        ("zero threads", vec!["render", "--threads", "0"]),
        ("too many threads", vec!["render", "--threads", "100000"]),
        ("zero peels", vec!["render", "--max-peels", "0"]),
        ("unwritable output", vec!["render", "-o", unwritable.to_str().unwrap()]),
        ("not a png", vec!["render", "-o", "out.jpg"]),
        ("compare unknown technique", vec!["compare", "--techniques", "dp,nope"]),
        ("compare unknown scene", vec!["compare", "--scene", "no-such-scene"]),
        ("sweep zero views", vec!["sweep", "--views", "0"]),
        ("sweep 0x0 size", vec!["sweep", "--views", "2", "--size", "0x0"]),
        ("sweep plot not svg or png", vec!["sweep", "--views", "2", "--plot", "plot.jpg"]),
    ];
    for (what, mut args) in cases {
        // Outputs go to the scratch folder, and renders stay small, unless the case says otherwise.
        if args[0] == "render" && !args.contains(&"-o") {
            args.extend(["-o", png]);
        }
        if !args.contains(&"--size") {
            args.extend(["--size", "16x16"]);
        }
        assert_one_error(&oit(&args), what);
    }
    // `info` bounds the threads as the others do (it once reported "100000 rayon threads")
    assert_one_error(&oit(&["info", "--threads", "100000"]), "info with too many threads");
}

/// `--near` and `--far` (issue 13.17) reach the camera, and every bad value is one clear error
/// naming the flag.
#[test]
fn near_and_far_planes() {
    let dir = scratch("near_far");
    let png = dir.join("out.png");
    let png = png.to_str().unwrap();
    let out = oit(&["render", "--size", "16x16", "--near", "0.5", "--far", "20", "--json", "-o", png]);
    let v = parse_json(&out, "render --near --far");
    let (near, far) = (v["camera"]["near"].as_f64().unwrap(), v["camera"]["far"].as_f64().unwrap());
    assert!((near - 0.5).abs() < 1e-6 && (far - 20.0).abs() < 1e-5, "{near} {far}");
    let cases: [(&[&str], &str); 7] = [
        (&["--near", "0"], "--near 0 is not a distance"),
        (&["--near", "-1"], "--near -1 is not a distance"),
        (&["--far", "inf"], "--far inf is not a distance"),
        (&["--near", "nan"], "--near NaN is not a distance"),
        (&["--near", "5", "--far", "2"], "--near 5 must be less than --far 2"),
        // against the plane fitted to the scene: checked once the scene is loaded
        (&["--near", "1000"], "set --far beyond --near"),
        (&["--far", "0.001"], "set --near below --far"),
    ];
    for (flags, message) in cases {
        let mut args = vec!["render", "--size", "16x16", "-o", png];
        args.extend(flags);
        let out = oit(&args);
        assert_one_error(&out, message);
        assert!(stderr(&out).contains(message), "{flags:?}: {}", stderr(&out));
    }
}

/// A scene scaled to 10⁻²⁰ or 10²⁰ renders the fragments it renders at unit scale (issue 13.6: at
/// 10⁻³⁰ it rendered none); one too small for f32 is refused.
#[test]
fn scaled_scenes_render_alike() {
    let dir = scratch("scaled");
    let png = dir.join("out.png");
    let png = png.to_str().unwrap();
    let fragments = |scene: &str| {
        let out = oit(&["render", "--size", "32x32", "--scene", scene, "--json", "-o", png]);
        parse_json(&out, scene)["fragments"].as_u64().unwrap()
    };
    let unit = fragments("planes:4");
    assert!(unit > 1000, "{unit}");
    for scene in ["scale:1e-30:planes:4", "scale:1e-20:planes:4", "scale:1e20:planes:4"] {
        assert_eq!(fragments(scene), unit, "{scene}");
    }
    let out = oit(&["render", "--size", "16x16", "--scene", "scale:1e-32:planes:4", "-o", png]);
    assert_one_error(&out, "too small");
    assert!(stderr(&out).contains("too small to frame"), "{}", stderr(&out));
}

#[test]
fn usage_errors_keep_clap_exit_code() {
    let out = oit(&["render", "--azimuth", "north"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!stderr(&out).contains("panicked"));
    let out = oit(&["no-such-command"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn info_json_parses() {
    let v = parse_json(&oit(&["info", "--json"]), "info --json");
    let backends = v["backends"].as_array().expect("backends");
    let cpu =
        backends.iter().find(|b| b["name"] == "cpu").expect("the cpu backend is compiled in by default");
    assert_eq!(cpu["available"], true);
    assert!(cpu["device"].is_string());
    let techniques = cpu["techniques"].as_array().expect("techniques");
    assert!(techniques.iter().any(|t| t == "reference"));
    assert!(techniques.iter().any(|t| t == "adp"));
    let text = stdout(&oit(&["info"]));
    assert!(text.contains("backend cpu") && text.contains("techniques"), "{text}");
}

/// The keys of every `oit sweep --json` record: where and what (backend and raster path
/// included), the frame's counters as `oit compare --json` names them, and the accuracy.
const SWEEP_KEYS: [&str; 22] = [
    "azimuth",
    "quantized",
    "technique",
    "backend",
    "raster",
    "geometry_passes",
    "fragments",
    "captured",
    "lost",
    "occluded",
    "opaque_fragments",
    "masked",
    "merged",
    "tied",
    "storage_bytes",
    "wall_ms",
    "gpu_ms",
    "epr",
    "psnr",
    "max_error",
    "max_layers",
    "tiles",
];

#[test]
fn sweep_json_has_a_record_per_view_and_technique() {
    let dir = scratch("sweep");
    let svg = dir.join("epr.svg");
    let out = oit(&[
        "sweep",
        "--size",
        "32x32",
        "--views",
        "3",
        "--techniques",
        "dp,wavg,bdp",
        "--json",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let v = parse_json(&out, "sweep --json");
    let records = v.as_array().expect("an array");
    assert_eq!(records.len(), 3 * 3);
    let mut azimuths: Vec<f64> = records.iter().map(|r| r["azimuth"].as_f64().unwrap()).collect();
    azimuths.dedup();
    assert_eq!(azimuths, [0.0, 120.0, 240.0]);
    for r in records {
        let mut keys: Vec<&str> = r.as_object().unwrap().keys().map(String::as_str).collect();
        keys.sort_unstable();
        let mut expected = SWEEP_KEYS.to_vec();
        expected.sort_unstable();
        assert_eq!(keys, expected);
        assert_eq!(r["raster"], "cpu");
        assert!(r["geometry_passes"].as_u64().unwrap() >= 1);
    }
    let plot = std::fs::read_to_string(&svg).expect("the plot was written");
    assert!(plot.starts_with("<svg"));
    for label in ["dp", "wavg", "bdp", "azimuth", "EPR, % of covered pixels", "1e-3 %"] {
        assert!(plot.contains(label), "plot lacks {label}");
    }
}

#[test]
fn sweep_all_gives_views_times_techniques() {
    let out = oit(&["sweep", "--size", "16x16", "--views", "3", "--json"]);
    let v = parse_json(&out, "sweep --json");
    let techniques = oit_core::Technique::all().len();
    assert_eq!(v.as_array().expect("an array").len(), 3 * techniques);
}

#[test]
fn sweep_summary_table() {
    let out = oit(&["sweep", "--size", "16x16", "--views", "2", "--techniques", "dp,wsum"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    for word in ["raster", "mean EPR", "max EPR", "mean lost", "mean ms", "dp", "wsum"] {
        assert!(text.contains(word), "{word}: {text}");
    }
}

/// Every technique of the catalogue is named where a user picks one: `render --technique`'s and
/// `compare --techniques`' help (wboit and mboit were missing from both after they were added).
#[test]
fn help_names_every_technique() {
    for command in ["render", "compare"] {
        let out = oit(&[command, "--help"]);
        assert!(out.status.success());
        let text = stdout(&out);
        for kind in oit_core::TechniqueKind::ALL {
            let name = serde_json::to_value(kind).expect("a kind serializes");
            let name = name.as_str().expect("a kind serializes as its name");
            let named = text.split(|c: char| !c.is_ascii_alphanumeric()).any(|word| word == name);
            assert!(named, "`oit {command} --help` does not name {name}");
        }
    }
}

#[test]
fn help_mentions_every_option() {
    let shared = [
        "--scene",
        "--gltf-scene",
        "--size",
        "--azimuth",
        "--elevation",
        "--fov",
        "--alpha",
        "--shading",
        "--background",
        "--effect",
        "--bounds",
        "--bdp-mode",
        "--max-peels",
        "--backend",
        "--threads",
    ];
    let own: [(&str, &[&str]); 4] = [
        ("render", &["--technique", "--output", "--json"]),
        ("compare", &["--techniques", "--json", "--sheet"]),
        ("sweep", &["--techniques", "--views", "--json", "--plot"]),
        ("info", &["--json"]),
    ];
    for (command, options) in own {
        let out = oit(&[command, "--help"]);
        assert!(out.status.success());
        let text = stdout(&out);
        let expected: Vec<&str> = options
            .iter()
            .copied()
            .chain(if command == "info" { &[][..] } else { &shared[..] }.iter().copied())
            .collect();
        for option in expected {
            assert!(text.contains(option), "`oit {command} --help` lacks {option}");
        }
    }
    let text = stdout(&oit(&["--help"]));
    for command in ["render", "compare", "sweep", "info"] {
        assert!(text.contains(command), "`oit --help` lacks {command}");
    }
}

/// The GPU backend on both raster paths, where this build has it and finds an adapter (lavapipe
/// counts): `None` (and a note) where it does not.
#[cfg(feature = "wgpu")]
fn wgpu_paths() -> Option<()> {
    let v = parse_json(&oit(&["info", "--json"]), "info --json");
    let found = v["backends"].as_array()?.iter().any(|b| b["name"] == "wgpu" && b["available"] == true);
    if !found {
        // CI installs lavapipe and sets OIT_REQUIRE_GPU=1: a missing adapter there is a failure
        assert!(
            std::env::var("OIT_REQUIRE_GPU").as_deref() != Ok("1"),
            "OIT_REQUIRE_GPU=1 and oit info finds no wgpu adapter"
        );
        eprintln!("note: no wgpu adapter; the two-path test is skipped");
    }
    found.then_some(())
}

#[cfg(feature = "wgpu")]
#[test]
fn render_all_writes_one_image_per_backend_and_path() {
    if wgpu_paths().is_none() {
        return;
    }
    let dir = scratch("render_all");
    let png = dir.join("b.png");
    let out = oit(&["render", "--size", "16x16", "--backend", "all", "--json", "-o", png.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines: Vec<Value> =
        stdout(&out).lines().map(|l| serde_json::from_str(l).expect("a JSON line")).collect();
    assert_eq!(lines.len(), 3, "cpu, wgpu/hardware, wgpu/compute");
    let mut outputs: Vec<&str> = lines.iter().map(|l| l["output"].as_str().unwrap()).collect();
    outputs.sort_unstable();
    outputs.dedup();
    assert_eq!(outputs.len(), 3, "one name each: {outputs:?}");
    for name in ["b-cpu.png", "b-wgpu-hardware.png", "b-wgpu-compute.png"] {
        assert!(dir.join(name).is_file(), "{name} missing");
        assert!(stderr(&out).contains(name), "the note names {name}: {}", stderr(&out));
    }
    assert!(!png.exists(), "no image under the bare name");
}

#[cfg(feature = "wgpu")]
#[test]
fn sweep_rows_keep_their_raster_path() {
    if wgpu_paths().is_none() {
        return;
    }
    let out = oit(&[
        "sweep",
        "--size",
        "16x16",
        "--views",
        "2",
        "--techniques",
        "dp",
        "--backend",
        "all",
        "--json",
    ]);
    let v = parse_json(&out, "sweep --backend all --json");
    let mut paths: Vec<(String, String)> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|r| (r["backend"].as_str().unwrap().to_string(), r["raster"].as_str().unwrap().to_string()))
        .collect();
    assert_eq!(paths.len(), 2 * 3);
    paths.sort();
    paths.dedup();
    assert_eq!(paths.len(), 3, "{paths:?}");
    let table =
        stdout(&oit(&["sweep", "--size", "16x16", "--views", "2", "--techniques", "dp", "--backend", "all"]));
    for path in ["hardware", "compute"] {
        assert!(
            table.lines().any(|l| l.starts_with("dp") && l.contains("wgpu") && l.contains(path)),
            "{table}"
        );
    }
}

#[test]
fn bench_checks_every_option_before_measuring() {
    let dir = scratch("bench_checks");
    let out_dir = dir.join("report");
    let out_dir = out_dir.to_str().unwrap();
    let cases: [(&str, &[&str], &str); 9] = [
        ("unknown curve mesh", &["--curves", "nosuchmesh"], "nosuchmesh"),
        ("curve depth 0", &["--curve-depth", "0"], "--curve-depth"),
        ("curve depth too deep", &["--curve-depth", "100000"], "--curve-depth"),
        ("unknown scene in the list", &["--scenes", "planes:2,no-such-scene"], "no-such-scene"),
        ("empty curve grid", &["--curve-grids", "1x1,0x2"], "0x2"),
        ("bad curve technique", &["--curve-techniques", "dp,nope"], "nope"),
        ("bad curve size", &["--curve-size", "0x0"], "--curve-size"),
        ("huge curve size", &["--curve-size", "20000x2"], "20000"),
        ("zero frames", &["--frames", "0"], "--frames"),
    ];
    for (what, extra, named) in cases {
        let mut args = vec!["bench", "--size", "16x16", "--techniques", "dp", "--out", out_dir];
        args.extend_from_slice(extra);
        let start = std::time::Instant::now();
        let out = oit(&args);
        assert_one_error(&out, what);
        assert!(stderr(&out).contains(named), "{what}: the message names {named}: {}", stderr(&out));
        // nothing was measured: no report, and no time spent (the full run takes minutes here)
        assert!(!std::path::Path::new(out_dir).join("report.json").exists(), "{what}");
        assert!(start.elapsed().as_secs() < 30, "{what}: took {:?}", start.elapsed());
    }
}

#[test]
fn replot_rejects_absurd_numbers() {
    let dir = scratch("replot");
    let report = dir.join("report");
    let r = report.to_str().unwrap();
    let args = ["bench", "--size", "16x16", "--techniques", "dp,wavg", "--frames", "1", "--warmup", "0"];
    let out = oit(&[&args[..], &["--no-curves", "--out", r]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let json = report.join("report.json");
    let good = std::fs::read_to_string(&json).unwrap();
    let out = oit(&["bench", "--replot", r]);
    assert!(out.status.success(), "a report oit wrote draws again: {}", stderr(&out));

    // an EPR of 1e308 once made the plot's log axis span 300 decades, and the replot never ended
    let mut v: Value = serde_json::from_str(&good).unwrap();
    v["rows"][1]["epr"] = 1e308.into();
    std::fs::write(&json, v.to_string()).unwrap();
    let out = oit(&["bench", "--replot", r]);
    assert_one_error(&out, "epr 1e308");
    assert!(stderr(&out).contains("rows[1].epr"), "{}", stderr(&out));

    let mut v: Value = serde_json::from_str(&good).unwrap();
    v["rows"][0]["time_ms"] = (-1.0).into();
    std::fs::write(&json, v.to_string()).unwrap();
    assert_one_error(&oit(&["bench", "--replot", r]), "negative time");

    let damaged = good.replacen("\"epr\": 0.0", "\"epr\": 1e999", 1);
    assert_ne!(damaged, good, "dp is exact here");
    std::fs::write(&json, damaged).unwrap();
    assert_one_error(&oit(&["bench", "--replot", r]), "a number past f64");
}

/// Issue 41.6: `-t all` with an option some techniques refuse runs the others, lists the refused
/// ones with the reason after the table and exits 0; named techniques that are refused still fail
/// the command. Mutations caught: counting `Measurement::refused` runs as failures again in
/// compare.rs or bench.rs (exit 1), or treating named techniques as the catalogue (the named cases
/// exit 0). (A run of the catalogue where every technique is refused exits 1 too; no option refuses
/// every technique, so no case here reaches it.)
#[test]
fn all_runs_what_the_options_allow_and_lists_the_rest() {
    let base = ["--scene", "planes:4", "--size", "24x24", "--effect", "translucency"];
    let compare = |t: &str| oit(&[&["compare", "-t", t][..], &base[..]].concat());
    let out = compare("all");
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("refused under these options"), "{text}");
    for t in ["plain", "wavg", "wsum", "wboit", "mboit:4"] {
        assert!(text.contains(&format!("  {t} on cpu:")), "{t} listed: {text}");
    }
    assert!(text.lines().any(|l| l.starts_with("dp ")), "dp ran: {text}");
    assert_eq!(compare("wavg,dp").status.code(), Some(1), "a named technique refused fails");

    let dir = scratch("all-refused");
    let bench = |t: &str, out: &str| {
        let out_dir = dir.join(out);
        let out_dir = out_dir.to_str().expect("a UTF-8 path");
        let args = [
            &["bench", "-t", t, "--frames", "1", "--warmup", "0", "--no-curves", "--out", out_dir][..],
            &["--scenes", "planes:4", "--size", "24x24", "--effect", "translucency"][..],
        ]
        .concat();
        oit(&args)
    };
    let out = bench("all", "all");
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("refused under these options"), "{}", stdout(&out));
    assert_eq!(bench("wavg,wsum", "none").status.code(), Some(1), "nothing ran");
}

/// Issue 41.6: the CPU takes `--blend-target` as `--help` says (it ignores the target):
/// `-t wavg --blend-target unorm8` once failed on the CPU with "unorm8 holds [0, 1]", and `-t all`
/// listed wavg/wsum/wboit as refused. Mutation caught: the unorm8 refusal put back into
/// `Settings::validate` (both commands exit 1 or list refusals).
#[test]
fn the_cpu_takes_any_blend_target() {
    let dir = scratch("blend-target");
    let png = dir.join("out.png");
    let out = oit(&[
        "render",
        "--size",
        "16x16",
        "-t",
        "wavg",
        "--blend-target",
        "unorm8",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out =
        oit(&["compare", "--size", "16x16", "--scene", "planes:4", "-t", "all", "--blend-target", "unorm8"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stdout(&out).contains("refused"), "{}", stdout(&out));
    assert!(stdout(&out).lines().any(|l| l.starts_with("wsum ")), "{}", stdout(&out));
}

/// `oit ARGS` run in the background, killed after `seconds`: `None` when it had not ended (a
/// hang), so that a regression fails the test instead of hanging it.
#[cfg(unix)]
fn oit_within(args: &[&str], seconds: u64) -> Option<Output> {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_oit"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the oit binary runs");
    let until = std::time::Instant::now() + std::time::Duration::from_secs(seconds);
    while child.try_wait().expect("the child's status").is_none() {
        if std::time::Instant::now() > until {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Some(child.wait_with_output().expect("the child's output"))
}

/// Issue 41.5: a FIFO given as any file input is refused before it is opened for reading:
/// `open()` on a FIFO waits for a writer, and `--scene fifo.obj` hung. Every file oit reads is
/// tried: a model (alone and in a grid), `--calibration`, `bench --model`, `bench --replot` (its
/// report.json) and `view --script` (read before any window opens). Mutation caught: any of those
/// readers opening the path before `oit_core::open_regular`'s check (`File::open` or
/// `read_to_string` first) blocks, and the case fails after 30 s instead of hanging CI.
#[cfg(unix)]
#[test]
fn a_fifo_is_refused_for_every_file_input() {
    let dir = scratch("fifo");
    let fifo = dir.join("pipe.obj");
    let replot = dir.join("report");
    std::fs::create_dir_all(&replot).unwrap();
    let report_fifo = replot.join("report.json");
    for path in [&fifo, &report_fifo] {
        let made = Command::new("mkfifo").arg(path).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo {} (coreutils)", path.display());
    }
    let png = dir.join("out.png");
    let (f, png, replot) = (fifo.to_str().unwrap(), png.to_str().unwrap(), replot.to_str().unwrap());
    let grid = format!("grid:2x2:{f}");
    let mut cases: Vec<(&str, Vec<&str>)> = vec![
        ("--scene", vec!["render", "--size", "8x8", "--scene", f, "-o", png]),
        ("--scene grid", vec!["render", "--size", "8x8", "--scene", &grid, "-o", png]),
        ("compare --scene", vec!["compare", "--size", "8x8", "--scene", f]),
        ("--calibration", vec!["render", "--size", "8x8", "-t", "auto", "--calibration", f, "-o", png]),
        ("bench --model", vec!["bench", "--size", "8x8", "--model", f, "--frames", "1", "--out", replot]),
        ("bench --replot", vec!["bench", "--replot", replot]),
    ];
    if cfg!(feature = "view") {
        cases.push(("view --script", vec!["view", "--size", "8x8", "--script", f, "--screenshot", png]));
    }
    for (what, args) in cases {
        let out = oit_within(&args, 30).unwrap_or_else(|| panic!("{what}: oit blocked on a FIFO for 30 s"));
        assert_one_error(&out, what);
        assert!(stderr(&out).contains("not a regular file"), "{what}: {}", stderr(&out));
    }
}

/// Issue 41.4: a frame that covers no pixel has no error rate. `compare`'s table once printed EPR
/// and PSNR `NaN`, and `sweep`'s summary mean EPR `NaN`; both now say n/a, and the JSON has null.
/// The scene is one triangle of no area (its corners on a line): every technique renders nothing.
/// Mutations caught: `output::percent` or `output::psnr` without their NaN arm (`NaN` in a row),
/// sweep's summary averaging over views that covered nothing (`NaN`).
#[test]
fn empty_coverage_is_not_available_in_every_table() {
    let dir = scratch("empty-coverage");
    let flat = dir.join("flat.obj");
    std::fs::write(&flat, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let flat = flat.to_str().unwrap();
    let out = oit(&["compare", "--size", "16x16", "--scene", flat, "-t", "dp,wavg"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    for t in ["dp", "wavg"] {
        let row =
            text.lines().find(|l| l.starts_with(&format!("{t} "))).unwrap_or_else(|| panic!("{t}: {text}"));
        assert!(row.matches("n/a").count() >= 2, "EPR and PSNR n/a: {row}");
        assert!(!row.contains("inf"), "no perfect score: {row}");
    }
    assert!(!text.contains("NaN"), "{text}");
    let v = parse_json(
        &oit(&["compare", "--size", "16x16", "--scene", flat, "-t", "dp", "--json"]),
        "compare --json",
    );
    let row = &v.as_array().expect("an array of runs")[0];
    assert!(row["epr"].is_null() && row["psnr"].is_null(), "{row}");
    let out = oit(&["sweep", "--size", "16x16", "--scene", flat, "-t", "dp", "--views", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("n/a") && !text.contains("NaN"), "{text}");
}

/// A GLB of two scenes: scene 0 draws one quad (2 triangles), scene 1 two (4), the default 0.
fn two_scene_glb() -> Vec<u8> {
    let mut bin = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        p.iter().for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]},{"nodes":[1,2]}],
        "nodes":[{"mesh":0},{"mesh":0,"translation":[0,0,1]},{"mesh":0,"translation":[0,0,2]}],
        "meshes":[{"name":"quad","primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
        "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[1,0,0,0.5]},"alphaMode":"BLEND","doubleSided":true}],
        "buffers":[{"byteLength":60}],
        "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                     {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}]}"#;
    oit_core::pack_glb(json.as_bytes(), &bin).expect("a small GLB")
}

/// `--gltf-scene N` draws scene N of a glTF file on every command that takes `--scene`; an index
/// past the file's scenes, or the option with a scene that is not a glTF file, is one error line.
#[test]
fn gltf_scene_picks_a_scene_of_the_file() {
    let dir = scratch("gltf_scene");
    let file = dir.join("two.glb");
    std::fs::write(&file, two_scene_glb()).unwrap();
    let file = file.to_str().unwrap();
    let png = dir.join("out.png");
    let png = png.to_str().unwrap();
    let render = |extra: &[&str]| {
        let mut args = vec!["render", "--size", "16x16", "-t", "dp", "--scene", file, "-o", png];
        args.extend_from_slice(extra);
        oit(&args)
    };
    for (extra, triangles) in [(&[][..], 2), (&["--gltf-scene", "0"][..], 2), (&["--gltf-scene", "1"][..], 4)]
    {
        let out = render(extra);
        assert!(out.status.success(), "{extra:?}: {}", stderr(&out));
        assert!(stdout(&out).contains(&format!("({triangles} triangles)")), "{extra:?}: {}", stdout(&out));
    }
    let out = render(&["--gltf-scene", "2"]);
    assert_one_error(&out, "--gltf-scene past the scenes");
    assert!(
        stderr(&out).contains("scene 2 does not exist: the file has 2 scenes (numbered from 0)"),
        "{}",
        stderr(&out)
    );
    let out =
        oit(&["compare", "--size", "16x16", "--techniques", "dp", "--scene", file, "--gltf-scene", "1"]);
    assert!(out.status.success(), "compare: {}", stderr(&out));
    // with a scene that is not a glTF file: refused by every command, before anything is read
    let mut commands: Vec<Vec<&str>> = vec![
        vec!["render", "--size", "16x16", "-o", png],
        vec!["compare", "--size", "16x16"],
        vec!["sweep", "--size", "16x16"],
        vec!["bench", "--size", "16x16", "--out", dir.to_str().unwrap()],
    ];
    if cfg!(feature = "view") {
        commands.push(vec!["view"]);
    }
    for mut args in commands {
        args.extend_from_slice(&["--scene", "planes:2", "--gltf-scene", "1"]);
        let out = oit(&args);
        assert_one_error(&out, args[0]);
        assert!(
            stderr(&out)
                .contains("--gltf-scene 1 picks a scene of a glTF file, and scene 'planes:2' is not one"),
            "{}: {}",
            args[0],
            stderr(&out)
        );
    }
    // bench: --gltf-scene applies to every scene of --scenes
    let out = oit(&[
        "bench",
        "--size",
        "16x16",
        "--out",
        dir.to_str().unwrap(),
        "--scenes",
        &format!("{file},knot"),
        "--gltf-scene",
        "1",
        "--no-curves",
    ]);
    assert_one_error(&out, "bench --scenes with a scene that is not glTF");
    assert!(stderr(&out).contains("scene 'knot' is not one"), "{}", stderr(&out));
}
