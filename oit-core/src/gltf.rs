//! glTF 2.0 scenes (`.gltf` with its buffers, or `.glb`), read through the `gltf` crate into
//! oit's scene model: the default scene (or the first), its node hierarchy flattened into
//! instances with their world transforms, each primitive of triangles (strips and fans turned
//! into triangles, points and lines refused by name) a mesh with its positions, normals (computed
//! where the file has none), vertex colours and indices, and each primitive's material an object:
//! `pbrMetallicRoughness.baseColorFactor`, `alphaMode` and `alphaCutoff`
//! ([`crate::AlphaMode`]), and `KHR_materials_transmission`'s factor ([`Object::transmission`]).
//!
//! The base-colour texture is read with its sampler's wrap modes and the primitive's
//! TEXCOORD_0 ([`crate::Texture`]). What oit does not draw yet is said, never dropped in silence:
//! a single-sided material (drawn from both sides), a texture on another coordinate set, and the
//! volume extension each add one warning to [`Scene::warnings`]; an extension the file *requires* and oit does not read
//! is an error naming it, one it only uses is a warning. Sparse accessors are refused by name, an
//! accessor of more than [`MAX_VERTICES`] elements before anything is read from it.

use std::path::Path;

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::{AlphaMode, Instance, Mesh, Object, OitError, Scene, Texture, Wrap};

/// The extensions oit reads: a file that requires any other is refused.
pub const GLTF_EXTENSIONS: [&str; 1] = ["KHR_materials_transmission"];

/// The most elements an accessor read into a mesh may have (64 Mi): a primitive past it is
/// refused before its data is read (a scene holds at most [`Scene::MAX_TRIANGLES`] triangles).
pub const MAX_VERTICES: usize = 1 << 26;

/// The deepest node hierarchy walked: a file whose nodes nest deeper (or loop) is refused.
const MAX_DEPTH: usize = 256;

/// Reads the glTF 2.0 file `path` (`.gltf` or `.glb`; buffers in the GLB's binary chunk, in data
/// URIs or in files beside it) into a scene; `scene_index` picks a scene of the file (its default
/// scene, or the first, when `None`).
pub fn load_gltf(path: &Path, scene_index: Option<usize>) -> Result<Scene, OitError> {
    let limit = crate::obj::model_byte_limit()?;
    let bytes = crate::obj::read_bounded_bytes(path, limit, "glTF (.gltf, .glb)")?;
    parse_gltf(path, &bytes, scene_index)
}

/// [`load_gltf`] of a file already in memory: `path` names it in messages and locates external
/// buffers (relative to its folder).
pub fn parse_gltf(path: &Path, bytes: &[u8], scene_index: Option<usize>) -> Result<Scene, OitError> {
    let err = |message: String| OitError::Model { path: path.to_path_buf(), message };
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| {
        let text = e.to_string();
        // a required extension the crate has no reader for is refused by it, by name (and oit
        // builds it with readers for only those it draws, and volume's, to warn that it is not)
        if text.contains("extensionsRequired") {
            err(format!(
                "the file requires an extension oit does not read (it reads {}): {text}",
                GLTF_EXTENSIONS.join(", ")
            ))
        } else {
            err(format!("not a valid glTF 2.0 file: {text}"))
        }
    })?;
    let mut warnings = Vec::new();
    let unread: Vec<&str> = gltf.extensions_used().filter(|e| !GLTF_EXTENSIONS.contains(e)).collect();
    if !unread.is_empty() {
        warnings.push(format!(
            "{}: extensions not read (drawn without them): {}",
            path.display(),
            unread.join(", ")
        ));
    }
    let document = &gltf.document;
    let scene = match scene_index {
        Some(i) => document.scenes().nth(i).ok_or_else(|| {
            err(format!("the file has {} scenes: scene {i} does not exist", document.scenes().count()))
        })?,
        None => document
            .default_scene()
            .or_else(|| document.scenes().next())
            .ok_or_else(|| err("the file has no scene".into()))?,
    };
    // every accessor a primitive reads, checked before any buffer is loaded
    for mesh in document.meshes() {
        for prim in mesh.primitives() {
            let accessors = prim.attributes().map(|(_, a)| a).chain(prim.indices());
            for a in accessors {
                if a.sparse().is_some() {
                    return Err(err(format!("mesh {}: sparse accessors are not read", mesh.index())));
                }
                if a.count() > MAX_VERTICES {
                    return Err(err(format!(
                        "mesh {}: an accessor of {} elements, over the limit of {MAX_VERTICES}",
                        mesh.index(),
                        a.count()
                    )));
                }
            }
        }
    }
    let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(document, Some(base), gltf.blob.clone())
        .map_err(|e| err(format!("cannot load its buffers: {e}")))?;
    let images = if document.textures().next().is_some() {
        gltf::import_images(document, Some(base), &buffers)
            .map_err(|e| err(format!("cannot load its images: {e}")))?
    } else {
        Vec::new()
    };
    let name = path.file_stem().map_or_else(|| "gltf".to_string(), |s| s.to_string_lossy().into_owned());
    // one texture per (image, wrap modes), made the first time a material samples it
    let mut textures: std::collections::HashMap<(usize, [Wrap; 2]), usize> = std::collections::HashMap::new();
    let mut out = Scene { name, ..Scene::default() };
    // one mesh and one object per (mesh, primitive), made the first time a node draws it
    let mut made: std::collections::HashMap<(usize, usize), usize> = std::collections::HashMap::new();
    let mut notes = Notes::default();
    // depth first, in the file's order: the roots and each node's children pushed last first
    let roots: Vec<_> = scene.nodes().collect();
    let mut stack: Vec<(gltf::Node<'_>, Mat4, usize)> =
        roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err(err(format!("the node hierarchy is deeper than {MAX_DEPTH} (or loops)")));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let key = (mesh.index(), prim.index());
                let object = match made.get(&key) {
                    Some(&o) => o,
                    None => {
                        let mut m = primitive_mesh(&mesh, &prim, &buffers).map_err(err)?;
                        let mut o = material_object(&mesh, &prim, out.meshes.len(), &mut notes);
                        o.texture =
                            base_texture(&prim, &images, &mut out, &mut textures, &mut notes).map_err(err)?;
                        if o.texture.is_some() && m.uvs.is_none() {
                            return Err(err(format!("{}: a base-colour texture without TEXCOORD_0", m.name)));
                        }
                        if o.texture.is_none() {
                            // coordinates no texture reads are not kept (oit refuses them as unused)
                            m.uvs = None;
                        }
                        out.meshes.push(m);
                        out.objects.push(o);
                        made.insert(key, out.objects.len() - 1);
                        out.objects.len() - 1
                    }
                };
                out.instances.push(Instance { object, transform: world });
            }
        }
        // children pushed in reverse, so that they are drawn in the file's order
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world, depth + 1)));
        if out.instances.len() as u64 > Scene::MAX_INSTANCES {
            Scene::check_size(&out.name, out.triangle_count(), out.instances.len() as u64)?;
        }
    }
    warnings.extend(notes.lines(path));
    out.warnings = warnings;
    if out.instances.is_empty() {
        return Err(err("its scene draws no triangles (no node has a mesh of triangles)".into()));
    }
    Scene::check_size(&out.name, out.triangle_count(), out.instances.len() as u64)?;
    Ok(out)
}

/// What the file asked for that oit does not draw yet: one warning each.
#[derive(Default)]
struct Notes {
    other_coordinates: bool,
    single_sided: bool,
    volume: bool,
}

impl Notes {
    fn lines(&self, path: &Path) -> Vec<String> {
        let p = path.display();
        let mut out = Vec::new();
        if self.other_coordinates {
            out.push(format!("{p}: a texture on a coordinate set other than TEXCOORD_0 is not drawn"));
        }
        if self.single_sided {
            out.push(format!("{p}: single-sided materials are drawn from both sides"));
        }
        if self.volume {
            out.push(format!("{p}: KHR_materials_volume's thickness and attenuation are not read"));
        }
        out
    }
}

/// The mesh of one primitive: triangles from its mode, indices or vertex order.
fn primitive_mesh(
    mesh: &gltf::Mesh<'_>,
    prim: &gltf::Primitive<'_>,
    buffers: &[gltf::buffer::Data],
) -> Result<Mesh, String> {
    let name = match mesh.name() {
        Some(n) => format!("{n} #{}", prim.index()),
        None => format!("mesh {} #{}", mesh.index(), prim.index()),
    };
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| format!("{name}: a primitive without POSITION"))?
        .map(Vec3::from_array)
        .collect();
    let n = positions.len() as u32;
    let order: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..n).collect(),
    };
    if let Some(&bad) = order.iter().find(|&&i| i >= n) {
        return Err(format!("{name}: index {bad} past its {n} vertices"));
    }
    use gltf::mesh::Mode;
    let indices: Vec<[u32; 3]> = match prim.mode() {
        Mode::Triangles => order.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        // every other triangle of a strip flips its first two vertices, so all keep one winding
        Mode::TriangleStrip => (0..order.len().saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [order[i], order[i + 1], order[i + 2]]
                } else {
                    [order[i + 1], order[i], order[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => {
            (1..order.len().saturating_sub(1)).map(|i| [order[0], order[i], order[i + 1]]).collect()
        }
        other => return Err(format!("{name}: primitives of mode {other:?} are not drawn (triangles only)")),
    };
    let mut m = Mesh::new(name, positions, indices);
    if let Some(normals) = reader.read_normals() {
        let normals: Vec<Vec3> = normals.map(Vec3::from_array).collect();
        if normals.len() == m.positions.len()
            && normals.iter().all(|v| v.is_finite() && v.length_squared() > 0.0)
        {
            m.normals = normals.into_iter().map(Vec3::normalize).collect();
        }
    }
    if let Some(uvs) = reader.read_tex_coords(0) {
        let uvs: Vec<Vec2> = uvs.into_f32().map(Vec2::from_array).collect();
        if uvs.len() == m.positions.len() {
            m.uvs = Some(uvs);
        }
    }
    if let Some(colors) = reader.read_colors(0) {
        let colors: Vec<Vec3> = colors.into_rgb_f32().map(Vec3::from_array).collect();
        if colors.len() == m.positions.len() {
            m.colors = Some(colors);
        }
    }
    Ok(m)
}

/// The primitive's base-colour texture, added to `out.textures` the first time (per image and
/// wrap modes); `None` where its material has none (or one on another coordinate set, noted).
fn base_texture(
    prim: &gltf::Primitive<'_>,
    images: &[gltf::image::Data],
    out: &mut Scene,
    made: &mut std::collections::HashMap<(usize, [Wrap; 2]), usize>,
    notes: &mut Notes,
) -> Result<Option<usize>, String> {
    let Some(info) = prim.material().pbr_metallic_roughness().base_color_texture() else {
        return Ok(None);
    };
    if info.tex_coord() != 0 {
        notes.other_coordinates = true;
        return Ok(None);
    }
    let texture = info.texture();
    let wrap = |w: gltf::texture::WrappingMode| match w {
        gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
    };
    let sampler = texture.sampler();
    let wraps = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
    let index = texture.source().index();
    if let Some(&t) = made.get(&(index, wraps)) {
        return Ok(Some(t));
    }
    let image = images.get(index).ok_or_else(|| format!("image {index} was not loaded"))?;
    let name = texture.source().name().map_or_else(|| format!("image {index}"), str::to_string);
    let texels =
        rgba8(image).ok_or_else(|| format!("{name}: pixels of format {:?} are not read", image.format))?;
    let t = Texture::new(name, image.width, image.height, texels, wraps).map_err(|e| e.to_string())?;
    out.textures.push(t);
    made.insert((index, wraps), out.textures.len() - 1);
    Ok(Some(out.textures.len() - 1))
}

/// An image's pixels as RGBA8 (grey as RGB, no alpha as 255); `None` for the 16-bit and float
/// formats.
fn rgba8(image: &gltf::image::Data) -> Option<Vec<[u8; 4]>> {
    use gltf::image::Format;
    let p = &image.pixels;
    Some(match image.format {
        Format::R8G8B8A8 => p.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
        Format::R8G8B8 => p.chunks_exact(3).map(|c| [c[0], c[1], c[2], 255]).collect(),
        Format::R8G8 => p.chunks_exact(2).map(|c| [c[0], c[0], c[0], c[1]]).collect(),
        Format::R8 => p.iter().map(|&c| [c, c, c, 255]).collect(),
        _ => return None,
    })
}

/// The object of one primitive: its material as oit reads it.
fn material_object(
    mesh: &gltf::Mesh<'_>,
    prim: &gltf::Primitive<'_>,
    index: usize,
    notes: &mut Notes,
) -> Object {
    let material = prim.material();
    let pbr = material.pbr_metallic_roughness();
    notes.single_sided |= !material.double_sided();
    notes.volume |= material.volume().is_some();
    let mut o = Object::new(
        mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_string),
        index,
        Vec4::from_array(pbr.base_color_factor()),
    );
    o.alpha_mode = match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: material.alpha_cutoff().unwrap_or(0.5) },
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    };
    o.transmission = material.transmission().map_or(0.0, |t| t.transmission_factor());
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GLB of `json` (its `buffers[0]` the binary chunk `bin`).
    pub(crate) fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        let pad = |mut v: Vec<u8>, with: u8| {
            while !v.len().is_multiple_of(4) {
                v.push(with);
            }
            v
        };
        let json = pad(json.as_bytes().to_vec(), b' ');
        let bin = pad(bin.to_vec(), 0);
        let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        if !bin.is_empty() {
            out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&bin);
        }
        out
    }

    /// A unit quad's four positions (f32) and its six u16 indices.
    fn quad_bin() -> Vec<u8> {
        let mut bin = Vec::new();
        for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
            p.iter().for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
        }
        for i in [0u16, 1, 2, 0, 2, 3] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        bin
    }

    /// `nodes`, `meshes`, `materials` and `extra` (more top-level keys) around the quad's buffer.
    fn document(nodes: &str, meshes: &str, materials: &str, extra: &str) -> String {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],"nodes":{nodes},
            "meshes":{meshes},"materials":{materials},"buffers":[{{"byteLength":60}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
            {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}]{extra}}}"#
        )
    }

    const NODES: &str =
        r#"[{"mesh":0,"translation":[1,0,0]},{"mesh":0,"children":[2]},{"mesh":1,"scale":[2,2,2]}]"#;
    const MESHES: &str = r#"[{"name":"quad","primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]},
        {"primitives":[{"attributes":{"POSITION":0},"mode":5}]}]"#;
    const BLEND: &str = r#"[{"pbrMetallicRoughness":{"baseColorFactor":[1,0,0,0.5]},"alphaMode":"BLEND","doubleSided":true}]"#;

    fn parse(json: &str) -> Result<Scene, OitError> {
        parse_gltf(Path::new("test.glb"), &glb(json, &quad_bin()), None)
    }

    #[test]
    fn nodes_meshes_and_materials() {
        let s = parse(&document(NODES, MESHES, BLEND, "")).expect("loads");
        s.validate().expect("valid");
        // two (mesh, primitive) pairs, drawn by three nodes in the file's order
        assert_eq!((s.meshes.len(), s.objects.len(), s.instances.len()), (2, 2, 3));
        assert_eq!(s.instances.iter().map(|i| i.object).collect::<Vec<_>>(), [0, 0, 1]);
        assert_eq!(s.instances[0].transform, Mat4::from_translation(Vec3::X));
        assert_eq!(
            s.instances[2].transform,
            Mat4::from_scale(Vec3::splat(2.0)),
            "the child under an identity parent"
        );
        assert_eq!(s.meshes[0].indices, [[0, 1, 2], [0, 2, 3]]);
        // the strip: every other triangle's first two vertices swapped, one winding
        assert_eq!(s.meshes[1].indices, [[0, 1, 2], [2, 1, 3]]);
        let (blend, default) = (&s.objects[0], &s.objects[1]);
        assert_eq!((blend.color, blend.alpha_mode), (Vec4::new(1.0, 0.0, 0.0, 0.5), AlphaMode::Blend));
        // no material: glTF's default, opaque white, single-sided
        assert_eq!((default.color, default.alpha_mode), (Vec4::ONE, AlphaMode::Opaque));
        assert!(s.warnings.iter().any(|w| w.contains("single-sided")), "{:?}", s.warnings);
        assert!(s.meshes[0].normals.iter().all(|n| (n.z - 1.0).abs() < 1e-6), "normals computed");
    }

    #[test]
    fn masks_transmission_and_fans() {
        let materials = r#"[{"alphaMode":"MASK","alphaCutoff":0.25,"doubleSided":true,
            "extensions":{"KHR_materials_transmission":{"transmissionFactor":0.75}}}]"#;
        let meshes = r#"[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]},
            {"primitives":[{"attributes":{"POSITION":0},"mode":6}]}]"#;
        let extra = r#","extensionsUsed":["KHR_materials_transmission"],"extensionsRequired":["KHR_materials_transmission"]"#;
        let s = parse(&document(NODES, meshes, materials, extra)).expect("loads");
        assert_eq!(s.objects[0].alpha_mode, AlphaMode::Mask { cutoff: 0.25 });
        assert_eq!(s.objects[0].transmission, 0.75);
        assert_eq!(s.meshes[1].indices, [[0, 1, 2], [0, 2, 3]], "the fan");
    }

    #[test]
    fn what_oit_cannot_read_is_refused_or_said() {
        let text = |r: Result<Scene, OitError>| r.expect_err("refused").to_string();
        let extra = r#","extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"]"#;
        let e = text(parse(&document(NODES, MESHES, BLEND, extra)));
        assert!(
            e.contains("requires an extension oit does not read") && e.contains("KHR_draco_mesh_compression"),
            "{e}"
        );
        // one the glTF crate reads but oit does not draw
        let extra =
            r#","extensionsUsed":["KHR_materials_volume"],"extensionsRequired":["KHR_materials_volume"]"#;
        let e = text(parse(&document(NODES, MESHES, BLEND, extra)));
        assert!(
            e.contains("requires an extension oit does not read") && e.contains("KHR_materials_volume"),
            "{e}"
        );
        let extra = r#","extensionsUsed":["EXT_lights_ies"]"#;
        let s = parse(&document(NODES, MESHES, BLEND, extra)).expect("an optional extension is ignored");
        assert!(s.warnings.iter().any(|w| w.contains("EXT_lights_ies")), "{:?}", s.warnings);
        let points = r#"[{"primitives":[{"attributes":{"POSITION":0},"mode":0}]},{"primitives":[{"attributes":{"POSITION":0}}]}]"#;
        let e = text(parse(&document(NODES, points, BLEND, "")));
        assert!(e.contains("Points") && e.contains("triangles only"), "{e}");
        // a truncated GLB, JSON that is not glTF, an index past the vertices
        let whole = glb(&document(NODES, MESHES, BLEND, ""), &quad_bin());
        let e = text(parse_gltf(Path::new("cut.glb"), &whole[..whole.len() - 20], None));
        assert!(e.contains("cut.glb"), "{e}");
        let e = text(parse_gltf(Path::new("x.gltf"), br#"{"hello":1}"#, None));
        assert!(e.contains("not a valid glTF"), "{e}");
        let mut bin = quad_bin();
        bin[48..50].copy_from_slice(&9u16.to_le_bytes());
        let e = text(parse_gltf(Path::new("i.glb"), &glb(&document(NODES, MESHES, BLEND, ""), &bin), None));
        assert!(e.contains("index 9 past its 4 vertices"), "{e}");
        // a scene that does not exist
        let e = text(parse_gltf(Path::new("s.glb"), &whole, Some(3)));
        assert!(e.contains("scene 3 does not exist"), "{e}");
    }

    #[test]
    fn renders_as_its_parts_say() {
        // the quad of the first node, opaque red, behind the blended node: both layers present
        let s = parse(&document(NODES, MESHES, BLEND, "")).expect("loads");
        let layers = s.layers(None);
        assert!(layers.opaque.is_some() && layers.transparent.triangle_count() == 4);
    }

    /// A textured quad: TEXCOORD_0, a PNG in the binary chunk, a clamping sampler; the texels
    /// and wrap modes arrive as the file has them, and the untextured object's coordinates are
    /// dropped (oit refuses coordinates no texture reads).
    #[test]
    fn textures_and_their_samplers() {
        let mut bin = quad_bin();
        for uv in [[0f32, 0.], [1., 0.], [1., 1.], [0., 1.]] {
            uv.iter().for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
        }
        let texels: [[u8; 4]; 4] = [[255, 0, 0, 255], [0, 255, 0, 128], [0, 0, 255, 0], [255, 255, 255, 255]];
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            texels.as_flattened(),
            2,
            2,
            image::ExtendedColorType::Rgba8,
        )
        .unwrap();
        let png_at = bin.len();
        bin.extend_from_slice(&png);
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0,1]}}],"nodes":[{{"mesh":0}},{{"mesh":1}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2}},"indices":1,"material":0}}]}},
                      {{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2}},"indices":1,"material":1}}]}}],
            "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}},"alphaMode":"BLEND","doubleSided":true}},
                         {{"doubleSided":true}}],
            "textures":[{{"source":0,"sampler":0}}],"samplers":[{{"wrapS":33071,"wrapT":33648}}],
            "images":[{{"bufferView":3,"mimeType":"image/png","name":"checker"}}],
            "buffers":[{{"byteLength":{}}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}},
                           {{"buffer":0,"byteOffset":60,"byteLength":32}},{{"buffer":0,"byteOffset":{png_at},"byteLength":{}}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}},
                         {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}}]}}"#,
            bin.len(),
            png.len()
        );
        let s = parse_gltf(Path::new("tex.glb"), &glb(&json, &bin), None).expect("loads");
        s.validate().expect("valid");
        assert_eq!(s.textures.len(), 1);
        let t = &s.textures[0];
        assert_eq!((t.name.as_str(), t.width(), t.height()), ("checker", 2, 2));
        assert_eq!(t.texels(), &texels[..]);
        assert_eq!(t.wrap, [Wrap::ClampToEdge, Wrap::MirroredRepeat]);
        assert_eq!((s.objects[0].texture, s.objects[1].texture), (Some(0), None));
        assert_eq!(s.meshes[0].uvs.as_ref().map(Vec::len), Some(4));
        assert!(s.meshes[1].uvs.is_none(), "coordinates no texture reads are dropped");
    }
}
