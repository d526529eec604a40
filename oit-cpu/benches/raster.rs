//! One geometry pass of the software rasterizer at 512×512, on the bunny and `planes:64`: the
//! span walk of every triangle in parallel chunks ([`RasterMode::Scatter`], the rasterizer before
//! issue 12 and still the default) against the tiled walk with the vectorized coverage test of
//! small triangles ([`RasterMode::Tiled`]), side by side in one run. `setup` is
//! [`Rasterizer::new`] (transform, clipping, snapping and the traversal's records, in fresh
//! storage), `setup/warm` the same into the storage of the frame before ([`Rasterizer::rebuild`],
//! a prepared scene's frames). Each mode is timed twice: `coverage` is the traversal alone
//! ([`Rasterizer::coverage_pass`]), `pass` the whole geometry pass (each fragment's depth, id and
//! shaded colour, what a capture pass of the transparency effect stores) with a per-fragment
//! relaxed atomic add into a per-pixel counter, about the cheapest a technique does, so the
//! rasterizer's own cost dominates; `depth` the same pass reading only depth and primitive id, as
//! a counting pass or a peel's depth test does (colour and normal are computed only where a
//! shader reads them).
//! `in_order/pass` is the banded pass of `plain` ([`Rasterizer::for_each_fragment_in_order`]: each
//! pixel's fragments from one thread, highest primitive first), shaded, with the pixel's count
//! read and written back.
//! Throughput is in fragments.
//!
//! `cargo bench -p oit-cpu --bench raster -- --warm-up-time 1 --measurement-time 3`
//! (fragments per second per core: divide by the threads, `RAYON_NUM_THREADS` or the cores)

use std::hint::black_box;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use oit_core::{Camera, Scene, Settings, View, builtin_scene, load_scene};
use oit_cpu::raster::{RasterMode, Rasterizer, Shade};

const SIZE: u32 = 512;
fn scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    // the built-in mesh: no file, whatever the directory benches run in
    out.push(("bunny".to_string(), load_scene("bunny").expect("the built-in bunny loads")));
    if let Some(Ok(scene)) = builtin_scene("planes:64") {
        out.push(("planes:64".to_string(), scene));
    }
    out
}

fn pass(c: &mut Criterion) {
    let settings = Settings { width: SIZE, height: SIZE, ..Settings::default() };
    let counts: Vec<AtomicU32> = (0..SIZE * SIZE).map(|_| AtomicU32::new(0)).collect();
    eprintln!("{} rayon threads", rayon::current_num_threads());
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
        // a persistent renderer's setup: the same frame again in the storage of the last
        let mut warm = Rasterizer::new(&scene, &camera, &settings);
        group
            .bench_function("setup/warm", |b| b.iter(|| warm.rebuild(black_box(&scene), &camera, &settings)));
        for mode in [RasterMode::Scatter, RasterMode::Tiled] {
            let r = Rasterizer::new(&scene, &camera, &settings).with_mode(mode);
            let mode = format!("{mode:?}").to_lowercase();
            group.bench_function(format!("{mode}/coverage"), |b| b.iter(|| r.coverage_pass()));
            group.bench_function(format!("{mode}/pass"), |b| {
                b.iter(|| {
                    r.for_each_shaded_fragment(|f| {
                        // what a capture of the transparency effect reads: depth, id and colour
                        // (colour and normal are computed only where read; none reads both)
                        black_box((f.depth, f.prim, f.color()));
                        counts[f.pixel as usize].fetch_add(1, Ordering::Relaxed);
                    })
                })
            });
            group.bench_function(format!("{mode}/depth"), |b| {
                b.iter(|| {
                    r.for_each_fragment(|f| {
                        // a depth-only pass (a peel's test, a counting pass): no colour, no normal
                        black_box((f.depth, f.prim));
                        counts[f.pixel as usize].fetch_add(1, Ordering::Relaxed);
                    })
                })
            });
        }
        // the banded pass that keeps each pixel's fragments in order (plain's), with the cheapest
        // in-order capture: the pixel's count read and written back, no atomic add (the pixel's
        // band is one thread)
        let r = Rasterizer::new(&scene, &camera, &settings);
        group.bench_function("in_order/pass", |b| {
            b.iter(|| {
                r.for_each_fragment_in_order(Shade::Color, |f| {
                    black_box((f.depth, f.prim, f.color()));
                    let c = &counts[f.pixel as usize];
                    c.store(c.load(Ordering::Relaxed) + 1, Ordering::Relaxed);
                })
            })
        });
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
