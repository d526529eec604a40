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
    t.extend([
        Technique::Bdp { passes: 3 },
        Technique::Mdts64 { k: Some(3) },
        Technique::Mlp { m: 1 },
        Technique::Mboit { m: 6 },
    ]);
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
            checks::same_fragments_as_cpu(&v, &c, t).unwrap_or_else(|e| panic!("{what}: {e}"));
        }
    }
}

/// The hardware path runs oit-wgpu's hardware-path WGSL on the same driver's rasterizer: every
/// technique's fragments, counters and image equal wgpu's hardware path (the images within 1 in 8
/// bits, as between the compute paths), and the reference's per-pixel layers too; `plain` blends
/// in one draw on both.
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
            checks::same_fragments(&v, &w).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(v.layers, w.layers, "{what}: per-pixel layers");
        }
    }
}

/// The graphics pipeline's own captures (`--hardware-capture blend`) against wgpu's on the same
/// driver: dp (depth test, occlusion queries), ddp and bdp (MAX blending), wavg and wsum
/// (additive blending) run the same WGSL, so their fragments, counters and images are equal; adp's
/// histogram by logic-op OR into 8 R32G32B32A32_UINT targets (wgpu has no logic ops and keeps its
/// atomics histogram there) sets the same bins, so adp is equal too. Each is held to the
/// reference as well: dp and ddp exact over distinct depths, and never wrong in silence.
#[cfg(feature = "wgpu")]
#[test]
fn vulkan_blend_captures_equal_wgpu_blend_captures() {
    let Some(vk) = oit_vulkan::backend_or_skip("vulkan_blend_captures_equal_wgpu_blend_captures") else {
        return;
    };
    let Some(wgpu) = oit_wgpu::backend_or_skip("vulkan_blend_captures_equal_wgpu_blend_captures") else {
        return;
    };
    for name in ["planes:8", "knot", "ties:5", "grid:2x2:spheres:2"] {
        let scene = scene(name);
        let base = Settings {
            raster: Some(RasterPath::Hardware),
            hardware_capture: oit_core::HardwareCapture::Blend,
            ..settings(64, "reference")
        };
        let cam = camera(&scene, &base, View::default());
        let reference = render(&vk, &scene, &cam, &base);
        for t in ["dp", "ddp", "bdp", "wavg", "wsum", "adp"] {
            let t: Technique = t.parse().unwrap();
            for max_peels in [None, Some(2)] {
                let s = Settings { technique: t, max_peels, ..base.clone() };
                let what = format!("{t} --max-peels {max_peels:?} on {name}");
                let v = render(&vk, &scene, &cam, &s);
                let w = render(&wgpu, &scene, &cam, &s);
                checks::same_fragments(&v, &w).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(v.stats.captured, w.stats.captured, "{what}");
                // adp's logic-op histogram adds its 8 targets (128 bytes a pixel) to the storage
                let targets = if t == Technique::Adp { 128 * u64::from(s.width * s.height) } else { 0 };
                assert_eq!(v.stats.storage_bytes, w.stats.storage_bytes + targets, "{what}");
                // against the reference itself: the peels exact where they run to the end over
                // distinct depths (equal depths in one peel keep one fragment, the others counted
                // lost: ties:5), and everything never wrong in silence (wavg and wsum are
                // approximations, held to wgpu's blend and atomics captures above)
                let distinct = !name.starts_with("ties");
                if matches!(t, Technique::Dp | Technique::Ddp) && max_peels.is_none() && distinct {
                    checks::exact(&reference, &v).unwrap_or_else(|e| panic!("{what}: {e}"));
                } else if !matches!(t, Technique::WeightedAverage | Technique::WeightedSum) {
                    checks::never_silent(&reference, &v).unwrap_or_else(|e| panic!("{what}: {e}"));
                }
            }
        }
    }
}
