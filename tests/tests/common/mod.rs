//! What the compute-path conformance tests (`ported_a.rs`, `ported_b.rs`) share.

use oit_core::{Backend, Camera, Settings, View, load_scene};

/// The scenes every ported technique is compared on.
pub const SCENES: [&str; 4] = ["planes:8", "spheres:4", "knot", "cluster:200"];

/// Renders `scene_name` with `s` on wgpu and on oit-cpu and checks that they agree: the same
/// fragments, losses, ties, geometry passes and storage, and no image channel off by more than 1.
pub fn compare(gpu: &oit_wgpu::WgpuBackend, cpu: &oit_cpu::CpuBackend, scene_name: &str, s: &Settings) {
    let scene = load_scene(scene_name).unwrap();
    let cam = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
    let what = format!(
        "{scene_name} {} {:?} {:?} {:?} max_peels {:?}",
        s.technique, s.bdp_mode, s.bounds, s.effect, s.max_peels
    );
    let g = gpu.render(&scene, &cam, s).unwrap_or_else(|e| panic!("{what}: {e}"));
    let c = cpu.render(&scene, &cam, s).unwrap();
    assert_eq!(g.stats.fragments, c.stats.fragments, "{what}: fragments");
    assert_eq!(g.stats.lost, c.stats.lost, "{what}: lost");
    assert_eq!(g.stats.tied, c.stats.tied, "{what}: tied");
    assert_eq!(g.stats.geometry_passes, c.stats.geometry_passes, "{what}: geometry passes");
    oit_tests::checks::same_storage_as_cpu("wgpu", &g, &c, &scene, s)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let worst = g
        .image
        .pixels
        .iter()
        .zip(&c.image.pixels)
        .map(|(a, b)| (0..4).map(|i| a[i].abs_diff(b[i])).max().unwrap())
        .max()
        .unwrap();
    assert!(worst <= 1, "{what}: a channel off by {worst}");
    println!(
        "{what}: fragments {} lost {} passes {} worst {worst}",
        g.stats.fragments, g.stats.lost, g.stats.geometry_passes
    );
}
