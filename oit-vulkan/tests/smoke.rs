//! The Vulkan backend opens (or says why not) and its compute path reproduces oit-cpu on a few
//! techniques; the conformance suite (`tests/`, feature `vulkan`) runs every body on it.

use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};

#[test]
fn compute_path_matches_cpu() {
    let Some(vk) = oit_vulkan::backend_or_skip("compute_path_matches_cpu") else { return };
    println!("{:?}", vk.capabilities());
    let cpu = oit_cpu::CpuBackend::default();
    for scene_name in ["planes:4", "knot"] {
        let scene = load_scene(scene_name).unwrap();
        for t in ["reference", "fabs", "wavg", "mdts64"] {
            let s = Settings {
                width: 64,
                height: 64,
                technique: t.parse::<Technique>().unwrap(),
                ..Settings::default()
            };
            let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
            let g = vk.render(&scene, &cam, &s).unwrap_or_else(|e| panic!("{scene_name} {t}: {e}"));
            let c = cpu.render(&scene, &cam, &s).unwrap();
            assert_eq!(g.stats.fragments, c.stats.fragments, "{scene_name} {t}");
            assert_eq!(g.stats.lost, c.stats.lost, "{scene_name} {t}");
            assert_eq!(g.stats.tied, c.stats.tied, "{scene_name} {t}");
            // ±1 in 8 bits: the GPU composites in f32 in its own order of operations (as oit-wgpu)
            let worst = g
                .image
                .pixels
                .iter()
                .zip(&c.image.pixels)
                .map(|(a, b)| (0..4).map(|i| a[i].abs_diff(b[i])).max().unwrap())
                .max()
                .unwrap();
            assert!(worst <= 1, "{scene_name} {t}: {worst}");
            println!("{scene_name} {t}: fragments {} wall {:.1} ms", g.stats.fragments, g.stats.wall_ms);
        }
    }
}

/// A device with a graphics queue, fragment-stage atomics and a blendable R32_SFLOAT counter
/// (lavapipe has them) offers both paths and says so in `oit info`'s limits; a frame on the
/// hardware path counts the fragments the compute path counts, off the triangles' edges.
#[test]
fn hardware_path_is_offered_and_runs() {
    let Some(vk) = oit_vulkan::backend_or_skip("hardware_path_is_offered_and_runs") else { return };
    let caps = vk.capabilities();
    assert!(caps.raster_paths.contains(&oit_core::RasterPath::Hardware), "{:?}", caps.raster_paths);
    let line = caps.limits.iter().find(|(k, _)| k == "hardware raster path").expect("reported");
    assert_eq!(line.1, "yes");
    // planes seen face-on cover whole pixels: no fragment on an edge differs between the paths
    let scene = load_scene("planes:4").unwrap();
    let s = |raster| Settings {
        width: 16,
        height: 16,
        raster: Some(raster),
        technique: oit_core::Technique::Fabs { k: None },
        ..Settings::default()
    };
    let cam =
        Camera::orbit_scene(&scene, View { azimuth: 0.0, elevation: 0.0, ..View::default() }, 1.0).unwrap();
    let hw = vk.render(&scene, &cam, &s(oit_core::RasterPath::Hardware)).unwrap();
    let compute = vk.render(&scene, &cam, &s(oit_core::RasterPath::Compute)).unwrap();
    assert!(hw.stats.fragments > 0);
    assert_eq!((hw.stats.fragments, hw.stats.lost), (compute.stats.fragments, 0));
}
