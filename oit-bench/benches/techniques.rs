//! Criterion benches: one frame of every technique (the reference included) × backend × raster
//! path × scene, at 64×64 pixels. Scenes: `planes:8`, `spheres:4`, `knot`, and the built-in
//! `bunny`. Backends: every one compiled in (features `cpu`
//! and `wgpu`, both default), wgpu on each raster path when an adapter is found (else a note says
//! why it is skipped; with `OIT_REQUIRE_GPU=1` a missing adapter is a panic).
//!
//! Before anything is timed, each technique's frame on every backend/path is held to the
//! cross-backend conformance bounds ([`oit_bench::cross_check`]: at most 1 of 8 bits between paths
//! with oit's fixed-point rules, and off projected triangle edges where a hardware rasterizer is
//! one side); a pair that breaks them panics, so a bench run never times a wrong frame. A technique
//! a device refuses (`Unsupported`, `TooLarge`: over the device's limits) is skipped with a note;
//! any other error panics.
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
use oit_core::{Backend, Camera, Frame, OitError, Scene, Settings, Technique, View, load_scene};

/// Image side of every bench.
const SIZE: u32 = 64;

fn scenes() -> Vec<(String, Scene)> {
    let names: Vec<String> =
        ["planes:8", "spheres:4", "knot", "bunny"].iter().map(|s| (*s).to_string()).collect();
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
        let base = Settings { width: SIZE, height: SIZE, ..Settings::default() };
        let edges = oit_core::metrics::edge_mask(&scene, &camera, SIZE, SIZE, 1.0);
        // which techniques each backend runs: those it rendered, checked across backends
        let mut runs = vec![Vec::new(); backends.len()];
        for &technique in &techniques {
            let settings = Settings { technique, ..base.clone() };
            let frames: Vec<(String, &dyn Backend, Frame)> = backends
                .iter()
                .zip(&mut runs)
                .filter_map(|(backend, runs)| {
                    let frame = rendered(backend.as_ref(), &scene, &camera, &settings)?;
                    runs.push(technique);
                    Some((oit_bench::label(backend.as_ref(), &base), backend.as_ref(), frame))
                })
                .collect();
            check_matrix(&name, technique, &frames, &base, &edges);
        }
        for (backend, runs) in backends.iter().zip(&runs) {
            let mut group =
                c.benchmark_group(format!("{name}/{}", oit_bench::label(backend.as_ref(), &base)));
            group.sampling_mode(SamplingMode::Flat);
            for &technique in runs {
                let settings = Settings { technique, ..base.clone() };
                group.bench_function(technique.to_string(), |b| {
                    b.iter(|| backend.render(&scene, &camera, &settings).expect("rendered once already"))
                });
            }
            group.finish();
        }
    }
}

/// One frame, or `None` with a note where the device refuses the technique; any other error
/// panics.
fn rendered(backend: &dyn Backend, scene: &Scene, camera: &Camera, settings: &Settings) -> Option<Frame> {
    match backend.render(scene, camera, settings) {
        Ok(frame) => Some(frame),
        Err(e @ (OitError::Unsupported { .. } | OitError::TooLarge { .. })) => {
            eprintln!("note: {} on {} skipped: {e}", settings.technique, backend.name());
            None
        }
        Err(e) => panic!("{} on {}: {e}", settings.technique, backend.name()),
    }
}

fn side<'a>(
    (label, backend, frame): &'a (String, &dyn Backend, Frame),
    base: &Settings,
) -> oit_bench::Side<'a> {
    oit_bench::Side {
        label: label.as_str(),
        raster: backend.raster_path(base),
        image: &frame.image,
        lost: frame.stats.lost,
    }
}

/// Every pair of backend/paths that ran `technique` held to the conformance bounds.
fn check_matrix(
    scene: &str,
    technique: Technique,
    frames: &[(String, &dyn Backend, Frame)],
    base: &Settings,
    edges: &[bool],
) {
    for (i, a) in frames.iter().enumerate() {
        for b in &frames[i + 1..] {
            let (_, note, failed) = oit_bench::cross_check(technique, &side(a, base), &side(b, base), edges);
            assert!(!failed, "{technique} on {scene}: {}", note.unwrap_or_default());
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
