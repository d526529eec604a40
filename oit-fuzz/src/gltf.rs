//! The `gltf` target's inputs: the seed GLBs the harness writes itself (`--write-gltf-seeds`,
//! committed in `tests/fuzz/corpus/gltf/`), the scene set's GLBs (`oit_core::scene_set`) and any
//! other glTF file of the repository listed in [`ASSET_SEEDS`] as more seeds, and the mutator that knows the format: it splits a GLB into its JSON and
//! binary chunks, edits the JSON where the loader's checks are (counts, offsets, lengths, strides,
//! component types, indices, URIs, sparse accessors, node children), edits the binary chunk
//! (indices and floats), cuts the file in its header or a chunk, and packs the GLB again, with its
//! header's length mended or not.

use std::f64::consts::FRAC_1_SQRT_2;
use std::path::Path;

use serde_json::{Value, json};

use crate::dictionary::Rng;

/// glTF files of the repository the `gltf` target also starts from, besides every scene of the
/// scene set (`oit_core::scene_set::SCENE_SET`, which are seeds by themselves): paths relative to
/// the repository's root, one a line, so a file is one more line here. A file that is not there is
/// skipped; a seed larger than [`POOL_MAX_BYTES`] is replayed but not mutated.
pub const ASSET_SEEDS: &[&str] = &[
    // e.g. "models/lamp.glb",
];

/// The largest input the `gltf` target mutates: a larger seed (a real scene of megabytes) is
/// replayed once, and its mutants would spend the run's seconds parsing it again.
pub const POOL_MAX_BYTES: usize = 256 << 10;

/// The scene set's GLBs (decompressed), then the files of [`ASSET_SEEDS`] that exist.
pub fn asset_seeds() -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let set = oit_core::scene_set::SCENE_SET.iter().filter_map(|s| s.glb().ok());
    set.chain(ASSET_SEEDS.iter().filter_map(|p| std::fs::read(root.join(p)).ok())).collect()
}

/// A GLB of `json` and `bin` (the binary chunk left out when empty), chunks padded as the format
/// asks.
pub fn pack(json: &[u8], bin: &[u8]) -> Vec<u8> {
    oit_core::pack_glb(json, bin).expect("a fuzz input is far below 4 GiB")
}

/// The JSON and binary chunks of a GLB, read leniently (what is there, as far as it goes); a
/// file that is not a GLB is all JSON.
pub fn unpack(input: &[u8]) -> (Vec<u8>, Vec<u8>) {
    if !input.starts_with(b"glTF") || input.len() < 20 {
        return (input.to_vec(), Vec::new());
    }
    let word = |at: usize| {
        input.get(at..at + 4).map_or(0, |w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize)
    };
    let json_len = word(12).min(input.len() - 20);
    let json = input[20..20 + json_len].to_vec();
    let bin_at = 20 + json_len + 8;
    let bin = if input.len() > bin_at {
        let len = word(bin_at - 8).min(input.len() - bin_at);
        input[bin_at..bin_at + len].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// The bytes of `values` as little-endian f32s.
fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A 2×2 RGBA PNG (red, green at half alpha, blue at a quarter, white), its image data one
/// stored deflate block: the harness does not depend on an image encoder.
fn png() -> Vec<u8> {
    let rows: [[u8; 9]; 2] = [[0, 255, 0, 0, 255, 0, 255, 0, 128], [0, 0, 0, 255, 64, 255, 255, 255, 255]];
    let raw: Vec<u8> = rows.concat();
    let (mut a, mut b) = (1u32, 0u32);
    for &x in &raw {
        a = (a + u32::from(x)) % 65521;
        b = (b + a) % 65521;
    }
    let mut zlib = vec![0x78, 0x01, 0x01];
    zlib.extend_from_slice(&(raw.len() as u16).to_le_bytes());
    zlib.extend_from_slice(&(!(raw.len() as u16)).to_le_bytes());
    zlib.extend_from_slice(&raw);
    zlib.extend_from_slice(&((b << 16) | a).to_be_bytes());
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let crc = crc32fast::hash(&out[start..]);
        out.extend_from_slice(&crc.to_be_bytes());
    };
    chunk(b"IHDR", &[0, 0, 0, 2, 0, 0, 0, 2, 8, 6, 0, 0, 0]);
    chunk(b"IDAT", &zlib);
    chunk(b"IEND", &[]);
    out
}

/// The seed GLBs, by file name: small files that reach every part of the loader — nodes with
/// transforms and children, indexed and plain triangles, strips and fans, normals, u8 vertex
/// colours, a textured material with a sampler, MASK and BLEND with transmission, two scenes,
/// an interleaved buffer view, u32 indices, and a `.gltf` whose buffer is a data URI.
pub fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    // a unit quad: 4 positions (48 bytes), 6 u16 indices (12), 4 normals (48), 4 uvs (32), 4
    // RGBA8 colours (16), then the PNG
    let mut bin = floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]);
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend(floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.]));
    bin.extend(floats(&[0., 0., 1., 0., 1., 1., 0., 1.]));
    bin.extend_from_slice(&[255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 64, 255, 255, 255, 255]);
    let png_at = bin.len();
    let png = png();
    bin.extend_from_slice(&png);
    let views = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": 12},
        {"buffer": 0, "byteOffset": 60, "byteLength": 48},
        {"buffer": 0, "byteOffset": 108, "byteLength": 32},
        {"buffer": 0, "byteOffset": 140, "byteLength": 16},
        {"buffer": 0, "byteOffset": png_at, "byteLength": png.len()},
    ]);
    let accessors = json!([
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
        {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
        {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC2"},
        {"bufferView": 4, "componentType": 5121, "count": 4, "type": "VEC4", "normalized": true},
    ]);
    let doc = |scenes: Value, nodes: Value, meshes: Value, materials: Value, extra: Value| {
        let mut d = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": scenes,
            "nodes": nodes,
            "meshes": meshes,
            "materials": materials,
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": views,
            "accessors": accessors,
        });
        if let (Some(d), Some(extra)) = (d.as_object_mut(), extra.as_object()) {
            d.extend(extra.clone());
        }
        serde_json::to_vec(&d).unwrap_or_default()
    };
    let blend = json!([{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0, 0.5]}, "alphaMode": "BLEND", "doubleSided": true}]);
    let indexed = json!([{"name": "quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1, "material": 0}]}]);
    let mut out = Vec::new();
    out.push((
        "quad.glb",
        pack(
            &doc(json!([{"nodes": [0]}]), json!([{"mesh": 0}]), indexed.clone(), blend.clone(), json!({})),
            &bin,
        ),
    ));
    // a hierarchy: translation, rotation, scale and a matrix, children two deep
    out.push((
        "nodes.glb",
        pack(
            &doc(
                json!([{"nodes": [0, 3]}]),
                json!([
                    {"mesh": 0, "translation": [1, 0, 0], "children": [1]},
                    {"mesh": 0, "rotation": [0, FRAC_1_SQRT_2, 0, FRAC_1_SQRT_2], "children": [2]},
                    {"mesh": 0, "scale": [2, 2, 2]},
                    {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -2, 1]},
                ]),
                indexed.clone(),
                blend.clone(),
                json!({}),
            ),
            &bin,
        ),
    ));
    // strips and fans without indices, u8 colours, MASK with transmission (the mutator's edits of
    // "mode" reach points and lines)
    out.push((
        "modes.glb",
        pack(
            &doc(
                json!([{"nodes": [0, 1, 2]}]),
                json!([{"mesh": 0}, {"mesh": 1}, {"mesh": 2}]),
                json!([
                    {"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 4}, "mode": 5, "material": 0}]},
                    {"primitives": [{"attributes": {"POSITION": 0}, "mode": 6, "material": 0}]},
                    {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
                ]),
                json!([{"alphaMode": "MASK", "alphaCutoff": 0.25, "doubleSided": true,
                        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.75}}}]),
                json!({"extensionsUsed": ["KHR_materials_transmission"]}),
            ),
            &bin,
        ),
    ));
    // the textured quad: TEXCOORD_0, a PNG in the binary chunk, a sampler
    out.push((
        "textured.glb",
        pack(
            &doc(
                json!([{"nodes": [0]}]),
                json!([{"mesh": 0}]),
                json!([{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 3}, "indices": 1, "material": 0}]}]),
                json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, "alphaMode": "BLEND", "doubleSided": true}]),
                json!({"textures": [{"source": 0, "sampler": 0}], "samplers": [{"wrapS": 33071, "wrapT": 33648}],
                       "images": [{"bufferView": 5, "mimeType": "image/png"}]}),
            ),
            &bin,
        ),
    ));
    // two scenes, the second the default
    let mut two = serde_json::from_slice::<Value>(&doc(
        json!([{"nodes": [0]}, {"nodes": [1, 2]}]),
        json!([{"mesh": 0}, {"mesh": 0, "translation": [0, 0, 1]}, {"mesh": 0, "translation": [0, 0, 2]}]),
        indexed.clone(),
        blend.clone(),
        json!({}),
    ))
    .unwrap_or_default();
    two["scene"] = json!(1);
    out.push(("two-scenes.glb", pack(&serde_json::to_vec(&two).unwrap_or_default(), &bin)));
    // positions and normals interleaved in one view (stride 24), u32 indices
    let mut interleaved = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        interleaved.extend(floats(&p));
        interleaved.extend(floats(&[0., 0., 1.]));
    }
    for i in [0u32, 1, 2, 0, 2, 3] {
        interleaved.extend_from_slice(&i.to_le_bytes());
    }
    let strided = json!({
        "asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "buffers": [{"byteLength": interleaved.len()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 24},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"}],
    });
    out.push(("interleaved.glb", pack(&serde_json::to_vec(&strided).unwrap_or_default(), &interleaved)));
    // a .gltf (JSON alone) whose buffer is a base64 data URI
    let mut data_uri = strided.clone();
    data_uri["buffers"][0]["uri"] =
        json!(format!("data:application/octet-stream;base64,{}", base64(&interleaved)));
    out.push(("data-uri.gltf", serde_json::to_vec(&data_uri).unwrap_or_default()));
    out
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = u32::from_be_bytes([0, c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)]);
        for k in 0..4 {
            out.push(if k <= c.len() { ALPHABET[(n >> (18 - 6 * k)) as usize & 63] as char } else { '=' });
        }
    }
    out
}

/// Writes [`seeds`] into `dir` (the committed corpus is written so).
pub fn write_seeds(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for (name, bytes) in seeds() {
        std::fs::write(dir.join(name), bytes)?;
    }
    Ok(())
}

/// Keys whose numbers the loader checks: the JSON edits pick among them.
const KEYS: &[&str] = &[
    "count",
    "byteOffset",
    "byteLength",
    "byteStride",
    "componentType",
    "bufferView",
    "buffer",
    "indices",
    "mode",
    "material",
    "mesh",
    "scene",
    "source",
    "index",
    "texCoord",
    "POSITION",
    "NORMAL",
    "TEXCOORD_0",
    "COLOR_0",
    "sampler",
    "wrapS",
    "alphaCutoff",
];

/// Numbers at the edges of what the loader checks.
const EDGES: &[f64] = &[
    0.0,
    1.0,
    -1.0,
    2.0,
    3.0,
    4.0,
    7.0,
    12.0,
    255.0,
    256.0,
    65535.0,
    65536.0,
    67_108_864.0,
    67_108_865.0,
    1_073_741_824.0,
    2_147_483_647.0,
    4_294_967_295.0,
    4_294_967_296.0,
    1e15,
    1e30,
    0.5,
    5120.0,
    5121.0,
    5122.0,
    5123.0,
    5125.0,
    5126.0,
];

/// URIs that reach the loader's reader: missing files, folders, devices, the worker's FIFOs,
/// other schemes, broken escapes and broken base64.
const URIS: &[&str] = &[
    "missing.bin",
    ".",
    "..",
    "/dev/zero",
    "/dev/null",
    "hostile/model.obj",
    "%FF%FE.bin",
    "%",
    "file:///dev/zero",
    "https://example.com/a.bin",
    "data:application/octet-stream;base64,",
    "data:application/octet-stream;base64,AAAA*",
    "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA",
    "data:,plain",
    "data:image/png;base64,iVBORw0KGgo=",
];

/// Every number of `v` under a key of [`KEYS`] (or in an array under one), as JSON pointers.
fn number_paths(v: &Value, path: &str, key: Option<&str>, out: &mut Vec<String>) {
    match v {
        Value::Object(map) => {
            for (k, child) in map {
                number_paths(
                    child,
                    &format!("{path}/{}", k.replace('~', "~0").replace('/', "~1")),
                    Some(k),
                    out,
                );
            }
        }
        Value::Array(items) => {
            for (i, child) in items.iter().enumerate() {
                number_paths(child, &format!("{path}/{i}"), key, out);
            }
        }
        Value::Number(_) if key.is_some_and(|k| KEYS.contains(&k) || k == "nodes" || k == "children") => {
            out.push(path.to_string());
        }
        _ => {}
    }
}

/// Every object of `v` that holds `key`, as JSON pointers.
fn objects_with(v: &Value, key: &str, path: &str, out: &mut Vec<String>) {
    match v {
        Value::Object(map) => {
            if map.contains_key(key) {
                out.push(path.to_string());
            }
            for (k, child) in map {
                objects_with(child, key, &format!("{path}/{}", k.replace('~', "~0").replace('/', "~1")), out);
            }
        }
        Value::Array(items) => {
            for (i, child) in items.iter().enumerate() {
                objects_with(child, key, &format!("{path}/{i}"), out);
            }
        }
        _ => {}
    }
}

/// One edit of the parsed JSON.
fn json_edit(rng: &mut Rng, doc: &mut Value) {
    match rng.below(8) {
        0..=2 => {
            // a number the loader checks set to an edge, or moved by one
            let mut paths = Vec::new();
            number_paths(doc, "", None, &mut paths);
            if paths.is_empty() {
                return;
            }
            let path = rng.pick(&paths).clone();
            if let Some(n) = doc.pointer_mut(&path) {
                let old = n.as_f64().unwrap_or(0.0);
                let new = match rng.below(3) {
                    0 => old + 1.0,
                    1 => old - 1.0,
                    _ => *rng.pick(EDGES),
                };
                *n = if new.fract() == 0.0 && new.abs() < 1.8e19 {
                    if new < 0.0 { json!(new as i64) } else { json!(new as u64) }
                } else {
                    json!(new)
                };
            }
        }
        3 => {
            // an accessor's type, or a material's alpha mode
            let mut paths = Vec::new();
            objects_with(doc, "type", "", &mut paths);
            objects_with(doc, "alphaMode", "", &mut paths);
            if paths.is_empty() {
                return;
            }
            let path = rng.pick(&paths).clone();
            if let Some(Value::Object(o)) = doc.pointer_mut(&path) {
                if o.contains_key("type") {
                    o.insert(
                        "type".into(),
                        json!(rng.pick(&["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT4", "X"])),
                    );
                } else {
                    o.insert("alphaMode".into(), json!(rng.pick(&["OPAQUE", "MASK", "BLEND", "blend"])));
                }
            }
        }
        4 => {
            // a key dropped from an object
            let key = *rng.pick(&[
                "bufferView",
                "byteLength",
                "indices",
                "POSITION",
                "min",
                "max",
                "mimeType",
                "uri",
                "nodes",
                "source",
                "asset",
            ]);
            let mut paths = Vec::new();
            objects_with(doc, key, "", &mut paths);
            if paths.is_empty() {
                return;
            }
            let path = rng.pick(&paths).clone();
            if let Some(Value::Object(o)) = doc.pointer_mut(&path) {
                o.remove(key);
            }
        }
        5 => {
            // a URI on a buffer or an image
            let uri = *rng.pick(URIS);
            let list = if rng.one_in(2) { "buffers" } else { "images" };
            if let Some(Value::Array(items)) = doc.get_mut(list)
                && !items.is_empty()
            {
                let i = rng.below(items.len());
                if let Value::Object(o) = &mut items[i] {
                    o.insert("uri".into(), json!(uri));
                    if list == "images" {
                        o.remove("bufferView");
                    }
                }
            }
        }
        6 => {
            // a sparse accessor, or an extension required
            if rng.one_in(2) {
                if let Some(Value::Array(items)) = doc.get_mut("accessors")
                    && !items.is_empty()
                {
                    let i = rng.below(items.len());
                    if let Some(o) = items[i].as_object_mut() {
                        o.insert(
                            "sparse".into(),
                            json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                                   "values": {"bufferView": 0}}),
                        );
                    }
                }
            } else {
                let ext = *rng.pick(&[
                    "KHR_materials_volume",
                    "KHR_draco_mesh_compression",
                    "KHR_materials_transmission",
                ]);
                // (serde_json's `doc[key] = v` panics where `doc` is not an object)
                if let Some(o) = doc.as_object_mut() {
                    o.insert("extensionsRequired".into(), json!([ext]));
                    o.insert("extensionsUsed".into(), json!([ext]));
                }
            }
        }
        _ => {
            // node children that loop or share, or a node list repeated
            if let Some(Value::Array(nodes)) = doc.get_mut("nodes")
                && !nodes.is_empty()
            {
                let n = nodes.len();
                let i = rng.below(n);
                let child = rng.below(n + 1);
                if let Value::Object(o) = &mut nodes[i] {
                    let children = o.entry("children").or_insert_with(|| json!([]));
                    if let Value::Array(c) = children {
                        c.push(json!(child));
                    }
                }
            }
        }
    }
}

/// One glTF-aware edit of `input` (a GLB or a `.gltf`): its JSON or binary chunk edited and the
/// GLB packed again, or the file cut where the loader splits it.
pub fn edit(rng: &mut Rng, input: &mut Vec<u8>) {
    let (json, mut bin) = unpack(input);
    match rng.below(6) {
        0 => {
            // cut in the header, the JSON chunk's header or body, or the binary chunk; one time in
            // two with the header's length mended to the cut
            let len = input.len();
            let json_end = 20 + json.len();
            let at = match rng.below(4) {
                0 => rng.below(12.min(len) + 1),
                1 => 12 + rng.below(8),
                2 => 20 + rng.below(json.len() + 1),
                _ => json_end + rng.below(len.saturating_sub(json_end) + 1),
            }
            .min(len);
            input.truncate(at);
            if rng.one_in(2) && input.len() >= 12 {
                let n = input.len() as u32;
                input[8..12].copy_from_slice(&n.to_le_bytes());
            }
        }
        1 if !bin.is_empty() => {
            // a word of the binary chunk set to an edge (an index past the vertices, a NaN or a
            // huge coordinate)
            let at = rng.below(bin.len() / 2) * 2;
            let value: [u8; 4] = *rng.pick(&[
                [0xff, 0xff, 0xff, 0xff],
                [0x04, 0x00, 0x00, 0x00],
                [0x00, 0x00, 0xc0, 0x7f],
                [0x00, 0x00, 0x80, 0x7f],
                [0xff, 0xff, 0x7f, 0x7f],
                [0x00, 0x00, 0x00, 0x00],
            ]);
            for (k, b) in value.iter().enumerate() {
                if let Some(x) = bin.get_mut(at + k) {
                    *x = *b;
                }
            }
            *input = repack(input, &json, &bin);
        }
        2 if !bin.is_empty() => {
            bin.truncate(rng.below(bin.len()));
            *input = repack(input, &json, &bin);
        }
        _ => {
            let Ok(mut doc) = serde_json::from_slice::<Value>(&json) else {
                // not JSON (any more): a byte edit elsewhere does the work
                return;
            };
            for _ in 0..1 + rng.below(3) {
                json_edit(rng, &mut doc);
            }
            let json = serde_json::to_vec(&doc).unwrap_or_default();
            *input = repack(input, &json, &bin);
        }
    }
}

/// `json` and `bin` packed as `input` was: a GLB again, or JSON alone.
fn repack(input: &[u8], json: &[u8], bin: &[u8]) -> Vec<u8> {
    if input.starts_with(b"glTF") { pack(json, bin) } else { json.to_vec() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_load_and_pack_round_trips() {
        for (name, bytes) in seeds() {
            let (json, bin) = unpack(&bytes);
            if bytes.starts_with(b"glTF") {
                assert_eq!(pack(&json, &bin), bytes, "{name}");
            }
            // every seed loads: its mutants start from a file that reaches the whole loader
            let scene = oit_core::parse_gltf(Path::new(name), &bytes, None).expect("a seed loads");
            scene.validate().expect("a seed that loads validates");
            assert!(scene.triangle_count() > 0, "{name}");
        }
    }

    #[test]
    fn the_scene_set_is_seeded() {
        let seeds = asset_seeds();
        assert!(seeds.len() >= oit_core::scene_set::SCENE_SET.len());
        for (set, glb) in oit_core::scene_set::SCENE_SET.iter().zip(&seeds) {
            assert!(glb.starts_with(b"glTF"), "{}", set.name);
            // accepted as it is: its mutants start from a file that reaches the whole loader
            let scene =
                oit_core::parse_gltf(Path::new(set.name), glb, None).expect("a scene of the set loads");
            scene.validate().expect("a scene of the set validates");
            println!(
                "{}: {} bytes{}",
                set.name,
                glb.len(),
                if glb.len() > POOL_MAX_BYTES { " (replayed only)" } else { "" }
            );
        }
    }

    #[test]
    fn the_committed_seeds_are_the_generators() {
        let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fuzz/corpus/gltf");
        for (name, bytes) in seeds() {
            let committed = std::fs::read(corpus.join(name)).unwrap_or_default();
            assert!(
                committed == bytes,
                "tests/fuzz/corpus/gltf/{name} differs from the generator: write them again with \
                 `oit-fuzz --write-gltf-seeds tests/fuzz/corpus/gltf`"
            );
        }
    }

    #[test]
    fn edits_make_inputs_the_loader_refuses_or_reads() {
        let mut rng = Rng::new(7);
        let seeds = seeds();
        for round in 0..2000 {
            let mut input = seeds[round % seeds.len()].1.clone();
            for _ in 0..1 + rng.below(4) {
                edit(&mut rng, &mut input);
            }
            if let Ok(scene) = oit_core::parse_gltf(Path::new("m.glb"), &input, None) {
                scene.validate().expect("a mutant that loads validates");
            }
        }
    }

    /// The mutator and the generator run outside the worker's `catch_unwind`: a panic there ends
    /// the worker (JSON that is not an object once took `doc[key] = v` down).
    #[test]
    fn the_mutator_and_generator_never_panic() {
        let vocabulary = crate::dictionary::Vocabulary::new();
        let mut rng = Rng::new(13);
        let seeds = seeds();
        for round in 0..10_000 {
            let mut input = seeds[round % seeds.len()].1.clone();
            let other = &seeds[(round + 1) % seeds.len()].1;
            if round % 4 == 0 {
                input = crate::generate::generate(&mut rng, crate::Target::Gltf, &vocabulary);
            }
            crate::mutate::mutate(&mut rng, crate::Target::Gltf, &mut input, other, 16 << 20, &vocabulary);
        }
    }
}
