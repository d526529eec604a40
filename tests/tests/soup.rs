//! Random triangle soups (proptest; the seed is fixed by proptest's deterministic runner in CI):
//! the reference does not depend on triangle order, and depth peeling equals the reference.

use glam::{Vec3, Vec4};
use oit_core::metrics::accuracy;
use oit_core::{Mesh, Scene, Settings, Technique, View};
use oit_tests::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

fn soup(points: &[(f32, f32, f32)], colors: &[(f32, f32, f32, f32)]) -> Scene {
    let tris = points.len() / 3;
    let mut meshes = Vec::new();
    let mut scene = Scene { name: "soup".into(), ..Default::default() };
    for t in 0..tris {
        let p: Vec<Vec3> = points[3 * t..3 * t + 3].iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        meshes.push(Mesh::new(format!("t{t}"), p, vec![[0, 1, 2]]));
        let (r, g, b, a) = colors[t % colors.len()];
        scene.objects.push(oit_core::Object::new(format!("t{t}"), t, Vec4::new(r, g, b, a)));
        scene.instances.push(oit_core::Instance { object: t, transform: glam::Mat4::IDENTITY });
    }
    scene.meshes = meshes;
    scene
}

#[test]
fn random_soups() {
    let config = Config { cases: 24, failure_persistence: None, ..Config::default() };
    let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]));
    let strategy = (
        prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 9..60),
        prop::collection::vec((0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0, 0.05f32..0.95), 1..8),
        any::<u64>(),
    );
    runner
        .run(&strategy, |(points, colors, shuffle_seed)| {
            let n = points.len() / 3 * 3;
            let scene = soup(&points[..n], &colors);
            // the same triangles in another order
            let mut order: Vec<usize> = (0..n / 3).collect();
            let mut s = shuffle_seed | 1;
            for i in (1..order.len()).rev() {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                order.swap(i, (s % (i as u64 + 1)) as usize);
            }
            let shuffled_points: Vec<_> =
                order.iter().flat_map(|&t| points[3 * t..3 * t + 3].to_vec()).collect();
            let shuffled_colors: Vec<_> = order.iter().map(|&t| colors[t % colors.len()]).collect();
            let shuffled = soup(&shuffled_points, &shuffled_colors);
            for backend in backends_for("random_soups") {
                eprintln!("on {}", label(backend.as_ref()));
                let b = backend.as_ref();
                let base = Settings { ..settings(48, "reference") };
                let view = View { azimuth: 10.0, elevation: 15.0, fov: 50.0, ..View::default() };
                let cam = camera(&scene, &base, view);
                let r1 = render(b, &scene, &cam, &base);
                let r2 = render(b, &shuffled, &cam, &base);
                prop_assert_eq!(&r1.image, &r2.image);
                let dp = render(b, &scene, &cam, &Settings { technique: Technique::Dp, ..base.clone() });
                let a = accuracy(&r1, &dp.image).unwrap();
                prop_assert_eq!(a.epr, 0.0);
            }
            Ok(())
        })
        .unwrap();
}
