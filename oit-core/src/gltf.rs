//! glTF 2.0 scenes (`.gltf` with its buffers, or `.glb`), read through the `gltf` crate into
//! oit's scene model: the default scene (or the first, or the one asked for), its node hierarchy
//! flattened into instances with their world transforms, each primitive of triangles (strips and
//! fans turned into triangles, points and lines refused by name) a mesh with its positions,
//! normals (computed where the file has none), vertex colours and indices, and each primitive's
//! material an object: `pbrMetallicRoughness.baseColorFactor`, `alphaMode` and `alphaCutoff`
//! ([`crate::AlphaMode`]), `doubleSided` ([`Object::double_sided`]: glTF's default, false, drops
//! back faces), `KHR_materials_transmission`'s factor ([`Object::transmission`]) and
//! `KHR_materials_volume` ([`Object::thickness`], [`Object::absorption`], below).
//!
//! The base-colour texture is read with its sampler's wrap modes and the primitive's
//! TEXCOORD_0 ([`crate::Texture`]). What oit does not draw yet is said, never dropped in silence:
//! a texture on another coordinate set, and an attenuation colour the translucency effect cannot
//! represent each add one warning to [`Scene::warnings`]; an extension the file *requires* and oit does not read is an error naming
//! it, one it only uses is a warning.
//!
//! # `KHR_materials_volume` and the translucency effect
//!
//! glTF's medium absorbs `σ = −ln(attenuationColor) / attenuationDistance` per channel and per
//! unit of world-space length (an absent, infinite distance absorbs nothing); `thicknessFactor`
//! 0 (its default) makes the surface thin-walled, with no volume at all. oit's translucency
//! effect absorbs `(1 − c)·k` per channel and per unit of view-space length, which is world-space
//! length (the camera does not scale distances), `c` the entering layer's colour and `k` one
//! value for the whole scene, [`Scene::absorption_per_length`]: the mean of the objects'
//! [`Object::absorption`] per 1/8 of the scene's bounding radius `R`. The loader maps a volume
//! (`thicknessFactor` above 0) onto that model so that the mean over the channels agrees:
//!
//! ```text
//! k = mean(σ) / mean(1 − baseColorFactor.rgb)        absorption = k · R / 8
//! ```
//!
//! with `R` the loaded scene's radius ([`volume_absorption`]). Both sides are then the same
//! medium on average over the channels, for a layer of the material's base colour (vertex
//! colours and texture samples change `c` per fragment, as they do for every object). oit's
//! per-channel shape is fixed by the base colour, so an attenuation colour is drawn exactly only
//! where `σ` is proportional to `1 − baseColorFactor.rgb` (an `attenuationColor` of
//! `exp(−s·(1 − baseColorFactor.rgb))` for any `s`, as oit's writer writes); any other is drawn
//! as its channel mean, with one warning line. A base colour of white absorbs nothing in oit's
//! model whatever `k`: its volume is drawn without absorption (warned too, where `σ` is not 0).
//! An attenuation channel of 0 is read as the smallest positive `f32`.
//!
//! The effect has one medium per scene, where glTF has one per material, so the objects that do
//! not bound a volume (no extension, or `thicknessFactor` 0: thin-walled or opaque surfaces,
//! which glTF gives no absorption) take the mean of the volumes' values, and do not dilute it:
//! a scene whose volumes share one medium is drawn with exactly that medium (over the channels'
//! mean), and one whose volumes differ with their mean (one warning line). A file without a volume
//! keeps oit's default absorption, 1, on every object, as before the extension was read.
//! `thicknessFactor` itself is not otherwise read (the effect measures the thickness between the
//! entering and the leaving layer), nor `thicknessTexture`; a volume boundary is drawn from both
//! sides whatever its `doubleSided` (glTF says the property does not apply to it, and the effect
//! pairs the layer that enters a medium with the one that leaves it, a back face). A negative thickness, a distance of 0
//! or less or an attenuation colour outside [0, 1] is refused with the material's name.
//!
//! Bad input is an [`OitError::Model`] naming what is wrong, and nothing is half-loaded: the GLB
//! container is split here (a file cut short says in which part), the JSON is read and checked
//! by the `gltf` crate (after the indices its checks would follow unchecked), the node hierarchy
//! must be a set of trees (a node reached twice — a loop, or two parents — is refused), and every
//! accessor a drawn primitive reads is checked before any is read: its type for its attribute,
//! a count from 1 to [`MAX_VERTICES`], offsets aligned to its components, its elements within its
//! buffer view and the view within its buffer; sparse accessors are refused by name. Buffers and
//! images are read here too, not by the crate's importer: external files through oit's bounded
//! reader (regular files only, at most `OIT_MAX_MODEL_BYTES`), a file that is missing is an error
//! naming it, and an image is decoded with limits (a side of at most [`Texture::MAX_SIDE`], and
//! no more pixels than its bytes can encode), so a small file cannot make a large allocation.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::{AlphaMode, Instance, Mesh, Object, OitError, Scene, Texture, Wrap};

/// The extensions oit reads: a file that requires any other is refused.
pub const GLTF_EXTENSIONS: [&str; 2] = ["KHR_materials_transmission", "KHR_materials_volume"];

/// The most elements an accessor read into a mesh may have (64 Mi): a primitive past it is
/// refused before its data is read (a scene holds at most [`Scene::MAX_TRIANGLES`] triangles).
pub const MAX_VERTICES: usize = 1 << 26;

/// The deepest node hierarchy walked: a file whose nodes nest deeper is refused.
const MAX_DEPTH: usize = 256;

/// The validation errors of the `gltf` crate listed in a message, at most.
const LISTED_ERRORS: usize = 4;

/// Reads the glTF 2.0 file `path` (`.gltf` or `.glb`; buffers in the GLB's binary chunk, in data
/// URIs or in files beside it) into a scene; `scene_index` picks a scene of the file (its default
/// scene, or the first, when `None`).
pub fn load_gltf(path: &Path, scene_index: Option<usize>) -> Result<Scene, OitError> {
    let limit = crate::obj::model_byte_limit()?;
    let bytes = crate::obj::read_bounded_bytes(path, limit, "glTF (.gltf, .glb)")?;
    parse_gltf(path, &bytes, scene_index)
}

/// Whether `name` is the path of a glTF file (`.gltf` or `.glb`), as [`crate::load_scene`] reads
/// it.
pub fn is_gltf_path(name: &str) -> bool {
    Path::new(name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// [`crate::load_scene`] with a scene of a glTF file picked: with `gltf_scene` (the CLI's
/// `--gltf-scene N`), `name` must be the path of a `.gltf` or `.glb` file and scene N of it is
/// read; with `None` this is `load_scene(name)`, the file's default scene.
pub fn load_scene_with(name: &str, gltf_scene: Option<usize>) -> Result<Scene, OitError> {
    match gltf_scene {
        None => crate::load_scene(name),
        Some(n) if is_gltf_path(name) => load_gltf(Path::new(name), Some(n)),
        Some(n) => Err(OitError::InvalidSettings(format!(
            "--gltf-scene {n} picks a scene of a glTF file, and scene '{name}' is not one: give \
             --scene the path of a .gltf or .glb file, or leave --gltf-scene out"
        ))),
    }
}

/// [`load_gltf`] of a file already in memory: `path` names it in messages and locates external
/// buffers and images (relative to its folder).
pub fn parse_gltf(path: &Path, bytes: &[u8], scene_index: Option<usize>) -> Result<Scene, OitError> {
    let err = |message: String| OitError::Model { path: path.to_path_buf(), message };
    let (json, blob) = split_glb(bytes).map_err(err)?;
    let document = read_document(json).map_err(err)?;
    let mut warnings = Vec::new();
    let unread: Vec<&str> = document.extensions_used().filter(|e| !GLTF_EXTENSIONS.contains(e)).collect();
    if !unread.is_empty() {
        warnings.push(format!(
            "{}: extensions not read (drawn without them): {}",
            path.display(),
            unread.join(", ")
        ));
    }
    let scene = match scene_index {
        Some(i) => document.scenes().nth(i).ok_or_else(|| {
            let n = document.scenes().count();
            err(format!(
                "scene {i} does not exist: the file has {n} scene{} (numbered from 0)",
                if n == 1 { "" } else { "s" }
            ))
        })?,
        None => document
            .default_scene()
            .or_else(|| document.scenes().next())
            .ok_or_else(|| err("the file has no scene".into()))?,
    };
    let draws = walk(&document, &scene).map_err(err)?;
    // every accessor a drawn primitive reads, checked before any buffer is loaded
    let mut checked = vec![false; document.meshes().len()];
    for (mesh, _) in &draws {
        if !std::mem::replace(&mut checked[mesh.index()], true) {
            for prim in mesh.primitives() {
                check_primitive(mesh, &prim).map_err(err)?;
            }
        }
    }
    let limit = crate::obj::model_byte_limit()?;
    let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let buffers = load_buffers(&document, base, blob, limit).map_err(err)?;
    let name = path.file_stem().map_or_else(|| "gltf".to_string(), |s| s.to_string_lossy().into_owned());
    let mut out = Scene { name, ..Scene::default() };
    let mut images = Images { base, limit, decoded: Vec::new(), made: std::collections::HashMap::new() };
    // one mesh and one object per (mesh, primitive), made the first time a node draws it
    let mut made: std::collections::HashMap<(usize, usize), usize> = std::collections::HashMap::new();
    let mut notes = Notes::default();
    // per object, its volume's absorption where its material bounds one
    let mut volumes: Vec<Option<VolumeRead>> = Vec::new();
    for (mesh, world) in &draws {
        for prim in mesh.primitives() {
            let key = (mesh.index(), prim.index());
            let object = match made.get(&key) {
                Some(&o) => o,
                None => {
                    let mut m = primitive_mesh(mesh, &prim, &buffers).map_err(err)?;
                    let (mut o, volume) = material_object(mesh, &prim, out.meshes.len()).map_err(err)?;
                    o.texture = base_texture(&document, &prim, &buffers, &mut images, &mut out, &mut notes)
                        .map_err(err)?;
                    if o.texture.is_some() && m.uvs.is_none() {
                        return Err(err(format!("{}: a base-colour texture without TEXCOORD_0", m.name)));
                    }
                    if o.texture.is_none() {
                        // coordinates no texture reads are not kept (oit refuses them as unused)
                        m.uvs = None;
                    }
                    out.meshes.push(m);
                    out.objects.push(o);
                    volumes.push(volume);
                    made.insert(key, out.objects.len() - 1);
                    out.objects.len() - 1
                }
            };
            out.instances.push(Instance { object, transform: *world });
        }
        if out.instances.len() as u64 > Scene::MAX_INSTANCES {
            Scene::check_size(&out.name, out.triangle_count(), out.instances.len() as u64)?;
        }
    }
    if out.instances.is_empty() {
        return Err(err("its scene draws no triangles (no node has a mesh of triangles)".into()));
    }
    Scene::check_size(&out.name, out.triangle_count(), out.instances.len() as u64)?;
    // what loads is what every backend takes: a transform or a vertex past oit's limits is the
    // file's error, not a scene that fails later
    let bounds = out.validated_bounds().map_err(|e| err(format!("it is not a scene oit can draw: {e}")))?;
    apply_volumes(&mut out, &volumes, bounds.radius(), &mut notes).map_err(err)?;
    warnings.extend(notes.lines(path));
    out.warnings = warnings;
    Ok(out)
}

/// A GLB chunk: its body and its type.
type Chunk<'a> = (&'a [u8], [u8; 4]);

/// An image's width, height and RGBA8 texels.
type Pixels = (u32, u32, Vec<[u8; 4]>);

/// The JSON of a GLB and its binary chunk, or the whole of a `.gltf` as JSON. Chunks after the
/// JSON chunk other than `BIN` are skipped, as the format asks; a file cut short says where.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok((bytes, None));
    }
    let word = |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!("a GLB cut short in its 12-byte header (the file has {} bytes)", bytes.len()));
    };
    if version != 2 {
        return Err(format!("a GLB of version {version}: only glTF 2.0 (version 2) is read"));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!(
            "a GLB cut short: its header says {length} bytes and the file has {}",
            bytes.len()
        ));
    }
    let mut rest = &bytes[12.min(length)..length];
    let mut chunk = |what: &str| -> Result<Option<Chunk<'_>>, String> {
        if rest.is_empty() {
            return Ok(None);
        }
        if rest.len() < 8 {
            return Err(format!("a GLB cut short in the header of its {what} chunk"));
        }
        let size = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        let kind = [rest[4], rest[5], rest[6], rest[7]];
        let body = &rest[8..];
        if size > body.len() {
            return Err(format!(
                "a GLB cut short in its {} chunk: {size} bytes announced, {} there",
                if &kind == b"JSON" {
                    "JSON"
                } else if &kind == b"BIN\0" {
                    "BIN"
                } else {
                    what
                },
                body.len()
            ));
        }
        rest = &body[size..];
        Ok(Some((&body[..size], kind)))
    };
    let json = match chunk("JSON")? {
        Some((json, kind)) if &kind == b"JSON" => json,
        Some((_, kind)) => {
            return Err(format!(
                "a GLB whose first chunk is not JSON (its type is {:?})",
                String::from_utf8_lossy(&kind)
            ));
        }
        None => return Err("a GLB without its JSON chunk".into()),
    };
    let mut bin = None;
    while let Some((body, kind)) = chunk("next")? {
        if &kind == b"BIN\0" {
            if bin.is_some() {
                return Err("a GLB of two BIN chunks (it may have one)".into());
            }
            bin = Some(body);
        }
    }
    Ok((json, bin))
}

/// The glTF document of `json`: parsed, the indices the `gltf` crate's own checks follow
/// checked first, then checked by the crate (indices, enumerations, required fields and
/// extensions).
fn read_document(json: &[u8]) -> Result<gltf::Document, String> {
    let mut root: gltf::json::Root = gltf::json::deserialize::from_slice(json).map_err(|e| {
        if e.is_syntax() || e.is_eof() {
            format!("not a glTF file: its JSON does not parse ({e})")
        } else {
            format!("its JSON is not a glTF 2.0 document: {e}")
        }
    })?;
    // the crate reads KHR_materials_volume (with its feature) but leaves it out of the list of
    // extensions a file may require (gltf-json 1.4's ENABLED_EXTENSIONS), so its check would
    // refuse a file that requires it: oit reads it, and takes it off that list before the check
    root.extensions_required.retain(|e| e != "KHR_materials_volume");
    // the crate's check of a primitive reads its POSITION accessor without checking the index
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: {} names accessor {}, and the file has {}",
                        semantic.to_string(),
                        index.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let listed: Vec<String> =
                errors.iter().take(LISTED_ERRORS).map(|(path, e)| format!("{path}: {e}")).collect();
            let more = errors.len().saturating_sub(LISTED_ERRORS);
            let text = format!(
                "{}{}",
                listed.join("; "),
                if more > 0 { format!("; {more} more") } else { String::new() }
            );
            // a required extension the crate has no reader for is refused by it, by name (and
            // oit builds it with readers for only those it reads)
            if errors.iter().any(|(path, _)| path.as_str().starts_with("extensionsRequired")) {
                format!(
                    "the file requires an extension oit does not read (it reads {}): {text}",
                    GLTF_EXTENSIONS.join(", ")
                )
            } else {
                format!("not a valid glTF 2.0 file: {text}")
            }
        }
        other => format!("not a valid glTF 2.0 file: {other}"),
    })
}

/// The meshes `scene` draws and the world transform of each, depth first in the file's order.
/// The hierarchy must be a set of trees (glTF's rule): a node reached twice — a loop, or a node
/// with two parents — is refused, which also bounds the walk by the file's nodes.
fn walk<'a>(
    document: &'a gltf::Document,
    scene: &gltf::Scene<'a>,
) -> Result<Vec<(gltf::Mesh<'a>, Mat4)>, String> {
    let mut seen = vec![false; document.nodes().len()];
    let mut draws = Vec::new();
    let roots: Vec<_> = scene.nodes().collect();
    let mut stack: Vec<(gltf::Node<'_>, Mat4, usize)> =
        roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err(format!("the node hierarchy is deeper than {MAX_DEPTH}"));
        }
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(format!(
                "node {} is reached twice from scene {}: the node hierarchy loops, or a node has two \
                 parents (glTF's nodes form trees)",
                node.index(),
                scene.index()
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            draws.push((mesh, world));
        }
        // children pushed in reverse, so that they are drawn in the file's order
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world, depth + 1)));
    }
    Ok(draws)
}

/// Checks every accessor `prim` will have read: [`check_accessor`] with the types glTF allows
/// for its attribute.
fn check_primitive(mesh: &gltf::Mesh<'_>, prim: &gltf::Primitive<'_>) -> Result<(), String> {
    use gltf::Semantic;
    use gltf::accessor::DataType::{F32, U8, U16, U32};
    use gltf::accessor::Dimensions::{Scalar, Vec2, Vec3, Vec4};
    let at = format!("mesh {} primitive {}", mesh.index(), prim.index());
    for (semantic, accessor) in prim.attributes() {
        let allowed: (&[gltf::accessor::Dimensions], &[gltf::accessor::DataType]) = match semantic {
            Semantic::Positions | Semantic::Normals => (&[Vec3], &[F32]),
            Semantic::TexCoords(0) => (&[Vec2], &[F32, U8, U16]),
            Semantic::Colors(0) => (&[Vec3, Vec4], &[F32, U8, U16]),
            // the others are not read
            _ => continue,
        };
        check_accessor(&accessor, &format!("{at}: {}", semantic.to_string()), allowed)?;
    }
    if let Some(indices) = prim.indices() {
        check_accessor(&indices, &format!("{at}: its indices"), (&[Scalar], &[U8, U16, U32]))?;
    }
    Ok(())
}

/// Checks an accessor before it is read: not sparse, of a type in `allowed`, of 1 to
/// [`MAX_VERTICES`] elements, its offsets and stride aligned to its components, its elements
/// within its buffer view and the view within its buffer (as the buffer declares its length; the
/// buffer's data is checked against that when loaded).
fn check_accessor(
    a: &gltf::Accessor<'_>,
    what: &str,
    allowed: (&[gltf::accessor::Dimensions], &[gltf::accessor::DataType]),
) -> Result<(), String> {
    let what = format!("{what} (accessor {})", a.index());
    if a.sparse().is_some() {
        return Err(format!("{what}: sparse accessors are not read"));
    }
    if !allowed.0.contains(&a.dimensions()) || !allowed.1.contains(&a.data_type()) {
        return Err(format!(
            "{what}: of type {:?} {:?}, which glTF does not allow there",
            a.dimensions(),
            a.data_type()
        ));
    }
    let count = a.count();
    if count == 0 {
        return Err(format!("{what}: an accessor of 0 elements (glTF asks for 1 or more)"));
    }
    if count > MAX_VERTICES {
        return Err(format!("{what}: an accessor of {count} elements, over the limit of {MAX_VERTICES}"));
    }
    let Some(view) = a.view() else {
        return Err(format!("{what}: an accessor without a buffer view"));
    };
    let component = a.data_type().size() as u64;
    let element = a.size() as u64;
    let stride = view.stride().map_or(element, |s| s as u64);
    let (offset, view_offset) = (a.offset() as u64, view.offset() as u64);
    // offsets are any u64 the file writes: sums saturate (a saturated end is past any view)
    if !offset.is_multiple_of(component) || !offset.wrapping_add(view_offset).is_multiple_of(component) {
        return Err(format!(
            "{what}: misaligned: its offset {offset} in buffer view {} (at {view_offset} in its buffer) is \
             not a multiple of its {component}-byte components",
            view.index()
        ));
    }
    if stride < element || !stride.is_multiple_of(component) {
        return Err(format!(
            "{what}: buffer view {}'s byteStride {stride} does not fit its {element}-byte elements",
            view.index()
        ));
    }
    // count ≤ 2^26 and stride ≤ 252 (the crate checks it): their product does not overflow
    let end = offset.saturating_add(stride * (count as u64 - 1) + element);
    if end > view.length() as u64 {
        return Err(format!(
            "{what}: {count} elements from byte {offset} end at byte {end}, past the {} bytes of buffer view {}",
            view.length(),
            view.index()
        ));
    }
    check_view(&view)
}

/// Checks that a buffer view lies within its buffer (as the buffer declares its length).
fn check_view(view: &gltf::buffer::View<'_>) -> Result<(), String> {
    let end = (view.offset() as u64).saturating_add(view.length() as u64);
    let buffer = view.buffer();
    if end > buffer.length() as u64 {
        return Err(format!(
            "buffer view {} ends at byte {end}, past the {} bytes of buffer {}",
            view.index(),
            buffer.length(),
            buffer.index()
        ));
    }
    Ok(())
}

/// The data of every buffer: the GLB's binary chunk (borrowed), a data URI or a file beside the
/// glTF file; each at least as long as it declares.
fn load_buffers<'b>(
    document: &gltf::Document,
    base: &Path,
    blob: Option<&'b [u8]>,
    limit: u64,
) -> Result<Vec<Cow<'b, [u8]>>, String> {
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let what = format!("buffer {}", buffer.index());
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => Cow::Borrowed(
                blob.ok_or_else(|| format!("{what} is the GLB's binary chunk, and the file has none"))?,
            ),
            gltf::buffer::Source::Uri(uri) => Cow::Owned(read_uri(uri, base, limit, &what)?),
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "{what} holds {} bytes, fewer than its byteLength of {}",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes a URI names: a base64 data URI, or a file by a path relative to `base` (percent
/// escapes decoded) read as a model file is (regular files only, at most `limit` bytes). Other
/// schemes are refused.
fn read_uri(uri: &str, base: &Path, limit: u64, what: &str) -> Result<Vec<u8>, String> {
    if let Some(data) = uri.strip_prefix("data:") {
        let Some((_, payload)) = data.split_once(";base64,") else {
            return Err(format!("{what}: a data URI that is not base64"));
        };
        return base64(payload).ok_or_else(|| format!("{what}: a data URI whose base64 does not decode"));
    }
    // a scheme is letters before a ':' that comes before any '/'
    if let Some((scheme, _)) = uri.split_once(':')
        && !scheme.contains('/')
        && scheme.len() > 1
    {
        return Err(format!(
            "{what}: the URI '{uri}' is not read (its scheme {scheme}: — oit reads relative paths and \
             base64 data URIs)"
        ));
    }
    // a relative reference, as glTF's URIs are: `base.join` of an absolute path (`/etc/...`,
    // `C:\...`, `\\server\...`) would read it wherever it is
    let relative = percent_decode(uri);
    if relative.has_root() || relative.is_absolute() || uri.starts_with(['/', '\\']) {
        return Err(format!(
            "{what}: the URI '{uri}' is an absolute path (glTF's URIs are relative to the file; oit reads those and base64 data URIs)"
        ));
    }
    let path = base.join(relative);
    crate::obj::read_bounded_bytes(&path, limit, "glTF buffer and image")
        .map_err(|e| format!("{what}: '{uri}': {}", describe(&path, e)))
}

/// A read error about `path` as a message part (the path once).
fn describe(path: &Path, e: OitError) -> String {
    match e {
        OitError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            format!("file {} not found", path.display())
        }
        OitError::Io { source, .. } => format!("cannot read {}: {source}", path.display()),
        OitError::Obj { message, .. } => format!("{}: {message}", path.display()),
        other => other.to_string(),
    }
}

/// A URI's path with its `%XX` escapes decoded (a malformed escape kept as it is).
fn percent_decode(uri: &str) -> PathBuf {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let hex = |b: u8| (b as char).to_digit(16).map(|d| d as u8);
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && let (Some(h), Some(l)) =
                (bytes.get(i + 1).copied().and_then(hex), bytes.get(i + 2).copied().and_then(hex))
        {
            out.push((h << 4) | l);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    #[cfg(unix)]
    {
        PathBuf::from(<std::ffi::OsString as std::os::unix::ffi::OsStringExt>::from_vec(out))
    }
    #[cfg(not(unix))]
    {
        PathBuf::from(String::from_utf8_lossy(&out).into_owned())
    }
}

/// Standard base64 (padding optional, no whitespace); `None` for any other character.
fn base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let text = text.trim_end_matches('=').as_bytes();
    if text.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 2);
    for group in text.chunks(4) {
        let mut bits = 0u32;
        for &c in group {
            bits = (bits << 6) | value(c)?;
        }
        bits <<= 6 * (4 - group.len() as u32);
        let bytes = bits.to_be_bytes();
        out.extend_from_slice(&bytes[1..group.len()]);
    }
    Some(out)
}

/// The images decoded so far, and the textures made of them.
struct Images<'p> {
    base: &'p Path,
    limit: u64,
    /// Per image index, its decoded pixels once a material has sampled it.
    decoded: Vec<Option<Pixels>>,
    /// One texture per (image, wrap modes), made the first time a material samples it.
    made: std::collections::HashMap<(usize, [Wrap; 2]), usize>,
}

impl Images<'_> {
    /// Decodes image `index` of `document` (once).
    fn decode(
        &mut self,
        document: &gltf::Document,
        index: usize,
        buffers: &[Cow<'_, [u8]>],
    ) -> Result<&Pixels, String> {
        if self.decoded.len() <= index {
            self.decoded.resize_with(index + 1, || None);
        }
        if self.decoded[index].is_none() {
            let json = document.as_json();
            let image = json.images.get(index).ok_or_else(|| format!("image {index} does not exist"))?;
            let what = match &image.name {
                Some(n) => format!("image {index} ('{n}')"),
                None => format!("image {index}"),
            };
            let mime = image.mime_type.as_ref().map(|m| m.0.as_str());
            let bytes: Cow<'_, [u8]> = match (&image.buffer_view, &image.uri) {
                (Some(v), _) => {
                    let view = document
                        .views()
                        .nth(v.value())
                        .ok_or_else(|| format!("{what}: buffer view {} does not exist", v.value()))?;
                    check_view(&view).map_err(|e| format!("{what}: {e}"))?;
                    let data = &buffers[view.buffer().index()];
                    Cow::Borrowed(&data[view.offset()..view.offset() + view.length()])
                }
                (None, Some(uri)) => Cow::Owned(read_uri(uri, self.base, self.limit, &what)?),
                (None, None) => return Err(format!("{what} has neither a uri nor a buffer view")),
            };
            self.decoded[index] = Some(decode_image(&bytes, mime, &what)?);
        }
        Ok(self.decoded[index].as_ref().expect("decoded above"))
    }
}

/// Decodes a PNG or JPEG (by its MIME type, else by its bytes) into RGBA8, with
/// [`crate::texture::decode_limited`]'s limits.
fn decode_image(bytes: &[u8], mime: Option<&str>, what: &str) -> Result<Pixels, String> {
    use image::ImageFormat;
    let format = match mime {
        Some("image/png") => ImageFormat::Png,
        Some("image/jpeg") => ImageFormat::Jpeg,
        _ => match image::guess_format(bytes) {
            Ok(f @ (ImageFormat::Png | ImageFormat::Jpeg)) => f,
            _ => return Err(format!("{what}: not a PNG or JPEG image (the formats glTF allows)")),
        },
    };
    let image = crate::texture::decode_limited(bytes, format, what)?;
    let (width, height) = (image.width(), image.height());
    let texels = image.into_rgba8().into_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Ok((width, height, texels))
}

/// What the file asked for that oit does not draw yet: one warning each.
#[derive(Default)]
struct Notes {
    other_coordinates: bool,
    /// A volume's attenuation colour that oit's per-channel absorption does not represent.
    attenuation: bool,
    /// Volumes of different absorptions (the effect has one medium per scene).
    media: bool,
}

impl Notes {
    fn lines(&self, path: &Path) -> Vec<String> {
        let p = path.display();
        let mut out = Vec::new();
        if self.other_coordinates {
            out.push(format!("{p}: a texture on a coordinate set other than TEXCOORD_0 is not drawn"));
        }
        if self.attenuation {
            out.push(format!(
                "{p}: KHR_materials_volume: an attenuationColor whose absorption is not proportional to 1 − \
                 baseColorFactor is drawn as the mean over its channels (oit's translucency absorbs (1 − colour)·k)"
            ));
        }
        if self.media {
            out.push(format!(
                "{p}: KHR_materials_volume: the volumes absorb differently, and the translucency effect has one \
                 medium per scene: they are drawn with their mean absorption"
            ));
        }
        out
    }
}

/// The mesh of one primitive: triangles from its mode, indices or vertex order. Its accessors
/// were checked ([`check_primitive`]) and its buffers loaded.
fn primitive_mesh(
    mesh: &gltf::Mesh<'_>,
    prim: &gltf::Primitive<'_>,
    buffers: &[Cow<'_, [u8]>],
) -> Result<Mesh, String> {
    let name = match mesh.name() {
        Some(n) => format!("{n} #{}", prim.index()),
        None => format!("mesh {} #{}", mesh.index(), prim.index()),
    };
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| format!("{name}: a primitive without POSITION"))?
        .map(Vec3::from_array)
        .collect();
    let n = positions.len() as u32;
    let order: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None if prim.indices().is_some() => return Err(format!("{name}: its indices cannot be read")),
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
    document: &gltf::Document,
    prim: &gltf::Primitive<'_>,
    buffers: &[Cow<'_, [u8]>],
    images: &mut Images<'_>,
    out: &mut Scene,
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
    if let Some(&t) = images.made.get(&(index, wraps)) {
        return Ok(Some(t));
    }
    let name = texture.source().name().map_or_else(|| format!("image {index}"), str::to_string);
    let (width, height, texels) = images.decode(document, index, buffers)?.clone();
    let t = Texture::new(name, width, height, texels, wraps).map_err(|e| e.to_string())?;
    out.textures.push(t);
    images.made.insert((index, wraps), out.textures.len() - 1);
    Ok(Some(out.textures.len() - 1))
}

/// A material's `KHR_materials_volume`, where it bounds a volume (`thicknessFactor` above 0).
#[derive(Clone, Copy, Debug)]
struct VolumeRead {
    /// `attenuationDistance`, in world units (infinite where the file leaves it out).
    distance: f32,
    /// `attenuationColor`.
    attenuation: Vec3,
}

/// The object of one primitive: its material as oit reads it, and its volume where it bounds one
/// (its absorption is set once the scene's radius is known, [`apply_volumes`]).
fn material_object(
    mesh: &gltf::Mesh<'_>,
    prim: &gltf::Primitive<'_>,
    index: usize,
) -> Result<(Object, Option<VolumeRead>), String> {
    let material = prim.material();
    let pbr = material.pbr_metallic_roughness();
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
    o.double_sided = material.double_sided();
    let Some(volume) = material.volume() else { return Ok((o, None)) };
    let what = match (material.index(), material.name()) {
        (Some(i), Some(n)) => format!("material {i} ('{n}')"),
        (i, _) => format!("material {}", i.unwrap_or(0)),
    };
    let (thickness, distance) = (volume.thickness_factor(), volume.attenuation_distance());
    let attenuation = Vec3::from_array(volume.attenuation_color());
    if !(thickness.is_finite() && thickness >= 0.0) {
        return Err(format!(
            "{what}: KHR_materials_volume's thicknessFactor {thickness} is not finite and ≥ 0"
        ));
    }
    if distance.is_nan() || distance <= 0.0 {
        return Err(format!("{what}: KHR_materials_volume's attenuationDistance {distance} is not above 0"));
    }
    if !attenuation.is_finite() || attenuation.min_element() < 0.0 || attenuation.max_element() > 1.0 {
        return Err(format!(
            "{what}: KHR_materials_volume's attenuationColor {:?} is outside [0, 1]",
            attenuation.to_array()
        ));
    }
    o.thickness = thickness;
    // a volume boundary: both sides, whatever doubleSided says
    o.double_sided |= thickness > 0.0;
    Ok((o, (thickness > 0.0).then_some(VolumeRead { distance, attenuation })))
}

/// The absorption ([`Object::absorption`]) that makes the translucency effect's medium absorb,
/// in a scene of bounding radius `radius` (world units), the mean over the channels of glTF's
/// `σ = −ln(attenuation) / distance` (per world unit) for a layer of colour `color`:
/// `mean(σ) / mean(1 − color) · radius / 8` ([`Scene::absorption_per_length`] divides by
/// `radius / 8` again). 0 where `σ` is 0 (an infinite distance, a white attenuation colour) and
/// where `color` is white, which absorbs nothing in oit's model. The flag says whether oit's
/// per-channel absorption `(1 − color)·k` is `σ` on every channel (each within 10⁻³ of `σ`'s
/// largest channel); a channel of `attenuation` at 0 is read as the smallest positive `f32`.
/// The module docs say why ([`crate::load_gltf`]).
pub fn volume_absorption(color: Vec3, distance: f32, attenuation: Vec3, radius: f32) -> (f32, bool) {
    let sigma = attenuation.as_dvec3().to_array().map(|a| {
        let d = f64::from(distance);
        if d.is_infinite() { 0.0 } else { -a.max(f64::from(f32::MIN_POSITIVE)).ln() / d }
    });
    let open = (glam::DVec3::ONE - color.as_dvec3()).to_array();
    let (s, w) = (sigma.iter().sum::<f64>() / 3.0, open.iter().sum::<f64>() / 3.0);
    if s <= 0.0 {
        return (0.0, true);
    }
    if w <= 0.0 {
        return (0.0, false);
    }
    let k = s / w;
    let largest = sigma.iter().copied().fold(0.0, f64::max);
    let exact = sigma.iter().zip(open).all(|(&sg, o)| (o * k - sg).abs() <= 1e-3 * largest);
    ((k * f64::from(radius).max(1e-6) / 8.0) as f32, exact)
}

/// Sets each object's absorption from the volumes read (`volumes`, one per object): a volume
/// its [`volume_absorption`], every other object the volumes' mean; nothing where there is no
/// volume (every object keeps oit's default). A volume that absorbs more than an `f32` holds is
/// refused with its object's name.
fn apply_volumes(
    scene: &mut Scene,
    volumes: &[Option<VolumeRead>],
    radius: f32,
    notes: &mut Notes,
) -> Result<(), String> {
    let values: Vec<Option<f32>> = scene
        .objects
        .iter()
        .zip(volumes)
        .map(|(o, v)| {
            v.map(|v| {
                let (a, exact) = volume_absorption(o.color.truncate(), v.distance, v.attenuation, radius);
                notes.attenuation |= !exact;
                a
            })
        })
        .collect();
    if let Some((o, _)) = scene.objects.iter().zip(&values).find(|(_, v)| v.is_some_and(|a| !a.is_finite())) {
        return Err(format!(
            "'{}': its KHR_materials_volume absorbs more than oit can hold (attenuationDistance too small)",
            o.name
        ));
    }
    let read: Vec<f32> = values.iter().flatten().copied().collect();
    if read.is_empty() {
        return Ok(());
    }
    let mean = (read.iter().map(|&a| f64::from(a)).sum::<f64>() / read.len() as f64) as f32;
    notes.media = read.iter().any(|&a| (a - mean).abs() > 1e-3 * mean);
    for (o, v) in scene.objects.iter_mut().zip(values) {
        o.absorption = v.unwrap_or(mean);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GLB of `json` (its `buffers[0]` the binary chunk `bin`).
    pub(crate) fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        crate::pack_glb(json.as_bytes(), bin).expect("a small GLB")
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
        // no material: glTF's default, opaque white, single-sided (drawn so, nothing to warn of)
        assert_eq!((default.color, default.alpha_mode), (Vec4::ONE, AlphaMode::Opaque));
        assert!(!default.double_sided && blend.double_sided);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
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

    /// The quad document with material 0 blended in `color` and `volume` as its
    /// `KHR_materials_volume` (the strip of mesh 1 keeps glTF's default material, opaque). The
    /// scene's bounds run from (0, 0, 0) to (2, 2, 0): radius √2.
    fn with_volume(color: [f32; 3], volume: &str) -> Result<Scene, OitError> {
        let materials = format!(
            r#"[{{"pbrMetallicRoughness":{{"baseColorFactor":[{},{},{},0.5]}},"alphaMode":"BLEND","doubleSided":true,
            "extensions":{{"KHR_materials_volume":{volume}}}}}]"#,
            color[0], color[1], color[2]
        );
        parse(&document(NODES, MESHES, &materials, r#","extensionsUsed":["KHR_materials_volume"]"#))
    }

    /// `KHR_materials_volume` onto the translucency effect: mean(σ) / mean(1 − c) per unit of
    /// length, the scene's one medium, its objects without a volume taking the volume's value.
    #[test]
    fn volumes_feed_the_translucency_effect() {
        let radius = 2f64.sqrt();
        // an attenuation colour of exp(−(1 − c)·t): σ = (1 − c)·t / distance on every channel,
        // which oit represents exactly; here σ = (1.6, 0.8, 0), k = 0.8 / 0.4 = 2
        let c = [0.2f32, 0.6, 1.0];
        let a = c.map(|c| (-(1.0 - f64::from(c))).exp());
        let s = with_volume(
            c,
            &format!(
                r#"{{"thicknessFactor":0.1,"attenuationDistance":0.5,"attenuationColor":[{},{},{}]}}"#,
                a[0], a[1], a[2]
            ),
        )
        .expect("loads");
        let volume_lines =
            |s: &Scene| s.warnings.iter().filter(|w| w.contains("KHR_materials_volume")).count();
        assert_eq!(volume_lines(&s), 0, "{:?}", s.warnings);
        assert_eq!(s.objects[0].thickness, 0.1);
        let expected = 2.0 * radius / 8.0;
        for o in &s.objects {
            assert!((f64::from(o.absorption) - expected).abs() < 1e-6, "{}: {}", o.name, o.absorption);
        }
        assert!((s.absorption_per_length() - 2.0).abs() < 1e-5, "{}", s.absorption_per_length());
        // a grey attenuation: σ = ln 2 / 2 on every channel, its mean kept (k = 0.3466 / 0.4),
        // and one line says the channels are not drawn as they are
        let s = with_volume(
            c,
            r#"{"thicknessFactor":1,"attenuationDistance":2,"attenuationColor":[0.5,0.5,0.5]}"#,
        )
        .expect("loads");
        let k = 2f64.ln() / 2.0 / 0.4;
        assert!(
            (f64::from(s.objects[0].absorption) - k * radius / 8.0).abs() < 1e-6,
            "{}",
            s.objects[0].absorption
        );
        assert!((s.absorption_per_length() - k).abs() < 1e-5);
        let said: Vec<_> = s.warnings.iter().filter(|w| w.contains("KHR_materials_volume")).collect();
        assert!(said.len() == 1 && said[0].contains("attenuationColor"), "{:?}", s.warnings);
        // the same absorption through the public mapping, and a white base colour absorbs nothing
        let (got, exact) = volume_absorption(Vec3::from_array(c), 2.0, Vec3::splat(0.5), radius as f32);
        assert!(!exact && (f64::from(got) - k * radius / 8.0).abs() < 1e-6);
        assert_eq!(volume_absorption(Vec3::ONE, 2.0, Vec3::splat(0.5), 1.0), (0.0, false));
        // an infinite distance (left out): no absorption, for the volume and the scene
        let s = with_volume(c, r#"{"thicknessFactor":0.1,"attenuationColor":[0.1,0.2,0.3]}"#).expect("loads");
        assert!(s.objects.iter().all(|o| o.absorption == 0.0), "{:?}", s.objects);
        assert_eq!(s.absorption_per_length(), 0.0);
        assert_eq!(volume_lines(&s), 0, "{:?}", s.warnings);
        // a volume boundary is drawn from both sides whatever doubleSided says; a thin wall as
        // it says
        let single = |volume: &str| {
            let materials =
                format!(r#"[{{"alphaMode":"BLEND","extensions":{{"KHR_materials_volume":{volume}}}}}]"#);
            parse(&document(NODES, MESHES, &materials, "")).expect("loads").objects[0].double_sided
        };
        assert!(single(r#"{"thicknessFactor":0.5}"#) && !single("{}"));
        // thickness 0 (glTF's default): thin-walled, no volume; the file has none, so every
        // object keeps oit's default
        let s =
            with_volume(c, r#"{"attenuationDistance":0.5,"attenuationColor":[0.1,0.2,0.3]}"#).expect("loads");
        assert!(s.objects.iter().all(|o| o.absorption == 1.0 && o.thickness == 0.0), "{:?}", s.objects);
        // two volumes of different media: their mean, said in one line
        let materials = r#"[{"alphaMode":"BLEND","pbrMetallicRoughness":{"baseColorFactor":[0,0,0,0.5]},
            "extensions":{"KHR_materials_volume":{"thicknessFactor":1,"attenuationDistance":1,"attenuationColor":[0.5,0.5,0.5]}}},
            {"alphaMode":"BLEND","pbrMetallicRoughness":{"baseColorFactor":[0,0,0,0.5]},
            "extensions":{"KHR_materials_volume":{"thicknessFactor":1,"attenuationDistance":3,"attenuationColor":[0.5,0.5,0.5]}}}]"#;
        let meshes = MESHES.replace(r#""mode":5}"#, r#""mode":5,"material":1}"#);
        let s = parse(&document(NODES, &meshes, materials, "")).expect("loads");
        let (k0, k1) = (2f64.ln(), 2f64.ln() / 3.0);
        assert!((s.absorption_per_length() - (k0 + k1) / 2.0).abs() < 1e-5, "{}", s.absorption_per_length());
        assert!(s.warnings.iter().any(|w| w.contains("one medium per scene")), "{:?}", s.warnings);
        // what glTF does not allow is refused with the material's name
        for (volume, says) in [
            (r#"{"thicknessFactor":-1}"#, "thicknessFactor -1 is not finite and ≥ 0"),
            (r#"{"thicknessFactor":1,"attenuationDistance":0}"#, "attenuationDistance 0 is not above 0"),
            (r#"{"thicknessFactor":1,"attenuationDistance":-2}"#, "attenuationDistance -2 is not above 0"),
            (
                r#"{"thicknessFactor":1,"attenuationColor":[1.5,0,0]}"#,
                "attenuationColor [1.5, 0.0, 0.0] is outside [0, 1]",
            ),
            (
                r#"{"thicknessFactor":1,"attenuationDistance":1e-44,"attenuationColor":[0,0,0]}"#,
                "absorbs more than oit can hold",
            ),
        ] {
            let e = with_volume(c, volume).expect_err(volume).to_string();
            assert!(e.contains(says) && e.contains("test.glb"), "{volume}: {e}");
        }
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
        // every extension the glTF crate is built to read, oit reads: a file may require them
        for name in GLTF_EXTENSIONS {
            let extra = format!(r#","extensionsUsed":["{name}"],"extensionsRequired":["{name}"]"#);
            parse(&document(NODES, MESHES, BLEND, &extra)).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
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
        assert!(e.contains("not a glTF 2.0 document"), "{e}");
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

    /// The quad document of [`document`] with `edits` (pairs of text and its replacement) made.
    fn edited(edits: &[(&str, &str)]) -> String {
        let mut json = document(NODES, MESHES, BLEND, "");
        for (from, to) in edits {
            assert!(json.contains(from), "{from} is in the document");
            json = json.replacen(from, to, 1);
        }
        json
    }

    /// The error of `bytes` as `name`, checked to be a model error naming the file; a panic
    /// fails the test with the input's name.
    fn refused(name: &str, bytes: &[u8]) -> String {
        let result = std::panic::catch_unwind(|| parse_gltf(Path::new(name), bytes, None));
        match result {
            Ok(Err(e @ OitError::Model { .. })) => {
                let text = e.to_string();
                assert!(text.contains(name), "{text}");
                text
            }
            Ok(Err(other)) => panic!("{name}: not a model error: {other:?}"),
            Ok(Ok(_)) => panic!("{name}: loaded"),
            Err(_) => panic!("{name}: panicked"),
        }
    }

    /// `bytes` with the GLB header's length set to their length (a file cut and its header
    /// mended, so the cut is found in a chunk).
    fn mended(bytes: &[u8]) -> Vec<u8> {
        let mut out = bytes.to_vec();
        let n = out.len() as u32;
        out[8..12].copy_from_slice(&n.to_le_bytes());
        out
    }

    #[test]
    fn truncated_glbs_are_refused_where_cut() {
        let whole = glb(&document(NODES, MESHES, BLEND, ""), &quad_bin());
        let json_len = u32::from_le_bytes(whole[12..16].try_into().unwrap()) as usize;
        let bin_at = 20 + json_len;
        // in the magic (then not a GLB: not JSON either), in the header, in each chunk's header
        // and body
        for cut in [0, 3] {
            let e = refused("cut.glb", &whole[..cut]);
            assert!(e.contains("not a glTF file") && e.contains("does not parse"), "{cut}: {e}");
        }
        for cut in [4, 7, 11] {
            let e = refused("cut.glb", &whole[..cut]);
            assert!(e.contains("cut short in its 12-byte header"), "{cut}: {e}");
        }
        for cut in
            [12, 17, 19, 20, 40, bin_at - 1, bin_at, bin_at + 5, bin_at + 8, bin_at + 30, whole.len() - 1]
        {
            let e = refused("cut.glb", &whole[..cut]);
            assert!(e.contains("cut short: its header says"), "{cut}: {e}");
        }
        // the header mended to the cut length: the cut is found in its chunk
        let e = refused("cut.glb", &mended(&whole[..12]));
        assert!(e.contains("without its JSON chunk"), "{e}");
        let e = refused("cut.glb", &mended(&whole[..17]));
        assert!(e.contains("cut short in the header of its JSON chunk"), "{e}");
        for cut in [20, 40, bin_at - 1] {
            let e = refused("cut.glb", &mended(&whole[..cut]));
            assert!(e.contains("cut short in its JSON chunk"), "{cut}: {e}");
        }
        let e = refused("cut.glb", &mended(&whole[..bin_at + 5]));
        assert!(e.contains("cut short in the header of its next chunk"), "{e}");
        for cut in [bin_at + 8, bin_at + 30, whole.len() - 1] {
            let e = refused("cut.glb", &mended(&whole[..cut]));
            assert!(e.contains("cut short in its BIN chunk"), "{cut}: {e}");
        }
        // the JSON whole and the BIN chunk gone: its buffer has no data
        let e = refused("cut.glb", &mended(&whole[..bin_at]));
        assert!(e.contains("buffer 0 is the GLB's binary chunk, and the file has none"), "{e}");
        // every cut, mended or not: an error, never a panic
        for cut in 0..whole.len() {
            refused("cut.glb", &whole[..cut]);
            if cut >= 12 {
                refused("cut.glb", &mended(&whole[..cut]));
            }
        }
        // another version, a first chunk that is not JSON
        let mut v1 = whole.clone();
        v1[4] = 1;
        assert!(refused("v1.glb", &v1).contains("version 1"));
        let mut bin_first = whole.clone();
        bin_first[16..20].copy_from_slice(b"BIN\0");
        assert!(refused("b.glb", &bin_first).contains("first chunk is not JSON"));
    }

    #[test]
    fn json_that_is_not_gltf_is_refused() {
        for (json, says) in [
            (&br#"{"hello":1}"#[..], "its JSON is not a glTF 2.0 document: missing field `asset`"),
            (b"[1, 2, 3]", "its JSON is not a glTF 2.0 document"),
            (br#"{"asset":{"version":"2.0"},"meshes":7}"#, "its JSON is not a glTF 2.0 document"),
            (b"\x00\x01\x02 binary", "not a glTF file: its JSON does not parse"),
            (br#"{"asset":"#, "not a glTF file: its JSON does not parse"),
            (b"", "not a glTF file: its JSON does not parse"),
        ] {
            let e = refused("x.gltf", json);
            assert!(e.contains(says), "{e}");
            // the same in a GLB's JSON chunk
            let e = refused("x.glb", &glb(std::str::from_utf8(json).unwrap_or("\u{1}"), &quad_bin()));
            assert!(e.contains("JSON"), "{e}");
        }
        // glTF's shape, its indices broken: the crate's checks, listed
        let e = refused("x.glb", &glb(&edited(&[(r#""bufferView":1,"#, r#""bufferView":7,"#)]), &quad_bin()));
        assert!(e.contains("not a valid glTF 2.0 file") && e.contains("accessors[1].bufferView"), "{e}");
        // a POSITION past the accessors, which the crate's own check would index unchecked
        let e = refused(
            "x.glb",
            &glb(&edited(&[(r#""POSITION":0},"indices""#, r#""POSITION":9},"indices""#)]), &quad_bin()),
        );
        assert!(e.contains("POSITION names accessor 9, and the file has 2"), "{e}");
    }

    #[test]
    fn accessors_out_of_range_or_misaligned_are_refused() {
        let bin = quad_bin();
        for (edits, says) in [
            // five positions in a view of four
            (
                &[(r#""count":4"#, r#""count":5"#)][..],
                "5 elements from byte 0 end at byte 60, past the 48 bytes of buffer view 0",
            ),
            // offsets near 2^64: no overflow, past the view
            (
                &[(
                    r#""componentType":5126,"count":4"#,
                    r#""byteOffset":18446744073709551612,"componentType":5126,"count":4"#,
                )],
                "end at byte 18446744073709551615, past the 48 bytes",
            ),
            (
                &[(
                    r#""byteOffset":0,"byteLength":48}"#,
                    r#""byteOffset":18446744073709551612,"byteLength":48}"#,
                )],
                "buffer view 0 ends at byte 18446744073709551615, past the 60 bytes of buffer 0",
            ),
            // an offset within the view, the last element past it
            (
                &[(r#""componentType":5126,"count":4"#, r#""byteOffset":12,"componentType":5126,"count":4"#)],
                "end at byte 60, past the 48 bytes",
            ),
            // misaligned: a float at byte 2 of its view, the view at an odd byte of its buffer
            (
                &[(r#""componentType":5126,"count":4"#, r#""byteOffset":2,"componentType":5126,"count":3"#)],
                "misaligned: its offset 2",
            ),
            (
                &[(r#""byteOffset":48,"byteLength":12"#, r#""byteOffset":47,"byteLength":12"#)],
                "misaligned: its offset 0 in buffer view 1 (at 47 in its buffer)",
            ),
            // a stride shorter than the elements, or not of whole components
            (
                &[(
                    r#""byteOffset":0,"byteLength":48}"#,
                    r#""byteOffset":0,"byteLength":48,"byteStride":8}"#,
                )],
                "byteStride 8 does not fit its 12-byte elements",
            ),
            (
                &[(
                    r#""byteOffset":0,"byteLength":48}"#,
                    r#""byteOffset":0,"byteLength":48,"byteStride":16}"#,
                )],
                "end at byte 60, past the 48 bytes",
            ),
            // a view past its buffer, a buffer longer than the data
            (
                &[(r#""byteOffset":48,"byteLength":12"#, r#""byteOffset":52,"byteLength":12"#)],
                "buffer view 1 ends at byte 64, past the 60 bytes of buffer 0",
            ),
            (
                &[
                    (r#"{"byteLength":60}"#, r#"{"byteLength":1000}"#),
                    (r#""byteOffset":48,"byteLength":12"#, r#""byteOffset":900,"byteLength":12"#),
                ],
                "buffer 0 holds 60 bytes, fewer than its byteLength of 1000",
            ),
            // types glTF does not allow for the attribute (the crate's reader would not return)
            (
                &[(r#""componentType":5123,"count":6"#, r#""componentType":5126,"count":3"#)],
                "its indices (accessor 1): of type Scalar F32",
            ),
            (
                &[(r#""componentType":5123,"count":6"#, r#""componentType":5122,"count":6"#)],
                "its indices (accessor 1): of type Scalar I16",
            ),
            (&[(r#""type":"VEC3""#, r#""type":"VEC2""#)], "POSITION (accessor 0): of type Vec2 F32"),
            (
                &[(r#""componentType":5126,"count":4"#, r#""componentType":5121,"count":4"#)],
                "POSITION (accessor 0): of type Vec3 U8",
            ),
            (&[(r#""count":4"#, r#""count":0"#)], "an accessor of 0 elements"),
            // more than MAX_VERTICES elements: refused before any buffer is read or allocated
            (
                &[(r#""count":4"#, r#""count":1073741824"#)],
                "an accessor of 1073741824 elements, over the limit of 67108864",
            ),
        ] {
            let e = refused("a.glb", &glb(&edited(edits), &bin));
            assert!(e.contains(says), "{edits:?}: {e}");
        }
        // a vertex colour of a type glTF does not allow
        let json = edited(&[
            (r#""POSITION":0},"indices""#, r#""POSITION":0,"COLOR_0":2},"indices""#),
            (
                r#""type":"SCALAR"}]"#,
                r#""type":"SCALAR"},{"bufferView":0,"componentType":5120,"count":4,"type":"VEC4"}]"#,
            ),
        ]);
        let e = refused("c.glb", &glb(&json, &bin));
        assert!(e.contains("COLOR_0 (accessor 2): of type Vec4 I8"), "{e}");
        // the same file with unsigned bytes loads (4 of them per vertex, 16 bytes in all)
        let ok = json.replace(
            r#""componentType":5120,"count":4,"type":"VEC4""#,
            r#""componentType":5121,"count":4,"type":"VEC4","normalized":true"#,
        );
        let s = parse_gltf(Path::new("c.glb"), &glb(&ok, &bin), None).expect("u8 colours load");
        assert!(s.meshes[0].colors.is_some());
    }

    #[test]
    fn indices_past_the_vertices_are_refused() {
        let mut bin = quad_bin();
        bin[58..60].copy_from_slice(&4u16.to_le_bytes());
        let e = refused("i.glb", &glb(&document(NODES, MESHES, BLEND, ""), &bin));
        assert!(e.contains("quad #0: index 4 past its 4 vertices"), "{e}");
        // u32 indices, in a strip
        let mut bin = quad_bin();
        bin.truncate(48);
        for i in [0u32, 1, 2, 70000] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let json = edited(&[
            (r#"{"byteLength":60}"#, r#"{"byteLength":64}"#),
            (r#""byteOffset":48,"byteLength":12"#, r#""byteOffset":48,"byteLength":16"#),
            (r#""componentType":5123,"count":6"#, r#""componentType":5125,"count":4"#),
            (r#""indices":1,"material":0"#, r#""indices":1,"material":0,"mode":5"#),
        ]);
        let e = refused("i.glb", &glb(&json, &bin));
        assert!(e.contains("index 70000 past its 4 vertices"), "{e}");
    }

    /// A folder of its own under the system's temporary folder.
    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("oit-gltf-test-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn external_and_data_uri_buffers() {
        let dir = temp("external");
        let json =
            |uri: &str| edited(&[(r#"{"byteLength":60}"#, &format!(r#"{{"byteLength":60,"uri":"{uri}"}}"#))]);
        // a missing file: named, and nothing loaded
        let path = dir.join("scene.gltf");
        std::fs::write(&path, json("missing.bin")).unwrap();
        let e = load_gltf(&path, None).expect_err("the buffer is missing");
        assert!(matches!(e, OitError::Model { .. }), "{e:?}");
        let e = e.to_string();
        assert!(e.contains("buffer 0: 'missing.bin': file") && e.contains("not found"), "{e}");
        // the file beside it, its name percent-escaped in the URI
        std::fs::write(dir.join("quad data.bin"), quad_bin()).unwrap();
        std::fs::write(&path, json("quad%20data.bin")).unwrap();
        let s = load_gltf(&path, None).expect("the external buffer loads");
        assert_eq!(s.meshes[0].indices, [[0, 1, 2], [0, 2, 3]]);
        // a folder, a file too short, another scheme, a data URI
        std::fs::write(&path, json(".")).unwrap();
        let e = load_gltf(&path, None).expect_err("a folder").to_string();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::write(dir.join("short.bin"), [0u8; 8]).unwrap();
        std::fs::write(&path, json("short.bin")).unwrap();
        let e = load_gltf(&path, None).expect_err("too short").to_string();
        assert!(e.contains("buffer 0 holds 8 bytes, fewer than its byteLength of 60"), "{e}");
        std::fs::write(&path, json("https://example.com/quad.bin")).unwrap();
        let e = load_gltf(&path, None).expect_err("a web URI").to_string();
        assert!(e.contains("scheme https: — oit reads relative paths"), "{e}");
        // an absolute path, though the file exists (mutation: no root check reads it, and the
        // error is then its length against byteLength)
        let absolute = dir.join("quad data.bin");
        std::fs::write(&path, json(&absolute.display().to_string().replace(' ', "%20"))).unwrap();
        let e = load_gltf(&path, None).expect_err("an absolute path").to_string();
        assert!(e.contains("is an absolute path"), "{e}");
        let encoded = {
            const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
            let mut out = String::new();
            for c in quad_bin().chunks(3) {
                let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
                let n = u32::from_be_bytes([0, b[0], b[1], b[2]]);
                for k in 0..=c.len() {
                    out.push(ALPHABET[(n >> (18 - 6 * k)) as usize & 63] as char);
                }
            }
            out
        };
        let s = parse_gltf(
            Path::new("d.gltf"),
            json(&format!("data:application/octet-stream;base64,{encoded}")).as_bytes(),
            None,
        )
        .expect("a data URI loads");
        assert_eq!(s.meshes[0].positions[2], Vec3::new(1.0, 1.0, 0.0));
        let e = refused("d.gltf", json("data:application/octet-stream;base64,AB*D").as_bytes());
        assert!(e.contains("base64 does not decode"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The textured quad of `textures_and_their_samplers` with `png` as its image (`mime`: its
    /// image's mimeType, if any).
    fn textured(png: &[u8], mime: Option<&str>) -> Vec<u8> {
        let mut bin = quad_bin();
        for uv in [[0f32, 0.], [1., 0.], [1., 1.], [0., 1.]] {
            uv.iter().for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
        }
        let png_at = bin.len();
        bin.extend_from_slice(png);
        let mime = mime.map_or_else(String::new, |m| format!(r#","mimeType":"{m}""#));
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2}},"indices":1,"material":0}}]}}],
            "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}},"doubleSided":true}}],
            "textures":[{{"source":0}}],"images":[{{"bufferView":3{mime}}}],
            "buffers":[{{"byteLength":{}}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}},
                           {{"buffer":0,"byteOffset":60,"byteLength":32}},{{"buffer":0,"byteOffset":{png_at},"byteLength":{}}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}},
                         {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}}]}}"#,
            bin.len(),
            png.len()
        );
        glb(&json, &bin)
    }

    /// A PNG of `width` × `height` grey pixels.
    fn png(width: u32, height: u32) -> Vec<u8> {
        let mut out = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut out),
            &vec![128u8; (width * height) as usize],
            width,
            height,
            image::ExtendedColorType::L8,
        )
        .unwrap();
        out
    }

    #[test]
    fn images_that_do_not_decode_are_refused() {
        let good = png(2, 2);
        let s = parse_gltf(Path::new("t.glb"), &textured(&good, Some("image/png")), None).expect("loads");
        assert_eq!(s.textures[0].texels(), &[[128, 128, 128, 255]; 4][..], "grey read as RGB");
        // without a mimeType (which the crate's importer would panic on): told by its bytes
        parse_gltf(Path::new("t.glb"), &textured(&good, None), None).expect("a PNG by its bytes");
        // garbage, a PNG cut short, a JPEG that is not one, bytes of no format glTF allows
        let mut cut = good.clone();
        cut.truncate(good.len() - 20);
        for (bytes, mime, says) in [
            (
                &b"\x89PNG\r\n\x1a\n but garbage after the signature"[..],
                Some("image/png"),
                "image 0 does not decode as Png",
            ),
            (&cut[..], Some("image/png"), "image 0 does not decode as Png"),
            (b"not a jpeg at all", Some("image/jpeg"), "image 0 does not decode as Jpeg"),
            (b"GIF89a....", None, "image 0: not a PNG or JPEG image"),
        ] {
            let e = refused("t.glb", &textured(bytes, mime));
            assert!(e.contains(says), "{e}");
        }
        // a small PNG whose header claims 16384 × 16384 (a GiB of RGBA): refused before the
        // pixels are allocated, and one past the largest side oit takes
        for (side, says) in [
            (16384u32, "16384 × 16384 pixels from 70 bytes, more than its encoding can hold"),
            (16385, "16385 × 16385 pixels, over the largest side of a texture (16384)"),
        ] {
            let mut big = png(1, 1);
            // IHDR: length, type, width, height, ..., its CRC over type and data
            big[16..20].copy_from_slice(&side.to_be_bytes());
            big[20..24].copy_from_slice(&side.to_be_bytes());
            let crc = crc32fast::hash(&big[12..29]);
            big[29..33].copy_from_slice(&crc.to_be_bytes());
            let e = refused("t.glb", &textured(&big, Some("image/png")));
            assert!(e.contains(says), "{side}: {e}");
        }
        // an image no material samples is not decoded
        let unused = textured(b"garbage", Some("image/png"));
        let json_len = u32::from_le_bytes(unused[12..16].try_into().unwrap()) as usize;
        let json = std::str::from_utf8(&unused[20..20 + json_len])
            .unwrap()
            .replace(r#""material":0"#, r#""material":0,"mode":4"#);
        let json = json.replace(
            r#"{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}},"doubleSided":true}"#,
            r#"{"doubleSided":true}"#,
        );
        let bin = &unused[28 + json_len..];
        parse_gltf(Path::new("t.glb"), &glb(&json, bin), None).expect("an image nothing samples is not read");
    }

    #[test]
    fn sparse_accessors_are_refused_by_name() {
        let json = edited(&[(
            r#""count":4,"type":"VEC3","#,
            r#""count":4,"type":"VEC3","sparse":{"count":1,"indices":{"bufferView":1,"componentType":5123},"values":{"bufferView":0}},"#,
        )]);
        let e = refused("s.glb", &glb(&json, &quad_bin()));
        assert!(e.contains("POSITION (accessor 0): sparse accessors are not read"), "{e}");
    }

    #[test]
    fn node_hierarchies_that_loop_or_share_are_refused() {
        let with_nodes = |nodes: &str, roots: &str| {
            let json = document(nodes, MESHES, BLEND, "")
                .replace(r#""scenes":[{"nodes":[0,1]}]"#, &format!(r#""scenes":[{{"nodes":{roots}}}]"#));
            glb(&json, &quad_bin())
        };
        for (nodes, roots, says) in [
            // a node its own child, two nodes each other's, a loop back to the root
            (r#"[{"mesh":0,"children":[0]}]"#, "[0]", "node 0 is reached twice from scene 0"),
            (r#"[{"mesh":0,"children":[1]},{"mesh":0,"children":[0]}]"#, "[0]", "node 0 is reached twice"),
            (
                r#"[{"children":[1]},{"children":[2]},{"mesh":0,"children":[1]}]"#,
                "[0]",
                "node 1 is reached twice",
            ),
            // a node with two parents, a root listed twice
            (r#"[{"children":[2]},{"children":[2]},{"mesh":0}]"#, "[0,1]", "node 2 is reached twice"),
            (r#"[{"mesh":0}]"#, "[0,0]", "node 0 is reached twice"),
        ] {
            let e = refused("n.glb", &with_nodes(nodes, roots));
            assert!(e.contains(says) && e.contains("loops, or a node has two parents"), "{nodes}: {e}");
        }
        // a chain deeper than the limit
        let chain: Vec<String> = (0..300)
            .map(|i| if i < 299 { format!(r#"{{"children":[{}]}}"#, i + 1) } else { r#"{"mesh":0}"#.into() })
            .collect();
        let e = refused("n.glb", &with_nodes(&format!("[{}]", chain.join(",")), "[0]"));
        assert!(e.contains("deeper than 256"), "{e}");
        // 40 levels of two children each, no mesh until the end: 2^40 paths, refused at once
        let dag: Vec<String> =
            (0..41)
                .map(|i| {
                    if i < 40 {
                        format!(r#"{{"children":[{0},{0}]}}"#, i + 1)
                    } else {
                        r#"{"mesh":0}"#.into()
                    }
                })
                .collect();
        let started = std::time::Instant::now();
        let e = refused("n.glb", &with_nodes(&format!("[{}]", dag.join(",")), "[0]"));
        assert!(e.contains("is reached twice") && started.elapsed().as_secs() < 5, "{e}");
    }

    /// Every byte of a loadable GLB set to a few values in turn: each parses to an error or to a
    /// scene that validates, never a panic.
    #[test]
    fn single_byte_edits_never_panic() {
        let mut bin = quad_bin();
        for uv in [[0f32, 0.], [1., 0.], [1., 1.], [0., 1.]] {
            uv.iter().for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
        }
        let seeds =
            [glb(&document(NODES, MESHES, BLEND, ""), &quad_bin()), textured(&png(2, 2), Some("image/png"))];
        for seed in &seeds {
            for at in 0..seed.len() {
                for value in [0u8, 0xff, seed[at] ^ 1, b'9', b'"'] {
                    let mut input = seed.clone();
                    input[at] = value;
                    let result = std::panic::catch_unwind(|| parse_gltf(Path::new("m.glb"), &input, None));
                    match result {
                        Ok(Ok(scene)) => scene.validate().expect("a scene that loads validates"),
                        Ok(Err(_)) => {}
                        Err(_) => panic!("byte {at} set to {value} panics"),
                    }
                }
            }
        }
    }

    #[test]
    fn a_scene_of_a_file_is_picked_by_path_only() {
        let e = load_scene_with("planes:2", Some(1)).expect_err("not a glTF file").to_string();
        assert!(e.contains("--gltf-scene 1 picks a scene of a glTF file") && e.contains("'planes:2'"), "{e}");
        assert_eq!(
            load_scene_with("planes:2", None).expect("built in").name,
            crate::load_scene("planes:2").unwrap().name
        );
        assert!(is_gltf_path("a/b.GLB") && is_gltf_path("x.gltf") && !is_gltf_path("x.obj"));
    }
}
