//! The scene for a GPU's own rasterizer, by vertex pulling: what oit-wgpu's and oit-vulkan's
//! hardware-raster paths upload, defined once.
//!
//! Each mesh's vertices go up once in the mesh's own space, however many instances place it; per
//! triangle, its three vertex indices and its instance, in primitive order
//! ([`Scene::primitive_bases`]), so triangle `t` of the one draw is primitive `t`. Per frame only
//! the instances' data changes ([`instance_data`]): `view_proj · transform`, the normal matrix
//! ([`crate::setup::normal_matrix`]) and the material's base colour, with a small shading uniform
//! ([`raster_uniform`]). The vertex stage (oit-wgpu's `raster_hardware.wgsl`, shared by both
//! backends) pulls a vertex by vertex index and applies them in the same order of operations as
//! oit-cpu's setup.
//!
//! Layouts are plain words, as the WGSL structs declare them: a vertex is 12 floats
//! (`position.xyz`, 1 in `w` when the mesh has vertex colours; `normal`, the texture coordinate
//! u in `w`; `color`, v in `w`), an instance 32 (the column-major `mvp`, the normal matrix's three
//! columns padded to four, the first `w` the opaque pass's cutoff ([`instance_cutoff`]), the
//! second the back faces' sign ([`crate::setup::back_face_sign`]: the fragment stage drops a
//! fragment that is not `front_facing` where it is 1, one that is where it is −1), the base
//! colour).

use glam::{Mat3, Vec2, Vec3, Vec4};

use crate::{Aabb, AlphaMode, Camera, Object, OitError, Scene, Settings};

/// One vertex of a mesh in its own space (`HwVertex` in raster_hardware.wgsl).
pub type PulledVertex = [f32; 12];
/// One instance's data of one frame (`HwInstance` in raster_hardware.wgsl).
pub type PulledInstance = [f32; 32];

/// A scene's (or its instances' bounding boxes') geometry for vertex pulling.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PulledGeometry {
    /// Each mesh's vertices, once.
    pub vertices: Vec<PulledVertex>,
    /// Per triangle, in primitive order: its three vertices (indices into `vertices`) and its
    /// instance.
    pub triangles: Vec<[u32; 4]>,
    /// Instances (boxes, for [`PulledGeometry::boxes`]) the per-frame data covers.
    pub instances: usize,
    /// True for bounding boxes, whose corners are already in world space.
    pub boxes: bool,
}

fn too_many() -> OitError {
    OitError::Device("over 2^32 vertices in one draw".into())
}

impl PulledGeometry {
    /// The scene's meshes and triangles (`boxes`: its instances' bounding boxes instead).
    pub fn new(scene: &Scene, boxes: bool) -> Result<PulledGeometry, OitError> {
        if boxes {
            let bounds: Vec<Aabb> = scene.instances.iter().map(|inst| scene.instance_bounds(inst)).collect();
            return PulledGeometry::boxes(&bounds);
        }
        let mut vertices: Vec<PulledVertex> = Vec::new();
        let mut triangles: Vec<[u32; 4]> = Vec::new();
        // each mesh an instance places, once
        let mut firsts: Vec<Option<u32>> = vec![None; scene.meshes.len()];
        for (i, inst) in scene.instances.iter().enumerate() {
            let (object, mesh) = scene.instance_parts(inst);
            let first = match firsts[object.mesh] {
                Some(first) => first,
                None => {
                    let first = u32::try_from(vertices.len()).map_err(|_| too_many())?;
                    let has_color = if mesh.colors.is_some() { 1.0 } else { 0.0 };
                    for (v, p) in mesh.positions.iter().enumerate() {
                        let n = mesh.normals.get(v).copied().unwrap_or(Vec3::ZERO);
                        let c = mesh.colors.as_ref().and_then(|c| c.get(v).copied()).unwrap_or(Vec3::ZERO);
                        let uv = mesh.uvs.as_ref().and_then(|t| t.get(v).copied()).unwrap_or(Vec2::ZERO);
                        vertices.push(vertex(p.extend(has_color), n, c, uv));
                    }
                    firsts[object.mesh] = Some(first);
                    first
                }
            };
            let i = u32::try_from(i).map_err(|_| too_many())?;
            triangles.extend(mesh.indices.iter().map(|t| [first + t[0], first + t[1], first + t[2], i]));
        }
        PulledGeometry::checked(vertices, triangles, scene.instances.len(), false)
    }

    /// The 12 triangles of each of `bounds` (world-space boxes, one per instance:
    /// [`Aabb::TRIANGLES`] over its corners, normals out from its centre, as
    /// [`crate::setup::box_vertices`]); triangle `t` of box `i` is primitive `12·i + t`, as
    /// [`crate::setup::TriangleSetup::bounding_boxes`] orders them.
    pub fn boxes(bounds: &[Aabb]) -> Result<PulledGeometry, OitError> {
        let mut vertices: Vec<PulledVertex> = Vec::with_capacity(bounds.len() * 8);
        let mut triangles: Vec<[u32; 4]> = Vec::with_capacity(bounds.len() * 12);
        for (i, b) in bounds.iter().enumerate() {
            let first = u32::try_from(vertices.len()).map_err(|_| too_many())?;
            for c in b.corners() {
                vertices.push(vertex(
                    c.extend(0.0),
                    (c - b.center()).normalize_or_zero(),
                    Vec3::ZERO,
                    Vec2::ZERO,
                ));
            }
            let i = u32::try_from(i).map_err(|_| too_many())?;
            triangles.extend(Aabb::TRIANGLES.iter().map(|t| [first + t[0], first + t[1], first + t[2], i]));
        }
        PulledGeometry::checked(vertices, triangles, bounds.len(), true)
    }

    fn checked(
        vertices: Vec<PulledVertex>,
        triangles: Vec<[u32; 4]>,
        instances: usize,
        boxes: bool,
    ) -> Result<PulledGeometry, OitError> {
        u32::try_from(vertices.len()).map_err(|_| too_many())?;
        u32::try_from(triangles.len() * 3).map_err(|_| too_many())?;
        Ok(PulledGeometry { vertices, triangles, instances, boxes })
    }

    /// The vertices of the one draw: three per triangle (fits in a `u32`, checked when made).
    pub fn vertex_count(&self) -> u32 {
        (self.triangles.len() * 3) as u32
    }

    /// Bytes of the per-frame instance data (at least one instance's: a binding may not be
    /// empty).
    pub fn instance_bytes(&self) -> u64 {
        (self.instances.max(1) * size_of::<PulledInstance>()) as u64
    }
}

/// A frame's instance data: for the scene (`boxes` false), `view_proj · transform`, the normal
/// matrix and the material's base colour of each instance; for its instances' bounding boxes
/// (corners in world space), `view_proj` and the identity, with each box's object's colour.
pub fn instance_data(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    boxes: bool,
) -> Vec<PulledInstance> {
    let view_proj = camera.view_proj();
    scene
        .instances
        .iter()
        .map(|inst| {
            let (object, _) = scene.instance_parts(inst);
            let (mvp, nm) = if boxes {
                (view_proj, Mat3::IDENTITY)
            } else {
                (view_proj * inst.transform, crate::setup::normal_matrix(&inst.transform))
            };
            let cutoff = if boxes { 0.0 } else { instance_cutoff(object) };
            let cull = if boxes { 0 } else { crate::setup::back_face_sign(object, &inst.transform) };
            instance(mvp.to_cols_array(), nm, settings.material_color(object.color), cutoff, cull as f32)
        })
        .collect()
}

/// The opaque pass's cutoff of an object's fragments, as oit-core's setup gives its triangles
/// ([`crate::setup::Triangle::cutoff`]): a textured masked object's cutoff; one half for an
/// untextured masked object, whose alpha is 1 or 0 ([`Object::effective_alpha`]); 0 (nothing
/// discarded) for any other.
pub fn instance_cutoff(object: &Object) -> f32 {
    match object.alpha_mode {
        AlphaMode::Mask { cutoff } if object.texture.is_some() => cutoff,
        AlphaMode::Mask { .. } => 0.5,
        _ => 0.0,
    }
}

/// The instance data of `count` boxes made by [`PulledGeometry::boxes`] without their scene:
/// `view_proj` and the identity for each, base colour white (with the settings' alpha). The bounds
/// passes boxes serve read only their fragments' depths, so the colour makes no difference to a
/// frame.
pub fn boxes_data(count: usize, camera: &Camera, settings: &Settings) -> Vec<PulledInstance> {
    let one = instance(
        camera.view_proj().to_cols_array(),
        Mat3::IDENTITY,
        settings.material_color(Vec4::ONE),
        0.0,
        0.0,
    );
    vec![one; count]
}

fn vertex(position: Vec4, normal: Vec3, color: Vec3, uv: Vec2) -> PulledVertex {
    let mut v = [0.0; 12];
    v[..4].copy_from_slice(&position.to_array());
    v[4..7].copy_from_slice(&normal.to_array());
    v[7] = uv.x;
    v[8..11].copy_from_slice(&color.to_array());
    v[11] = uv.y;
    v
}

fn instance(mvp: [f32; 16], normal: Mat3, base: Vec4, cutoff: f32, cull: f32) -> PulledInstance {
    let mut d = [0.0; 32];
    d[..16].copy_from_slice(&mvp);
    for (k, c) in [normal.x_axis, normal.y_axis, normal.z_axis].iter().enumerate() {
        d[16 + 4 * k..19 + 4 * k].copy_from_slice(&c.to_array());
    }
    d[19] = cutoff;
    d[23] = cull;
    d[28..].copy_from_slice(&base.to_array());
    d
}

/// The vertex and fragment stages' uniform (`HwUniform`): the shading code, then the camera's
/// forward direction (for Fresnel shading) as float bits.
pub fn raster_uniform(camera: &Camera, settings: &Settings) -> [u32; 8] {
    let f = camera.forward;
    [settings.shading.code(), 0, 0, 0, f.x.to_bits(), f.y.to_bits(), f.z.to_bits(), 0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{View, load_scene};

    /// Triangle `t` of the draw is primitive `t`: the pulled triangles' vertices are the scene's
    /// own, in primitive order, each mesh uploaded once however many instances place it.
    #[test]
    fn triangles_are_in_primitive_order_and_meshes_uploaded_once() {
        let scene = load_scene("grid:2x2:knot").unwrap();
        let g = PulledGeometry::new(&scene, false).unwrap();
        let total: usize = scene.instances.iter().map(|i| scene.instance_parts(i).1.indices.len()).sum();
        assert_eq!(g.triangles.len(), total);
        assert_eq!(g.vertices.len(), scene.meshes.iter().map(|m| m.positions.len()).sum::<usize>());
        let (bases, _) = scene.primitive_bases();
        for (i, inst) in scene.instances.iter().enumerate() {
            let mesh = scene.instance_parts(inst).1;
            let base = bases[i] as usize;
            for (t, tri) in mesh.indices.iter().enumerate() {
                let pulled = g.triangles[base + t];
                assert_eq!(pulled[3], i as u32);
                for k in 0..3 {
                    let v = g.vertices[pulled[k] as usize];
                    assert_eq!(&v[..3], &mesh.positions[tri[k] as usize].to_array()[..]);
                }
            }
        }
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        let data = instance_data(&scene, &camera, &Settings::default(), false);
        assert_eq!(data.len(), scene.instances.len());
        let mvp = camera.view_proj() * scene.instances[1].transform;
        assert_eq!(&data[1][..16], &mvp.to_cols_array()[..]);
    }

    #[test]
    fn boxes_are_twelve_triangles_each() {
        let scene = load_scene("grid:2x1:knot").unwrap();
        let g = PulledGeometry::new(&scene, true).unwrap();
        assert_eq!((g.triangles.len(), g.vertices.len(), g.instances), (24, 16, 2));
        let t = Aabb::TRIANGLES[0];
        assert_eq!(g.triangles[12], [8 + t[0], 8 + t[1], 8 + t[2], 1]);
        assert_eq!(g.vertex_count(), 72);
    }
}
