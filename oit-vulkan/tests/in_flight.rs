//! Frames in flight on the Vulkan backend (issue 10): `Prepared::frame_loop` records and submits
//! frame i + 1 before it waits for frame i, as a renderer's frame loop does, and counts what the
//! same frames one at a time count; one frame at a time never has two submissions on the queue.

use oit_core::{Backend, Camera, Frame, Prepared, RasterPath, Settings, Stats, Technique, View, load_scene};

/// The counters a frame loop reports, as compared with one frame at a time.
fn key(t: &Stats) -> (u32, u64, u64, u64, u64, u64, u32) {
    (t.geometry_passes, t.fragments, t.captured, t.lost, t.tied, t.storage_bytes, t.max_layers)
}

fn settings(technique: &str, path: RasterPath) -> Settings {
    Settings {
        width: 48,
        height: 40,
        technique: technique.parse::<Technique>().unwrap(),
        raster: Some(path),
        ..Settings::default()
    }
}

/// Each frame of `cameras` one at a time, on a prepared scene of its own.
fn one_at_a_time(prepared: &mut dyn Prepared, cameras: &[Camera], s: &Settings) -> Vec<Stats> {
    cameras.iter().map(|c| prepared.frame_stats(c, s).unwrap()).collect()
}

/// A loop over `cameras`, each frame reported once.
fn looped(prepared: &mut dyn Prepared, cameras: &[Camera], s: &Settings) -> Vec<Stats> {
    let mut got = vec![None; cameras.len()];
    prepared
        .frame_loop(cameras, s, &mut |i, stats| {
            assert!(got[i].is_none(), "frame {i} reported twice");
            got[i] = Some(stats);
        })
        .unwrap();
    got.into_iter().map(|g| g.expect("every frame reported")).collect()
}

/// Techniques that read nothing back in mid-frame keep two frames on the queue in a loop, and
/// only there; the loop counts what one frame at a time counts, and a frame rendered after it
/// equals a one-shot render (image included).
#[test]
fn a_frame_loop_keeps_two_frames_in_flight() {
    let Some(vk) = oit_vulkan::backend_or_skip("a_frame_loop_keeps_two_frames_in_flight") else { return };
    let gpu = vk.gpu().expect("opened above");
    let scene = load_scene("planes:6").unwrap();
    let cameras: Vec<Camera> = (0..5)
        .map(|i| {
            Camera::orbit_scene(&scene, View { azimuth: 9.0 * i as f32, ..View::default() }, 1.2).unwrap()
        })
        .collect();
    let paths: Vec<RasterPath> = vk.capabilities().raster_paths;
    let techniques = ["plain", "wavg", "bdp", "fabs", "mdts64:8"];
    let mut expected = Vec::new();
    for &path in &paths {
        for technique in techniques {
            let s = settings(technique, path);
            let mut prepared = vk.prepare(&scene).unwrap();
            expected.push(one_at_a_time(prepared.as_mut(), &cameras, &s));
        }
    }
    assert_eq!(gpu.most_in_flight(), 1, "one frame at a time");
    let mut expected = expected.into_iter();
    for &path in &paths {
        for technique in techniques {
            let s = settings(technique, path);
            let mut prepared = vk.prepare(&scene).unwrap();
            assert_eq!(prepared.frames_in_flight(), oit_vulkan::FRAMES_IN_FLIGHT);
            let want: Vec<_> = expected.next().unwrap().iter().map(key).collect();
            let got: Vec<_> = looped(prepared.as_mut(), &cameras, &s).iter().map(key).collect();
            assert_eq!(got, want, "{technique} on {path}: a loop counts what frames one at a time count");
            let after = prepared.frame(&cameras[2], &s).unwrap();
            let fresh = vk.render(&scene, &cameras[2], &s).unwrap();
            assert_eq!(after.image, fresh.image, "{technique} on {path}: a frame after the loop");
        }
    }
    assert_eq!(gpu.most_in_flight(), oit_vulkan::FRAMES_IN_FLIGHT, "a frame loop");
}

/// The host's setup (no GPU setup) in a loop whose views zoom in, so the kept triangle and
/// work-list buffers grow while the frame before is in flight (they are replaced only after the
/// queue idles): every frame counts what it counts alone. Techniques with a mid-frame readback
/// (dp's peel stop, ll's sizing pass) wait there and still count the same.
#[test]
fn a_loop_whose_setup_grows_counts_what_frames_alone_count() {
    let Some(vk) = oit_vulkan::backend_or_skip("a_loop_whose_setup_grows_counts_what_frames_alone_count")
    else {
        return;
    };
    let vk = vk.with_gpu_setup(false);
    let scene = load_scene("knot").unwrap();
    let cameras: Vec<Camera> = [70.0, 40.0, 20.0, 10.0, 5.0, 30.0]
        .into_iter()
        .map(|fov| {
            Camera::orbit_scene(&scene, View { fov, elevation: 20.0, ..View::default() }, 1.2).unwrap()
        })
        .collect();
    for technique in ["fabs", "dp", "ll"] {
        let s = settings(technique, RasterPath::Compute);
        // storage as a one-shot frame's: ll's frames may keep the capacity an earlier view took
        let key = |t: &Stats| key(&as_one_shot(&scene, &s, t));
        let want: Vec<_> =
            one_at_a_time(vk.prepare(&scene).unwrap().as_mut(), &cameras, &s).iter().map(key).collect();
        assert!(want.windows(2).any(|w| w[0].1 < w[1].1), "{technique}: the views grow");
        let mut prepared = vk.prepare(&scene).unwrap();
        let got: Vec<_> = looped(prepared.as_mut(), &cameras, &s).iter().map(key).collect();
        assert_eq!(got, want, "{technique}");
    }
}

/// `t` with its storage as a one-shot frame of its view reports it: where the plan sizes arrays
/// by the fragment total (dfb, ll, the reference), a prepared frame may keep an earlier frame's
/// capacity (`Plan::fragment_capacity`); its capacity must hold its count, and is replaced by
/// its own count's. (oit-tests' `checks::one_shot_storage`, for this crate's tests.)
fn as_one_shot(scene: &oit_core::Scene, s: &Settings, t: &Stats) -> Stats {
    use oit_core::plan::{Counted, Plan, RESOLVE_STATE_BYTES};
    let plan = Plan::new("vulkan", scene, s).expect("planned");
    let pixels = u64::from(s.width) * u64::from(s.height);
    let base = plan.storage_bytes(pixels, Counted::default()) - pixels * RESOLVE_STATE_BYTES;
    let per_fragment: u64 =
        plan.arrays(Counted::default()).iter().map(|a| a.per_fragment * a.element_bytes).sum();
    if per_fragment == 0 {
        return t.clone();
    }
    let held = t.storage_bytes - base;
    assert!(
        held.is_multiple_of(per_fragment) && held / per_fragment >= t.fragments,
        "capacity under the count: {t:?}"
    );
    Stats { storage_bytes: base + per_fragment * plan.fragment_capacity(t.fragments), ..t.clone() }
}

/// Two views of `scene`: at it (its planes overlapping on screen), and looking away from it
/// (nothing on screen: one peel).
fn at_and_away(scene: &oit_core::Scene) -> (Camera, Camera) {
    let bounds = scene.bounds();
    let (c, r) = (bounds.center(), (bounds.max - bounds.min).length() * 0.5);
    let dir = glam::Vec3::new(0.1, 0.2, 1.0);
    let at = Camera::look_at(c + dir * 3.0 * r, c, 45.0, 1.0, 0.01 * r, 100.0 * r);
    let away = Camera::look_at(c + dir * 3.0 * r, c + dir * 6.0 * r, 45.0, 1.0, 0.01 * r, 100.0 * r);
    (at, away)
}

/// `got`, a prepared scene's frame, is what a one-shot render makes (`want`).
fn assert_frame_eq(got: &Frame, want: &Frame, what: &str) {
    assert_eq!(got.image, want.image, "{what}");
    assert_eq!(got.stats.geometry_passes, want.stats.geometry_passes, "{what}");
    assert_eq!(got.stats.fragments, want.stats.fragments, "{what}");
    assert_eq!(got.stats.captured, want.stats.captured, "{what}");
    assert_eq!(got.stats.lost, want.stats.lost, "{what}");
    assert_eq!(got.stats.storage_bytes, want.stats.storage_bytes, "{what}");
    assert_eq!(got.layers, want.layers, "{what}: the reference's layers");
}

/// A speculation made to miss and to fit on `vk`: after a frame of the view `away`, a frame of
/// `at` (whose count differs) runs again, taking at least `missed_waits` waits, and equals a
/// one-shot render; `at` again, speculated right, waits once; and, where `fewer_fits`, `away`
/// speculated from `at` fits, waits once and equals its one-shot render.
fn miss_then_fit(
    vk: &oit_vulkan::VulkanBackend,
    scene: &oit_core::Scene,
    s: &Settings,
    missed_waits: u64,
    fewer_fits: bool,
    what: &str,
) {
    let gpu = vk.gpu().expect("opened by the caller");
    let (at, away) = at_and_away(scene);
    let one_shot_at = vk.render(scene, &at, s).unwrap();
    let one_shot_away = vk.render(scene, &away, s).unwrap();
    let mut prepared = vk.prepare(scene).unwrap();
    let mut frame = |camera: &Camera| {
        let before = gpu.waits();
        let frame = prepared.frame(camera, s).unwrap();
        (frame, gpu.waits() - before)
    };
    frame(&away);
    let (got, waits) = frame(&at);
    assert!(waits >= missed_waits, "{what}: the speculation missed, the frame ran again ({waits} waits)");
    assert_frame_eq(&got, &one_shot_at, what);
    let (got, waits) = frame(&at);
    assert_eq!(waits, 1, "{what}: speculated right, one wait");
    assert_frame_eq(&got, &one_shot_at, what);
    if fewer_fits {
        let (got, waits) = frame(&away);
        assert_eq!(waits, 1, "{what}: a view that needs less fits, one wait");
        // arrays sized by the fragment total (dfb, ll, the reference) stay at the capacity `at`
        // took: what the frame allocated, and reports (`Plan::fragment_capacity`)
        let plan = oit_core::plan::Plan::new("vulkan", scene, s).expect("planned");
        let by_total = plan.arrays(oit_core::plan::Counted::default()).iter().any(|a| a.per_fragment > 0);
        let mut want = one_shot_away.clone();
        if by_total {
            want.stats.storage_bytes = one_shot_at.stats.storage_bytes;
        }
        assert_frame_eq(&got, &want, what);
    }
}

/// A peel loop run with the last frame's pass count (oit-gpu's peel loop, and the blend captures'
/// `OcclusionPeel`): each pass after the
/// first gated on the device by its predecessor's flag, the last flag checked at the end, so a
/// steady frame waits once. A view that needs more passes runs again (the first attempt's end,
/// then the second's wait after each pass, and its end); a view that needs fewer closes its gates
/// and counts only the passes that ran, without running again. The compute path's setup is on
/// the GPU here (on a CPU device it is on the host by default, and the host's work list cannot
/// be gated).
#[test]
fn a_speculated_peel_count_that_misses_runs_again() {
    let Some(vk) = oit_vulkan::backend_or_skip("a_speculated_peel_count_that_misses_runs_again") else {
        return;
    };
    let vk = vk.with_gpu_setup(true);
    let scene = load_scene("planes:5").unwrap();
    let (at, _) = at_and_away(&scene);
    for path in vk.capabilities().raster_paths {
        // and on the hardware path dp and ddp by the blend capture, whose loops end on their
        // occlusion queries (folded into the gate's flag on the device)
        let blend = if path == RasterPath::Hardware { &["dp", "ddp"][..] } else { &[] };
        let runs = ["dp", "ddp", "mlp:2"]
            .map(|t| (t, oit_core::HardwareCapture::Atomics))
            .into_iter()
            .chain(blend.iter().map(|&t| (t, oit_core::HardwareCapture::Blend)));
        for (technique, hardware_capture) in runs {
            let s = Settings { width: 40, hardware_capture, ..settings(technique, path) };
            let what = format!("{technique} ({hardware_capture:?}) on {path}");
            let passes = vk.render(&scene, &at, &s).unwrap().stats.geometry_passes;
            assert!(passes >= 3, "{what}: the planes need several passes");
            miss_then_fit(&vk, &scene, &s, u64::from(passes) + 1, true, &what);
        }
    }
}

/// Techniques that size storage from a counting pass's deepest pixel (`fabs`, `mdts`, and `plain`
/// on the compute path) or batch by it (`adp`) take an earlier frame's count instead of waiting
/// for it, and check it at the end (`VkCtx::deepest`): a view whose count differs runs again and
/// equals a one-shot render of it; one speculated right waits once.
#[test]
fn a_speculated_deepest_pixel_that_misses_runs_again() {
    let Some(vk) = oit_vulkan::backend_or_skip("a_speculated_deepest_pixel_that_misses_runs_again") else {
        return;
    };
    let scene = load_scene("planes:5").unwrap();
    let (at, _) = at_and_away(&scene);
    for path in vk.capabilities().raster_paths {
        for technique in ["plain", "fabs", "mdts", "adp"] {
            if technique == "plain" && path == RasterPath::Hardware {
                // blended in submission order: no counting pass
                continue;
            }
            let s = Settings { width: 40, ..settings(technique, path) };
            let layers = vk.render(&scene, &at, &s).unwrap().stats.max_layers;
            assert!(layers >= 3, "{technique}: the planes overlap");
            miss_then_fit(&vk, &scene, &s, 3, false, &format!("{technique} on {path}"));
        }
    }
}

/// `dfb`, `ll` and the reference size their fragment arrays from an earlier frame's fragment total rounded up to
/// its size class (`VkCtx::fragment_capacity`), checked at the end: a view with more fragments
/// than the capacity runs again and equals a one-shot render (image, counts, storage); one with
/// fewer fits, waits once and reports the capacity it kept (what it allocated).
#[test]
fn a_speculated_fragment_total_that_misses_runs_again() {
    let Some(vk) = oit_vulkan::backend_or_skip("a_speculated_fragment_total_that_misses_runs_again") else {
        return;
    };
    let scene = load_scene("planes:5").unwrap();
    let (at, away) = at_and_away(&scene);
    for path in vk.capabilities().raster_paths {
        for technique in ["dfb", "ll", "reference"] {
            let s = Settings { width: 40, ..settings(technique, path) };
            let fragments = |c: &Camera| vk.render(&scene, c, &s).unwrap().stats.fragments;
            assert!(
                fragments(&at) > 0 && fragments(&away) == 0,
                "{technique}: a view at the planes, one away"
            );
            miss_then_fit(&vk, &scene, &s, 3, true, &format!("{technique} on {path}"));
        }
    }
}

/// `fabs:K`'s overflow passes (and the tail's, `--overflow tail`), and `mdts:K`'s tail pass, are
/// gated on the device by the overflow flag where the raster has a gate: a steady frame waits once, and counts what the
/// host's setup (whose passes read the flag back) counts, image, passes, losses and merged
/// fragments included.
#[test]
fn fabs_overflow_passes_are_gated_on_the_device() {
    let Some(vk) = oit_vulkan::backend_or_skip("fabs_overflow_passes_are_gated_on_the_device") else {
        return;
    };
    let (gated, read_back) =
        (oit_vulkan::VulkanBackend::default().with_gpu_setup(true), vk.with_gpu_setup(false));
    let gpu = gated.gpu().expect("opened above");
    let scene = load_scene("planes:5").unwrap();
    let (at, _) = at_and_away(&scene);
    let cases = [
        ("fabs:2", oit_core::Overflow::Drop, 3),
        ("fabs:2", oit_core::Overflow::Tail, 4),
        // mdts:K's one tail pass, gated by the same word
        ("mdts:2", oit_core::Overflow::Tail, 2),
    ];
    for (technique, overflow, passes) in cases {
        let s = Settings { width: 40, overflow, ..settings(technique, RasterPath::Compute) };
        let want = read_back.render(&scene, &at, &s).unwrap();
        let overflow = format!("{technique} {overflow:?}");
        assert!(want.stats.lost > 0 || want.stats.merged > 0, "{overflow}: two slots overflow");
        assert!(want.stats.geometry_passes >= passes, "{overflow}: the overflow passes ran");
        let mut prepared = gated.prepare(&scene).unwrap();
        prepared.frame(&at, &s).unwrap();
        let before = gpu.waits();
        let got = prepared.frame(&at, &s).unwrap();
        assert_eq!(gpu.waits() - before, 1, "{overflow}: a steady frame waits once");
        assert_eq!(got.image, want.image, "{overflow}");
        let key = |t: &Stats| (key(t), t.merged);
        assert_eq!(key(&got.stats), key(&want.stats), "{overflow}");
    }
}
