#![cfg(feature = "wgpu")]
//! The hardware-raster path against oit-cpu directly: the GPU's rasterizer has its own sub-pixel
//! precision and edge rules, so a pixel's fragments may differ only where its centre lies within
//! the snapping precision of a projected triangle edge; every pixel both cover alike (the same
//! fragment count) must have oit-cpu's colour. (`wgpu.rs` holds every technique's hardware path
//! to its compute path the same way.)

use oit_core::{Backend, Camera, RasterPath, Settings, Technique, View, load_scene};
use oit_tests::{checks, differ_off_mask, edge_mask};

#[test]
fn hardware_path_differs_from_cpu_only_at_edges() {
    let Some(gpu) = oit_wgpu::backend_or_skip("hardware_path_differs_from_cpu_only_at_edges") else { return };
    let cpu = oit_cpu::CpuBackend::default();
    for scene_name in ["planes:8", "knot", "cluster:200", "spheres:4"] {
        let scene = load_scene(scene_name).unwrap();
        let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        let mask = edge_mask(&scene, &cam, 64, 64, checks::COVERAGE_SNAP);
        let settings = |t: &str, raster| Settings {
            width: 64,
            height: 64,
            technique: t.parse::<Technique>().unwrap(),
            raster,
            ..Settings::default()
        };
        let cpu_ref = cpu.render(&scene, &cam, &settings("reference", None)).unwrap();
        let edge_frags: u64 = cpu_ref
            .layers
            .as_ref()
            .expect("oit-cpu's reference records coverage")
            .iter()
            .zip(&mask)
            .filter(|(_, m)| **m)
            .map(|(&n, _)| u64::from(n))
            .sum();
        let gpu_layers = gpu
            .render(&scene, &cam, &settings("reference", Some(RasterPath::Hardware)))
            .unwrap()
            .layers
            .expect("the reference's counts");
        let cpu_layers = cpu_ref.layers.as_ref().expect("oit-cpu's reference records coverage");
        for t in ["reference", "fabs", "ddp", "mdts64"] {
            let g = gpu.render(&scene, &cam, &settings(t, Some(RasterPath::Hardware))).unwrap();
            let c = cpu.render(&scene, &cam, &settings(t, None)).unwrap();
            let (alike, moved) =
                checks::covered_alike_equal(&cpu_ref.image, &g.image, cpu_layers, &gpu_layers, &mask)
                    .unwrap_or_else(|e| panic!("{scene_name} {t}: {e}"));
            // oit-cpu's own technique against its reference: these are exact, so not one pixel
            let (worst_cc, differ_cc) = differ_off_mask(&cpu_ref.image, &c.image, &vec![false; mask.len()]);
            println!(
                "{scene_name} {t}: {alike} pixels covered alike equal, {moved} moved by a snap; cpu's own worst {worst_cc} ({differ_cc}); fragments {} vs {}",
                g.stats.fragments, c.stats.fragments
            );
            assert_eq!(
                differ_cc, 0,
                "{scene_name} {t}: oit-cpu's exact technique differs from its reference"
            );
            // fragments on edge pixels go one way or the other; none elsewhere
            assert!(
                g.stats.fragments.abs_diff(c.stats.fragments) <= edge_frags,
                "{scene_name} {t}: fragments {} vs {} ({edge_frags} on edge pixels)",
                g.stats.fragments,
                c.stats.fragments
            );
            assert_eq!(g.stats.lost, 0, "{scene_name} {t}: the exact techniques lose nothing");
            assert_eq!(c.stats.lost, 0, "{scene_name} {t}: the exact techniques lose nothing");
        }
    }
}
