//! GPU time per frame: with timestamps (`Gpu::has_timestamps`; on lavapipe only with
//! `OIT_GPU_TIMESTAMPS=1`) a frame's `gpu_ms` is positive and the sum of its `gpu_pass_ms`;
//! without, it is `None` and the per-pass list empty. On a device without them (lavapipe, as CI
//! has) the test also runs itself again in a child process with `OIT_GPU_TIMESTAMPS=1`, so the
//! query pool's use is exercised (and checked by the validation layer where it is on).

use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};

/// On a device without timestamps, runs test `name` again in a child process with
/// `OIT_GPU_TIMESTAMPS=1` (once: the child has the variable) and requires it to pass.
fn again_with_timestamps(name: &str) {
    if std::env::var_os("OIT_GPU_TIMESTAMPS").is_some() {
        return;
    }
    again_with(name, &[("OIT_GPU_TIMESTAMPS", "1")]);
}

/// Runs test `name` again in a child process with the variables `vars` and requires it to pass.
fn again_with(name: &str, vars: &[(&str, &str)]) {
    let exe = std::env::current_exe().expect("the test binary");
    let status = std::process::Command::new(exe)
        .args([name, "--exact", "--test-threads=1"])
        .envs(vars.iter().copied())
        .status()
        .expect("the test binary runs again");
    assert!(status.success(), "{name} with {vars:?} failed");
}

#[test]
fn gpu_ms_is_the_sum_of_the_passes() {
    let Some(vk) = oit_vulkan::backend_or_skip("gpu_ms_is_the_sum_of_the_passes") else { return };
    let timed = vk.gpu().unwrap().has_timestamps();
    if !timed {
        again_with_timestamps("gpu_ms_is_the_sum_of_the_passes");
    }
    let scene = load_scene("planes:4").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    for t in ["dp", "fabs"] {
        let s = Settings {
            width: 24,
            height: 24,
            technique: t.parse::<Technique>().unwrap(),
            ..Settings::default()
        };
        let stats = vk.render(&scene, &cam, &s).unwrap_or_else(|e| panic!("{t}: {e}")).stats;
        println!("{t}: timestamps {timed}, gpu_ms {:?}, gpu_pass_ms {:?}", stats.gpu_ms, stats.gpu_pass_ms);
        if !timed {
            assert_eq!(stats.gpu_ms, None, "{t}");
            assert!(stats.gpu_pass_ms.is_empty(), "{t}: {:?}", stats.gpu_pass_ms);
            continue;
        }
        let total = stats.gpu_ms.unwrap_or_else(|| panic!("{t}: timestamps but no gpu_ms"));
        assert!(total > 0.0 && total.is_finite(), "{t}: gpu_ms {total}");
        let sum: f64 = stats.gpu_pass_ms.iter().map(|(_, ms)| ms).sum();
        assert!((total - sum).abs() <= 1e-9 * total, "{t}: gpu_ms {total} but the passes sum to {sum}");
        let labels: Vec<&str> = stats.gpu_pass_ms.iter().map(|(l, _)| l.as_str()).collect();
        for label in ["geometry", "resolve_main", "resolve"] {
            assert!(labels.contains(&label), "{t}: no '{label}' in {labels:?}");
        }
        // each label once
        let mut unique = labels.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), labels.len(), "{t}: {labels:?}");
    }
}

/// A frame with an opaque part times the opaque pass apart (`oit_gpu::geometry_label`):
/// `opaque` beside `geometry` on both raster paths, `classify` before the compute path's first
/// scene pass over it, and the labels still sum to `gpu_ms`.
#[test]
fn the_opaque_pass_is_timed_apart() {
    let Some(vk) = oit_vulkan::backend_or_skip("the_opaque_pass_is_timed_apart") else { return };
    if !vk.gpu().unwrap().has_timestamps() {
        again_with_timestamps("the_opaque_pass_is_timed_apart");
        return;
    }
    let scene = load_scene("wall:0.4:planes:4").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    for raster in [oit_core::RasterPath::Compute, oit_core::RasterPath::Hardware] {
        let s = Settings {
            width: 32,
            height: 32,
            technique: Technique::Fabs { k: None },
            raster: Some(raster),
            ..Settings::default()
        };
        let stats = vk.render(&scene, &cam, &s).unwrap_or_else(|e| panic!("{raster}: {e}")).stats;
        let labels: Vec<&str> = stats.gpu_pass_ms.iter().map(|(l, _)| l.as_str()).collect();
        println!("{raster}: {:?}", stats.gpu_pass_ms);
        assert!(stats.occluded > 0, "{raster}: the wall holds nothing back");
        let mut wanted = vec!["opaque", "geometry"];
        if raster == oit_core::RasterPath::Compute {
            wanted.push("classify");
        }
        for label in wanted {
            assert!(labels.contains(&label), "{raster}: no '{label}' in {labels:?}");
        }
        let total = stats.gpu_ms.unwrap_or_else(|| panic!("{raster}: timestamps but no gpu_ms"));
        let sum: f64 = stats.gpu_pass_ms.iter().map(|(_, ms)| ms).sum();
        assert!((total - sum).abs() <= 1e-9 * total, "{raster}: gpu_ms {total} but the passes sum to {sum}");
    }
}

/// `OIT_SETUP_PASSES=1` times the GPU setup's kernels apart (`setup setup_main`, ...), and they
/// still sum with the rest to `gpu_ms`; run in a child process with the setup forced onto the
/// GPU (`OIT_HOST_SETUP=0`) and timestamps on, so the variables reach no other test.
#[test]
fn the_setup_kernels_are_timed_apart_on_request() {
    const NAME: &str = "the_setup_kernels_are_timed_apart_on_request";
    let Some(vk) = oit_vulkan::backend_or_skip(NAME) else { return };
    if std::env::var_os("OIT_SETUP_PASSES").is_none() {
        again_with(NAME, &[("OIT_SETUP_PASSES", "1"), ("OIT_HOST_SETUP", "0"), ("OIT_GPU_TIMESTAMPS", "1")]);
        return;
    }
    let scene = load_scene("planes:4").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let s = Settings {
        width: 32,
        height: 32,
        technique: Technique::Fabs { k: None },
        raster: Some(oit_core::RasterPath::Compute),
        ..Settings::default()
    };
    let stats = vk.render(&scene, &cam, &s).unwrap().stats;
    let labels: Vec<&str> = stats.gpu_pass_ms.iter().map(|(l, _)| l.as_str()).collect();
    println!("{:?}", stats.gpu_pass_ms);
    for label in
        ["setup setup_main", "setup setup_count_main", "setup setup_items_main", "setup setup_finish_main"]
    {
        assert!(labels.contains(&label), "no '{label}' in {labels:?}");
    }
    assert!(!labels.contains(&"setup"), "the kernels are also timed together: {labels:?}");
    let total = stats.gpu_ms.expect("timestamps but no gpu_ms");
    let sum: f64 = stats.gpu_pass_ms.iter().map(|(_, ms)| ms).sum();
    assert!((total - sum).abs() <= 1e-9 * total, "gpu_ms {total} but the passes sum to {sum}");
}

/// `OIT_HOST_TIMES=1` prints a line a frame (stderr): its recording and its end's wait, which
/// the frame's wall time holds, and with timestamps its span on the device, which holds every
/// pass the frame timed (they run one after another, a barrier between each two), and from the
/// second frame on the device's idle time before it; the untimed gaps between its passes, which
/// with the passes fit the span; and the commands it recorded by kind. Run in a child process with timestamps on,
/// its output captured. Mutations caught: a span from the last pass's start (under the passes'
/// sum), the wait left out of the line, a gap counted to the later pass's end (passes and gaps
/// over the span).
#[test]
fn host_times_hold_the_frame_and_its_span_on_the_device() {
    const NAME: &str = "host_times_hold_the_frame_and_its_span_on_the_device";
    let Some(vk) = oit_vulkan::backend_or_skip(NAME) else { return };
    if std::env::var_os("OIT_HOST_TIMES").is_none() {
        let exe = std::env::current_exe().expect("the test binary");
        let out = std::process::Command::new(exe)
            .args([NAME, "--exact", "--test-threads=1", "--nocapture"])
            .envs([("OIT_HOST_TIMES", "1"), ("OIT_GPU_TIMESTAMPS", "1")])
            .output()
            .expect("the test binary runs again");
        let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(out.status.success(), "{NAME} with OIT_HOST_TIMES=1 failed:\n{stdout}\n{stderr}");
        // each number of a line that follows `key ` and ends at the next space
        let number = |line: &str, key: &str| -> Option<f64> {
            let at = line.find(key)? + key.len();
            line[at..].trim_start().split(' ').next()?.parse().ok()
        };
        let frames: Vec<&str> = stdout.lines().filter(|l| l.contains("frame gpu_ms ")).collect();
        let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("oit host times: ")).collect();
        assert_eq!(lines.len(), frames.len(), "a line a frame:\n{stdout}\n{stderr}");
        assert_eq!(frames.len(), 2, "{stdout}");
        for (i, (frame, line)) in frames.iter().zip(&lines).enumerate() {
            let gpu = number(frame, "gpu_ms").unwrap_or_else(|| panic!("{frame}"));
            let wall = number(frame, "wall_ms").unwrap_or_else(|| panic!("{frame}"));
            let recorded = number(line, "record+submit").unwrap_or_else(|| panic!("{line}"));
            let waited = number(line, "end readback").unwrap_or_else(|| panic!("{line}"));
            let span = number(line, "device span").unwrap_or_else(|| panic!("{line}"));
            // the line's figures are rounded to 0.001 ms
            assert!(recorded + waited <= wall + 0.002, "{line} over the frame's wall {wall} ms");
            assert!(span + 0.001 >= gpu, "{line}: the span is under the passes' {gpu} ms");
            assert!(span <= wall + 0.001, "{line}: the span is over the frame's wall {wall} ms");
            // the passes and the untimed gaps between them lie end to end within the span
            let untimed = number(line, "untimed in span").unwrap_or_else(|| panic!("{line}"));
            assert!(
                untimed >= 0.0 && gpu + untimed <= span + 0.003,
                "{line}: passes {gpu} ms and gaps over the span"
            );
            // every frame is submitted, clears its counters and copies its totals back
            let count = |kind: &str| {
                line.find(kind).and_then(|at| line[..at].trim_end().rsplit(' ').next()?.parse::<u32>().ok())
            };
            for kind in [" submissions", " transfers", " barriers"] {
                assert!(count(kind).is_some_and(|n| n >= 1), "{line}: no{kind}");
            }
            let idle = number(line, "device idle before");
            assert_eq!(idle.is_some(), i > 0, "{line}: idle time before every frame but the first");
        }
        return;
    }
    let scene = load_scene("planes:4").unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let s = Settings { width: 32, height: 32, technique: Technique::Fabs { k: None }, ..Settings::default() };
    for _ in 0..2 {
        let stats = vk.render(&scene, &cam, &s).unwrap().stats;
        let gpu = stats.gpu_ms.expect("timestamps but no gpu_ms");
        println!("frame gpu_ms {gpu} wall_ms {}", stats.wall_ms);
    }
}
