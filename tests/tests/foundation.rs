//! The foundation's conformance: the reference against hand computation, the peeling family
//! against the reference, weighted blending's error bounded, losses counted, bad input refused.

use glam::{DVec3, Vec3};
use oit_core::composite::{front_to_back_f64, linear_to_srgb8_f64};
use oit_core::metrics::accuracy;
use oit_core::rules::{pack_rgba8, unpack_rgba8_f64};
use oit_core::{Backend, Settings, Shading, Technique, View};
use oit_tests::*;

/// 8-bit sRGB back to linear.
fn to_linear(c: u8) -> f64 {
    let s = f64::from(c) / 255.0;
    if s <= 0.04045 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) }
}

#[test]
fn reference_equals_hand_composite_on_planes() {
    for backend in backends_for("reference_equals_hand_composite_on_planes") {
        eprintln!("on {}", label(backend.as_ref()));
        for n in 1..=8u32 {
            let scene = scene(&format!("planes:{n}"));
            let s = Settings {
                shading: Shading::Flat,
                background: Vec3::new(0.9, 0.9, 0.9),
                ..settings(64, "reference")
            };
            let cam = camera(&scene, &s, FRONT);
            let frame = render(backend.as_ref(), &scene, &cam, &s);
            // Plane 0 is nearest (z = +0.5 faces the camera on +z); colours are the 8-bit quantized
            // object colours, composited front to back by hand.
            let colors: Vec<[f64; 4]> =
                scene.objects.iter().map(|o| unpack_rgba8_f64(pack_rgba8(o.color))).collect();
            let c = front_to_back_f64(colors, DVec3::splat(0.9));
            let expected =
                [linear_to_srgb8_f64(c.x), linear_to_srgb8_f64(c.y), linear_to_srgb8_f64(c.z), 255];
            let layers = frame.layers.as_ref().expect("reference records layers");
            let full: Vec<usize> = (0..layers.len()).filter(|&i| layers[i] == n).collect();
            assert!(full.len() > 100, "planes:{n}: only {} pixels see every plane", full.len());
            for &i in &full {
                assert_eq!(frame.image.pixels[i], expected, "planes:{n} pixel {i}");
            }
            // where fewer planes overlap (the far planes are smaller on screen) the count is right
            assert!(layers.iter().all(|&l| l <= n));
        }
    }
}

#[test]
fn peeling_is_exact_and_weighted_is_bounded_on_planes() {
    for backend in backends_for("peeling_is_exact_and_weighted_is_bounded_on_planes") {
        eprintln!("on {}", label(backend.as_ref()));
        let b = backend.as_ref();
        for n in 1..=8u32 {
            let scene = scene(&format!("planes:{n}"));
            let bg = Vec3::new(0.9, 0.9, 0.9);
            let s = Settings { shading: Shading::Flat, background: bg, ..settings(64, "reference") };
            for t in [Technique::Dp, Technique::Ddp] {
                let (r, f) = with_reference(b, &scene, FRONT, &s, t);
                let a = accuracy(&r, &f.image).unwrap();
                assert_eq!(a.epr, 0.0, "{t} planes:{n}");
                assert_eq!(f.stats.lost, 0, "{t} planes:{n}");
            }
            for t in [Technique::WeightedAverage, Technique::WeightedSum] {
                let (r, f) = with_reference(b, &scene, FRONT, &s, t);
                let a = accuracy(&r, &f.image).unwrap();
                if n >= 2 {
                    assert!(
                        a.epr > 0.0,
                        "{t} planes:{n} should differ: the colours differ and order matters"
                    );
                }
                // The bound. Every plane has alpha a = 0.4, so at a pixel under k planes the reference
                // is T·bg + Σ wᵢcᵢ with T = (1 − a)^k and Σ wᵢ = 1 − T. Weighted average keeps T and
                // spreads 1 − T by alpha over the same colours; weighted sum uses weights a each,
                // Σ = k·a, then clamps. Per channel, both therefore lie within
                //   |Σ weights − (1 − T)|·max(cᵢ, bg) + (1 − T)·(max cᵢ − min cᵢ)
                // of the reference in linear space; 8-bit quantization adds at most 1.5/255 (half a
                // step each way, sRGB's slope ≤ 12.92 near black handled by going back to linear).
                let layers = r.layers.as_ref().unwrap();
                let colors: Vec<Vec3> = scene.objects.iter().map(|o| o.color.truncate()).collect();
                for (i, &k) in layers.iter().enumerate() {
                    if k == 0 {
                        continue;
                    }
                    let visible = &colors[..]; // every plane covers the pixels of the ones behind it
                    let t_ref = 0.6f64.powi(k as i32);
                    let weights =
                        if t == Technique::WeightedAverage { 1.0 - t_ref } else { 0.4 * f64::from(k) };
                    for ch in 0..3 {
                        let vals: Vec<f64> = visible.iter().map(|c| f64::from(c[ch])).collect();
                        let (lo, hi) = vals.iter().fold((1.0f64, 0.0f64), |(l, h), &v| (l.min(v), h.max(v)));
                        let bound = (weights - (1.0 - t_ref)).abs() * hi.max(0.9) + (1.0 - t_ref) * (hi - lo);
                        let diff =
                            (to_linear(r.image.pixels[i][ch]) - to_linear(f.image.pixels[i][ch])).abs();
                        assert!(
                            diff <= bound + 1.5 / 255.0 * 1.2,
                            "{t} planes:{n} px {i} ch {ch}: {diff} > {bound}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn order_matters_on_a_lit_mesh() {
    for backend in backends_for("order_matters_on_a_lit_mesh") {
        eprintln!("on {}", label(backend.as_ref()));
        let b = backend.as_ref();
        let scene = scene("knot");
        let s = settings(96, "reference"); // headlight shading: colours vary along the tube
        let view = View::default();
        assert!(
            epr(b, &scene, view, &s, Technique::WeightedAverage) > 0.01,
            "wavg must show ordering errors"
        );
        assert_eq!(epr(b, &scene, view, &s, Technique::Dp), 0.0);
        assert_eq!(epr(b, &scene, view, &s, Technique::Ddp), 0.0);
    }
}

#[test]
fn peeling_matches_reference_on_meshes() {
    for backend in backends_for("peeling_matches_reference_on_meshes") {
        eprintln!("on {}", label(backend.as_ref()));
        let b = backend.as_ref();
        for name in ["spheres:8", "knot", "cluster:200"] {
            let scene = scene(name);
            let s = settings(96, "reference");
            for t in [Technique::Dp, Technique::Ddp] {
                let (r, f) = with_reference(b, &scene, View::default(), &s, t);
                let a = accuracy(&r, &f.image).unwrap();
                assert_eq!(a.epr, 0.0, "{t} on {name}: EPR {}", a.epr);
                assert_eq!(f.stats.fragments, r.stats.fragments, "{t} on {name}");
                assert_eq!(f.stats.captured + f.stats.lost, f.stats.fragments);
            }
        }
    }
}

#[test]
fn coplanar_tie_is_counted_lost() {
    for backend in backends_for("coplanar_tie_is_counted_lost") {
        eprintln!("on {}", label(backend.as_ref()));
        let b = backend.as_ref();
        let scene = scene("coplanar");
        let s = settings(64, "reference");
        let (r, f) = with_reference(b, &scene, FRONT, &s, Technique::Dp);
        let overlap = r.layers.as_ref().unwrap().iter().filter(|&&l| l == 2).count() as u64;
        assert!(overlap > 100);
        assert_eq!(r.stats.lost, 0, "the reference keeps both");
        assert_eq!(f.stats.lost, overlap, "dp peels one of two coplanar fragments per pixel");
        assert_eq!(f.stats.captured + f.stats.lost, f.stats.fragments);
    }
}

#[test]
fn exact_techniques_do_not_depend_on_thread_count() {
    let scene = scene("cluster:200");
    for t in
        ["reference", "dp", "ddp", "wavg", "wsum", "fabs", "mdts64", "mlp:3", "adp", "bdp", "bdp2", "mdts"]
    {
        let s = settings(96, t);
        let cam = camera(&scene, &s, View::default());
        let one = render(cpu_with_threads(1).as_ref(), &scene, &cam, &s);
        let many = render(cpu_with_threads(4).as_ref(), &scene, &cam, &s);
        assert_eq!(one.image, many.image, "{t}");
        assert_eq!(one.stats.lost, many.stats.lost, "{t}");
    }
}

#[test]
fn bad_input_is_an_error() {
    let b = oit_cpu::CpuBackend::default();
    let scene = scene("planes:2");
    let cam = camera(&scene, &settings(8, "dp"), FRONT);
    let zero = Settings { width: 0, height: 0, ..settings(8, "dp") };
    assert!(b.render(&scene, &cam, &zero).unwrap_err().to_string().contains("0x0"));
    let mut nan = scene.clone();
    nan.meshes[0].positions[1].x = f32::NAN;
    assert!(b.render(&nan, &cam, &settings(8, "dp")).unwrap_err().to_string().contains("NaN"));
    assert!("nope".parse::<Technique>().is_err());
    assert!(oit_core::load_scene("no-such-scene").is_err());
    assert!(oit_core::load_scene("/no/such/file.obj").unwrap_err().to_string().contains("/no/such/file.obj"));
    let bad_view = View { azimuth: f32::NAN, ..View::default() };
    assert!(oit_core::Camera::orbit(&scene.bounds(), bad_view, 1.0).is_err());
}
