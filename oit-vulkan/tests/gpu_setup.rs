//! The compute path's setup on the GPU (oit-wgpu's `setup.wgsl` compiled to SPIR-V) against the
//! host's (oit-core's `TriangleSetup`): frames through either are the same bits (image, fragments,
//! captured, lost, ties, passes), on scenes that clip at the near and far planes and past the
//! guard band, in windows of a larger frame (screen tiles), and for the bounds passes of bdp and
//! adp (the instances' boxes). A prepared scene whose view later needs more room than its kept
//! buffers hold (seen only at the frame's end once they were trusted) runs the frame again into
//! grown buffers, and still equals the host's. Run on lavapipe in CI, where the GPU setup is not
//! the default (`VulkanBackend::gpu_setup` forces it).

use glam::Vec3;
use oit_core::{Backend, Camera, Frame, RasterPath, Region, Scene, Settings, Technique, View, load_scene};
use oit_vulkan::VulkanBackend;

fn backends() -> Option<(VulkanBackend, VulkanBackend)> {
    oit_vulkan::backend_or_skip("gpu_setup_frames_equal_host_setup")?;
    let gpu = VulkanBackend::default().with_gpu_setup(true);
    let host = VulkanBackend::default().with_gpu_setup(false);
    Some((gpu, host))
}

/// The fitted orbit; a view whose near and far planes cut the scene; one so narrow that most
/// triangles reach past the guard band.
fn cameras(scene: &Scene, aspect: f32) -> Vec<(&'static str, Camera)> {
    let bounds = scene.bounds();
    let (c, r) = (bounds.center(), (bounds.max - bounds.min).length() * 0.5);
    let eye = c + Vec3::new(0.3, 0.4, 1.5) * r;
    let d = (eye - c).length();
    vec![
        (
            "orbit",
            Camera::orbit_scene(scene, View { azimuth: 30.0, elevation: 20.0, ..View::default() }, aspect)
                .unwrap(),
        ),
        ("near and far cut", Camera::look_at(eye, c, 50.0, aspect, d - 0.3 * r, d + 0.2 * r)),
        ("guard band", Camera::look_at(c + Vec3::new(0.0, 0.1, 0.6) * r, c, 0.4, aspect, 0.01 * r, 4.0 * r)),
    ]
}

fn same(what: &str, g: &Frame, h: &Frame) {
    let key = |f: &Frame| {
        (
            f.stats.fragments,
            f.stats.captured,
            f.stats.lost,
            f.stats.tied,
            f.stats.geometry_passes,
            f.stats.max_layers,
        )
    };
    assert_eq!(key(g), key(h), "{what}: (fragments, captured, lost, tied, passes, max layers), gpu vs host");
    assert_eq!((g.image.width, g.image.height), (h.image.width, h.image.height), "{what}: size");
    let differ = g.image.pixels.iter().zip(&h.image.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{what}: {differ} pixels differ between the GPU's setup and the host's");
}

#[test]
fn gpu_setup_frames_equal_host_setup() {
    let Some((gpu, host)) = backends() else { return };
    let size = |technique| Settings {
        width: 61,
        height: 47,
        raster: Some(RasterPath::Compute),
        technique,
        ..Settings::default()
    };
    let window = |technique| Settings {
        width: 24,
        height: 19,
        region: Some(Region { x: 30, y: 20, full_width: 61, full_height: 47 }),
        ..size(technique)
    };
    let mut fragments = 0;
    for name in [
        "planes:6",
        "spheres:3",
        "coplanar",
        "near:4",
        "scale:1e-20:planes:4",
        "grid:2x1:knot",
        "single-sided",
    ] {
        // grid:2x1:knot single-sided, its second copy mirrored: back faces dropped by the sign
        // of the snapped area, turned over under the mirror (oit_core::setup::back_face_sign)
        let scene = if name == "single-sided" {
            let mut scene = load_scene("grid:2x1:knot").unwrap();
            scene.objects.iter_mut().for_each(|o| o.double_sided = false);
            scene.instances[1].transform *= glam::Mat4::from_scale(glam::Vec3::new(-1.0, 1.0, 1.0));
            scene
        } else {
            load_scene(name).unwrap()
        };
        for (view, camera) in cameras(&scene, 61.0 / 47.0) {
            for t in ["reference", "fabs", "bdp", "adp"] {
                let technique: Technique = t.parse().unwrap();
                for (part, s) in [("frame", size(technique)), ("window", window(technique))] {
                    let what = format!("{name}, {view}, {t}, {part}");
                    let g = gpu.render(&scene, &camera, &s).unwrap_or_else(|e| panic!("{what}: gpu: {e}"));
                    let h = host.render(&scene, &camera, &s).unwrap_or_else(|e| panic!("{what}: host: {e}"));
                    same(&what, &g, &h);
                    fragments += g.stats.fragments;
                }
            }
        }
    }
    assert!(fragments > 0, "every view came out empty: the comparison tested nothing");
}

/// One prepared scene, views that need ever more work items (the field of view narrowing: each
/// triangle covers more 8×8 tiles): the kept buffers are outgrown after they were trusted, so the
/// frame's end finds the setup did not fit, and the frame runs again into grown buffers. Every
/// frame equals the host's, and the buffers did grow (the backend's allocation counter).
#[test]
fn outgrown_setup_buffers_run_the_frame_again() {
    let Some((gpu, host)) = backends() else { return };
    // four quads: a first guess of 2 items a triangle and 4096 spare, against about 5,000 work
    // items once they fill the view (each triangle keeps the half of its box it covers)
    let scene = load_scene("planes:4").unwrap();
    let s = Settings {
        width: 512,
        height: 512,
        raster: Some(RasterPath::Compute),
        technique: Technique::Fabs { k: None },
        ..Settings::default()
    };
    let mut prepared = gpu.prepare(&scene).unwrap();
    let mut grew = 0;
    let mut before = None;
    for (i, fov) in [170.0f32, 60.0, 10.0].into_iter().enumerate() {
        let camera = Camera::orbit_scene(&scene, View { fov, ..View::default() }, 1.0).unwrap();
        let g = prepared.frame(&camera, &s).unwrap();
        let h = host.render(&scene, &camera, &s).unwrap();
        same(&format!("field of view {fov} (frame {i})"), &g, &h);
        let made = prepared.storage_allocations();
        if before.is_some_and(|b| made > b) {
            grew += 1;
        }
        before = Some(made);
    }
    assert!(grew > 0, "no later view outgrew the first one's buffers: the re-run was not tested");
    // the last view again: the buffers fit and are trusted, so the frame makes nothing
    let (made, pipelines) = (prepared.storage_allocations(), prepared.pipelines_created());
    let camera = Camera::orbit_scene(&scene, View { fov: 10.0, ..View::default() }, 1.0).unwrap();
    let again = prepared.frame(&camera, &s).unwrap();
    same("the last view again", &again, &host.render(&scene, &camera, &s).unwrap());
    assert_eq!(prepared.storage_allocations(), made, "a steady frame with the GPU setup allocated");
    assert_eq!(prepared.pipelines_created(), pipelines, "a steady frame with the GPU setup made a pipeline");
}
