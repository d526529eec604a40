//! What a GPU backend hands the compute path's setup kernel (oit-wgpu's `shaders/setup.wgsl`,
//! which oit-wgpu runs through wgpu and oit-vulkan compiles to SPIR-V): the scene's world-space
//! geometry as one array of words, uploaded once per prepared scene ([`SetupGeometry`]); per
//! frame, the instance table ([`SetupGeometry::instance_words`]) and the kernel's uniform
//! ([`SetupGeometry::uniform_words`]). The layouts are defined here once, beside the host's setup
//! ([`crate::setup`]) whose results the kernel reproduces bit for bit; the kernel's constants
//! (`INSTANCE_WORDS`, `VERT_WORDS`, the `I_*` offsets) mirror them.

use glam::{Mat3, Vec3, Vec4};

use crate::setup::{box_vertices, normal_matrix};
use crate::{Aabb, Camera, MAX_SIZE, OitError, Scene, Settings};

/// Words of the setup kernel's uniform (setup.wgsl's `SetupUniform`;
/// [`SetupGeometry::uniform_words`]).
pub const SETUP_UNIFORM_WORDS: usize = 16;

/// Words per instance in the instance table (setup.wgsl's `INSTANCE_WORDS`).
pub const INSTANCE_WORDS: usize = 40;
/// Words of one vertex-cache record (setup.wgsl's `VERT_WORDS`).
pub const VERT_WORDS: usize = 12;
/// Words of the setup's indirect arguments, as `setup_finish_main` writes them: the per-pixel
/// raster dispatch (4 words), the per-item one (4) and the item count (word 8, padded to 12).
pub const ARGS_WORDS: usize = 12;
/// Byte offset of the per-item raster dispatch in the arguments.
pub const ARGS_PER_ITEM: u64 = 16;
/// Byte offset of the item count in the arguments (copied into the raster uniform's word 0).
pub const ARGS_ITEMS: u64 = 32;
/// The most pieces a frame whose work items `setup_count_main` and `setup_items_main` count and
/// write, a workgroup a piece, rather
/// than the piece's own invocation in `setup_main` (setup.wgsl's `SPREAD_PIECES`): those with more
/// than [`SPREAD_ITEMS`] items, the first this many of them.
pub const SPREAD_PIECES: usize = 2048;
/// The most pieces one setup task can leave: a triangle clipped against the near and far planes
/// and the guard band's four sides gains at most a corner a plane (setup.wgsl's nine-corner
/// polygon), and its fan of nine corners is seven triangles.
pub const MAX_PIECES_PER_TASK: u32 = 7;
/// Tiles of its box above which a piece's work items are counted and written by a workgroup of
/// `setup_count_main` and `setup_items_main` (setup.wgsl's `SPREAD_ITEMS`).
pub const SPREAD_ITEMS: usize = 16;
/// Words of the setup's counters: pieces kept, work items, pieces spread, their tiles kept, then
/// two a spread piece: its slot, and the tiles it keeps.
pub const COUNTER_WORDS: usize = 4 + 2 * SPREAD_PIECES;

/// Where one instance's mesh lies in [`SetupGeometry::words`], and its primitive ids.
#[derive(Clone, Copy, Debug)]
struct InstanceGeometry {
    vertex_base: u32,
    vertex_count: u32,
    /// First colour word, `u32::MAX` without vertex colours.
    color_base: u32,
    index_base: u32,
    tri_count: u32,
    prim_base: u32,
    first_task: u32,
    /// Normals used as given (the boxes' are world-space already), not through a normal matrix.
    raw_normals: bool,
    /// The instance's object colour.
    color: Vec4,
}

/// A scene's world-space geometry for the setup kernel: all positions, then all normals, all
/// vertex colours and all indices in one array of words, each mesh once (the instances of a mesh
/// share it); or, for the bounds passes, each instance's box.
#[derive(Clone, Debug)]
pub struct SetupGeometry {
    /// The words to upload (the kernel's `geometry` binding); a backend may take them once they
    /// are on the device.
    pub words: Vec<u32>,
    instances: Vec<InstanceGeometry>,
    positions: u32,
    normals: u32,
    /// Setup tasks: one per (instance, triangle).
    pub tasks: u32,
    /// Whether these are the instances' bounding boxes.
    pub boxes: bool,
}

impl SetupGeometry {
    /// The scene's geometry, or its instances' boxes where `boxes`.
    pub fn new(scene: &Scene, boxes: bool) -> Result<SetupGeometry, OitError> {
        let (mut pos, mut nor, mut col, mut idx): (Vec<u32>, Vec<u32>, Vec<u32>, Vec<u32>) =
            Default::default();
        let mut instances = Vec::with_capacity(scene.instances.len());
        let mut colors_at = Vec::new();
        let mut tasks = 0u32;
        let word = |v: Vec3| v.to_array().map(f32::to_bits);
        if boxes {
            idx.extend(Aabb::TRIANGLES.iter().flatten());
            let mesh_bounds = scene.mesh_bounds();
            for (i, inst) in scene.instances.iter().enumerate() {
                let Some(object) = scene.objects.get(inst.object) else { continue };
                let Some(bounds) = mesh_bounds.get(object.mesh) else { continue };
                let (corners, normals) = box_vertices(bounds, &inst.transform);
                let vertex_base = (pos.len() / 3) as u32;
                corners.iter().for_each(|&c| pos.extend(word(c)));
                normals.iter().for_each(|&n| nor.extend(word(n)));
                instances.push(InstanceGeometry {
                    vertex_base,
                    vertex_count: 8,
                    color_base: u32::MAX,
                    index_base: 0,
                    tri_count: 12,
                    prim_base: u32::try_from(i).unwrap_or(u32::MAX).saturating_mul(12),
                    first_task: tasks,
                    raw_normals: true,
                    color: object.color,
                });
                colors_at.push(None);
                tasks = tasks.saturating_add(12);
            }
        } else {
            // each mesh once: (vertex base, colour offset in `col`, index base)
            let mut meshes: Vec<Option<(u32, Option<u32>, u32)>> = vec![None; scene.meshes.len()];
            let mut prim_base = 0u32;
            for inst in &scene.instances {
                let Some(object) = scene.objects.get(inst.object) else { continue };
                let Some(mesh) = scene.meshes.get(object.mesh) else { continue };
                let tri_count = u32::try_from(mesh.indices.len()).unwrap_or(u32::MAX);
                let (vertex_base, color_at, index_base) = *meshes[object.mesh].get_or_insert_with(|| {
                    let (vertex_base, index_base) = ((pos.len() / 3) as u32, idx.len() as u32);
                    mesh.positions.iter().for_each(|&p| pos.extend(word(p)));
                    // Scene::validate holds one normal per position; a short list reads as zero
                    for k in 0..mesh.positions.len() {
                        nor.extend(word(mesh.normals.get(k).copied().unwrap_or(Vec3::ZERO)));
                    }
                    idx.extend(mesh.indices.iter().flatten());
                    let color_at = mesh.colors.as_ref().map(|c| {
                        let at = col.len() as u32;
                        c.iter().for_each(|&c| col.extend(word(c)));
                        at
                    });
                    (vertex_base, color_at, index_base)
                });
                instances.push(InstanceGeometry {
                    vertex_base,
                    vertex_count: mesh.positions.len() as u32,
                    color_base: u32::MAX,
                    index_base,
                    tri_count,
                    prim_base,
                    first_task: tasks,
                    raw_normals: false,
                    color: object.color,
                });
                colors_at.push(color_at);
                prim_base = prim_base.saturating_add(tri_count);
                tasks = tasks.checked_add(tri_count).ok_or_else(|| {
                    OitError::InvalidScene("more than 2^32 triangles for the compute path's setup".into())
                })?;
            }
        }
        let positions = 0u32;
        let normals = pos.len() as u32;
        let colors = normals + nor.len() as u32;
        let indices = colors + col.len() as u32;
        for (g, at) in instances.iter_mut().zip(colors_at) {
            g.color_base = at.map_or(u32::MAX, |at| colors + at);
            g.index_base += indices;
        }
        let mut words = pos;
        words.extend(nor);
        words.extend(col);
        words.extend(idx);
        Ok(SetupGeometry { words, instances, positions, normals, tasks, boxes })
    }

    /// Instances in the table (the kernel's `instance_count`).
    pub fn instance_count(&self) -> usize {
        self.instances.len()
    }

    /// Bytes of the instance table ([`SetupGeometry::instance_words`]; one record at least).
    pub fn instance_bytes(&self) -> u64 {
        (self.instances.len().max(1) * INSTANCE_WORDS * 4) as u64
    }

    /// Vertices of all instances: the vertex cache's records (setup.wgsl's `vertex_main`).
    pub fn vertex_total(&self) -> u64 {
        self.instances.iter().map(|g| u64::from(g.vertex_count)).sum()
    }

    /// The instance table of one frame (setup.wgsl's layout): mvp, normal matrix, base colour,
    /// where the mesh lies, primitive ids.
    pub fn instance_words(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Vec<u32> {
        let view_proj = camera.view_proj();
        let mut out = Vec::with_capacity(self.instances.len().max(1) * INSTANCE_WORDS);
        // each instance's first record in the vertex cache (setup.wgsl's `I_FIRST_VERT`)
        let mut first_vert = 0u32;
        let mut live = scene.instances.iter().filter(|inst| {
            scene.objects.get(inst.object).is_some_and(|o| scene.meshes.get(o.mesh).is_some())
        });
        for g in &self.instances {
            let Some(inst) = live.next() else { break };
            // as TriangleSetup::new and ::bounding_boxes compute them
            let (mvp, nm) = if self.boxes {
                (view_proj, Mat3::IDENTITY)
            } else {
                (view_proj * inst.transform, normal_matrix(&inst.transform))
            };
            let base = settings.material_color(g.color);
            let cull_bits = match scene.objects.get(inst.object) {
                Some(o) if !self.boxes => match crate::setup::back_face_sign(o, &inst.transform) {
                    1 => 2,
                    -1 => 4,
                    _ => 0,
                },
                _ => 0,
            };
            out.extend(mvp.to_cols_array().map(f32::to_bits));
            out.extend(nm.to_cols_array().map(f32::to_bits));
            out.extend(base.to_array().map(f32::to_bits));
            out.extend([
                g.vertex_base,
                g.vertex_count,
                g.color_base,
                g.index_base,
                g.tri_count,
                g.prim_base,
                g.first_task,
                // bit 0: raw normals; bits 1 and 2: drop back faces of positive or negative
                // snapped area (crate::setup::back_face_sign)
                u32::from(g.raw_normals) | cull_bits,
                self.positions,
                self.normals,
                first_vert,
            ]);
            first_vert = first_vert.saturating_add(g.vertex_count);
        }
        if out.is_empty() {
            out.resize(INSTANCE_WORDS, 0);
        }
        debug_assert_eq!(out.len() % INSTANCE_WORDS, 0);
        out
    }

    /// The setup kernel's uniform (setup.wgsl's `SetupUniform`) for a frame of `settings` into
    /// buffers holding `tri_capacity` triangles and `item_capacity` work items; `use_verts` when
    /// the vertex cache is bound. A window of a larger frame (`Settings::region`, a screen tile)
    /// snaps in the full frame's viewport and shifts by its origin, as oit-core's setup does.
    pub fn uniform_words(
        &self,
        settings: &Settings,
        tri_capacity: u64,
        item_capacity: u64,
        use_verts: bool,
    ) -> [u32; SETUP_UNIFORM_WORDS] {
        let (full, origin) = match settings.region {
            Some(r) => ((r.full_width, r.full_height), (r.x << 8, r.y << 8)),
            None => ((settings.width, settings.height), (0, 0)),
        };
        let (full, origin) = (
            (full.0.min(MAX_SIZE), full.1.min(MAX_SIZE)),
            (origin.0.min(MAX_SIZE << 8), origin.1.min(MAX_SIZE << 8)),
        );
        let clamp = |v: u64| v.min(u64::from(u32::MAX)) as u32;
        let reach = crate::setup::reach(settings.samples);
        [
            settings.width.min(MAX_SIZE),
            settings.height.min(MAX_SIZE),
            (full.0 as f32).to_bits(),
            (full.1 as f32).to_bits(),
            self.instances.len() as u32,
            self.tasks,
            clamp(tri_capacity),
            clamp(item_capacity),
            origin.0,
            origin.1,
            clamp(self.vertex_total()),
            u32::from(use_verts),
            // the reach of a pixel's samples in 1/256 pixel (`setup::reach`): pixel boxes are
            // sized by it, so a triangle that covers a sample but no centre keeps its pixels
            reach.0 as u32,
            reach.1 as u32,
            0,
            0,
        ]
    }

    /// Workgroups of `setup_count_main` and `setup_items_main`: one a piece that may be spread,
    /// no more than [`SPREAD_PIECES`] and no more than the tasks can leave
    /// ([`MAX_PIECES_PER_TASK`]). Those past the pieces spread end at once, but on a CPU
    /// device (lavapipe) 2,048 of them took milliseconds of a frame of a few triangles.
    pub fn spread_groups(&self) -> u32 {
        self.tasks.saturating_mul(MAX_PIECES_PER_TASK).min(SPREAD_PIECES as u32)
    }

    /// A first guess at the bytes the set-up triangles and the work list need, each at most
    /// `limit` (a backend grows its buffers when a frame's counters say they were short).
    pub fn first_guess(&self, limit: u64) -> (u64, u64) {
        let tasks = u64::from(self.tasks);
        let tris = ((tasks + tasks / 8 + 64) * crate::setup::TRIANGLE_WORDS as u64 * 4).min(limit);
        let items = ((2 * tasks + 4096) * 8).min(limit);
        (tris, items)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each mesh's words once however many instances share it; the instance table has one record
    /// per instance and the tasks add up to the scene's triangles.
    #[test]
    fn meshes_once_instances_each() {
        let one = crate::load_scene("knot").unwrap();
        let grid = crate::load_scene("grid:2x2:knot").unwrap();
        let (g1, g4) = (SetupGeometry::new(&one, false).unwrap(), SetupGeometry::new(&grid, false).unwrap());
        assert_eq!(g1.words.len(), g4.words.len());
        assert_eq!((g1.instance_count(), g4.instance_count()), (1, 4));
        let triangles: usize = grid.meshes[0].indices.len();
        assert_eq!(g4.tasks as usize, 4 * triangles);
        let camera = Camera::orbit_scene(&grid, crate::View::default(), 1.0).unwrap();
        let words = g4.instance_words(&grid, &camera, &Settings::default());
        assert_eq!(words.len(), 4 * INSTANCE_WORDS);
        // first tasks and primitive bases step by the mesh's triangles
        for (i, rec) in words.chunks_exact(INSTANCE_WORDS).enumerate() {
            assert_eq!(rec[35] as usize, i * triangles, "first task of instance {i}");
            assert_eq!(rec[34] as usize, i * triangles, "primitive base of instance {i}");
        }
        let boxes = SetupGeometry::new(&grid, true).unwrap();
        assert_eq!((boxes.tasks, boxes.instance_count()), (48, 4));
    }
}
