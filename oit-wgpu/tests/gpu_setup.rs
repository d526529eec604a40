//! The compute path's GPU setup (oit-shaders' `wgsl/core/setup.wgsl`) against oit-core's host setup: the
//! triangles it writes equal `TriangleSetup::triangle_words` bit for bit, and its work list holds
//! the same (triangle, 8×8 tile) pairs, on the bunny, procedural scenes, tiny and huge scales, and
//! views whose near and far planes cut through the scene or whose narrow field of view sends the
//! geometry past the guard band, and single-sided objects (back faces dropped), one mirrored. The GPU writes pieces in an order of its choosing (no result
//! depends on it), so both sides are compared as sorted lists; each piece's items lie together,
//! in row-major order (what the resolves' speed depends on).

use glam::Vec3;
use oit_core::setup::{TRIANGLE_WORDS, TriangleSetup};
use oit_core::{Camera, RasterPath, Scene, Settings, View, load_scene};

const BUNNY: &str = "bunny";

fn settings() -> Settings {
    Settings { width: 203, height: 150, raster: Some(RasterPath::Compute), ..Settings::default() }
}

/// The cameras each scene is set up under: the fitted orbit; one whose near and far planes cut
/// the scene; one so narrow that most triangles reach past the guard band (64 viewport widths).
fn cameras(scene: &Scene) -> Vec<(&'static str, Camera)> {
    let s = settings();
    let aspect = s.width as f32 / s.height as f32;
    let bounds = scene.bounds();
    let (c, r) = (bounds.center(), (bounds.max - bounds.min).length() * 0.5);
    let eye = c + Vec3::new(0.3, 0.4, 1.5) * r;
    let d = (eye - c).length();
    vec![
        (
            "orbit",
            Camera::orbit_scene(scene, View { azimuth: 30.0, elevation: 20.0, ..View::default() }, aspect)
                .unwrap(),
        ),
        ("near and far cut", Camera::look_at(eye, c, 50.0, aspect, d - 0.3 * r, d + 0.2 * r)),
        ("guard band", Camera::look_at(c + Vec3::new(0.0, 0.1, 0.6) * r, c, 0.4, aspect, 0.01 * r, 4.0 * r)),
    ]
}

/// A work item by its triangle's words and its tile.
type Item = (Vec<u32>, u32);

/// Triangles (44 words each) sorted, and work items as (triangle's words, tile) sorted.
fn canonical(words: &[u32], items: &[[u32; 2]]) -> (Vec<Vec<u32>>, Vec<Item>) {
    let tris: Vec<Vec<u32>> = words.chunks_exact(TRIANGLE_WORDS).map(<[u32]>::to_vec).collect();
    let mut list: Vec<Item> = items.iter().map(|&[t, tile]| (tris[t as usize].clone(), tile)).collect();
    let mut tris = tris;
    tris.sort_unstable();
    list.sort_unstable();
    (tris, list)
}

/// Whether each piece's work items lie together in the list, its tiles in row-major order: the
/// raster kernel takes items in list order, so a pixel's fragments then arrive piece by piece,
/// which the resolves' sorts are fast on (setup.wgsl's `setup_items_main`).
fn pieces_lie_together(items: &[[u32; 2]]) -> Result<(), String> {
    let mut seen = std::collections::HashSet::new();
    for (i, pair) in items.windows(2).enumerate() {
        let ([t0, tile0], [t1, tile1]) = (pair[0], pair[1]);
        if t0 == t1 && tile1 <= tile0 {
            return Err(format!("piece {t0}: tile {tile1:#x} after {tile0:#x} (item {})", i + 1));
        }
        if t0 != t1 && !seen.insert(t0) {
            return Err(format!("piece {t0}'s items are split (item {i})"));
        }
    }
    if let Some(&[t, _]) = items.last()
        && seen.contains(&t)
    {
        return Err(format!("piece {t}'s items are split (the last)"));
    }
    Ok(())
}

/// Scene `name` with every object single-sided and its second instance mirrored in x: the
/// setup drops back faces by the sign of the snapped area, turned over under the mirror
/// (`oit_core::setup::back_face_sign`).
fn single_sided(name: &str) -> Scene {
    let mut scene = load_scene(name).unwrap();
    scene.objects.iter_mut().for_each(|o| o.double_sided = false);
    scene.instances[1].transform *= glam::Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    scene
}

#[test]
fn gpu_setup_equals_host_setup() {
    let Some(backend) = oit_wgpu::backend_or_skip("gpu_setup_equals_host_setup") else { return };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let mut scenes = vec![
        "default".to_string(),
        "planes:8".into(),
        "spheres:4".into(),
        "coplanar".into(),
        "near:6".into(),
        "scale:1e-20:planes:8".into(),
        "scale:1e20:knot".into(),
        "scale:1e-30:spheres:3".into(),
        // more large pieces than `setup_items_main` spreads (oit-core's `SPREAD_PIECES`): the
        // rest write their own work items
        "planes:1100".into(),
    ];
    scenes.push(BUNNY.into());
    scenes.push(format!("grid:2x2:{BUNNY}"));
    let mut scenes: Vec<(String, Scene)> =
        scenes.into_iter().map(|name| (name.clone(), load_scene(&name).unwrap())).collect();
    scenes.push(("single-sided".into(), single_sided(&format!("grid:2x2:{BUNNY}"))));
    let mut split = 0;
    for (name, scene) in &scenes {
        for (view, camera) in cameras(scene) {
            // the whole frame, and a window of it (a screen tile: `Settings::region`)
            let window = Settings {
                width: 80,
                height: 61,
                region: Some(oit_core::Region { x: 97, y: 40, full_width: 203, full_height: 150 }),
                ..settings()
            };
            for (boxes, s) in
                [(false, settings()), (true, settings()), (false, window.clone()), (true, window)]
            {
                let host = if boxes {
                    TriangleSetup::bounding_boxes(scene, &camera, &s)
                } else {
                    TriangleSetup::new(scene, &camera, &s)
                };
                let (host_tris, host_list) = canonical(&host.triangle_words(), &host.work_items(8));
                // through the vertex cache (each vertex transformed once) and without it
                for cache in [true, false] {
                    let view = format!("{view}, region {:?}, vertex cache {cache}", s.region);
                    let (words, items) =
                        oit_wgpu::ComputeRaster::setup_words(gpu, scene, &camera, &s, boxes, true, cache)
                            .unwrap_or_else(|e| panic!("{name}, {view}: {e}"));
                    pieces_lie_together(&items)
                        .unwrap_or_else(|e| panic!("{name}, {view}, boxes {boxes}: {e}"));
                    let (gpu_tris, gpu_items) = canonical(&words, &items);
                    assert_eq!(
                        gpu_tris.len(),
                        host_tris.len(),
                        "{name}, {view}, boxes {boxes}: triangle count"
                    );
                    for (g, h) in gpu_tris.iter().zip(&host_tris) {
                        assert_eq!(g, h, "{name}, {view}, boxes {boxes}: a triangle differs (gpu, host)");
                    }
                    assert!(gpu_items == host_list, "{name}, {view}, boxes {boxes}: the work lists differ");
                }
                let mut prims: Vec<u32> = host.triangles.iter().map(|t| t.prim).collect();
                let n = prims.len();
                prims.dedup();
                split += n - prims.len();
            }
        }
    }
    // the views do clip: some triangles came out in more than one piece
    assert!(split > 0, "no triangle was clipped into pieces: the views test nothing of clipping");
}
