//! Scenes: meshes, the objects made of them (a material: colour, alpha mode, transmission,
//! absorption) and their instances.
//!
//! A [`Scene`] is plain data. Every backend walks it in the same order — instance by instance,
//! triangle by triangle — and numbers triangles along the way: the *primitive id* of triangle `t`
//! of instance `i` is `scene.primitive_base(i) + t`. Ties between fragments of equal depth are broken
//! by that id wherever a technique can.
//!
//! Opaque first: a frame draws the scene's opaque and alpha-masked objects into a depth buffer
//! and a colour image before any technique runs, as every renderer that uses OIT does, and each
//! technique then captures only the transparent fragments strictly in front of that depth and
//! composites them over that colour. Both backends split the scene the same way
//! ([`Scene::layers`]): the opaque part and the transparent part are scenes of their own, each
//! numbering its triangles as above, so the reference and every technique order the same
//! transparent fragments by the same ids.

use glam::{DVec3, Mat4, Vec2, Vec3, Vec4};

use crate::{OitError, Texture};

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The smallest corner.
    pub min: Vec3,
    /// The largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (grows to whatever is added).
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// Grows the box to hold `p`.
    pub fn include(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Grows the box to hold `other`.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// True when nothing was added.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// The centre.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The centre, in f64 (no overflow for boxes near f32's range).
    pub fn center_f64(&self) -> DVec3 {
        (self.min.as_dvec3() + self.max.as_dvec3()) * 0.5
    }

    /// Radius of the bounding sphere around the centre.
    pub fn radius(&self) -> f32 {
        self.radius_f64() as f32
    }

    /// Radius of the bounding sphere around the centre, in f64: the squared diagonal of a box at
    /// 10²⁰ (10⁴⁰) overflows f32, and of a box at 10⁻²⁰ underflows to 0.
    pub fn radius_f64(&self) -> f64 {
        (self.max.as_dvec3() - self.min.as_dvec3()).length() * 0.5
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// The box transformed by `m` (the bounds of its transformed corners).
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        let mut out = Aabb::EMPTY;
        for c in self.corners() {
            out.include(m.transform_point3(c));
        }
        out
    }

    /// The 12 triangles of the box's surface, as indices into [`Aabb::corners`].
    pub const TRIANGLES: [[u32; 3]; 12] = [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
}

/// A triangle mesh: positions, normals (one per position), optional per-vertex colours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// A name, for messages.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals, one per position (unit length, or zero where undefined).
    pub normals: Vec<Vec3>,
    /// Linear RGB per vertex, where the source had them.
    pub colors: Option<Vec<Vec3>>,
    /// Texture coordinates per vertex (glTF's `TEXCOORD_0`: u across, v down the image), for
    /// the textured objects that draw the mesh; `None` on a mesh no textured object draws.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles, as indices into `positions`.
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    /// The largest coordinate magnitude a vertex may have: 10³⁰, about as far above 1 as
    /// [`crate::Camera::MIN_RADIUS`] (10⁻³¹) is below it (the camera fits both ends alike), and
    /// far below where a camera framing the scene overflows f32 ([`crate::Camera::MAX_RADIUS`],
    /// 10³⁶).
    pub const MAX_COORDINATE: f32 = 1e30;

    /// A mesh from positions and triangles, with area-weighted vertex normals computed.
    pub fn new(name: impl Into<String>, positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Mesh {
        let mut mesh =
            Mesh { name: name.into(), positions, normals: Vec::new(), colors: None, uvs: None, indices };
        mesh.compute_normals();
        mesh
    }

    /// Replaces the normals by area-weighted averages of the adjacent faces' normals. Computed in
    /// f64, where the cross products of f32 coordinates neither underflow (a mesh at 10⁻²⁰ has
    /// face areas of 10⁻⁴⁰) nor overflow (at 10²⁰, 10⁴⁰): the normals are the same at every scale.
    pub fn compute_normals(&mut self) {
        let mut normals = vec![DVec3::ZERO; self.positions.len()];
        for tri in &self.indices {
            let [a, b, c] =
                tri.map(|i| self.positions.get(i as usize).copied().unwrap_or(Vec3::ZERO).as_dvec3());
            let n = (b - a).cross(c - a);
            if n.is_finite() {
                for &i in tri {
                    if let Some(slot) = normals.get_mut(i as usize) {
                        *slot += n;
                    }
                }
            }
        }
        self.normals = normals.into_iter().map(|n| n.normalize_or_zero().as_vec3()).collect();
    }

    /// The bounds of the positions.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in &self.positions {
            b.include(p);
        }
        b
    }

    /// Checks that every number is finite, every coordinate within ±[`Mesh::MAX_COORDINATE`] and
    /// every index in range.
    pub fn validate(&self) -> Result<(), OitError> {
        self.validated_bounds().map(drop)
    }

    /// [`Mesh::validate`], returning the mesh's bounds ([`Mesh::bounds`]) when it passes: the
    /// positions are read once for both (a one-shot frame validates its scene, and on a many-core
    /// host a small frame's serial scans over the vertices were a tenth of it).
    pub fn validated_bounds(&self) -> Result<Aabb, OitError> {
        // one pass: every coordinate within the limit (NaN fails every comparison) and the box;
        // the passes below find the first bad vertex only when one is there
        let limit = Mesh::MAX_COORDINATE;
        let (in_range, bounds) = self.positions.iter().fold((true, Aabb::EMPTY), |(ok, mut b), &p| {
            b.include(p);
            (ok & (p.x.abs() <= limit) & (p.y.abs() <= limit) & (p.z.abs() <= limit), b)
        });
        if !in_range {
            self.positions_error()?;
        }
        self.attributes_error()?;
        Ok(bounds)
    }

    /// The error for the first vertex with a non-finite or out-of-range coordinate, if any.
    fn positions_error(&self) -> Result<(), OitError> {
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(OitError::InvalidScene(format!(
                "mesh '{}': vertex {} has a NaN or infinite coordinate ({:?})",
                self.name,
                i + 1,
                self.positions[i]
            )));
        }
        if let Some(i) = self.positions.iter().position(|p| p.abs().max_element() > Mesh::MAX_COORDINATE) {
            return Err(OitError::InvalidScene(format!(
                "mesh '{}': vertex {} is out of range ({:?}): coordinates must lie within ±{:e}; scale the model down",
                self.name,
                i + 1,
                self.positions[i],
                Mesh::MAX_COORDINATE
            )));
        }
        Ok(())
    }

    /// The error for normals, colours or indices that do not fit the positions, if any.
    fn attributes_error(&self) -> Result<(), OitError> {
        if self.normals.len() != self.positions.len() {
            return Err(OitError::InvalidScene(format!(
                "mesh '{}': {} normals for {} positions",
                self.name,
                self.normals.len(),
                self.positions.len()
            )));
        }
        if let Some(c) = &self.colors
            && (c.len() != self.positions.len() || c.iter().any(|c| !c.is_finite()))
        {
            return Err(OitError::InvalidScene(format!(
                "mesh '{}': vertex colours must be finite, one per position",
                self.name
            )));
        }
        if let Some(uvs) = &self.uvs {
            if uvs.len() != self.positions.len() {
                return Err(OitError::InvalidScene(format!(
                    "mesh '{}': {} texture coordinates for {} positions",
                    self.name,
                    uvs.len(),
                    self.positions.len()
                )));
            }
            if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
                return Err(OitError::InvalidScene(format!(
                    "mesh '{}': vertex {} has a NaN or infinite texture coordinate ({:?})",
                    self.name,
                    i + 1,
                    uvs[i]
                )));
            }
        }
        let n = self.positions.len() as u32;
        // the largest index first (a loop the compiler vectorizes), the first bad triangle only
        // when there is one
        let largest = self.indices.iter().fold(0u32, |m, t| m.max(t[0]).max(t[1]).max(t[2]));
        if self.indices.is_empty() || largest < n {
            return Ok(());
        }
        if let Some(t) = self.indices.iter().position(|t| t.iter().any(|&i| i >= n)) {
            return Err(OitError::InvalidScene(format!(
                "mesh '{}': triangle {} indexes past the {} vertices",
                self.name,
                t + 1,
                n
            )));
        }
        Ok(())
    }
}

/// How an object's alpha is read (glTF's `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Drawn in the opaque pass, alpha ignored (taken as 1).
    Opaque,
    /// Drawn in the opaque pass where alpha ≥ `cutoff`, discarded (and counted,
    /// [`crate::Stats::masked`]) below it.
    Mask {
        /// In [0, 1].
        cutoff: f32,
    },
    /// Transparent: captured by the technique, composited by alpha. What every object was before
    /// materials, and the default.
    #[default]
    Blend,
}

/// A mesh with a material: a base colour (straight-alpha linear RGBA), how its alpha is read, an
/// optional transmission (glTF's
/// `KHR_materials_transmission`) and an absorption coefficient (per unit of view-space distance,
/// used by the translucency effect).
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// A name, for messages.
    pub name: String,
    /// Index into [`Scene::meshes`].
    pub mesh: usize,
    /// Linear RGB and straight alpha: the base colour factor, times the vertex colours where the
    /// mesh has them.
    pub color: Vec4,
    /// Beer–Lambert absorption coefficient, read by the translucency effect: per 1/8 of the
    /// scene's bounding radius, the medium this object bounds absorbs `(1 − c)·absorption` per
    /// channel, `c` the entering layer's colour. The effect has one medium per scene, the mean of
    /// its objects' values ([`Scene::absorption_per_length`]). 1 unless set; the glTF loader maps
    /// `KHR_materials_volume` onto it ([`crate::load_gltf`]).
    pub absorption: f32,
    /// How alpha is read: opaque, masked or blended ([`AlphaMode::Blend`] unless set).
    pub alpha_mode: AlphaMode,
    /// The share of light a blended surface lets through, in [0, 1] (glTF's
    /// `KHR_materials_transmission`): the fragment's alpha is the colour's alpha × (1 −
    /// transmission) ([`Object::effective_alpha`]). 0 unless set.
    pub transmission: f32,
    /// The thickness of the volume beneath the surface, in the mesh's units (glTF's
    /// `KHR_materials_volume` `thicknessFactor`): 0 is a thin-walled surface, above 0 the object
    /// bounds a volume whose medium is [`Object::absorption`]. The translucency effect measures
    /// the thickness it absorbs through between paired layers, so only whether this is above 0
    /// is read: the glTF writer writes a volume for such an object. 0 unless set.
    pub thickness: f32,
    /// Whether both sides of its triangles are drawn (glTF's `doubleSided`). A single-sided
    /// object's back-facing triangles — clockwise on screen, where glTF's front is
    /// counter-clockwise, or counter-clockwise under an instance transform that mirrors
    /// (negative determinant) — produce no fragment, on every backend and raster path
    /// ([`crate::setup::back_face_sign`]). True unless set: every built-in and OBJ scene is drawn
    /// from both sides.
    pub double_sided: bool,
    /// The base-colour texture, an index into [`Scene::textures`]: a fragment's colour and alpha
    /// are `color` times the texture's sample at the fragment's texture coordinates (the mesh
    /// must have them). `None` unless set.
    pub texture: Option<usize>,
}

impl Object {
    /// A blended object of `mesh` in `color`, absorption 1, no transmission: what
    /// every object was before materials.
    pub fn new(name: impl Into<String>, mesh: usize, color: Vec4) -> Object {
        Object {
            name: name.into(),
            mesh,
            color,
            absorption: 1.0,
            alpha_mode: AlphaMode::Blend,
            transmission: 0.0,
            thickness: 0.0,
            double_sided: true,
            texture: None,
        }
    }

    /// The same object, opaque.
    pub fn opaque(self) -> Object {
        Object { alpha_mode: AlphaMode::Opaque, ..self }
    }

    /// The same object, single-sided ([`Object::double_sided`] false).
    pub fn single_sided(self) -> Object {
        Object { double_sided: false, ..self }
    }

    /// Whether the opaque pass draws it (opaque or masked).
    pub fn is_opaque_pass(&self) -> bool {
        !matches!(self.alpha_mode, AlphaMode::Blend)
    }

    /// The same object, textured by texture `texture` of [`Scene::textures`].
    pub fn textured(self, texture: usize) -> Object {
        Object { texture: Some(texture), ..self }
    }

    /// The alpha a fragment of this object carries, before its texture: under
    /// [`AlphaMode::Blend`] the colour's alpha × (1 − transmission); under [`AlphaMode::Opaque`]
    /// 1; under [`AlphaMode::Mask`] 1 where the colour's alpha reaches the cutoff and 0
    /// (discarded) below it. Without a texture the colour's alpha is the object's own (vertex
    /// colours are RGB), so a mask keeps or discards a whole object; with one, a fragment's alpha
    /// is this times the texture's, and a masked textured object is decided fragment by fragment
    /// instead ([`Scene::layers`] keeps its colour's alpha for that).
    pub fn effective_alpha(&self) -> f32 {
        match self.alpha_mode {
            AlphaMode::Opaque => 1.0,
            AlphaMode::Mask { cutoff } => {
                if self.color.w >= cutoff {
                    1.0
                } else {
                    0.0
                }
            }
            AlphaMode::Blend => self.color.w * (1.0 - self.transmission),
        }
    }
}

/// A prepared scene's [`Layers`], made the first time a frame asks for them and kept while
/// frames ask with the same alpha override (every backend's prepared scene holds one).
#[derive(Debug, Default)]
pub struct LayersCache<'a> {
    kept: std::sync::Mutex<Option<(Option<u32>, std::sync::Arc<Layers<'a>>)>>,
}

impl<'a> LayersCache<'a> {
    /// `scene`'s layers under the alpha override `alpha` (`Settings::alpha`).
    pub fn get(&self, scene: &'a Scene, alpha: Option<f32>) -> std::sync::Arc<Layers<'a>> {
        let key = alpha.map(f32::to_bits);
        let mut kept = self.kept.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        match &*kept {
            Some((k, layers)) if *k == key => layers.clone(),
            _ => {
                let layers = std::sync::Arc::new(scene.layers(alpha));
                *kept = Some((key, layers.clone()));
                layers
            }
        }
    }
}

/// A scene split for a frame ([`Scene::layers`]).
#[derive(Clone, Debug)]
pub struct Layers<'a> {
    /// The opaque and masked instances, alpha 1 (kept) or 0 (masked away); `None` where there
    /// are none.
    pub opaque: Option<Scene>,
    /// The blended instances, each object's colour carrying its fragments' alpha.
    pub transparent: std::borrow::Cow<'a, Scene>,
    /// Whether `--alpha`'s override is in the colours already (the layers are then drawn
    /// without it: [`Layers::settings`]).
    pub baked: bool,
}

impl Layers<'_> {
    /// The settings the layers are drawn under: `settings` without the alpha override where the
    /// layers carry it already.
    pub fn settings(&self, settings: &crate::Settings) -> crate::Settings {
        if self.baked { crate::Settings { alpha: None, ..settings.clone() } } else { settings.clone() }
    }
}

/// One placement of an object.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`Scene::objects`].
    pub object: usize,
    /// Object to world.
    pub transform: Mat4,
}

/// Meshes, objects and their instances.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// A name, for reports.
    pub name: String,
    /// The meshes.
    pub meshes: Vec<Mesh>,
    /// The objects (a mesh and its material).
    pub objects: Vec<Object>,
    /// The instances, drawn in this order.
    pub instances: Vec<Instance>,
    /// The textures objects name ([`Object::texture`]).
    pub textures: Vec<Texture>,
    /// What loading left out (an OBJ file's line and point elements, ...), one message each, for
    /// the front end to print.
    pub warnings: Vec<String>,
}

impl Scene {
    /// The most triangles a scene may draw (over all instances): 50 million, about 1.8 GB of
    /// vertex data at the 36 bytes a triangle's positions take, and far more than any model oit
    /// ships with (the bunny has 70 thousand).
    pub const MAX_TRIANGLES: u64 = 50_000_000;

    /// The most instances a scene may place: a million, about 170 MB of objects and transforms
    /// (`grid:RxC:MESH` copies every instance of MESH R×C times, so nesting multiplies them).
    pub const MAX_INSTANCES: u64 = 1_000_000;

    /// Refuses a scene called `name` of `triangles` triangles in `instances` instances when
    /// either is over its limit ([`Scene::MAX_TRIANGLES`], [`Scene::MAX_INSTANCES`]), so a
    /// scene expression can be checked before it is built.
    pub fn check_size(name: &str, triangles: u64, instances: u64) -> Result<(), OitError> {
        if triangles > Scene::MAX_TRIANGLES {
            return Err(OitError::InvalidScene(format!(
                "scene '{name}' has {triangles} triangles, over the limit of {}: use fewer copies or a smaller mesh",
                Scene::MAX_TRIANGLES
            )));
        }
        if instances > Scene::MAX_INSTANCES {
            return Err(OitError::InvalidScene(format!(
                "scene '{name}' has {instances} instances, over the limit of {}: use fewer copies",
                Scene::MAX_INSTANCES
            )));
        }
        Ok(())
    }

    /// A scene with one instance (identity transform) of each mesh, coloured `color`.
    pub fn from_meshes(name: impl Into<String>, meshes: Vec<Mesh>, color: Vec4) -> Scene {
        let objects: Vec<Object> =
            meshes.iter().enumerate().map(|(i, m)| Object::new(m.name.clone(), i, color)).collect();
        let instances =
            (0..objects.len()).map(|object| Instance { object, transform: Mat4::IDENTITY }).collect();
        Scene { name: name.into(), meshes, objects, instances, ..Scene::default() }
    }

    /// The mesh and object an instance draws.
    pub fn instance_parts(&self, instance: &Instance) -> (&Object, &Mesh) {
        let object = &self.objects[instance.object];
        (object, &self.meshes[object.mesh])
    }

    /// The primitive id of the first triangle of each instance, and the total.
    pub fn primitive_bases(&self) -> (Vec<u32>, u32) {
        let mut bases = Vec::with_capacity(self.instances.len());
        let mut total = 0u32;
        for inst in &self.instances {
            bases.push(total);
            total = total.saturating_add(self.instance_parts(inst).1.indices.len() as u32);
        }
        (bases, total)
    }

    /// Total triangles over all instances.
    pub fn triangle_count(&self) -> u64 {
        self.instances.iter().map(|i| self.instance_parts(i).1.indices.len() as u64).sum()
    }

    /// World-space bounds of one instance.
    pub fn instance_bounds(&self, instance: &Instance) -> Aabb {
        self.instance_parts(instance).1.bounds().transformed(&instance.transform)
    }

    /// World-space bounds of everything: each instance's mesh box, transformed (the same boxes
    /// as [`Scene::instance_bounds`]). Each mesh's box is computed once, however many instances
    /// share it: every frame of a GPU backend asks (translucency's absorption), and a grid of
    /// 144 bunnies walked 5 million vertices for it.
    pub fn bounds(&self) -> Aabb {
        self.bounds_of(&self.mesh_bounds())
    }

    /// The world bounds of the instances, given each mesh's own bounds.
    fn bounds_of(&self, mesh_bounds: &[Aabb]) -> Aabb {
        self.instances.iter().fold(Aabb::EMPTY, |b, inst| {
            let local = mesh_bounds[self.objects[inst.object].mesh];
            b.union(&local.transformed(&inst.transform))
        })
    }

    /// Each mesh's own bounds ([`Mesh::bounds`]), in the order of [`Scene::meshes`]: one walk
    /// over each mesh's vertices, for whatever needs every instance's box.
    pub fn mesh_bounds(&self) -> Vec<Aabb> {
        self.meshes.iter().map(Mesh::bounds).collect()
    }

    /// Translucency's absorption per unit of view-space distance: the objects' mean absorption
    /// σ (1 without objects) per 1/8 of the scene's bounding radius, so a scene of any scale
    /// absorbs alike. One value for the whole scene: the effect does not tell objects apart.
    pub fn absorption_per_length(&self) -> f64 {
        self.absorption_per_length_in(&self.bounds())
    }

    /// What a frame under `effect` reads of [`Scene::absorption_per_length`]: the value under
    /// translucency, 0 under the effects that do not read it (so a GPU frame's uniforms skip the
    /// walk over every vertex that the value costs).
    pub fn absorption_for(&self, effect: crate::Effect) -> f64 {
        if effect == crate::Effect::Translucency { self.absorption_per_length() } else { 0.0 }
    }

    /// [`Scene::absorption_per_length`] for the scene's bounds already at hand (those
    /// [`Scene::validated_bounds`] returns), without another walk over the vertices.
    pub fn absorption_per_length_in(&self, bounds: &Aabb) -> f64 {
        let sigma = if self.objects.is_empty() {
            1.0
        } else {
            self.objects.iter().map(|o| f64::from(o.absorption)).sum::<f64>() / self.objects.len() as f64
        };
        sigma / (f64::from(bounds.radius()).max(1e-6) / 8.0)
    }

    /// Whether the scene has anything for the opaque pass or any material that changes a
    /// fragment's alpha (transmission): where not, [`Scene::layers`] is the scene itself.
    pub fn has_materials(&self) -> bool {
        self.objects.iter().any(|o| o.is_opaque_pass() || o.transmission != 0.0)
    }

    /// Whether any instance draws an opaque or masked object: a frame then runs the opaque pass.
    pub fn has_opaque(&self) -> bool {
        self.instances.iter().any(|i| self.objects.get(i.object).is_some_and(Object::is_opaque_pass))
    }

    /// The scene as a frame draws it: its opaque part (the instances of opaque and masked
    /// objects, drawn first into a depth buffer and a colour image) and its transparent part
    /// (the blended ones, which the technique captures), each a scene of its own, its meshes the
    /// ones its instances draw, its triangles numbered from 0 in instance order. Each object's
    /// colour carries the alpha a fragment gets ([`Object::effective_alpha`], after `alpha`,
    /// `--alpha`'s override of the blended objects' alpha): the layers are drawn without the
    /// override. A scene without materials ([`Scene::has_materials`]) is its own transparent
    /// part, borrowed, with no opaque part; the override then stays the frame's to apply.
    pub fn layers(&self, alpha: Option<f32>) -> Layers<'_> {
        if !self.has_materials() {
            return Layers { opaque: None, transparent: std::borrow::Cow::Borrowed(self), baked: false };
        }
        let part = |opaque: bool, suffix: &str| {
            let mut out = Scene { name: format!("{}{suffix}", self.name), ..Scene::default() };
            let mut mesh_of = vec![usize::MAX; self.meshes.len()];
            let mut object_of = vec![usize::MAX; self.objects.len()];
            for inst in &self.instances {
                let Some(o) = self.objects.get(inst.object) else { continue };
                if o.is_opaque_pass() != opaque {
                    continue;
                }
                if object_of[inst.object] == usize::MAX {
                    let Some(m) = self.meshes.get(o.mesh) else { continue };
                    if mesh_of[o.mesh] == usize::MAX {
                        mesh_of[o.mesh] = out.meshes.len();
                        out.meshes.push(m.clone());
                    }
                    let mut o = o.clone();
                    if let (Some(a), AlphaMode::Blend) = (alpha, o.alpha_mode) {
                        o.color.w = a;
                    }
                    // a masked textured object keeps its factor's alpha: its fragments are kept
                    // or discarded one by one, by the factor times the texture's alpha against
                    // the cutoff (which the object keeps, with its alpha mode)
                    if !(o.texture.is_some() && matches!(o.alpha_mode, AlphaMode::Mask { .. })) {
                        o.color.w = o.effective_alpha();
                    }
                    o.transmission = 0.0;
                    o.mesh = mesh_of[o.mesh];
                    object_of[inst.object] = out.objects.len();
                    out.objects.push(o);
                }
                out.instances.push(Instance { object: object_of[inst.object], transform: inst.transform });
            }
            // the textures keep their indices; a mesh whose textured objects are all in the other
            // part loses its texture coordinates here (they would be coordinates no object reads)
            if out.objects.iter().any(|o| o.texture.is_some()) {
                out.textures = self.textures.clone();
            }
            for (m, mesh) in out.meshes.iter_mut().enumerate() {
                if mesh.uvs.is_some() && !out.objects.iter().any(|o| o.mesh == m && o.texture.is_some()) {
                    mesh.uvs = None;
                }
            }
            out
        };
        let opaque = part(true, " (opaque)");
        Layers {
            opaque: (!opaque.instances.is_empty()).then_some(opaque),
            transparent: std::borrow::Cow::Owned(part(false, "")),
            baked: true,
        }
    }

    /// Checks the scene before any raster: finite data, valid references, something to draw.
    pub fn validate(&self) -> Result<(), OitError> {
        self.validated_bounds().map(drop)
    }

    /// [`Scene::validate`], returning the scene's world bounds ([`Scene::bounds`]) when it passes,
    /// from the same walk over each mesh's vertices.
    pub fn validated_bounds(&self) -> Result<Aabb, OitError> {
        let mesh_bounds = self.meshes.iter().map(Mesh::validated_bounds).collect::<Result<Vec<_>, _>>()?;
        for o in &self.objects {
            if o.mesh >= self.meshes.len() {
                return Err(OitError::InvalidScene(format!("object '{}' names a missing mesh", o.name)));
            }
            if !o.color.is_finite() || !o.absorption.is_finite() || o.absorption < 0.0 {
                return Err(OitError::InvalidScene(format!(
                    "object '{}': colour and absorption must be finite, absorption ≥ 0",
                    o.name
                )));
            }
            if let AlphaMode::Mask { cutoff } = o.alpha_mode
                && !(0.0..=1.0).contains(&cutoff)
            {
                return Err(OitError::InvalidScene(format!(
                    "object '{}': alpha cutoff {cutoff} is outside [0, 1]",
                    o.name
                )));
            }
            if !(0.0..=1.0).contains(&o.transmission) {
                return Err(OitError::InvalidScene(format!(
                    "object '{}': transmission {} is outside [0, 1]",
                    o.name, o.transmission
                )));
            }
            if !(o.thickness.is_finite() && o.thickness >= 0.0) {
                return Err(OitError::InvalidScene(format!(
                    "object '{}': thickness {} must be finite and ≥ 0",
                    o.name, o.thickness
                )));
            }
            if let Some(t) = o.texture {
                let Some(texture) = self.textures.get(t) else {
                    return Err(OitError::InvalidScene(format!(
                        "object '{}' names texture {t}, and the scene has {}",
                        o.name,
                        self.textures.len()
                    )));
                };
                let mesh = &self.meshes[o.mesh];
                if mesh.uvs.is_none() {
                    return Err(OitError::InvalidScene(format!(
                        "object '{}' has texture '{}' but its mesh '{}' has no texture coordinates",
                        o.name, texture.name, mesh.name
                    )));
                }
            }
        }
        for (m, mesh) in self.meshes.iter().enumerate() {
            if mesh.uvs.is_some() && !self.objects.iter().any(|o| o.mesh == m && o.texture.is_some()) {
                return Err(OitError::InvalidScene(format!(
                    "mesh '{}' has texture coordinates but no textured object draws it: give an object of it a texture, or drop them",
                    mesh.name
                )));
            }
        }
        for (i, inst) in self.instances.iter().enumerate() {
            if inst.object >= self.objects.len() {
                return Err(OitError::InvalidScene(format!("instance {i} names a missing object")));
            }
            if !inst.transform.is_finite() {
                return Err(OitError::InvalidScene(format!("instance {i} has a non-finite transform")));
            }
        }
        if self.triangle_count() == 0 {
            return Err(OitError::InvalidScene(format!("scene '{}' has no triangles", self.name)));
        }
        Scene::check_size(&self.name, self.triangle_count(), self.instances.len() as u64)?;
        let bounds = self.bounds_of(&mesh_bounds);
        let extent = bounds.min.abs().max(bounds.max.abs()).max_element();
        if extent.is_nan() || extent > Mesh::MAX_COORDINATE {
            return Err(OitError::InvalidScene(format!(
                "scene '{}' reaches {extent:e} from the origin once placed: world coordinates must lie within ±{:e}",
                self.name,
                Mesh::MAX_COORDINATE
            )));
        }
        Ok(bounds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_are_the_same_at_every_scale() {
        // f32 cross products of a mesh at 1e-20 (1e-40) are subnormal and at 1e20 (1e40) infinite
        let knot = crate::procedural::torus_knot(2, 3, 0.14, 48, 8);
        let mut unit = knot.clone();
        unit.compute_normals();
        for k in [1e-30f32, 1e-20, 1e20, 1e30] {
            let mut m = knot.clone();
            m.positions.iter_mut().for_each(|p| *p *= k);
            m.compute_normals();
            let worst = m
                .normals
                .iter()
                .zip(&unit.normals)
                .map(|(a, b)| (*a - *b).abs().max_element())
                .fold(0.0, f32::max);
            assert!(worst < 1e-6, "{k}: normals differ by {worst}");
            assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-6), "{k}");
        }
        // a power-of-two scale gives the same bits
        let mut m = knot.clone();
        m.positions.iter_mut().for_each(|p| *p *= 2f32.powi(-70));
        m.compute_normals();
        assert_eq!(m.normals, unit.normals);
    }

    #[test]
    fn bounds_hold_at_the_ends_of_f32() {
        let b = Aabb { min: Vec3::splat(-1e30), max: Vec3::splat(1e30) };
        assert!((f64::from(b.radius()) / (1e30 * 3f64.sqrt()) - 1.0).abs() < 1e-6, "{}", b.radius());
        let b = Aabb { min: Vec3::ZERO, max: Vec3::splat(1e-25) };
        assert!((f64::from(b.radius()) / (0.5e-25 * 3f64.sqrt()) - 1.0).abs() < 1e-6, "{}", b.radius());
    }
}
