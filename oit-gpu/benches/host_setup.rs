//! The host's setup of a textured compute frame ([`oit_gpu::host_setup`]: every textured frame of
//! both GPU backends sets its triangles up and bins their work list on the host) on the scene set's
//! `particles` (1,200 billboards) at 1024×1024, and the binning alone two ways side by side:
//! `row runs` ([`TriangleSetup::work_items`]: each row of a triangle's box a run of tiles, from
//! each edge's ends and a bisection) and `tile by tile` (every tile of the box tested at the
//! rule's four corners, [`TriangleSetup::work_items_tile_by_tile`], as the work list was binned
//! before the runs).
//!
//! Before timing, the two binnings are checked to give the same work list. Single-threaded here
//! (oit-core's `rayon` feature off); the backends bin chunks of triangles in parallel.
//!
//! `cargo bench -p oit-gpu --bench host_setup` (`cargo test` runs it once, in criterion's test mode)

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use oit_core::setup::TriangleSetup;
use oit_core::{Camera, Settings, View, load_scene};
use oit_gpu::TILE;

const SIZE: u32 = 1024;

fn setup(c: &mut Criterion) {
    let scene = load_scene("particles").expect("the scene set's particles load");
    let settings = Settings { width: SIZE, height: SIZE, ..Settings::default() };
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0).expect("a camera frames particles");
    let layers = scene.layers(None);
    let transparent = &layers.transparent;
    let set_up = TriangleSetup::new(transparent, &camera, &settings);
    let runs = set_up.work_items(TILE);
    assert!(
        runs.len() > set_up.triangles.len(),
        "{} items for {} triangles",
        runs.len(),
        set_up.triangles.len()
    );
    assert_eq!(runs, set_up.work_items_tile_by_tile(TILE), "the row runs bin other tiles than the rule");
    let mut group = c.benchmark_group("host_setup/particles");
    group.bench_function("whole", |b| {
        b.iter(|| black_box(oit_gpu::host_setup(transparent, &camera, &settings, false)))
    });
    group.bench_function("binning: row runs", |b| b.iter(|| black_box(set_up.work_items(TILE))));
    group.bench_function("binning: tile by tile", |b| {
        b.iter(|| black_box(set_up.work_items_tile_by_tile(TILE)))
    });
    group.finish();
}

criterion_group!(benches, setup);
criterion_main!(benches);
