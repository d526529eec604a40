//! Issue 41.8: each GPU backend's hardware path against its compute path (whose fragments are
//! oit-cpu's, bit for bit) on the pixels the two rasterizers cover alike. The two may disagree on
//! a pixel whose centre lies on a projected edge, within the snapping precision
//! ([`checks::COVERAGE_SNAP`]); every other pixel has the same fragment count on both, the same
//! fragments, and must have the same colour ([`checks::covered_alike_equal`]). On the bunny at 64² nearly every pixel lies within a pixel
//! of some edge, so the one-pixel mask of `wgpu.rs` compares next to nothing there; this compares
//! every pixel but the few a snap can move.

use oit_core::metrics::edge_mask;
use oit_core::{Backend, RasterPath, Settings, Technique, View};
use oit_tests::*;

/// Each GPU backend whose device runs both raster paths (the backend itself, not one pinned to a
/// path, so that a frame's settings pick the path).
fn gpu_backends(test: &str) -> Vec<Box<dyn Backend>> {
    #[cfg_attr(not(any(feature = "wgpu", feature = "vulkan")), expect(unused_mut, reason = "no GPU backend"))]
    let mut out: Vec<Box<dyn Backend>> = Vec::new();
    #[cfg(feature = "wgpu")]
    if let Some(b) = oit_wgpu::backend_or_skip(test) {
        out.push(Box::new(b));
    }
    #[cfg(feature = "vulkan")]
    if let Some(b) = oit_vulkan::backend_or_skip(test)
        && b.capabilities().raster_paths.contains(&RasterPath::Hardware)
    {
        out.push(Box::new(b));
    }
    out
}

#[test]
fn hardware_path_equals_compute_path_where_both_cover_alike() {
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    for backend in gpu_backends("hardware_path_equals_compute_path_where_both_cover_alike") {
        let b = backend.as_ref();
        for name in ["bunny", "knot"] {
            let scene = scene(name);
            let base = settings(64, "reference");
            let cam = camera(&scene, &base, View::default());
            let near = edge_mask(&scene, &cam, 64, 64, checks::COVERAGE_SNAP);
            let on = |t: Technique, path| {
                let s = Settings { technique: t, raster: Some(path), ..base.clone() };
                b.render(&scene, &cam, &s).map_err(|e| format!("{t} on {path}: {e}"))
            };
            let counts =
                |path| on(Technique::Reference, path).map(|f| f.layers.expect("the reference's counts"));
            let (hl, cl) = (counts(RasterPath::Hardware).unwrap(), counts(RasterPath::Compute).unwrap());
            let covered = cl.iter().filter(|&&n| n > 0).count();
            assert!(covered > 1000, "{name}: {covered} covered pixels");
            for &t in &techniques {
                let (h, c) = match (on(t, RasterPath::Hardware), on(t, RasterPath::Compute)) {
                    (Ok(h), Ok(c)) => (h, c),
                    // refused alike on both paths (kbuf without interlock, mdts's alpha...)
                    (Err(_), Err(_)) => continue,
                    (h, c) => panic!("{} {t} on {name}: {:?} / {:?}", b.name(), h.err(), c.err()),
                };
                let (alike, moved) = checks::covered_alike_equal(&h.image, &c.image, &hl, &cl, &near)
                    .unwrap_or_else(|e| panic!("{} {t} on {name}: {e}", b.name()));
                println!(
                    "{} {t} on {name}: {alike} pixels covered alike compared, {moved} moved by a snap ({} near an edge)",
                    b.name(),
                    near.iter().filter(|&&m| m).count()
                );
            }
        }
    }
}

/// The check above fails on a production mutation of the hardware capture: this test binary runs
/// that test again in a child process under `OIT_MUTATION=hardware-drop-third` (oit-wgpu's
/// hardware raster then drops every third primitive's fragments, losing a layer or more at most
/// covered pixels of the bunny) and requires it to fail, naming a pixel whose fragment count
/// moved away from every edge. Only where wgpu's hardware path runs here.
#[test]
fn a_hardware_capture_that_loses_layers_fails_the_check() {
    let Some(_) = oit_wgpu::backend_or_skip("a_hardware_capture_that_loses_layers_fails_the_check") else {
        return;
    };
    let out = std::process::Command::new(std::env::current_exe().expect("this test binary"))
        .args(["hardware_path_equals_compute_path_where_both_cover_alike", "--exact", "--nocapture"])
        .env("OIT_MUTATION", "hardware-drop-third")
        .output()
        .expect("the test binary runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(!out.status.success(), "the mutated hardware capture passed the check:\n{text}");
    assert!(
        text.contains("wgpu") && text.contains("farther than"),
        "it failed, but not on the moved fragment counts:\n{text}"
    );
}
