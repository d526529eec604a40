//! OBJ loading with tobj: several objects per file, missing normals computed, vertex colours
//! (`v x y z r g b`) kept.
//!
//! Reading is bounded: only regular files, at most [`DEFAULT_MAX_MODEL_BYTES`] unless
//! `OIT_MAX_MODEL_BYTES` says otherwise. Before tobj sees the text, a first pass here checks every
//! vertex (with its line number), drops line (`l`) and point (`p`) elements, which have no area and
//! are reported in [`Scene::warnings`], and triangulates every face of more than three vertices by
//! ear clipping in the face's dominant plane: tobj's own triangulation is a fan, which covers a
//! concave polygon many times over.

use std::io::Read;
use std::path::Path;

use glam::{DVec2, DVec3, Vec3, Vec4};

use crate::{Mesh, OitError, Scene};

/// The colour OBJ objects get (linear, straight alpha): a light blue glass.
pub const OBJ_COLOR: Vec4 = Vec4::new(0.35, 0.6, 0.95, 0.35);

/// The largest model file read when `OIT_MAX_MODEL_BYTES` is not set: 1 GiB.
pub const DEFAULT_MAX_MODEL_BYTES: u64 = 1 << 30;

/// The most corners one face may have: ear clipping is O(n·r) at worst for n corners of which r
/// are reflex, so this bounds the time one face can take (a few seconds for the worst shapes;
/// milliseconds for stars and combs).
pub const MAX_FACE_CORNERS: usize = 65_536;

/// The environment variable that raises (or lowers) the model file size limit, in bytes.
pub const MAX_MODEL_BYTES_VAR: &str = "OIT_MAX_MODEL_BYTES";

/// The model size limit: `OIT_MAX_MODEL_BYTES` when set (a whole number of bytes), else
/// [`DEFAULT_MAX_MODEL_BYTES`].
fn max_model_bytes(var: Option<&str>) -> Result<u64, OitError> {
    match var {
        None => Ok(DEFAULT_MAX_MODEL_BYTES),
        Some(v) => v.trim().parse::<u64>().map_err(|_| {
            OitError::InvalidSettings(format!(
                "{MAX_MODEL_BYTES_VAR}='{v}' is not a whole number of bytes (e.g. {MAX_MODEL_BYTES_VAR}=4294967296 for 4 GiB)"
            ))
        }),
    }
}

/// Loads every object of an OBJ file as one mesh and one instance each.
///
/// Errors name the file, and the line for malformed, non-finite or out-of-range vertices and for
/// faces that cannot be triangulated (tobj itself reports no lines, so those are checked here
/// first). Files that are not regular files (devices, pipes, folders) and files over
/// `OIT_MAX_MODEL_BYTES` (default 1 GiB) are refused before anything is read.
pub fn load_obj(path: &Path) -> Result<Scene, OitError> {
    load_obj_limited(path, model_byte_limit()?)
}

/// The most bytes a model file may have: [`MAX_MODEL_BYTES_VAR`]'s, or the default.
pub(crate) fn model_byte_limit() -> Result<u64, OitError> {
    max_model_bytes(std::env::var(MAX_MODEL_BYTES_VAR).ok().as_deref())
}

/// `O_NONBLOCK` where its value is known without libc (Linux on these architectures): opening a
/// FIFO with it returns at once instead of waiting for a writer.
#[cfg(all(
    target_os = "linux",
    any(
        target_arch = "x86_64",
        target_arch = "x86",
        target_arch = "aarch64",
        target_arch = "arm",
        target_arch = "riscv64"
    )
))]
const O_NONBLOCK: i32 = 0o4000;

/// Opens `path` for reading if it is a regular file, and `Ok(None)` if it is not (a FIFO, device,
/// socket or folder), before anything can block: the path's metadata is checked first (nothing
/// else is opened), then the file is opened non-blocking where the flag is known (a FIFO put in
/// its place meanwhile does not wait for a writer) and its handle checked again. Every user path
/// oit reads (models, calibrations, reports, view scripts) goes through here: `open()` on a FIFO
/// blocks until someone writes to it, which hung `oit render --scene fifo.obj` (issue 41.5).
pub fn open_regular(path: &Path) -> std::io::Result<Option<(std::fs::File, std::fs::Metadata)>> {
    if !std::fs::metadata(path)?.is_file() {
        return Ok(None);
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(all(
        target_os = "linux",
        any(
            target_arch = "x86_64",
            target_arch = "x86",
            target_arch = "aarch64",
            target_arch = "arm",
            target_arch = "riscv64"
        )
    ))]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, O_NONBLOCK);
    let file = options.open(path)?;
    let meta = file.metadata()?;
    Ok(meta.is_file().then_some((file, meta)))
}

/// Reads `path` as UTF-8 text, refusing anything but a regular file of at most `limit` bytes.
fn read_bounded(path: &Path, limit: u64) -> Result<String, OitError> {
    let bytes = read_bounded_bytes(path, limit, ".obj")?;
    String::from_utf8(bytes).map_err(|e| OitError::Obj {
        path: path.to_path_buf(),
        line: None,
        message: format!("not UTF-8 text (byte {}): is this an .obj file?", e.utf8_error().valid_up_to()),
    })
}

/// The bytes of the model file `path` (a `kind` file, for the message when it is not a regular
/// file), refused past `limit` bytes before more than one byte past it is read.
pub(crate) fn read_bounded_bytes(path: &Path, limit: u64, kind: &str) -> Result<Vec<u8>, OitError> {
    let io = |source| OitError::Io { path: path.to_path_buf(), source };
    let too_large = |needed: u64| OitError::TooLarge {
        what: format!("model file {}", path.display()),
        needed,
        limit_name: MAX_MODEL_BYTES_VAR.into(),
        limit,
        hint: format!("set {MAX_MODEL_BYTES_VAR} to a larger number of bytes to read it"),
    };
    let Some((file, meta)) = open_regular(path).map_err(io)? else {
        return Err(OitError::Obj {
            path: path.to_path_buf(),
            line: None,
            message: format!(
                "not a regular file (a device, pipe or folder): models are read from {kind} files only"
            ),
        });
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    // The file may grow between the check and the read: read one byte past the limit at most.
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`load_obj`] with an explicit size limit.
fn load_obj_limited(path: &Path, limit: u64) -> Result<Scene, OitError> {
    parse_obj(path, &read_bounded(path, limit)?)
}

/// Parses `text` as the contents of the OBJ file `path` (which only names it in errors and
/// warnings): what [`load_obj`] does once the file is read, for text already in memory.
pub fn parse_obj(path: &Path, text: &str) -> Result<Scene, OitError> {
    let obj_err =
        |line: Option<usize>, message: String| OitError::Obj { path: path.to_path_buf(), line, message };
    let prepared = prepare(text).map_err(|(line, message)| obj_err(Some(line), message))?;
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mut reader = std::io::BufReader::new(prepared.text.as_bytes());
    // `mtllib` files are read beside the OBJ file (a missing one is a warning, not an error), as
    // the model is: regular files only, bounded (tobj's own reader opened a FIFO and waited for a
    // writer, and read /dev/zero until the OOM killer came)
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let limit = model_byte_limit()?;
    let mtl_error = std::cell::RefCell::new(None::<String>);
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |mtl| {
        match read_bounded_bytes(&dir.join(mtl), limit, ".mtl") {
            Ok(bytes) => tobj::load_mtl_buf(&mut bytes.as_slice()),
            Err(e) => {
                *mtl_error.borrow_mut() = Some(e.to_string());
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    })
    .map_err(|e| obj_err(None, e.to_string()))?;
    let mut warnings: Vec<String> = Vec::new();
    let materials = match materials {
        Ok(m) => m,
        Err(e) => {
            if prepared.text.lines().any(|l| l.trim_start().starts_with("mtllib")) {
                let why = mtl_error.borrow_mut().take().unwrap_or_else(|| e.to_string());
                warnings.push(format!("its materials (mtllib) were not read ({why}): drawn in oit's colour"));
            }
            Vec::new()
        }
    };
    let mut meshes = Vec::new();
    let mut material_of = Vec::new();
    let mut uvs_of = Vec::new();
    for (i, model) in models.into_iter().enumerate() {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let to_vec3 = |v: &[f32]| v.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
        let positions = to_vec3(&m.positions);
        if let Some(&bad) = m.indices.iter().find(|&&ix| ix as usize >= positions.len()) {
            return Err(obj_err(None, format!("a face refers to vertex {} of {}", bad + 1, positions.len())));
        }
        let indices: Vec<[u32; 3]> = m.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let name = if model.name.is_empty() { format!("object {}", i + 1) } else { model.name };
        let mut mesh = Mesh::new(name, positions, indices);
        if m.normals.len() == m.positions.len() {
            let normals = to_vec3(&m.normals);
            if normals.iter().all(|n| n.is_finite() && n.length_squared() > 0.0) {
                mesh.normals = normals.into_iter().map(|n| n.normalize()).collect();
            }
        }
        if m.vertex_color.len() == m.positions.len() {
            mesh.colors = Some(to_vec3(&m.vertex_color));
        }
        // OBJ's v runs up the image, oit's (glTF's) down it
        let uvs = (m.texcoords.len() / 2 == m.positions.len() / 3 && !m.texcoords.is_empty()).then(|| {
            m.texcoords.chunks_exact(2).map(|c| glam::Vec2::new(c[0], 1.0 - c[1])).collect::<Vec<_>>()
        });
        material_of.push(m.material_id.filter(|&i| i < materials.len()));
        uvs_of.push(uvs);
        meshes.push(mesh);
    }
    if meshes.is_empty() {
        let skipped = if prepared.warnings.is_empty() {
            String::new()
        } else {
            format!(" ({})", prepared.warnings.join("; "))
        };
        return Err(obj_err(None, format!("no faces{skipped}")));
    }
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut scene = Scene::from_meshes(name, meshes, OBJ_COLOR);
    for (i, material) in material_of.iter().enumerate() {
        let Some(material) = material.map(|k| &materials[k]) else { continue };
        apply_material(&mut scene, i, material, uvs_of[i].take(), &dir, &mut warnings);
    }
    scene.warnings =
        prepared.warnings.iter().chain(&warnings).map(|w| format!("{}: {w}", path.display())).collect();
    scene.validate().map_err(|e| obj_err(None, e.to_string()))?;
    Ok(scene)
}

/// Object `i` of `scene` (mesh `i`) as its `.mtl` material `m` says: `Kd` its colour, `d` (or
/// `1 − Tr`) its alpha, blended where below 1 and opaque at 1 (an OBJ drawn with materials is drawn
/// as its author lit it: solid where not said otherwise); `map_Kd` its base-colour texture (and
/// `map_d`'s first channel its alpha, where the two are the same size), read beside the OBJ file
/// with the mesh's texture coordinates. What cannot be read is a warning, and the object keeps
/// its colour.
fn apply_material(
    scene: &mut Scene,
    i: usize,
    m: &tobj::Material,
    uvs: Option<Vec<glam::Vec2>>,
    dir: &Path,
    warnings: &mut Vec<String>,
) {
    let alpha = m
        .dissolve
        .or_else(|| m.unknown_param.get("Tr").and_then(|t| t.trim().parse::<f32>().ok()).map(|t| 1.0 - t))
        .filter(|a| a.is_finite())
        .map_or(1.0, |a| a.clamp(0.0, 1.0));
    let object = &mut scene.objects[i];
    let kd = m.diffuse.map_or(OBJ_COLOR.truncate(), Vec3::from_array);
    object.color = kd.clamp(Vec3::ZERO, Vec3::ONE).extend(alpha);
    object.name = format!("{} ({})", object.name, m.name);
    object.alpha_mode = if alpha < 1.0 { crate::AlphaMode::Blend } else { crate::AlphaMode::Opaque };
    let texture = match (&m.diffuse_texture, &m.dissolve_texture) {
        (None, None) => return,
        (colour, dissolve) => read_texture(dir, colour.as_deref(), dissolve.as_deref()),
    };
    match (texture, uvs) {
        (Ok(t), Some(uvs)) => {
            // a texture's alpha below 1 makes the surface see-through where the material said so
            if alpha == 1.0 && t.texels().iter().any(|p| p[3] < 255) {
                scene.objects[i].alpha_mode = crate::AlphaMode::Blend;
            }
            scene.meshes[i].uvs = Some(uvs);
            scene.textures.push(t);
            scene.objects[i].texture = Some(scene.textures.len() - 1);
        }
        (Ok(_), None) => warnings.push(format!(
            "material '{}' has a texture and its mesh no texture coordinates: drawn in its colour",
            m.name
        )),
        (Err(e), _) => warnings.push(format!("material '{}': {e}: drawn in its colour", m.name)),
    }
}

/// The RGBA texture of `map_Kd` (`colour`) with `map_d`'s first channel as alpha (`dissolve`),
/// either optional, read from `dir` as the model is (a regular file of at most
/// `OIT_MAX_MODEL_BYTES`) and decoded with glTF's image limits (a side of at most
/// [`crate::Texture::MAX_SIDE`], no more pixels than its bytes can encode).
fn read_texture(dir: &Path, colour: Option<&str>, dissolve: Option<&str>) -> Result<crate::Texture, String> {
    let limit = model_byte_limit().map_err(|e| e.to_string())?;
    let open = |name: &str| {
        let bytes = read_bounded_bytes(&dir.join(name), limit, "image").map_err(|e| match e {
            OitError::Io { source, .. } => format!("cannot read {name}: {source}"),
            OitError::Obj { message, .. } => format!("cannot read {name}: {message}"),
            other => format!("cannot read {name}: {other}"),
        })?;
        let format = image::guess_format(&bytes).map_err(|e| format!("cannot decode {name}: {e}"))?;
        crate::texture::decode_limited(&bytes, format, name).map_err(|e| format!("cannot decode {e}"))
    };
    let base = colour.map(|c| open(c).map(|i| i.to_rgba8())).transpose()?;
    let alpha = dissolve.map(|d| open(d).map(|i| i.to_luma8())).transpose()?;
    let (w, h) = match (&base, &alpha) {
        (Some(b), _) => b.dimensions(),
        (None, Some(a)) => a.dimensions(),
        (None, None) => return Err("no texture".into()),
    };
    let mut texels: Vec<[u8; 4]> = match &base {
        Some(b) => b.pixels().map(|p| p.0).collect(),
        None => vec![[255; 4]; w as usize * h as usize],
    };
    if let Some(a) = &alpha {
        if a.dimensions() != (w, h) {
            return Err(format!("map_d is {}×{}, map_Kd {w}×{h}", a.width(), a.height()));
        }
        texels.iter_mut().zip(a.pixels()).for_each(|(t, p)| t[3] = p.0[0]);
    }
    let name = colour.or(dissolve).unwrap_or("texture");
    crate::Texture::new(name, w, h, texels, [crate::Wrap::Repeat; 2]).map_err(|e| e.to_string())
}

/// The OBJ text as tobj gets it, and what was left out of it.
struct Prepared<'a> {
    text: std::borrow::Cow<'a, str>,
    warnings: Vec<String>,
}

/// Element kinds skipped, counted for one warning each.
#[derive(Default)]
struct Skipped {
    count: usize,
    first_line: usize,
}

impl Skipped {
    fn add(&mut self, line: usize) {
        if self.count == 0 {
            self.first_line = line;
        }
        self.count += 1;
    }

    fn warning(&self, what: &str) -> Option<String> {
        (self.count > 0).then(|| format!("skipped {} {what} (first at line {})", self.count, self.first_line))
    }
}

/// The first pass over the text: checks vertices, drops `l` and `p` elements and faces of fewer
/// than three vertices, and rewrites faces of four or more vertices as ear-clipped triangles
/// (keeping each corner's `v/vt/vn` token, so tobj still resolves texture coordinates and
/// normals). Errors carry the 1-based line.
fn prepare(text: &str) -> Result<Prepared<'_>, (usize, String)> {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut out: Option<String> = None;
    let (mut lines, mut points, mut short, mut flat) =
        (Skipped::default(), Skipped::default(), Skipped::default(), Skipped::default());
    let mut offset = 0;
    for (i, raw) in text.split_inclusive('\n').enumerate() {
        let number = i + 1;
        let start = offset;
        offset += raw.len();
        let line = raw.trim_end_matches(['\n', '\r']);
        let mut words = line.split_whitespace();
        // What replaces this line in tobj's text (None: the line as it is).
        let replacement: Option<String> = match words.next() {
            Some("v") => {
                positions.push(parse_vertex(line, words).map_err(|m| (number, m))?);
                None
            }
            Some("l") => {
                lines.add(number);
                Some(String::new())
            }
            Some("p") => {
                points.add(number);
                Some(String::new())
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    short.add(number);
                    Some(String::new())
                } else if corners.len() > MAX_FACE_CORNERS {
                    return Err((
                        number,
                        format!(
                            "face of {} vertices is over the limit of {MAX_FACE_CORNERS} vertices a face: split it into smaller polygons",
                            corners.len()
                        ),
                    ));
                } else if corners.len() == 3 {
                    for c in &corners {
                        resolve(c, positions.len()).map_err(|m| (number, m))?;
                    }
                    None
                } else {
                    let polygon = corners
                        .iter()
                        .map(|c| resolve(c, positions.len()).map(|ix| positions[ix]))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|m| (number, m))?;
                    let triangles = triangulate(&polygon).map_err(|m| {
                        (number, format!("face of {} vertices {m}; split it into triangles", corners.len()))
                    })?;
                    if triangles.is_empty() {
                        flat.add(number);
                    }
                    let mut s = String::new();
                    for t in triangles {
                        s.push_str(&format!("f {} {} {}\n", corners[t[0]], corners[t[1]], corners[t[2]]));
                    }
                    Some(s)
                }
            }
            _ => None,
        };
        match (replacement, &mut out) {
            (Some(r), Some(o)) => o.push_str(&r),
            (Some(r), None) => out = Some(format!("{}{r}", &text[..start])),
            (None, Some(o)) => o.push_str(raw),
            (None, None) => {}
        }
    }
    let warnings = [
        lines.warning("line elements ('l'): they have no area"),
        points.warning("point elements ('p'): they have no area"),
        short.warning("faces of fewer than 3 vertices"),
        flat.warning("polygons of no area"),
    ]
    .into_iter()
    .flatten()
    .collect();
    let text = match out {
        Some(o) => std::borrow::Cow::Owned(o),
        None => std::borrow::Cow::Borrowed(text),
    };
    Ok(Prepared { text, warnings })
}

/// Parses a `v` line's values (after the `v`): x y z, optionally w (which divides them, as tobj
/// does) or r g b. Every value must be a finite number and every coordinate within
/// ±[`Mesh::MAX_COORDINATE`].
fn parse_vertex<'a>(line: &str, words: impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
    let mut values = Vec::with_capacity(6);
    let line = clip(line);
    for v in words {
        match v.parse::<f32>() {
            Ok(x) if x.is_finite() => values.push(x),
            Ok(_) => return Err(format!("vertex has a NaN or infinite value: '{line}'")),
            Err(_) => return Err(format!("'{}' is not a number: '{line}'", clip(v))),
        }
    }
    if values.len() < 3 {
        return Err(format!("vertex needs at least 3 coordinates: '{line}'"));
    }
    let mut p = Vec3::new(values[0], values[1], values[2]);
    if values.len() == 4 {
        if values[3] == 0.0 {
            return Err(format!("vertex has w = 0: '{line}'"));
        }
        p /= values[3];
    }
    let max = Mesh::MAX_COORDINATE;
    if !p.is_finite() || p.abs().max_element() > max {
        return Err(format!(
            "vertex coordinate out of range: '{line}' (oit takes coordinates within ±{max:e}; scale the model down)"
        ));
    }
    Ok(p.as_dvec3())
}

/// Text of the file quoted in a message: at most [`QUOTED_CHARS`] characters, the rest said as
/// "…" (a line of 200,000 digits was quoted whole, a 200 KB error line).
fn clip(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(QUOTED_CHARS) {
        Some((end, _)) => format!("{}… ({} bytes)", &text[..end], text.len()).into(),
        None => text.into(),
    }
}

/// The most characters of the file's text a message quotes.
const QUOTED_CHARS: usize = 80;

/// The 0-based position a face corner (`v`, `v/vt`, `v//vn`, `v/vt/vn`; negative counts back from
/// the last vertex so far) refers to.
fn resolve(corner: &str, count: usize) -> Result<usize, String> {
    let v = corner.split('/').next().unwrap_or_default();
    let bad = || format!("face corner '{}' refers to no vertex ({count} defined so far)", clip(corner));
    let i: i64 = v.parse().map_err(|_| bad())?;
    let ix = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || ix < 0 || ix >= count as i64 {
        return Err(bad());
    }
    Ok(ix as usize)
}

/// Triangulates a simple polygon (any winding, convex or not, roughly planar) by ear clipping in
/// the plane its Newell normal is most aligned with. Triangles keep the polygon's winding (each is
/// three corners in the polygon's own order); a polygon of no area gives none. Fails when no ear
/// is left (a polygon that crosses itself).
///
/// Ears are clipped by priority, the largest `2·area / longest edge³` first (the smallest
/// height over the longest edge squared: small ears and fat ones before long thin ones): a
/// rasterizer snaps corners to 1/256 pixel, and a long ear whose tip lies almost on the line
/// through its neighbours can turn over when snapped and cover pixels its neighbours cover too.
/// Clipping the next ear in polygon order did that for random stars of 32,768 corners and more
/// (27 pixels 2 and 3 layers deep at 512² for one of 65,536; 1 in this order, issue 41.3). A
/// small ear turned over covers next to nothing; on a circle the priority clips every other
/// corner, round after round, as the polygon order did (the plain smallest height makes fans of
/// ever longer slivers there).
///
/// Only reflex vertices can lie inside an ear, so each candidate ear is tested against those
/// alone, and of those only the ones a [`ReflexGrid`] finds near it (rebuilt as reflex corners
/// go, so that the large ears of the end do not wade through dead ones): about O(n log n) for
/// the stars and combs of real models, O(n·r) at worst for n vertices of which r are reflex;
/// faces are at most [`MAX_FACE_CORNERS`] corners, so that worst case stays bounded.
fn triangulate(polygon: &[DVec3]) -> Result<Vec<[usize; 3]>, String> {
    let n = polygon.len();
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        normal += DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    let axis = normal.abs().max_position();
    if normal[axis] == 0.0 {
        return Ok(Vec::new());
    }
    // Drop the dominant axis; order the other two so the polygon winds counter-clockwise.
    let (u, v) = [(1, 2), (2, 0), (0, 1)][axis];
    let flip = normal[axis] < 0.0;
    let p: Vec<DVec2> =
        polygon.iter().map(|q| if flip { DVec2::new(q[v], q[u]) } else { DVec2::new(q[u], q[v]) }).collect();
    let cross = |a: usize, b: usize, c: usize| (p[b] - p[a]).perp_dot(p[c] - p[a]);
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    // Not strictly convex: reflex or collinear; only these can lie in or on an ear.
    let mut reflex: Vec<bool> = (0..n).map(|i| cross(prev[i], i, next[i]) <= 0.0).collect();
    let mut removed = vec![false; n];
    let mut grid = ReflexGrid::new(&p, &reflex);
    let mut live_reflex = grid.items.len();
    let inside = |a: usize, b: usize, c: usize, r: usize| {
        // in the closed triangle (a, b, c), counter-clockwise, unless it is one of its corners
        let q = p[r];
        q != p[a]
            && q != p[b]
            && q != p[c]
            && (p[b] - p[a]).perp_dot(q - p[a]) >= 0.0
            && (p[c] - p[b]).perp_dot(q - p[b]) >= 0.0
            && (p[a] - p[c]).perp_dot(q - p[c]) >= 0.0
    };
    // The ear at b as a priority (larger first): 2·area / longest³, or infinity for a straight
    // or back-tracking corner (dropping it loses no area and makes no triangle); `None` when b is
    // no ear (reflex, or a reflex corner lies in or on its triangle).
    let ear = |grid: &ReflexGrid, reflex: &[bool], removed: &[bool], a: usize, b: usize, c: usize| {
        let turn = cross(a, b, c);
        if turn == 0.0 {
            return Some(f64::INFINITY);
        }
        if turn < 0.0 {
            return None;
        }
        let (lo, hi) = (p[a].min(p[b]).min(p[c]), p[a].max(p[b]).max(p[c]));
        if grid.any_in(lo, hi, |r| reflex[r] && !removed[r] && r != a && r != c && inside(a, b, c, r)) {
            return None;
        }
        let longest = (p[b] - p[a]).length().max((p[c] - p[b]).length()).max((p[a] - p[c]).length());
        Some(turn / (longest * longest * longest))
    };
    // Ears by priority: (height's bits, corner, the corner's stamp when pushed). A non-negative
    // f64's bits order as the f64 does; an entry is stale once its corner's neighbours changed.
    let mut heap = std::collections::BinaryHeap::new();
    let mut stamp = vec![0u32; n];
    for b in 0..n {
        if let Some(h) = ear(&grid, &reflex, &removed, prev[b], b, next[b]) {
            heap.push((h.to_bits(), b, 0u32));
        }
    }
    let mut triangles = Vec::with_capacity(n - 2);
    let mut left = n;
    while left > 3 {
        let Some((_, b, pushed)) = heap.pop() else {
            // A reflex corner that stops blocking an ear needs no neighbour of that ear to change,
            // so an ear can be missing from the heap: look at every corner again.
            for b in (0..n).filter(|&b| !removed[b]) {
                stamp[b] = stamp[b].wrapping_add(1);
                if let Some(h) = ear(&grid, &reflex, &removed, prev[b], b, next[b]) {
                    heap.push((h.to_bits(), b, stamp[b]));
                }
            }
            if heap.is_empty() {
                return Err("crosses itself or folds back on itself: no ear left to clip".into());
            }
            continue;
        };
        if removed[b] || pushed != stamp[b] {
            continue;
        }
        let (a, c) = (prev[b], next[b]);
        if cross(a, b, c) != 0.0 {
            triangles.push([a, b, c]);
        }
        removed[b] = true;
        if reflex[b] {
            live_reflex -= 1;
        }
        next[a] = c;
        prev[c] = a;
        left -= 1;
        for x in [a, c] {
            if reflex[x] && cross(prev[x], x, next[x]) > 0.0 {
                reflex[x] = false;
                live_reflex -= 1;
            }
        }
        if live_reflex * 2 < grid.items.len() && grid.items.len() > 64 {
            let live: Vec<bool> = (0..n).map(|i| reflex[i] && !removed[i]).collect();
            grid = ReflexGrid::new(&p, &live);
        }
        for x in [a, c] {
            stamp[x] = stamp[x].wrapping_add(1);
            if let Some(h) = ear(&grid, &reflex, &removed, prev[x], x, next[x]) {
                heap.push((h.to_bits(), x, stamp[x]));
            }
        }
    }
    let b = (0..n).find(|&b| !removed[b]).unwrap_or(0);
    let (a, c) = (prev[b], next[b]);
    if cross(a, b, c) != 0.0 {
        triangles.push([a, b, c]);
    }
    Ok(triangles)
}

/// The reflex corners of a polygon (2-D, [`triangulate`]'s plane) bucketed in a uniform grid
/// over its bounding box, about one corner a cell, so that an ear is tested only against the
/// corners whose cells its bounding box overlaps. Ear clipping never makes a convex corner
/// reflex, so the grid is built once; corners that stop being reflex or are clipped stay in it and
/// the caller's test skips them.
struct ReflexGrid {
    min: DVec2,
    /// Cells per unit length, on each axis.
    scale: DVec2,
    /// Cells on a side.
    side: usize,
    /// Where each cell's corners start in `items` (and the last cell's end).
    start: Vec<usize>,
    items: Vec<usize>,
}

impl ReflexGrid {
    fn new(p: &[DVec2], reflex: &[bool]) -> ReflexGrid {
        let count = reflex.iter().filter(|&&r| r).count();
        let side = ((count as f64).sqrt().ceil() as usize).clamp(1, 1024);
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &q in p {
            min = min.min(q);
            max = max.max(q);
        }
        let scale = DVec2::splat(side as f64) / (max - min).max(DVec2::splat(f64::MIN_POSITIVE));
        let mut grid =
            ReflexGrid { min, scale, side, start: vec![0; side * side + 1], items: vec![0; count] };
        // a counting sort of the reflex corners by cell
        let cells: Vec<(usize, usize)> =
            (0..p.len()).filter(|&i| reflex[i]).map(|i| (grid.cell_index(p[i]), i)).collect();
        for &(cell, _) in &cells {
            grid.start[cell + 1] += 1;
        }
        for i in 0..side * side {
            grid.start[i + 1] += grid.start[i];
        }
        let mut fill = grid.start.clone();
        for (cell, i) in cells {
            grid.items[fill[cell]] = i;
            fill[cell] += 1;
        }
        grid
    }

    /// The cell column and row of `q` (clamped to the grid: float rounding at the far edge).
    fn cell(&self, q: DVec2) -> (usize, usize) {
        let c = (q - self.min) * self.scale;
        // `as` saturates: negative rounding noise gives 0, the far edge `side`
        ((c.x as usize).min(self.side - 1), (c.y as usize).min(self.side - 1))
    }

    fn cell_index(&self, q: DVec2) -> usize {
        let (x, y) = self.cell(q);
        y * self.side + x
    }

    /// Whether `test` holds for a corner in a cell that the box `lo`..`hi` overlaps.
    fn any_in(&self, lo: DVec2, hi: DVec2, mut test: impl FnMut(usize) -> bool) -> bool {
        let ((x0, y0), (x1, y1)) = (self.cell(lo), self.cell(hi));
        (y0..=y1).any(|y| {
            let row = y * self.side;
            self.items[self.start[row + x0]..self.start[row + x1 + 1]].iter().any(|&r| test(r))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("oit-obj-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// Σ |area| of a scene's triangles (f64): equals the polygon's area only if the triangles
    /// neither overlap nor spill out of it.
    fn unsigned_area(scene: &Scene) -> f64 {
        let m = &scene.meshes[0];
        m.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                (b - a).cross(c - a).length() * 0.5
            })
            .sum()
    }

    /// Shoelace area of a polygon in the z = 0 plane.
    fn shoelace(points: &[(f32, f32)]) -> f64 {
        let n = points.len();
        (0..n)
            .map(|i| {
                let (a, b) = (points[i], points[(i + 1) % n]);
                f64::from(a.0) * f64::from(b.1) - f64::from(b.0) * f64::from(a.1)
            })
            .sum::<f64>()
            * 0.5
    }

    fn polygon_obj(points: &[(f32, f32)]) -> String {
        let mut s: String = points.iter().map(|(x, y)| format!("v {x} {y} 0\n")).collect();
        s.push('f');
        for i in 1..=points.len() {
            s.push_str(&format!(" {i}"));
        }
        s.push('\n');
        s
    }

    #[test]
    fn loads_objects_quads_and_colors() {
        let p = write(
            "two.obj",
            "o a\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nf 1 2 3 4\no b\nv 0 0 1 1 0 0\nv 1 0 1 0 1 0\nv 1 1 1 0 0 1\nv 0 1 1 1 1 1\nf 5 6 7\n",
        );
        let s = load_obj(&p).unwrap();
        assert_eq!(s.meshes.len(), 2);
        assert_eq!(s.meshes[0].indices.len(), 2, "quad triangulated");
        assert_eq!(s.meshes[1].indices.len(), 1);
        assert!(s.meshes[0].colors.is_some());
        assert!(s.meshes[0].normals.iter().all(|n| (n.z.abs() - 1.0).abs() < 1e-6), "normals computed");
        assert!(s.warnings.is_empty());
    }

    #[test]
    fn errors_name_file_and_line() {
        let p = write("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
        let e = load_obj(&p).unwrap_err().to_string();
        assert!(e.contains("nan.obj") && e.contains("line 2"), "{e}");
        let p = write("junk.obj", "v 0 0 zero\n");
        assert!(load_obj(&p).unwrap_err().to_string().contains("line 1"));
        let p = write("empty.obj", "# nothing\n");
        assert!(load_obj(&p).unwrap_err().to_string().contains("empty.obj"));
        let missing = std::env::temp_dir().join("definitely-missing-oit.obj");
        assert!(load_obj(&missing).unwrap_err().to_string().contains("definitely-missing-oit.obj"));
        let p = write("badidx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
        let e = load_obj(&p).unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("'9'"), "{e}");
    }

    #[test]
    fn huge_finite_vertex_is_out_of_range_not_non_finite() {
        // 1e37 is a finite f32, but its bounding sphere overflows f32: the message must say what
        // is wrong (the range), not call it NaN or infinite
        let p = write("huge.obj", "v 0 0 0\nv 1e37 0 0\nv 0 1 0\nf 1 2 3\n");
        let e = load_obj(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("out of range"), "{e}");
        assert!(!e.contains("NaN") && !e.contains("finite"), "{e}");
        // the largest allowed coordinate loads
        let p = write("big.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n");
        load_obj(&p).unwrap();
    }

    #[test]
    fn concave_quad_is_ear_clipped() {
        // A dart: the reflex vertex (2, 1) is the second, so tobj's fan from the first vertex
        // makes one clockwise triangle spilling outside (|areas| 2 + 6 = 8 for a true area of 4).
        let dart = [(0.0, 0.0), (2.0, 1.0), (4.0, 0.0), (2.0, 3.0)];
        let s = load_obj(&write("dart.obj", &polygon_obj(&dart))).unwrap();
        assert_eq!(s.meshes[0].indices.len(), 2);
        assert_eq!(shoelace(&dart), 4.0);
        assert!((unsigned_area(&s) - 4.0).abs() < 1e-9, "{}", unsigned_area(&s));
        // the same dart in the x–z plane, wound the other way (its normal is −y), is still exact
        let text = "v 0 0 0\nv 2 0 1\nv 4 0 0\nv 2 0 3\nf 4 3 2 1\n";
        let s = load_obj(&write("dart-xz.obj", text)).unwrap();
        assert!((unsigned_area(&s) - 4.0).abs() < 1e-9, "{}", unsigned_area(&s));
    }

    #[test]
    fn concave_10000_gon_area_is_exact() {
        // A star of 5,000 spikes (radii 1 and 0.5 alternating): fan triangulation covers most of
        // it thousands of times; ear clipping covers it exactly once.
        let n = 10_000;
        let star: Vec<(f32, f32)> = (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = if i % 2 == 0 { 1.0 } else { 0.5 };
                ((r * a.cos()) as f32, (r * a.sin()) as f32)
            })
            .collect();
        let s = load_obj(&write("star.obj", &polygon_obj(&star))).unwrap();
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), n - 2);
        let truth = shoelace(&star);
        let got = unsigned_area(&s);
        assert!((got - truth).abs() < 1e-6 * truth, "triangulated {got}, polygon {truth}");
        // every triangle keeps the polygon's (counter-clockwise) winding
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            assert!((b - a).cross(c - a).z >= 0.0);
        }
    }

    #[test]
    fn large_stars_are_ear_clipped_and_huge_faces_refused() {
        // 60,000 corners, half of them reflex: every ear once tested against every reflex corner
        // (seconds); the grid tests each against its neighbours
        let n = 60_000;
        let star: Vec<(f32, f32)> = (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = if i % 2 == 0 { 1.0 } else { 0.5 };
                ((r * a.cos()) as f32, (r * a.sin()) as f32)
            })
            .collect();
        let s = load_obj(&write("star60k.obj", &polygon_obj(&star))).unwrap();
        // at most n − 2: corners that f32 rounding made collinear add none
        assert!(s.meshes[0].indices.len() <= n - 2);
        let (truth, got) = (shoelace(&star), unsigned_area(&s));
        assert!((got - truth).abs() < 1e-6 * truth, "triangulated {got}, polygon {truth}");
        let square: Vec<(f32, f32)> = (0..=MAX_FACE_CORNERS).map(|i| (i as f32, (i % 2) as f32)).collect();
        let e = load_obj(&write("huge-face.obj", &polygon_obj(&square))).unwrap_err().to_string();
        assert!(e.contains("65537 vertices") && e.contains("split it"), "{e}");
    }

    #[test]
    fn random_star_of_65536_corners_is_covered_once() {
        // Issue 41.3: random radii in [0.2, 1] at even angles, one face of 65,536 corners. The
        // triangles must cover the polygon exactly once (Σ|area| = the shoelace area: an overlap
        // or a triangle outside adds to the sum) and keep its winding. Mutations caught: an ear
        // test that skips the reflex corners (`any_in` never true: overlapping ears), a grid
        // rebuilt without the live reflex corners, a heap entry clipped after its neighbours
        // changed (the stamp check dropped).
        let n = 65_536;
        let mut rng = crate::rng::Rng(0x2545_f491_4f6c_dd1d);
        let star: Vec<(f32, f32)> = (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = 0.2 + 0.8 * f64::from(rng.next_f32());
                ((r * a.cos()) as f32, (r * a.sin()) as f32)
            })
            .collect();
        let s = load_obj(&write("random-star.obj", &polygon_obj(&star))).unwrap();
        let m = &s.meshes[0];
        assert!(m.indices.len() <= n - 2 && m.indices.len() > n - 100, "{} triangles", m.indices.len());
        let (truth, got) = (shoelace(&star), unsigned_area(&s));
        assert!((got - truth).abs() < 1e-9 * truth, "triangulated {got}, polygon {truth}");
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            assert!((b - a).cross(c - a).z >= 0.0, "a triangle turned over");
        }
    }

    #[test]
    fn lines_and_points_are_skipped_with_a_warning() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nl 1 2 3\nl 2 4\np 4\nf 2 4\n";
        let s = load_obj(&write("lines.obj", text)).unwrap();
        assert_eq!(s.triangle_count(), 1, "only the face is drawn");
        let w = s.warnings.join("\n");
        assert!(w.contains("2 line elements") && w.contains("line 6"), "{w}");
        assert!(w.contains("1 point elements") && w.contains("line 8"), "{w}");
        assert!(w.contains("1 faces of fewer than 3") && w.contains("line 9"), "{w}");
        let e = load_obj(&write("only-lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no faces") && e.contains("line elements"), "{e}");
    }

    #[test]
    fn non_regular_files_are_refused_before_reading() {
        // /dev/zero would otherwise be read until memory runs out
        let e = load_obj(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let dir = std::env::temp_dir();
        assert!(load_obj(&dir).unwrap_err().to_string().contains("not a regular file"));
    }

    #[test]
    fn a_fifo_is_refused_without_waiting_for_a_writer() {
        // Issue 41.5: the model was opened before the regular-file check, and open() on a FIFO
        // waits for a writer: `--scene fifo.obj` hung. Mutation caught: opening before the
        // metadata check without O_NONBLOCK (`File::open` first, as before) blocks here, and the
        // thread's answer never comes (the test fails after 20 s instead of hanging CI).
        let fifo = std::env::temp_dir().join(format!("oit-obj-fifo-{}.obj", std::process::id()));
        let _ = std::fs::remove_file(&fifo);
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("skipped: no mkfifo on this system");
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || tx.send(load_obj(&path).map(|_| ()).map_err(|e| e.to_string())));
        let answer = rx.recv_timeout(std::time::Duration::from_secs(20));
        std::fs::remove_file(&fifo).ok();
        let e = answer.expect("load_obj on a FIFO blocked").unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn a_long_line_is_quoted_in_part() {
        // The hostile re-run of 2026-12-05: `v 111…1 0 0` (200,000 digits) was refused with the
        // whole line quoted, a 200 KB error line. Mutation caught: `clip` returning its text whole.
        let digits = "1".repeat(200_000);
        for text in [
            format!("v {digits} 0 0\n"),
            format!("v 0 0 0\nv x{digits} 0 0\n"),
            format!("v 0 0 0\nv 1 0 0\nf 1 2 {digits}\n"),
        ] {
            let e = parse_obj(Path::new("long.obj"), &text).unwrap_err().to_string();
            assert!(e.len() < 400 && e.contains("bytes)"), "{} bytes: {}", e.len(), &e[..e.len().min(400)]);
        }
    }

    #[test]
    fn materials_and_textures_are_read_as_models_are() {
        // The hostile re-run of 2026-12-05 (bench/results/cpu/hostile-2026-12-05): `mtllib` and
        // `map_Kd` were opened by tobj and the image crate directly, so `mtllib /dev/zero` was
        // read until the OOM killer came (exit 137) and `mtllib fifo.mtl` or `map_Kd fifo.png`
        // waited for a writer (a hang). Each is now a warning naming the file, the object drawn
        // in its colour. Mutation caught: `tobj::load_mtl(dir.join(mtl))` back in the material
        // loader, or `image::ImageReader::open` in `read_texture` (the thread's answer never
        // comes, and the test fails after 20 s).
        let dir = std::env::temp_dir().join(format!("oit-obj-hostile-mtl-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = |name: &str| {
            let p = dir.join(name);
            let _ = std::fs::remove_file(&p);
            std::process::Command::new("mkfifo").arg(&p).status().is_ok_and(|s| s.success())
        };
        if !(fifo("fifo.mtl") && fifo("fifo.png")) {
            eprintln!("skipped: no mkfifo on this system");
            return;
        }
        std::fs::write(dir.join("tex.mtl"), "newmtl m\nd 0.5\nmap_Kd fifo.png\n").unwrap();
        std::fs::write(dir.join("zero.mtl"), "newmtl m\nd 0.5\nmap_Kd /dev/zero\n").unwrap();
        // a PNG whose header claims 100,000² pixels: refused before they are allocated
        let mut png = Vec::new();
        image::RgbaImage::new(1, 1)
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        png[16..24].copy_from_slice(&[0, 1, 0x86, 0xa0, 0, 1, 0x86, 0xa0]);
        let mut crc = flate2::Crc::new();
        crc.update(&png[12..29]);
        png[29..33].copy_from_slice(&crc.sum().to_be_bytes());
        std::fs::write(dir.join("huge.png"), &png).unwrap();
        std::fs::write(dir.join("huge.mtl"), "newmtl m\nd 0.5\nmap_Kd huge.png\n").unwrap();
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3 4/4\n";
        for (mtllib, said) in [
            // the FIFOs first: under the mutations they fail after 20 s, before /dev/zero is read
            ("fifo.mtl", "not a regular file"),
            ("tex.mtl", "fifo.png: not a regular file"),
            ("/dev/zero", "not a regular file"),
            (".", "not a regular file"),
            ("zero.mtl", "/dev/zero: not a regular file"),
            ("huge.mtl", "100000 × 100000 pixels"),
        ] {
            let obj = dir.join(format!("with-{}.obj", mtllib.replace(['/', '.'], "_")));
            std::fs::write(&obj, format!("mtllib {mtllib}\n{quad}")).unwrap();
            let (tx, rx) = std::sync::mpsc::channel();
            let path = obj.clone();
            std::thread::spawn(move || {
                let _ = tx.send(load_obj(&path).map_err(|e| e.to_string()));
            });
            let scene =
                rx.recv_timeout(std::time::Duration::from_secs(20)).expect("load_obj blocked").unwrap();
            assert!(scene.warnings.iter().any(|w| w.contains(said)), "mtllib {mtllib}: {:?}", scene.warnings);
            assert!(scene.textures.is_empty(), "mtllib {mtllib}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn model_size_is_capped() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let p = write("small.obj", text);
        let e = load_obj_limited(&p, 10).unwrap_err().to_string();
        assert!(e.contains("OIT_MAX_MODEL_BYTES") && e.contains(&text.len().to_string()), "{e}");
        load_obj_limited(&p, text.len() as u64).unwrap();
        assert_eq!(max_model_bytes(None).unwrap(), 1 << 30);
        assert_eq!(max_model_bytes(Some("4096")).unwrap(), 4096);
        assert!(max_model_bytes(Some("1G")).unwrap_err().to_string().contains("OIT_MAX_MODEL_BYTES"));
    }

    #[test]
    fn ear_clipping_edges() {
        let v = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        // collinear corners add no triangles of their own
        let square = [v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let t = triangulate(&square).unwrap();
        let area: f64 =
            t.iter().map(|t| (square[t[1]] - square[t[0]]).cross(square[t[2]] - square[t[0]]).z * 0.5).sum();
        assert!((area - 4.0).abs() < 1e-12 && t.len() <= 3, "{t:?}");
        // all on one line: nothing to draw
        assert!(triangulate(&[v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(3.0, 0.0)]).unwrap().is_empty());
    }

    /// Issue 39.2: an OBJ's `.mtl` materials: `Kd` and `d` (or `Tr`) the colour and alpha, blended
    /// below 1 and opaque at 1, `map_Kd` the texture read beside it with the faces' coordinates
    /// (v flipped); a missing `.mtl` still loads, with a warning.
    #[test]
    fn materials_from_mtl() {
        let dir = std::env::temp_dir().join(format!("oit-mtl-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 -1\nv 1 0 -1\nv 0 1 -1\n\
                   vt 0 0\nvt 1 0\nvt 0 1\no glass\nusemtl glass\nf 1/1 2/2 3/3\no wall\nusemtl wall\nf 4 5 6\n\
                   o pane\nusemtl pane\nf 1/1 2/2 3/3\n";
        let mtl = "newmtl glass\nKd 0.2 0.4 0.6\nd 0.25\nnewmtl wall\nKd 0.5 0.5 0.5\n\
                   newmtl pane\nKd 1 1 1\nTr 0.75\nmap_Kd pane.png\n";
        std::fs::write(dir.join("scene.obj"), obj).unwrap();
        std::fs::write(dir.join("scene.mtl"), mtl).unwrap();
        image::RgbaImage::from_raw(2, 1, vec![255, 0, 0, 255, 0, 0, 255, 128])
            .unwrap()
            .save(dir.join("pane.png"))
            .unwrap();
        let s = load_obj(&dir.join("scene.obj")).expect("loads");
        s.validate().expect("valid");
        let by = |n: &str| s.objects.iter().find(|o| o.name.contains(n)).unwrap_or_else(|| panic!("{n}"));
        assert_eq!(by("(glass)").color, Vec4::new(0.2, 0.4, 0.6, 0.25));
        assert_eq!(by("(glass)").alpha_mode, crate::AlphaMode::Blend);
        assert_eq!(by("(wall)").alpha_mode, crate::AlphaMode::Opaque);
        let pane = by("(pane)");
        assert_eq!((pane.color.w, pane.texture), (0.25, Some(0)));
        assert_eq!(s.textures[0].texels(), &[[255, 0, 0, 255], [0, 0, 255, 128]]);
        let uvs = s.meshes[pane.mesh].uvs.as_ref().expect("coordinates kept");
        assert_eq!(
            uvs[..3],
            [glam::Vec2::new(0.0, 1.0), glam::Vec2::new(1.0, 1.0), glam::Vec2::new(0.0, 0.0)]
        );
        assert!(s.meshes[by("(glass)").mesh].uvs.is_none(), "an untextured object's coordinates are dropped");
        // without its .mtl: oit's colour, one warning
        std::fs::remove_file(dir.join("scene.mtl")).unwrap();
        let s = load_obj(&dir.join("scene.obj")).expect("loads without its materials");
        assert!(s.objects.iter().all(|o| o.color == OBJ_COLOR && o.texture.is_none()));
        assert!(
            s.warnings.iter().any(|w| w.contains("materials (mtllib) were not read")),
            "{:?}",
            s.warnings
        );
        // a texture that is not there: the colour, one warning
        std::fs::write(dir.join("scene.mtl"), mtl).unwrap();
        std::fs::remove_file(dir.join("pane.png")).unwrap();
        let s = load_obj(&dir.join("scene.obj")).expect("loads without its texture");
        assert!(
            s.textures.is_empty() && s.warnings.iter().any(|w| w.contains("pane.png")),
            "{:?}",
            s.warnings
        );
        s.validate().expect("valid without the texture's coordinates");
        std::fs::remove_dir_all(&dir).ok();
    }
}
