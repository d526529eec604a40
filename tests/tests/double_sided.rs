//! Double-sidedness (issue 38 item 1, issue 39 item 1: glTF's `doubleSided`): a single-sided
//! object's back faces produce no fragment, on every backend and raster path, the reference
//! included, opaque objects as well as blended ones, and a culled triangle is in no count.
//!
//! - [`back_faces_are_dropped_on_every_path`]: quads facing the camera and facing away, under a
//!   plain and a mirroring transform, before an opaque wall facing away and an opaque backdrop
//!   facing the camera: on every backend × path, the frame of the single-sided scene is the frame
//!   of the scene with the back faces removed by hand (each quad its own colour, so drawing the
//!   wrong one of a pair changes the image, not only the counts).
//! - [`a_closed_mesh_draws_half_its_fragments_single_sided`]: `spheres:4` made single-sided and
//!   taken through glTF (`write_glb`, `parse_gltf`: `doubleSided: false` read back): every pixel
//!   centre a closed convex surface covers has one front and one back fragment, so the reference
//!   draws half the fragments of the double-sided spheres (within 1 %, for the triangles
//!   seen edge-on at the silhouette); the exact techniques (dp, fabs, ll, dfb) equal the reference
//!   on every backend × path, and the compute paths draw exactly oit-cpu's fragments.
//!
//! Mutations that make it fail: make `hw_culled` drop front faces (tried: wgpu/hardware fails,
//! the wall facing away is drawn and hides the quads); turn the sign round in
//! `oit_core::setup::back_face_sign` (every path, the reference included, draws the back faces:
//! the images differ); turn it round in the compute setup only (`setup.wgsl`'s `area > 0li` for
//! `area < 0li`; tried: wgpu/compute fails with `OIT_HOST_SETUP=0`, and on a device that sets up
//! on the GPU; lavapipe sets up on the host, where oit-vulkan's and oit-wgpu's `gpu_setup` tests,
//! which hold a single-sided scene with a mirrored instance, fail instead).
//!
//! GPU backends without a device are left out with a message (`OIT_REQUIRE_GPU=1`: a failure).

use glam::{Mat4, Vec3, Vec4};
use oit_core::{Camera, Frame, Instance, Mesh, Object, RasterPath, Scene, Settings, Technique};
use oit_tests::checks;
use oit_tests::*;

/// A unit quad in the plane z = 0 about the origin, counter-clockwise seen from +z (its front
/// faces a camera on +z, as glTF's winding says), or clockwise where `clockwise`.
fn quad(name: &str, clockwise: bool) -> Mesh {
    let positions = vec![
        Vec3::new(-0.5, -0.5, 0.0),
        Vec3::new(0.5, -0.5, 0.0),
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(-0.5, 0.5, 0.0),
    ];
    let indices = if clockwise { vec![[0, 2, 1], [0, 3, 2]] } else { vec![[0, 1, 2], [0, 2, 3]] };
    Mesh::new(name, positions, indices)
}

/// The quads' scene: (name, clockwise, mirrored, colour, opaque, transform), each object
/// single-sided where `single`, the instances whose `keep` is false left out.
fn quads(single: bool, keep: impl Fn(&str) -> bool) -> Scene {
    let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let at = |x: f32, z: f32| Mat4::from_translation(Vec3::new(x, 0.0, z));
    let parts: [(&str, bool, Vec4, bool, Mat4); 6] = [
        // facing the camera: drawn
        ("front", false, Vec4::new(0.9, 0.1, 0.1, 0.5), false, at(-1.5, 0.0)),
        // facing away: dropped
        ("back", true, Vec4::new(0.1, 0.9, 0.1, 0.5), false, at(-0.5, 0.0)),
        // counter-clockwise in its own space under a mirror: clockwise on screen, glTF's front
        // there (a negative determinant turns the winding over): it still faces the camera
        ("mirrored front", false, Vec4::new(0.1, 0.2, 0.9, 0.5), false, at(0.5, 0.0) * mirror),
        // clockwise in its own space under a mirror: its back, dropped
        ("mirrored back", true, Vec4::new(0.9, 0.8, 0.1, 0.5), false, at(1.5, 0.0) * mirror),
        // an opaque wall in front of them all, facing away: dropped, it hides nothing
        (
            "wall",
            true,
            Vec4::new(0.5, 0.5, 0.5, 1.0),
            true,
            at(0.0, 0.4) * Mat4::from_scale(Vec3::new(4.5, 1.4, 1.0)),
        ),
        // an opaque backdrop behind them, facing the camera: drawn
        (
            "backdrop",
            false,
            Vec4::new(0.8, 0.7, 0.6, 1.0),
            true,
            at(0.0, -0.5) * Mat4::from_scale(Vec3::new(4.0, 1.2, 1.0)),
        ),
    ];
    let mut scene =
        Scene { name: format!("quads ({})", if single { "single" } else { "double" }), ..Scene::default() };
    for (name, clockwise, color, opaque, transform) in parts {
        if !keep(name) {
            continue;
        }
        scene.meshes.push(quad(name, clockwise));
        let mut o = Object::new(name, scene.meshes.len() - 1, color);
        o.double_sided = !single;
        if opaque {
            o = o.opaque();
        }
        scene.objects.push(o);
        scene.instances.push(Instance { object: scene.objects.len() - 1, transform });
    }
    scene
}

/// The counts a back face would change, and the image.
fn same_frame(a: &Frame, b: &Frame) -> Result<(), String> {
    let (x, y) = (&a.stats, &b.stats);
    for (what, p, q) in [
        ("fragments", x.fragments, y.fragments),
        ("captured", x.captured, y.captured),
        ("occluded", x.occluded, y.occluded),
        ("opaque_fragments", x.opaque_fragments, y.opaque_fragments),
    ] {
        if p != q {
            return Err(format!("{what}: {p} vs {q}"));
        }
    }
    if a.image != b.image {
        return Err(format!(
            "the images differ at {} pixels",
            checks::error_pixels(&a.image, &b.image).count()
        ));
    }
    Ok(())
}

#[test]
fn back_faces_are_dropped_on_every_path() {
    let single = quads(true, |_| true);
    let by_hand = quads(false, |name| matches!(name, "front" | "mirrored front" | "backdrop"));
    let both = quads(false, |_| true);
    let base = settings(64, "reference");
    // one camera for the three scenes: the same pixels
    let cam = camera(&single, &base, FRONT);
    let mut cpu_fragments = None;
    for backend in backends() {
        let b = backend.as_ref();
        let what = label(b);
        for t in [Technique::Reference, Technique::Ll] {
            let s = Settings { technique: t, ..base.clone() };
            let f = render(b, &single, &cam, &s);
            checks::accounting(&f).unwrap_or_else(|e| panic!("{what} {t}: {e}"));
            same_frame(&f, &render(b, &by_hand, &cam, &s)).unwrap_or_else(|e| {
                panic!("{what} {t}: the single-sided quads are not the front faces alone: {e}")
            });
            let all = render(b, &both, &cam, &s);
            assert_eq!(f.stats.occluded, 0, "{what} {t}: the wall faces away and hides nothing");
            assert!(all.stats.occluded > 0, "{what} {t}: drawn from both sides, the wall hides the quads");
            assert!(
                f.stats.opaque_fragments < all.stats.opaque_fragments,
                "{what} {t}: the wall's fragments are dropped"
            );
            if t == Technique::Reference {
                // two of the four equal quads: half the transparent fragments of all four (which
                // the wall, drawn from both sides, holds back: counted, not removed)
                assert!(f.stats.fragments > 0, "{what}");
                assert_eq!(2 * f.stats.fragments, all.stats.fragments, "{what}: two of four equal quads");
                // the compute paths drop exactly what oit-cpu drops (the hardware rasterizer
                // places quad edges by its own rules)
                let path = b.raster_path(&s);
                match (path, cpu_fragments) {
                    (RasterPath::Cpu, _) => cpu_fragments = Some(f.stats.fragments),
                    (RasterPath::Compute, Some(c)) => assert_eq!(f.stats.fragments, c, "{what}"),
                    _ => {}
                }
            }
        }
    }
}

#[test]
fn a_closed_mesh_draws_half_its_fragments_single_sided() {
    let double = scene("spheres:4");
    let mut made = double.clone();
    for o in &mut made.objects {
        o.double_sided = false;
    }
    // through glTF: doubleSided false is written and read back
    let bytes = oit_core::write_glb(&made).expect("writes");
    let single = oit_core::parse_gltf(std::path::Path::new("single.glb"), &bytes, None).expect("reads back");
    assert!(single.objects.iter().all(|o| !o.double_sided), "doubleSided false read back");
    assert!(single.warnings.is_empty(), "{:?}", single.warnings);
    let base = settings(64, "reference");
    let cam: Camera = camera(&double, &base, oit_core::View::default());
    let mut cpu_fragments = None;
    for backend in backends() {
        let b = backend.as_ref();
        let what = label(b);
        let both = render(b, &double, &cam, &base);
        let reference = render(b, &single, &cam, &base);
        checks::accounting(&reference).unwrap_or_else(|e| panic!("{what}: {e}"));
        let (one, two) = (reference.stats.fragments, both.stats.fragments);
        eprintln!("{what}: {one} fragments single-sided, {two} double-sided");
        // each covered pixel centre: one front and one back fragment of each sphere, but for
        // triangles edge-on at a silhouette
        assert!(
            (2 * one).abs_diff(two) * 100 <= two,
            "{what}: {one} fragments single-sided, not half the {two} double-sided"
        );
        // the deepest pixel: the four fronts, not eight layers
        assert_eq!(reference.stats.max_layers, 4, "{what}");
        assert_eq!(both.stats.max_layers, 8, "{what}");
        match (b.raster_path(&base), cpu_fragments) {
            (RasterPath::Cpu, _) => cpu_fragments = Some(one),
            (RasterPath::Compute, Some(c)) => assert_eq!(one, c, "{what}: oit-cpu's fragments"),
            _ => {}
        }
        for t in ["dp", "fabs", "ll", "dfb"] {
            let f = render(b, &single, &cam, &Settings { technique: t.parse().unwrap(), ..base.clone() });
            checks::exact(&reference, &f).unwrap_or_else(|e| panic!("{what} {t}: {e}"));
            assert_eq!(f.stats.fragments, one, "{what} {t}");
        }
    }
}
