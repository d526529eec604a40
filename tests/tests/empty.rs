//! Frames with no fragments (issue 13.8): a camera looking away from the scene, and a degenerate
//! (zero-area) mesh. Every technique, every effect, on every backend × path: the background (or
//! the reference's picture for the heat map), 0 fragments, 0 lost, no error — zero-sized storage
//! is handled wherever a size follows the fragment count.

use glam::Vec3;
use oit_core::{Camera, Effect, Scene, Settings, Technique};
use oit_tests::*;

fn all_techniques() -> Vec<Technique> {
    let mut t = vec![Technique::Reference];
    t.extend(Technique::all());
    t.extend([
        Technique::Bdp { passes: 3 },
        Technique::Fabs { k: Some(4) },
        Technique::Mdts { k: Some(4) },
        Technique::Mdts64 { k: Some(4) },
        Technique::Mlp { m: 1 },
    ]);
    t
}

const EFFECTS: [Effect; 4] =
    [Effect::Transparency, Effect::Translucency, Effect::Fresnel, Effect::Complexity];

fn check_empty(backend: &dyn oit_core::Backend, scene: &Scene, cam: &Camera, size: (u32, u32), what: &str) {
    let mut prepared = backend.prepare(scene).unwrap_or_else(|e| panic!("{what}: {e}"));
    for effect in EFFECTS {
        let base = Settings { width: size.0, height: size.1, effect, ..Settings::default() };
        let reference = prepared
            .frame(cam, &Settings { technique: Technique::Reference, ..base.clone() })
            .unwrap_or_else(|e| panic!("{what} reference {effect:?}: {e}"));
        for t in all_techniques() {
            let s = Settings { technique: t, ..base.clone() };
            let f = match prepared.frame(cam, &s) {
                Ok(f) => f,
                // refusals of technique × effect (the same on every scene): not this issue
                Err(oit_core::OitError::Unsupported { .. }) if effect != Effect::Transparency => continue,
                Err(e) => panic!("{} {what} {t} {effect:?}: {e}", label(backend)),
            };
            let w = format!("{} {what} {t} {effect:?}", label(backend));
            assert_eq!((f.stats.fragments, f.stats.captured, f.stats.lost), (0, 0, 0), "{w}");
            assert_eq!(f.image, reference.image, "{w}: not the reference's picture");
            if effect != Effect::Complexity {
                let bg = base.background.to_array().map(oit_core::composite::linear_to_srgb8);
                assert!(f.image.pixels.iter().all(|p| p[..3] == bg), "{w}: not the background");
            }
        }
    }
}

#[test]
fn camera_looking_away() {
    for backend in backends_for("camera_looking_away") {
        let scene = scene("default");
        let c = scene.bounds().center();
        let r = scene.bounds().radius().max(1.0);
        let eye = c + Vec3::new(0.0, 0.0, 3.0 * r);
        let cam = Camera::look_at(eye, eye + Vec3::Z, 45.0, 1.0, 0.1 * r, 10.0 * r);
        check_empty(backend.as_ref(), &scene, &cam, (16, 16), "looking away");
        check_empty(backend.as_ref(), &scene, &cam, (2, 1), "looking away 2x1");
    }
}

#[test]
fn degenerate_mesh() {
    for backend in backends_for("degenerate_mesh") {
        let planes = scene("planes:2");
        let s = settings(16, "reference");
        let cam = camera(&planes, &s, FRONT);
        // every vertex moved onto one line: triangles of zero area cover no pixel centre
        let mut flat = planes.clone();
        for mesh in &mut flat.meshes {
            for p in &mut mesh.positions {
                *p = Vec3::new(p.x, p.x, p.z);
            }
        }
        check_empty(backend.as_ref(), &flat, &cam, (16, 16), "degenerate mesh");
    }
}
