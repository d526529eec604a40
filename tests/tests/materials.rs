//! Opaque first (issue 38): a scene's opaque and masked objects are drawn into a depth buffer and
//! a colour image before the technique runs; every technique captures only the transparent
//! fragments strictly in front and composites them over that colour, and what the opaque depth
//! holds back is counted (`occluded`), so `captured + merged + lost + occluded = fragments`.
//!
//! On the CPU backend; the GPU backends' opaque pass is held to the CPU's elsewhere.

use glam::{Mat4, Vec3, Vec4};
use oit_core::{AlphaMode, Backend, Instance, Mesh, Object, Scene, Settings, Technique, View};
use oit_tests::checks;
use oit_tests::*;

fn cpu() -> oit_cpu::CpuBackend {
    oit_cpu::CpuBackend::default()
}

/// Every technique the CPU runs that is exact on these scenes (no fixed K too small, no
/// approximation; not `mdts`, whose 12-bit colour rounds): they must equal the reference, ties
/// and all.
const EXACT: [&str; 10] = ["dp", "ddp", "bdp2", "adp", "fabs", "mdts64", "mlp:4", "dfb", "ll", "bdp:1"];

/// The exact techniques equal the reference on scenes with opaque parts: a wall through the
/// middle of the planes (about half the transparent fragments behind it), through the default
/// scene, and behind everything (an opaque backdrop that holds nothing back); and every
/// technique, exact or not, keeps the accounting with `occluded` in it.
#[test]
fn exact_techniques_equal_the_reference_with_opaque_parts() {
    let b = cpu();
    for (name, size) in [("wall:0.5:planes:16", 64), ("wall:0.45:default", 96), ("wall:1:knot", 64)] {
        let scene = scene(name);
        let base = settings(size, "reference");
        let cam = camera(&scene, &base, View::default());
        let reference = render(&b, &scene, &cam, &base);
        checks::accounting(&reference).unwrap_or_else(|e| panic!("{name} reference: {e}"));
        let s = &reference.stats;
        assert!(s.opaque_fragments > 0 && s.captured > 0, "{name}: {s:?}");
        if name.starts_with("wall:1:") {
            assert_eq!(s.occluded, 0, "{name}: a backdrop holds nothing back");
        } else {
            assert!(s.occluded > s.fragments / 5, "{name}: the wall holds back too little: {s:?}");
        }
        for t in EXACT {
            let f = render(&b, &scene, &cam, &Settings { technique: t.parse().unwrap(), ..base.clone() });
            // bdp's colour mode packs alpha in 7 bits: exact in what it captures, not in colour
            if t == "bdp:1" {
                checks::accounting(&f).unwrap_or_else(|e| panic!("{name} {t}: {e}"));
                assert_eq!(f.stats.occluded, s.occluded, "{name} {t}");
                continue;
            }
            checks::exact(&reference, &f).unwrap_or_else(|e| panic!("{name} {t}: {e}"));
            assert_eq!((f.stats.occluded, f.stats.captured), (s.occluded, s.captured), "{name} {t}");
        }
        // the approximate and fixed-size ones: losses counted, the same fragments held back
        for t in ["plain", "wavg", "wsum", "wboit", "mboit", "bdp", "fabs:2", "mdts:2", "mdts64:2", "mlp:1"] {
            let f = render(&b, &scene, &cam, &Settings { technique: t.parse().unwrap(), ..base.clone() });
            checks::accounting(&f).unwrap_or_else(|e| panic!("{name} {t}: {e}"));
            assert_eq!(f.stats.occluded, s.occluded, "{name} {t}: the same fragments held back");
        }
    }
}

/// `occluded` against an independent count: the fragments the transparent part draws with the
/// opaque parts removed (same camera), less those the frame with them captured.
#[test]
fn occluded_is_what_the_opaque_parts_remove() {
    let b = cpu();
    for name in ["wall:0.5:planes:16", "wall:0.3:cluster:100"] {
        let with = scene(name);
        let base = settings(64, "reference");
        let cam = camera(&with, &base, View::default());
        let mut without = with.clone();
        without.instances.retain(|i| !with.objects[i.object].is_opaque_pass());
        let w = render(&b, &with, &cam, &base).stats;
        let wo = render(&b, &without, &cam, &base).stats;
        assert_eq!(w.fragments, wo.fragments, "{name}: the same transparent fragments drawn");
        assert_eq!(w.occluded, wo.fragments - w.captured, "{name}");
        assert!(w.occluded > 0 && wo.occluded == 0, "{name}: {w:?} {wo:?}");
    }
}

/// A wall in front of everything: nothing captured, every transparent fragment occluded, and the
/// image is the wall's (the same as with every transparent object at alpha 0, whose fragments
/// change no pixel), under every effect.
#[test]
fn everything_behind_a_wall_renders_the_wall() {
    let b = cpu();
    let walled = scene("wall:0:planes:8");
    let mut invisible = walled.clone();
    for o in invisible.objects.iter_mut().filter(|o| !o.is_opaque_pass()) {
        o.color.w = 0.0;
        o.alpha_mode = AlphaMode::Blend;
    }
    let mut unwalled_objects = walled.clone();
    unwalled_objects.instances.retain(|i| walled.objects[i.object].is_opaque_pass());
    for t in ["reference", "fabs", "dp", "wavg"] {
        let base = settings(48, t);
        let cam = camera(&walled, &base, View::default());
        let f = render(&b, &walled, &cam, &base);
        assert_eq!(f.stats.captured, 0, "{t}");
        assert!(f.stats.fragments > 0 && f.stats.occluded == f.stats.fragments, "{t}: {:?}", f.stats);
        let only_wall = render(&b, &unwalled_objects, &cam, &base);
        assert_eq!(f.image, only_wall.image, "{t}: the wall alone");
        let g = render(&b, &invisible, &cam, &Settings { technique: Technique::Reference, ..base.clone() });
        assert_eq!(f.image, g.image, "{t}: as if the planes were invisible");
        // the wall covers most of the frame, in its own grey shading
        let grey = f.image.pixels.iter().filter(|p| p[0] == p[1] && p[1] == p[2] && p[0] > 60).count();
        assert!(grey > f.image.pixels.len() / 4, "{t}: {grey} grey pixels");
    }
}

/// Masks: an object whose alpha is under its cutoff is discarded whole and counted; at or over
/// it, drawn opaque. `nowall:` (the wall masked away) draws the same transparent fragments as
/// `wall:` and holds none back.
#[test]
fn masks_keep_or_discard_and_count() {
    let b = cpu();
    let base = settings(64, "reference");
    let walled = scene("wall:0.5:planes:8");
    let cam = camera(&walled, &base, View::default());
    let masked = scene("nowall:0.5:planes:8");
    let w = render(&b, &walled, &cam, &base).stats;
    let m = render(&b, &masked, &cam, &base);
    assert_eq!(m.stats.masked, m.stats.opaque_fragments, "every wall fragment masked away");
    assert_eq!(m.stats.opaque_fragments, w.opaque_fragments);
    assert_eq!((m.stats.fragments, m.stats.occluded, m.stats.captured), (w.fragments, 0, w.fragments));
    // with the wall's instance removed entirely, the same image
    let mut none = masked.clone();
    none.instances.retain(|i| !masked.objects[i.object].is_opaque_pass());
    assert_eq!(render(&b, &none, &cam, &base).image, m.image);
    // a cutoff the alpha reaches keeps the wall: the walled image
    let mut kept = masked.clone();
    for o in kept.objects.iter_mut().filter(|o| o.is_opaque_pass()) {
        o.color.w = 0.5;
    }
    assert_eq!(render(&b, &kept, &cam, &base).image, render(&b, &walled, &cam, &base).image);
}

/// Two coplanar opaque squares of different colours: the lower primitive id wins every pixel,
/// whatever the thread count (the z-buffer's MIN over (depth, id)).
#[test]
fn coplanar_opaque_ties_go_to_the_lower_id() {
    let quad = |z: f32| {
        let p = vec![
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ];
        Mesh::new("q", p, vec![[0, 1, 2], [0, 2, 3]])
    };
    let mut scene = Scene { name: "coplanar opaque".into(), ..Scene::default() };
    scene.meshes = vec![quad(0.0), quad(0.0), quad(0.3)];
    scene.objects = vec![
        Object::new("red", 0, Vec4::new(1.0, 0.0, 0.0, 1.0)).opaque(),
        Object::new("green", 1, Vec4::new(0.0, 1.0, 0.0, 1.0)).opaque(),
        Object::new("glass", 2, Vec4::new(0.0, 0.0, 1.0, 0.5)),
    ];
    scene.instances = (0..3).map(|object| Instance { object, transform: Mat4::IDENTITY }).collect();
    let mut base = settings(32, "reference");
    base.shading = oit_core::Shading::Flat;
    let cam = camera(&scene, &base, View { azimuth: 0.0, elevation: 0.0, ..View::default() });
    let mut order = scene.clone();
    order.instances.swap(0, 1);
    for threads in [1, 2, 4] {
        let b = cpu_with_threads(threads);
        let f = render(b.as_ref(), &scene, &cam, &base);
        let centre = f.image.get(16, 16);
        assert!(centre[0] > centre[1], "{threads} threads: red (id 0) wins, got {centre:?}");
        let g = render(b.as_ref(), &order, &cam, &base);
        let centre = g.image.get(16, 16);
        assert!(centre[1] > centre[0], "{threads} threads: green first wins, got {centre:?}");
    }
}

/// Transmission scales a blended fragment's alpha by (1 − transmission); `--alpha` overrides
/// the blended objects' alpha only (before the transmission), never an opaque one's.
#[test]
fn transmission_and_the_alpha_override() {
    let b = cpu();
    let base = settings(48, "reference");
    let plain = scene("planes:4");
    let cam = camera(&plain, &base, View::default());
    let mut half = plain.clone();
    half.objects.iter_mut().for_each(|o| o.color.w *= 0.5);
    let mut transmitting = plain.clone();
    transmitting.objects.iter_mut().for_each(|o| o.transmission = 0.5);
    assert_eq!(render(&b, &transmitting, &cam, &base).image, render(&b, &half, &cam, &base).image);
    // the override, then the transmission
    let over = Settings { alpha: Some(0.8), ..base.clone() };
    let mut at = plain.clone();
    at.objects.iter_mut().for_each(|o| o.color.w = 0.4);
    assert_eq!(render(&b, &transmitting, &cam, &over).image, render(&b, &at, &cam, &base).image);
    // an opaque wall stays opaque under the override
    let walled = scene("wall:0:planes:4");
    let cam = camera(&walled, &base, View::default());
    let f = render(&b, &walled, &cam, &Settings { alpha: Some(0.1), ..base.clone() });
    assert_eq!(f.image, render(&b, &walled, &cam, &base).image);
}

/// Bad materials are refused with a message that names the object and the value.
#[test]
fn bad_materials_are_refused_by_name() {
    let b = cpu();
    let mut s = scene("planes:2");
    s.objects[0].alpha_mode = AlphaMode::Mask { cutoff: 1.5 };
    let e = b.prepare(&s).err().expect("a cutoff over 1").to_string();
    assert!(e.contains("plane 0") && e.contains("cutoff 1.5"), "{e}");
    s.objects[0].alpha_mode = AlphaMode::Mask { cutoff: f32::NAN };
    assert!(b.prepare(&s).is_err(), "a NaN cutoff");
    let mut s = scene("planes:2");
    s.objects[1].transmission = -0.1;
    let e = b.prepare(&s).err().expect("a negative transmission").to_string();
    assert!(e.contains("plane 1") && e.contains("transmission"), "{e}");
    for bad in ["wall:1.5:planes:4", "wall:x:planes:4", "wall:0.5", "nowall:-1:knot"] {
        let e = oit_core::load_scene(bad).err().unwrap_or_else(|| panic!("{bad} loads")).to_string();
        assert!(e.contains("F a number from 0 to 1"), "{bad}: {e}");
    }
}

/// A tiled frame with opaque parts equals the whole frame, its counts added over the tiles.
#[test]
fn tiles_with_opaque_parts_equal_the_whole_frame() {
    let b = cpu();
    let scene = scene("wall:0.5:planes:16");
    for t in ["reference", "fabs", "dp"] {
        let base = settings(64, t);
        let cam = camera(&scene, &base, View::default());
        let whole = render(&b, &scene, &cam, &base);
        let tiled = render(&b, &scene, &cam, &Settings { memory: Some(96 << 10), ..base.clone() });
        assert!(tiled.stats.tiles > 1, "{t}: the budget must force tiles");
        assert_eq!(tiled.image, whole.image, "{t}");
        let key = |s: &oit_core::Stats| (s.fragments, s.captured, s.occluded, s.opaque_fragments, s.masked);
        assert_eq!(key(&tiled.stats), key(&whole.stats), "{t}");
    }
}
