//! `--atomic-storage image` (mdts, mdts64 and fabs on storage images by `imageAtomicMin` /
//! `imageAtomicAdd`) against the same techniques on storage buffers, which the conformance suite
//! holds to oit-cpu: frames are the same bits (image, fragments, captured, lost, merged, ties,
//! passes, storage), on both raster paths, at an odd size and in a window of a larger frame (the
//! texel of a pixel is `(px % width, px / width)`), with K fixed (pixels overflow: `--overflow
//! drop` and `tail`) and K from the counting pass. The exact ones (fabs, mdts64) also against the
//! reference. mdts64 runs where the device has 64-bit image atomics and is refused, naming the
//! extension, where it has not (lavapipe). A second frame of a prepared scene allocates nothing.

use oit_core::metrics::accuracy;
use oit_core::{
    AtomicStorage, Backend, Camera, Frame, OitError, Overflow, RasterPath, Region, Settings, Technique, View,
    load_scene,
};
use oit_vulkan::VulkanBackend;

fn backend(test: &str) -> Option<VulkanBackend> {
    oit_vulkan::backend_or_skip(test)?;
    Some(VulkanBackend::default())
}

fn key(f: &Frame) -> (u64, u64, u64, u64, u64, u32, u64) {
    let s = &f.stats;
    (s.fragments, s.captured, s.lost, s.merged, s.tied, s.geometry_passes, s.storage_bytes)
}

fn same(what: &str, image: &Frame, buffer: &Frame) {
    assert_eq!(
        key(image),
        key(buffer),
        "{what}: (fragments, captured, lost, merged, tied, passes, storage bytes), images vs buffers"
    );
    let differ = image.image.pixels.iter().zip(&buffer.image.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{what}: {differ} pixels differ between image and buffer atomics");
}

fn paths(vulkan: &VulkanBackend) -> Vec<RasterPath> {
    vulkan.capabilities().raster_paths
}

fn wide(vulkan: &VulkanBackend) -> bool {
    vulkan.gpu().expect("a device").info.image_atomics_64
}

#[test]
fn image_atomics_equal_buffer_atomics() {
    let Some(vulkan) = backend("image_atomics_equal_buffer_atomics") else { return };
    let mut techniques = vec!["mdts:3", "mdts", "fabs:3", "fabs"];
    if wide(&vulkan) {
        techniques.extend(["mdts64:3", "mdts64"]);
    }
    let mut overflowed = 0;
    let mut merged = 0;
    for name in ["planes:7", "spheres:3", "coplanar", "ties:4", "grid:2x1:knot"] {
        let scene = load_scene(name).unwrap();
        let camera = Camera::orbit_scene(
            &scene,
            View { azimuth: 25.0, elevation: 15.0, ..View::default() },
            61.0 / 47.0,
        )
        .unwrap();
        for &path in &paths(&vulkan) {
            for t in &techniques {
                let technique: Technique = t.parse().unwrap();
                for overflow in [Overflow::Drop, Overflow::Tail] {
                    let frame = Settings {
                        width: 61,
                        height: 47,
                        technique,
                        raster: Some(path),
                        overflow,
                        ..Settings::default()
                    };
                    let window = Settings {
                        width: 24,
                        height: 19,
                        region: Some(Region { x: 30, y: 20, full_width: 61, full_height: 47 }),
                        ..frame.clone()
                    };
                    for (part, buffers) in [("frame", frame), ("window", window)] {
                        let what = format!("{name}, {path:?}, {t}, {overflow:?}, {part}");
                        let images = Settings { atomic_storage: AtomicStorage::Image, ..buffers.clone() };
                        let b = vulkan
                            .render(&scene, &camera, &buffers)
                            .unwrap_or_else(|e| panic!("{what}: {e}"));
                        let i =
                            vulkan.render(&scene, &camera, &images).unwrap_or_else(|e| panic!("{what}: {e}"));
                        same(&what, &i, &b);
                        overflowed += u64::from(i.stats.lost > 0 || i.stats.merged > 0);
                        merged += i.stats.merged;
                    }
                }
            }
        }
    }
    // the cases must include pixels past K, dropped and merged, or the overflow passes went untried
    assert!(overflowed > 0 && merged > 0, "no frame overflowed ({overflowed}) or merged ({merged})");
}

#[test]
fn exact_image_atomics_match_the_reference() {
    let Some(vulkan) = backend("exact_image_atomics_match_the_reference") else { return };
    let mut techniques = vec!["fabs"];
    if wide(&vulkan) {
        techniques.push("mdts64");
    }
    for name in ["planes:9", "spheres:4", "coplanar"] {
        let scene = load_scene(name).unwrap();
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        for &path in &paths(&vulkan) {
            let base = Settings { width: 48, height: 48, raster: Some(path), ..Settings::default() };
            let reference = vulkan.render(&scene, &camera, &base).unwrap();
            for t in &techniques {
                let s = Settings {
                    technique: t.parse().unwrap(),
                    atomic_storage: AtomicStorage::Image,
                    ..base.clone()
                };
                let frame = vulkan.render(&scene, &camera, &s).unwrap();
                let what = format!("{name}, {path:?}, {t}");
                assert_eq!(frame.stats.fragments, reference.stats.fragments, "{what}: fragments");
                assert_eq!(frame.stats.lost, 0, "{what}: lost");
                let a = accuracy(&reference, &frame.image).unwrap();
                assert_eq!(
                    a.error_pixels, 0,
                    "{what}: {} error pixels against the reference",
                    a.error_pixels
                );
            }
        }
    }
}

#[test]
fn mdts64_on_images_needs_64_bit_image_atomics() {
    let Some(vulkan) = backend("mdts64_on_images_needs_64_bit_image_atomics") else { return };
    let scene = load_scene("planes:3").unwrap();
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let s = Settings {
        width: 16,
        height: 16,
        technique: "mdts64:4".parse().unwrap(),
        atomic_storage: AtomicStorage::Image,
        ..Settings::default()
    };
    match vulkan.render(&scene, &camera, &s) {
        Ok(frame) => {
            assert!(wide(&vulkan), "mdts64 ran on images on a device without 64-bit image atomics");
            assert_eq!(frame.stats.lost, 0);
        }
        Err(OitError::Unsupported { what, .. }) => {
            assert!(!wide(&vulkan), "refused on a device with 64-bit image atomics: {what}");
            assert!(
                what.contains("VK_EXT_shader_image_atomic_int64"),
                "the refusal names the extension: {what}"
            );
        }
        Err(e) => panic!("mdts64 on images: {e}"),
    }
    // the other backends refuse it whatever the technique's K
    for t in ["mdts:4", "fabs"] {
        let s = Settings { technique: t.parse().unwrap(), ..s.clone() };
        let err = oit_cpu::CpuBackend::default().render(&scene, &camera, &s).unwrap_err();
        assert!(err.to_string().contains("vulkan backend only"), "cpu, {t}: {err}");
    }
}

#[test]
fn a_second_image_atomics_frame_allocates_nothing() {
    let Some(vulkan) = backend("a_second_image_atomics_frame_allocates_nothing") else { return };
    let scene = load_scene("planes:5").unwrap();
    let mut prepared = vulkan.prepare(&scene).unwrap();
    for t in ["mdts:4", "fabs:4"] {
        let s = Settings {
            width: 40,
            height: 30,
            technique: t.parse().unwrap(),
            atomic_storage: AtomicStorage::Image,
            ..Settings::default()
        };
        let first = Camera::orbit_scene(&scene, View::default(), 4.0 / 3.0).unwrap();
        let second =
            Camera::orbit_scene(&scene, View { azimuth: 40.0, ..View::default() }, 4.0 / 3.0).unwrap();
        let a = prepared.frame(&first, &s).unwrap();
        let (allocations, pipelines) = (prepared.storage_allocations(), prepared.pipelines_created());
        let b = prepared.frame(&second, &s).unwrap();
        assert_eq!(prepared.storage_allocations(), allocations, "{t}: the second frame allocated");
        assert_eq!(prepared.pipelines_created(), pipelines, "{t}: the second frame built a pipeline");
        // the pooled images were cleared: the first view again is the first frame
        let again = prepared.frame(&first, &s).unwrap();
        same(&format!("{t}, the first view again"), &again, &a);
        assert_ne!(a.image.pixels, b.image.pixels, "{t}: two views, one image");
    }
}
