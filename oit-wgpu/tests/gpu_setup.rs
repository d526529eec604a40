//! The compute path's GPU setup (oit-shaders' `wgsl/core/setup.wgsl`) against oit-core's host setup: the
//! triangles it writes equal `TriangleSetup::triangle_words` bit for bit, and its work list holds
//! the same (triangle, 8×8 tile) pairs, on the bunny, procedural scenes, tiny and huge scales, and
//! views whose near and far planes cut through the scene or whose narrow field of view sends the
//! geometry past the guard band, and single-sided objects (back faces dropped), one mirrored. The GPU writes pieces in an order of its choosing (no result
//! depends on it), so both sides are compared as sorted lists; each piece's items lie together,
//! in row-major order (what the resolves' speed depends on). The work list's row runs
//! (`row_run`) are also held to the host's tile rule directly, on triangles built to put edges
//! through tiles' corners.

mod kernel;

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

/// setup.wgsl's `row_run` (the tiles of a row its work list keeps, on the GPU) against the
/// host's rule, `Triangle::may_cover` tile by tile, row by row, on 20,000 triangles whose
/// vertices lie on an 8×8 tile's corner or one 1/256 pixel to either side of it, where the
/// solved turn's floors are off by one if anywhere, and anywhere in a 256² frame, in both
/// windings. A scene's work list (above) rarely puts an edge exactly through a tile's corner.
#[test]
fn gpu_row_runs_keep_the_tiles_the_host_keeps() {
    use oit_core::setup::{HALF_PIXEL, SUBPIXEL, Triangle};
    use wgpu::util::DeviceExt;
    const TILE: u32 = 8;
    let Some(backend) = oit_wgpu::backend_or_skip("gpu_row_runs_keep_the_tiles_the_host_keeps") else {
        return;
    };
    let gpu = backend.gpu().expect("opened by backend_or_skip");
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut words, mut cases, mut expected) = (Vec::new(), Vec::new(), Vec::new());
    for n in 0..20_000u32 {
        let width = i64::from(TILE) * SUBPIXEL;
        let mut coordinate = || -> i32 {
            if n % 3 == 0 {
                (next() % (256 * SUBPIXEL as u64)) as i32
            } else {
                let corner = (next() % u64::from(256 / TILE)) as i64 * width;
                (corner + [-1, 0, 0, 1][(next() % 4) as usize]) as i32
            }
        };
        let x = [0; 3].map(|_| coordinate());
        let y = [0; 3].map(|_| coordinate());
        let pixel = |v: i32| (i64::from(v) - HALF_PIXEL).div_euclid(SUBPIXEL).clamp(0, 255) as u32;
        let (xs, ys) = (x.map(pixel), y.map(pixel));
        let bbox = [
            xs[0].min(xs[1]).min(xs[2]),
            ys[0].min(ys[1]).min(ys[2]),
            xs[0].max(xs[1]).max(xs[2]),
            ys[0].max(ys[1]).max(ys[2]),
        ];
        let t = Triangle {
            x,
            y,
            z: [0.0; 3],
            inv_w: [1.0; 3],
            normal: [Vec3::Z; 3],
            color: [Vec3::ONE; 3],
            inv_area: 0.0,
            base: glam::Vec4::ONE,
            has_color: false,
            prim: n,
            bbox,
            uv: [glam::Vec2::ZERO; 3],
            texture: oit_core::setup::NO_TEXTURE,
            lod: 0,
            cutoff: 0.0,
        };
        // row_run reads a piece's snapped x and y (words 0..6) and its box (words 37..41)
        let mut tri = [0u32; TRIANGLE_WORDS];
        for k in 0..3 {
            tri[k] = x[k] as u32;
            tri[3 + k] = y[k] as u32;
        }
        tri[37..41].copy_from_slice(&bbox);
        words.extend_from_slice(&tri);
        let [x0, y0, x1, y1] = bbox;
        for ty in y0 / TILE..=y1 / TILE {
            cases.push([n, ty, x0 / TILE, x1 / TILE]);
            let kept: Vec<u32> = (x0 / TILE..=x1 / TILE).filter(|&tx| t.may_cover(tx, ty, TILE)).collect();
            // a row's kept tiles are one run (`RowEdges::run`)
            assert!(kept.windows(2).all(|w| w[1] == w[0] + 1), "triangle {n}, row {ty}: {kept:?}");
            expected.push(kept.first().map_or([0, 0], |&first| [first, first + kept.len() as u32]));
        }
    }
    let kernel = format!(
        "{}\n{}",
        oit_shaders::SETUP,
        r#"
@compute @workgroup_size(64)
fn row_runs_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 64u;
    if (i >= arrayLength(&out_items)) {
        return;
    }
    // case i: piece, row, the box's first and last tile column (in `instances`, four words)
    let run = row_run(instances[4u * i] * TRI_WORDS, instances[4u * i + 1u], instances[4u * i + 2u], instances[4u * i + 3u]);
    // an empty run as [0, 0], as the host's expectation writes it
    out_items[i] = select(vec2<u32>(0u, 0u), run, run.y > run.x);
}
"#
    );
    let device = &gpu.device;
    let buffer = |contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage })
    };
    let input = buffer(bytemuck::cast_slice(&cases), wgpu::BufferUsages::STORAGE);
    let tris = buffer(bytemuck::cast_slice(&words), wgpu::BufferUsages::STORAGE);
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (cases.len() * 8) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let entry = kernel::storage_entry;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[entry(1, true), entry(3, false), entry(4, false)],
    });
    let pipeline = gpu.compute_pipeline(&kernel, "row_runs_main", &[&layout]).expect("kernel builds");
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 1, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 3, resource: tris.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 4, resource: output.as_entire_binding() },
        ],
    });
    kernel::dispatch(gpu, &pipeline, &group, cases.len() as u64);
    let got = gpu.read_u32(&output).expect("runs read back");
    let mut turned = 0;
    for (i, (case, want)) in cases.iter().zip(&expected).enumerate() {
        let run = [got[2 * i], got[2 * i + 1]];
        assert_eq!(
            run, *want,
            "case {i}: triangle {} row {}, box columns {}..={}",
            case[0], case[1], case[2], case[3]
        );
        turned += usize::from(want[1] > want[0] && (want[0] > case[2] || want[1] <= case[3]));
    }
    assert!(turned > 1000, "{turned} of {} rows end inside their box", cases.len());
}
