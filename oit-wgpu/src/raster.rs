//! The compute-raster path: the papers' "CUDA rasterizer" as a compute shader. Setup (vertex
//! transform, clipping, snapping) is oit-core's `setup`, shared with oit-cpu, so the triangles are the same bits; the
//! kernel in `shaders/raster_compute.wgsl` walks each triangle's pixels with the same integer edge
//! functions and f32 interpolation, which makes the fragment sets equal oit-cpu's by construction.

use oit_core::setup::{TRIANGLE_WORDS, TriangleSetup};
use oit_core::{Camera, OitError, RasterPath, Scene, Settings};
use wgpu::util::DeviceExt;

use crate::ctx::{Driver, GpuCtx, dispatch_size};
use crate::gpu::Gpu;

const RASTER_WGSL: &str = include_str!("shaders/raster_compute.wgsl");
/// Pixels on a side of the tile one workgroup of 64 covers (one invocation per pixel).
const TILE: u32 = 8;

/// Triangles on the GPU and the (triangle, tile) work list of the compute rasterizer.
pub struct ComputeRaster {
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    generated: wgpu::Buffer,
    items: u64,
}

impl ComputeRaster {
    /// Sets up the scene's triangles (or its instances' bounding boxes) for compute raster.
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
    ) -> Result<Self, OitError> {
        let r = if boxes {
            TriangleSetup::bounding_boxes(scene, camera, settings)
        } else {
            TriangleSetup::new(scene, camera, settings)
        };
        let words = r.triangle_words();
        let mut items: Vec<[u32; 2]> = Vec::new();
        for (i, [x0, y0, x1, y1]) in r.triangle_boxes().enumerate() {
            for ty in y0 / TILE..=y1 / TILE {
                for tx in x0 / TILE..=x1 / TILE {
                    items.push([i as u32, ty << 16 | tx]);
                }
            }
        }
        gpu.check_scene_storage("the triangles", words.len() as u64 * 4)?;
        gpu.check_storage("the raster work list", items.len() as u64 * 8)?;
        let device = &gpu.device;
        let storage = |label: &str, bytes: &[u8]| {
            let padded: Vec<u8> = if bytes.is_empty() { vec![0; 16] } else { bytes.to_vec() };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &padded,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let tris = storage("triangles", bytemuck::cast_slice(&words));
        let item_buf = storage("raster items", bytemuck::cast_slice(&items));
        let forward = camera.forward;
        let shading = settings.shading.code();
        let uniform: [u32; 8] = [
            items.len() as u32,
            settings.width,
            settings.height,
            shading,
            forward.x.to_bits(),
            forward.y.to_bits(),
            forward.z.to_bits(),
            0,
        ];
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("raster uniform"),
            contents: bytemuck::cast_slice(&uniform),
            usage: wgpu::BufferUsages::UNIFORM,
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
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("compute raster"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: tris.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: item_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: generated.as_entire_binding() },
            ],
        });
        let _ = TRIANGLE_WORDS;
        Ok(ComputeRaster { layout, group, generated, items: items.len() as u64 })
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
