//! Criterion bench of issue 39's loading target: "a 1M-triangle `.glb` loads in less time than
//! one CPU frame of it at 1024² (same run)". The setup writes a GLB of 1,000,000 triangles (a
//! wavy 500 × 1000-quad sheet folded over itself three times, so that pixels see several layers;
//! positions, normals and u32 indices in the binary chunk, one BLEND material at alpha 0.5) to
//! the system's temporary folder, then two benches of the group `gltf_load` run side by side:
//!
//! - `load_1m_triangles`: `oit_core::load_gltf` of the file (read, checked, meshes built);
//! - `cpu_frame_1024`: one frame of the loaded scene on the CPU backend at 1024 × 1024, with the
//!   technique `oit render` draws by default (the reference).
//!
//! The target holds when the first's time is below the second's. Not part of `cargo test` (the
//! file is 36 MB and the frame takes a while on a small machine): run it with
//! `cargo bench -p oit-bench --bench gltf_load`, or once each with
//! `cargo bench -p oit-bench --bench gltf_load -- --test`.

use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use oit_core::{Camera, Settings, Technique, View};

/// Quads across and along the sheet: 2 × 500 × 1000 = 1,000,000 triangles.
const QUADS: (u32, u32) = (500, 1000);

/// Image side of the frame.
const SIDE: u32 = 1024;

/// A GLB of `json` and `bin`, chunks padded as the format asks.
fn pack(json: &str, bin: &[u8]) -> Vec<u8> {
    oit_core::pack_glb(json.as_bytes(), bin).expect("a GLB under 4 GiB")
}

/// Writes the 1M-triangle GLB and returns its path.
fn write_glb() -> PathBuf {
    let (nx, ny) = QUADS;
    let (vx, vy) = (nx + 1, ny + 1);
    let vertices = (vx * vy) as usize;
    let mut positions = Vec::with_capacity(vertices * 12);
    let mut normals = Vec::with_capacity(vertices * 12);
    let (mut min, mut max) = ([f32::MAX; 3], [f32::MIN; 3]);
    for j in 0..vy {
        for i in 0..vx {
            // a sheet along y, folded over itself: x runs 0..1, y zig-zags through three layers
            let u = i as f32 / nx as f32;
            let v = j as f32 / ny as f32;
            let t = v * 3.0;
            let layer = t.floor().min(2.0);
            let along = if (layer as u32).is_multiple_of(2) { t - layer } else { 1.0 - (t - layer) };
            let p = [u, along, 0.2 * layer + 0.03 * (u * 20.0).sin()];
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
            p.iter().for_each(|c| positions.extend_from_slice(&c.to_le_bytes()));
            [0f32, 0.0, 1.0].iter().for_each(|c| normals.extend_from_slice(&c.to_le_bytes()));
        }
    }
    let mut indices = Vec::with_capacity((nx * ny * 6 * 4) as usize);
    for j in 0..ny {
        for i in 0..nx {
            let a = j * vx + i;
            for k in [a, a + 1, a + vx + 1, a, a + vx + 1, a + vx] {
                indices.extend_from_slice(&k.to_le_bytes());
            }
        }
    }
    let (p_len, n_len, i_len) = (positions.len(), normals.len(), indices.len());
    let mut bin = positions;
    bin.extend_from_slice(&normals);
    bin.extend_from_slice(&indices);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"name":"sheet","primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"material":0}}]}}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.2,0.6,1.0,0.5]}},"alphaMode":"BLEND","doubleSided":true}}],
        "buffers":[{{"byteLength":{}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{p_len}}},{{"buffer":0,"byteOffset":{p_len},"byteLength":{n_len}}},
                       {{"buffer":0,"byteOffset":{},"byteLength":{i_len}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{vertices},"type":"VEC3","min":{min:?},"max":{max:?}}},
                     {{"bufferView":1,"componentType":5126,"count":{vertices},"type":"VEC3"}},
                     {{"bufferView":2,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        p_len + n_len,
        i_len / 4
    );
    let path = std::env::temp_dir().join(format!("oit-gltf-load-{}.glb", std::process::id()));
    std::fs::write(&path, pack(&json, &bin)).expect("the temporary folder takes the GLB");
    path
}

fn gltf_load(c: &mut Criterion) {
    let path = write_glb();
    let scene = oit_core::load_gltf(&path, None).expect("the generated GLB loads");
    assert_eq!(scene.triangle_count(), 2 * u64::from(QUADS.0) * u64::from(QUADS.1));
    let options = oit_bench::backends::BackendOptions { threads: None, adapter: None };
    let cpu = oit_bench::backends::select("cpu", &options).expect("the cpu backend").remove(0);
    let camera = Camera::orbit_scene(&scene, View::default(), 1.0).expect("the sheet is framed");
    let settings =
        Settings { width: SIDE, height: SIDE, technique: Technique::Reference, ..Settings::default() };
    let mut group = c.benchmark_group("gltf_load");
    group.sampling_mode(SamplingMode::Flat).sample_size(10).warm_up_time(Duration::from_millis(500));
    group.bench_function("load_1m_triangles", |b| {
        b.iter(|| oit_core::load_gltf(&path, None).expect("loads"));
    });
    group.bench_function("cpu_frame_1024", |b| {
        b.iter(|| cpu.render(&scene, &camera, &settings).expect("renders"));
    });
    group.finish();
    let _ = std::fs::remove_file(&path);
}

criterion_group!(benches, gltf_load);
criterion_main!(benches);
