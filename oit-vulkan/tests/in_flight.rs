//! Frames in flight on the Vulkan backend (issue 10): `Prepared::frame_loop` records and submits
//! frame i + 1 before it waits for frame i, as a renderer's frame loop does, and counts what the
//! same frames one at a time count; one frame at a time never has two submissions on the queue.

use oit_core::{Backend, Camera, Prepared, RasterPath, Settings, Stats, Technique, View, load_scene};

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
        let want: Vec<_> =
            one_at_a_time(vk.prepare(&scene).unwrap().as_mut(), &cameras, &s).iter().map(key).collect();
        assert!(want.windows(2).any(|w| w[0].1 < w[1].1), "{technique}: the views grow");
        let mut prepared = vk.prepare(&scene).unwrap();
        let got: Vec<_> = looped(prepared.as_mut(), &cameras, &s).iter().map(key).collect();
        assert_eq!(got, want, "{technique}");
    }
}
