//! The shaded geometry pass of the software rasterizer on `particles` (1,200 billboards of a soft
//! round texture in front of an opaque backdrop) at 512×512, textured and with its textures
//! taken away (`untextured:particles`, the same fragments), side by side in one run: what
//! sampling a texture adds to each fragment's colour, the part of issue 38's texture target that
//! is the rasterizer's. `pass` is every fragment's depth, id and shaded colour with a relaxed
//! atomic add into a per-pixel counter, as `raster`'s `pass`.
//!
//! Before timing, the two scenes are checked to give the same number of fragments and the
//! textured one to give different colours (a pass that skipped its textures would not).
//!
//! `cargo bench -p oit-cpu --bench texture` (`cargo test` runs it once, in criterion's test mode)

use std::hint::black_box;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use oit_core::{Camera, Settings, View, load_scene};
use oit_cpu::raster::Rasterizer;

const SIZE: u32 = 512;

fn pass(c: &mut Criterion) {
    let settings = Settings { width: SIZE, height: SIZE, ..Settings::default() };
    let counts: Vec<AtomicU32> = (0..SIZE * SIZE).map(|_| AtomicU32::new(0)).collect();
    let textured = load_scene("particles").expect("the scene set's particles load");
    let camera = Camera::orbit_scene(&textured, View::default(), 1.0).expect("a camera frames particles");
    let plain = load_scene("untextured:particles").expect("untextured:particles loads");
    let mut group = c.benchmark_group("texture/particles");
    let mut sums = Vec::new();
    for (name, scene) in [("textured", &textured), ("untextured", &plain)] {
        let r = Rasterizer::new(scene, &camera, &settings);
        // fragments, and a sum of their colours' bits
        let (n, bits) = (AtomicU64::new(0), AtomicU64::new(0));
        r.for_each_shaded_fragment(|f| {
            n.fetch_add(1, Ordering::Relaxed);
            let c = f.color();
            bits.fetch_add(u64::from(c.x.to_bits() ^ c.w.to_bits()), Ordering::Relaxed);
        });
        sums.push((n.into_inner(), bits.into_inner()));
        group.throughput(Throughput::Elements(sums.last().unwrap().0));
        group.bench_function(format!("{name}/pass"), |b| {
            b.iter(|| {
                r.for_each_shaded_fragment(|f| {
                    black_box((f.depth, f.prim, f.color()));
                    counts[f.pixel as usize].fetch_add(1, Ordering::Relaxed);
                })
            })
        });
    }
    assert_eq!(sums[0].0, sums[1].0, "the textured and untextured scenes' fragments differ in number");
    assert!(sums[0].0 > 100_000, "{} fragments", sums[0].0);
    assert_ne!(sums[0].1, sums[1].1, "the textured pass's colours are the untextured one's");
    group.finish();
    black_box(&counts);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(3));
    targets = pass
}
criterion_main!(benches);
