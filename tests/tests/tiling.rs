//! Issue 11, item 2: a frame over its memory budget (`Settings::memory`, `--memory`) runs in screen
//! tiles that each fit, and the tiles put together are the untiled frame: on the paths with oit's
//! fixed-point rules (cpu, compute) image, per-pixel counts and losses bit for bit and the
//! counters equal, on the hardware path within the edge bound. Item 6: the depth complexity (the
//! reference's per-pixel counts as a histogram) is the same on every backend and path.

use oit_core::metrics::{DepthComplexity, edge_mask};
use oit_core::plan::{Counted, Plan};
use oit_core::{OitError, RasterPath, Settings, Technique, View};
use oit_tests::checks::off_edges_equal;
use oit_tests::*;

/// The plan's storage of `pixels` pixels before any count: what the tiling loop sizes tiles by.
fn need(scene: &oit_core::Scene, s: &Settings, pixels: u64) -> u64 {
    Plan::new("test", scene, s).expect("plan").storage_bytes(pixels, Counted::default())
}

#[test]
fn tiled_frames_equal_untiled_frames() {
    let scene = scene("knot");
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    let view = View { azimuth: 25.0, elevation: 15.0, ..View::default() };
    for backend in backends_for("tiled_frames_equal_untiled_frames") {
        let b = backend.as_ref();
        let who = label(b);
        let exact = b.raster_path(&Settings::default()) != RasterPath::Hardware;
        // (width, height, pixels a tile may hold, fewest tiles): a 2×2 grid, and an uneven one
        for (width, height, tile, fewest) in [(48, 48, 24 * 24, 4), (45, 37, 45 * 37 / 5, 5)] {
            for &technique in &techniques {
                let s = Settings { width, height, technique, ..Settings::default() };
                let cam = camera(&scene, &s, view);
                let what = format!("{who} {technique} {width}x{height}");
                let whole = render(b, &scene, &cam, &s);
                assert_eq!(whole.stats.tiles, 1, "{what}: an untiled frame is one tile");
                let budget = need(&scene, &s, tile);
                let tiled = render(b, &scene, &cam, &Settings { memory: Some(budget), ..s.clone() });
                let (w, t) = (&whole.stats, &tiled.stats);
                assert!(t.tiles >= fewest, "{what}: {} tiles under a budget of {tile} pixels", t.tiles);
                assert!(
                    t.storage_bytes <= budget,
                    "{what}: a tile of {} bytes over {budget}",
                    t.storage_bytes
                );
                assert!(t.geometry_passes >= w.geometry_passes, "{what}: tiles count their passes");
                assert_eq!(t.captured + t.lost, t.fragments, "{what}: accounting");
                if exact {
                    assert!(tiled.image == whole.image, "{what}: image");
                    assert_eq!(tiled.layers, whole.layers, "{what}: layers");
                    assert_eq!(tiled.lost_pixels, whole.lost_pixels, "{what}: lost per pixel");
                    assert_eq!(
                        (t.fragments, t.captured, t.lost, t.tied, t.max_layers),
                        (w.fragments, w.captured, w.lost, w.tied, w.max_layers),
                        "{what}: counters"
                    );
                } else {
                    let mask = edge_mask(&scene, &cam, width, height, 1.0);
                    off_edges_equal(&tiled.image, &whole.image, &mask)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    let drift = t.fragments.abs_diff(w.fragments) as f64 / w.fragments.max(1) as f64;
                    assert!(drift < 0.02, "{what}: {} fragments tiled, {} whole", t.fragments, w.fragments);
                }
            }
        }
    }
}

/// A budget that one pixel does not fit is a clear error, whether the plan says so before
/// anything runs or the backend finds it after its counting pass (a deep pixel of `fabs`); and a
/// budget that would need more tiles than oit runs is one too.
#[test]
fn budgets_too_small_are_clear_errors() {
    let scene = scene("knot");
    for backend in backends_for("budgets_too_small_are_clear_errors") {
        let b = backend.as_ref();
        let who = label(b);
        let s = Settings {
            width: 8,
            height: 8,
            technique: Technique::Fabs { k: Some(4) },
            ..Settings::default()
        };
        let cam = camera(&scene, &s, View::default());
        let e = b.render(&scene, &cam, &Settings { memory: Some(50), ..s.clone() }).unwrap_err();
        assert!(matches!(e, OitError::TooLarge { .. }), "{who}: {e}");
        assert!(e.to_string().contains("one pixel") && e.to_string().contains("--memory"), "{who}: {e}");
        // fabs sized from the count: one slot a pixel fits the plan's first figure, the knot's
        // deep pixels do not
        let counted = Settings { technique: Technique::Fabs { k: None }, ..s.clone() };
        let one_slot = need(&scene, &counted, 1);
        let e = b.render(&scene, &cam, &Settings { memory: Some(one_slot), ..counted }).unwrap_err();
        assert!(e.to_string().contains("one pixel"), "{who}: {e}");
        let big = Settings { width: 4096, height: 4096, memory: Some(need(&scene, &s, 64)), ..s.clone() };
        let e = b.render(&scene, &cam, &big).unwrap_err();
        assert!(e.to_string().contains("screen tiles"), "{who}: {e}");
    }
}

/// The reference's per-pixel counts give the same depth histogram on every backend and path (on
/// the hardware path, over the pixels away from triangle edges).
#[test]
fn depth_complexity_is_the_same_everywhere() {
    let scene = scene("knot");
    let s = settings(40, "reference");
    let cam = camera(&scene, &s, View::default());
    let mask = edge_mask(&scene, &cam, 40, 40, 1.0);
    let counts =
        |b: &dyn oit_core::Backend| render(b, &scene, &cam, &s).layers.expect("the reference counts");
    let cpu = counts(&oit_cpu::CpuBackend::default());
    let off_edges = |layers: &[u32]| -> Vec<u32> {
        layers.iter().zip(&mask).filter(|(_, e)| !**e).map(|(&n, _)| n).collect()
    };
    let expected = DepthComplexity::from_layers(&cpu);
    assert!(expected.max_depth >= 4, "the knot is deep: {expected:?}");
    assert_eq!(expected.histogram.iter().sum::<u64>(), 1600);
    for backend in backends_for("depth_complexity_is_the_same_everywhere") {
        let b = backend.as_ref();
        let layers = counts(b);
        if b.raster_path(&Settings::default()) == RasterPath::Hardware {
            let (mine, cpus) = (off_edges(&layers), off_edges(&cpu));
            assert_eq!(
                DepthComplexity::from_layers(&mine),
                DepthComplexity::from_layers(&cpus),
                "{}",
                label(b)
            );
        } else {
            assert_eq!(DepthComplexity::from_layers(&layers), expected, "{}", label(b));
        }
    }
}
