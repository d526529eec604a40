//! Criterion benches: one frame of every technique (the reference included) × backend × raster
//! path × scene, at 64×64 pixels. Scenes: `planes:8`, `spheres:4`, `knot`, and
//! `../shared/models/bunny.obj` when it is there. Backends: oit-cpu (feature `cpu`, default) and,
//! with feature `wgpu`, wgpu on each raster path when an adapter is found (else a note says why
//! they are skipped). A run that fails (a technique a device cannot hold) is skipped with a note.
//!
//! Settings: 10 flat samples, 0.3 s warm-up, 1 s measurement per bench, so that
//! `cargo bench -p oit-bench` (default features) runs 48 benches in about 1.5 minutes on 2 cores
//! (measured: see the crate's report for the number of this machine); `cargo test` runs each once
//! (criterion's test mode, without `--bench`).
//!
//! Run one group: `cargo bench -p oit-bench -- knot/cpu`.

use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use oit_core::{Camera, Scene, Settings, Technique, View, load_scene};

/// Image side of every bench.
const SIZE: u32 = 64;

fn scenes() -> Vec<(String, Scene)> {
    let mut names: Vec<String> = ["planes:8", "spheres:4", "knot"].iter().map(|s| (*s).to_string()).collect();
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/models/bunny.obj");
    if bunny.is_file() {
        names.push(bunny.to_string_lossy().into_owned());
    } else {
        eprintln!("note: {} not found; the bunny benches are skipped", bunny.display());
    }
    names
        .into_iter()
        .filter_map(|name| match load_scene(&name) {
            Ok(scene) => {
                let short =
                    Path::new(&name).file_stem().map_or(name.clone(), |s| s.to_string_lossy().into_owned());
                Some((short, scene))
            }
            Err(e) => {
                eprintln!("note: scene {name} skipped: {e}");
                None
            }
        })
        .collect()
}

fn techniques(c: &mut Criterion) {
    let backends = oit_bench::available_backends();
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    for (name, scene) in scenes() {
        let camera = match Camera::orbit_scene(&scene, View::default(), 1.0) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("note: scene {name} skipped: {e}");
                continue;
            }
        };
        for backend in &backends {
            let base = Settings { width: SIZE, height: SIZE, ..Settings::default() };
            let mut group =
                c.benchmark_group(format!("{name}/{}", oit_bench::label(backend.as_ref(), &base)));
            group.sampling_mode(SamplingMode::Flat);
            for &technique in &techniques {
                let settings = Settings { technique, ..base.clone() };
                // one frame first: a technique this device cannot run is a note, not a panic
                if let Err(e) = backend.render(&scene, &camera, &settings) {
                    eprintln!("note: {technique} on {} skipped: {e}", backend.name());
                    continue;
                }
                group.bench_function(technique.to_string(), |b| {
                    b.iter(|| backend.render(&scene, &camera, &settings).expect("rendered once already"))
                });
            }
            group.finish();
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = techniques
}
criterion_main!(benches);
