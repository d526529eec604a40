//! Issue 42, item 4: what `auto` predicts of a candidate's frame, its screen tiles and the storage
//! it reports, is what that frame then runs and reports, exactly, not a bound. On the CPU, over
//! scenes, sizes and `--memory` budgets that run whole, that force a few tiles, many, and
//! splits after a count (sizes from a counting pass), every candidate `auto` foresaw is rendered
//! under the same budget: `Stats::tiles` and `Stats::storage_bytes` must be the candidate's
//! `tiles` and `storage_bytes` (and the pick's reason says them), and a candidate whose frame
//! the tiling loop refuses must be refused when it runs.

use oit_bench::auto::{Budget, Tables, resolve};
use oit_bench::backends::{BackendOptions, select};
use oit_core::{Camera, OitError, Settings, View, load_scene};

/// Renders every candidate `auto` foresaw under `s` and holds its frame to the prediction: the
/// tiles and storage it was foreseen with, a tile within `--memory`, or refused where it was
/// foreseen refused (the tiling loop, or a technique the backend lacks). Returns how many were
/// compared, how many of those tiled, and how many were refused as too large.
fn run_candidates(
    b: &dyn oit_core::Backend,
    scene: &oit_core::Scene,
    camera: &Camera,
    s: &Settings,
    candidates: &[oit_bench::auto::Candidate],
    what: &str,
) -> (usize, usize, usize) {
    let (mut compared, mut tiled, mut refused) = (0, 0, 0);
    for c in candidates {
        let technique = c.technique.parse().unwrap();
        let run = b.render(scene, camera, &Settings { technique, ..s.clone() });
        let what = format!("{what} {}", c.technique);
        if c.tiles == 0 {
            assert!(run.is_err() && c.rejected.is_some(), "{what}: ran ({:?})", c.rejected);
            refused += usize::from(matches!(run, Err(OitError::TooLarge { .. })));
            continue;
        }
        let frame = run.unwrap_or_else(|e| panic!("{what}: foreseen in {} tiles, refused: {e}", c.tiles));
        assert_eq!(
            (u64::from(frame.stats.tiles), frame.stats.storage_bytes),
            (c.tiles, c.storage_bytes),
            "{what}: (tiles, storage) ran vs predicted"
        );
        if let Some(m) = s.memory {
            assert!(c.frame_bytes <= m, "{what}: a tile of {} bytes over --memory", c.frame_bytes);
        }
        compared += 1;
        tiled += usize::from(c.tiles > 1);
    }
    (compared, tiled, refused)
}

#[test]
fn predicted_tiles_and_storage_are_the_frames() {
    let tables = Tables::new(None).expect("the shipped tables");
    let cpu = select("cpu", &BackendOptions::default()).expect("the cpu backend").remove(0);
    let b = cpu.as_ref();
    let mut compared = 0;
    let mut tiled = 0;
    let mut refused = 0;
    for (name, width, height, memories) in [
        // whole, a few tiles, many tiles, and budgets no candidate's frame fits in (61,000 bytes
        // cannot hold the stitched image and outputs, 61,440, beside a tile)
        ("default", 96, 80, &[None, Some(4 << 20), Some(400_000), Some(90_000), Some(61_000), Some(900)][..]),
        ("planes:6", 64, 64, &[None, Some(150_000), Some(40_000)][..]),
        ("bunny", 72, 72, &[Some(1 << 20), Some(200_000)][..]),
        ("cluster:200", 50, 70, &[Some(120_000)][..]),
    ] {
        let scene = load_scene(name).expect("the scene loads");
        let settings = Settings { width, height, ..Settings::default() };
        let aspect = width as f32 / height as f32;
        let camera =
            Camera::orbit_scene(&scene, View::default(), aspect).expect("the camera frames the scene");
        for &memory in memories {
            let s = Settings { memory, ..settings.clone() };
            let what = format!("{name} {width}x{height} --memory {memory:?}");
            // --max-epr 1: every candidate but mdts's is eligible, so each is foreseen and ranked
            let budget = Budget::new(1.0, memory).unwrap();
            let choice = match resolve(b, &scene, &camera, &s, &tables, budget) {
                Ok((choice, _)) => choice,
                Err(e) => {
                    // no candidate fits: each one's frame must be refused too (below, per candidate)
                    assert!(memory.is_some_and(|m| m < 65_536), "{what}: {e}");
                    assert!(e.to_string().contains("auto: no technique"), "{what}: {e}");
                    let supported = b.capabilities().techniques;
                    for technique in oit_core::Technique::all() {
                        if !supported.contains(&technique.kind()) {
                            continue;
                        }
                        let run = b.render(&scene, &camera, &Settings { technique, ..s.clone() });
                        assert!(matches!(run, Err(OitError::TooLarge { .. })), "{what} {technique}: ran");
                        refused += 1;
                    }
                    continue;
                }
            };
            let (c, t, r) = run_candidates(b, &scene, &camera, &s, &choice.candidates, &what);
            (compared, tiled, refused) = (compared + c, tiled + t, refused + r);
            // the pick is one of them, and its reason names its tiles as they are
            let picked = choice.picked();
            let said = if picked.tiles > 1 {
                format!(
                    ", {} screen tiles, {} bytes of storage in the largest)",
                    picked.tiles, picked.storage_bytes
                )
            } else {
                format!(", {} bytes of storage)", picked.storage_bytes)
            };
            assert!(choice.reason.contains(&said), "{what}: {} lacks {said}", choice.reason);
        }
    }
    eprintln!("{compared} compared, {tiled} tiled, {refused} refused");
    // enough of each kind for the comparison to mean something
    assert!(
        compared >= 100 && tiled >= 50 && refused >= 10,
        "{compared} compared, {tiled} tiled, {refused} refused"
    );
}

/// The same prediction on every GPU backend and raster path present (wgpu, and vulkan where
/// compiled): `auto`'s candidates run in the tiles and with the storage they were foreseen with.
/// Fewer cases than the CPU's (lavapipe is slow): whole, a few tiles and many. Without a Vulkan
/// driver it says so and compares nothing (`OIT_REQUIRE_GPU=1` makes that a failure).
#[test]
fn gpu_predicted_tiles_and_storage_are_the_frames() {
    let tables = Tables::new(None).expect("the shipped tables");
    let gpus: Vec<_> =
        oit_bench::backends::available_backends().into_iter().filter(|b| b.name() != "cpu").collect();
    if gpus.is_empty() {
        eprintln!("skipped: no GPU backend present (install a Vulkan driver, e.g. mesa-vulkan-drivers)");
        return;
    }
    let scene = load_scene("default").expect("the scene loads");
    let (width, height) = (64, 48);
    let camera = Camera::orbit_scene(&scene, View::default(), width as f32 / height as f32).unwrap();
    let mut compared = 0;
    let mut tiled = 0;
    for b in &gpus {
        let path = b.raster_path(&Settings::default());
        for memory in [None, Some(1 << 20), Some(150_000)] {
            let s = Settings { width, height, memory, ..Settings::default() };
            let what = format!("{} {path:?} --memory {memory:?}", b.name());
            let (choice, _) =
                resolve(b.as_ref(), &scene, &camera, &s, &tables, Budget::new(1.0, memory).unwrap())
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
            let (c, t, _) = run_candidates(b.as_ref(), &scene, &camera, &s, &choice.candidates, &what);
            (compared, tiled) = (compared + c, tiled + t);
        }
    }
    eprintln!("{compared} compared, {tiled} tiled");
    assert!(compared >= 20 && tiled >= 5, "{compared} compared, {tiled} tiled");
}
