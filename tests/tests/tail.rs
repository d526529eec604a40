//! `--overflow tail` (issue 11.3): `fabs:K`, `mdts:K` and `mdts64:K` merge a pixel's fragments
//! behind its K nearest into a tail (multi-layer alpha blending's tail, Salvi & Vaidyanathan 2014,
//! kept as the order-independent integer sums of a weighted average, Bavoil & Myers 2008) instead
//! of dropping them. On every backend × path: what `drop` counts lost is merged (`fabs` merges all
//! of it; the one-word `mdts` keep in `lost` a carried-off word equal to the K-th kept); only the
//! pixels that overflowed change; one more geometry pass runs; the output repeats exactly; the
//! error against the reference is bounded and smaller than `drop`'s; and turning the camera by
//! small steps changes the error between neighbouring frames less than `drop` does.

use oit_core::{Frame, Overflow, Settings, Stats, View};
use oit_tests::*;

const FIXED: [&str; 3] = ["fabs:2", "mdts:2", "mdts64:2"];

fn tail(s: &Settings) -> Settings {
    Settings { overflow: Overflow::Tail, ..s.clone() }
}

/// The stats that must repeat: all but the times.
fn counts(s: &Stats) -> Stats {
    Stats { wall_ms: 0.0, gpu_ms: None, gpu_pass_ms: Vec::new(), ..s.clone() }
}

fn same(a: &Frame, b: &Frame, what: &str) {
    assert_eq!(counts(&a.stats), counts(&b.stats), "{what}: stats");
    let differ = a.image.pixels.iter().zip(&b.image.pixels).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{what}: {differ} pixels differ");
}

#[test]
fn tail_merges_what_drop_loses() {
    let scene = scene("default");
    for backend in backends_for("tail_merges_what_drop_loses") {
        let b = backend.as_ref();
        for t in FIXED {
            let s = settings(64, t);
            let cam = camera(&scene, &s, View::default());
            let dropped = render(b, &scene, &cam, &s);
            let merged = render(b, &scene, &cam, &tail(&s));
            let what = format!("{} {t}", label(b));
            let (d, m) = (&dropped.stats, &merged.stats);
            assert!(d.lost > 0 && d.merged == 0, "{what}: the test needs overflow ({d:?})");
            assert!(m.merged > 0, "{what}: nothing merged");
            assert_eq!(m.captured, d.captured, "{what}: the K nearest are the same");
            assert_eq!(m.merged + m.lost, d.lost, "{what}: merged + lost under tail = lost under drop");
            assert_eq!(m.captured + m.merged + m.lost, m.fragments, "{what}: accounting");
            if t.starts_with("fabs") {
                assert_eq!(m.lost, 0, "{what}: fabs's keys are unique, every fragment past K is merged");
            }
            assert_eq!(m.geometry_passes, d.geometry_passes + 1, "{what}: one tail pass");
            let lost_pixels = merged.lost_pixels.as_ref().expect("counted per pixel");
            assert_eq!(lost_pixels.iter().map(|&l| u64::from(l)).sum::<u64>(), m.lost, "{what}");
            // the tail is behind the K nearest of the pixels that overflowed, nowhere else
            let overflowed = dropped.lost_pixels.as_ref().expect("counted per pixel");
            let mut changed = 0;
            for (i, ((a, c), &lost)) in
                dropped.image.pixels.iter().zip(&merged.image.pixels).zip(overflowed).enumerate()
            {
                if lost == 0 {
                    assert_eq!(a, c, "{what}: pixel {i} did not overflow but changed");
                } else if a != c {
                    changed += 1;
                }
            }
            assert!(changed > 0, "{what}: no overflowing pixel changed");
        }
    }
}

/// The same input gives the same output: repeated renders on every backend × path, and the CPU
/// with 1 and 4 threads (which hand fragments to the atomics in different orders).
#[test]
fn tail_is_deterministic() {
    let scene = scene("default");
    let mut runs: Vec<(String, Box<dyn oit_core::Backend>)> =
        backends_for("tail_is_deterministic").into_iter().map(|b| (label(b.as_ref()), b)).collect();
    runs.push(("cpu, 1 thread".into(), cpu_with_threads(1)));
    runs.push(("cpu, 4 threads".into(), cpu_with_threads(4)));
    for t in FIXED {
        let s = tail(&settings(64, t));
        let cam = camera(&scene, &s, View::default());
        let mut cpu_first: Option<Frame> = None;
        for (name, backend) in &runs {
            let first = render(backend.as_ref(), &scene, &cam, &s);
            assert!(first.stats.merged > 0, "{name} {t}: the test needs a tail");
            for run in 1..3 {
                same(&first, &render(backend.as_ref(), &scene, &cam, &s), &format!("{name} {t} run {run}"));
            }
            if name.starts_with("cpu") {
                match &cpu_first {
                    Some(f) => same(f, &first, &format!("{name} {t} against the first cpu run")),
                    None => cpu_first = Some(first),
                }
            }
        }
    }
}

/// The tail's error against the reference, by the error pixel rate (HPG 2009's EPR: channels
/// more than 1/255 off). Three bounds, each with its reason:
/// - every error pixel is a pixel the reference shows more than K layers at: elsewhere the K slots
///   hold every fragment and the tail is empty, so the frame is the exact technique's;
/// - the tail's EPR and its squared error are at most `drop`'s: the tail adds, behind the same K
///   fragments, the weighted average of what `drop` leaves out;
/// - on these scenes the tail's EPR is at most the measured value plus a margin (the table below,
///   measured on oit-cpu at 128²; the GPU paths' own references move edge pixels, hence the
///   margin). Where a pixel's hidden layers share one alpha (one object's, as here), the tail's
///   transmittance (1 − ᾱ)ⁿ is the exact Π(1 − αᵢ); what remains is their colours' order, which
///   the weighted average cannot see: pixels where differently coloured surfaces overlap behind
///   the K.
#[test]
fn tail_error_is_bounded() {
    // (scene, technique, tail EPR measured on oit-cpu, drop's, both in per cent)
    let cases = [
        ("knot", "fabs:2", 3.124, 24.383),
        ("knot", "mdts64:2", 3.124, 24.383),
        ("default", "fabs:4", 6.930, 29.179),
        ("cluster:8", "fabs:4", 0.397, 3.601),
    ];
    for backend in backends_for("tail_error_is_bounded") {
        let b = backend.as_ref();
        for (name, t, measured, _drop) in cases {
            let scene = scene(name);
            let s = settings(128, t);
            let k: u32 = t.split(':').nth(1).unwrap().parse().unwrap();
            let cam = camera(&scene, &s, View::default());
            let reference = render(b, &scene, &cam, &settings(128, "reference"));
            let dropped = render(b, &scene, &cam, &s);
            let merged = render(b, &scene, &cam, &tail(&s));
            let what = format!("{} {t} on {name}", label(b));
            let a_drop = oit_core::metrics::accuracy(&reference, &dropped.image).unwrap();
            let a_tail = oit_core::metrics::accuracy(&reference, &merged.image).unwrap();
            eprintln!(
                "{what}: EPR drop {:.3}% tail {:.3}%, PSNR drop {:.2} tail {:.2} dB",
                100.0 * a_drop.epr,
                100.0 * a_tail.epr,
                a_drop.psnr,
                a_tail.psnr
            );
            let layers = reference.layers.as_ref().expect("the reference counts layers");
            for (i, (r, p)) in reference.image.pixels.iter().zip(&merged.image.pixels).enumerate() {
                let off = r.iter().zip(p).any(|(x, y)| x.abs_diff(*y) > 1);
                assert!(!off || layers[i] > k, "{what}: pixel {i} of {} layers is off", layers[i]);
            }
            assert!(a_tail.epr <= a_drop.epr, "{what}: tail EPR {} over drop's {}", a_tail.epr, a_drop.epr);
            assert!(
                a_tail.psnr >= a_drop.psnr,
                "{what}: tail PSNR {} under drop's {}",
                a_tail.psnr,
                a_drop.psnr
            );
            let bound = measured * 1.25 + 0.5;
            assert!(
                100.0 * a_tail.epr <= bound,
                "{what}: tail EPR {:.3}% over {bound:.3}%",
                100.0 * a_tail.epr
            );
        }
    }
}

/// The error's change between neighbouring frames of a camera turning by `step` degrees: for each
/// pair, the mean over pixels of the largest channel change of (frame − reference), in 8-bit
/// levels. The reference moves with the camera, so what remains is the technique's flicker.
fn flicker(
    b: &dyn oit_core::Backend,
    scene: &oit_core::Scene,
    s: &Settings,
    step: f32,
    frames: u32,
) -> Vec<f64> {
    let mut errors: Vec<Vec<i32>> = Vec::new();
    for i in 0..frames {
        let view = View { azimuth: 30.0 + step * i as f32, ..View::default() };
        let cam = camera(scene, s, view);
        let reference =
            render(b, scene, &cam, &Settings { technique: oit_core::Technique::Reference, ..s.clone() });
        let frame = render(b, scene, &cam, s);
        errors.push(
            frame
                .image
                .pixels
                .iter()
                .zip(&reference.image.pixels)
                .flat_map(|(p, r)| (0..3).map(move |c| i32::from(p[c]) - i32::from(r[c])))
                .collect(),
        );
    }
    errors
        .windows(2)
        .map(|w| {
            let pixels = w[0].len() / 3;
            let sum: i64 = w[0]
                .chunks(3)
                .zip(w[1].chunks(3))
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| i64::from((x - y).abs())).max().unwrap_or(0))
                .sum();
            sum as f64 / pixels as f64
        })
        .collect()
}

/// Turning the camera by half a degree at a time, the tail's error changes between neighbouring
/// frames by less than half of `drop`'s, in the mean over the turn and at the worst pair, and by at
/// most 0.06 of an 8-bit level a pixel at the worst pair. Measured on knot at 96², fabs:2 and
/// mdts64:2 alike: tail 0.034–0.038 against drop's 0.083–0.100 on oit-cpu, wgpu (both paths) and
/// vulkan (lavapipe); the bound leaves room for other GPUs' edges.
#[test]
fn tail_is_stable_under_a_turning_camera() {
    let scene = scene("knot");
    for backend in backends_for("tail_is_stable_under_a_turning_camera") {
        let b = backend.as_ref();
        for t in ["fabs:2", "mdts64:2"] {
            let s = settings(96, t);
            let dropped = flicker(b, &scene, &s, 0.5, 6);
            let merged = flicker(b, &scene, &tail(&s), 0.5, 6);
            let what = format!("{} {t}", label(b));
            eprintln!(
                "{what}: error change between neighbouring frames, drop {dropped:.3?}, tail {merged:.3?}"
            );
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
            assert!(mean(&merged) < mean(&dropped), "{what}: mean {merged:?} not under drop's {dropped:?}");
            assert!(
                worst(&merged) < worst(&dropped),
                "{what}: worst {merged:?} not under drop's {dropped:?}"
            );
            assert!(worst(&merged) <= 0.06, "{what}: {merged:?} over 0.06 levels");
        }
    }
}

/// The tail merges colours and keeps no order or normals: the other effects are refused with a
/// clear error on every backend, not run wrong; the techniques sized from a counting pass (no K
/// to overflow) and the other techniques ignore the setting.
#[test]
fn tail_refuses_effects_other_than_transparency() {
    use oit_core::{Effect, OitError};
    let scene = scene("planes:4");
    for backend in backends_for("tail_refuses_effects_other_than_transparency") {
        let b = backend.as_ref();
        for effect in [Effect::Translucency, Effect::Complexity] {
            let s = Settings { effect, ..tail(&settings(16, "fabs:2")) };
            match b.render(&scene, &camera(&scene, &s, View::default()), &s) {
                Err(OitError::Unsupported { what, .. }) => assert!(what.contains("--overflow"), "{what}"),
                other => panic!("{} {effect:?}: {:?}", label(b), other.map(|f| f.stats)),
            }
        }
        for t in ["fabs", "dp", "reference"] {
            let s = tail(&settings(16, t));
            let cam = camera(&scene, &s, View::default());
            let plain = render(b, &scene, &cam, &settings(16, t));
            same(&plain, &render(b, &scene, &cam, &s), &format!("{} {t} ignores the tail", label(b)));
        }
    }
}
