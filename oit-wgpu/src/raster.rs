//! The compute-raster path: the papers' "CUDA rasterizer" as a compute shader. Setup (vertex
//! transform, clipping, snapping) is oit-core's `setup`, shared with oit-cpu, so the triangles are
//! the same bits; the kernel in `shaders/raster_compute.wgsl` walks each triangle's pixels with
//! the same integer edge functions and f32 interpolation, which makes the fragment sets equal
//! oit-cpu's by construction.
//!
//! Setup depends on the camera, so it runs on the host every frame (moving it to the GPU is a
//! later step). What a prepared scene keeps is the buffers it goes into: [`ComputeBuffers`] holds
//! the triangles, the (triangle, tile) work list, the raster uniform and the `generated` counter,
//! one set for the scene and one for the instances' bounding boxes; a frame writes them with
//! `queue.write_buffer` and creates a buffer only when it needs more room than any frame before.

use std::cell::Cell;

use oit_core::setup::{TRIANGLE_WORDS, TriangleSetup};
use oit_core::{Camera, OitError, RasterPath, Scene, Settings};

use crate::ctx::{Driver, GpuCtx, dispatch_size};
use crate::gpu::Gpu;

const RASTER_WGSL: &str = include_str!("shaders/raster_compute.wgsl");
/// Pixels on a side of the tile one workgroup of 64 covers (one invocation per pixel).
const TILE: u32 = 8;
/// Bytes of the smallest triangle and work-list buffers (a binding may not be empty).
const MIN_BYTES: u64 = 256;

/// Triangles on the GPU and the (triangle, tile) work list of the compute rasterizer, for one
/// frame: handles to a `ComputeBuffers`' buffers.
pub struct ComputeRaster {
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    generated: wgpu::Buffer,
    items: u64,
}

impl ComputeRaster {
    /// Sets up the scene's triangles (or its instances' bounding boxes) for compute raster, in
    /// buffers of its own (a prepared scene keeps a `ComputeBuffers` instead).
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
    ) -> Result<Self, OitError> {
        let made = Cell::new(0);
        ComputeBuffers::new(gpu, &made).frame(gpu, scene, camera, settings, boxes, &made)
    }
}

/// The compute rasterizer's buffers, kept between the frames of a prepared scene: the set-up
/// triangles and the work list (grown, never shrunk, when a frame needs more), the raster uniform
/// and the `generated` counter. A frame that fits creates no buffer.
pub(crate) struct ComputeBuffers {
    tris: wgpu::Buffer,
    items: wgpu::Buffer,
    uniform: wgpu::Buffer,
    generated: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
}

fn storage_buffer(gpu: &Gpu, label: &str, size: u64, made: &Cell<u64>) -> wgpu::Buffer {
    made.set(made.get() + 1);
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The size a buffer of `old` bytes grows to when `needed` bytes do not fit: at least double, so
/// that views needing a little more each time do not create a buffer each frame, but never over
/// the device's limit (`needed` was checked against it).
fn grown(gpu: &Gpu, old: u64, needed: u64) -> u64 {
    let limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
    needed.max(old.saturating_mul(2).min(limit)).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
}

impl ComputeBuffers {
    /// Empty buffers (grown by the first frame that needs more); `made` counts the buffers created.
    pub(crate) fn new(gpu: &Gpu, made: &Cell<u64>) -> ComputeBuffers {
        let device = &gpu.device;
        let tris = storage_buffer(gpu, "triangles", MIN_BYTES, made);
        let items = storage_buffer(gpu, "raster items", MIN_BYTES, made);
        made.set(made.get() + 2);
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raster uniform"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let generated = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("generated"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("compute raster"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(2, wgpu::BufferBindingType::Uniform),
                entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
            ],
        });
        let group = Self::bind(gpu, &layout, [&tris, &items, &uniform, &generated]);
        ComputeBuffers { tris, items, uniform, generated, layout, group }
    }

    fn bind(gpu: &Gpu, layout: &wgpu::BindGroupLayout, buffers: [&wgpu::Buffer; 4]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
            .collect();
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("compute raster"),
            layout,
            entries: &entries,
        })
    }

    /// Sets up this frame's triangles of the scene (or of its instances' bounding boxes) on the
    /// host and writes them, their work list and the uniform into the kept buffers, growing a
    /// buffer first where they do not fit (counted in `made`).
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
        gpu.check_scene_storage("the triangles", tri_bytes)?;
        gpu.check_storage("the raster work list", item_bytes)?;
        let mut rebind = false;
        if tri_bytes > self.tris.size() {
            self.tris = storage_buffer(gpu, "triangles", grown(gpu, self.tris.size(), tri_bytes), made);
            rebind = true;
        }
        if item_bytes > self.items.size() {
            self.items = storage_buffer(gpu, "raster items", grown(gpu, self.items.size(), item_bytes), made);
            rebind = true;
        }
        if rebind {
            self.group =
                Self::bind(gpu, &self.layout, [&self.tris, &self.items, &self.uniform, &self.generated]);
        }
        let queue = &gpu.queue;
        if !words.is_empty() {
            queue.write_buffer(&self.tris, 0, bytemuck::cast_slice(&words));
        }
        if !items.is_empty() {
            queue.write_buffer(&self.items, 0, bytemuck::cast_slice(&items));
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
        queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(&uniform));
        Ok(ComputeRaster {
            layout: self.layout.clone(),
            group: self.group.clone(),
            generated: self.generated.clone(),
            items: items.len() as u64,
        })
    }
}

impl Driver for ComputeRaster {
    fn path(&self) -> RasterPath {
        RasterPath::Compute
    }

    fn geometry_pass(
        &self,
        ctx: &mut GpuCtx<'_>,
        source: &str,
        layout0: &wgpu::BindGroupLayout,
        group0: &wgpu::BindGroup,
    ) -> Result<u64, OitError> {
        // A workgroup per item spreads a large triangle over the GPU (measured on the H100, fabs on
        // planes:64 at 1024²: 7.5 ms of GPU time a frame, 2.7 of them the two geometry passes,
        // against 10.9 ms with one invocation walking each 16×16 tile); on a CPU device (lavapipe)
        // it tests 64 pixels for each small triangle and ran the conformance tests 7× slower, so
        // there one invocation walks an item.
        let per_pixel = ctx.gpu.info.device_type != wgpu::DeviceType::Cpu;
        let entry = if per_pixel { "raster_main" } else { "raster_loop_main" };
        let pipeline =
            ctx.gpu.compute_pipeline(&format!("{source}\n{RASTER_WGSL}"), entry, &[layout0, &self.layout])?;
        let (x, y) = dispatch_size(if per_pixel { self.items * 64 } else { self.items });
        let mut encoder = ctx.gpu.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.generated, 0, None);
        let writes = ctx.render_timestamps().map(|w| wgpu::ComputePassTimestampWrites {
            query_set: w.query_set,
            beginning_of_pass_write_index: w.beginning_of_pass_write_index,
            end_of_pass_write_index: w.end_of_pass_write_index,
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("geometry"),
                timestamp_writes: writes,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, group0, &[]);
            pass.set_bind_group(1, &self.group, &[]);
            if x > 0 {
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        ctx.finish_timed("geometry", encoder)?;
        Ok(u64::from(ctx.gpu.read_u32(&self.generated)?[0]))
    }
}
