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

/// The hardware paths' own depth peels (`--hardware-capture blend`) on `coplanar`, in both
/// primitive orders and both views, count what a tie loses, at one sample and at four:
/// - `dp` at one sample keeps one of two equal depths a peel (the last drawn) and never peels the
///   other: `lost` is the pixels where the reference holds two layers, each lost fragment an
///   error pixel at most, as the atomics capture's `dp` (`coplanar_tie_is_counted_lost`). Seen
///   face-on every overlapping pixel ties; seen at an angle some depths of the overlap are an ulp
///   apart (ordered, not tied), and the count is the atomics capture's, which keys every depth.
/// - `dp` at four samples peels each sample's ties in primitive order (the depth test keeps the
///   first drawn, the previous peel's primitive a sample): the per-sample reference exactly, none
///   lost, though the scene ties at a hundred pixels and more.
/// - `ddp` at one sample hands both ends of a collapsed range over: both fragments of a tie are
///   composited, in key order, and counted `tied` (face-on: both fragments of every overlapping
///   pixel); nothing lost, never silent, the atomics capture's image and counts.
/// - `ddp` at four samples cannot order a tie at a sample (its range targets hold depths, no
///   primitive ids): the frame that meets one at a sample's range end is refused by name, naming
///   `--hardware-capture atomics` (face-on always; at an angle, where no depth ties exactly, the
///   frame must equal the reference instead). Mutations tried: the tie flag never set (both
///   backends render face-on: 400 error pixels, nothing counted, on the reversed scene), the end
///   check dropped from the frame's end on one backend (that backend renders).
///
/// Mutation tried: the per-sample peel's behind-test ignoring the primitive (`depth <=
/// previous`, the tie's loser never peeled): 400 error pixels, 420 lost face-on at 4 samples.
/// Writing the primitive as `prim` instead of `prim + 1` peels the same winner again forever: a
/// hang, not a failure.
#[test]
fn blend_peels_count_coplanar_ties() {
    let mut ran = 0;
    for backend in backends_for("blend_peels_count_coplanar_ties") {
        let b = backend.as_ref();
        if b.raster_path(&Settings::default()) != oit_core::RasterPath::Hardware {
            continue;
        }
        for scene in [scene("coplanar"), reversed(&scene("coplanar"))] {
            for view in VIEWS {
                for samples in [1, 4] {
                    let s = Settings { samples, ..settings(64, "reference") };
                    let cam = camera(&scene, &s, view);
                    let r = render(b, &scene, &cam, &s);
                    // the pixels where the two quads overlap: a tie of two fragments each
                    let overlap = r
                        .layers
                        .as_ref()
                        .expect("the reference's layers")
                        .iter()
                        .filter(|&&l| l == 2)
                        .count() as u64;
                    assert!(overlap > 100, "{} {} at {samples}: {overlap} pixels tie", label(b), scene.name);
                    for t in [Technique::Dp, Technique::Ddp] {
                        let blend =
                            Settings { technique: t, hardware_capture: HardwareCapture::Blend, ..s.clone() };
                        let on = format!("{} {t} blend on {} ({view:?}) at {samples}", label(b), scene.name);
                        if t == Technique::Ddp && samples > 1 {
                            // the range targets order no primitive ids: the frame that meets a tie
                            // at a sample's range end is refused by name, where it would be wrong
                            match b.render(&scene, &cam, &blend) {
                                Err(oit_core::OitError::Unsupported { what, .. }) => assert!(
                                    what.contains("coplanar") && what.contains("--hardware-capture atomics"),
                                    "{on}: {what}"
                                ),
                                // seen at an angle some depths of the overlap are an ulp apart:
                                // where none ties at a sample's end the frame must be right
                                Ok(f) if view != FRONT => {
                                    oit_tests::checks::exact(&r, &f).unwrap_or_else(|e| panic!("{on}: {e}"))
                                }
                                other => panic!("{on}: {:?}", other.map(|f| f.stats)),
                            }
                            ran += 1;
                            continue;
                        }
                        let f = render(b, &scene, &cam, &blend);
                        let atomics = render(
                            b,
                            &scene,
                            &cam,
                            &Settings { hardware_capture: HardwareCapture::Atomics, ..blend.clone() },
                        );
                        let a = accuracy(&r, &f.image).expect("same size");
                        let what = format!(
                            "{} {t} blend on {} ({view:?}) at {samples}: {} error pixels, captured {}, lost {}, tied {}",
                            label(b),
                            scene.name,
                            a.error_pixels,
                            f.stats.captured,
                            f.stats.lost,
                            f.stats.tied
                        );
                        oit_tests::checks::accounting(&f).unwrap_or_else(|e| panic!("{what}: {e}"));
                        oit_tests::checks::never_silent(&r, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
                        assert_eq!(f.stats.fragments, r.stats.fragments, "{what}");
                        match (t, samples) {
                            (Technique::Dp, 1) => {
                                if view == FRONT {
                                    assert_eq!(f.stats.lost, overlap, "{what}: one of each tie lost");
                                }
                                assert!(a.error_pixels <= f.stats.lost, "{what}");
                                assert_eq!(
                                    (f.stats.captured, f.stats.lost),
                                    (atomics.stats.captured, atomics.stats.lost),
                                    "{what}: the atomics capture's"
                                );
                            }
                            (Technique::Dp, _) => {
                                oit_tests::checks::exact(&r, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
                            }
                            _ => {
                                assert_eq!(f.stats.lost, 0, "{what}: both ends of each tie handed over");
                                if view == FRONT {
                                    assert_eq!(
                                        f.stats.tied,
                                        2 * overlap,
                                        "{what}: each tie's two fragments tied"
                                    );
                                }
                                assert_eq!(f.stats.tied, atomics.stats.tied, "{what}: the atomics capture's");
                                assert_eq!(f.image, atomics.image, "{what}: the atomics capture's");
                            }
                        }
                        ran += 1;
                    }
                }
            }
        }
    }
    // wgpu and vulkan hardware: 2 scenes × 2 views × (dp and ddp at 1 and 4)
    if std::env::var_os("OIT_REQUIRE_GPU").is_some() {
        assert!(ran >= 2 * 2 * 2 * 4, "{ran} runs");
    }
}

/// ddp's blend capture at several samples refuses only the frames that tie at a sample's range
/// end (`blend_peels_count_coplanar_ties`): `planes:6`, whose quads overlap apart in depth, in both
/// primitive orders and both views, renders on each GPU backend's hardware path at 4 samples, the
/// per-sample reference exactly, with the atomics capture's counts (the bunny and the wall through
/// `planes:16` in `hardware_blend_captures_at_samples`, tests/tests/msaa.rs, likewise). Mutation
/// tried: the flag set by every hand-over, tie or not: refused here.
#[test]
fn ddp_blend_at_samples_renders_what_does_not_tie() {
    let mut ran = 0;
    for backend in backends_for("ddp_blend_at_samples_renders_what_does_not_tie") {
        let b = backend.as_ref();
        if b.raster_path(&Settings::default()) != oit_core::RasterPath::Hardware {
            continue;
        }
        for scene in [scene("planes:6"), reversed(&scene("planes:6"))] {
            for view in VIEWS {
                let s = Settings { samples: 4, ..settings(64, "reference") };
                let cam = camera(&scene, &s, view);
                let r = render(b, &scene, &cam, &s);
                let blend = Settings {
                    technique: Technique::Ddp,
                    hardware_capture: HardwareCapture::Blend,
                    ..s.clone()
                };
                let on = format!("{} ddp blend on {} ({view:?}) at 4", label(b), scene.name);
                let f = b.render(&scene, &cam, &blend).unwrap_or_else(|e| panic!("{on}: {e}"));
                let atomics = render(
                    b,
                    &scene,
                    &cam,
                    &Settings { hardware_capture: HardwareCapture::Atomics, ..blend.clone() },
                );
                oit_tests::checks::accounting(&f).unwrap_or_else(|e| panic!("{on}: {e}"));
                oit_tests::checks::exact(&r, &f).unwrap_or_else(|e| panic!("{on}: {e}"));
                assert_eq!(
                    (f.stats.fragments, f.stats.captured, f.stats.tied),
                    (atomics.stats.fragments, atomics.stats.captured, atomics.stats.tied),
                    "{on}: the atomics capture's"
                );
                // the quads overlap: pixels of several layers, so the ranges' two ends both hand over
                assert!(r.stats.max_layers >= 2, "{on}: {} layers", r.stats.max_layers);
                ran += 1;
            }
        }
    }
    if std::env::var_os("OIT_REQUIRE_GPU").is_some() {
        // wgpu and vulkan hardware: 2 orders × 2 views
        assert!(ran >= 2 * 2 * 2, "{ran} runs");
    }
}

/// ddp's blend capture at several samples sees a tie at either end of an open range, not only on
/// a collapsed one: `coplanar` with a copy of its right quad, three times as wide, 0.3 in front of
/// the plane, then 0.3 behind it, so that where the three overlap the two coplanar fragments are one sample's far
/// end in one scene and its near end in the other. Each frame is refused by name on each GPU
/// backend's hardware path at 4 samples, both views (at an angle, a device whose interpolated
/// depths do not tie renders the frame, and then it must equal the reference). Mutations tried: the hand-over's tie test
/// kept on the near end alone (the scene with the copy in front renders: one of the two tied
/// fragments kept, both counted captured), on the far end alone (the other scene renders).
#[test]
fn ddp_blend_at_samples_refuses_ties_at_either_end() {
    let mut ran = 0;
    for backend in backends_for("ddp_blend_at_samples_refuses_ties_at_either_end") {
        let b = backend.as_ref();
        if b.raster_path(&Settings::default()) != oit_core::RasterPath::Hardware {
            continue;
        }
        for dz in [0.3f32, -0.3] {
            let mut scene = scene("coplanar");
            let right = scene.instances[1].clone();
            scene.instances.push(oit_core::Instance {
                // three times as wide, so that behind the plane too it covers the whole overlap
                // (where it did not, two coplanar fragments alone would make a collapsed range)
                transform: glam::Mat4::from_translation(glam::Vec3::new(0.0, 0.0, dz))
                    * glam::Mat4::from_scale(glam::Vec3::new(3.0, 3.0, 1.0))
                    * right.transform,
                ..right
            });
            scene.name = format!("coplanar with its right quad, scaled, again at z = {dz}");
            for view in VIEWS {
                let s = Settings { samples: 4, ..settings(64, "reference") };
                let cam = camera(&scene, &s, view);
                let r = render(b, &scene, &cam, &s);
                // three layers where the quads overlap (more on a pixel the quads' diagonals cross)
                assert!(r.stats.max_layers >= 3, "{}: {} layers", scene.name, r.stats.max_layers);
                let blend = Settings {
                    technique: Technique::Ddp,
                    hardware_capture: HardwareCapture::Blend,
                    ..s.clone()
                };
                let on = format!("{} ddp blend on {} ({view:?}) at 4", label(b), scene.name);
                match b.render(&scene, &cam, &blend) {
                    Err(oit_core::OitError::Unsupported { what, .. }) => assert!(
                        what.contains("coplanar") && what.contains("--hardware-capture atomics"),
                        "{on}: {what}"
                    ),
                    // Seen at an angle, the two coplanar quads' depths at a pixel are each
                    // triangle's own interpolation, which a GPU need not make bit-equal (an NVIDIA
                    // H200 does not, lavapipe does): where nothing ties, the frame renders, and
                    // then it must be the reference's. Face on, every device's depths tie.
                    Ok(f) if view != FRONT => {
                        oit_tests::checks::accounting(&f).unwrap_or_else(|e| panic!("{on}: {e}"));
                        oit_tests::checks::exact(&r, &f).unwrap_or_else(|e| panic!("{on}: {e}"));
                        eprintln!("{on}: no tie at an angle on this device; equal to the reference");
                    }
                    other => panic!("{on}: {:?}", other.map(|f| f.stats)),
                }
                ran += 1;
            }
        }
    }
    if std::env::var_os("OIT_REQUIRE_GPU").is_some() {
        // wgpu and vulkan hardware: 2 copies × 2 views
        assert!(ran >= 2 * 2 * 2, "{ran} runs");
    }
}
