//! The plan's storage (`Plan::arrays`, summed in `Plan::storage_bytes`, what every backend checks
//! against its memory budget before allocating) is what every backend reports allocating, to the
//! byte, for every technique, on every backend and raster path: a backend that allocated past the
//! plan would make the budget check a promise it does not keep, and one that allocated something
//! else would be restating the plan in its own words.
//!
//! What a GPU frame reports is what it allocated: `dfb`'s, `ll`'s and the reference's
//! per-fragment arrays at their capacity, the fragment count rounded up to its size class, not
//! rewritten to the count (issue 41.10: the contexts used to report the count, so an allocation
//! past it could not show here). The rounding is the plan's own rule
//! (`Plan::fragment_capacity`, on the backends it marks `pooled`), which the GPU contexts
//! allocate by; this test applies no correction of its own. Mutation that fails it:
//! `OIT_MUTATION=wgpu-capacity-doubled` (oit-wgpu's `GpuCtx::fragment_capacity` allocates twice
//! the plan's capacity) — "wgpu/compute dfb Drop on knot: reports ... bytes".

use oit_core::plan::{Counted, Plan, RESOLVE_STATE_BYTES};
use oit_core::{Overflow, Settings, Technique, View};
use oit_tests::*;

/// Each technique with `--overflow drop`, and the fixed-size ones (`fabs:K`, `mdts:K`, `mdts64:K`)
/// with `--overflow tail` too (its sums are an array of the plan, its pass a pass of the schedule).
fn with_tails(techniques: &[Technique]) -> Vec<(Technique, Overflow)> {
    let mut out = Vec::new();
    for &t in techniques {
        out.push((t, Overflow::Drop));
        if matches!(
            t,
            Technique::Fabs { k: Some(_) }
                | Technique::Mdts { k: Some(_) }
                | Technique::Mdts64 { k: Some(_) }
        ) {
            out.push((t, Overflow::Tail));
        }
    }
    out
}

#[test]
fn reported_storage_is_the_plans_arrays() {
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    techniques.extend([
        Technique::Bdp { passes: 3 },
        Technique::Fabs { k: Some(3) },
        Technique::Mdts { k: Some(3) },
        Technique::Mdts64 { k: Some(3) },
        Technique::Mlp { m: 2 },
        Technique::Mboit { m: 6 },
    ]);
    for backend in backends_for("reported_storage_is_the_plans_arrays") {
        let b = backend.as_ref();
        for name in ["knot", "spheres:3", "planes:5"] {
            let scene = scene(name);
            let base = settings(40, "reference");
            let cam = camera(&scene, &base, View::default());
            let reference = render(b, &scene, &cam, &base);
            let deepest = reference.layers.as_ref().and_then(|l| l.iter().copied().max()).unwrap_or(0);
            for (technique, overflow) in with_tails(&techniques) {
                let s = Settings { technique, overflow, ..base.clone() };
                let plan = Plan::new(b.name(), &scene, &s)
                    .unwrap_or_else(|e| panic!("{technique}: {e}"))
                    .on_path(b.raster_path(&s));
                let frame = render(b, &scene, &cam, &s);
                let pixels = u64::from(s.width) * u64::from(s.height);
                let counted = Counted { deepest, fragments: reference.stats.fragments };
                let bound = plan.storage_bytes(pixels, counted);
                // the plan's arrays are what every backend allocates, to the byte (the resolve
                // state, counted once in the plan's figure, is not in Stats::storage_bytes)
                assert_eq!(
                    frame.stats.storage_bytes,
                    bound - pixels * RESOLVE_STATE_BYTES,
                    "{} {technique} {overflow:?} on {name}: reports {} bytes, the plan's arrays {:?}",
                    label(b),
                    frame.stats.storage_bytes,
                    plan.arrays(counted)
                );
                assert!(
                    frame.stats.storage_bytes > 0,
                    "{} {technique} on {name}: no storage reported",
                    label(b)
                );
            }
            // the peels per sample at 4 samples (docs/msaa.md): their keys, the peeled layers'
            // payloads and masks and the per-sample accumulators
            for technique in PER_SAMPLE_PEELS {
                let s = Settings { technique, samples: 4, ..base.clone() };
                let plan = Plan::new(b.name(), &scene, &s)
                    .unwrap_or_else(|e| panic!("{technique}: {e}"))
                    .on_path(b.raster_path(&s));
                assert!(plan.sample_peel, "{technique}");
                let frame = render(b, &scene, &cam, &s);
                let pixels = u64::from(s.width) * u64::from(s.height);
                assert_eq!(
                    frame.stats.storage_bytes,
                    plan.storage_bytes(pixels, Counted::default()) - pixels * RESOLVE_STATE_BYTES,
                    "{} {technique} at 4 samples on {name}: the plan's arrays {:?}",
                    label(b),
                    plan.arrays(Counted::default())
                );
            }
        }
    }
}

/// The techniques that peel per sample above one sample (`oit_core::msaa::peels_masks`), with
/// M = 1 and 3 for mlp. Mutations caught: oit-cpu's mlp per sample keeping the previous pass's
/// keys in an allocation it does not count (`reported_storage_is_the_plans_arrays`: "cpu/cpu
/// mlp:1 at 4 samples on knot"), and running no pass past its peel limit
/// (`geometry_passes_follow_the_plans_schedule`: "mlp:1 at 4 samples --max-peels Some(2) on
/// knot (24 layers): schedule [(Peel, 3)]").
const PER_SAMPLE_PEELS: [Technique; 4] =
    [Technique::Dp, Technique::Ddp, Technique::Mlp { m: 1 }, Technique::Mlp { m: 3 }];

/// A rule the plan holds for every backend: the weighted blends never order fragments, so the
/// effects that need the order (translucency, Fresnel) are refused, not run wrong.
#[test]
fn weighted_blends_refuse_ordered_effects_everywhere() {
    use oit_core::{Effect, OitError};
    let scene = scene("planes:4");
    for backend in backends_for("weighted_blends_refuse_ordered_effects_everywhere") {
        let b = backend.as_ref();
        for t in ["plain", "wavg", "wsum", "wboit", "mboit", "mboit:6"] {
            for effect in [Effect::Translucency, Effect::Fresnel] {
                let s = Settings { effect, ..settings(16, t) };
                match b.render(&scene, &camera(&scene, &s, View::default()), &s) {
                    Err(OitError::Unsupported { .. }) => {}
                    other => panic!("{} {t} {effect:?}: {:?}", label(b), other.map(|f| f.stats)),
                }
            }
            let s = Settings { effect: Effect::Complexity, ..settings(16, t) };
            assert!(b.render(&scene, &camera(&scene, &s, View::default()), &s).is_ok(), "{t} complexity");
        }
    }
}

/// The plan's pass schedule (`Plan::schedule`) is what every backend runs: its geometry passes
/// equal the schedule's total for every technique, with and without a peel limit, on scenes whose
/// pixels hold no two equal depths (so a pixel's layers are its fragments: the reference's
/// deepest count). adp's bins are at most the layers and these scenes stay under 32 layers, so
/// one batch either way. The peels per sample (dp, ddp, mlp:1, mlp:3) at 4 samples too, their
/// layers the fragments (every fragment its own (depth, primitive id) key).
#[test]
fn geometry_passes_follow_the_plans_schedule() {
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    techniques.extend([
        Technique::Bdp { passes: 3 },
        Technique::Fabs { k: Some(3) },
        Technique::Fabs { k: Some(64) },
        Technique::Mdts { k: Some(3) },
        Technique::Mdts64 { k: Some(3) },
        Technique::Mlp { m: 3 },
        Technique::Mboit { m: 6 },
    ]);
    for backend in backends_for("geometry_passes_follow_the_plans_schedule") {
        let b = backend.as_ref();
        for name in ["knot", "spheres:3", "planes:5"] {
            let scene = scene(name);
            let base = settings(40, "reference");
            let cam = camera(&scene, &base, View::default());
            let reference = render(b, &scene, &cam, &base);
            let layers = reference.layers.as_ref().and_then(|l| l.iter().copied().max()).unwrap_or(0);
            assert!(layers > 2 && layers < 32, "{name}: {layers} layers");
            for (technique, overflow) in with_tails(&techniques) {
                for max_peels in [None, Some(2)] {
                    let s = Settings { technique, max_peels, overflow, ..base.clone() };
                    let plan = Plan::new(b.name(), &scene, &s)
                        .unwrap_or_else(|e| panic!("{technique}: {e}"))
                        .on_path(b.raster_path(&s));
                    let schedule = plan.schedule(layers, layers);
                    let frame = render(b, &scene, &cam, &s);
                    assert_eq!(
                        frame.stats.geometry_passes,
                        schedule.iter().map(|(_, n)| n).sum::<u32>(),
                        "{} {technique} {overflow:?} --max-peels {max_peels:?} on {name} ({layers} layers): schedule {schedule:?}",
                        label(b)
                    );
                }
            }
            // the peels per sample at 4 samples: a pixel's layers its fragments (each its own
            // (depth, primitive id) key), the reference's deepest count at 4 samples
            let four = Settings { samples: 4, ..base.clone() };
            let reference = render(b, &scene, &cam, &four);
            let layers = reference.layers.as_ref().and_then(|l| l.iter().copied().max()).unwrap_or(0);
            for technique in PER_SAMPLE_PEELS {
                for max_peels in [None, Some(2)] {
                    let s = Settings { technique, max_peels, ..four.clone() };
                    let plan = Plan::new(b.name(), &scene, &s)
                        .unwrap_or_else(|e| panic!("{technique}: {e}"))
                        .on_path(b.raster_path(&s));
                    let schedule = plan.schedule(layers, layers);
                    let frame = render(b, &scene, &cam, &s);
                    assert_eq!(
                        frame.stats.geometry_passes,
                        schedule.iter().map(|(_, n)| n).sum::<u32>(),
                        "{} {technique} at 4 samples --max-peels {max_peels:?} on {name} ({layers} layers): schedule {schedule:?}",
                        label(b)
                    );
                }
            }
        }
    }
}
