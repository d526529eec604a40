#![cfg(feature = "wgpu")]
//! Quick checks while the backend grows: compute path against oit-cpu.

use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};

#[test]
fn compute_path_matches_cpu() {
    let Some(gpu) = oit_wgpu::backend_or_skip("compute_path_matches_cpu") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for scene_name in ["planes:4", "knot"] {
        let scene = load_scene(scene_name).unwrap();
        for t in ["reference", "fabs"] {
            let s = Settings {
                width: 64,
                height: 64,
                technique: t.parse::<Technique>().unwrap(),
                ..Settings::default()
            };
            let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
            let g = gpu.render(&scene, &cam, &s).unwrap();
            let c = cpu.render(&scene, &cam, &s).unwrap();
            assert_eq!(g.stats.fragments, c.stats.fragments, "{scene_name} {t}");
            assert_eq!(g.stats.lost, c.stats.lost, "{scene_name} {t}");
            assert_eq!(g.stats.tied, c.stats.tied, "{scene_name} {t}");
            let worst = g
                .image
                .pixels
                .iter()
                .zip(&c.image.pixels)
                .map(|(a, b)| (0..3).map(|i| a[i].abs_diff(b[i])).max().unwrap())
                .max()
                .unwrap();
            assert!(worst <= 1, "{scene_name} {t}: {worst}");
            println!("{scene_name} {t}: fragments {} gpu_ms {:?}", g.stats.fragments, g.stats.gpu_ms);
        }
    }
}
