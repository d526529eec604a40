//! The persistent renderer: frames of one `Prepared` scene equal one-shot renders bit for bit, and
//! a frame of the same size as an earlier one allocates no per-pixel storage (the backend's own
//! counter, `Prepared::storage_allocations`), on every backend and raster path.

use oit_core::{Frame, Settings, Shading, Technique, View};
use oit_tests::*;

/// Everything of a frame that does not depend on the clock.
fn same(a: &Frame, b: &Frame, what: &str) {
    assert_eq!(a.image, b.image, "{what}: image");
    assert_eq!(a.layers, b.layers, "{what}: layers");
    let (s, t) = (&a.stats, &b.stats);
    assert_eq!(
        (s.geometry_passes, s.fragments, s.captured, s.lost, s.tied, s.storage_bytes),
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
        for &technique in &techniques {
            let s = Settings { shading: Shading::Headlight, ..settings(48, &technique.to_string()) };
            let views = [View::default(), View { azimuth: 40.0, elevation: 15.0, ..View::default() }];
            let mut prepared = b.prepare(&scene).unwrap_or_else(|e| panic!("{who} prepare: {e}"));
            for (i, &view) in views.iter().enumerate() {
                let cam = camera(&scene, &s, view);
                let framed = prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
                let one_shot = render(b, &scene, &cam, &s);
                same(&framed, &one_shot, &format!("{who} {technique} view {i}"));
            }
            let made = prepared.storage_allocations();
            assert!(made > 0, "{who} {technique}: the counter counts the first frames' storage");
            // The same views again: the same sizes (K of the scene-sized techniques follows the
            // view, so both views' arrays are kept), nothing new.
            for (i, &view) in views.iter().enumerate() {
                let cam = camera(&scene, &s, view);
                let again = prepared.frame(&cam, &s).unwrap_or_else(|e| panic!("{who} {technique}: {e}"));
                let one_shot = render(b, &scene, &cam, &s);
                same(&again, &one_shot, &format!("{who} {technique} view {i}, again"));
                assert_eq!(
                    prepared.storage_allocations(),
                    made,
                    "{who} {technique} view {i}: a frame of a size seen before allocated per-pixel storage"
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
