//! The persistent renderer: frames of one `Prepared` scene equal one-shot renders bit for bit, and
//! a frame of the same size and view as an earlier one creates nothing (the backend's own
//! counter, `Prepared::storage_allocations`: per-pixel storage, and on wgpu the geometry's
//! buffers too), on every backend and raster path.

use oit_core::{Camera, Frame, HardwareCapture, OitError, Scene, Settings, Shading, Technique, View};
use oit_tests::*;

/// Everything of a frame that does not depend on the clock; a prepared frame's storage (`a`,
/// of `backend` rendering `scene` under `settings`) as its one-shot frame's (`b`):
/// `checks::one_shot_storage`, where it kept an earlier view's capacity.
fn same(a: &Frame, b: &Frame, what: &str, (backend, scene, settings): (&str, &Scene, &Settings)) {
    assert_eq!(a.image, b.image, "{what}: image");
    assert_eq!(a.layers, b.layers, "{what}: layers");
    let (s, t) = (&a.stats, &b.stats);
    let storage =
        checks::one_shot_storage(backend, scene, settings, s).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(
        (s.geometry_passes, s.fragments, s.captured, s.lost, s.tied, storage),
        (t.geometry_passes, t.fragments, t.captured, t.lost, t.tied, t.storage_bytes),
        "{what}: stats"
    );
}

#[test]
fn prepared_frames_equal_one_shot_renders_and_reuse_storage() {
    let scene = scene("knot");
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    for backend in backends_for("prepared_frames_equal_one_shot_renders_and_reuse_storage") {
        let b = backend.as_ref();
        let who = label(b);
        // every technique with its default capture, and the hardware path's blend captures (oit's
        // own vertex stage in the techniques' pipelines; elsewhere the setting is ignored)
        let runs = techniques.iter().map(|&t| (t, HardwareCapture::Atomics)).chain(
            ["dp", "ddp", "bdp", "wavg", "wsum"]
                .map(|t| (t.parse::<Technique>().expect("a technique"), HardwareCapture::Blend)),
        );
        for (technique, capture) in runs {
            let s = Settings {
                shading: Shading::Headlight,
                hardware_capture: capture,
                ..settings(48, &technique.to_string())
            };
            let what = format!("{who} {technique} ({capture:?})");
            let views = [View::default(), View { azimuth: 40.0, elevation: 15.0, ..View::default() }];
            let mut prepared = b.prepare(&scene).unwrap_or_else(|e| panic!("{who} prepare: {e}"));
            let mut refused = false;
            for (i, &view) in views.iter().enumerate() {
                let cam = camera(&scene, &s, view);
                let framed = match prepared.frame(&cam, &s) {
                    Ok(frame) => frame,
                    // a blend capture the device cannot run (no FLOAT32_BLENDABLE) says so
                    Err(OitError::Unsupported { what: why, .. }) if capture == HardwareCapture::Blend => {
                        eprintln!("{what}: not run: {why}");
                        refused = true;
                        break;
                    }
                    Err(e) => panic!("{what}: {e}"),
                };
                let one_shot = render(b, &scene, &cam, &s);
                same(&framed, &one_shot, &format!("{what} view {i}"), (b.name(), &scene, &s));
            }
            if refused {
                continue;
            }
            let made = prepared.storage_allocations();
            let pipelines = prepared.pipelines_created();
            assert!(made > 0, "{what}: the counter counts the first frames' storage");
            // The same views again: the same sizes (K of the scene-sized techniques follows the
            // view, so both views' arrays are kept) and the same triangles (the compute path's
            // buffers have grown to the larger view's), nothing new.
            for (i, &view) in views.iter().enumerate() {
                let cam = camera(&scene, &s, view);
                // what ran once runs again: an error here is a failure, not the end of the check
                let again =
                    prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("{what} view {i}, again: {e}"));
                let one_shot = render(b, &scene, &cam, &s);
                same(&again, &one_shot, &format!("{what} view {i}, again"), (b.name(), &scene, &s));
                assert_eq!(
                    prepared.storage_allocations(),
                    made,
                    "{what} view {i}: a frame of a view and size seen before created a buffer"
                );
                assert_eq!(
                    prepared.pipelines_created(),
                    pipelines,
                    "{what} view {i}: a pipeline was created"
                );
            }
        }
    }
}

#[test]
fn a_new_size_allocates_and_then_reuses() {
    let scene = scene("planes:4");
    for backend in backends_for("a_new_size_allocates_and_then_reuses") {
        let b = backend.as_ref();
        let who = label(b);
        let mut prepared = b.prepare(&scene).unwrap();
        let small = settings(16, "fabs");
        let large = settings(32, "fabs");
        let cam = camera(&scene, &small, FRONT);
        prepared.frame(&cam, &small).unwrap();
        let n1 = prepared.storage_allocations();
        prepared.frame(&cam, &large).unwrap();
        let n2 = prepared.storage_allocations();
        assert!(n2 > n1, "{who}: a larger frame needs larger arrays");
        prepared.frame(&cam, &small).unwrap();
        prepared.frame(&cam, &large).unwrap();
        assert_eq!(prepared.storage_allocations(), n2, "{who}: both sizes are kept");
    }
}

/// On wgpu the geometry is uploaded once: the hardware path's frames at new views write only the
/// instances' matrices (no buffer created, the scene's or the boxes'), and the compute path's
/// frames write their triangles into the buffers kept since the first frames.
#[cfg(feature = "wgpu")]
#[test]
fn wgpu_geometry_is_uploaded_once() {
    use oit_core::RasterPath;
    let Some(backend) = oit_wgpu::backend_or_skip("wgpu_geometry_is_uploaded_once") else {
        return;
    };
    // four instances of one mesh: its vertices are uploaded once for all four
    let scene = scene("grid:2x2:knot");
    let views = [
        View::default(),
        View { azimuth: 40.0, elevation: 15.0, ..View::default() },
        View { azimuth: -70.0, elevation: -20.0, ..View::default() },
    ];
    for path in [RasterPath::Hardware, RasterPath::Compute] {
        let mut prepared = backend.prepare_scene(&scene).unwrap();
        // fabs draws the scene; bdp (bounds from the boxes) also the instances' bounding boxes
        for technique in ["fabs:8", "bdp"] {
            let s = Settings { raster: Some(path), ..settings(40, technique) };
            let frame = |prepared: &mut oit_wgpu::WgpuPrepared<'_>, view: View| {
                use oit_core::Prepared as _;
                let cam = camera(&scene, &s, view);
                let framed = prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("{path} {technique}: {e}"));
                same(
                    &framed,
                    &render(&backend, &scene, &cam, &s),
                    &format!("{path} {technique}"),
                    ("wgpu", &scene, &s),
                );
            };
            frame(&mut prepared, views[0]);
            let first = prepared.geometry_allocations();
            assert!(first > 0, "{path} {technique}: the first frame uploads");
            if path == RasterPath::Hardware {
                // no view needs more: the geometry is the same, only the matrices change
                for &view in &views[1..] {
                    frame(&mut prepared, view);
                    assert_eq!(
                        prepared.geometry_allocations(),
                        first,
                        "{path} {technique}: a new view uploaded"
                    );
                }
            } else {
                for &view in &views[1..] {
                    frame(&mut prepared, view);
                }
                let grown = prepared.geometry_allocations();
                for &view in &views {
                    frame(&mut prepared, view);
                }
                assert_eq!(
                    prepared.geometry_allocations(),
                    grown,
                    "{path} {technique}: a view seen before grew a buffer"
                );
            }
        }
    }
}

/// Issue 10.1: after the first frame, frames of a prepared scene create no pipeline, at any view
/// (views change the scene-sized techniques' K, a kernel parameter, never a shader's source), on
/// every backend and path that makes pipelines (the counter is the device's,
/// `Prepared::pipelines_created`).
#[test]
fn steady_frames_create_no_pipeline() {
    let scene = scene("knot");
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    let views: Vec<View> =
        (0..4).map(|i| View { azimuth: 35.0 * i as f32, elevation: 10.0, ..View::default() }).collect();
    for backend in backends_for("steady_frames_create_no_pipeline") {
        let b = backend.as_ref();
        let who = label(b);
        for &technique in &techniques {
            let s = settings(40, &technique.to_string());
            let mut prepared = b.prepare(&scene).unwrap_or_else(|e| panic!("{who} prepare: {e}"));
            prepared
                .frame(&camera(&scene, &s, views[0]), &s)
                .unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
            let Some(first) = prepared.pipelines_created() else { continue };
            assert!(first > 0, "{who} {technique}: the first frame builds its pipelines");
            for (i, &view) in views.iter().enumerate().skip(1) {
                let cam = camera(&scene, &s, view);
                prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
                prepared.frame_stats(&cam, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
                assert_eq!(prepared.pipelines_created(), Some(first), "{who} {technique}, frame {}", i + 1);
            }
        }
    }
}

/// `Prepared::frame_stats` (the steady-state frame `oit bench` times: no image read back) renders
/// the same frame as `Prepared::frame`: the same counters.
#[test]
fn frame_stats_counts_what_frame_counts() {
    let scene = scene("spheres:3");
    for backend in backends_for("frame_stats_counts_what_frame_counts") {
        let b = backend.as_ref();
        let who = label(b);
        for technique in ["plain", "dp", "wavg", "fabs", "adp", "dfb"] {
            let s = settings(40, technique);
            let cam = camera(&scene, &s, FRONT);
            let mut prepared = b.prepare(&scene).unwrap();
            let frame = prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
            let stats = prepared.frame_stats(&cam, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
            let key = |t: &oit_core::Stats| {
                (t.geometry_passes, t.fragments, t.captured, t.lost, t.tied, t.storage_bytes, t.max_layers)
            };
            assert_eq!(key(&stats), key(&frame.stats), "{who} {technique}");
            assert!(stats.fragments > 0, "{who} {technique}");
        }
    }
}

/// `Prepared::frame_loop` (the frame loop `oit bench` times as the steady state, frames in flight
/// on wgpu) renders each view's frame: its counters equal `frame_stats`' for that view, each frame
/// is reported once, and the views differ in depth complexity, so a frame whose speculation
/// (sizing, peel count) the previous view set wrong runs again. In the steady state (one view,
/// looped twice) the second loop allocates nothing: the frames in flight take turns with the
/// storage the first made.
#[test]
fn frame_loop_counts_what_frame_stats_counts() {
    let scene = scene("knot");
    let views: Vec<View> =
        (0..5).map(|i| View { azimuth: 40.0 * i as f32, elevation: 15.0, ..View::default() }).collect();
    for backend in backends_for("frame_loop_counts_what_frame_stats_counts") {
        let b = backend.as_ref();
        let who = label(b);
        for technique in
            ["reference", "plain", "dp", "ddp", "wavg", "bdp", "fabs", "mdts", "adp", "mlp:2", "dfb", "ll"]
        {
            let s = settings(40, technique);
            let cameras: Vec<Camera> = views.iter().map(|&v| camera(&scene, &s, v)).collect();
            // storage as a one-shot frame's: a frame may keep the capacity an earlier view took
            let key = |t: &oit_core::Stats| {
                let storage = checks::one_shot_storage(b.name(), &scene, &s, t)
                    .unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
                (t.geometry_passes, t.fragments, t.captured, t.lost, t.tied, storage, t.max_layers)
            };
            let expected: Vec<_> = {
                let mut prepared = b.prepare(&scene).unwrap();
                cameras
                    .iter()
                    .map(|c| {
                        key(&prepared.frame_stats(c, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}")))
                    })
                    .collect()
            };
            assert!(expected.windows(2).any(|w| w[0].1 != w[1].1), "{who} {technique}: the views differ");
            let mut prepared = b.prepare(&scene).unwrap();
            let mut run = |cameras: &[Camera]| {
                let mut got = vec![None; cameras.len()];
                prepared
                    .frame_loop(cameras, &s, &mut |i, stats| {
                        assert!(got[i].is_none(), "{who} {technique}: frame {i} reported twice");
                        got[i] = Some(key(&stats));
                    })
                    .unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
                got.into_iter().map(|g| g.expect("every frame reported")).collect::<Vec<_>>()
            };
            assert_eq!(run(&cameras), expected, "{who} {technique}: a loop over the views");
            let steady = vec![cameras[0]; 4];
            assert_eq!(run(&steady), vec![expected[0]; 4], "{who} {technique}: one view");
            let allocations = prepared.storage_allocations();
            let mut run = |cameras: &[Camera]| {
                prepared.frame_loop(cameras, &s, &mut |_, _| {}).map(|()| prepared.storage_allocations())
            };
            assert_eq!(run(&steady).unwrap(), allocations, "{who} {technique}: a second loop at one view");
        }
    }
}
