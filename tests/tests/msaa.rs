//! Multisampling (issue 40; docs/msaa.md): the standard sample positions, per-sample coverage that
//! covers each sample of a surface once, `--samples 1` as before, the exact techniques equal to
//! the per-sample reference, no seam along the shared edges of a tessellated surface where
//! per-pixel coverage shows one, the supersampled reference against the MSAA one, the GPU
//! backends' compute paths equal to oit-cpu at several samples, opaque objects (the opaque pass a
//! sample; the techniques without a mask and fabs's tail over an opaque edge held to their
//! definitions; the supersampled reference's opaque pass a frame), and the refusals.

use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use oit_core::metrics::accuracy;
use oit_core::msaa::{Coverage, full_mask, positions, positions_f32};
use oit_core::{Backend, Frame, OitError, Settings, Shading, Technique, View};
use oit_cpu::CpuBackend;
use oit_cpu::raster::Rasterizer;
use oit_tests::*;

/// The two patterns: 4 and 8 positions, each strictly inside the pixel, all distinct, each on
/// the 1/16-pixel grid (exact in the rasterizer's 1/256 fixed point); one sample is the centre.
#[test]
fn sample_positions_are_the_standard_patterns() {
    assert_eq!(positions_f32(1), vec![(0.5, 0.5)]);
    assert_eq!(positions_f32(4), vec![(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)]);
    let eight = [
        (0.5625, 0.3125),
        (0.4375, 0.6875),
        (0.8125, 0.5625),
        (0.3125, 0.1875),
        (0.1875, 0.8125),
        (0.0625, 0.4375),
        (0.6875, 0.9375),
        (0.9375, 0.0625),
    ];
    assert_eq!(positions_f32(8), eight.to_vec());
    for n in [4, 8] {
        let p = positions(n);
        assert_eq!(p.len(), n as usize);
        for (i, a) in p.iter().enumerate() {
            assert!((1..16).contains(&a.0) && (1..16).contains(&a.1), "{n}×: {a:?} inside the pixel");
            assert!(p[..i].iter().all(|b| b != a), "{n}×: {a:?} twice");
        }
        assert_eq!(full_mask(n).count_ones(), n);
    }
}

/// Per sample of every pixel, how many fragments of the masked pass cover it.
fn sample_counts(scene: &str, size: u32, samples: u32, view: View) -> (Vec<Vec<u32>>, u64) {
    let scene = scene_of(scene);
    let s = Settings { samples, ..settings(size, "reference") };
    let cam = camera(&scene, &s, view);
    let raster = Rasterizer::new(&scene, &cam, &s);
    let counts: Vec<AtomicU32> = (0..s.pixel_count() * samples as usize).map(|_| AtomicU32::new(0)).collect();
    let n = raster.for_each_masked_fragment(samples, |f, mask| {
        assert_ne!(mask, 0, "a fragment covers a sample");
        assert_eq!(mask & !full_mask(samples), 0, "only the pixel's samples");
        for i in 0..samples as usize {
            if mask >> i & 1 == 1 {
                counts[f.pixel as usize * samples as usize + i].fetch_add(1, Relaxed);
            }
        }
    });
    let per_pixel =
        counts.chunks(samples as usize).map(|c| c.iter().map(|a| a.load(Relaxed)).collect()).collect();
    (per_pixel, n)
}

fn scene_of(name: &str) -> oit_core::Scene {
    scene(name)
}

/// Two triangles sharing an edge (`planes:1` face on: one quad, split along its diagonal) cover
/// each sample of the quad exactly once: no sample is covered twice along the diagonal, none
/// missed; and a closed tessellated sphere (`spheres:1`, many small triangles) covers each
/// sample of its silhouette exactly twice (its front and its back), never once or three times:
/// the fill rule at the samples leaves no crack and no overlap between triangles that share an
/// edge. Mutation caught: `v > above` turned into `v >= 0` at the samples (the shared edges'
/// samples covered twice).
#[test]
fn shared_edges_cover_each_sample_once() {
    for samples in [4, 8] {
        let (counts, fragments) = sample_counts("planes:1", 32, samples, FRONT);
        assert!(fragments > 0);
        let mut full = 0;
        for c in &counts {
            assert!(c.iter().all(|&n| n <= 1), "{samples}×: a sample covered twice: {c:?}");
            full += usize::from(c.iter().all(|&n| n == 1));
        }
        assert!(full > 100, "{samples}×: {full} pixels inside the quad");
        let (counts, _) = sample_counts("spheres:1", 48, samples, View::default());
        let mut inside = 0;
        for c in &counts {
            assert!(c.iter().all(|&n| n == 0 || n == 2), "{samples}×: a sphere's sample covered {c:?}");
            inside += usize::from(c.iter().all(|&n| n == 2));
        }
        assert!(inside > 200, "{samples}×: {inside} pixels inside the sphere");
    }
}

/// With one sample the masked pass is the single-sample pass: the same (pixel, primitive,
/// depth) fragments, each with mask 1; and `samples: 1` renders what settings without it render,
/// for the reference and every technique (the default is 1: the images of before).
#[test]
fn one_sample_is_as_before() {
    let scene = scene_of("knot");
    let s = settings(48, "reference");
    let cam = camera(&scene, &s, View::default());
    let raster = Rasterizer::new(&scene, &cam, &s);
    let collect = |masked: bool| {
        let out = std::sync::Mutex::new(Vec::new());
        if masked {
            raster.for_each_masked_fragment(1, |f, mask| {
                assert_eq!(mask, 1);
                out.lock().unwrap().push((f.pixel, f.prim, f.depth.to_bits()));
            });
        } else {
            raster.for_each_fragment(|f| out.lock().unwrap().push((f.pixel, f.prim, f.depth.to_bits())));
        }
        let mut v = out.into_inner().unwrap();
        v.sort_unstable();
        v
    };
    let (a, b) = (collect(true), collect(false));
    assert!(!a.is_empty());
    assert_eq!(a, b);
    let cpu = CpuBackend::default();
    for t in ["reference", "dfb", "ll", "fabs", "dp", "mlp:2", "wavg"] {
        let unset = settings(48, t);
        assert_eq!(unset.samples, 1);
        let one = Settings { samples: 1, ..unset.clone() };
        let (mut x, mut y) = (render(&cpu, &scene, &cam, &unset), render(&cpu, &scene, &cam, &one));
        x.stats.wall_ms = 0.0;
        y.stats.wall_ms = 0.0;
        assert_eq!(x, y, "{t}");
    }
}

/// The exact techniques at 4 and 8 samples equal the per-sample reference (EPR 0), capture every
/// fragment, and count the same fragments; fabs sized from the count and fabs:K with K above the
/// deepest pixel alike. More fragments than one sample's: the samples off the centres add edge
/// fragments.
#[test]
fn exact_techniques_equal_the_per_sample_reference() {
    let cpu = CpuBackend::default();
    for (name, size) in [("bunny", 96), ("knot", 64), ("planes:6", 64)] {
        let scene = scene_of(name);
        for samples in [4, 8] {
            let s = Settings { samples, ..settings(size, "reference") };
            let cam = camera(&scene, &s, View::default());
            let r = render(&cpu, &scene, &cam, &s);
            let single = render(&cpu, &scene, &cam, &settings(size, "reference"));
            assert!(r.stats.fragments > single.stats.fragments, "{name} {samples}×: edge fragments");
            let deepest = r.stats.max_layers;
            for t in [
                Technique::Dfb,
                Technique::Ll,
                Technique::Fabs { k: None },
                Technique::Fabs { k: Some(deepest + 2) },
                Technique::Dp,
                Technique::Ddp,
                Technique::Mlp { m: 1 },
                Technique::Mlp { m: 2 },
                Technique::Mlp { m: 4 },
            ] {
                let f = render(&cpu, &scene, &cam, &Settings { technique: t, ..s.clone() });
                assert_eq!(f.stats.coverage, Some(Coverage::Sample), "{t}");
                let a = accuracy(&r, &f.image).unwrap();
                let what = format!("{t} on {name} at {samples}×");
                assert!(a.is_measured(), "{what}");
                assert_eq!((a.error_pixels, f.stats.lost), (0, 0), "{what}: max error {}", a.max_error);
                assert_eq!(
                    (f.stats.fragments, f.stats.captured),
                    (r.stats.fragments, r.stats.fragments),
                    "{what}"
                );
            }
        }
    }
}

/// dp, ddp and mlp:M per sample (docs/msaa.md): each peel finds a pixel's next layers by their
/// (depth, primitive id) keys (one, the near and the far, or the M nearest) and composites each
/// into the samples its mask covers, so at 4 and 8 samples they equal the per-sample reference
/// (EPR 0) on the bunny, a tessellated sphere (flat shaded, its shared edges' halves one surface)
/// and the knot, lose nothing and peel every fragment as a layer: the plan's schedule, the layers
/// and one pass (dp), half of them and one (ddp), ⌈layers / M⌉ and one (mlp:M, M = 1, 2, 4).
/// Under Fresnel (the transmittances per sample) they are exact too, and the heat map is the
/// reference's. Under `--max-peels 2` one more pass fetches the last layers and what lies behind
/// is counted lost (where there is more than two passes' worth). `--coverage fraction` keeps the former peel (each layer over the whole pixel,
/// alpha × covered fraction), which errs where the per-sample peel does not. Mutations tried:
/// oit-cpu's `accumulate` compositing each layer into every sample, its mask ignored ("dp on
/// bunny at 4×: max error 0.29", 2732 error pixels); the same in the GPU's `peel_samples.wgsl`,
/// caught by `gpu_paths_equal_the_cpu_at_samples` ("wgpu/hardware: dp on bunny at 4×: 1236 error
/// pixels"). For mlp: oit-cpu's fetch storing every sample's bit as the layer's mask ("mlp:1 on
/// bunny at 4×: max error 0.29"; in `mlp_samples.wgsl`, "wgpu/hardware: mlp:1 on bunny at 4×:
/// 1236 error pixels" in `gpu_paths_equal_the_cpu_at_samples`); its keys by depth alone, the
/// primitive id dropped ("mlp:1 on bunny at 4×: max error 0.031"; in `mlp_samples.wgsl`, the
/// frame's accounting refuses it, one fragment short).
#[test]
fn peels_per_sample_equal_the_reference() {
    let cpu = CpuBackend::default();
    for (name, size, alpha) in [("bunny", 96, None), ("spheres:1", 48, Some(0.4)), ("knot", 48, None)] {
        let scene = scene_of(name);
        for samples in [4, 8] {
            let s = Settings { samples, alpha, shading: Shading::Flat, ..settings(size, "reference") };
            let cam = camera(&scene, &s, View::default());
            let r = render(&cpu, &scene, &cam, &s);
            let layers = r.stats.max_layers;
            let mlp = |m| Technique::Mlp { m };
            for t in [Technique::Dp, Technique::Ddp, mlp(1), mlp(2), mlp(4)] {
                let what = format!("{t} on {name} at {samples}×");
                // layers a pass: one (dp), two (ddp), M (mlp:M)
                let per = match t {
                    Technique::Dp => 1,
                    Technique::Ddp => 2,
                    Technique::Mlp { m } => m,
                    _ => unreachable!(),
                };
                let at = |extra: Settings| render(&cpu, &scene, &cam, &Settings { technique: t, ..extra });
                let f = at(s.clone());
                let a = accuracy(&r, &f.image).unwrap();
                assert_eq!(f.stats.coverage, Some(Coverage::Sample), "{what}");
                assert_eq!((a.error_pixels, f.stats.lost), (0, 0), "{what}: max error {}", a.max_error);
                assert_eq!(
                    (f.stats.captured, f.stats.fragments),
                    (r.stats.fragments, r.stats.fragments),
                    "{what}"
                );
                let peels = layers.div_ceil(per);
                assert!(peels > 1 || per > 2, "{what}: {layers} layers, one pass");
                assert_eq!(f.stats.geometry_passes, peels + 1, "{what}: passes");
                let plan = oit_core::plan::Plan::new("cpu", &scene, &Settings { technique: t, ..s.clone() })
                    .unwrap();
                let scheduled: u32 = plan.schedule(layers, layers).iter().map(|p| p.1).sum();
                assert_eq!(f.stats.geometry_passes, scheduled, "{what}: the plan's schedule");
                // the per-sample accumulators are the plan's, to the byte
                let pixels = u64::from(s.width) * u64::from(s.height);
                let arrays = plan.storage_bytes(pixels, oit_core::plan::Counted::default())
                    - pixels * oit_core::plan::RESOLVE_STATE_BYTES;
                assert_eq!(f.stats.storage_bytes, arrays, "{what}: storage");
                assert!(
                    plan.arrays(Default::default())
                        .iter()
                        .any(|a| a.name.starts_with("sample accumulators")
                            && a.per_pixel == u64::from(samples))
                );
                // the peel limit: two peels and the pass that fetches the second's layers; lost
                // what lies behind them
                let limited = at(Settings { max_peels: Some(2), ..s.clone() });
                checks::accounting(&limited).unwrap_or_else(|e| panic!("{what} --max-peels 2: {e}"));
                assert_eq!(limited.stats.geometry_passes, 3.min(peels + 1), "{what} --max-peels 2");
                assert_eq!(limited.stats.lost > 0, layers > 2 * per, "{what} --max-peels 2: lost");
                // Fresnel and the heat map
                for effect in [oit_core::Effect::Fresnel, oit_core::Effect::Complexity] {
                    let e = Settings { effect, ..s.clone() };
                    let (re, fe) = (render(&cpu, &scene, &cam, &e), at(e.clone()));
                    assert_eq!(fe.stats.coverage, Some(Coverage::Sample), "{what} {effect:?}");
                    let a = accuracy(&re, &fe.image).unwrap();
                    assert_eq!(a.error_pixels, 0, "{what} {effect:?}: max error {}", a.max_error);
                }
                // the coverage-fraction peel errs at the edges
                let fraction = at(Settings { fraction_coverage: true, ..s.clone() });
                assert_eq!(fraction.stats.coverage, Some(Coverage::Fraction), "{what}");
                let (mf, ms) = (mean_error(&r.image, &fraction.image), mean_error(&r.image, &f.image));
                eprintln!("{what}: mean error {ms:.4} per sample, {mf:.4} by coverage fraction");
                assert!(mf > ms, "{what}: fraction {mf:.4}, per sample {ms:.4}");
            }
        }
    }
}

/// fabs:K below the deepest pixel at 4 samples keeps each pixel's K nearest whatever the arrival
/// order: the same image on 1 and 4 threads, and every fragment past K counted lost.
#[test]
fn fabs_overflow_at_samples_is_repeatable() {
    let scene = scene_of("bunny");
    let s = Settings { samples: 4, ..settings(64, "fabs:2") };
    let cam = camera(&scene, &s, View::default());
    let a = render(&CpuBackend::with_threads(Some(1)), &scene, &cam, &s);
    let b = render(&CpuBackend::with_threads(Some(4)), &scene, &cam, &s);
    assert_eq!(a.image, b.image);
    assert!(a.stats.lost > 0);
    assert_eq!(a.stats.captured + a.stats.lost, a.stats.fragments);
}

/// Flat shading at alpha 0.4, 64², `samples` samples.
fn flat_settings(samples: u32, technique: &str) -> Settings {
    Settings { samples, shading: Shading::Flat, alpha: Some(0.4), ..settings(64, technique) }
}

/// Largest channel difference of two pixels.
fn diff(a: [u8; 4], b: [u8; 4]) -> u8 {
    (0..3).map(|i| a[i].abs_diff(b[i])).max().unwrap_or(0)
}

/// The seam test, on oit-cpu and every GPU path (the hardware paths' masks are the device's
/// `sample_mask`). A tessellated sphere, flat shaded at
/// alpha 0.4, so that every sample inside its silhouette composites the same two layers (its
/// front and its back, of one colour) to the same colour: at 4 samples the per-sample reference
/// and `ll`, `dfb` and `fabs` give every
/// pixel whose samples all lie inside the silhouette that colour, within 1 level of 8 bits (the
/// mean of equal samples rounds at most that far) — the pixels on the triangles' shared edges
/// included, which receive 3 or 4 fragments. Per-pixel coverage (every mask full, what
/// compositing a pixel's fragments at full weight gives, worked out here from the same
/// fragments) makes those edge pixels more opaque: the test fails without the per-sample
/// composite. The bound: 1 level; the seam it would miss is one fragment of alpha 0.4 more, many
/// levels.
#[test]
fn no_seam_along_shared_edges() {
    let scene = scene_of("spheres:1");
    let cpu = CpuBackend::default();
    let s = flat_settings(4, "reference");
    let cam = camera(&scene, &s, View::default());
    // per pixel: fragments, and how many samples are covered twice
    let raster = Rasterizer::new(&scene, &cam, &s);
    let n = s.pixel_count();
    let frags: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(0)).collect();
    let covered: Vec<[AtomicU32; 4]> = (0..n).map(|_| Default::default()).collect();
    let colour = std::sync::Mutex::new(None);
    raster.for_each_masked_fragment(4, |f, mask| {
        colour.lock().unwrap().get_or_insert(f.color());
        frags[f.pixel as usize].fetch_add(1, Relaxed);
        for (i, c) in covered[f.pixel as usize].iter().enumerate() {
            if mask >> i & 1 == 1 {
                c.fetch_add(1, Relaxed);
            }
        }
    });
    let inside: Vec<usize> = (0..n).filter(|&p| covered[p].iter().all(|c| c.load(Relaxed) == 2)).collect();
    let seams: Vec<usize> = inside.iter().copied().filter(|&p| frags[p].load(Relaxed) > 2).collect();
    assert!(
        inside.len() > 500 && seams.len() > 50,
        "{} inside, {} on shared edges",
        inside.len(),
        seams.len()
    );
    // the interior colour: a pixel of two fragments, each covering every sample
    let plain = *inside.iter().find(|&&p| frags[p].load(Relaxed) == 2).expect("a pixel off every edge");
    let background = s.background;
    let colour = colour.into_inner().unwrap().expect("a fragment");
    assert_eq!(colour.w, 0.4);
    // `layers` fragments of the one colour composited at full weight over the background
    let over = |layers: u32| {
        let mut c = background;
        for _ in 0..layers {
            c = c * (1.0 - colour.w) + colour.truncate() * colour.w;
        }
        oit_core::composite::linear_to_srgb8(c.max_element())
    };
    // on oit-cpu and every GPU path
    let backends: Vec<Box<dyn Backend>> = std::iter::once(Box::new(cpu) as Box<dyn Backend>)
        .chain(backends_for("no_seam_along_shared_edges").into_iter().filter(|b| b.name() != "cpu"))
        .collect();
    for backend in &backends {
        let on = label(backend.as_ref());
        if let Err(e) = backend.render(&scene, &cam, &flat_settings(4, "dfb")) {
            // a device without the standard sample locations (4 samples are otherwise required)
            assert!(e.to_string().contains("standardSampleLocations"), "{on}: {e}");
            continue;
        }
        for t in ["reference", "ll", "dfb", "fabs"] {
            let f: Frame = render(backend.as_ref(), &scene, &cam, &flat_settings(4, t));
            let want = f.image.pixels[plain];
            let worst = inside.iter().map(|&p| diff(f.image.pixels[p], want)).max().unwrap();
            assert!(worst <= 1, "{on} {t}: a pixel inside the silhouette {worst} levels off its interior");
        }
        // per-pixel coverage (`--coverage pixel`): the same fragments at full weight make the
        // seam pixels a layer more opaque, rendered (mutation: `coverage` keeping the mask as it
        // is makes the baseline seamless and this fails)
        for t in ["ll", "dfb", "fabs"] {
            let s = Settings { pixel_coverage: true, ..flat_settings(4, t) };
            let f: Frame = render(backend.as_ref(), &scene, &cam, &s);
            let want = f.image.pixels[plain];
            let worst = seams.iter().map(|&p| diff(f.image.pixels[p], want)).max().unwrap();
            assert!(worst > 4, "{on} {t} --coverage pixel: the seam is only {worst} levels off the interior");
        }
    }
    // and worked out by hand: a seam pixel composites all of its fragments at full weight
    let seam = seams.iter().map(|&p| frags[p].load(Relaxed)).max().unwrap();
    assert!(
        over(seam).abs_diff(over(2)) > 4,
        "per-pixel coverage shows the seam: {} against {}",
        over(seam),
        over(2)
    );
}

/// `fabs:K --overflow tail` above one sample: what lies behind a pixel's K nearest is merged into
/// one tail a pixel (not a tail a sample: the same 40 bytes a pixel as at one sample), each
/// fragment's alpha weighted by its coverage fraction as the techniques without a mask weigh
/// theirs, and each sample composites the slots that cover it over that tail. Every fragment the
/// K slots drop is merged, none lost; and against the per-sample reference the tail errs less
/// than dropping them (what it is for), on the bunny and the knot at 4 and 8 samples. Its cost
/// is the tail's own approximation (one weighted-average colour for every fragment behind the K)
/// plus the coverage fraction's where the tail's fragments cover different samples (measured:
/// mean error 2.0 levels a pixel with the tail, 15.8 dropped, fabs:2 on the bunny at 4×). The GPU
/// paths make the same frames (`gpu_paths_equal_the_cpu_at_samples`, `hardware_at_samples`).
/// Over opaque objects (the wall through `planes:16` and through the default scene) the tail is
/// put behind each sample over that sample's own opaque colour (the fragments merged into it
/// those the cut left in front at some sample, weighted by the fraction they keep): the pixels
/// that did not overflow are the per-sample reference's (their tail empty), `occluded` is the
/// reference's, and the tail errs less than dropping.
/// Mutation tried: oit-cpu's tail weight counted over every sample's bit (`kept(mask) | 0xff`:
/// "wgpu/compute: fabs:2 on bunny at 4× (Transparency): 1193 pixels off the edges differ, by up
/// to 69" in `gpu_paths_equal_the_cpu_at_samples`; this test's bound held, the tail still nearer
/// than the drop).
#[test]
fn fabs_tail_at_samples_merges_behind_the_k() {
    let cpu = CpuBackend::default();
    let cases = [
        ("bunny", 4, View::default()),
        ("knot", 4, View::default()),
        ("knot", 8, View::default()),
        (WALLED[0], 4, oblique()),
        (WALLED[1], 4, oblique()),
        (WALLED[0], 8, oblique()),
    ];
    for (name, samples, view) in cases {
        let scene = scene_of(name);
        let base = Settings { samples, ..settings(96, "reference") };
        let cam = camera(&scene, &base, view);
        let reference = render(&cpu, &scene, &cam, &base);
        let drop =
            render(&cpu, &scene, &cam, &Settings { technique: "fabs:2".parse().unwrap(), ..base.clone() });
        let tail_settings = Settings {
            technique: "fabs:2".parse().unwrap(),
            overflow: oit_core::Overflow::Tail,
            ..base.clone()
        };
        let tail = render(&cpu, &scene, &cam, &tail_settings);
        let what = format!("fabs:2 on {name} at {samples}×");
        checks::accounting(&tail).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(drop.stats.lost > 0, "{what}: overflows");
        assert_eq!(
            (tail.stats.lost, tail.stats.merged),
            (0, drop.stats.lost),
            "{what}: every fragment past K merged"
        );
        assert_eq!(tail.stats.geometry_passes, drop.stats.geometry_passes + 1, "{what}: one tail pass");
        assert_eq!(tail.stats.occluded, reference.stats.occluded, "{what}: occluded");
        // a pixel that did not overflow has an empty tail: each sample over its own colour, exact
        let dropped = drop.lost_pixels.as_ref().expect("per-pixel losses");
        let mut whole = 0;
        for (px, _) in dropped.iter().enumerate().filter(|&(_, &l)| l == 0) {
            let (got, want) = (tail.image.pixels[px], reference.image.pixels[px]);
            assert!(
                diff(got, want) <= 1,
                "{what}: pixel {px} without a tail is {got:?}, the reference {want:?}"
            );
            whole += 1;
        }
        assert!(whole > 100, "{what}: {whole} pixels without a tail");
        let (ed, et) = (mean_error(&reference.image, &drop.image), mean_error(&reference.image, &tail.image));
        let (ad, at) =
            (accuracy(&reference, &drop.image).unwrap(), accuracy(&reference, &tail.image).unwrap());
        eprintln!(
            "{what}: mean error {ed:.3} dropped, {et:.3} with the tail; EPR {:.1}% and {:.1}%",
            100.0 * ad.epr,
            100.0 * at.epr
        );
        assert!(et < ed, "{what}: the tail errs less than dropping ({et} against {ed})");
    }
}

/// The supersampled reference (every sample shaded and rasterized as a pixel of its own) differs
/// from the MSAA reference only along the silhouette: with flat shading every sample of a pixel
/// well inside it (its 3×3 neighbourhood covered at every sample) composites the same layers in
/// both, so those pixels agree within 1 level; the silhouette's pixels may differ (the moved
/// projection snaps its vertices anew). Under the headlight, whose shading varies across a
/// pixel, the two differ (one shading a sample against one a fragment); and the supersampled
/// reference at 4 samples is not the single-sample reference.
#[test]
fn supersampled_differs_from_msaa_only_at_edges() {
    let scene = scene_of("spheres:1");
    let cpu = CpuBackend::default();
    let s = flat_settings(4, "reference");
    let cam = camera(&scene, &s, View::default());
    let msaa = render(&cpu, &scene, &cam, &s);
    let ss = render(&cpu, &scene, &cam, &Settings { supersample: true, ..s.clone() });
    let counts = sample_counts_with(&scene, &s, &cam);
    let (w, h) = (s.width as usize, s.height as usize);
    let deep_inside = |x: usize, y: usize| {
        (x > 0 && y > 0 && x + 1 < w && y + 1 < h)
            && (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| counts[yy * w + xx].iter().all(|&c| c == 2)))
    };
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            if deep_inside(x, y) {
                let p = y * w + x;
                assert!(diff(msaa.image.pixels[p], ss.image.pixels[p]) <= 1, "pixel ({x}, {y})");
                checked += 1;
            }
        }
    }
    assert!(checked > 300, "{checked} pixels inside");
    // headlight shading varies across a pixel: supersampling shades each sample, MSAA the centre
    let lit = Settings { shading: Shading::Headlight, ..s.clone() };
    let (a, b) = (
        render(&cpu, &scene, &cam, &lit),
        render(&cpu, &scene, &cam, &Settings { supersample: true, ..lit }),
    );
    assert_ne!(a.image, b.image, "supersampling shades per sample");
    let single = render(&cpu, &scene, &cam, &Settings { samples: 1, ..s.clone() });
    assert_ne!(single.image, ss.image);
}

fn sample_counts_with(scene: &oit_core::Scene, s: &Settings, cam: &oit_core::Camera) -> Vec<Vec<u32>> {
    let raster = Rasterizer::new(scene, cam, s);
    let k = s.samples as usize;
    let counts: Vec<AtomicU32> = (0..s.pixel_count() * k).map(|_| AtomicU32::new(0)).collect();
    raster.for_each_masked_fragment(s.samples, |f, mask| {
        for i in 0..k {
            if mask >> i & 1 == 1 {
                counts[f.pixel as usize * k + i].fetch_add(1, Relaxed);
            }
        }
    });
    counts.chunks(k).map(|c| c.iter().map(|a| a.load(Relaxed)).collect()).collect()
}

/// What is not done yet says so by name: the hardware paths' own captures not yet done at 4
/// samples (dp's and ddp's blend captures under `--max-peels` among them, refused on each GPU
/// backend's hardware path before the capture runs; mutations tried: the refusal's `--max-peels`
/// arm removed; oit-vulkan's call of the refusal removed, and vulkan renders it), the
/// supersampled reference on a GPU backend's hardware path; a sample count other than
/// 1, 4 or 8 and `--supersample` at one sample are invalid settings. Scenes with opaque objects
/// render at 4 samples for every other technique, fabs's tail and the supersampled reference
/// included.
#[test]
fn refusals_name_what_is_not_done() {
    let scene = scene_of("knot");
    let cpu = CpuBackend::default();
    let base = Settings { samples: 4, ..settings(32, "reference") };
    // kbuf keeps its masks (tests/tests/kbuf.rs): its plan takes the samples, and a backend
    // without an interlock refuses it for that alone, as at one sample
    let kbuf = Settings { technique: "kbuf:4".parse().unwrap(), ..base.clone() };
    let plan = oit_core::plan::Plan::new("vulkan", &scene, &kbuf).expect("kbuf at 4 samples planned");
    assert!(plan.needs_interlock());
    match cpu.render(&scene, &camera(&scene, &kbuf, View::default()), &kbuf) {
        Err(OitError::Unsupported { what, .. }) => {
            assert!(what.contains("VK_EXT_fragment_shader_interlock") && !what.contains("samples"), "{what}")
        }
        other => panic!("cpu kbuf at 4 samples: {:?}", other.map(|f| f.stats)),
    }
    // a hardware path's own captures where they cannot give what is asked (dp's and ddp's, which
    // peel each sample, under the coverages that peel the pixel; plain's blender, which blends
    // each sample, under `--coverage pixel` or `fraction`; each message saying why and what to
    // use), refused where a backend would run one; wavg, wsum, bdp, dp, ddp and plain themselves
    // run, over opaque objects too (`hardware_blend_captures_at_samples`)
    let refused = |s: &Settings| match oit_core::plan::refuse_multisampled_own_capture("wgpu", s) {
        Err(OitError::Unsupported { what, .. }) => what,
        Ok(()) => panic!("{} at 4 samples (coverage pixel {}): not refused", s.technique, s.pixel_coverage),
        Err(e) => panic!("{e}"),
    };
    // dp's and ddp's blend captures peel each sample: the coverages that are not per sample are
    // refused
    for t in [Technique::Dp, Technique::Ddp] {
        let peel = Settings { technique: t, ..base.clone() };
        for s in [
            Settings { pixel_coverage: true, ..peel.clone() },
            Settings { fraction_coverage: true, ..peel.clone() },
            Settings { effect: oit_core::Effect::Translucency, ..peel.clone() },
        ] {
            let what = refused(&s);
            assert!(
                what.contains("peels each sample") && what.contains("--hardware-capture atomics"),
                "{what}"
            );
        }
        // and under a peel limit, which would cut a fragment off at one sample while another
        // peeled it, where the count (a fragment once) calls it captured
        let limited = Settings { max_peels: Some(2), ..peel.clone() };
        let what = refused(&limited);
        assert!(what.contains("--max-peels") && what.contains("--hardware-capture atomics"), "{what}");
        assert!(
            oit_core::plan::refuse_multisampled_own_capture("wgpu", &Settings { samples: 1, ..limited })
                .is_ok(),
            "{t} --max-peels at one sample"
        );
    }
    // on each GPU backend's hardware path, where it starts the capture: refused by name, not
    // rendered (the atomics capture renders it)
    let mut limited_on = 0;
    for backend in gpu_backends_for("refusals_name_what_is_not_done") {
        let backend = backend.as_ref();
        if backend.raster_path(&Settings::default()) != oit_core::RasterPath::Hardware {
            continue;
        }
        for t in [Technique::Dp, Technique::Ddp] {
            let s = Settings {
                technique: t,
                max_peels: Some(2),
                hardware_capture: oit_core::HardwareCapture::Blend,
                ..base.clone()
            };
            let cam = camera(&scene, &s, View::default());
            let on = format!("{} {t} blend --max-peels 2 at 4 samples", label(backend));
            match backend.render(&scene, &cam, &s) {
                Err(OitError::Unsupported { what, .. }) => {
                    assert!(
                        what.contains("--max-peels") && what.contains("--hardware-capture atomics"),
                        "{on}: {what}"
                    )
                }
                other => panic!("{on}: {:?}", other.map(|f| f.stats)),
            }
            let atomics = Settings { hardware_capture: oit_core::HardwareCapture::Atomics, ..s.clone() };
            let f = render(backend, &scene, &cam, &atomics);
            checks::accounting(&f).unwrap_or_else(|e| panic!("{on}, atomics: {e}"));
            limited_on += 1;
        }
    }
    if std::env::var_os("OIT_REQUIRE_GPU").is_some() {
        // wgpu's and vulkan's hardware paths, dp and ddp
        assert!(limited_on >= 4, "{limited_on} GPU refusals checked");
    }
    let plain = Settings { technique: Technique::Plain, ..base.clone() };
    for (what, named) in [
        (refused(&Settings { pixel_coverage: true, ..plain.clone() }), "--coverage pixel"),
        (refused(&Settings { fraction_coverage: true, ..plain.clone() }), "--coverage fraction"),
    ] {
        assert!(
            what.contains(named)
                && what.contains("only the samples it covers")
                && what.contains("--raster compute"),
            "{what}"
        );
    }
    for t in ["plain", "wavg", "wsum", "bdp", "dp", "ddp"] {
        let s = Settings { technique: t.parse().unwrap(), ..base.clone() };
        assert!(oit_core::plan::refuse_multisampled_own_capture("wgpu", &s).is_ok(), "{t}");
    }
    assert!(
        oit_core::plan::refuse_multisampled_own_capture(
            "wgpu",
            &Settings { samples: 1, pixel_coverage: true, ..plain }
        )
        .is_ok()
    );
    // opaque objects (an opaque wall behind the knot) render at 4 samples (the opaque pass is
    // multisampled), for the techniques without a mask too (their coverage cut at each sample's
    // opaque depth), fabs's tail and the supersampled reference (an opaque pass a frame)
    let walled = scene_of("wall:1:knot");
    assert!(walled.has_opaque());
    let walled_cam = camera(&walled, &base, View::default());
    let tail = Settings { overflow: oit_core::Overflow::Tail, samples: 4, ..settings(32, "fabs:2") };
    for s in [
        base.clone(),
        Settings { technique: Technique::Dp, ..base.clone() },
        Settings { technique: Technique::Dp, fraction_coverage: true, ..base.clone() },
        tail,
        Settings { supersample: true, ..base.clone() },
    ] {
        let f = cpu
            .render(&walled, &walled_cam, &s)
            .unwrap_or_else(|e| panic!("{} over a wall: {e}", s.technique));
        checks::accounting(&f).unwrap_or_else(|e| panic!("{} over a wall: {e}", s.technique));
    }
    // the GPU backends' plans take the samples on either path (oit-vulkan's hardware path
    // refuses them where it starts a frame: `gpu_paths_equal_the_cpu_at_samples`)
    for backend in ["wgpu", "vulkan"] {
        let compute = Settings { raster: Some(oit_core::RasterPath::Compute), ..base.clone() };
        assert!(oit_core::plan::Plan::new(backend, &scene, &compute).is_ok(), "{backend} compute");
        // the supersampled reference, on either path (`gpu_supersampled_reference_equals_the_cpus`)
        for raster in [oit_core::RasterPath::Compute, oit_core::RasterPath::Hardware] {
            let s = Settings { supersample: true, raster: Some(raster), ..base.clone() };
            assert!(oit_core::plan::Plan::new(backend, &scene, &s).is_ok(), "{backend} {raster}");
        }
    }
    for samples in [0, 2, 3, 16] {
        let e = Settings { samples, ..base.clone() }.validate().unwrap_err().to_string();
        assert!(e.contains("1, 4 or 8"), "{e}");
    }
    assert!(Settings { supersample: true, ..settings(32, "reference") }.validate().is_err());
}

/// A multisampled frame tiled under `--memory` (each window's masked pass over its own pixels,
/// the boxes cut to the window) is the untiled frame, for the reference and the exact techniques.
#[test]
fn tiled_frames_equal_untiled_at_samples() {
    let scene = scene_of("bunny");
    let cpu = CpuBackend::default();
    for t in ["reference", "dfb", "ll", "fabs", "fabs:3"] {
        let s = Settings { samples: 4, ..settings(96, t) };
        let cam = camera(&scene, &s, View::default());
        let whole = render(&cpu, &scene, &cam, &s);
        let tiled = render(&cpu, &scene, &cam, &Settings { memory: Some(150 << 10), ..s.clone() });
        assert!(tiled.stats.tiles > 1, "{t}: {} tiles", tiled.stats.tiles);
        assert_eq!(whole.image, tiled.image, "{t}");
        assert_eq!(whole.stats.fragments, tiled.stats.fragments, "{t}");
    }
}

/// The storage a multisampled frame reports is the plan's, the coverage masks included (a byte
/// an entry), so the budget and the tiling forecast count them.
#[test]
fn storage_is_the_plans_with_the_masks() {
    let scene = scene_of("bunny");
    let cpu = CpuBackend::default();
    for t in ["reference", "dfb", "ll", "fabs", "fabs:3"] {
        let s = Settings { samples: 4, ..settings(64, t) };
        let cam = camera(&scene, &s, View::default());
        let f = render(&cpu, &scene, &cam, &s);
        let plan = oit_core::plan::Plan::new("cpu", &scene, &s).unwrap();
        let one = oit_core::plan::Plan::new("cpu", &scene, &Settings { samples: 1, ..s.clone() }).unwrap();
        let counted = oit_core::plan::Counted { deepest: f.stats.max_layers, fragments: f.stats.fragments };
        let pixels = s.pixel_count() as u64;
        let masks = plan.storage_bytes(pixels, counted) - one.storage_bytes(pixels, counted);
        assert!(masks > 0, "{t}");
        // (the resolve state, counted once in the plan's figure, is not in Stats::storage_bytes)
        let state = pixels * oit_core::plan::RESOLVE_STATE_BYTES;
        assert_eq!(f.stats.storage_bytes, plan.storage_bytes(pixels, counted) - state, "{t}");
    }
}

/// Issue 40's edge-error target: at 4 samples, `fabs:4`'s error pixel rate against the per-sample
/// reference is at most half the per-pixel-coverage baseline's (`--coverage pixel`, the same
/// fragments composited at full weight), on the bunny at 512². Both lose the same fragments past
/// 4 at the deep pixels; what per-sample coverage removes is the edge pixels' error. `dfb` holds
/// it with 0 error pixels against the baseline's many. (At 128² the bunny's triangles are smaller
/// than a pixel, nearly every fragment is an edge fragment, and `fabs:4` loses half of them
/// either way: docs/msaa.md.) Mutation: `coverage` always full (the baseline for both) fails it.
#[test]
fn per_sample_coverage_halves_the_edge_error() {
    let scene = scene_of("bunny");
    let cpu = CpuBackend::default();
    let s = Settings { samples: 4, ..settings(512, "reference") };
    let cam = camera(&scene, &s, View::default());
    let r = render(&cpu, &scene, &cam, &s);
    // (not fabs:2: at 2 slots a pixel the edge fragments of the front surface fill both, the back
    // surface is lost at every sample, and the baseline's doubled front layer happens to stand in
    // for it: 94.7 % against 65.3 % at 512², docs/msaa.md)
    for t in ["fabs:4", "dfb"] {
        let per_sample =
            render(&cpu, &scene, &cam, &Settings { technique: t.parse::<Technique>().unwrap(), ..s.clone() });
        let per_pixel = render(
            &cpu,
            &scene,
            &cam,
            &Settings { technique: t.parse::<Technique>().unwrap(), pixel_coverage: true, ..s.clone() },
        );
        let (a, b) = (accuracy(&r, &per_sample.image).unwrap(), accuracy(&r, &per_pixel.image).unwrap());
        assert!(a.is_measured() && b.is_measured(), "{t}");
        // the same fragments in both: the baseline differs only in what it composites
        assert_eq!(per_sample.stats.fragments, per_pixel.stats.fragments, "{t}");
        assert_eq!(per_sample.stats.lost, per_pixel.stats.lost, "{t}");
        assert!(b.error_pixels > 0, "{t}: the baseline shows no edge error");
        assert!(
            2 * a.error_pixels <= b.error_pixels,
            "{t}: EPR {:.4} per sample against {:.4} per pixel ({} / {} error pixels of {})",
            a.epr,
            b.epr,
            a.error_pixels,
            b.error_pixels,
            a.covered
        );
    }
}

/// Issue 40's memory target: the mask costs bits, not fragments. Bytes a captured fragment of
/// `ll` and `dfb` at 4 samples are at most 1.15× single-sample's on the bunny (a byte of mask
/// beside an `ll` node of 16 bytes and a `dfb` entry of 12; the per-pixel heads and offsets
/// spread over more fragments at 4 samples), and a fragment is one entry whatever its mask: the
/// storage grows with the fragments the samples add, never by a slot a sample. Mutation: the
/// masks in 32-bit words (the first slice's layout) fails it for `dfb` (16/12 = 1.33).
#[test]
fn masks_cost_bits_not_fragments() {
    let scene = scene_of("bunny");
    let cpu = CpuBackend::default();
    for t in ["ll", "dfb"] {
        let one = settings(256, t);
        let cam = camera(&scene, &one, View::default());
        let (a, b) = (
            render(&cpu, &scene, &cam, &one),
            render(&cpu, &scene, &cam, &Settings { samples: 4, ..one.clone() }),
        );
        assert!(b.stats.captured > a.stats.captured, "{t}: the samples add edge fragments");
        let per = |f: &Frame| f.stats.storage_bytes as f64 / f.stats.captured as f64;
        let ratio = per(&b) / per(&a);
        assert!(
            ratio <= 1.15,
            "{t}: {:.2} bytes a captured fragment at 4 samples against {:.2} at 1 ({ratio:.3}×; {} and {} fragments)",
            per(&b),
            per(&a),
            b.stats.captured,
            a.stats.captured
        );
    }
}

/// The GPU backends at several samples against oit-cpu. The compute paths at 4 and 8 samples (the same fixed-point
/// coverage masks, written once in WGSL): the same fragments, losses and passes, each pixel
/// within 1 of 8 bits, the plan's storage (the masks a byte an entry, in whole words), and the
/// exact techniques equal to the path's own per-sample reference; `fabs:2` overflowing, the
/// per-pixel coverage baseline and the other effects alike; a tiled frame equal to the whole.
/// The hardware paths: [`hardware_at_samples`]. Mutations caught (each tried): the
/// compute rasterizer's mask forced full (every pixel of the per-sample resolve off the CPU's
/// along the edges), the masks not swapped by the in-place sorts (dfb and the reference off).
#[test]
fn gpu_paths_equal_the_cpu_at_samples() {
    let cpu = CpuBackend::default();
    let gpus: Vec<_> = gpu_backends_for("gpu_paths_equal_the_cpu_at_samples");
    let mut compared = 0;
    for backend in &gpus {
        let on = label(backend.as_ref());
        let path = backend.raster_path(&Settings::default());
        if path == oit_core::RasterPath::Hardware {
            compared += hardware_at_samples(backend.as_ref(), &cpu);
            continue;
        }
        for (name, size, samples) in [("bunny", 64, 4), ("knot", 48, 8), ("planes:6", 40, 4)] {
            let scene = scene_of(name);
            let base = Settings { samples, ..settings(size, "reference") };
            let cam = camera(&scene, &base, View::default());
            let reference = render(backend.as_ref(), &scene, &cam, &base);
            let mut cases: Vec<Settings> = ["reference", "dfb", "ll", "fabs", "fabs:2"]
                .iter()
                .map(|t| Settings { technique: t.parse().unwrap(), ..base.clone() })
                .collect();
            cases.push(Settings { pixel_coverage: true, ..settings(size, "fabs:2") });
            cases.push(Settings { pixel_coverage: true, ..settings(size, "ll") });
            cases.push(Settings { overflow: oit_core::Overflow::Tail, ..settings(size, "fabs:2") });
            // the techniques that keep no mask: alpha weighted by coverage, and per pixel
            cases.extend(
                FRACTION_TECHNIQUES
                    .iter()
                    .map(|t| Settings { technique: t.parse().unwrap(), ..base.clone() }),
            );
            cases.push(Settings { pixel_coverage: true, ..settings(size, "wboit") });
            // dp and ddp per sample: under a peel limit, Fresnel, the heat map; and by coverage
            // fraction (`--coverage fraction`)
            for t in ["dp", "ddp", "mlp:2"] {
                cases.push(Settings { max_peels: Some(2), ..settings(size, t) });
                cases.push(Settings { effect: oit_core::Effect::Complexity, ..settings(size, t) });
                cases.push(Settings { fraction_coverage: true, ..settings(size, t) });
            }
            cases.push(Settings { effect: oit_core::Effect::Fresnel, ..settings(size, "dp") });
            // mlp:M per sample, M nearest layers a pass (several passes at M = 1 and 2)
            for t in ["mlp:1", "mlp:2", "mlp:4"] {
                cases.push(settings(size, t));
            }
            cases.push(Settings { effect: oit_core::Effect::Fresnel, ..settings(size, "mlp:4") });
            for effect in
                [oit_core::Effect::Translucency, oit_core::Effect::Fresnel, oit_core::Effect::Complexity]
            {
                cases.push(Settings { effect, ..settings(size, "dfb") });
            }
            for s in cases {
                let s = Settings { samples, ..s };
                let what = format!(
                    "{on}: {} on {name} at {samples}× ({:?}{})",
                    s.technique,
                    s.effect,
                    if s.pixel_coverage { ", per-pixel coverage" } else { "" }
                );
                let g = render(backend.as_ref(), &scene, &cam, &s);
                let c = render(&cpu, &scene, &cam, &s);
                checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
                checks::same_fragments_as_cpu(&g, &c, s.technique).unwrap_or_else(|e| panic!("{what}: {e}"));
                // (plain's storage is the path's: oit-cpu's banded pass keeps none, `Plan::on_path`)
                if s.technique != Technique::Plain {
                    checks::same_storage_as_cpu(backend.name(), &g, &c, &scene, &s)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                }
                let exact = matches!(
                    s.technique,
                    Technique::Dfb
                        | Technique::Ll
                        | Technique::Fabs { k: None }
                        | Technique::Dp
                        | Technique::Ddp
                        | Technique::Mlp { .. }
                ) && !s.fraction_coverage
                    && s.max_peels.is_none();
                if exact && s.effect == oit_core::Effect::Transparency && !s.pixel_coverage {
                    checks::exact(&reference, &g).unwrap_or_else(|e| panic!("{what}: {e}"));
                }
                compared += 1;
            }
        }
        // oit-vulkan's `--atomic-storage image`: fabs's counters in a storage image, the masks
        // beside them (binding 8, the image at 9), the same frame as oit-cpu's over buffers
        if backend.name() == "vulkan" {
            let scene = scene_of("bunny");
            for t in ["fabs", "fabs:2"] {
                let s = Settings { samples: 4, ..settings(64, t) };
                let cam = camera(&scene, &s, View::default());
                let image = Settings { atomic_storage: oit_core::AtomicStorage::Image, ..s.clone() };
                let g = render(backend.as_ref(), &scene, &cam, &image);
                let c = render(&cpu, &scene, &cam, &s);
                checks::same_fragments_as_cpu(&g, &c, s.technique)
                    .unwrap_or_else(|e| panic!("{on}: {t} with image atomics at 4×: {e}"));
                compared += 1;
            }
        }
        // a frame in screen tiles (`--memory`) equals the whole one
        let scene = scene_of("bunny");
        for t in ["reference", "fabs:3"] {
            let s = Settings { samples: 4, ..settings(96, t) };
            let cam = camera(&scene, &s, View::default());
            let whole = render(backend.as_ref(), &scene, &cam, &s);
            let tiled =
                render(backend.as_ref(), &scene, &cam, &Settings { memory: Some(200 << 10), ..s.clone() });
            assert!(tiled.stats.tiles > 1, "{on} {t}: {} tiles", tiled.stats.tiles);
            assert_eq!(
                (whole.image, whole.stats.fragments),
                (tiled.image, tiled.stats.fragments),
                "{on} {t}"
            );
        }
    }
    eprintln!("{compared} multisampled GPU frames compared with oit-cpu's");
}

/// The supersampled reference (`--supersample`) on the GPU backends' compute paths equals
/// oit-cpu's: oit-core's frames (one single-sample reference frame a sample position, under the
/// projection moved so that the position falls on the pixels' centres), their linear colours
/// added up on the device (`supersample.wgsl`): the same fragments, passes and per-pixel layer
/// counts (every sample's frame's), each pixel within 1 of 8 bits, on the bunny at 4 samples, the
/// knot at 8 under the headlight (shading that varies across a pixel) and `planes:6` under
/// translucency, and a tiled frame equal to the whole. It is not the per-sample reference: the
/// exact `dfb` equals the per-sample reference (EPR 0) and errs against the supersampled one on
/// the edge pixels (MSAA's own error, what `oit compare --supersample` reports), by as many
/// pixels as on oit-cpu. With opaque objects (the wall through the default scene) each sample's
/// frame draws its own opaque pass: `occluded`, the opaque fragments and the passes are oit-cpu's,
/// summed over the frames. The hardware paths' frames are compared off the snapped edges (and off
/// the lines where a surface crosses the wall) ([`hardware_supersampled`]). Mutations tried: the kernel's
/// sum of the earlier frames dropped (the last sample's frame alone, times n: "bunny at 4×: 802
/// pixels off the edges differ, by up to 86"); oit-wgpu's frames all under the unmoved camera
/// (shaded at the pixels' centres: "bunny at 4×: fragments: 9760 vs 9800").
#[test]
fn gpu_supersampled_reference_equals_the_cpus() {
    let cpu = CpuBackend::default();
    let gpus: Vec<_> = gpu_backends_for("gpu_supersampled_reference_equals_the_cpus");
    let mut compared = 0;
    for backend in &gpus {
        let on = label(backend.as_ref());
        let path = backend.raster_path(&Settings::default());
        let cases = [
            ("bunny", 64, 4, Settings::default().shading, oit_core::Effect::Transparency, View::default()),
            ("knot", 48, 8, Shading::Headlight, oit_core::Effect::Transparency, View::default()),
            ("planes:6", 40, 4, Settings::default().shading, oit_core::Effect::Translucency, View::default()),
            // opaque objects: an opaque pass in each sample's frame
            (WALLED[1], 48, 4, Settings::default().shading, oit_core::Effect::Transparency, oblique()),
            // triangles of a few pixels, shading that varies across a pixel: MSAA's own error
            // off the snapped edges too
            ("spheres:1", 64, 4, Shading::Headlight, oit_core::Effect::Transparency, View::default()),
        ];
        for (name, size, samples, shading, effect, view) in cases {
            let scene = scene_of(name);
            let s = Settings { samples, supersample: true, shading, effect, ..settings(size, "reference") };
            let cam = camera(&scene, &s, view);
            let what = format!("{on}: the supersampled reference of {name} at {samples}×");
            if path == oit_core::RasterPath::Hardware {
                // 8 samples where the device's count target takes none: the supersampled frames
                // take any count, the per-sample frames they are measured with do not; then at 4
                // (the knot under the headlight: MSAA's error off the edges too)
                let run = |s: &Settings| hardware_supersampled(backend.as_ref(), &cpu, &scene, &cam, s);
                compared += match run(&s) {
                    Ok(n) => n,
                    Err(why) if samples == 8 => {
                        eprintln!("{what}: {why}; at 4× instead");
                        run(&Settings { samples: 4, ..s.clone() })
                            .unwrap_or_else(|why| panic!("{what} (at 4×): {why}"))
                    }
                    Err(why) => panic!("{what}: {why}"),
                };
                continue;
            }
            let g = render(backend.as_ref(), &scene, &cam, &s);
            let c = render(&cpu, &scene, &cam, &s);
            checks::same_fragments_as_cpu(&g, &c, s.technique).unwrap_or_else(|e| panic!("{what}: {e}"));
            checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(
                (g.stats.occluded, g.stats.opaque_fragments, g.stats.masked),
                (c.stats.occluded, c.stats.opaque_fragments, c.stats.masked),
                "{what}: occluded, opaque, masked"
            );
            // a counting pass and a fill a sample's frame, and two opaque passes where it has some
            let opaque = if scene.has_opaque() { 2 } else { 0 };
            assert_eq!(g.stats.geometry_passes, (2 + opaque) * samples, "{what}: passes");
            if scene.has_opaque() {
                assert!(g.stats.occluded > 0, "{what}: the wall holds fragments back");
            }
            // MSAA's own error: the exact dfb against the per-sample reference and against this
            let msaa = render(backend.as_ref(), &scene, &cam, &Settings { supersample: false, ..s.clone() });
            let dfb = Settings { technique: Technique::Dfb, supersample: false, ..s.clone() };
            let (gd, cd) = (render(backend.as_ref(), &scene, &cam, &dfb), render(&cpu, &scene, &cam, &dfb));
            assert_eq!(accuracy(&msaa, &gd.image).unwrap().error_pixels, 0, "{what}: dfb per sample");
            let (ge, ce) = (accuracy(&g, &gd.image).unwrap(), accuracy(&c, &cd.image).unwrap());
            eprintln!(
                "{what}: dfb against it: {} error pixels (oit-cpu: {})",
                ge.error_pixels, ce.error_pixels
            );
            if effect == oit_core::Effect::Transparency {
                // (translucency's flat colours absorb alike at every sample of a quad: equal there)
                assert!(ge.error_pixels > 0, "{what}: MSAA is not supersampling");
            }
            assert_eq!(ge.error_pixels, ce.error_pixels, "{what}: MSAA's error against it, GPU and CPU");
            compared += 1;
        }
        if path == oit_core::RasterPath::Compute {
            // a frame in screen tiles (`--memory`): each tile's frames under the full frame's moves
            let scene = scene_of("bunny");
            let s = Settings { samples: 4, supersample: true, ..settings(96, "reference") };
            let cam = camera(&scene, &s, View::default());
            let whole = render(backend.as_ref(), &scene, &cam, &s);
            let tiled =
                render(backend.as_ref(), &scene, &cam, &Settings { memory: Some(200 << 10), ..s.clone() });
            assert!(tiled.stats.tiles > 1, "{on}: {} tiles", tiled.stats.tiles);
            assert_eq!((whole.image, whole.stats.fragments), (tiled.image, tiled.stats.fragments), "{on}");
        }
    }
    eprintln!("{compared} supersampled GPU frames compared with oit-cpu's");
}

/// The supersampled reference on a GPU hardware path against oit-cpu's: the same frames, one a
/// sample position under the moved projection, each the hardware path's own single-sample
/// reference frame, but the device snaps the moved vertices in its own precision, so they are
/// compared as [`hardware_at_samples`] compares the MSAA frames, off the snapped edges: on the
/// pixels none of whose samples lies within a snap ([`checks::COVERAGE_SNAP`]) of a projected
/// edge (each sample's frame's edge mask under its moved camera, the union of the frames'), the
/// per-pixel fragment counts equal ([`checks::covered_alike_equal`]: the most fragments one
/// sample's frame gave the pixel) and each pixel within 1 of 8 bits. The passes are a counting
/// pass and a fill a sample's frame, and the exact `dfb` on the same path, which equals the
/// path's per-sample reference, errs against it on as many of those pixels as on oit-cpu (MSAA's
/// own error off the snapped edges; on these scenes it lies on the edges, 0 and 0). Returns the
/// frames compared, or why the path does not draw the per-sample frames at this count. Mutation
/// tried: the hardware path's frames all under the unmoved camera ("planes:6 at 4×: 175 pixels'
/// fragment counts differ"; the centre's mask widened by the samples' reach, 0.62 pixel, which
/// leaves out the silhouettes, let it pass).
fn hardware_supersampled(
    backend: &dyn Backend,
    cpu: &CpuBackend,
    scene: &oit_core::Scene,
    cam: &oit_core::Camera,
    s: &Settings,
) -> Result<usize, String> {
    let msaa = match backend.render(scene, cam, &Settings { supersample: false, ..s.clone() }) {
        Ok(f) => f,
        Err(OitError::Unsupported { what, .. }) => return Err(what),
        Err(e) => panic!("{e}"),
    };
    let g = render(backend, scene, cam, s);
    let c = render(cpu, scene, cam, s);
    checks::accounting(&g)?;
    // a counting pass and a fill a sample's frame, after its opaque pass's two where it has one
    let per_frame = if scene.has_opaque() { 4 } else { 2 };
    if g.stats.geometry_passes != per_frame * s.samples {
        return Err(format!(
            "{} passes, not {per_frame} a sample's frame (its opaque pass's, a counting pass and a fill)",
            g.stats.geometry_passes
        ));
    }
    // the pixels one of whose samples lies within a snap of a projected edge: each sample's
    // frame's edge mask under its moved camera (its centres are that sample's positions), the
    // union of the frames'. (Tighter than the centre's mask widened by the samples' reach, which
    // leaves out every silhouette pixel and so cannot tell a frame whose projection did not move.)
    let (_, moved_cameras) = oit_core::msaa::supersample_frames(cam, s);
    let mut near = vec![false; s.pixel_count()];
    for moved in &moved_cameras {
        let mask = oit_core::metrics::edge_mask(scene, moved, s.width, s.height, checks::COVERAGE_SNAP);
        near.iter_mut().zip(mask).for_each(|(n, m)| *n |= m);
        // and where a surface crosses an opaque one: there the device's depth may fall either side
        let crossings =
            oit_core::metrics::crossing_mask(scene, moved, s.width, s.height, checks::COVERAGE_SNAP);
        near.iter_mut().zip(crossings).for_each(|(n, m)| *n |= m);
    }
    let (gl, cl) = (g.layers.clone().expect("counts"), c.layers.clone().expect("counts"));
    let (alike, moved) = checks::covered_alike_equal(&g.image, &c.image, &gl, &cl, &near)?;
    if alike < 300 {
        return Err(format!("{alike} pixels compared"));
    }
    // MSAA's own error off the snapped edges: dfb per sample, against the supersampled reference
    let dfb = Settings { technique: Technique::Dfb, supersample: false, ..s.clone() };
    let (gd, cd) = (render(backend, scene, cam, &dfb), render(cpu, scene, cam, &dfb));
    checks::exact(&msaa, &gd)?;
    let off = |a: &oit_core::Image, b: &oit_core::Image| {
        (0..near.len()).filter(|&i| !near[i] && diff(a.pixels[i], b.pixels[i]) > 1).count()
    };
    let (ge, ce) = (off(&g.image, &gd.image), off(&c.image, &cd.image));
    eprintln!(
        "{}: the supersampled reference of {} at {}×: {alike} pixels compared ({moved} near an edge \
         counted otherwise); dfb against it off the edges: {ge} error pixels (oit-cpu: {ce}; in all {}, oit-cpu {})",
        label(backend),
        scene.name,
        s.samples,
        accuracy(&g, &gd.image).unwrap().error_pixels,
        accuracy(&c, &cd.image).unwrap().error_pixels
    );
    if ge != ce {
        return Err(format!("dfb against it off the edges: {ge} error pixels, on oit-cpu {ce}"));
    }
    Ok(1)
}

/// A GPU hardware path at 4 and 8 samples against oit-cpu: a multisampled pass reading each
/// fragment's mask from `sample_mask` (the device's standard positions); 8 samples refused by
/// name where the device's count target takes none. The
/// device's rasterizer has its own snapping, so the frames are compared on the pixels both cover
/// alike ([`checks::covered_alike_equal`]), with every pixel one of whose samples lies within a
/// snap of an edge left out (the centre within [`checks::COVERAGE_SNAP`] and the samples' reach,
/// 0.65 pixel); the exact techniques equal the path's own per-sample reference. (The seam test
/// holds the hardware masks along the shared edges.) Returns the frames compared.
fn hardware_at_samples(backend: &dyn Backend, cpu: &CpuBackend) -> usize {
    let on = label(backend);
    let mut compared = 0;
    for (name, samples) in [("bunny", 4), ("knot", 4), ("knot", 8)] {
        let scene = scene_of(name);
        let base = Settings { samples, ..settings(64, "reference") };
        let cam = camera(&scene, &base, View::default());
        let reference = match backend.render(&scene, &cam, &base) {
            Ok(f) => f,
            // 8 samples where the device's count target takes none; the standard locations
            Err(OitError::Unsupported { what, .. })
                if samples == 8 || what.contains("standardSampleLocations") =>
            {
                eprintln!("{on} at {samples}×: {what}");
                continue;
            }
            Err(e) => panic!("{on} at {samples}×: {e}"),
        };
        let cpu_reference = render(cpu, &scene, &cam, &base);
        let near = oit_core::metrics::edge_mask(&scene, &cam, 64, 64, checks::COVERAGE_SNAP + 0.65);
        let (hl, cl) =
            (reference.layers.clone().expect("counts"), cpu_reference.layers.clone().expect("counts"));
        let cases = [
            Settings { technique: Technique::Reference, ..base.clone() },
            Settings { technique: Technique::Dfb, ..base.clone() },
            Settings { technique: Technique::Ll, ..base.clone() },
            Settings { technique: Technique::Fabs { k: None }, ..base.clone() },
            Settings { technique: Technique::Fabs { k: Some(2) }, ..base.clone() },
            Settings { technique: Technique::Ll, pixel_coverage: true, ..base.clone() },
            Settings {
                technique: Technique::Fabs { k: Some(2) },
                overflow: oit_core::Overflow::Tail,
                ..base.clone()
            },
            // dp and ddp per sample, and by coverage fraction
            Settings { technique: Technique::Dp, ..base.clone() },
            Settings { technique: Technique::Ddp, ..base.clone() },
            Settings { technique: Technique::Dp, max_peels: Some(2), ..base.clone() },
            Settings { technique: Technique::Ddp, fraction_coverage: true, ..base.clone() },
            // mlp:M per sample (M = 1 and 2: several passes), under a peel limit, by coverage fraction
            Settings { technique: Technique::Mlp { m: 1 }, ..base.clone() },
            Settings { technique: Technique::Mlp { m: 2 }, ..base.clone() },
            Settings { technique: Technique::Mlp { m: 4 }, ..base.clone() },
            Settings { technique: Technique::Mlp { m: 2 }, max_peels: Some(2), ..base.clone() },
            Settings { technique: Technique::Mlp { m: 4 }, fraction_coverage: true, ..base.clone() },
            // the techniques that keep no mask (alpha weighted by coverage; plain's blender is refused)
            Settings { technique: Technique::WeightedAverage, ..base.clone() },
            Settings { technique: Technique::Mboit { m: 4 }, ..base.clone() },
            Settings { technique: Technique::Adp, ..base.clone() },
            Settings { technique: "mdts:4".parse().unwrap(), ..base.clone() },
            Settings { technique: Technique::Wboit, pixel_coverage: true, ..base.clone() },
        ];
        for s in cases {
            let what = format!(
                "{on}: {} on {name} at {samples}×{}",
                s.technique,
                if s.pixel_coverage { " (per-pixel coverage)" } else { "" }
            );
            let h = render(backend, &scene, &cam, &s);
            let c = render(cpu, &scene, &cam, &s);
            checks::accounting(&h).unwrap_or_else(|e| panic!("{what}: {e}"));
            let (alike, _) = checks::covered_alike_equal(&h.image, &c.image, &hl, &cl, &near)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            assert!(alike > 500, "{what}: {alike} pixels compared");
            let exact = matches!(
                s.technique,
                Technique::Dfb
                    | Technique::Ll
                    | Technique::Fabs { k: None }
                    | Technique::Dp
                    | Technique::Ddp
                    | Technique::Mlp { .. }
            ) && !s.fraction_coverage
                && s.max_peels.is_none();
            if exact && !s.pixel_coverage {
                checks::exact(&reference, &h).unwrap_or_else(|e| panic!("{what}: {e}"));
            }
            compared += 1;
        }
    }
    compared
}

/// The hardware paths' own captures at several samples (docs/msaa.md, "The blend captures at
/// several samples"), on each GPU backend's hardware path at 4 samples (8 where the device has
/// 8-sample targets, else skipped with its reason):
///
/// - `wavg`, `wsum` and `bdp` (`--hardware-capture blend`: additive and MAX blending, each
///   fragment written at one of its samples, the samples combined by the blend's own operator):
///   the same image as the atomics capture of the same path, bit for bit (the same device
///   fragments and masks, so no snapping to step around: the integer sums are exact in any order,
///   MAX is MAX), with the same fragments, captured and coverage; so they are the coverage
///   fraction the compute paths and oit-cpu take (`hardware_at_samples` holds the atomics
///   capture to oit-cpu off the snapped edges). `wavg` under `--coverage pixel` alike.
/// - `plain` (its blender composites each sample, `coverage: sample`): on `planes:6` seen from
///   behind, where every sample's fragments come in primitive order back to front, equal to the
///   path's own per-sample reference (the MSAA target) within 1 of 8 bits on every pixel (the
///   blender's f32 over operator back to front against the reference's f64 front to back), the
///   edges and the quads' shared diagonals included, and its count (split over the samples)
///   equal to the fragments. Against oit-cpu's `plain`, which weighs each fragment by its
///   coverage fraction over the whole pixel, it differs only where several fragments of one pixel
///   cover some of its samples each: measured on the bunny, and held below the seam that
///   per-pixel coverage leaves (`plain --coverage pixel` against the fraction on oit-cpu), the
///   error both coverage-aware forms remove. Over an opaque wall (`wall:0.5:planes:16` seen from
///   behind, the wall's edges crossing the planes) each sample's blend is cut at its opaque depth
///   and put over its own opaque colour: the per-sample reference within the same 1 of 8 bits,
///   with its fragments and captured counts and something occluded.
/// - `dp` and `ddp` (`--hardware-capture blend`: each sample peels its own layers, into
///   multisampled depth and layer targets, or its own pairs, through multisampled range targets):
///   the per-sample reference exactly (EPR 0, nothing lost) on the bunny and on the wall through
///   `planes:16`, with the atomics capture's fragments, captured and occluded, and the plan's
///   storage. (8 samples where the device's targets take them: lavapipe's take 4.)
///
/// Mutations tried (on wgpu, each failing this test): the weighted blend writing every kept
/// sample instead of the first (the frame's own accounting refuses it: its count 34 fragments
/// over), `hw_blend_packed` without the coverage weight (`wavg`: 1236 pixels off the atomics
/// capture), the bdp resolve taking sample 0 only instead of the MAX over the samples (`bdp`'s
/// captured off the atomics capture's), the plain resolve's mean taken of sample 0 alone (`plain`
/// 79 levels off the reference on the planes' edges). A first version that weighed plain's
/// alpha by its coverage as well was off by 37 levels there. Over opaque objects (wgpu): plain's
/// resolve putting each sample over the samples' mean opaque colour (`background_at`) instead of
/// its own (5 levels off the reference over the wall); dp's peel reading the previous depth of
/// sample 0 for every sample (its accounting refuses it: 11253 captured of 9766 fragments on the
/// bunny), its composite counting a fragment at every sample it is peeled (9800 captured of
/// 9766), and its composite putting each sample's layer into every sample the fragment keeps
/// (24 pixels off the reference on the bunny); ddp's resolve putting each sample's far layer into
/// its front instead of its back (46 pixels off), its hand-overs counted at every sample (9800
/// captured of 9766), its peel reading the previous range of sample 0 for every sample (its
/// captured off the atomics capture's).
#[test]
fn hardware_blend_captures_at_samples() {
    use oit_core::HardwareCapture;
    let cpu = CpuBackend::default();
    let mut compared = 0;
    for backend in gpu_backends_for("hardware_blend_captures_at_samples") {
        let backend = backend.as_ref();
        if backend.raster_path(&Settings::default()) != oit_core::RasterPath::Hardware {
            continue;
        }
        let on = label(backend);
        'samples: for samples in [4, 8] {
            let scene = scene_of("bunny");
            let base = Settings { samples, hardware_capture: HardwareCapture::Blend, ..settings(64, "wavg") };
            let cam = camera(&scene, &base, View::default());
            let cases = [
                Settings { technique: Technique::WeightedAverage, ..base.clone() },
                Settings { technique: Technique::WeightedSum, ..base.clone() },
                Settings { technique: "bdp".parse().unwrap(), ..base.clone() },
                Settings { technique: Technique::WeightedAverage, pixel_coverage: true, ..base.clone() },
            ];
            for s in cases {
                let what = format!(
                    "{on}: {} blend at {samples}×{}",
                    s.technique,
                    if s.pixel_coverage { " (pixel)" } else { "" }
                );
                let blend = match backend.render(&scene, &cam, &s) {
                    Ok(f) => f,
                    Err(OitError::Unsupported { what: why, .. }) if samples == 8 => {
                        eprintln!("{what}: {why}");
                        continue 'samples;
                    }
                    Err(e) => panic!("{what}: {e}"),
                };
                let atomics = render(
                    backend,
                    &scene,
                    &cam,
                    &Settings { hardware_capture: HardwareCapture::Atomics, ..s.clone() },
                );
                checks::accounting(&blend).unwrap_or_else(|e| panic!("{what}: {e}"));
                blend_storage_is_the_plans(backend, &scene, &s, &blend)
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(blend.stats.fragments, atomics.stats.fragments, "{what}");
                assert_eq!(blend.stats.captured, atomics.stats.captured, "{what}");
                assert_eq!(blend.stats.coverage, atomics.stats.coverage, "{what}");
                assert!(blend.stats.coverage.is_some(), "{what}");
                let differ =
                    blend.image.pixels.iter().zip(&atomics.image.pixels).filter(|(a, b)| a != b).count();
                assert_eq!(differ, 0, "{what}: {differ} pixels off the atomics capture");
                compared += 1;
            }

            // over an opaque wall: each fragment at its first sample in front of the wall, the
            // samples' sums over the mean of their opaque colours, as the atomics capture's
            let walled = scene_of("wall:0.5:planes:16");
            let wall_cam = camera(&walled, &base, View::default());
            for t in ["wavg", "wsum", "bdp"] {
                let s = Settings { technique: t.parse().unwrap(), ..base.clone() };
                let what = format!("{on}: {t} blend over a wall at {samples}×");
                let blend = render(backend, &walled, &wall_cam, &s);
                let atomics = render(
                    backend,
                    &walled,
                    &wall_cam,
                    &Settings { hardware_capture: HardwareCapture::Atomics, ..s.clone() },
                );
                checks::accounting(&blend).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert!(blend.stats.occluded > 0, "{what}: the wall holds back nothing");
                assert_eq!(
                    (blend.stats.fragments, blend.stats.captured, blend.stats.occluded),
                    (atomics.stats.fragments, atomics.stats.captured, atomics.stats.occluded),
                    "{what}"
                );
                let differ =
                    blend.image.pixels.iter().zip(&atomics.image.pixels).filter(|(a, b)| a != b).count();
                assert_eq!(differ, 0, "{what}: {differ} pixels off the atomics capture");
                compared += 1;
            }

            // dp's depth peel and ddp's dual peel a sample: the per-sample reference exactly (EPR
            // 0), through the bunny and over the wall, with the atomics capture's fragments,
            // captured and occluded
            let peels = [Technique::Dp, Technique::Ddp];
            for (name, t) in ["bunny", "wall:0.5:planes:16"].into_iter().flat_map(|n| peels.map(|t| (n, t))) {
                let peeled = scene_of(name);
                let s = Settings { technique: t, ..base.clone() };
                let cam = camera(&peeled, &s, View::default());
                let what = format!("{on}: {t} blend on {name} at {samples}×");
                let blend = match backend.render(&peeled, &cam, &s) {
                    Ok(f) => f,
                    // 8 samples where the device's range or layer target takes none (the H200
                    // has no 8-sample Rg32Float target); the refusal names the compute path
                    Err(OitError::Unsupported { what: why, .. })
                        if samples == 8 && why.contains("8-sample") && why.contains("--raster compute") =>
                    {
                        eprintln!("{what}: {why}");
                        continue;
                    }
                    Err(e) => panic!("{what}: {e}"),
                };
                let atomics = render(
                    backend,
                    &peeled,
                    &cam,
                    &Settings { hardware_capture: HardwareCapture::Atomics, ..s.clone() },
                );
                let reference = render(
                    backend,
                    &peeled,
                    &cam,
                    &Settings { technique: Technique::Reference, ..s.clone() },
                );
                checks::accounting(&blend).unwrap_or_else(|e| panic!("{what}: {e}"));
                blend_storage_is_the_plans(backend, &peeled, &s, &blend)
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(blend.stats.coverage, Some(Coverage::Sample), "{what}");
                assert_eq!(
                    (blend.stats.fragments, blend.stats.captured, blend.stats.occluded),
                    (atomics.stats.fragments, atomics.stats.captured, atomics.stats.occluded),
                    "{what}"
                );
                assert_eq!(blend.stats.occluded > 0, peeled.has_opaque(), "{what}: occluded");
                checks::exact(&reference, &blend).unwrap_or_else(|e| panic!("{what}: {e}"));
                compared += 1;
            }

            // plain: per sample, equal to the per-sample reference where primitive order is depth order
            let planes = scene_of("planes:6");
            let p = Settings { samples, ..settings(64, "plain") };
            let behind = camera(&planes, &p, View { azimuth: 200.0, elevation: 25.0, ..View::default() });
            let what = format!("{on}: plain on planes:6 from behind at {samples}×");
            let plain = render(backend, &planes, &behind, &p);
            let reference =
                render(backend, &planes, &behind, &Settings { technique: Technique::Reference, ..p.clone() });
            checks::accounting(&plain).unwrap_or_else(|e| panic!("{what}: {e}"));
            blend_storage_is_the_plans(backend, &planes, &p, &plain)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(plain.stats.coverage, Some(Coverage::Sample), "{what}");
            assert_eq!(plain.stats.fragments, reference.stats.fragments, "{what}");
            assert_eq!(plain.stats.captured, reference.stats.captured, "{what}");
            let worst =
                plain.image.pixels.iter().zip(&reference.image.pixels).map(|(&a, &b)| diff(a, b)).max();
            assert!(worst <= Some(1), "{what}: {worst:?} levels off the per-sample reference");
            // over an opaque wall: each sample's blend cut at that sample's opaque depth and put
            // over that sample's opaque colour, the per-sample reference's within the same level
            // (the wall through the middle of the planes, their submission order depth order from
            // behind; its edges cross the planes)
            let walled = scene_of("wall:0.5:planes:16");
            let behind_wall =
                camera(&walled, &p, View { azimuth: 200.0, elevation: 25.0, ..View::default() });
            let over_what = format!("{on}: plain over wall:0.5:planes:16 from behind at {samples}×");
            let over = render(backend, &walled, &behind_wall, &p);
            let walled_reference = render(
                backend,
                &walled,
                &behind_wall,
                &Settings { technique: Technique::Reference, ..p.clone() },
            );
            checks::accounting(&over).unwrap_or_else(|e| panic!("{over_what}: {e}"));
            blend_storage_is_the_plans(backend, &walled, &p, &over)
                .unwrap_or_else(|e| panic!("{over_what}: {e}"));
            assert!(over.stats.occluded > 0, "{over_what}: the wall holds back nothing");
            assert_eq!(over.stats.coverage, Some(Coverage::Sample), "{over_what}");
            assert_eq!(
                (over.stats.fragments, over.stats.captured),
                (walled_reference.stats.fragments, walled_reference.stats.captured),
                "{over_what}"
            );
            let worst =
                over.image.pixels.iter().zip(&walled_reference.image.pixels).map(|(&a, &b)| diff(a, b)).max();
            // (the wall's edge pixels, where the samples' opaque colours differ: what the mean of
            // the samples' composites over one colour would miss)
            let walled_fraction = render(&cpu, &walled, &behind_wall, &p);
            eprintln!(
                "{over_what}: {worst:?} levels off the per-sample reference at worst; mean error {:.4} (oit-cpu's fraction {:.4})",
                mean_error(&walled_reference.image, &over.image),
                mean_error(&walled_reference.image, &walled_fraction.image)
            );
            assert!(worst <= Some(1), "{over_what}: {worst:?} levels off the per-sample reference");

            // the planes' edges at partial coverage, overlapping: where the fraction differs
            let cpu_plain = render(&cpu, &planes, &behind, &p);
            let fraction_error = mean_error(&reference.image, &cpu_plain.image);
            eprintln!(
                "{what}: mean error of oit-cpu's fraction {fraction_error:.4}, of the blender's samples {:.4}",
                mean_error(&reference.image, &plain.image)
            );

            // the bunny: against oit-cpu's fraction, bounded by per-pixel coverage's seam
            let p = Settings { samples, ..settings(96, "plain") };
            let cam = camera(&scene, &p, View::default());
            let plain = render(backend, &scene, &cam, &p);
            assert_eq!(plain.stats.coverage, Some(Coverage::Sample), "{on}");
            let fraction = render(&cpu, &scene, &cam, &p);
            let pixel = render(&cpu, &scene, &cam, &Settings { pixel_coverage: true, ..p.clone() });
            let reference =
                render(&cpu, &scene, &cam, &Settings { technique: Technique::Reference, ..p.clone() });
            let (apart, seam) =
                (mean_error(&plain.image, &fraction.image), mean_error(&pixel.image, &fraction.image));
            eprintln!(
                "{on}: plain on the bunny at {samples}×: per sample against the fraction {apart:.4} (mean 8-bit levels a pixel), \
                 per-pixel coverage against it {seam:.4}; against the per-sample reference: per sample {:.4}, fraction {:.4}, pixel {:.4}",
                mean_error(&plain.image, &reference.image),
                mean_error(&fraction.image, &reference.image),
                mean_error(&pixel.image, &reference.image)
            );
            assert!(
                apart > 0.0 && apart < seam,
                "{on}: plain per sample {apart:.4} off the fraction, the seam {seam:.4}"
            );
            compared += 1;
        }
    }
    eprintln!("{compared} blend captures at several samples compared");
}

/// A hardware path's own capture at several samples (`backend`, `settings` on `scene`): the
/// storage its `frame` reports, its multisampled targets each sample counted, is the plan's
/// (`Plan::blend_targets`: the arrays the budget and `--memory`'s tiles count; the resolve state,
/// counted once in the plan's figure, is not in `Stats::storage_bytes`). Mutation tried: the
/// plan counting the targets a pixel, as it did (fails: the frame's storage is 4 or 8 times the
/// plan's targets).
fn blend_storage_is_the_plans(
    backend: &dyn Backend,
    scene: &oit_core::Scene,
    settings: &Settings,
    frame: &Frame,
) -> Result<(), String> {
    use oit_core::plan::{Counted, Plan, RESOLVE_STATE_BYTES};
    // (the backend runs it on its path: `Settings::raster` named, as oit-core's `OnPath` names it)
    let s = Settings { raster: Some(backend.raster_path(settings)), ..settings.clone() };
    let plan = Plan::new(backend.name(), scene, &s).map_err(|e| e.to_string())?;
    // (the colour target's bytes a sample: RGBA32F's; dp's (payload, mask) layer, two u32;
    // ddp's range, two f32)
    let colour = if matches!(s.technique, Technique::Dp | Technique::Ddp) { 8 } else { 16 };
    if plan.blend_targets != Some((s.samples, colour)) {
        return Err(format!("the plan's blend targets: {:?}", plan.blend_targets));
    }
    let pixels = s.pixel_count() as u64;
    let planned = plan.storage_bytes(pixels, Counted::default()) - pixels * RESOLVE_STATE_BYTES;
    if frame.stats.storage_bytes != planned {
        return Err(format!("storage {} bytes, the plan's {planned}", frame.stats.storage_bytes));
    }
    Ok(())
}

/// The techniques that keep no coverage mask, at `--samples 4` on oit-cpu: each fragment over the
/// whole pixel with its alpha weighted by its coverage fraction ([`oit_core::msaa::Coverage`]).
/// (dp, ddp and mlp peel per sample: `peels_per_sample_equal_the_reference`.)
const FRACTION_TECHNIQUES: [&str; 9] =
    ["wavg", "wsum", "wboit", "mboit", "bdp", "adp", "mdts", "mdts64", "plain"];

/// Mean absolute difference of two images, in 8-bit levels a pixel (the largest channel's).
fn mean_error(a: &oit_core::Image, b: &oit_core::Image) -> f64 {
    let sum: u64 = a.pixels.iter().zip(&b.pixels).map(|(&p, &q)| u64::from(diff(p, q))).sum();
    sum as f64 / a.pixels.len() as f64
}

/// Issue 40 item 2 for the techniques without room for a mask: at 4 samples each composites a
/// fragment over its whole pixel, its alpha weighted by the fraction of the pixel's samples it
/// covers (`coverage: fraction` in the frame's stats), which errs less than compositing it at full
/// alpha (`--coverage pixel`) against the per-sample reference, on the bunny, on a tessellated
/// sphere and over opaque objects (the wall through `planes:16` and through the default scene,
/// the fraction that of the samples in front of each sample's opaque depth, the same fragments
/// `occluded` as the per-sample reference's; [`techniques_without_masks_over_an_opaque_edge`]
/// holds the opaque edge itself; the choice between fraction and pixel is made on the meshes,
/// and over the walls the fraction, where it is the default, errs less too; bdp's colour mode
/// keeps its choice, per pixel, which errs less through the default scene and more through the
/// planes, whose quads split few edges). The bound, in mean 8-bit levels a pixel: no more than the technique's own error at one
/// sample against the one-sample reference (what its approximation costs without the samples)
/// plus the coverage error of an exact technique composited per pixel (`dfb --coverage pixel`
/// against the per-sample reference: what MSAA's edge fragments cost a technique that ignores the
/// mask) — the two errors a technique that keeps no mask adds to the per-sample reference, by the
/// triangle inequality where the two add independently; a technique below it loses no more at the
/// edges than per-pixel capture does. Mutation tried: the alpha weight dropped in oit-cpu's
/// covered walk (every fragment at full alpha: "dp on bunny: the choice 12.6825 against 12.6825",
/// when dp was among them; dp and ddp now peel per sample: `peels_per_sample_equal_the_reference`).
#[test]
fn techniques_without_masks_weigh_alpha_by_coverage() {
    let cpu = CpuBackend::default();
    let cases = [
        ("bunny", 160, None, View::default()),
        ("spheres:1", 64, Some(0.4), View::default()),
        // opaque objects: the wall through 16 planes and through the default scene, their coverage
        // cut at each sample's opaque depth, composited over the mean of the samples' colours (the
        // default scene at one alpha, as the others have: mdts's word keeps one alpha for every
        // fragment, an error of its own that grows with the fragments the samples add, not the
        // coverage's)
        (WALLED[0], 96, None, oblique()),
        (WALLED[1], 96, Some(0.4), oblique()),
    ];
    for (name, size, alpha, view) in cases {
        let scene = scene_of(name);
        let walled = scene.has_opaque();
        let one = Settings { alpha, shading: Shading::Flat, ..settings(size, "reference") };
        let four = Settings { samples: 4, ..one.clone() };
        let cam = camera(&scene, &one, view);
        let (r1, r4) = (render(&cpu, &scene, &cam, &one), render(&cpu, &scene, &cam, &four));
        let seam = mean_error(
            &r4.image,
            &render(
                &cpu,
                &scene,
                &cam,
                &Settings { technique: Technique::Dfb, pixel_coverage: true, ..four.clone() },
            )
            .image,
        );
        assert!(seam > 0.0, "{name}: per-pixel coverage shows no seam");
        for t in FRACTION_TECHNIQUES {
            let technique: Technique = t.parse().unwrap();
            let at = |s: &Settings| render(&cpu, &scene, &cam, &Settings { technique, ..s.clone() });
            let single = at(&one);
            let chosen = at(&four);
            let fraction = at(&Settings { fraction_coverage: true, ..four.clone() });
            let pixel = at(&Settings { pixel_coverage: true, ..four.clone() });
            assert_eq!(single.stats.coverage, None, "{t}");
            // mdts's 32-bit word keeps no alpha to weight: per pixel whatever is asked, and said
            let weighs = technique.kind() != oit_core::TechniqueKind::Mdts;
            let asked = if weighs { Coverage::Fraction } else { Coverage::Pixel };
            assert_eq!(fraction.stats.coverage, Some(asked), "{t}");
            assert_eq!(pixel.stats.coverage, Some(Coverage::Pixel), "{t}");
            // the multisampled fragments, the reference's, in each, and as many held back by the
            // opaque cut a sample
            for f in [&chosen, &fraction, &pixel] {
                assert_eq!(f.stats.fragments, r4.stats.fragments, "{t} on {name}");
                assert_eq!(f.stats.occluded, r4.stats.occluded, "{t} on {name}: occluded");
                checks::accounting(f).unwrap_or_else(|e| panic!("{t} on {name}: {e}"));
            }
            let own = mean_error(&r1.image, &single.image);
            let (f, p) = (mean_error(&r4.image, &fraction.image), mean_error(&r4.image, &pixel.image));
            let c = mean_error(&r4.image, &chosen.image);
            eprintln!(
                "{name} {t}: mean error at 4 samples {f:.4} (fraction), {p:.4} (pixel), {c:.4} chosen \
                 ({:?}); at 1 sample {own:.4}; per-pixel dfb {seam:.4}",
                chosen.stats.coverage
            );
            // the choice is the one that errs least (made on the meshes; over the walls, where
            // the fraction is the default, it errs less there too), and within the bound
            if weighs && !walled {
                let (best, worse) = if f <= p { (Coverage::Fraction, p) } else { (Coverage::Pixel, f) };
                assert_eq!(chosen.stats.coverage, Some(best), "{t} on {name}: fraction {f:.4}, pixel {p:.4}");
                assert!(c < worse, "{t} on {name}: the choice {c:.4} against {worse:.4}");
            } else if weighs {
                if chosen.stats.coverage == Some(Coverage::Fraction) {
                    assert!(f < p, "{t} on {name}: fraction {f:.4} against pixel {p:.4}");
                }
            } else {
                assert_eq!((&chosen.image, &fraction.image), (&pixel.image, &pixel.image), "{t} on {name}");
            }
            assert!(c <= own + seam, "{t} on {name}: {c:.4} over {own:.4} + {seam:.4}");
        }
    }
}

// The opaque pass at several samples (docs/msaa.md, "Opaque geometry at several samples").

/// The scenes with opaque parts the multisampled opaque pass is tested on: the wall through the
/// middle of 16 planes (about half their fragments behind it, its edges across the planes), through
/// the default scene (surfaces crossing it), and in front of everything (the frame shows the wall
/// and, beside its edges, the background).
const WALLED: [&str; 3] = ["wall:0.5:planes:16", "wall:0.4:default", "wall:0:planes:4"];

/// The view the walled scenes are seen from: turned 50° from the default, so that the wall (which
/// faces the default view and is as wide as the scene's bounding sphere) is seen obliquely and its
/// edges cross the frame.
fn oblique() -> View {
    View { azimuth: View::default().azimuth + 50.0, ..View::default() }
}

/// The fragments of `scene` under `s` by the plain rule, not through a rasterizer: every
/// (pixel, triangle) of each set-up triangle's box where `setup::sample_mask` is not empty, with
/// its mask and its depth at the pixel's centre (`DepthPlane` over `setup::centre_edges`).
fn plain_fragments(
    scene: &oit_core::Scene,
    cam: &oit_core::Camera,
    s: &Settings,
) -> Vec<(usize, u32, u8, f32)> {
    let setup = oit_core::setup::TriangleSetup::new(scene, cam, s);
    let mut out = Vec::new();
    for t in &setup.triangles {
        let plane = oit_core::setup::DepthPlane::new(t);
        let [x0, y0, x1, y1] = t.bbox;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let mask = oit_core::setup::sample_mask(t, x, y, s.samples);
                if mask != 0 {
                    let d = plane.depth(plane.barycentrics(oit_core::setup::centre_edges(t, x, y)));
                    out.push(((y * s.width + x) as usize, t.prim, mask, d));
                }
            }
        }
    }
    out
}

/// Each sample's nearest opaque key worked out by hand from the plain rule (sample `i` of pixel
/// `px` at `px · samples + i`): the smallest `depth bits << 32 | id` of the opaque fragments
/// whose mask covers it, `u64::MAX` where none does.
fn opaque_keys_by_hand(scene: &oit_core::Scene, cam: &oit_core::Camera, s: &Settings) -> Vec<u64> {
    let layers = scene.layers(s.alpha);
    let drawn = layers.settings(s);
    let n = s.samples as usize;
    let mut keys = vec![u64::MAX; s.pixel_count() * n];
    for (px, prim, mask, d) in plain_fragments(layers.opaque.as_ref().expect("an opaque part"), cam, &drawn) {
        let key = u64::from(oit_core::rules::depth_bits(d)) << 32 | u64::from(prim);
        for i in (0..n).filter(|i| mask >> i & 1 == 1) {
            keys[px * n + i] = keys[px * n + i].min(key);
        }
    }
    keys
}

/// The depth of an opaque key ([`opaque_keys_by_hand`]): infinite where none.
fn key_depth(k: u64) -> f32 {
    if k == u64::MAX { f32::INFINITY } else { f32::from_bits((k >> 32) as u32) }
}

/// What the multisampled opaque pass should leave, worked out by hand from the plain rule: each
/// sample's nearest opaque depth ([`opaque_keys_by_hand`]), the transparent fragments held back
/// (behind or at that depth at every sample they cover: `occluded`), the transparent fragments
/// drawn, and per pixel how many of its samples an opaque fragment covers.
fn opaque_by_hand(scene: &oit_core::Scene, cam: &oit_core::Camera, s: &Settings) -> (u64, u64, Vec<u32>) {
    let layers = scene.layers(s.alpha);
    let drawn = layers.settings(s);
    let n = s.samples as usize;
    let keys = opaque_keys_by_hand(scene, cam, s);
    let transparent = plain_fragments(&layers.transparent, cam, &drawn);
    let occluded = transparent
        .iter()
        .filter(|&&(px, _, mask, d)| (0..n).all(|i| mask >> i & 1 == 0 || d >= key_depth(keys[px * n + i])))
        .count() as u64;
    let covered = keys.chunks(n).map(|k| k.iter().filter(|&&k| k != u64::MAX).count() as u32).collect();
    (occluded, transparent.len() as u64, covered)
}

/// The opaque pass at 4 and 8 samples on oit-cpu: the opaque depth and colour kept a sample, each
/// transparent fragment's mask reduced to the samples it lies in front of. `occluded` is the
/// count worked out by hand ([`opaque_by_hand`]) and the accounting holds with it; the wall's
/// edges cut pixels (some have some but not all samples on the wall); `dfb`, `ll` and `fabs` equal
/// the per-sample reference; `fabs:2` keeps the accounting; the frame's storage is the plan's
/// (the opaque image at 20 bytes a sample); a tiled frame equals the whole one.
/// Mutations caught: the cut at each sample's depth replaced by sample 0's for every sample (the
/// opaque depth kept a pixel) fails `occluded` and the images; the mask not reduced (every covered
/// sample kept where any is in front) fails `occluded`'s count and the exactness.
#[test]
fn opaque_pass_at_samples_on_the_cpu() {
    let cpu = CpuBackend::default();
    for (name, samples) in [(WALLED[0], 4), (WALLED[1], 4), (WALLED[2], 4), (WALLED[0], 8)] {
        let scene = scene_of(name);
        let base = Settings { samples, ..settings(64, "reference") };
        let cam = camera(&scene, &base, oblique());
        let reference = render(&cpu, &scene, &cam, &base);
        let (occluded, fragments, covered) = opaque_by_hand(&scene, &cam, &base);
        let what = format!("{name} at {samples}×");
        assert_eq!(reference.stats.fragments, fragments, "{what}: fragments");
        assert_eq!(reference.stats.occluded, occluded, "{what}: occluded against the count by hand");
        assert!(occluded > 0, "{what}: the wall holds fragments back");
        let edge = covered.iter().filter(|&&c| c > 0 && c < samples).count();
        assert!(edge > 20, "{what}: {edge} pixels on the wall's edges");
        checks::accounting(&reference).unwrap_or_else(|e| panic!("{what}: {e}"));
        for t in ["dfb", "ll", "fabs", "fabs:2", "dp", "ddp", "mlp:1", "mlp:2", "mlp:4"] {
            let s = Settings { technique: t.parse().unwrap(), ..base.clone() };
            let f = render(&cpu, &scene, &cam, &s);
            let what = format!("{t} on {what}");
            checks::accounting(&f).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(f.stats.occluded, occluded, "{what}: occluded");
            if t != "fabs:2" {
                checks::exact(&reference, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
            }
            let plan = oit_core::plan::Plan::new("cpu", &scene, &s).unwrap();
            assert_eq!(plan.opaque_bytes(), 20 * u64::from(samples), "{what}");
            // dfb's entries are the fragments its counting pass let through the cut, ll's nodes
            // every fragment its sizing pass drew
            let fragments = match t {
                "dfb" => Some(f.stats.captured),
                "ll" => Some(f.stats.fragments),
                // the per-sample peels' arrays are per pixel
                _ if plan.sample_peel => Some(0),
                _ => None,
            };
            if let Some(fragments) = fragments {
                let counted = oit_core::plan::Counted { deepest: 0, fragments };
                let pixels = s.pixel_count() as u64;
                let state = pixels * oit_core::plan::RESOLVE_STATE_BYTES;
                assert_eq!(
                    f.stats.storage_bytes,
                    plan.storage_bytes(pixels, counted) - state,
                    "{what}: storage"
                );
            }
        }
        let tiled = render(
            &cpu,
            &scene,
            &cam,
            &Settings { memory: Some(200 << 10), technique: Technique::Dfb, ..base.clone() },
        );
        let whole = render(&cpu, &scene, &cam, &Settings { technique: Technique::Dfb, ..base.clone() });
        assert!(tiled.stats.tiles > 1, "{what}: {} tiles", tiled.stats.tiles);
        assert_eq!(
            (&whole.image, whole.stats.occluded),
            (&tiled.image, tiled.stats.occluded),
            "{what}: tiled"
        );
    }
    // at one sample the count by hand is the single-sample pass's (the same rule, one sample)
    let scene = scene_of(WALLED[0]);
    let one = settings(64, "reference");
    let cam = camera(&scene, &one, oblique());
    assert_eq!(render(&cpu, &scene, &cam, &one).stats.occluded, opaque_by_hand(&scene, &cam, &one).0);
}

/// The linear value of an sRGB8 level.
fn linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// The sRGB8 level of a linear value.
fn srgb(v: f32) -> u8 {
    let c = if v <= 0.0031308 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The wall's edge is antialiased: `wall:0.5:planes:4` at 4 samples seen obliquely, flat shaded,
/// the planes drawn at alpha 0 (`--alpha 0`: captured and cut as any, but compositing nothing, so
/// the background lies beside the wall everywhere). Each pixel of which the wall covers k of
/// the 4 samples (counted by hand, [`opaque_by_hand`]) is the mean of k samples of the wall's
/// colour and 4 − k of the background, within 2 levels of 8 bits (the wall's and the background's
/// linear colours are read back from 8-bit pixels, half a level each; the mean of the samples
/// rounds once more); at one sample an edge pixel would be all wall or all background, 1/4 of the
/// way from the nearer at least (many levels). Returns the edge pixels of each frame checked. On
/// oit-cpu and on every GPU path; a hardware path's rasterizer snaps on its own, so there a pixel
/// whose samples lie within a snap of the wall's edge may count one sample otherwise: it is held
/// to the bound on 90 % of the edge pixels, and none of them may be all one or the other where
/// the count by hand says 2 of 4. The supersampled reference (`--supersample`, on oit-cpu and the
/// compute paths), whose frames each draw the opaque pass at one sample under their moved
/// camera, antialiases the edge alike (held as the hardware paths, its frames snapping the moved
/// vertices anew).
/// Mutation caught: the opaque pass writing every sample of a pixel a fragment covers any of (the
/// opaque image kept a pixel) makes the edge all or nothing.
#[test]
fn the_opaque_edge_is_antialiased() {
    let scene = scene_of("wall:0.5:planes:4");
    let mut checked = 0;
    for backend in backends_for("the_opaque_edge_is_antialiased") {
        let on = label(backend.as_ref());
        let hardware = backend.raster_path(&Settings::default()) == oit_core::RasterPath::Hardware;
        let cases =
            [("reference", false), ("dfb", false), ("ll", false), ("fabs", false), ("reference", true)];
        // (the hardware paths' supersampled frames snap their moved edges in the device's own precision,
        // held to oit-cpu off those edges by `gpu_supersampled_reference_equals_the_cpus`)
        for (t, supersample) in cases.into_iter().filter(|&(_, ss)| !(ss && hardware)) {
            let s = Settings {
                samples: 4,
                shading: Shading::Flat,
                alpha: Some(0.0),
                supersample,
                ..settings(64, t)
            };
            let t = if supersample { "reference --supersample" } else { t };
            let cam = camera(&scene, &s, oblique());
            let (_, _, covered) = opaque_by_hand(&scene, &cam, &s);
            let f = render(backend.as_ref(), &scene, &cam, &s);
            checks::accounting(&f).unwrap_or_else(|e| panic!("{on} {t}: {e}"));
            let inside = covered.iter().position(|&c| c == 4).expect("a pixel all on the wall");
            let outside = covered.iter().position(|&c| c == 0).expect("a pixel beside the wall");
            let (wall, bg) = (f.image.pixels[inside], f.image.pixels[outside]);
            assert!(diff(wall, bg) > 40, "{on} {t}: the wall {wall:?} against the background {bg:?}");
            let (mut edge, mut within, mut halves) = (0, 0, 0);
            for (px, &k) in covered.iter().enumerate().filter(|(_, k)| (1..4).contains(*k)) {
                let w = k as f32 / 4.0;
                let expected: [u8; 4] = std::array::from_fn(|c| {
                    if c == 3 { 255 } else { srgb(w * linear(wall[c]) + (1.0 - w) * linear(bg[c])) }
                });
                let got = f.image.pixels[px];
                edge += 1;
                within += usize::from(diff(got, expected) <= 2);
                if k == 2 {
                    halves += 1;
                    assert!(
                        diff(got, wall) > 10 && diff(got, bg) > 10,
                        "{on} {t}: pixel {px}, half on the wall, is {got:?} (wall {wall:?}, beside {bg:?})"
                    );
                }
            }
            assert!(edge > 40 && halves > 5, "{on} {t}: {edge} edge pixels, {halves} halves");
            // (the supersampled reference's frames snap their moved vertices anew)
            let needed = if hardware || supersample { edge * 9 / 10 } else { edge };
            assert!(within >= needed, "{on} {t}: {within} of {edge} edge pixels the mean of their samples");
            checked += 1;
        }
    }
    assert!(checked >= 4);
}

/// The scene of [`techniques_without_masks_over_an_opaque_edge`]: one transparent quad
/// (`planes:1`) behind an opaque wall (`wall:0`: in front of everything), seen from [`beside`],
/// so that the quad shows beside one edge of the wall, which crosses the quad's interior.
const EDGE_SCENE: &str = "wall:0:planes:1";

/// What a technique that keeps no coverage mask composites at several samples over opaque
/// objects (docs/msaa.md, "The techniques without a mask over opaque objects"), held to its
/// definition on the edge of an opaque wall in front of one transparent quad ([`EDGE_SCENE`] seen
/// from [`beside`], flat shaded, the quad at alpha α = 0.4, 4 and 8 samples), on every path: each fragment over
/// the pixel's **mean opaque colour** B̄ (the mean of its samples' opaque colours, the background
/// where none covers a sample), its alpha times the fraction f of the pixel's samples it covers
/// **in front of each sample's opaque depth** (`coverage: fraction`), or at full alpha where it
/// keeps any sample (`coverage: pixel`: `mdts`, bdp's colour mode). On each pixel the quad covers
/// whole and the wall partly: the quad's colour c (straight alpha), the wall's W and the
/// background's bg read back from the reference's pixels, the fraction's pixel is
/// α·f·c + (1 − α·f)·B̄, within 2 levels of 8 bits (the colours read back from 8-bit pixels, the
/// alpha's 8 bits, the encoding; a hardware path, whose rasterizer snaps its own edges, on 90 % of
/// the pixels). The per-sample reference's is the mean over the samples of α·c + (1 − α)·Bᵢ where
/// the quad is kept and Bᵢ where the wall hides it: the two differ by α·f(1 − f)·(bg − W), at
/// most α/4 of the wall's contrast with what lies beside it (at f = ½), the cost of the mean
/// background against the per-sample reference, which this test holds on the measured pixels
/// (3/255 of slack in linear light for the 8-bit reads). The accounting holds and `occluded` is
/// the reference's. Mutations caught (each tried): oit-cpu's covered walk weighing the fraction of
/// every sample the fragment covers, not of those it keeps in front ("cpu/cpu: dp on
/// wall:0:planes:1 at 4×: 0 of 33 edge pixels its definition"); oit-cpu's background the first
/// sample's colour instead of the mean (0 of 33 alike); the GPU's opaque pass taking its
/// fragments weighted by their fraction, which discards a wall's edge fragments under the cutoff
/// ("wgpu/compute: dp …: 15 of 29 edge pixels").
#[test]
fn techniques_without_masks_over_an_opaque_edge() {
    let scene = scene_of(EDGE_SCENE);
    let mut checked = 0;
    for backend in backends_for("techniques_without_masks_over_an_opaque_edge") {
        let on = label(backend.as_ref());
        let hardware = backend.raster_path(&Settings::default()) == oit_core::RasterPath::Hardware;
        for samples in [4, 8] {
            let base =
                Settings { samples, shading: Shading::Flat, alpha: Some(0.4), ..settings(128, "reference") };
            let cam = camera(&scene, &base, beside());
            let (n, full) = (samples as usize, full_mask(samples));
            let reference = match backend.render(&scene, &cam, &base) {
                Ok(f) => f,
                Err(OitError::Unsupported { what, .. }) if hardware && samples == 8 => {
                    eprintln!("{on} at {samples}×: {what}");
                    continue;
                }
                Err(e) => panic!("{on} at {samples}×: {e}"),
            };
            // by hand: each sample's opaque key, and per pixel the quad's fragments (how many, the
            // last one's mask and depth)
            let keys = opaque_keys_by_hand(&scene, &cam, &base);
            let layers = scene.layers(base.alpha);
            let drawn = layers.settings(&base);
            let mut quad = vec![(0u32, 0u8, 0f32); base.pixel_count()];
            for (px, _, mask, d) in plain_fragments(&layers.transparent, &cam, &drawn) {
                quad[px] = (quad[px].0 + 1, mask, d);
            }
            let wall_of =
                |px: usize| (0..n).fold(0u8, |m, i| m | u8::from(keys[px * n + i] != u64::MAX) << i);
            let kept_of = |px: usize| {
                (0..n).fold(0u8, |m, i| m | u8::from(quad[px].2 < key_depth(keys[px * n + i])) << i)
                    & quad[px].1
            };
            let whole = |px: usize| quad[px].0 == 1 && quad[px].1 == full;
            // the colours, read back from the reference's pixels (flat shading: one each)
            let pixels = 0..base.pixel_count();
            let find = |what: &str, pick: &dyn Fn(usize) -> bool| {
                let px =
                    pixels.clone().find(|&px| pick(px)).unwrap_or_else(|| panic!("{on}: a pixel {what}"));
                glam::Vec3::from_array(std::array::from_fn(|c| linear(reference.image.pixels[px][c])))
            };
            let wall = find("all wall", &|px| wall_of(px) == full);
            let bg = find("of background", &|px| quad[px].0 == 0 && wall_of(px) == 0);
            let over_bg = find("of the quad alone", &|px| whole(px) && wall_of(px) == 0);
            let alpha = (0.4f32 * 255.0).round() / 255.0;
            let ac = over_bg - (1.0 - alpha) * bg;
            assert!((wall - bg).abs().max_element() > 0.1, "{on}: the wall {wall} against {bg}");
            // the pixels of the wall's edge over the quad's interior, their per-sample reference
            let edge: Vec<(usize, glam::Vec3, f32, glam::Vec3)> = pixels
                .clone()
                .filter(|&px| whole(px) && wall_of(px) != 0 && wall_of(px) != full)
                .map(|px| {
                    let (w, kept) = (wall_of(px), kept_of(px));
                    let b = |i: usize| if w >> i & 1 == 1 { wall } else { bg };
                    let mean = (0..n).map(b).sum::<glam::Vec3>() / n as f32;
                    let per_sample = (0..n)
                        .map(|i| if kept >> i & 1 == 1 { ac + (1.0 - alpha) * b(i) } else { b(i) })
                        .sum::<glam::Vec3>()
                        / n as f32;
                    (px, mean, kept.count_ones() as f32 / n as f32, per_sample)
                })
                .collect();
            // (the pixels whose fraction kept is near ½, where the mean background errs most)
            let halves = edge.iter().filter(|e| (0.25..=0.75).contains(&e.2)).count();
            assert!(
                edge.len() > 20 && halves > 4,
                "{on} at {samples}×: {} edge pixels, {halves} halves",
                edge.len()
            );
            let srgb3 = |c: glam::Vec3| [srgb(c.x), srgb(c.y), srgb(c.z), 255];
            let near = |got: [u8; 4], want: glam::Vec3| diff(got, srgb3(want)) <= 2;
            let within = |n: usize| if hardware { n >= edge.len() * 9 / 10 } else { n == edge.len() };
            let good = edge.iter().filter(|e| near(reference.image.pixels[e.0], e.3)).count();
            let contrast = diff(srgb3(wall), srgb3(bg));
            eprintln!(
                "{on} at {samples}×: {} edge pixels, the wall {contrast} levels from the background",
                edge.len()
            );
            assert!(
                within(good),
                "{on} at {samples}×: the reference on {good} of {} edge pixels",
                edge.len()
            );
            let bound = alpha / 4.0 * (wall - bg).abs() + glam::Vec3::splat(3.0 / 255.0);
            for t in FRACTION_TECHNIQUES {
                let s = Settings { technique: t.parse().unwrap(), ..base.clone() };
                let what = format!("{on}: {t} on {EDGE_SCENE} at {samples}×");
                // (plain's blender on a hardware path composites each sample over its own opaque
                // colour: `coverage: sample`, held to the per-sample definition below)
                let f = render(backend.as_ref(), &scene, &cam, &s);
                checks::accounting(&f).unwrap_or_else(|e| panic!("{what}: {e}"));
                if hardware {
                    checks::occluded_near(&f, &reference).unwrap_or_else(|e| panic!("{what}: {e}"));
                } else {
                    assert_eq!(f.stats.occluded, reference.stats.occluded, "{what}: occluded");
                }
                let fraction = f.stats.coverage == Some(Coverage::Fraction);
                let (mut good, mut bounded) = (0, 0);
                for &(px, mean, kept, per_sample) in &edge {
                    let a = if fraction {
                        alpha * kept
                    } else if kept > 0.0 {
                        alpha
                    } else {
                        0.0
                    };
                    // (a technique that comes to keep masks composites per sample: the reference's)
                    let want = if f.stats.coverage == Some(Coverage::Sample) {
                        per_sample
                    } else {
                        a / alpha * ac + (1.0 - a) * mean
                    };
                    let got = f.image.pixels[px];
                    good += usize::from(near(got, want));
                    let got = glam::Vec3::from_array(std::array::from_fn(|c| linear(got[c])));
                    bounded += usize::from(((got - per_sample).abs() - bound).max_element() <= 0.0);
                }
                let worst = edge.iter().map(|e| diff(f.image.pixels[e.0], reference.image.pixels[e.0])).max();
                eprintln!(
                    "{what}: {good} of {} edge pixels its definition; off the reference by up to {worst:?} levels",
                    edge.len()
                );
                assert!(within(good), "{what}: {good} of {} edge pixels its definition", edge.len());
                if fraction {
                    assert!(
                        within(bounded),
                        "{what}: {bounded} of {} edge pixels within α/4 of the contrast",
                        edge.len()
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 2 * FRACTION_TECHNIQUES.len());
}

/// The view of the opaque-edge tests ([`techniques_without_masks_over_an_opaque_edge`],
/// [`fabs_tail_over_an_opaque_edge`]): turned 65° from the default the other way from [`oblique`],
/// so that the planes behind a wall in front of everything (`wall:0`) show beside its edge, which
/// crosses them, the two quads of `planes:2` overlapping there.
fn beside() -> View {
    View { azimuth: View::default().azimuth - 65.0, ..View::default() }
}

/// fabs's one tail a pixel over opaque objects, held to its definition (docs/msaa.md, "The tail of
/// `fabs` over opaque objects") on the edge of an opaque wall in front of two transparent quads
/// (`wall:0:planes:2`, seen from [`beside`], flat shaded, alpha α = 0.4, 4 samples), with one
/// slot (`fabs:1 --overflow tail`): on each pixel both quads cover whole and the wall partly, the
/// nearer quad (α·c₁ premultiplied) takes the slot and the farther (α·c₂) the tail, both kept at
/// the samples S the wall leaves (f = |S|/N). Each sample composites the slot where it covers
/// the sample over the tail put over **that sample's own opaque colour** Bᵢ; the tail is one
/// fragment weighted by its fraction, f·α·c₂ + (1 − α·f)·Bᵢ, so a sample in S is
/// α·c₁ + (1 − α)·(f·α·c₂ + (1 − α·f)·Bᵢ) and one the wall hides f·α·c₂ + (1 − α·f)·W: the pixel
/// their mean, within 2 levels of 8 bits (each α·c read back from a pixel its quad covers alone
/// beside the wall, W and the background from theirs; a hardware path on 90 % of the pixels).
/// Against the per-sample reference it errs by the tail's fraction only (the wall's samples
/// dimmed by the tail they do not see, the samples in S by less than its full alpha), not by
/// dropping the tail nor by putting it over the background. The accounting holds and every
/// fragment past the slot is merged. Mutation caught: oit-cpu's tail put over the pixel's mean
/// colour instead of each sample's ("cpu/cpu: …: 0 of 41 edge pixels its definition").
#[test]
fn fabs_tail_over_an_opaque_edge() {
    let scene = scene_of("wall:0:planes:2");
    let mut checked = 0;
    for backend in backends_for("fabs_tail_over_an_opaque_edge") {
        let on = label(backend.as_ref());
        let hardware = backend.raster_path(&Settings::default()) == oit_core::RasterPath::Hardware;
        let samples = 4;
        let base =
            Settings { samples, shading: Shading::Flat, alpha: Some(0.4), ..settings(256, "reference") };
        let cam = camera(&scene, &base, beside());
        let (n, full) = (samples as usize, full_mask(samples));
        let reference = render(backend.as_ref(), &scene, &cam, &base);
        let tail = Settings {
            technique: Technique::Fabs { k: Some(1) },
            overflow: oit_core::Overflow::Tail,
            ..base.clone()
        };
        let f = render(backend.as_ref(), &scene, &cam, &tail);
        let what = format!("{on}: fabs:1 --overflow tail on wall:0:planes:2 at {samples}×");
        checks::accounting(&f).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(
            f.stats.merged > 0 && f.stats.lost == 0,
            "{what}: merged {}, lost {}",
            f.stats.merged,
            f.stats.lost
        );
        // by hand: each sample's opaque key; per pixel the quads' fragments (depth, primitive,
        // mask), nearest first
        let keys = opaque_keys_by_hand(&scene, &cam, &base);
        let layers = scene.layers(base.alpha);
        let drawn = layers.settings(&base);
        let mut quads = vec![Vec::new(); base.pixel_count()];
        for (px, prim, mask, d) in plain_fragments(&layers.transparent, &cam, &drawn) {
            quads[px].push((d, prim, mask));
        }
        quads.iter_mut().for_each(|q| q.sort_by(|a, b| a.0.total_cmp(&b.0)));
        let wall_of = |px: usize| (0..n).fold(0u8, |m, i| m | u8::from(keys[px * n + i] != u64::MAX) << i);
        let whole = |px: usize, k: usize| quads[px].len() == k && quads[px].iter().all(|q| q.2 == full);
        let read = |px: usize| {
            glam::Vec3::from_array(std::array::from_fn(|c| linear(reference.image.pixels[px][c])))
        };
        let pixels = 0..base.pixel_count();
        let wall = read(pixels.clone().find(|&px| wall_of(px) == full).expect("a pixel all wall"));
        let bg =
            read(pixels.clone().find(|&px| quads[px].is_empty() && wall_of(px) == 0).expect("background"));
        let alpha = (0.4f32 * 255.0).round() / 255.0;
        // each quad's α·c (by its triangles' primitives), from a pixel it covers alone
        let mut ac = std::collections::HashMap::new();
        for px in pixels.clone().filter(|&px| whole(px, 1) && wall_of(px) == 0) {
            ac.entry(quads[px][0].1).or_insert_with(|| read(px) - (1.0 - alpha) * bg);
        }
        let srgb3 = |c: glam::Vec3| [srgb(c.x), srgb(c.y), srgb(c.z), 255];
        let (mut edge, mut good) = (0, 0);
        for px in pixels.clone().filter(|&px| whole(px, 2) && wall_of(px) != 0 && wall_of(px) != full) {
            let w = wall_of(px);
            let kept = |q: &(f32, u32, u8)| {
                (0..n).fold(0u8, |m, i| m | u8::from(q.0 < key_depth(keys[px * n + i])) << i) & q.2
            };
            let (front, back) = (&quads[px][0], &quads[px][1]);
            let (Some(&c1), Some(&c2)) = (ac.get(&front.1), ac.get(&back.1)) else { continue };
            // both behind the wall: kept where it is not
            assert_eq!((kept(front), kept(back)), (!w & full, !w & full), "{what}: pixel {px}");
            let frac = (!w & full).count_ones() as f32 / n as f32;
            let b = |i: usize| if w >> i & 1 == 1 { wall } else { bg };
            let want = (0..n)
                .map(|i| {
                    let behind = frac * c2 + (1.0 - alpha * frac) * b(i);
                    if w >> i & 1 == 1 { behind } else { c1 + (1.0 - alpha) * behind }
                })
                .sum::<glam::Vec3>()
                / n as f32;
            edge += 1;
            good += usize::from(diff(f.image.pixels[px], srgb3(want)) <= 2);
        }
        eprintln!("{what}: {good} of {edge} edge pixels its definition");
        assert!(edge > 20, "{what}: {edge} edge pixels");
        let needed = if hardware { edge * 9 / 10 } else { edge };
        assert!(good >= needed, "{what}: {good} of {edge} edge pixels its definition");
        checked += 1;
    }
    assert!(checked >= 1);
}

/// The multisampled opaque pass on the GPU backends, written once (`core/opaque.wgsl` over the
/// opaque image kept a sample; prelude.wgsl's `opaque_kept` reducing each fragment's mask): on
/// the compute paths, which follow oit-cpu's rules, every frame is oit-cpu's (the same fragments,
/// losses, passes and per-pixel counts, every pixel within 1 of 8 bits, the same `occluded`,
/// opaque and masked counts, the plan's storage with the opaque image at 20 bytes a sample); on
/// the hardware paths (`@builtin(sample_mask)` reduced at the cut, `hw_fs_masked`) the accounting
/// holds and the opaque and occluded counts are the CPU's within a hundredth of the fragments
/// (the device snaps its own edges). On every path the exact techniques equal the path's own
/// per-sample reference, the effects included. The same for fabs's tail (one a pixel, put behind
/// each sample over its own opaque colour) and every technique that keeps no mask (its coverage
/// cut at each sample's opaque depth, composited over the samples' mean colour; plain's blender is
/// refused on the hardware paths), on the walls and on the quad behind the wall's edge
/// ([`EDGE_SCENE`]). Mutations caught (each tried): oit-cpu's covered walk weighing the fraction of
/// every sample a fragment covers ("wgpu/compute: dp (Transparency) on wall:0:planes:1 at 4×: 18
/// pixels off the edges differ, by up to 20"); oit-cpu's background the first sample's colour
/// ("… on wall:0.5:planes:16 at 4×: 97 pixels off the edges differ, by up to 88"); the GPU's
/// opaque pass weighted by the fraction ("… dp … on wall:0.5:planes:16 at 4×: passes: 10 vs 8",
/// its edge fragments discarded under the cutoff, so more fragments kept to peel).
#[test]
fn opaque_pass_at_samples_on_the_gpu() {
    let cpu = CpuBackend::default();
    let mut compared = 0;
    let gpus = backends_for("opaque_pass_at_samples_on_the_gpu").into_iter().filter(|b| b.name() != "cpu");
    for backend in gpus {
        let on = label(backend.as_ref());
        let hardware = backend.raster_path(&Settings::default()) == oit_core::RasterPath::Hardware;
        // (and the quad behind the wall's edge, where the cut a sample reduces the masks)
        let cases = [
            (WALLED[0], 4, oblique()),
            (WALLED[1], 4, oblique()),
            (WALLED[0], 8, oblique()),
            (EDGE_SCENE, 4, beside()),
        ];
        for (name, samples, view) in cases {
            let scene = scene_of(name);
            let base = Settings { samples, ..settings(64, "reference") };
            let cam = camera(&scene, &base, view);
            let reference = match backend.render(&scene, &cam, &base) {
                Ok(f) => f,
                Err(OitError::Unsupported { what, .. }) if hardware && samples == 8 => {
                    eprintln!("{on} at {samples}×: {what}");
                    continue;
                }
                Err(e) => panic!("{on} {name} at {samples}×: {e}"),
            };
            let mut cases: Vec<Settings> =
                ["reference", "dfb", "ll", "fabs", "fabs:2", "dp", "ddp", "mlp:1", "mlp:2", "mlp:4"]
                    .iter()
                    .map(|t| Settings { technique: t.parse().unwrap(), ..base.clone() })
                    .collect();
            for effect in [oit_core::Effect::Translucency, oit_core::Effect::Complexity] {
                cases.push(Settings { effect, technique: Technique::Dfb, ..base.clone() });
            }
            cases.push(Settings { pixel_coverage: true, technique: Technique::Ll, ..base.clone() });
            // fabs's one tail a pixel over each sample's opaque colour; the techniques that keep no
            // mask, their coverage cut at each sample's opaque depth, over the samples' mean colour
            let fabs2 = Technique::Fabs { k: Some(2) };
            cases.push(Settings { overflow: oit_core::Overflow::Tail, technique: fabs2, ..base.clone() });
            cases.extend(
                FRACTION_TECHNIQUES
                    .iter()
                    .map(|t| Settings { technique: t.parse().unwrap(), ..base.clone() }),
            );
            cases.push(Settings { pixel_coverage: true, technique: Technique::Wboit, ..base.clone() });
            for s in cases {
                let what = format!("{on}: {} ({:?}) on {name} at {samples}×", s.technique, s.effect);
                let g = render(backend.as_ref(), &scene, &cam, &s);
                let c = render(&cpu, &scene, &cam, &s);
                checks::accounting(&g).unwrap_or_else(|e| panic!("{what}: {e}"));
                if hardware {
                    checks::occluded_near(&g, &c).unwrap_or_else(|e| panic!("{what}: {e}"));
                    let slack = c.stats.opaque_fragments / 100;
                    assert!(
                        g.stats.opaque_fragments.abs_diff(c.stats.opaque_fragments) <= slack,
                        "{what}: opaque fragments"
                    );
                } else {
                    checks::same_fragments_as_cpu(&g, &c, s.technique)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(
                        (g.stats.occluded, g.stats.opaque_fragments, g.stats.masked),
                        (c.stats.occluded, c.stats.opaque_fragments, c.stats.masked),
                        "{what}: occluded, opaque, masked"
                    );
                    // (plain's storage is the path's: oit-cpu's banded pass keeps none, `Plan::on_path`)
                    if s.technique != Technique::Plain {
                        checks::same_storage_as_cpu(backend.name(), &g, &c, &scene, &s)
                            .unwrap_or_else(|e| panic!("{what}: {e}"));
                    }
                }
                if hardware && s.technique == Technique::Plain {
                    // plain's blender composites each sample (`hardware_blend_captures_at_samples`)
                    assert_eq!(g.stats.coverage, Some(Coverage::Sample), "{what}: coverage");
                } else {
                    assert_eq!(g.stats.coverage, c.stats.coverage, "{what}: coverage");
                }
                let exact = matches!(
                    s.technique,
                    Technique::Dfb
                        | Technique::Ll
                        | Technique::Fabs { k: None }
                        | Technique::Dp
                        | Technique::Ddp
                        | Technique::Mlp { .. }
                ) && !s.fraction_coverage
                    && s.max_peels.is_none();
                if exact && s.effect == oit_core::Effect::Transparency && !s.pixel_coverage {
                    checks::exact(&reference, &g).unwrap_or_else(|e| panic!("{what}: {e}"));
                }
                compared += 1;
            }
        }
    }
    eprintln!("{compared} multisampled GPU frames with opaque parts compared");
}

/// A triangle clipped at the far plane is fan-triangulated into pieces that keep its primitive
/// id, and above one sample two pieces may cover one pixel at the same depth (never one sample).
/// The per-sample peels keep one fragment a key: keyed by (depth, primitive id) alone, `dp` and
/// `ddp` kept one piece and dropped the other without a count on oit-cpu (the GPUs' frame check
/// refused the frame), and `mlp:M` composited one over both's samples, an error pixel with
/// nothing counted. `planes:1` seen from above with the far plane through it, at 4 and 8
/// samples: the plain rule finds such a pair of pieces, and every peel on every backend and path
/// equals the per-sample reference with nothing lost (`msaa::peel_key` adds the lowest sample of
/// the mask). Mutation caught: `peel_key` without the sample (oit-core's, which oit-cpu takes, and
/// peel_samples.wgsl's): oit-cpu's dp refused by its frame check (`Stats::check_accounting`);
/// by hand with the CLI, oit-cpu's and the compute paths' dp and ddp fail that check, and mlp
/// on each one error pixel with nothing counted.
#[test]
fn clipped_pieces_peel_apart() {
    let scene = scene_of("planes:1");
    let view = View { azimuth: 30.0, elevation: 60.0, far: Some(4.0), ..View::default() };
    let mut compared = 0;
    for samples in [4, 8] {
        let base = Settings { samples, ..settings(64, "reference") };
        let cam = camera(&scene, &base, view);
        // the case itself: two fragments of one primitive on one pixel, their masks disjoint
        let mut seen = std::collections::HashMap::new();
        let mut pairs = 0;
        for (px, prim, mask, _) in plain_fragments(&scene, &cam, &base) {
            if let Some(other) = seen.insert((px, prim), mask) {
                assert_eq!(other & mask, 0, "pieces of one triangle share a sample");
                pairs += 1;
            }
        }
        assert!(pairs > 0, "the far plane cuts no triangle into pieces on one pixel at {samples}×");
        for backend in backends_for("clipped_pieces_peel_apart") {
            let b = backend.as_ref();
            // a device without 8-sample targets says so by name (wgpu's hardware path on lavapipe
            // and on the H200)
            let render_or_skip = |s: &Settings, what: &str| match b.render(&scene, &cam, s) {
                Ok(f) => Some(f),
                Err(OitError::Unsupported { what: why, .. })
                    if samples == 8
                        && ["--samples 8", "8-sample", "8 samples"].iter().any(|n| why.contains(n)) =>
                {
                    eprintln!("{what}: {why}");
                    None
                }
                Err(e) => panic!("{what}: {e}"),
            };
            let Some(reference) = render_or_skip(&base, &format!("{}: reference at {samples}×", label(b)))
            else {
                continue;
            };
            for t in ["dp", "ddp", "mlp:2", "mlp:4"] {
                let s = Settings { technique: t.parse().unwrap(), ..base.clone() };
                let what = format!("{}: {t} at {samples}× on the far plane's pieces", label(b));
                let Some(f) = render_or_skip(&s, &what) else { continue };
                assert_eq!(f.stats.coverage, Some(Coverage::Sample), "{what}");
                checks::accounting(&f).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!((f.stats.lost, f.stats.fragments), (0, reference.stats.fragments), "{what}");
                checks::exact(&reference, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
                compared += 1;
            }
        }
    }
    assert!(compared >= 8, "{compared} frames compared");
}
