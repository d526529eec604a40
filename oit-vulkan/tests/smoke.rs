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

#[test]
fn hardware_path_is_refused() {
    let Some(vk) = oit_vulkan::backend_or_skip("hardware_path_is_refused") else { return };
    let scene = load_scene("planes:4").unwrap();
    let s = Settings {
        width: 16,
        height: 16,
        raster: Some(oit_core::RasterPath::Hardware),
        ..Settings::default()
    };
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    match vk.render(&scene, &cam, &s) {
        Err(oit_core::OitError::Unsupported { what, .. }) => assert!(what.contains("hardware"), "{what}"),
        other => panic!("expected Unsupported, got {:?}", other.map(|f| f.stats)),
    }
}
