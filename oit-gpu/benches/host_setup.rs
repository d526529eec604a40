//! The host's setup of a textured compute frame (every textured frame of both GPU backends sets its
//! triangles up and bins their work list on the host) on the scene set's `particles` (1,200
//! billboards) and `foliage` (694 leaves, trunks and a ground, masked and blended) at 1024×1024:
//! every part of the frame set up `fresh` ([`oit_gpu::host_setup`], new storage each time) and
//! `kept` ([`oit_gpu::HostSetup`], the storage of the frame before reused, as the backends do);
//! and the transparent part's binning alone two ways side by side: `row runs`
//! ([`TriangleSetup::work_items`]: each row of a triangle's box a run of tiles, from each edge's
//! ends and the column where its verdict turns) and `tile by tile` (every tile of the box tested
//! at the rule's four corners, [`TriangleSetup::work_items_tile_by_tile`]).
//!
//! Before timing, the two binnings are checked to give the same work list, and a kept setup
//! (warmed by another view) the words and items of a fresh one. Single-threaded here (oit-core's
//! `rayon` feature off); the backends set up and bin chunks of triangles in parallel.
//!
//! `cargo bench -p oit-gpu --bench host_setup` (`cargo test` runs it once, in criterion's test mode)

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use oit_core::setup::TriangleSetup;
use oit_core::{Camera, Settings, View, load_scene};
use oit_gpu::TILE;

const SIZE: u32 = 1024;

fn setup(c: &mut Criterion) {
    for name in ["particles", "foliage"] {
        let scene = load_scene(name).expect("the scene set's scenes load");
        let settings = Settings { width: SIZE, height: SIZE, ..Settings::default() };
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).expect("a camera frames the scene");
        let layers = scene.layers(None);
        // the frame's parts, each set up on its own (the opaque part first, as a frame draws it)
        let parts: Vec<&oit_core::Scene> = layers.opaque.iter().chain([&*layers.transparent]).collect();
        let mut kept: Vec<oit_gpu::HostSetup> = parts.iter().map(|_| oit_gpu::HostSetup::default()).collect();
        for (part, kept) in parts.iter().zip(&mut kept) {
            let set_up = TriangleSetup::new(part, &camera, &settings);
            let runs = set_up.work_items(TILE);
            assert!(!runs.is_empty(), "{name}: no work items");
            assert_eq!(
                runs,
                set_up.work_items_tile_by_tile(TILE),
                "{name}: the row runs bin other tiles than the rule"
            );
            // a kept setup, warmed by another view, gives what a fresh one gives
            let other = Camera::orbit_scene(&scene, View { azimuth: 90.0, ..View::default() }, 1.0)
                .expect("a camera");
            kept.run(part, &other, &settings, false);
            kept.run(part, &camera, &settings, false);
            let (words, items) = oit_gpu::host_setup(part, &camera, &settings, false);
            assert!(
                kept.words == words && kept.items == items,
                "{name}: a kept setup differs from a fresh one"
            );
        }
        let mut group = c.benchmark_group(format!("host_setup/{name}"));
        group.bench_function("every part, fresh", |b| {
            b.iter(|| {
                for part in &parts {
                    black_box(oit_gpu::host_setup(part, &camera, &settings, false));
                }
            })
        });
        group.bench_function("every part, kept", |b| {
            b.iter(|| {
                for (part, kept) in parts.iter().zip(&mut kept) {
                    kept.run(part, &camera, &settings, false);
                    black_box((&kept.words, &kept.items));
                }
            })
        });
        let set_up = TriangleSetup::new(parts[parts.len() - 1], &camera, &settings);
        group.bench_function("transparent part's binning: row runs", |b| {
            b.iter(|| black_box(set_up.work_items(TILE)))
        });
        group.bench_function("transparent part's binning: tile by tile", |b| {
            b.iter(|| black_box(set_up.work_items_tile_by_tile(TILE)))
        });
        group.finish();
    }
}

criterion_group!(benches, setup);
criterion_main!(benches);
