use std::time::{Duration, Instant};
fn main() {
    let gap: u64 = std::env::var("GAP_US").ok().and_then(|v| v.parse().ok()).unwrap_or(1000);
    for name in ["particles:256", "foliage", "particles", "bunny", "grid:3x3:bunny"] {
        let Ok(scene) = oit_core::load_scene(name) else {
            println!("{name}: none");
            continue;
        };
        let settings = oit_core::Settings { width: 1024, height: 1024, ..Default::default() };
        let layers = scene.layers(None);
        let camera = oit_core::Camera::orbit_scene(&scene, oit_core::View::default(), 1.0).unwrap();
        let parts: Vec<&oit_core::Scene> = layers.opaque.iter().chain([&*layers.transparent]).collect();
        let mut kept: Vec<oit_gpu::HostSetup> = parts.iter().map(|_| oit_gpu::HostSetup::default()).collect();
        let mut times = Vec::new();
        for _ in 0..150 {
            std::thread::sleep(Duration::from_micros(gap));
            let t0 = Instant::now();
            for (p, k) in parts.iter().zip(&mut kept) {
                k.run(p, &camera, &settings, false);
                std::hint::black_box(&k.words);
            }
            times.push(t0.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        let tris: usize = parts.iter().map(|p| p.meshes.iter().map(|m| m.indices.len()).sum::<usize>()).sum();
        println!(
            "{name} ({tris} mesh triangles): least {:.3} median {:.3} ms",
            times[0],
            times[times.len() / 2]
        );
    }
}
