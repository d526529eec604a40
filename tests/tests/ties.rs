//! Equal depths, on every backend × raster path (issue 13, items 1 and 2): on scenes whose
//! fragments tie in depth, every exact technique either equals the same backend's reference
//! (which orders equal depths by primitive id) or says it could not: it counts `tied` or `lost`,
//! and at least as many of them as it has error pixels (a pixel it got wrong holds at least one
//! tied or lost fragment). Never silent and wrong.
//!
//! The scenes: `ties:N` (N quads in one plane, colour order unlike primitive order), `near:N`
//! (the same 10⁻⁷ apart), `coplanar`, each also with its primitives in reverse order (the
//! instances reversed), so that whichever order a technique falls back on, one of the two runs
//! disagrees with the reference.

use oit_core::metrics::accuracy;
use oit_core::{HardwareCapture, Scene, Settings, Technique, View};
use oit_tests::*;

/// The scene with its instances, hence its primitive ids, in reverse order.
fn reversed(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.instances.reverse();
    s.name = format!("{} reversed", s.name);
    s
}

/// The scenes, each in both primitive orders.
fn tie_scenes() -> Vec<Scene> {
    ["ties:2", "ties:5", "ties:8", "near:8", "coplanar"]
        .iter()
        .flat_map(|name| {
            let s = scene(name);
            [reversed(&s), s]
        })
        .collect()
}

/// Every exact technique of the catalogue, and with capacities that fit the scenes and that do
/// not.
fn exact_techniques() -> Vec<Technique> {
    let mut t: Vec<Technique> = Technique::all().into_iter().filter(Technique::is_exact).collect();
    t.extend([
        Technique::Fabs { k: Some(3) },
        Technique::Mdts64 { k: Some(3) },
        Technique::Mlp { m: 1 },
        Technique::Mlp { m: 3 },
        Technique::Mlp { m: 8 },
    ]);
    assert!(t.iter().all(Technique::is_exact));
    t
}

/// The ways to capture: the default, and the graphics pipeline's own for `dp` and `ddp` on the
/// wgpu hardware path (the CPU and compute paths ignore it and run the default again).
const CAPTURES: [HardwareCapture; 2] = [HardwareCapture::Atomics, HardwareCapture::Blend];

const VIEWS: [View; 2] = [FRONT, View { azimuth: 25.0, elevation: 20.0, ..FRONT }];

#[test]
fn ties_are_ordered_or_counted() {
    for backend in backends_for("ties_are_ordered_or_counted") {
        let b = backend.as_ref();
        let mut wrong_but_counted = 0;
        for scene in tie_scenes() {
            for view in VIEWS {
                let s = settings(64, "reference");
                let cam = camera(&scene, &s, view);
                let r = render(b, &scene, &cam, &s);
                let runs = exact_techniques().into_iter().flat_map(|t| {
                    let blend = matches!(t, Technique::Dp | Technique::Ddp);
                    CAPTURES.into_iter().take(if blend { 2 } else { 1 }).map(move |c| (t, c))
                });
                for (t, hardware_capture) in runs {
                    let f =
                        render(b, &scene, &cam, &Settings { technique: t, hardware_capture, ..s.clone() });
                    let a = accuracy(&r, &f.image).expect("same size");
                    let (tied, lost) = (f.stats.tied, f.stats.lost);
                    let what = format!(
                        "{} {t} ({hardware_capture:?}) on {} ({view:?}): {} error pixels (EPR {:.3}), tied {tied}, lost {lost}",
                        label(b),
                        scene.name,
                        a.error_pixels,
                        a.epr
                    );
                    assert!(a.is_measured(), "{what}: nothing covered");
                    assert_eq!(r.stats.tied, 0, "{what}: the reference orders every tie");
                    oit_tests::checks::never_silent(&r, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
                    if a.error_pixels > 0 {
                        wrong_but_counted += 1;
                    }
                    if matches!(t, Technique::Fabs { k: None } | Technique::Dfb | Technique::Ll) {
                        // fabs, dfb and ll carry the primitive id: they order ties as the
                        // reference does
                        assert_eq!((a.error_pixels, tied, lost), (0, 0, 0), "{what}");
                    }
                }
            }
        }
        println!("{}: {wrong_but_counted} runs wrong and counted", label(b));
        // the tie scenes do make the techniques that order ties by payload differ from the
        // reference somewhere, so `never_silent` above checked counts that were needed (were
        // every run right, the check would have held without a tie counted)
        assert!(wrong_but_counted > 0, "{}: no run ordered a tie otherwise than the reference", label(b));
    }
}

/// The 64-bit keys see the ties: on `ties:8` seen face-on the whole overlap is counted.
#[test]
fn key_ordered_techniques_count_ties() {
    for backend in backends_for("key_ordered_techniques_count_ties") {
        let b = backend.as_ref();
        for name in ["ties:8", "near:8"] {
            let scene = scene(name);
            let s = settings(64, "reference");
            let cam = camera(&scene, &s, FRONT);
            let r = render(b, &scene, &cam, &s);
            for t in [Technique::Mdts64 { k: None }, Technique::Mlp { m: 8 }, Technique::Ddp] {
                let f = render(b, &scene, &cam, &Settings { technique: t, ..s.clone() });
                let what = format!("{} {t} on {name}", label(b));
                assert!(f.stats.tied > 0, "{what}: no tie counted");
                assert!(f.stats.tied <= f.stats.captured, "{what}: tied counts captured fragments");
                if t != Technique::Ddp && name == "ties:8" {
                    // every fragment of the overlap is captured and ties with another colour (in
                    // `near:8` some depths of the overlap are an ulp apart: ordered, not tied)
                    let overlap: u64 = match &r.layers {
                        Some(l) => l.iter().filter(|&&n| n >= 2).map(|&n| u64::from(n)).sum(),
                        None => continue,
                    };
                    assert_eq!(f.stats.tied, overlap, "{what}");
                }
            }
        }
    }
}

/// `mdts`'s 20 depth bits merge `near:8`'s layers: the resolve counts them tied. With the alpha
/// override (mdts does not store alpha), what it gets wrong is what it counted.
#[test]
fn mdts_counts_what_its_depth_bits_merge() {
    for backend in backends_for("mdts_counts_what_its_depth_bits_merge") {
        let b = backend.as_ref();
        for scene in [scene("near:8"), reversed(&scene("near:8")), scene("planes:8")] {
            let s = Settings { alpha: Some(0.5), ..settings(64, "reference") };
            let (r, f) = with_reference(b, &scene, FRONT, &s, Technique::Mdts { k: None });
            let a = accuracy(&r, &f.image).expect("same size");
            let what = format!(
                "{} mdts on {}: {} error pixels, tied {}",
                label(b),
                scene.name,
                a.error_pixels,
                f.stats.tied
            );
            if scene.name.starts_with("planes") {
                assert_eq!((a.error_pixels, f.stats.tied), (0, 0), "{what}: separated layers");
            } else {
                assert!(f.stats.tied > 0, "{what}");
                assert!(a.error_pixels <= f.stats.tied + f.stats.lost, "{what}");
            }
        }
    }
}
