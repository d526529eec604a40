//! The Vulkan backend's compute path against oit-cpu, on lavapipe in CI (without a device each
//! test prints that it was skipped; `OIT_REQUIRE_GPU=1`, which CI sets, makes that a failure).
//! The same fragments (per-pixel counts of the reference; fragments, captured, lost and tied of
//! every technique) and the same 8-bit images, no channel off by more than 1 (f32 compositing in
//! another order of operations: the tolerance oit-wgpu's compute path has, `checks::same_fragments`).
#![cfg(feature = "vulkan")]

use oit_core::{RasterPath, Settings, Technique, View};
use oit_tests::*;

/// Techniques whose result does not depend on the order fragments arrive in.
fn order_independent() -> Vec<Technique> {
    let mut t = vec![Technique::Reference];
    t.extend(Technique::all());
    t.extend([Technique::Bdp { passes: 3 }, Technique::Mdts64 { k: Some(3) }, Technique::Mlp { m: 1 }]);
    t
}

#[test]
fn vulkan_compute_path_equals_cpu() {
    let Some(vk) = oit_vulkan::backend_or_skip("vulkan_compute_path_equals_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for name in ["planes:8", "spheres:4", "knot", "cluster:200", "ties:5"] {
        let scene = scene(name);
        let base = Settings { raster: Some(RasterPath::Compute), ..settings(64, "reference") };
        let cam = camera(&scene, &base, View::default());
        for t in order_independent() {
            let s = Settings { technique: t, ..base.clone() };
            let v = render(&vk, &scene, &cam, &s);
            let c = render(&cpu, &scene, &cam, &s);
            let what = format!("{t} on {name}");
            if t == Technique::Reference {
                assert!(v.layers.is_some() && c.layers.is_some(), "{what}: the references count layers");
            }
            checks::same_fragments(&v, &c).unwrap_or_else(|e| panic!("{what}: {e}"));
        }
    }
}

/// The hardware path runs oit-wgpu's hardware-path WGSL on the same driver's rasterizer: every
/// technique's fragments, counters and image equal wgpu's hardware path (the images within 1 in 8
/// bits, as between the compute paths), and the reference's per-pixel layers too.
#[cfg(feature = "wgpu")]
#[test]
fn vulkan_hardware_path_equals_wgpu_hardware_path() {
    let Some(vk) = oit_vulkan::backend_or_skip("vulkan_hardware_path_equals_wgpu_hardware_path") else {
        return;
    };
    let Some(wgpu) = oit_wgpu::backend_or_skip("vulkan_hardware_path_equals_wgpu_hardware_path") else {
        return;
    };
    for name in ["planes:8", "knot", "cluster:200", "ties:5", "grid:2x2:spheres:2"] {
        let scene = scene(name);
        let base = Settings { raster: Some(RasterPath::Hardware), ..settings(64, "reference") };
        let cam = camera(&scene, &base, View::default());
        for t in order_independent() {
            let s = Settings { technique: t, ..base.clone() };
            let v = render(&vk, &scene, &cam, &s);
            let w = render(&wgpu, &scene, &cam, &s);
            let what = format!("{t} on {name}");
            if t == Technique::Plain {
                // wgpu blends plain in one pass of a blending pipeline; here its fragments are
                // kept and sorted by primitive id (a counting pass and a capture pass), as on the
                // compute path: the same picture, one pass more
                assert_eq!((v.stats.fragments, v.stats.geometry_passes), (w.stats.fragments, 2), "{what}");
                checks::off_edges_equal(&v.image, &w.image, &vec![false; v.image.pixels.len()])
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
                continue;
            }
            checks::same_fragments(&v, &w).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(v.layers, w.layers, "{what}: per-pixel layers");
        }
    }
}

/// What the hardware path does not do yet is refused by name, never run another way in silence:
/// the blend captures (`--hardware-capture blend`).
#[test]
fn vulkan_hardware_blend_capture_is_refused_by_name() {
    let Some(vk) = oit_vulkan::backend_or_skip("vulkan_hardware_blend_capture_is_refused_by_name") else {
        return;
    };
    let scene = scene("planes:4");
    let s = Settings {
        raster: Some(RasterPath::Hardware),
        hardware_capture: oit_core::HardwareCapture::Blend,
        ..settings(16, "dp")
    };
    let cam = camera(&scene, &s, View::default());
    match oit_core::Backend::render(&vk, &scene, &cam, &s) {
        Err(oit_core::OitError::Unsupported { backend, what }) => {
            assert_eq!(backend, "vulkan");
            assert!(what.contains("blend"), "{what}");
        }
        other => panic!("expected Unsupported, got {:?}", other.map(|f| f.stats)),
    }
}
