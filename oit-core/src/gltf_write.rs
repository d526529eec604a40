//! A scene written as a binary glTF 2.0 file (`.glb`): what [`crate::parse_gltf`] reads back as
//! the same triangles, materials and textures.
//!
//! - **Meshes.** Each of [`Scene::meshes`] is written once into the binary chunk: `POSITION`
//!   (with its bounds), `NORMAL` (where every normal is a unit vector: a mesh with a degenerate
//!   vertex leaves them out, and a reader computes them), `COLOR_0` and `TEXCOORD_0` where the
//!   mesh has them (floats), and `u32` indices.
//! - **Objects.** Each of [`Scene::objects`] is a glTF mesh of one triangle primitive over its
//!   mesh's accessors, with a material of its own: `baseColorFactor` (the colour, alpha
//!   included), `alphaMode` and `alphaCutoff`, `KHR_materials_transmission`'s factor where the
//!   transmission is above 0 (used, not required: a reader without it draws the object without
//!   transmission), `KHR_materials_volume` where the object bounds a volume
//!   ([`crate::Object::thickness`] above 0; below), and the base-colour texture. `TEXCOORD_0` is given only to the primitives of
//!   textured objects. The loader makes one object per glTF (mesh, primitive), so objects come
//!   back one for one, each with a copy of its mesh.
//! - **Instances.** Each of [`Scene::instances`] is a root node drawing its object's glTF mesh,
//!   with its transform as a `matrix` (left out where it is the identity), in instance order:
//!   the loader walks the nodes in the file's order, so primitive order is kept.
//! - **Textures.** Each of [`Scene::textures`] is a PNG (RGBA8, the texels as they are) in the
//!   binary chunk, with a sampler whose `wrapS` / `wrapT` are its [`Wrap`] modes (linear
//!   filtering, mipmapped).
//!
//! Materials are `doubleSided` as the object is ([`crate::Object::double_sided`]), and
//! `metallicFactor: 0` (glTF's default of 1 would make the scene metal in other viewers).
//!
//! A volume is written as the loader reads it back ([`crate::volume_absorption`]): its
//! `thicknessFactor` is the object's thickness, its `attenuationDistance` `R / (8·a·max(1 − c))`
//! and its `attenuationColor` `exp(−(1 − c) / max(1 − c))` per channel, `a` the object's
//! absorption, `c` its base colour's RGB and `R` the scene's bounding radius: glTF's σ is then
//! `(1 − c)·a / (R / 8)` on every channel, oit's medium exactly, and the loader's `a` is the
//! object's (to `f32` rounding). A volume that absorbs nothing (`a` 0, or a white base colour)
//! leaves the distance out (infinite). The absorption of an object without a volume has no
//! place in glTF and is not written (the loader gives it the volumes' mean, or 1 where there
//! are none), nor are the names of meshes (objects keep theirs) or [`Scene::warnings`].
//!
//! Numbers are written as the shortest decimal that reads back as the same `f32`, so positions,
//! transforms and colours come back bit for bit. Both chunks, and every buffer view, start at a
//! multiple of 4 bytes.

use glam::{Mat4, Vec2, Vec3};
use serde_json::{Value, json};

use crate::{AlphaMode, OitError, Scene, Wrap};

/// glTF's component type of `f32`.
const FLOAT: u32 = 5126;
/// glTF's component type of `u32`.
const UNSIGNED_INT: u32 = 5125;
/// Buffer view targets: vertex attributes and indices.
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The scene as a binary glTF 2.0 file (the module docs say how each part is written). Refuses a
/// scene that does not validate ([`Scene::validate`]) or whose binary chunk would pass 4 GiB, the
/// most a GLB holds.
pub fn write_glb(scene: &Scene) -> Result<Vec<u8>, OitError> {
    scene.validate()?;
    let mut bin = Bin::default();
    // each mesh's accessors: positions, normals, colours, coordinates, indices
    let mut mesh_accessors = Vec::with_capacity(scene.meshes.len());
    for mesh in &scene.meshes {
        let bounds = mesh.bounds();
        let position = bin.accessor(
            floats(mesh.positions.iter().flat_map(|p| p.to_array())),
            mesh.positions.len(),
            "VEC3",
            ARRAY_BUFFER,
            Some((bounds.min, bounds.max)),
        )?;
        let unit = mesh.normals.iter().all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-3);
        let normal = if unit && !mesh.normals.is_empty() {
            Some(bin.accessor(
                floats(mesh.normals.iter().flat_map(|n| n.to_array())),
                mesh.normals.len(),
                "VEC3",
                ARRAY_BUFFER,
                None,
            )?)
        } else {
            None
        };
        let color = match &mesh.colors {
            Some(c) => Some(bin.accessor(
                floats(c.iter().flat_map(Vec3::to_array)),
                c.len(),
                "VEC3",
                ARRAY_BUFFER,
                None,
            )?),
            None => None,
        };
        let uv = match &mesh.uvs {
            Some(uv) => Some(bin.accessor(
                floats(uv.iter().flat_map(Vec2::to_array)),
                uv.len(),
                "VEC2",
                ARRAY_BUFFER,
                None,
            )?),
            None => None,
        };
        let indices = bin.index_accessor(&mesh.indices)?;
        mesh_accessors.push((position, normal, color, uv, indices));
    }
    // textures: one PNG, sampler and texture each
    let (mut images, mut samplers, mut textures) = (Vec::new(), Vec::new(), Vec::new());
    for (i, t) in scene.textures.iter().enumerate() {
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            t.texels().as_flattened(),
            t.width(),
            t.height(),
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| OitError::InvalidScene(format!("texture '{}' cannot be encoded as PNG: {e}", t.name)))?;
        let view = bin.view(&png, None)?;
        images.push(json!({"name": t.name, "bufferView": view, "mimeType": "image/png"}));
        samplers.push(json!({
            "magFilter": 9729,
            "minFilter": 9987,
            "wrapS": wrap(t.wrap[0]),
            "wrapT": wrap(t.wrap[1]),
        }));
        textures.push(json!({"source": i, "sampler": i}));
    }
    // objects: a material and a one-primitive mesh each
    let (mut materials, mut meshes) = (Vec::new(), Vec::new());
    let (mut transmission, mut volume) = (false, false);
    let radius = scene.bounds().radius();
    for (i, o) in scene.objects.iter().enumerate() {
        let mut pbr = json!({
            "baseColorFactor": o.color.to_array().map(num),
            "metallicFactor": 0,
            "roughnessFactor": if o.transmission > 0.0 { 0.1 } else { 0.6 },
        });
        if let Some(t) = o.texture {
            pbr["baseColorTexture"] = json!({"index": t});
        }
        let mut material =
            json!({"name": o.name, "pbrMetallicRoughness": pbr, "doubleSided": o.double_sided});
        match o.alpha_mode {
            AlphaMode::Opaque => material["alphaMode"] = json!("OPAQUE"),
            AlphaMode::Mask { cutoff } => {
                material["alphaMode"] = json!("MASK");
                material["alphaCutoff"] = num(cutoff);
            }
            AlphaMode::Blend => material["alphaMode"] = json!("BLEND"),
        }
        let mut extensions = serde_json::Map::new();
        if o.transmission > 0.0 {
            transmission = true;
            extensions.insert(
                "KHR_materials_transmission".into(),
                json!({"transmissionFactor": num(o.transmission)}),
            );
        }
        if o.thickness > 0.0 {
            volume = true;
            extensions.insert("KHR_materials_volume".into(), volume_of(o, radius));
        }
        if !extensions.is_empty() {
            material["extensions"] = Value::Object(extensions);
        }
        materials.push(material);
        let (position, normal, color, uv, indices) = mesh_accessors[o.mesh];
        let mut attributes = json!({"POSITION": position});
        if let Some(n) = normal {
            attributes["NORMAL"] = json!(n);
        }
        if let Some(c) = color {
            attributes["COLOR_0"] = json!(c);
        }
        if let (Some(uv), Some(_)) = (uv, o.texture) {
            attributes["TEXCOORD_0"] = json!(uv);
        }
        meshes.push(json!({
            "name": o.name,
            "primitives": [{"attributes": attributes, "indices": indices, "material": i, "mode": 4}],
        }));
    }
    let nodes: Vec<Value> = scene
        .instances
        .iter()
        .map(|inst| {
            if inst.transform == Mat4::IDENTITY {
                json!({"mesh": inst.object})
            } else {
                json!({"mesh": inst.object, "matrix": inst.transform.to_cols_array().map(num)})
            }
        })
        .collect();
    let mut root = json!({
        "asset": {"version": "2.0", "generator": concat!("oit-core ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": bin.accessors,
        "bufferViews": bin.views,
        "buffers": [{"byteLength": bin.data.len()}],
    });
    if !textures.is_empty() {
        root["textures"] = json!(textures);
        root["samplers"] = json!(samplers);
        root["images"] = json!(images);
    }
    let used: Vec<&str> = [(transmission, "KHR_materials_transmission"), (volume, "KHR_materials_volume")]
        .into_iter()
        .filter_map(|(u, name)| u.then_some(name))
        .collect();
    if !used.is_empty() {
        root["extensionsUsed"] = json!(used);
    }
    let json = serde_json::to_vec(&root)
        .map_err(|e| OitError::InvalidScene(format!("scene '{}': cannot write its glTF: {e}", scene.name)))?;
    pack_glb(&json, &bin.data).map_err(|e| match e {
        OitError::InvalidScene(m) => OitError::InvalidScene(format!("scene '{}': {m}", scene.name)),
        e => e,
    })
}

/// The `KHR_materials_volume` of object `o` in a scene of bounding radius `radius` (the module
/// docs say how it is chosen).
fn volume_of(o: &crate::Object, radius: f32) -> Value {
    let open = (glam::Vec3::ONE - o.color.truncate()).max(glam::Vec3::ZERO);
    let widest = open.max_element();
    let mut v = json!({"thicknessFactor": num(o.thickness)});
    let unit = f64::from(radius).max(1e-6) / 8.0;
    let distance = (unit / (f64::from(o.absorption) * f64::from(widest))) as f32;
    if o.absorption > 0.0 && widest > 0.0 && distance.is_finite() && distance > 0.0 {
        let color = open.to_array().map(|w| num((-f64::from(w) / f64::from(widest)).exp() as f32));
        v["attenuationDistance"] = num(distance);
        v["attenuationColor"] = json!(color);
    }
    v
}

/// The GLB container of `json` and `bin`: a 12-byte header, the JSON chunk (padded with spaces)
/// and the binary chunk (padded with zeros; left out when empty), each a multiple of 4 bytes long.
/// What [`write_glb`] writes its scene into, and how tests and the fuzz harness make GLBs.
pub fn pack_glb(json: &[u8], bin: &[u8]) -> Result<Vec<u8>, OitError> {
    let (mut json, mut bin) = (json.to_vec(), bin.to_vec());
    pad(&mut json, b' ');
    pad(&mut bin, 0);
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = u32::try_from(total)
        .map_err(|_| OitError::InvalidScene(format!("{total} bytes as a GLB, over the 4 GiB a GLB holds")))?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    Ok(out)
}

/// Pads `v` with `with` to a multiple of 4 bytes.
fn pad(v: &mut Vec<u8>, with: u8) {
    while !v.len().is_multiple_of(4) {
        v.push(with);
    }
}

/// The binary chunk as it is built, with its buffer views and accessors.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends `bytes` as a buffer view (starting at a multiple of 4), returning its index.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> Result<usize, OitError> {
        pad(&mut self.data, 0);
        if self.data.len() + bytes.len() > u32::MAX as usize - 64 {
            return Err(OitError::InvalidScene("the scene's data passes the 4 GiB a GLB holds".into()));
        }
        let mut view = json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.data.extend_from_slice(bytes);
        self.views.push(view);
        Ok(self.views.len() - 1)
    }

    /// A float accessor of `count` elements of `kind` over `bytes`, with `min`/`max` where given.
    fn accessor(
        &mut self,
        bytes: Vec<u8>,
        count: usize,
        kind: &str,
        target: u32,
        bounds: Option<(Vec3, Vec3)>,
    ) -> Result<usize, OitError> {
        let view = self.view(&bytes, Some(target))?;
        let mut a = json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": kind});
        if let Some((min, max)) = bounds {
            a["min"] = json!(min.to_array().map(num));
            a["max"] = json!(max.to_array().map(num));
        }
        self.accessors.push(a);
        Ok(self.accessors.len() - 1)
    }

    /// The `u32` index accessor of `indices`.
    fn index_accessor(&mut self, indices: &[[u32; 3]]) -> Result<usize, OitError> {
        let bytes: Vec<u8> = indices.as_flattened().iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER))?;
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": UNSIGNED_INT,
            "count": indices.len() * 3,
            "type": "SCALAR",
        }));
        Ok(self.accessors.len() - 1)
    }
}

/// Little-endian bytes of `values`.
fn floats(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_le_bytes).collect()
}

/// `x` as the shortest decimal that reads back as the same `f32` (Rust's `Display` of an `f32`),
/// carried as the `f64` of that decimal, which serde_json prints the same way.
fn num(x: f32) -> Value {
    let shortest: f64 = x.to_string().parse().unwrap_or(f64::from(x));
    json!(shortest)
}

/// glTF's sampler wrap code of `w`.
fn wrap(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 10497,
        Wrap::MirroredRepeat => 33648,
        Wrap::ClampToEdge => 33071,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Instance, Mesh, Object, Texture};
    use glam::Vec4;
    use std::path::Path;

    /// A small scene with every kind of part: a textured, vertex-coloured blended quad with
    /// transmission and a volume placed twice, a masked one, an opaque untextured single-sided
    /// triangle.
    fn sample() -> Scene {
        let mut quad = Mesh::new(
            "quad",
            vec![Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.1), Vec3::new(0.0, 1.0, 0.0)],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        quad.uvs = Some(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
        quad.colors = Some(vec![Vec3::ONE, Vec3::new(0.5, 0.25, 1.0), Vec3::ONE, Vec3::splat(0.1)]);
        let tri = Mesh::new("tri", vec![Vec3::ZERO, Vec3::X * 0.3, Vec3::Y * 0.7], vec![[0, 1, 2]]);
        let texels = (0..12u8).map(|i| [i * 20, 255 - i, i, i * 21]).collect();
        let texture = Texture::new("t", 4, 3, texels, [Wrap::ClampToEdge, Wrap::MirroredRepeat]).unwrap();
        let glass = Object {
            transmission: 0.7,
            thickness: 0.25,
            absorption: 0.8,
            ..Object::new("glass", 0, Vec4::new(0.2, 0.4, 0.6, 0.45))
        };
        let leaf =
            Object { alpha_mode: AlphaMode::Mask { cutoff: 0.3 }, ..Object::new("leaf", 0, Vec4::ONE) };
        Scene {
            name: "sample".into(),
            meshes: vec![quad, tri],
            objects: vec![
                glass.textured(0),
                leaf.textured(0),
                Object::new("solid", 1, Vec4::new(0.9, 0.1, 0.3, 1.0)).opaque().single_sided(),
            ],
            instances: vec![
                Instance { object: 0, transform: Mat4::IDENTITY },
                Instance {
                    object: 0,
                    transform: Mat4::from_scale_rotation_translation(
                        Vec3::splat(0.37),
                        glam::Quat::from_rotation_y(0.3),
                        Vec3::new(0.1, -2.0, 3.3),
                    ),
                },
                Instance { object: 2, transform: Mat4::from_translation(Vec3::Z) },
                Instance { object: 1, transform: Mat4::from_rotation_x(1.0) },
            ],
            textures: vec![texture],
            warnings: Vec::new(),
        }
    }

    /// Written and read back: every object, instance, vertex and texel the same, bit for bit;
    /// the chunks and views 4-byte aligned; no warning on reading.
    #[test]
    fn reads_back_as_written() {
        let scene = sample();
        let bytes = write_glb(&scene).unwrap();
        assert!(bytes.len().is_multiple_of(4));
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        assert!(json_len.is_multiple_of(4));
        let json: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        for v in json["bufferViews"].as_array().unwrap() {
            assert!(v["byteOffset"].as_u64().unwrap().is_multiple_of(4), "{v}");
        }
        let back = crate::parse_gltf(Path::new("sample.glb"), &bytes, None).unwrap();
        assert!(back.warnings.is_empty(), "{:?}", back.warnings);
        back.validate().unwrap();
        assert_eq!(back.instances.len(), scene.instances.len());
        assert_eq!(back.textures, scene.textures);
        for (a, b) in scene.instances.iter().zip(&back.instances) {
            assert_eq!(a.transform, b.transform);
            let ((oa, ma), (ob, mb)) = (scene.instance_parts(a), back.instance_parts(b));
            assert_eq!((&oa.name, oa.color, oa.alpha_mode), (&ob.name, ob.color, ob.alpha_mode));
            assert_eq!(oa.double_sided, ob.double_sided, "{}", oa.name);
            assert_eq!(
                (oa.transmission, oa.texture, oa.thickness),
                (ob.transmission, ob.texture, ob.thickness)
            );
            // the volume's absorption to f32 rounding, and the objects without one take it (the
            // effect's one medium)
            assert!((ob.absorption - 0.8).abs() < 1e-5, "{}: {}", ob.name, ob.absorption);
            assert_eq!((&ma.positions, &ma.indices, &ma.colors), (&mb.positions, &mb.indices, &mb.colors));
            assert_eq!(ma.uvs.is_some() && oa.texture.is_some(), mb.uvs.is_some());
            if mb.uvs.is_some() {
                assert_eq!(ma.uvs, mb.uvs);
            }
            for (na, nb) in ma.normals.iter().zip(&mb.normals) {
                assert!((*na - *nb).abs().max_element() < 1e-6);
            }
        }
    }

    /// A scene that does not validate is refused, not written.
    #[test]
    fn refuses_an_invalid_scene() {
        let mut scene = sample();
        scene.instances[0].object = 9;
        assert!(write_glb(&scene).is_err());
    }
}
