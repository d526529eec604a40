//! The plan's storage figure (`Plan::storage_bytes`, what both backends check against their memory
//! budget before allocating) bounds what every backend reports allocating, for every technique,
//! on every backend and raster path: a backend that allocated past the plan would make the budget
//! check a promise it does not keep.

use oit_core::plan::{Counted, Plan, RESOLVE_STATE_BYTES};
use oit_core::{Settings, Technique, View};
use oit_tests::*;

#[test]
fn reported_storage_stays_within_the_plan() {
    let mut techniques = vec![Technique::Reference];
    techniques.extend(Technique::all());
    techniques.extend([
        Technique::Bdp { passes: 3 },
        Technique::Fabs { k: Some(3) },
        Technique::Mlp { m: 2 },
    ]);
    for backend in backends_for("reported_storage_stays_within_the_plan") {
        let b = backend.as_ref();
        for name in ["knot", "spheres:3", "planes:5"] {
            let scene = scene(name);
            let base = settings(40, "reference");
            let cam = camera(&scene, &base, View::default());
            let reference = render(b, &scene, &cam, &base);
            let deepest = reference.layers.as_ref().and_then(|l| l.iter().copied().max()).unwrap_or(0);
            for &technique in &techniques {
                let s = Settings { technique, ..base.clone() };
                let plan = Plan::new(b.name(), &scene, &s).unwrap_or_else(|e| panic!("{technique}: {e}"));
                let frame = render(b, &scene, &cam, &s);
                let pixels = u64::from(s.width) * u64::from(s.height);
                let counted = Counted { deepest, fragments: reference.stats.fragments };
                let bound = plan.storage_bytes(pixels, counted);
                assert!(
                    frame.stats.storage_bytes <= bound,
                    "{} {technique} on {name}: reports {} bytes, the plan allows {bound}",
                    label(b),
                    frame.stats.storage_bytes
                );
                if matches!(technique, Technique::Dfb | Technique::Ll) {
                    // exact allocation: the plan's figure is what was allocated, to the byte
                    assert_eq!(
                        frame.stats.storage_bytes,
                        bound - pixels * RESOLVE_STATE_BYTES,
                        "{} {technique} on {name}: the plan's exact figure",
                        label(b)
                    );
                }
                assert!(
                    frame.stats.storage_bytes > 0,
                    "{} {technique} on {name}: no storage reported",
                    label(b)
                );
            }
        }
    }
}

/// A rule the plan holds for every backend: the weighted blends never order fragments, so the
/// effects that need the order (translucency, Fresnel) are refused, not run wrong.
#[test]
fn weighted_blends_refuse_ordered_effects_everywhere() {
    use oit_core::{Effect, OitError};
    let scene = scene("planes:4");
    for backend in backends_for("weighted_blends_refuse_ordered_effects_everywhere") {
        let b = backend.as_ref();
        for t in ["plain", "wavg", "wsum"] {
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
