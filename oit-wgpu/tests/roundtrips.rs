//! CPU–GPU round trips inside a frame (issue 10): a steady frame (a prepared scene after its first
//! frame) whose technique sizes nothing from the GPU and stops on no GPU count reads back once,
//! at its end (counters, timestamps, the compute path's setup check and, when asked, the image and
//! per-pixel losses together). Before, every geometry pass read its fragment count back, every
//! timed pass its timestamps, and every compute-path frame its setup's counters before its passes.

use oit_core::{Backend, Camera, HardwareCapture, RasterPath, Settings, Technique, View, load_scene};

/// Two views of `scene`: at it (its planes overlapping on screen), and looking away from it
/// (nothing on screen: no fragment, the deepest pixel 0, one peel).
fn at_and_away(scene: &oit_core::Scene) -> (Camera, Camera) {
    let bounds = scene.bounds();
    let (c, r) = (bounds.center(), (bounds.max - bounds.min).length() * 0.5);
    let dir = glam::Vec3::new(0.1, 0.2, 1.0);
    let at = Camera::look_at(c + dir * 3.0 * r, c, 45.0, 1.0, 0.01 * r, 100.0 * r);
    let away = Camera::look_at(c + dir * 3.0 * r, c + dir * 6.0 * r, 45.0, 1.0, 0.01 * r, 100.0 * r);
    (at, away)
}

/// Settings of `width` × `height` for `technique` on `path`.
fn on_path(width: u32, height: u32, technique: &str, path: RasterPath) -> Settings {
    Settings {
        width,
        height,
        technique: technique.parse::<Technique>().unwrap(),
        raster: Some(path),
        ..Settings::default()
    }
}

/// `techniques` with the default (atomics) capture, then, on the hardware path, `dp` and `ddp` by
/// the blend capture, whose loops end on occlusion queries.
fn with_blend_peels<'t>(techniques: &[&'t str], path: RasterPath) -> Vec<(&'t str, HardwareCapture)> {
    let blend: &[&str] = if path == RasterPath::Hardware { &["dp", "ddp"] } else { &[] };
    let atomics = techniques.iter().map(|&t| (t, HardwareCapture::Atomics));
    atomics.chain(blend.iter().map(|&t| (t, HardwareCapture::Blend))).collect()
}

#[test]
fn a_steady_frame_reads_back_once() {
    let Some(backend) = oit_wgpu::backend_or_skip("a_steady_frame_reads_back_once") else { return };
    let gpu = backend.gpu().expect("opened above");
    let scene = load_scene("planes:6").unwrap();
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    for path in [RasterPath::Compute, RasterPath::Hardware] {
        // fabs:2 and mdts64:2 overflow on six planes (their extra passes gated on the device);
        // dp, ddp and mlp:2 peel with the last frame's pass count, gated likewise
        // dfb and ll size their arrays from the last frame's fragment total, adp its batches from
        // the last frame's set-bin count, each checked at the end
        // and on the hardware path dp and ddp by the blend capture, their occlusion-query loops
        // gated likewise
        let techniques = [
            "wavg",
            "wsum",
            "bdp",
            "bdp:2",
            "mdts64:8",
            "fabs",
            "fabs:2",
            "dp",
            "ddp",
            "mlp:2",
            "dfb",
            "ll",
            "adp",
            "reference",
        ];
        for (technique, hardware_capture) in with_blend_peels(&techniques, path) {
            let settings = Settings { hardware_capture, ..on_path(48, 40, technique, path) };
            let technique = format!("{technique} ({hardware_capture:?})");
            let mut prepared = backend.prepare(&scene).unwrap();
            let first = prepared.frame(&camera, &settings).unwrap();
            assert!(first.stats.fragments > 0, "{technique} on {path}: the scene has fragments");
            // fabs sizes K from a counting pass: the last frame's count, checked at the end
            let sizing = 0;
            let before = gpu.readbacks();
            let stats = prepared.frame_stats(&camera, &settings).unwrap();
            let steady = gpu.readbacks() - before;
            assert_eq!(stats.fragments, first.stats.fragments, "{technique} on {path}");
            assert_eq!(steady, 1 + sizing, "{technique} on {path}: readbacks of a steady frame");
            let before = gpu.readbacks();
            let again = prepared.frame(&camera, &settings).unwrap();
            assert_eq!(gpu.readbacks() - before, 1 + sizing, "{technique} on {path}: with the image");
            assert_eq!(again.image, first.image, "{technique} on {path}: the same frame twice");
            assert_eq!(again.layers, first.layers, "{technique} on {path}: the reference's layers");
            assert_eq!(again.stats.fragments, first.stats.fragments);
            assert_eq!(again.stats.captured, first.stats.captured);
            assert_eq!(again.stats.lost, first.stats.lost);
            assert_eq!(again.stats.geometry_passes, first.stats.geometry_passes, "{technique} on {path}");
        }
    }
}

/// A peel loop run with the last frame's pass count ([`oit_wgpu::GpuCtx::speculated_peels`]):
/// each pass after the first gated on the device by its predecessor's flag, the last flag checked
/// at the end. A view that needs more passes runs again (and equals a one-shot render of it: image,
/// passes, losses); a view that needs fewer closes its gates and counts only the passes that ran,
/// without running again.
#[test]
fn a_speculated_peel_count_that_misses_runs_again() {
    let Some(backend) = oit_wgpu::backend_or_skip("a_speculated_peel_count_that_misses_runs_again") else {
        return;
    };
    let gpu = backend.gpu().expect("opened above");
    let scene = load_scene("planes:5").unwrap();
    let (at, away) = at_and_away(&scene);
    for path in [RasterPath::Compute, RasterPath::Hardware] {
        for (technique, hardware_capture) in with_blend_peels(&["dp", "ddp", "mlp:2"], path) {
            let settings = Settings { hardware_capture, ..on_path(40, 40, technique, path) };
            let technique = format!("{technique} ({hardware_capture:?})");
            let one_shot_at = backend.render(&scene, &at, &settings).unwrap();
            let one_shot_away = backend.render(&scene, &away, &settings).unwrap();
            assert!(one_shot_at.stats.geometry_passes >= 3, "{technique}: the planes need several passes");
            let mut prepared = backend.prepare(&scene).unwrap();
            prepared.frame(&away, &settings).unwrap();
            let before = gpu.readbacks();
            let frame = prepared.frame(&at, &settings).unwrap();
            // the first attempt's end; then the second's read after each pass, and its end
            let passes = u64::from(one_shot_at.stats.geometry_passes);
            let waits = gpu.readbacks() - before;
            assert!(
                waits > passes,
                "{technique} on {path}: the frame needed more passes and ran again ({waits} waits)"
            );
            assert_eq!(frame.image, one_shot_at.image, "{technique} on {path}");
            assert_eq!(
                frame.stats.geometry_passes, one_shot_at.stats.geometry_passes,
                "{technique} on {path}"
            );
            assert_eq!(frame.stats.lost, one_shot_at.stats.lost, "{technique} on {path}");
            assert_eq!(frame.stats.captured, one_shot_at.stats.captured, "{technique} on {path}");
            // now speculating the deep view's count: the empty view closes the gates at once
            let before = gpu.readbacks();
            let frame = prepared.frame(&away, &settings).unwrap();
            assert_eq!(gpu.readbacks() - before, 1, "{technique} on {path}: fewer passes need no second run");
            assert_eq!(frame.image, one_shot_away.image, "{technique} on {path}");
            assert_eq!(
                frame.stats.geometry_passes, one_shot_away.stats.geometry_passes,
                "{technique} on {path}"
            );
            // and the deep view once more, speculated right (the empty view kept no new count)
            let before = gpu.readbacks();
            let frame = prepared.frame(&at, &settings).unwrap();
            assert_eq!(gpu.readbacks() - before, 1, "{technique} on {path}: the deep view, speculated");
            assert_eq!(frame.image, one_shot_at.image, "{technique} on {path}");
            assert_eq!(
                frame.stats.geometry_passes, one_shot_at.stats.geometry_passes,
                "{technique} on {path}"
            );
        }
    }
}

/// A prepared scene's setup, trusted after a frame that fitted, waits for nothing before its
/// passes; when a later view needs more room than the kept buffers have (a far view, then one
/// close enough that each triangle covers thousands of 8×8 tiles), the frame's end finds it and
/// the frame runs again, waiting for the setup and growing first: the image and counts equal a
/// one-shot render of that view. On a CPU device (setup on the host by default) the test runs
/// itself again in a child process with `OIT_HOST_SETUP=0`.
#[test]
fn a_setup_that_outgrows_its_buffers_runs_again() {
    const NAME: &str = "a_setup_that_outgrows_its_buffers_runs_again";
    let Some(backend) = oit_wgpu::backend_or_skip(NAME) else { return };
    let gpu = backend.gpu().expect("opened above");
    // the GPU's setup whatever the part's size (planes:2 is small enough for the host's)
    if oit_wgpu::setup_site(gpu) != oit_gpu::SetupSite::Device {
        if std::env::var_os("OIT_HOST_SETUP").is_some() {
            return; // the host's setup was asked for: nothing of the GPU's to test
        }
        let exe = std::env::current_exe().expect("the test binary");
        let status = std::process::Command::new(exe)
            .args([NAME, "--exact", "--test-threads=1"])
            .env("OIT_HOST_SETUP", "0")
            .status()
            .expect("the test binary runs again");
        assert!(status.success(), "{NAME} with the GPU's setup failed");
        return;
    }
    let scene = load_scene("planes:2").unwrap();
    let settings = on_path(512, 512, "wavg", RasterPath::Compute);
    let bounds = scene.bounds();
    let (c, r) = (bounds.center(), (bounds.max - bounds.min).length() * 0.5);
    let look = |d: f32| {
        Camera::look_at(c + glam::Vec3::new(0.1, 0.2, 1.0) * d * r, c, 45.0, 1.0, 0.01 * r, 100.0 * r)
    };
    // the planes a few pixels across, then filling the frame
    let (far, near) = (look(60.0), look(1.2));
    let mut prepared = backend.prepare(&scene).unwrap();
    prepared.frame(&far, &settings).unwrap();
    let steady = gpu.readbacks();
    prepared.frame(&far, &settings).unwrap();
    assert_eq!(gpu.readbacks() - steady, 1, "a trusted frame waits once, at its end");
    let before = gpu.readbacks();
    let frame = prepared.frame(&near, &settings).unwrap();
    // the end of the first attempt; then the second's setup waits (too small), grows, sets up
    // again and waits (fits), and its end
    assert_eq!(gpu.readbacks() - before, 4, "the near view outgrew the buffers and ran again");
    let one_shot = backend.render(&scene, &near, &settings).unwrap();
    assert_eq!(frame.image, one_shot.image);
    assert_eq!(frame.stats.fragments, one_shot.stats.fragments);
    assert_eq!(frame.stats.captured, one_shot.stats.captured);
    assert!(frame.stats.fragments > 100_000, "the near view covers the frame: {}", frame.stats.fragments);
    let before = gpu.readbacks();
    prepared.frame(&near, &settings).unwrap();
    assert_eq!(gpu.readbacks() - before, 1, "grown, the near view fits and waits once");
}

/// A storage size taken from the last frame's counting pass ([`oit_wgpu::GpuCtx::speculated_deepest`])
/// is checked at the frame's end: a view whose deepest pixel differs runs again and equals a
/// one-shot render of it (image, counts, storage), and the view after that is sized right away.
#[test]
fn a_speculated_size_that_misses_runs_again() {
    let Some(backend) = oit_wgpu::backend_or_skip("a_speculated_size_that_misses_runs_again") else { return };
    let gpu = backend.gpu().expect("opened above");
    let scene = load_scene("planes:5").unwrap();
    let (at, away) = at_and_away(&scene);
    for path in [RasterPath::Compute, RasterPath::Hardware] {
        let on_gpu = u64::from(
            path == RasterPath::Compute && !oit_gpu::sets_up_on_host(oit_wgpu::setup_site(gpu), &scene),
        );
        let settings = on_path(40, 40, "fabs", path);
        let mut prepared = backend.prepare(&scene).unwrap();
        prepared.frame(&away, &settings).unwrap();
        let before = gpu.readbacks();
        let frame = prepared.frame(&at, &settings).unwrap();
        // the first attempt's end; the second's counting pass and its end (and, on the GPU's
        // setup, its capacity check: a rerun waits for the setup too)
        assert_eq!(
            gpu.readbacks() - before,
            3 + on_gpu,
            "{path}: the deepest pixel changed, the frame ran again"
        );
        let one_shot = backend.render(&scene, &at, &settings).unwrap();
        assert_eq!(frame.image, one_shot.image, "{path}");
        assert_eq!(
            frame.stats.storage_bytes, one_shot.stats.storage_bytes,
            "{path}: sized as a one-shot frame"
        );
        assert_eq!(frame.stats.captured, one_shot.stats.captured, "{path}");
        assert!(frame.stats.max_layers >= 2, "{path}: the planes overlap on screen");
        let before = gpu.readbacks();
        prepared.frame(&at, &settings).unwrap();
        assert_eq!(gpu.readbacks() - before, 1, "{path}: the same view again is sized without waiting");
    }
}

/// `dfb`'s, `ll`'s and the reference's arrays sized from the last frame's fragment total
/// ([`oit_wgpu::GpuCtx::fragment_capacity`], rounded up to its size class) without waiting: a view
/// with more fragments than that capacity runs again and equals a one-shot render of it (image,
/// counts, storage); a view with fewer fits in the capacity it kept, reports that capacity's
/// storage (what it allocated, not its own count's) and waits once; and the view after a miss is
/// sized right away.
#[test]
fn a_speculated_fragment_total_that_misses_runs_again() {
    let Some(backend) = oit_wgpu::backend_or_skip("a_speculated_fragment_total_that_misses_runs_again")
    else {
        return;
    };
    let gpu = backend.gpu().expect("opened above");
    let scene = load_scene("planes:5").unwrap();
    let (at, away) = at_and_away(&scene);
    for path in [RasterPath::Compute, RasterPath::Hardware] {
        let on_gpu = u64::from(
            path == RasterPath::Compute && !oit_gpu::sets_up_on_host(oit_wgpu::setup_site(gpu), &scene),
        );
        for technique in ["dfb", "ll", "reference"] {
            let what = format!("{technique} on {path}");
            let settings = on_path(40, 40, technique, path);
            let mut prepared = backend.prepare(&scene).unwrap();
            let empty = prepared.frame(&away, &settings).unwrap();
            assert_eq!(empty.stats.fragments, 0, "{what}: nothing on screen looking away");
            let before = gpu.readbacks();
            let frame = prepared.frame(&at, &settings).unwrap();
            // the first attempt's end; the second's sizing readback and its end (and, on the GPU's
            // setup, its capacity check: a rerun waits for the setup too)
            assert_eq!(gpu.readbacks() - before, 3 + on_gpu, "{what}: the total grew, the frame ran again");
            let one_shot = backend.render(&scene, &at, &settings).unwrap();
            assert_eq!(frame.image, one_shot.image, "{what}");
            assert_eq!(frame.layers, one_shot.layers, "{what}: the reference's layers");
            assert_eq!(
                frame.stats.storage_bytes, one_shot.stats.storage_bytes,
                "{what}: sized as a one-shot frame"
            );
            assert_eq!(frame.stats.captured, one_shot.stats.captured, "{what}");
            assert!(frame.stats.fragments > 0, "{what}");
            let before = gpu.readbacks();
            prepared.frame(&at, &settings).unwrap();
            assert_eq!(gpu.readbacks() - before, 1, "{what}: the same view again is sized without waiting");
            // fewer fragments than the capacity: no rerun, in the capacity kept (what it allocated)
            let before = gpu.readbacks();
            let fewer = prepared.frame(&away, &settings).unwrap();
            assert_eq!(gpu.readbacks() - before, 1, "{what}: fewer fragments fit");
            assert_eq!(fewer.stats.storage_bytes, frame.stats.storage_bytes, "{what}: the capacity it kept");
            assert!(
                fewer.stats.storage_bytes > empty.stats.storage_bytes,
                "{what}: more than its own count's"
            );
        }
    }
}
