//! `plain` (unsorted alpha blending in primitive order) on every backend and path, and the blend
//! capture of `wavg`/`wsum` on wgpu's hardware path against its atomics capture.
//!
//! plain's error against the reference: exact where a pixel's fragments in primitive order are
//! farthest first (the blender's order is then depth order), wrong where they are not. Overlapping
//! quads seen from the front and from behind give one view of each: in one, every pixel equals
//! the reference (within 1 in 8 bits: the GPU blends back to front in f32, the resolve composites
//! front to back in f32); in the other, exactly the pixels two quads or more cover differ. Its
//! agreement across backends is held by the suites that run every technique: the compute paths'
//! fragments and images equal oit-cpu's (`wgpu.rs`, `vulkan.rs`), the hardware path's equal the
//! compute path's off projected triangle edges (`wgpu.rs`).

use oit_core::{RasterPath, Settings, Technique, View};
use oit_tests::*;

#[test]
fn plain_is_exact_only_where_primitive_order_is_back_to_front() {
    let scene = scene("planes:3");
    for backend in backends_for("plain_is_exact_only_where_primitive_order_is_back_to_front") {
        let who = label(backend.as_ref());
        let base = settings(48, "plain");
        let mut exact_views = 0;
        for azimuth in [0.0, 180.0] {
            let view = View { azimuth, ..FRONT };
            let (r, f) = with_reference(backend.as_ref(), &scene, view, &base, Technique::Plain);
            assert_eq!(f.stats.lost, 0, "{who}");
            assert_eq!(f.stats.captured, f.stats.fragments, "{who}");
            assert_eq!(
                f.stats.fragments, r.stats.fragments,
                "{who} at {azimuth}°: the reference's fragments"
            );
            let layers = r.layers.as_ref().expect("the reference counts layers");
            let worst =
                |i: usize| (0..3).map(|c| r.image.pixels[i][c].abs_diff(f.image.pixels[i][c])).max().unwrap();
            let off: Vec<usize> = (0..layers.len()).filter(|&i| worst(i) > 1).collect();
            let deep = (0..layers.len()).filter(|&i| layers[i] >= 2).count();
            assert!(deep > 0, "{who}: no pixel holds two quads at {azimuth}°");
            if off.is_empty() {
                exact_views += 1;
            } else {
                assert!(
                    off.iter().all(|&i| layers[i] >= 2),
                    "{who} at {azimuth}°: a one-layer pixel differs"
                );
                assert_eq!(off.len(), deep, "{who} at {azimuth}°: every pixel of two quads or more differs");
            }
        }
        assert_eq!(exact_views, 1, "{who}: plain must equal the reference from exactly one side");
    }
}

/// wavg/wsum with `--hardware-capture blend` (additive float blending) against the atomics
/// capture on the same path. The blend adds the same 8-bit integers (α·c, α, 1) in f32: every
/// partial sum is an integer and exact below 2^24, so up to 258 full-alpha white layers the sums,
/// whatever order the blender adds them in, equal the atomics' exactly, and so do the images
/// (asserted bit for bit). Deeper, each addition rounds by at most half an ulp: the relative
/// error of a sum is below n · 2^-24, 1.8e-5 at 300 layers, far under 1 in 255 of the image
/// (asserted within 1 in 8 bits on planes:300).
#[cfg(feature = "wgpu")]
#[test]
fn weighted_blend_equals_atomics() {
    use oit_core::{Backend, HardwareCapture};
    let Some(gpu) = oit_wgpu::backend_or_skip("weighted_blend_equals_atomics") else { return };
    let blendable = gpu.capabilities().limits.iter().any(|(k, v)| k == "FLOAT32_BLENDABLE" && v == "true");
    for name in ["planes:8", "spheres:4", "knot", "cluster:200", "planes:300"] {
        let scene = scene(name);
        for t in [Technique::WeightedAverage, Technique::WeightedSum] {
            let base = Settings { technique: t, raster: Some(RasterPath::Hardware), ..settings(48, "wavg") };
            let cam = camera(&scene, &base, FRONT);
            let atomics = render(&gpu, &scene, &cam, &base);
            let blend = Settings { hardware_capture: HardwareCapture::Blend, ..base.clone() };
            let b = match gpu.render(&scene, &cam, &blend) {
                Ok(frame) => frame,
                Err(e) if !blendable => {
                    assert!(e.to_string().contains("FLOAT32_BLENDABLE"), "{e}");
                    continue;
                }
                Err(e) => panic!("{t} on {name}: {e}"),
            };
            let what = format!("{t} on {name}");
            assert_eq!(b.stats.fragments, atomics.stats.fragments, "{what}: fragments");
            assert_eq!(b.stats.captured, atomics.stats.captured, "{what}: captured");
            assert_eq!((b.stats.lost, b.stats.geometry_passes), (0, 1), "{what}");
            let deepest = atomics.stats.max_layers;
            let worst = (0..b.image.pixels.len())
                .flat_map(|i| (0..3).map(move |c| (i, c)))
                .map(|(i, c)| b.image.pixels[i][c].abs_diff(atomics.image.pixels[i][c]))
                .max()
                .unwrap_or(0);
            if deepest <= 258 {
                assert_eq!(worst, 0, "{what}: {deepest} layers, the sums are exact integers");
            } else {
                assert!(worst <= 1, "{what}: {deepest} layers, off by {worst}");
            }
        }
    }
}
