//! Built-in procedural scenes, by name, so that every test and example has geometry without files.
//!
//! | name | what | depth complexity |
//! |---|---|---|
//! | `planes:N` | N parallel, overlapping quads at distinct depths, distinct colours | N |
//! | `spheres:N` | N nested concentric spheres | 2N |
//! | `cluster:N` | N small spheres placed by a fixed seed | varies |
//! | `knot` | a self-overlapping (2, 3) torus-knot tube | ≈ 8 |
//! | `coplanar` | two overlapping quads in one plane, different colours | 2 (a tie) |
//! | `ties:N` | N overlapping quads in one plane, colour order unlike primitive order | up to N, all tied |
//! | `near:N` | `ties:N` with the quads 10⁻⁷ apart in depth (equal after projection to f32) | up to N |
//! | `scale:S:SCENE` | SCENE with every coordinate multiplied by S (e.g. `scale:1e-20:planes:8`) | SCENE's |
//! | `wall:F:SCENE` | SCENE with an opaque grey wall across it, facing the default view, a share F in [0, 1] of the way through its bounding sphere (0: in front of everything, 1: behind it) | SCENE's in front of the wall |
//! | `nowall:F:SCENE` | `wall:F:SCENE` with the wall masked away: the same frame with nothing occluded | SCENE's |
//! | `particles:N` | N camera-facing quads (billboards) with a soft round alpha texture, in front of an opaque backdrop | varies |
//! | `fence` | an alpha-masked quad textured with round holes, in front of `planes:4` and an opaque backdrop | 4 through the holes |
//! | `untextured:SCENE` | SCENE with its textures dropped (each object its factor's colour): what a textured frame is timed against | SCENE's |
//! | `default` | a see-through torus knot inside two glass spheres | 10 at the default view, up to 16 |
//! | `bunny`, `armadillo` | the Stanford scans, embedded ([`crate::assets`]) | varies |
//! | `particles`, `foliage`, `glass`, `cad` | the scene set: real content as glTF, embedded ([`crate::scene_set`]); a bare `particles` is the set's, `particles:N` the procedural one | varies |
//!
//! Any other bare name (no extension, not a file) is looked up as `NAME.obj` in
//! [`MODEL_SEARCH`]'s folders.

use std::f32::consts::TAU;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::rng::Rng;
use crate::{AlphaMode, Instance, Mesh, Object, OitError, Scene, Texture, Wrap};

/// The built-in names, for messages.
pub const BUILTIN_SCENES: &str = "default, bunny, armadillo, particles, foliage, glass, cad, planes:N, spheres:N, cluster:N, knot, coplanar, ties:N, near:N, grid:RxC:MESH, scale:S:SCENE, wall:F:SCENE, nowall:F:SCENE, particles:N, fence, untextured:SCENE";

/// Where a bare name that is not built in (`--scene dragon`, `grid:2x2:dragon`) is looked for, as
/// `NAME.obj`, in order: for messages. [`find_model`] is the lookup.
pub const MODEL_SEARCH: &str = "$OIT_MODELS, then models/ in the working directory";

/// The scene rendered when none is named.
pub const DEFAULT_SCENE: &str = "default";

/// Largest N accepted by `planes`, `spheres`, `cluster`.
const MAX_COUNT: u32 = 100_000;

/// Largest N accepted by `ties` and `near`: their alphas must stay distinct in 8 bits.
const MAX_TIES: u32 = 128;

/// A built-in scene or an OBJ file: names in [`BUILTIN_SCENES`] are built, a path to an `.obj` (or
/// any existing file) is read, and any other bare name is looked up as `NAME.obj` in
/// `MODEL_SEARCH`'s folders.
pub fn load_scene(name: &str) -> Result<Scene, OitError> {
    match builtin_scene(name) {
        Some(scene) => scene,
        None => {
            let path = Path::new(name);
            let gltf = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
            if gltf {
                crate::load_gltf(path, None)
            } else if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) || path.exists() {
                crate::load_obj(path)
            } else if let Some(found) = find_model(name) {
                crate::load_obj(&found)
            } else {
                Err(OitError::UnknownScene {
                    name: name.to_string(),
                    known: BUILTIN_SCENES,
                    searched: MODEL_SEARCH,
                })
            }
        }
    }
}

/// Whether scene expression `s` is built from oit's procedural scenes only (`planes:N`,
/// `spheres:N`, `cluster:N`, `knot`, and `grid:RxC:` / `scale:S:` of those): what `--calibrate`
/// may measure. A mesh file, or a bare mesh name looked up in the model folders, is not.
pub fn is_procedural(s: &str) -> bool {
    let mut rest = s.trim();
    loop {
        if let Some(inner) = rest.strip_prefix("untextured:") {
            rest = inner;
            continue;
        }
        let stripped = ["grid:", "scale:", "wall:", "nowall:"].iter().find_map(|p| {
            let tail = rest.strip_prefix(p)?;
            // the prefix's own argument (R×C or S), then the inner scene
            tail.split_once(':').map(|(_, inner)| inner)
        });
        match stripped {
            Some(inner) => rest = inner,
            None => break,
        }
    }
    rest == "knot" || ["planes:", "spheres:", "cluster:"].iter().any(|p| rest.starts_with(p))
}

/// Builds a built-in scene; `None` when the name is not a built-in one, `Some(Err)` when it is but
/// its parameter is bad.
///
/// Every scene built here holds at most [`Scene::MAX_TRIANGLES`] triangles in at most
/// [`Scene::MAX_INSTANCES`] instances; a nested grid is refused before its copies are made.
pub fn builtin_scene(name: &str) -> Option<Result<Scene, OitError>> {
    let scene = builtin_unchecked(name)?;
    Some(
        scene.and_then(|s| Scene::check_size(name, s.triangle_count(), s.instances.len() as u64).map(|()| s)),
    )
}

fn builtin_unchecked(name: &str) -> Option<Result<Scene, OitError>> {
    if let Some(rest) = name.strip_prefix("grid:") {
        return Some(grid(rest));
    }
    if let Some(rest) = name.strip_prefix("scale:") {
        return Some(scaled(rest));
    }
    if let Some(rest) = name.strip_prefix("wall:") {
        return Some(walled(rest, false));
    }
    if let Some(rest) = name.strip_prefix("nowall:") {
        return Some(walled(rest, true));
    }
    if let Some(rest) = name.strip_prefix("untextured:") {
        return Some(untextured(rest));
    }
    if let Some(mesh) = crate::assets::BuiltinMesh::find(name) {
        return Some(mesh.scene());
    }
    if let Some(set) = crate::scene_set::SetScene::find(name) {
        return Some(set.scene());
    }
    let (base, param) = match name.split_once(':') {
        Some((b, p)) => (b, Some(p)),
        None => (name, None),
    };
    let count = |default: u32| -> Result<u32, OitError> {
        match param {
            None => Ok(default),
            Some(p) => match p.parse::<u32>() {
                Ok(n) if (1..=MAX_COUNT).contains(&n) => Ok(n),
                _ => Err(OitError::InvalidSettings(format!(
                    "scene '{name}': N must be a whole number from 1 to {MAX_COUNT}"
                ))),
            },
        }
    };
    let no_param = |s: Scene| match param {
        None => Ok(s),
        Some(_) => Err(OitError::InvalidSettings(format!("scene '{base}' takes no parameter"))),
    };
    Some(match base {
        "planes" => count(8).map(planes),
        "spheres" => count(4).map(spheres),
        "cluster" => count(200).map(cluster),
        "knot" => no_param(knot()),
        "coplanar" => no_param(coplanar()),
        "ties" | "near" => count(8).and_then(|n| {
            if n > MAX_TIES {
                return Err(OitError::InvalidSettings(format!(
                    "scene '{name}': N must be at most {MAX_TIES} (each quad needs its own 8-bit alpha)"
                )));
            }
            Ok(if base == "ties" { ties(n) } else { near(n) })
        }),
        "default" => no_param(default_scene()),
        // a bare `particles` is the scene set's (found above): here only with a count
        "particles" => count(64).and_then(particles),
        "fence" => no_param(Scene::default()).and_then(|_| fence()),
        _ => return None,
    })
}

/// Where a bare mesh name that is not built in (`dragon` of `grid:RxC:dragon`) is looked for, as
/// `<name>.obj`, in order: `$OIT_MODELS`, then `models/` in the working directory
/// ([`MODEL_SEARCH`]). Names with an extension or a path separator are paths, not looked up.
fn find_model(name: &str) -> Option<std::path::PathBuf> {
    let path = Path::new(name);
    if name.is_empty() || path.extension().is_some() || path.components().count() != 1 {
        return None;
    }
    let file = format!("{name}.obj");
    let mut dirs: Vec<std::path::PathBuf> = Vec::new();
    if let Ok(d) = std::env::var("OIT_MODELS") {
        dirs.push(d.into());
    }
    dirs.push("models".into());
    dirs.into_iter().map(|d| d.join(&file)).find(|p| p.is_file())
}

/// `grid:RxC:MESH`: R×C copies of MESH (a built-in scene, an OBJ path, or a bare name looked up by
/// [`find_model`]) on a grid whose cells overlap by 30 % on screen and step back in depth, so
/// triangle count and depth complexity both grow with R×C. Each copy gets its own hue.
fn grid(spec: &str) -> Result<Scene, OitError> {
    let bad = || {
        OitError::InvalidSettings(format!(
            "scene 'grid:{spec}': expected grid:RxC:MESH, e.g. grid:4x4:bunny or grid:2x3:knot"
        ))
    };
    let (dims, mesh) = spec.split_once(':').ok_or_else(bad)?;
    let (r, c) = dims.split_once(['x', 'X']).ok_or_else(bad)?;
    let (rows, cols): (u32, u32) = (r.parse().map_err(|_| bad())?, c.parse().map_err(|_| bad())?);
    if rows == 0 || cols == 0 || rows.saturating_mul(cols) > 4096 {
        return Err(OitError::InvalidSettings(format!(
            "scene 'grid:{spec}': R and C from 1, R×C at most 4096"
        )));
    }
    let base = inner_scene(mesh)?;
    // R×C ≤ 4096 bounds one grid, not a grid of grids: count before copying
    let copies = u64::from(rows * cols);
    Scene::check_size(
        &format!("grid:{spec}"),
        copies.saturating_mul(base.triangle_count()),
        copies.saturating_mul(base.instances.len() as u64),
    )?;
    let bounds = base.bounds();
    if bounds.is_empty() {
        return Err(OitError::InvalidScene(format!("grid mesh '{mesh}' is empty")));
    }
    let size = bounds.max - bounds.min;
    let step = size * 0.7;
    let mut scene = Scene {
        name: format!("grid:{spec}"),
        meshes: base.meshes.clone(),
        textures: base.textures.clone(),
        warnings: base.warnings.clone(),
        ..Default::default()
    };
    for i in 0..rows * cols {
        let (row, col) = (i / cols, i % cols);
        let offset = Vec3::new(
            (col as f32 - (cols - 1) as f32 * 0.5) * step.x,
            (row as f32 - (rows - 1) as f32 * 0.5) * step.y,
            -(((row + col) % 3) as f32) * 0.35 * size.z,
        ) - bounds.center();
        let tint = hue(i as f32 / (rows * cols) as f32);
        for inst in &base.instances {
            let object = &base.objects[inst.object];
            let color = (tint * 0.5 + object.color.truncate() * 0.5).extend(object.color.w);
            // the grid's tint on a blended object's colour; an opaque one keeps its own
            let color = if object.is_opaque_pass() { object.color } else { color };
            scene.objects.push(Object { name: format!("{} {i}", object.name), color, ..object.clone() });
            scene.instances.push(Instance {
                object: scene.objects.len() - 1,
                transform: Mat4::from_translation(offset) * inst.transform,
            });
        }
    }
    Ok(scene)
}

/// The scene a `grid:` or `scale:` expression wraps: a built-in scene, a bare model name looked up
/// by [`find_model`], or a path.
fn inner_scene(name: &str) -> Result<Scene, OitError> {
    match builtin_scene(name) {
        Some(s) => s,
        None => load_scene(name),
    }
}

/// `scale:S:SCENE`: SCENE (as `grid:` takes it) with every world coordinate multiplied by S, a
/// positive number such as `1e-20`: mesh positions are scaled, and instances' translations, so a
/// point `M·p` lands at `S·M·p`. Normals, colours and primitive order are untouched, so the camera,
/// which fits any scale, draws the same picture. Refused when the scaled scene would reach beyond
/// ±[`crate::Mesh::MAX_COORDINATE`].
fn scaled(spec: &str) -> Result<Scene, OitError> {
    let bad = || {
        OitError::InvalidSettings(format!(
            "scene 'scale:{spec}': expected scale:S:SCENE with S a finite number above 0, e.g. scale:1e-20:planes:8"
        ))
    };
    let (factor, inner) = spec.split_once(':').ok_or_else(bad)?;
    let s: f32 = factor.parse().map_err(|_| bad())?;
    if !(s.is_finite() && s > 0.0) {
        return Err(bad());
    }
    let mut scene = inner_scene(inner)?;
    let bounds = scene.bounds();
    let reach = f64::from(bounds.min.abs().max(bounds.max.abs()).max_element()) * f64::from(s);
    if reach > f64::from(crate::Mesh::MAX_COORDINATE) {
        return Err(OitError::InvalidScene(format!(
            "scene 'scale:{spec}' would reach {reach:e} from the origin: world coordinates must lie within ±{:e}; use a smaller S",
            crate::Mesh::MAX_COORDINATE
        )));
    }
    for mesh in &mut scene.meshes {
        for p in &mut mesh.positions {
            *p *= s;
        }
    }
    for inst in &mut scene.instances {
        let t = inst.transform.w_axis;
        inst.transform.w_axis = (t.truncate() * s).extend(t.w);
    }
    scene.name = format!("scale:{spec}");
    Ok(scene)
}

/// `wall:F:SCENE`: SCENE with an opaque wall across it (a grey square of two triangles, drawn
/// first by the opaque pass), perpendicular to the default view's direction, through the point a
/// share F of the way along that direction across the scene's bounding sphere: 0 puts it in front
/// of everything (the frame shows the wall alone), 0.5 through the middle (about half of a
/// scene's transparent fragments behind it), 1 behind everything (an opaque backdrop). The wall
/// is as wide as the sphere, so from the default view it hides all that lies behind it. SCENE's
/// own objects, instances and primitive order are untouched; the wall's instance comes last.
///
/// `nowall:F:SCENE` is the same scene with the wall masked away (alpha 0 under a cutoff of 0.5,
/// [`crate::AlphaMode::Mask`]): the same camera, the same transparent fragments, the same opaque
/// pass, and nothing occluded. What a frame time with the wall is compared against.
fn walled(spec: &str, masked: bool) -> Result<Scene, OitError> {
    let prefix = if masked { "nowall" } else { "wall" };
    let bad = || {
        OitError::InvalidSettings(format!(
            "scene '{prefix}:{spec}': expected {prefix}:F:SCENE with F a number from 0 to 1, e.g. {prefix}:0.5:planes:16"
        ))
    };
    let (share, inner) = spec.split_once(':').ok_or_else(bad)?;
    let f: f32 = share.parse().map_err(|_| bad())?;
    if !(0.0..=1.0).contains(&f) {
        return Err(bad());
    }
    let mut scene = inner_scene(inner)?;
    add_wall(&mut scene, f, masked)?;
    scene.name = format!("{prefix}:{spec}");
    Ok(scene)
}

/// The wall of [`walled`], added to `scene` as its last object and instance.
fn add_wall(scene: &mut Scene, f: f32, masked: bool) -> Result<(), OitError> {
    scene.validate()?;
    let camera = crate::Camera::orbit_scene(scene, crate::View::default(), 1.0)?;
    let bounds = scene.bounds();
    let (center, r) = (bounds.center(), bounds.radius());
    let forward = camera.forward;
    let side = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = side.cross(forward);
    let at = center + forward * ((2.0 * f - 1.0) * r);
    // counter-clockwise seen from the camera (facing −forward)
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let positions = corners.iter().map(|&(a, b)| at + (side * a + up * b) * r).collect();
    scene.meshes.push(Mesh::new("wall", positions, vec![[0, 1, 2], [0, 2, 3]]));
    let mut wall = Object::new("wall", scene.meshes.len() - 1, Vec4::new(0.55, 0.55, 0.55, 1.0)).opaque();
    if masked {
        wall.color.w = 0.0;
        wall.alpha_mode = crate::AlphaMode::Mask { cutoff: 0.5 };
    }
    scene.objects.push(wall);
    scene.instances.push(Instance { object: scene.objects.len() - 1, transform: Mat4::IDENTITY });
    Ok(())
}

/// `untextured:SCENE`: SCENE with every object's texture and every mesh's texture coordinates
/// dropped, each object drawn in its factor's colour: the same geometry, camera and primitive
/// order, so a textured frame can be timed against it (`oit bench`).
fn untextured(inner: &str) -> Result<Scene, OitError> {
    let mut scene = inner_scene(inner)?;
    for o in &mut scene.objects {
        o.texture = None;
    }
    for m in &mut scene.meshes {
        m.uvs = None;
    }
    scene.textures.clear();
    scene.name = format!("untextured:{inner}");
    Ok(scene)
}

/// A 2×2 quad facing +z at z = 0, texture coordinates from (0, 0) at the top left to
/// (`repeat`, `repeat`) at the bottom right (v runs down the image, as glTF's does).
fn textured_quad(name: &str, repeat: f32) -> Mesh {
    let mut m = quad(name, (-1.0, -1.0), (1.0, 1.0), 0.0);
    m.uvs = Some(vec![
        Vec2::new(0.0, repeat),
        Vec2::new(repeat, repeat),
        Vec2::new(repeat, 0.0),
        Vec2::new(0.0, 0.0),
    ]);
    m
}

/// Side of the textures of `particles:N` and `fence`.
const SPRITE_SIZE: u32 = 256;

/// A soft round sprite: white, alpha falling from 1 at the centre to 0 at the inscribed circle
/// as `(1 − r²)²`, in 8 bits.
fn sprite_texture() -> Result<Texture, OitError> {
    let n = SPRITE_SIZE;
    let texels = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
            let (dx, dy) = (x / n as f32 * 2.0 - 1.0, y / n as f32 * 2.0 - 1.0);
            let fall = (1.0 - (dx * dx + dy * dy)).max(0.0);
            [255, 255, 255, (fall * fall * 255.0).round() as u8]
        })
        .collect();
    Texture::new("sprite", n, n, texels, [Wrap::ClampToEdge; 2])
}

/// `particles:N`: N billboards (2×2 quads facing the default view) of a soft round sprite
/// ([`sprite_texture`]), each its own colour at alpha 0.8, placed by a fixed seed in a ball of
/// radius 2, sized so the cloud stays about equally dense whatever N, in front of an opaque
/// backdrop (`wall:1:`). A smoke or spark effect's frame: most of each quad is nearly transparent,
/// and the texture decides what each fragment adds.
fn particles(n: u32) -> Result<Scene, OitError> {
    let mut scene = Scene {
        name: format!("particles:{n}"),
        meshes: vec![textured_quad("billboard", 1.0)],
        textures: vec![sprite_texture()?],
        ..Scene::default()
    };
    // the default view's direction, from a scene of the cloud's extent
    let probe = single("probe".into(), vec![quad("probe", (-2.0, -2.0), (2.0, 2.0), 0.0)], vec![Vec4::ONE]);
    let forward = crate::Camera::orbit_scene(&probe, crate::View::default(), 1.0)?.forward;
    let side = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = side.cross(forward);
    // the quad's +z towards the camera
    let facing = Mat4::from_cols(side.extend(0.0), up.extend(0.0), (-forward).extend(0.0), Vec4::W);
    let size = 0.9 / (n as f32).cbrt();
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    for i in 0..n {
        let mut c;
        loop {
            c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
            if c.length_squared() <= 1.0 {
                break;
            }
        }
        let scale = size * (0.6 + 0.8 * rng.next_f32());
        let color = hue(i as f32 / n as f32).extend(0.8);
        scene.objects.push(Object::new(format!("particle {i}"), 0, color).textured(0));
        scene.instances.push(Instance {
            object: i as usize,
            transform: Mat4::from_translation(c * 2.0) * facing * Mat4::from_scale(Vec3::splat(scale)),
        });
    }
    add_wall(&mut scene, 1.0, false)?;
    Ok(scene)
}

/// A fence's texture: a checker of grey and green cells, each with a round hole whose alpha rises
/// from 0 at its centre to 1 at a radius of 0.8 of the cell's half side (alpha as the distance,
/// so the bilinear samples cross a cutoff of 0.5 at many different texels).
fn fence_texture() -> Result<Texture, OitError> {
    let n = SPRITE_SIZE;
    let cells = 4;
    let cell = n / cells;
    let texels = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let (cx, cy) = (x / cell, y / cell);
            let (fx, fy) = (((x % cell) as f32 + 0.5) / cell as f32, ((y % cell) as f32 + 0.5) / cell as f32);
            let r = ((fx * 2.0 - 1.0).powi(2) + (fy * 2.0 - 1.0).powi(2)).sqrt() / 0.8;
            let a = (r.min(1.0) * 255.0).round() as u8;
            if (cx + cy) % 2 == 0 { [150, 150, 150, a] } else { [60, 170, 80, a] }
        })
        .collect();
    Texture::new("fence", n, n, texels, [Wrap::Repeat, Wrap::MirroredRepeat])
}

/// `fence`: an alpha-masked quad (cutoff 0.5) textured with round holes ([`fence_texture`],
/// repeated twice across it) in front of `planes:4` and an opaque backdrop: the planes show
/// through the holes, and the opaque pass discards (and counts) the fragments of the holes.
fn fence() -> Result<Scene, OitError> {
    let mut scene = planes(4);
    scene.name = "fence".into();
    scene.textures.push(fence_texture()?);
    scene.meshes.push(textured_quad("fence", 2.0));
    scene.objects.push(Object {
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        ..Object::new("fence", scene.meshes.len() - 1, Vec4::ONE).textured(0)
    });
    scene.instances.push(Instance {
        object: scene.objects.len() - 1,
        transform: Mat4::from_translation(Vec3::new(0.0, 0.0, 0.8)) * Mat4::from_scale(Vec3::splat(1.2)),
    });
    add_wall(&mut scene, 1.0, false)?;
    Ok(scene)
}

/// Hue `h` in [0, 1) to an RGB colour quantized to multiples of 1/255 (so 8-bit compositing by hand
/// is exact).
fn hue(h: f32) -> Vec3 {
    let h6 = h.rem_euclid(1.0) * 6.0;
    let x = 1.0 - (h6 % 2.0 - 1.0).abs();
    let (r, g, b) = match h6 as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    // a little white mixed in keeps colours away from pure black channels
    let c = Vec3::new(r, g, b) * 0.8 + Vec3::splat(0.15);
    (c * 255.0).round() / 255.0
}

fn quad(name: &str, min: (f32, f32), max: (f32, f32), z: f32) -> Mesh {
    let p = vec![
        Vec3::new(min.0, min.1, z),
        Vec3::new(max.0, min.1, z),
        Vec3::new(max.0, max.1, z),
        Vec3::new(min.0, max.1, z),
    ];
    Mesh::new(name, p, vec![[0, 1, 2], [0, 2, 3]])
}

fn single(name: String, meshes: Vec<Mesh>, colors: Vec<Vec4>) -> Scene {
    let objects = meshes
        .iter()
        .zip(&colors)
        .enumerate()
        .map(|(i, (m, &color))| Object::new(m.name.clone(), i, color))
        .collect::<Vec<_>>();
    let instances = (0..objects.len()).map(|object| Instance { object, transform: Mat4::IDENTITY }).collect();
    Scene { name, meshes, objects, instances, ..Scene::default() }
}

/// `planes:N`: N 2×2 quads facing +z, spread over a depth of 1 (z from +0.5 to −0.5), each with its
/// own colour and alpha 0.4 (102/255).
pub fn planes(n: u32) -> Scene {
    let mut meshes = Vec::new();
    let mut colors = Vec::new();
    for i in 0..n {
        let z = if n == 1 { 0.0 } else { 0.5 - i as f32 / (n - 1) as f32 };
        meshes.push(quad(&format!("plane {i}"), (-1.0, -1.0), (1.0, 1.0), z));
        colors.push(hue(i as f32 / n as f32 + 0.05).extend(102.0 / 255.0));
    }
    single(format!("planes:{n}"), meshes, colors)
}

/// A UV sphere of radius 1 at the origin.
pub fn uv_sphere(name: &str, segments: u32, rings: u32) -> Mesh {
    let mut positions = Vec::new();
    for r in 0..=rings {
        let theta = r as f32 / rings as f32 * std::f32::consts::PI;
        for s in 0..=segments {
            let phi = s as f32 / segments as f32 * TAU;
            positions.push(Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    let stride = segments + 1;
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = r * stride + s;
            let (b, c, d) = (a + 1, a + stride, a + stride + 1);
            if r != 0 {
                indices.push([a, c, b]);
            }
            if r != rings - 1 {
                indices.push([b, c, d]);
            }
        }
    }
    let mut m = Mesh::new(name, positions, indices);
    // analytic normals: exact and free of the seam's averaging
    m.normals = m.positions.iter().map(|p| p.normalize_or(Vec3::Y)).collect();
    m
}

/// `spheres:N`: N concentric spheres of radii (i+1)/N, each its own colour, alpha 0.3.
pub fn spheres(n: u32) -> Scene {
    let sphere = uv_sphere("sphere", 48, 24);
    let mut scene = Scene { name: format!("spheres:{n}"), meshes: vec![sphere], ..Default::default() };
    for i in 0..n {
        let r = (i + 1) as f32 / n as f32;
        scene.objects.push(Object {
            absorption: 1.5,
            ..Object::new(format!("sphere {i}"), 0, hue(i as f32 / n as f32 + 0.6).extend(0.3))
        });
        scene.instances.push(Instance { object: i as usize, transform: Mat4::from_scale(Vec3::splat(r)) });
    }
    scene
}

/// `cluster:N`: N spheres placed by a fixed seed in the unit cube, radii scaled so the cluster stays
/// about equally dense whatever N.
pub fn cluster(n: u32) -> Scene {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let sphere = uv_sphere("sphere", 16, 8);
    let mut scene = Scene { name: format!("cluster:{n}"), meshes: vec![sphere], ..Default::default() };
    let base = 0.6 / (n as f32).cbrt();
    for i in 0..n {
        let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let r = base * (0.6 + 0.8 * rng.next_f32());
        let color = hue(rng.next_f32()).extend(0.25 + 0.5 * rng.next_f32());
        scene.objects.push(Object { absorption: 2.0, ..Object::new(format!("ball {i}"), 0, color) });
        scene.instances.push(Instance {
            object: i as usize,
            transform: Mat4::from_translation(c) * Mat4::from_scale(Vec3::splat(r)),
        });
    }
    scene
}

/// A tube of radius `r` around the (p, q) torus knot.
pub fn torus_knot(p: u32, q: u32, r: f32, segments: u32, sides: u32) -> Mesh {
    let curve = |t: f32| {
        let (pt, qt) = (p as f32 * t, q as f32 * t);
        let rr = 0.6 + 0.3 * qt.cos();
        Vec3::new(rr * pt.cos(), 0.3 * qt.sin(), rr * pt.sin())
    };
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..segments {
        let t = i as f32 / segments as f32 * TAU;
        let c = curve(t);
        let tangent = (curve(t + 1e-3) - curve(t - 1e-3)).normalize();
        let side = tangent.cross(c.normalize_or(Vec3::X)).normalize_or(Vec3::Y);
        let up = side.cross(tangent);
        for j in 0..sides {
            let a = j as f32 / sides as f32 * TAU;
            let n = side * a.cos() + up * a.sin();
            positions.push(c + n * r);
            normals.push(n);
        }
    }
    let mut indices = Vec::new();
    for i in 0..segments {
        let i1 = (i + 1) % segments;
        for j in 0..sides {
            let j1 = (j + 1) % sides;
            let (a, b, c, d) = (i * sides + j, i1 * sides + j, i1 * sides + j1, i * sides + j1);
            indices.push([a, b, c]);
            indices.push([a, c, d]);
        }
    }
    Mesh { name: "knot".into(), positions, normals, colors: None, uvs: None, indices }
}

/// `knot`: a (2, 3) torus-knot tube that passes in front of and behind itself.
pub fn knot() -> Scene {
    single("knot".into(), vec![torus_knot(2, 3, 0.14, 384, 24)], vec![Vec4::new(1.0, 0.55, 0.15, 0.35)])
}

/// `coplanar`: two overlapping quads in the plane z = 0, red and blue: where they overlap the
/// fragments tie in depth.
pub fn coplanar() -> Scene {
    single(
        "coplanar".into(),
        vec![quad("left", (-1.0, -1.0), (0.5, 0.5), 0.0), quad("right", (-0.5, -0.5), (1.0, 1.0), 0.0)],
        vec![Vec4::new(0.9, 0.1, 0.1, 0.5), Vec4::new(0.1, 0.2, 0.9, 0.5)],
    )
}

/// `ties:N`: N 1.4 × 1.4 quads in the plane z = 0, each shifted from the last so that pixels see
/// different subsets of them and the middle sees all N, where every fragment ties in depth with
/// every other. Each quad has its own colour and alpha (alphas from 60/255 to 210/255), and the
/// order of the packed colours (alpha is their top byte) is neither the primitive order nor its
/// reverse (for N ≥ 3; for N = 2 it is the reverse): quad i gets alpha rank (N + ⌊N/2⌋ − i) mod N.
/// A technique that orders equal depths by colour instead of by primitive id, as the reference
/// does, composites these pixels in the wrong order (`coplanar` hides that: its colour order is
/// its primitive order).
pub fn ties(n: u32) -> Scene {
    tie_quads(format!("ties:{n}"), n, 0.0)
}

/// `near:N`: `ties:N` with quad i at z = i · 10⁻⁷: distinct in the scene, equal (or an ulp apart)
/// once projected to f32 depth, and always equal in `mdts`'s 20 depth bits.
pub fn near(n: u32) -> Scene {
    tie_quads(format!("near:{n}"), n, 1e-7)
}

fn tie_quads(name: String, n: u32, dz: f32) -> Scene {
    let mut meshes = Vec::new();
    let mut colors = Vec::new();
    for i in 0..n {
        let t = if n == 1 { 0.0 } else { i as f32 / (n - 1) as f32 };
        // x steps evenly, y zigzags, so neighbouring quads overlap in different corners
        let (x, y) = (-1.0 + 0.6 * t, -1.0 + 0.6 * ((i * 3) % n) as f32 / n.max(2) as f32);
        meshes.push(quad(&format!("quad {i}"), (x, y), (x + 1.4, y + 1.4), i as f32 * dz));
        let rank = (n + n / 2 - i) % n;
        let alpha = (60 + rank * 150 / (n - 1).max(1)) as f32 / 255.0;
        colors.push(hue(i as f32 / n as f32 + 0.1).extend(alpha));
    }
    single(name, meshes, colors)
}

/// `default`: a warm torus knot inside two cool glass spheres: at 512² the deepest pixel holds 10
/// layers at the default view, and up to 16 at others around the orbit. The knot's alpha (0.32)
/// and the glass's (0.06, 0.045) are low enough that where the tube crosses itself the crossing
/// behind shows through the one in front: 41 % of its colour passes the near walls of both glass
/// spheres and the front and back walls of the nearer tube, `(1 − 0.32)² · (1 − 0.06) · (1 −
/// 0.045)` (at the former alphas, 0.6, 0.14 and 0.1, it was 12 %, and the knot read as opaque).
pub fn default_scene() -> Scene {
    let mut scene = knot();
    scene.name = "default".into();
    scene.objects[0].color = Vec4::new(1.0, 0.42, 0.08, 0.32);
    scene.meshes.push(uv_sphere("sphere", 64, 32));
    for (i, (r, color)) in
        [(1.05f32, Vec4::new(0.2, 0.5, 1.0, 0.06)), (1.25, Vec4::new(0.45, 0.9, 0.8, 0.045))]
            .into_iter()
            .enumerate()
    {
        scene.objects.push(Object { absorption: 0.5, ..Object::new(format!("glass {i}"), 1, color) });
        scene.instances.push(Instance { object: i + 1, transform: Mat4::from_scale(Vec3::splat(r)) });
    }
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_validates() {
        for name in [
            "default",
            "planes:1",
            "planes:8",
            "spheres:4",
            "cluster:20",
            "knot",
            "coplanar",
            "ties:1",
            "ties:2",
            "ties:8",
            "near:8",
            "near:128",
        ] {
            let s = load_scene(name).unwrap();
            s.validate().unwrap();
        }
    }

    #[test]
    fn bad_names() {
        assert!(load_scene("planes:0").is_err());
        assert!(load_scene("planes:x").is_err());
        assert!(load_scene("knot:3").is_err());
        assert!(load_scene("ties:0").is_err());
        assert!(load_scene("ties:129").is_err());
        assert!(matches!(load_scene("nothing-like-this"), Err(OitError::UnknownScene { .. })));
    }

    /// `bunny` and `armadillo` need no file, also inside `grid:` and `scale:`; an unknown bare name's
    /// error lists the built-in names and where bare names are looked up.
    /// Fails if the built-in meshes are dropped from `builtin_unchecked`, or the error loses either
    /// list (e.g. `searched` printed as the old "expected a path to an .obj file").
    #[test]
    fn builtin_meshes_resolve_without_a_path() {
        assert_eq!(load_scene("bunny").unwrap().triangle_count(), 69_666);
        assert_eq!(load_scene("grid:2x2:bunny").unwrap().triangle_count(), 4 * 69_666);
        assert_eq!(load_scene("scale:2:armadillo").unwrap().triangle_count(), 52_000);
        let err = load_scene("no-such-mesh").unwrap_err().to_string();
        for needed in ["no-such-mesh.obj", "bunny", "armadillo", "$OIT_MODELS", "models/"] {
            assert!(err.contains(needed), "{needed} missing from: {err}");
        }
        let err = load_scene("grid:2x2:no-such-mesh").unwrap_err().to_string();
        assert!(err.contains("built-in scenes: default, bunny, armadillo"), "{err}");
    }

    #[test]
    fn grids() {
        let g = load_scene("grid:2x3:knot").unwrap();
        g.validate().unwrap();
        assert_eq!(g.instances.len(), 6);
        assert_eq!(g.triangle_count(), 6 * knot().triangle_count());
        for bad in ["grid:0x3:knot", "grid:2:knot", "grid:2x3", "grid:2x3:nope-nothing", "grid:axb:knot"] {
            assert!(load_scene(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn scaled_scenes() {
        let unit = load_scene("planes:3").unwrap();
        for (factor, k) in [("1e-20", 1e-20f32), ("1e20", 1e20), ("0.5", 0.5)] {
            let s = load_scene(&format!("scale:{factor}:planes:3")).unwrap();
            s.validate().unwrap();
            assert_eq!(s.name, format!("scale:{factor}:planes:3"));
            assert_eq!(s.triangle_count(), unit.triangle_count());
            let (a, b) = (s.bounds(), unit.bounds());
            assert_eq!((a.min, a.max), (b.min * k, b.max * k), "{factor}");
            assert_eq!(s.meshes[0].normals, unit.meshes[0].normals);
        }
        // instances: translations scale with the positions (spheres:2 places scaled copies)
        let s = load_scene("scale:4:grid:1x2:spheres:2").unwrap();
        let g = load_scene("grid:1x2:spheres:2").unwrap();
        let (a, b) = (s.bounds(), g.bounds());
        assert!(
            (a.min - b.min * 4.0).abs().max_element() < 1e-5
                && (a.max - b.max * 4.0).abs().max_element() < 1e-5
        );
        for bad in
            ["scale:0:planes:2", "scale:-1:planes:2", "scale:inf:planes:2", "scale:x:planes:2", "scale:2"]
        {
            let e = load_scene(bad).unwrap_err().to_string();
            assert!(e.contains("scale:S:SCENE"), "{bad}: {e}");
        }
        let e = load_scene("scale:1e31:planes:2").unwrap_err().to_string();
        assert!(e.contains("within ±1e30") && e.contains("smaller S"), "{e}");
        assert!(load_scene("scale:2:nothing-like-this").is_err());
    }

    #[test]
    fn nested_grids_are_capped() {
        // each level passes the R×C ≤ 4096 cap; the product is what must be bounded, and before
        // the copies are made (4096 × 4096 knots: 309G triangles)
        let e = load_scene("grid:64x64:grid:64x64:knot").unwrap_err().to_string();
        assert!(e.contains("triangles") && e.contains("over the limit of 50000000"), "{e}");
        // 4096² planes:1 copies are only 33.5M triangles, but 16.7M instances
        let e = load_scene("grid:64x64:grid:64x64:planes:1").unwrap_err().to_string();
        assert!(e.contains("16777216 instances") && e.contains("over the limit"), "{e}");
        let g = load_scene("grid:2x2:grid:2x2:planes:2").unwrap();
        assert_eq!(g.triangle_count(), 4 * 4 * 2 * 2);
        // a flat built-in over the cap is refused too (spheres:N has 2,208 triangles per sphere)
        let e = load_scene("spheres:100000").unwrap_err().to_string();
        assert!(e.contains("220800000 triangles"), "{e}");
    }

    #[test]
    fn tie_colours_are_out_of_primitive_order() {
        use crate::rules::pack_rgba8;
        for n in [2u32, 3, 4, 8, 128] {
            let s = ties(n);
            let keys: Vec<u32> = s.objects.iter().map(|o| pack_rgba8(o.color)).collect();
            let mut sorted = keys.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), n as usize, "ties:{n}: distinct colours");
            assert_ne!(keys, sorted, "ties:{n}: colour order is not primitive order");
            if n >= 3 {
                sorted.reverse();
                assert_ne!(keys, sorted, "ties:{n}: nor its reverse");
            }
        }
    }

    /// The default scene's knot is see-through where it crosses itself: the first picture a user
    /// gets must show transparency, not an opaque tube (issue 14). What passes to the eye of a
    /// crossing behind the tube: through the near walls of both glass spheres and both walls of
    /// the nearer tube. Below about a quarter the knot reads as opaque (it was 0.12).
    #[test]
    fn default_knot_shows_its_crossings() {
        let s = default_scene();
        let alpha = |i: usize| s.objects[i].color.w;
        let through = (1.0 - alpha(0)).powi(2) * (1.0 - alpha(1)) * (1.0 - alpha(2));
        assert!(through >= 0.4, "{through}");
        // and the knot still stands out from the glass: it is the most opaque object
        assert!(alpha(0) > 4.0 * alpha(1).max(alpha(2)));
    }

    #[test]
    fn cluster_is_deterministic() {
        assert_eq!(cluster(50), cluster(50));
    }

    #[test]
    fn calibration_scenes_are_procedural_and_meshes_are_not() {
        for s in [
            "planes:4",
            "spheres:6",
            "cluster:800",
            "knot",
            "grid:4x4:knot",
            "grid:2x2:grid:3x3:spheres:1",
            "scale:2:planes:3",
        ] {
            assert!(is_procedural(s), "{s}");
        }
        for s in [
            "bunny",
            "bunny.obj",
            "models/bunny.obj",
            "grid:4x4:bunny",
            "grid:4x4:bunny.obj",
            "scale:2:armadillo",
            "grid:4x4",
            "default",
            "coplanar",
        ] {
            assert!(!is_procedural(s), "{s}");
        }
    }
}
