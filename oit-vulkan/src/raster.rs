//! The compute-raster path: oit-wgpu's compute rasterizer (`raster_compute.wgsl`, compiled into
//! every technique's SPIR-V module by `build.rs`) on Vulkan. Setup (transform, clipping, snapping)
//! is oit-core's `setup`, shared with oit-cpu and oit-wgpu, so the triangles are the same bits and
//! the fragments equal oit-cpu's.
//!
//! As on wgpu, the setup runs on the host every frame; a prepared scene keeps the buffers it goes
//! into ([`ComputeBuffers`]), grown only when a frame needs more. The words are uploaded through
//! a staging buffer by the frame's first geometry pass that uses them, recorded in the frame's
//! command stream behind a barrier.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use ash::vk;
use oit_core::setup::{TRIANGLE_WORDS, TriangleSetup};
use oit_core::{Camera, OitError, Scene, Settings};

use crate::ctx::storage_usage;
use crate::device::{Buffer, Gpu};
use crate::record::Recorder;

/// Pixels on a side of the tile one work item covers.
const TILE: u32 = 8;
/// Bytes of the smallest triangle and work-list buffers (a binding may not be empty).
const MIN_BYTES: u64 = 256;

/// A frame's rasterizer of the scene (or of its instances' bounding boxes), on either path.
pub(crate) enum Raster {
    /// The compute rasterizer (this module).
    Compute(ComputeRaster),
    /// The GPU's own (`crate::hardware`).
    Hardware(crate::hardware::HardwareRaster),
}

/// One frame's triangles and work list, on the GPU once the first geometry pass uploads them.
pub(crate) struct ComputeRaster {
    tris: Rc<Buffer>,
    item_list: Rc<Buffer>,
    pub(crate) uniform: Rc<Buffer>,
    pub(crate) generated: Rc<Buffer>,
    /// Work items: (triangle, 8×8 tile of its box).
    pub(crate) items: u64,
    /// Triangle words, work items and the raster uniform, until uploaded.
    pending: RefCell<Option<[Vec<u8>; 3]>>,
}

impl ComputeRaster {
    /// Group 1's storage bindings (the uniform, binding 2, is bound apart).
    pub(crate) fn bindings(&self) -> Vec<(u32, &Buffer)> {
        vec![(0, &*self.tris), (1, &*self.item_list), (3, &*self.generated)]
    }

    /// Records the upload of this frame's words, once.
    pub(crate) fn upload(&self, rec: &mut Recorder<'_>) -> Result<(), OitError> {
        if let Some([tris, items, uniform]) = self.pending.borrow_mut().take() {
            rec.upload(&self.tris, &tris)?;
            rec.upload(&self.item_list, &items)?;
            rec.upload(&self.uniform, &uniform)?;
        }
        Ok(())
    }
}

/// The compute rasterizer's buffers, kept between the frames of a prepared scene.
pub(crate) struct ComputeBuffers {
    tris: Rc<Buffer>,
    items: Rc<Buffer>,
    uniform: Rc<Buffer>,
    generated: Rc<Buffer>,
}

fn geometry_usage() -> vk::BufferUsageFlags {
    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST
}

impl ComputeBuffers {
    /// Small buffers (grown by the first frame that needs more); `made` counts the buffers.
    pub(crate) fn new(gpu: &Gpu, made: &Cell<u64>) -> Result<ComputeBuffers, OitError> {
        made.set(made.get() + 4);
        Ok(ComputeBuffers {
            tris: Rc::new(gpu.buffer(MIN_BYTES, geometry_usage(), false)?),
            items: Rc::new(gpu.buffer(MIN_BYTES, geometry_usage(), false)?),
            uniform: Rc::new(gpu.buffer(
                32,
                vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                false,
            )?),
            generated: Rc::new(gpu.buffer(16, storage_usage(), false)?),
        })
    }

    /// Sets up this frame's triangles of the scene (or of its instances' bounding boxes) on the
    /// host, growing a buffer first where they do not fit (counted in `made`).
    pub(crate) fn frame(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<ComputeRaster, OitError> {
        let r = if boxes {
            TriangleSetup::bounding_boxes(scene, camera, settings)
        } else {
            TriangleSetup::new(scene, camera, settings)
        };
        let words = r.triangle_words();
        debug_assert_eq!(words.len() % TRIANGLE_WORDS, 0);
        let mut items: Vec<[u32; 2]> = Vec::new();
        for (i, [x0, y0, x1, y1]) in r.triangle_boxes().enumerate() {
            for ty in y0 / TILE..=y1 / TILE {
                for tx in x0 / TILE..=x1 / TILE {
                    items.push([i as u32, ty << 16 | tx]);
                }
            }
        }
        let (tri_bytes, item_bytes) = (words.len() as u64 * 4, items.len() as u64 * 8);
        gpu.check_storage_hint(
            "the triangles",
            tri_bytes,
            "use fewer triangles or instances (176 bytes each on the compute rasterizer), or the cpu backend",
        )?;
        gpu.check_storage("the raster work list", item_bytes)?;
        let limit = u64::from(gpu.info.limits.max_storage_buffer_range);
        let grown = |old: u64, needed: u64| needed.max(old.saturating_mul(2).min(limit)).next_multiple_of(4);
        if tri_bytes > self.tris.size {
            self.tris = Rc::new(gpu.buffer(grown(self.tris.size, tri_bytes), geometry_usage(), false)?);
            made.set(made.get() + 1);
        }
        if item_bytes > self.items.size {
            self.items = Rc::new(gpu.buffer(grown(self.items.size, item_bytes), geometry_usage(), false)?);
            made.set(made.get() + 1);
        }
        let forward = camera.forward;
        let uniform: [u32; 8] = [
            items.len() as u32,
            settings.width,
            settings.height,
            settings.shading.code(),
            forward.x.to_bits(),
            forward.y.to_bits(),
            forward.z.to_bits(),
            0,
        ];
        Ok(ComputeRaster {
            tris: self.tris.clone(),
            item_list: self.items.clone(),
            uniform: self.uniform.clone(),
            generated: self.generated.clone(),
            items: items.len() as u64,
            pending: RefCell::new(Some([
                bytemuck::cast_slice(&words).to_vec(),
                bytemuck::cast_slice(&items).to_vec(),
                bytemuck::cast_slice(&uniform).to_vec(),
            ])),
        })
    }
}
