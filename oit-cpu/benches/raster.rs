//! One geometry pass of the software rasterizer, Scatter against Tiled, at 512×512: the numbers
//! behind `oit_cpu::raster::DEFAULT_MODE`. The per-fragment work is one relaxed atomic add into a
//! per-pixel counter, about the cheapest a technique does, so the rasterizer's own cost dominates.
//!
//! `cargo bench -p oit-cpu --bench raster -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use oit_core::{Camera, Scene, Settings, View, builtin_scene, load_scene};
use oit_cpu::raster::{RasterMode, Rasterizer};

const SIZE: u32 = 512;
const BUNNY: &str = "/work/shared/models/bunny.obj";

fn scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for name in ["knot", "spheres:8"] {
        if let Some(Ok(scene)) = builtin_scene(name) {
            out.push((name.to_string(), scene));
        }
    }
    if Path::new(BUNNY).exists() {
        match load_scene(BUNNY) {
            Ok(scene) => out.push(("bunny".to_string(), scene)),
            Err(e) => eprintln!("skipping {BUNNY}: {e}"),
        }
    }
    out
}

fn pass(c: &mut Criterion) {
    let settings = Settings { width: SIZE, height: SIZE, ..Settings::default() };
    let counts: Vec<AtomicU32> = (0..SIZE * SIZE).map(|_| AtomicU32::new(0)).collect();
    for (name, scene) in scenes() {
        let Ok(camera) = Camera::orbit_scene(&scene, View::default(), 1.0) else {
            continue;
        };
        let mut group = c.benchmark_group(format!("raster/{name}"));
        group.sample_size(10);
        let base = Rasterizer::new(&scene, &camera, &settings);
        eprintln!(
            "{name}: {} triangles after setup, {} fragments per pass",
            base.triangle_count(),
            base.fragment_count()
        );
        group.throughput(Throughput::Elements(base.fragment_count()));
        group.bench_function("setup", |b| b.iter(|| Rasterizer::new(black_box(&scene), &camera, &settings)));
        for mode in [RasterMode::Scatter, RasterMode::Tiled] {
            let r = Rasterizer::new(&scene, &camera, &settings).with_mode(mode);
            group.bench_function(format!("{mode:?}").to_lowercase(), |b| {
                b.iter(|| {
                    r.for_each_fragment(|f| {
                        counts[f.pixel as usize].fetch_add(1, Ordering::Relaxed);
                    })
                })
            });
        }
        group.finish();
    }
    black_box(&counts);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(3));
    targets = pass
}
criterion_main!(benches);
