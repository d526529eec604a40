//! The scene set: four scenes of real content, the cases OIT exists for, made by oit itself and
//! shipped as glTF: `particles`, `foliage`, `glass` and `cad` ([`SCENE_SET`]).
//!
//! Each is built here in code ([`generate`]: fixed seeds, nothing from the operating system),
//! written as a binary glTF file by [`crate::write_glb`], gzip-compressed, and committed under
//! `oit-core/assets/scenes/` as `NAME.glb.gz`; the library embeds the four files
//! (`include_bytes!`, as it does the bunny), and `--scene NAME` reads them back through the glTF
//! loader ([`SetScene::scene`]). The example `scene_set` writes them again:
//!
//! ```text
//! cargo run --release -p oit-core --example scene_set -- oit-core/assets/scenes
//! ```
//!
//! and a test holds the committed files to what [`generate`] builds now, so they cannot drift.
//!
//! Every scene is laid out for the default view (azimuth 30°, elevation 20°): built facing +z,
//! then turned 30° about the vertical axis, so the camera looks at its front (`cad` a further 35°,
//! so the gears show their faces).

use std::f32::consts::{PI, TAU};
use std::io::{Read, Write};
use std::path::Path;

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

use crate::rng::Rng;
use crate::{AlphaMode, Instance, Mesh, Object, OitError, Scene, Texture, Wrap};

/// One scene of the set: its name, what it is, and its compressed GLB.
#[derive(Debug, Clone, Copy)]
pub struct SetScene {
    /// The scene name that loads it (`glass`), and the file's stem (`glass.glb.gz`).
    pub name: &'static str,
    /// What it is, in a few words.
    pub about: &'static str,
    /// The gzip-compressed GLB.
    gz: &'static [u8],
}

/// The scene set, by name.
pub const SCENE_SET: &[SetScene] = &[
    SetScene {
        name: "particles",
        about: "smoke and fire: 1,200 camera-facing billboards with a soft round alpha texture, over logs, a floor and a wall",
        gz: include_bytes!("../assets/scenes/particles.glb.gz"),
    },
    SetScene {
        name: "foliage",
        about: "three trees: alpha-masked and blended leaf cards on opaque trunks and branches, on opaque ground",
        gz: include_bytes!("../assets/scenes/foliage.glb.gz"),
    },
    SetScene {
        name: "glass",
        about: "the bunny and the armadillo in glass (blended, with transmission) on pedestals in an opaque room",
        gz: include_bytes!("../assets/scenes/glass.glb.gz"),
    },
    SetScene {
        name: "cad",
        about: "an opaque gearbox (plate, bearing blocks, shafts, gears, motor, bolts) inside three nested transparent housings",
        gz: include_bytes!("../assets/scenes/cad.glb.gz"),
    },
];

impl SetScene {
    /// The scene named `name`, if it is one of the set.
    pub fn find(name: &str) -> Option<&'static SetScene> {
        SCENE_SET.iter().find(|s| s.name == name)
    }

    /// The file's name in `oit-core/assets/scenes/` (`glass.glb.gz`).
    pub fn file_name(&self) -> String {
        format!("{}.glb.gz", self.name)
    }

    /// The compressed file as embedded.
    pub fn compressed(&self) -> &'static [u8] {
        self.gz
    }

    /// The GLB, decompressed.
    pub fn glb(&self) -> Result<Vec<u8>, OitError> {
        gunzip(self.gz).map_err(|e| OitError::Model {
            path: format!("{} (built in)", self.file_name()).into(),
            message: format!("cannot decompress the built-in scene: {e}"),
        })
    }

    /// The scene, read from the embedded GLB by the glTF loader ([`crate::parse_gltf`]), named
    /// after the set's name.
    pub fn scene(&self) -> Result<Scene, OitError> {
        let mut scene = crate::parse_gltf(Path::new(&format!("{}.glb", self.name)), &self.glb()?, None)?;
        scene.name = self.name.to_string();
        Ok(scene)
    }
}

/// `bytes` gzip-compressed at the highest level, with no name or time stamp in the header (the
/// same input gives the same bytes with the same `flate2`).
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::GzBuilder::new().mtime(0).write(Vec::new(), flate2::Compression::best());
    // writing into a Vec cannot fail
    e.write_all(bytes).expect("gzip into memory");
    e.finish().expect("gzip into memory")
}

/// The bytes of a gzip stream, decompressed.
pub fn gunzip(gz: &[u8]) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::with_capacity(gz.len() * 2);
    flate2::read::GzDecoder::new(gz).read_to_end(&mut out)?;
    Ok(out)
}

/// Builds scene `name` of the set from scratch, as it is committed; `None` for a name not in it.
pub fn generate(name: &str) -> Option<Result<Scene, OitError>> {
    let scene = match name {
        "particles" => particles(),
        "foliage" => foliage(),
        "glass" => glass(),
        "cad" => cad(),
        _ => return None,
    };
    Some(scene.and_then(|s| s.validate().map(|()| s)))
}

/// The turn about the vertical axis that makes the default view (azimuth 30°) look at the front
/// of a scene built facing +z.
fn front() -> Mat4 {
    Mat4::from_rotation_y(crate::View::default().azimuth.to_radians())
}

/// A scene as it is built: meshes, objects and placements added one by one.
struct Build {
    scene: Scene,
    /// What every placement is turned by: [`front`], unless a scene turns itself further.
    turn: Mat4,
}

impl Build {
    fn new(name: &str) -> Build {
        Build { scene: Scene { name: name.into(), ..Scene::default() }, turn: front() }
    }

    fn mesh(&mut self, mesh: Mesh) -> usize {
        self.scene.meshes.push(mesh);
        self.scene.meshes.len() - 1
    }

    fn texture(&mut self, texture: Texture) -> usize {
        self.scene.textures.push(texture);
        self.scene.textures.len() - 1
    }

    fn object(&mut self, object: Object) -> usize {
        self.scene.objects.push(object);
        self.scene.objects.len() - 1
    }

    /// An opaque object of `mesh` in `rgb`.
    fn solid(&mut self, name: &str, mesh: usize, rgb: Vec3) -> usize {
        self.object(Object::new(name, mesh, rgb.extend(1.0)).opaque())
    }

    fn place(&mut self, object: usize, transform: Mat4) {
        self.scene.instances.push(Instance { object, transform: self.turn * transform });
    }

    fn done(self) -> Result<Scene, OitError> {
        Ok(self.scene)
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes

/// A box of half sides `half` about the origin: 24 vertices, 4 a face, so each face is flat.
fn cuboid(name: &str, half: Vec3) -> Mesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    // each face: its normal axis and sign, and two axes spanning it (counter-clockwise seen from
    // outside)
    for (n, a, b) in [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ] {
        let base = positions.len() as u32;
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            positions.push((n + a * s + b * t) * half);
        }
        indices.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    Mesh::new(name, positions, indices)
}

/// A prism along y from `y0` to `y1` over a closed outline in the xz plane (star-shaped about the
/// origin, counter-clockwise seen from +y): smooth sides where `smooth`, flat ones otherwise,
/// and flat caps.
fn prism(name: &str, outline: &[Vec2], y0: f32, y1: f32, smooth: bool) -> Mesh {
    let n = outline.len() as u32;
    let at = |p: Vec2, y: f32| Vec3::new(p.x, y, -p.y);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    if smooth {
        for &p in outline {
            positions.extend([at(p, y0), at(p, y1)]);
        }
        for i in 0..n {
            let j = (i + 1) % n;
            indices.extend([[2 * i, 2 * j, 2 * j + 1], [2 * i, 2 * j + 1, 2 * i + 1]]);
        }
    } else {
        for i in 0..n as usize {
            let (p, q) = (outline[i], outline[(i + 1) % n as usize]);
            let base = positions.len() as u32;
            positions.extend([at(p, y0), at(q, y0), at(q, y1), at(p, y1)]);
            indices.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
    }
    // the caps: fans about the centre
    for (y, up) in [(y1, true), (y0, false)] {
        let centre = positions.len() as u32;
        positions.push(Vec3::new(0.0, y, 0.0));
        for &p in outline {
            positions.push(at(p, y));
        }
        for i in 0..n {
            let (a, b) = (centre + 1 + i, centre + 1 + (i + 1) % n);
            indices.push(if up { [centre, a, b] } else { [centre, b, a] });
        }
    }
    let mut mesh = Mesh::new(name, positions, indices);
    if smooth {
        // the sides' normals radial, exactly (the fan's own average would tilt them)
        for (i, &p) in outline.iter().enumerate() {
            let radial = at(p, 0.0).normalize_or(Vec3::X);
            mesh.normals[2 * i] = radial;
            mesh.normals[2 * i + 1] = radial;
        }
    }
    mesh
}

/// A circle of `segments` points of radius `r`.
fn circle(r: f32, segments: u32) -> Vec<Vec2> {
    (0..segments).map(|i| Vec2::from_angle(i as f32 / segments as f32 * TAU) * r).collect()
}

/// A cylinder of radius `r` along y from `y0` to `y1`.
fn cylinder(name: &str, r: f32, y0: f32, y1: f32, segments: u32) -> Mesh {
    prism(name, &circle(r, segments), y0, y1, true)
}

/// A spur gear's outline: `teeth` teeth between the root radius `root` and the tip radius `tip`.
fn gear_outline(teeth: u32, root: f32, tip: f32) -> Vec<Vec2> {
    let step = TAU / teeth as f32;
    let mut out = Vec::new();
    for i in 0..teeth {
        let a = i as f32 * step;
        // root, flank up, tip, flank down: the tip a third of the pitch, the flanks slanted
        for (da, r) in [(0.0, root), (0.2, tip), (0.5, tip), (0.7, root)] {
            out.push(Vec2::from_angle(a + da * step) * r);
        }
    }
    out
}

/// A card in the xy plane facing +z: `x` across from −w/2 to w/2, `y` from `y0` to `y0 + h`;
/// texture coordinates (0, 0) at the top left, (1, 1) at the bottom right (v down the image).
fn card(name: &str, w: f32, h: f32, y0: f32) -> Mesh {
    let positions = vec![
        Vec3::new(-w / 2.0, y0, 0.0),
        Vec3::new(w / 2.0, y0, 0.0),
        Vec3::new(w / 2.0, y0 + h, 0.0),
        Vec3::new(-w / 2.0, y0 + h, 0.0),
    ];
    let mut m = Mesh::new(name, positions, vec![[0, 1, 2], [0, 2, 3]]);
    m.uvs = Some(vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)]);
    m
}

/// The rotation taking +y to `dir` (a unit vector).
fn along(dir: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::Y, dir.normalize())
}

/// A colour given as 8-bit values, divided by 255: linear factors in [0, 1], picked by eye.
fn rgb(r: u8, g: u8, b: u8) -> Vec3 {
    Vec3::new(f32::from(r), f32::from(g), f32::from(b)) / 255.0
}

// ---------------------------------------------------------------------------------------------
// Textures

/// Side of the set's textures.
const TEXTURE_SIZE: u32 = 64;

/// `f(u, v)` sampled at the texel centres of a `TEXTURE_SIZE`² texture (row 0 at v = 0).
fn paint(name: &str, wrap: [Wrap; 2], f: impl Fn(f32, f32) -> [f32; 4]) -> Result<Texture, OitError> {
    let n = TEXTURE_SIZE;
    let texels = (0..n * n)
        .map(|i| {
            let (u, v) = (((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
            f(u, v).map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
        })
        .collect();
    Texture::new(name, n, n, texels, wrap)
}

/// A soft round puff: white, alpha falling smoothly as `(1 − r²)²` from 1 at the centre to 0 at
/// the inscribed circle.
fn puff_texture() -> Result<Texture, OitError> {
    paint("puff", [Wrap::ClampToEdge; 2], |u, v| {
        let r2 = (u * 2.0 - 1.0).powi(2) + (v * 2.0 - 1.0).powi(2);
        let a = (1.0 - r2).max(0.0).powi(2);
        [1.0, 1.0, 1.0, a]
    })
}

/// A leaf, its stalk at the bottom (v = 1) and its tip at the top: a pointed oval with a pale
/// midrib, alpha 1 inside and 0 outside with a one-texel ramp at the edge (where a mask's cutoff
/// of 0.5 cuts).
fn leaf_texture() -> Result<Texture, OitError> {
    paint("leaf", [Wrap::ClampToEdge; 2], |u, v| {
        let along = 1.0 - v; // 0 at the stalk, 1 at the tip
        let x = (u - 0.5).abs();
        let blade = if along > 0.12 {
            let t = (along - 0.12) / 0.86;
            0.44 * (PI * t.clamp(0.0, 1.0)).sin().powf(0.75)
        } else {
            0.0
        };
        let stalk = if along <= 0.2 { 0.035 } else { 0.0 };
        let half = blade.max(stalk);
        let edge = 1.0 / TEXTURE_SIZE as f32;
        let a = ((half - x) / edge + 0.5).clamp(0.0, 1.0);
        let rib = (1.0 - x / 0.03).max(0.0);
        let shade = 0.75 + 0.25 * along;
        let g = [0.36 * shade, 0.72 * shade, 0.22 * shade];
        [g[0] + 0.4 * rib, g[1] + 0.2 * rib, g[2] + 0.3 * rib, a]
    })
}

// ---------------------------------------------------------------------------------------------
// The scenes

/// `particles`: smoke rising from a fire of logs, 1,200 billboards (facing the default view) of a
/// soft round puff, coloured from flame (bottom) to grey smoke (top) by 12 materials, blended;
/// behind them an opaque wall, under them an opaque floor and the logs.
fn particles() -> Result<Scene, OitError> {
    let mut b = Build::new("particles");
    let floor = b.mesh(cuboid("floor", Vec3::new(3.2, 0.05, 2.2)));
    let floor = b.solid("floor", floor, rgb(96, 88, 80));
    b.place(floor, Mat4::from_translation(Vec3::new(0.0, -0.05, 0.0)));
    let wall = b.mesh(cuboid("wall", Vec3::new(3.2, 2.4, 0.05)));
    let wall = b.solid("wall", wall, rgb(120, 124, 132));
    b.place(wall, Mat4::from_translation(Vec3::new(0.0, 2.35, -2.15)));
    let log = b.mesh(cylinder("log", 0.09, -0.55, 0.55, 16));
    let log = b.solid("log", log, rgb(92, 60, 36));
    for i in 0..6 {
        let a = i as f32 / 6.0 * TAU;
        let dir = Vec3::new(a.cos(), 0.0, a.sin());
        // leaning inwards, their tops meeting over the fire's centre
        let tilt = along(Vec3::new(-dir.x * 0.8, 1.0, -dir.z * 0.8));
        b.place(log, Mat4::from_rotation_translation(tilt, dir * 0.3 + Vec3::Y * 0.3));
    }
    let stone = b.mesh(cuboid("stone", Vec3::new(0.1, 0.07, 0.08)));
    let stone = b.solid("stone", stone, rgb(110, 110, 104));
    for i in 0..10 {
        let a = i as f32 / 10.0 * TAU;
        b.place(
            stone,
            Mat4::from_rotation_translation(
                Quat::from_rotation_y(-a),
                Vec3::new(a.cos() * 0.62, 0.07, a.sin() * 0.62),
            ),
        );
    }
    // the billboards: +z of the card towards the camera, in the scene's own frame (turned by
    // `front` like the rest)
    let view = crate::View::default();
    let el = view.elevation.to_radians();
    let towards = Vec3::new(0.0, el.sin(), el.cos());
    let side = Vec3::Y.cross(towards).normalize();
    let up = towards.cross(side);
    let facing = Mat4::from_cols(side.extend(0.0), up.extend(0.0), towards.extend(0.0), Vec4::W);
    let puff = b.texture(puff_texture()?);
    let quad = b.mesh(card("billboard", 2.0, 2.0, -1.0));
    const BANDS: usize = 12;
    let mut colors = Vec::with_capacity(BANDS);
    for k in 0..BANDS {
        // flame yellow and orange low down, then a warm grey turning to a cool, thinner grey
        let t = k as f32 / (BANDS - 1) as f32;
        let (color, alpha) = if t < 0.25 {
            let s = t / 0.25;
            (rgb(255, 214, 90).lerp(rgb(240, 110, 40), s), 0.7)
        } else {
            let s = (t - 0.25) / 0.75;
            (rgb(150, 132, 120).lerp(rgb(196, 200, 210), s), 0.55 - 0.25 * s)
        };
        colors.push(b.object(Object::new(format!("smoke {k}"), quad, color.extend(alpha)).textured(puff)));
    }
    let mut rng = Rng(0x5eed_0001_b111_b0a7);
    const COUNT: usize = 1200;
    for _ in 0..COUNT {
        // height along the plume, denser low down; the plume widens and drifts as it rises
        let h = rng.next_f32().powf(1.3);
        let y = 0.35 + h * 3.6;
        let spread = 0.25 + 0.85 * h;
        let (r, a) = (spread * rng.next_f32().sqrt(), rng.next_f32() * TAU);
        let drift = Vec3::new(0.5 * h * h, 0.0, -0.3 * h);
        let centre = Vec3::new(r * a.cos(), y, r * a.sin() * 0.7) + drift;
        let size = (0.16 + 0.36 * h) * (0.75 + 0.5 * rng.next_f32());
        let band = ((h * BANDS as f32) as usize + (rng.next_f32() * 2.0) as usize).min(BANDS - 1);
        b.place(colors[band], Mat4::from_translation(centre) * facing * Mat4::from_scale(Vec3::splat(size)));
    }
    b.done()
}

/// `foliage`: three trees on a patch of ground, each a trunk and branches (opaque, smooth
/// cylinders) with leaf cards along its branches and in a crown at the top: the crown's cards
/// alpha-masked (cutoff 0.5), the branches' masked three times in five and blended (alpha 0.6)
/// otherwise; four greens for the masked, two yellow-greens for the blended, one leaf texture.
fn foliage() -> Result<Scene, OitError> {
    let mut b = Build::new("foliage");
    let ground = b.mesh(cuboid("ground", Vec3::new(2.3, 0.06, 1.5)));
    let ground = b.solid("ground", ground, rgb(84, 104, 52));
    b.place(ground, Mat4::from_translation(Vec3::new(0.0, -0.06, 0.0)));
    let bark = rgb(88, 66, 48);
    let trunk = b.mesh(cylinder("trunk", 1.0, 0.0, 1.0, 16));
    let trunk = b.solid("trunk", trunk, bark);
    let branch = b.mesh(cylinder("branch", 1.0, 0.0, 1.0, 10));
    let branch = b.solid("branch", branch, bark * 1.15);
    let leaf = b.texture(leaf_texture()?);
    let card = b.mesh(card("leaf card", 0.26, 0.36, 0.0));
    let mut masked = Vec::new();
    for (k, c) in
        [rgb(230, 255, 220), rgb(200, 235, 180), rgb(160, 210, 150), rgb(255, 255, 235)].iter().enumerate()
    {
        let o = Object {
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            ..Object::new(format!("leaf {k}"), card, c.extend(1.0))
        };
        masked.push(b.object(o.textured(leaf)));
    }
    let mut blended = Vec::new();
    for (k, c) in [rgb(255, 240, 120), rgb(230, 255, 150)].iter().enumerate() {
        blended.push(b.object(Object::new(format!("thin leaf {k}"), card, c.extend(0.6)).textured(leaf)));
    }
    let mut rng = Rng(0x5eed_0002_1eaf_ca7d);
    for (base, height, radius) in [
        (Vec3::new(-1.25, 0.0, -0.4), 2.2, 0.09),
        (Vec3::new(0.15, 0.0, 0.25), 2.7, 0.11),
        (Vec3::new(1.35, 0.0, -0.6), 2.0, 0.08),
    ] {
        b.place(trunk, Mat4::from_translation(base) * Mat4::from_scale(Vec3::new(radius, height, radius)));
        let branches = 8;
        for i in 0..branches {
            let a = i as f32 / branches as f32 * TAU + rng.next_f32() * 0.6;
            let y = height * (0.45 + 0.5 * i as f32 / branches as f32);
            let dir = Vec3::new(a.cos(), 0.5 + 0.6 * rng.next_f32(), a.sin()).normalize();
            let length = 0.55 + 0.35 * rng.next_f32();
            let start = base + Vec3::Y * y;
            b.place(
                branch,
                Mat4::from_scale_rotation_translation(
                    Vec3::new(radius * 0.4, length, radius * 0.4),
                    along(dir),
                    start,
                ),
            );
            // leaves along the outer two thirds and around the tip, each turned its own way
            for _ in 0..24 {
                let t = 0.35 + 0.75 * rng.next_f32();
                let at = start
                    + dir * (length * t)
                    + (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * 0.18;
                let turn = Quat::from_euler(
                    glam::EulerRot::YXZ,
                    rng.next_f32() * TAU,
                    (rng.next_f32() - 0.5) * 1.6,
                    (rng.next_f32() - 0.5) * 2.4,
                );
                let scale = Vec3::splat(0.8 + 0.5 * rng.next_f32());
                let object = if rng.next_f32() < 0.6 {
                    masked[(rng.next_u64() % masked.len() as u64) as usize]
                } else {
                    blended[(rng.next_u64() % blended.len() as u64) as usize]
                };
                b.place(object, Mat4::from_scale_rotation_translation(scale, turn, at));
            }
        }
        // a crown of leaves at the top of the trunk
        for _ in 0..30 {
            let at = base
                + Vec3::Y * height
                + (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * 0.6;
            let turn = Quat::from_euler(
                glam::EulerRot::YXZ,
                rng.next_f32() * TAU,
                (rng.next_f32() - 0.5) * 1.2,
                (rng.next_f32() - 0.5) * 1.2,
            );
            let object = masked[(rng.next_u64() % masked.len() as u64) as usize];
            b.place(object, Mat4::from_rotation_translation(turn, at));
        }
    }
    b.done()
}

/// The absorption of the `glass` scene's medium ([`Object::absorption`]): per 1/8 of the scene's
/// radius, `(1 − c)·1.5` per channel, `c` the glass's colour (a tint that deepens with the
/// thickness the translucency effect looks through).
const GLASS_ABSORPTION: f32 = 1.5;

/// `glass`: the bunny and the armadillo (the built-in scans, as they are) in glass — blended,
/// alpha 0.5 with transmission 0.5, so each surface lets 75 % through, and a volume
/// (`KHR_materials_volume`: a thickness of a fifth of the figure's height, and the medium
/// [`GLASS_ABSORPTION`], which the translucency effect absorbs through) — each on an opaque
/// pedestal, in an opaque room of a floor, a back wall and a side wall (open towards the camera).
fn glass() -> Result<Scene, OitError> {
    let mut b = Build::new("glass");
    let floor = b.mesh(cuboid("floor", Vec3::new(1.8, 0.05, 1.2)));
    let floor = b.solid("floor", floor, rgb(150, 136, 118));
    b.place(floor, Mat4::from_translation(Vec3::new(0.0, -0.05, 0.0)));
    let wall = b.mesh(cuboid("back wall", Vec3::new(1.8, 1.2, 0.05)));
    let wall = b.solid("back wall", wall, rgb(200, 196, 186));
    b.place(wall, Mat4::from_translation(Vec3::new(0.0, 1.2, -1.25)));
    let side = b.mesh(cuboid("side wall", Vec3::new(0.05, 1.2, 1.2)));
    let side = b.solid("side wall", side, rgb(176, 184, 190));
    b.place(side, Mat4::from_translation(Vec3::new(-1.85, 1.2, 0.0)));
    let skirting = b.mesh(cuboid("skirting", Vec3::new(1.8, 0.06, 0.02)));
    let skirting = b.solid("skirting", skirting, rgb(90, 80, 70));
    b.place(skirting, Mat4::from_translation(Vec3::new(0.0, 0.06, -1.18)));
    let pedestal = b.mesh(prism("pedestal", &circle(0.36, 32), 0.0, 0.45, true));
    let pedestal = b.solid("pedestal", pedestal, rgb(226, 222, 214));
    let plinth = b.mesh(cuboid("plinth", Vec3::new(0.44, 0.05, 0.44)));
    let plinth = b.solid("plinth", plinth, rgb(120, 116, 110));
    for (name, at, height, color) in [
        ("bunny", Vec3::new(-0.8, 0.0, -0.05), 1.25, rgb(140, 190, 255)),
        ("armadillo", Vec3::new(0.85, 0.0, -0.35), 1.6, rgb(255, 180, 100)),
    ] {
        b.place(plinth, Mat4::from_translation(at + Vec3::Y * 0.05));
        b.place(pedestal, Mat4::from_translation(at + Vec3::Y * 0.1));
        let source = crate::assets::BuiltinMesh::find(name).expect("a built-in mesh").scene()?;
        let mut mesh = source.meshes.into_iter().next().expect("one mesh");
        mesh.name = name.to_string();
        let bounds = mesh.bounds();
        let size = bounds.max - bounds.min;
        let scale = height / size.y;
        // standing on the pedestal's top, centred on it
        let foot =
            Vec3::new((bounds.min.x + bounds.max.x) / 2.0, bounds.min.y, (bounds.min.z + bounds.max.z) / 2.0);
        let m = b.mesh(mesh);
        let o = b.object(Object {
            transmission: 0.5,
            thickness: size.y / 5.0,
            absorption: GLASS_ABSORPTION,
            ..Object::new(name, m, color.extend(0.5))
        });
        b.place(
            o,
            Mat4::from_translation(at + Vec3::Y * 0.55)
                * Mat4::from_scale(Vec3::splat(scale))
                * Mat4::from_translation(-foot),
        );
    }
    // the effect has one medium per scene, the mean of the objects' absorptions: the room takes
    // the glass's, as the glTF loader gives it to the objects without a volume
    for o in &mut b.scene.objects {
        o.absorption = GLASS_ABSORPTION;
    }
    b.done()
}

/// `cad`: a gearbox — a base plate with bolts, two bearing blocks, two parallel shafts carrying
/// two pairs of spur gears in mesh, a motor on its mount — inside three nested transparent
/// housings: a tinted box around the gears (alpha 0.35), a cylinder around the box and the
/// shafts' middle (alpha 0.25), and a clear case over everything (alpha 0.15).
fn cad() -> Result<Scene, OitError> {
    let mut b = Build::new("cad");
    // turned a further 35° so the camera sees the gears' faces, not their rims
    b.turn = front() * Mat4::from_rotation_y(-35f32.to_radians());
    // the shafts run along x, at this height, a gear pair's radii apart in z
    let to_x = Quat::from_rotation_z(-PI / 2.0);
    let axis_y = 1.2;
    let (big_r, small_r) = (0.42, 0.24);
    let shaft_a = Vec3::new(0.0, axis_y, -(big_r + small_r) / 2.0);
    let shaft_b = Vec3::new(0.0, axis_y, (big_r + small_r) / 2.0);
    let plate = b.mesh(cuboid("base plate", Vec3::new(1.85, 0.06, 0.8)));
    let plate = b.solid("base plate", plate, rgb(70, 74, 82));
    b.place(plate, Mat4::from_translation(Vec3::new(-0.2, 0.06, 0.0)));
    let bolt = b.mesh(prism("bolt", &circle(0.045, 6), 0.0, 0.05, false));
    let bolt = b.solid("bolt", bolt, rgb(190, 190, 196));
    for x in [-1.9, -0.6, 0.6, 1.5] {
        for z in [-0.68, 0.68] {
            b.place(bolt, Mat4::from_translation(Vec3::new(x, 0.12, z)));
        }
    }
    let block_half_y = (axis_y + 0.15 - 0.12) / 2.0;
    let block = b.mesh(cuboid("bearing block", Vec3::new(0.1, block_half_y, 0.55)));
    let block = b.solid("bearing block", block, rgb(150, 40, 36));
    for x in [-1.15, 1.15] {
        b.place(block, Mat4::from_translation(Vec3::new(x, 0.12 + block_half_y, 0.0)));
    }
    let shaft = b.mesh(cylinder("shaft", 0.05, -1.4, 1.4, 20));
    let shaft = b.solid("shaft", shaft, rgb(180, 182, 188));
    for at in [shaft_a, shaft_b] {
        b.place(shaft, Mat4::from_rotation_translation(to_x, at));
    }
    let big = b.mesh(prism("large gear", &gear_outline(28, big_r - 0.03, big_r + 0.03), -0.08, 0.08, false));
    let big = b.solid("large gear", big, rgb(200, 160, 60));
    let small =
        b.mesh(prism("small gear", &gear_outline(16, small_r - 0.03, small_r + 0.03), -0.08, 0.08, false));
    let small = b.solid("small gear", small, rgb(60, 140, 190));
    let hub = b.mesh(cylinder("hub", 0.09, -0.12, 0.12, 20));
    let hub = b.solid("hub", hub, rgb(120, 122, 128));
    // the first pair: large on shaft a, small on b; the second the other way round; each small
    // gear turned half a tooth so the teeth interleave
    for (x, on_a, on_b) in [(-0.3, big, small), (0.45, small, big)] {
        for (object, at) in [(on_a, shaft_a), (on_b, shaft_b)] {
            let half_tooth = if object == small { PI / 16.0 } else { 0.0 };
            let at = at + Vec3::X * x;
            b.place(object, Mat4::from_rotation_translation(to_x * Quat::from_rotation_y(half_tooth), at));
            b.place(hub, Mat4::from_rotation_translation(to_x, at));
        }
    }
    let motor = b.mesh(cylinder("motor", 0.26, -0.3, 0.3, 32));
    let motor = b.solid("motor", motor, rgb(40, 90, 60));
    b.place(motor, Mat4::from_rotation_translation(to_x, shaft_a + Vec3::X * -1.62));
    let cap = b.mesh(cylinder("motor cap", 0.2, -0.04, 0.04, 32));
    let cap = b.solid("motor cap", cap, rgb(160, 164, 170));
    b.place(cap, Mat4::from_rotation_translation(to_x, shaft_a + Vec3::X * -1.96));
    let mount_half_y = (axis_y - 0.2 - 0.12) / 2.0;
    let mount = b.mesh(cuboid("motor mount", Vec3::new(0.2, mount_half_y, 0.16)));
    let mount = b.solid("motor mount", mount, rgb(90, 94, 100));
    b.place(mount, Mat4::from_translation(Vec3::new(-1.62, 0.12 + mount_half_y, shaft_a.z)));
    // the housings, innermost first, each inside the next
    let cover = b.mesh(cuboid("gear cover", Vec3::new(0.58, 0.55, 0.8)));
    let cover = b.object(Object::new("gear cover", cover, rgb(120, 180, 255).extend(0.35)));
    b.place(cover, Mat4::from_translation(Vec3::new(0.075, axis_y, 0.0)));
    let tube = b.mesh(cylinder("shaft tube", 1.0, -0.95, 0.95, 48));
    let tube = b.object(Object::new("shaft tube", tube, rgb(140, 230, 160).extend(0.25)));
    b.place(tube, Mat4::from_rotation_translation(to_x, Vec3::new(0.0, axis_y, 0.0)));
    let case = b.mesh(cuboid("outer case", Vec3::new(1.98, 1.19, 1.12)));
    let case = b.object(Object::new("outer case", case, rgb(220, 224, 232).extend(0.15)));
    b.place(case, Mat4::from_translation(Vec3::new(-0.2, 1.17, 0.0)));
    b.done()
}
