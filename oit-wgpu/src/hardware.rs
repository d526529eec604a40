//! The hardware-raster path: the GPU's own rasterizer, through the embeddable pass
//! ([`crate::embed`]) with oit as its user. The host transforms every instance's vertices to clip
//! space with oit-cpu's matrices (`camera.view_proj() * instance.transform`, normals by the
//! inverse transpose, `settings.material_color`), so the triangles are the same bits as oit-cpu's
//! before raster; the vertex stage (`shaders/raster_hardware.wgsl`) pulls them from storage by
//! vertex index, so triangle `t` of the one draw is primitive `t` (the layout follows
//! `scene.primitive_bases()`), and the fragment stage shades like `Shading::shade` and calls the
//! shared `oit_capture_full`.
//!
//! The GPU's rasterizer has its own sub-pixel precision and clipping, so against oit-cpu (and the
//! compute path) only pixels on triangle edges may differ; no culling, no depth test, wgpu's
//! viewport (row 0 at the top, depth in [0, 1]).

use glam::{Vec3, Vec4};
use oit_core::{Aabb, Camera, OitError, RasterPath, Scene, Settings};
use wgpu::util::DeviceExt;

use crate::ctx::{Driver, GpuCtx};
use crate::embed::{CaptureShader, GeometryPass, RenderDriver};
use crate::gpu::Gpu;

const RASTER_WGSL: &str = include_str!("shaders/raster_hardware.wgsl");

/// One vertex as `HwVertex` in raster_hardware.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct HwVertex {
    clip: [f32; 4],
    /// xyz: world normal; w: 1 when the mesh has vertex colours.
    normal: [f32; 4],
    color: [f32; 4],
    base: [f32; 4],
}

/// The scene (or its instances' bounding boxes) on the GPU's rasterizer.
pub struct HardwareRaster {
    driver: RenderDriver<'static>,
    stage: SceneStage,
}

/// The vertex stage of [`HardwareRaster`] for techniques that build their own render pipelines
/// (`technique::{bdp_blend, dp_depth}`): put [`SceneStage::wgsl`] after the technique's group 0
/// declarations, add [`SceneStage::layout`] as group 1, use `hw_vs` as the vertex entry point
/// (its output `HwOut`, and `shade`, serve the fragment stage), and call [`SceneStage::draw`].
pub struct SceneStage {
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    vertex_count: u32,
}

impl SceneStage {
    /// raster_hardware.wgsl without its fragment entry point (`hw_fs`, which calls the atomics
    /// capture): the group 1 bindings, `HwOut` and `hw_vs`.
    pub(crate) fn wgsl(&self) -> &'static str {
        RASTER_WGSL.split_once("@fragment").map_or(RASTER_WGSL, |(vertex, _)| vertex)
    }

    /// The layout of group 1 (the clip-space vertices, indices and the shading uniform).
    pub(crate) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Sets group 1 and draws every triangle (primitive `t` of the draw is the scene's `t`).
    pub(crate) fn draw(&self, rpass: &mut wgpu::RenderPass<'_>) {
        rpass.set_bind_group(1, &self.group, &[]);
        if self.vertex_count > 0 {
            rpass.draw(0..self.vertex_count, 0..1);
        }
    }
}

/// Where one pass of a blend capture draws: a colour target cleared to `clear`, and a depth
/// attachment cleared to 1 where the pass tests depth.
pub(crate) struct PassTarget<'a> {
    pub label: &'a str,
    pub color: &'a wgpu::TextureView,
    pub clear: wgpu::Color,
    pub depth: Option<&'a wgpu::TextureView>,
}

/// An occlusion query over one pass, and the buffer its result resolves into.
pub(crate) struct Occlusion {
    set: wgpu::QuerySet,
    buffer: wgpu::Buffer,
}

impl Occlusion {
    pub(crate) fn new(device: &wgpu::Device, label: &str) -> Occlusion {
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some(label),
            ty: wgpu::QueryType::Occlusion,
            count: 1,
        });
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Occlusion { set, buffer }
    }
}

impl SceneStage {
    /// One geometry pass of a blend capture (`technique::{dp_depth, ddp_blend}`): `pipeline`
    /// draws the scene into `target` with `groups` set as groups 0 and 2, inside `occlusion`'s
    /// query; it is timed and counted as a geometry pass. Returns whether any sample passed: zero
    /// or not is all an occlusion query promises on every backend.
    pub(crate) fn occlusion_pass(
        &self,
        ctx: &mut GpuCtx<'_>,
        pipeline: &wgpu::RenderPipeline,
        groups: (&wgpu::BindGroup, &wgpu::BindGroup),
        target: PassTarget<'_>,
        occlusion: &Occlusion,
    ) -> Result<bool, OitError> {
        let mut encoder = ctx.gpu.device.create_command_encoder(&Default::default());
        {
            let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(target.label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target.color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(target.clear),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: target.depth.map(|view| wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: ctx.render_timestamps(),
                occlusion_query_set: Some(&occlusion.set),
                multiview_mask: None,
            });
            rpass.set_pipeline(pipeline);
            rpass.set_bind_group(0, groups.0, &[]);
            rpass.set_bind_group(2, groups.1, &[]);
            rpass.begin_occlusion_query(0);
            self.draw(&mut rpass);
            rpass.end_occlusion_query();
        }
        encoder.resolve_query_set(&occlusion.set, 0..1, &occlusion.buffer, 0);
        ctx.finish_timed("geometry", encoder)?;
        ctx.passes += 1;
        Ok(ctx.gpu.read_u32(&occlusion.buffer)?.iter().any(|&s| s != 0))
    }
}

impl HardwareRaster {
    /// Sets up the scene's triangles for the hardware rasterizer.
    pub fn new(gpu: &Gpu, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Self, OitError> {
        let view_proj = camera.view_proj();
        let mut vertices = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        for inst in &scene.instances {
            let (object, mesh) = scene.instance_parts(inst);
            let mvp = view_proj * inst.transform;
            let nm = oit_core::setup::normal_matrix(&inst.transform);
            let base = settings.material_color(object.color).to_array();
            let first = vertices.len() as u32;
            let has_color = if mesh.colors.is_some() { 1.0 } else { 0.0 };
            for (i, p) in mesh.positions.iter().enumerate() {
                let n = nm * mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
                let c = mesh.colors.as_ref().and_then(|c| c.get(i).copied()).unwrap_or(Vec3::ZERO);
                vertices.push(HwVertex {
                    clip: (mvp * p.extend(1.0)).to_array(),
                    normal: n.extend(has_color).to_array(),
                    color: c.extend(0.0).to_array(),
                    base,
                });
            }
            indices.extend(mesh.indices.iter().flatten().map(|&i| first + i));
        }
        Self::upload(gpu, &vertices, &indices, camera, settings)
    }

    /// The 12 triangles of each instance's world bounding box (`Aabb::TRIANGLES` over the corners
    /// of `scene.instance_bounds`), triangle `t` of instance `i` primitive `12·i + t`, as oit-cpu's
    /// `TriangleSetup::bounding_boxes`: for the bounds passes of bdp and adp.
    pub fn boxes(gpu: &Gpu, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Self, OitError> {
        let view_proj = camera.view_proj();
        let mut vertices = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        for inst in &scene.instances {
            let (object, _) = scene.instance_parts(inst);
            let bounds: Aabb = scene.instance_bounds(inst);
            let base = settings.material_color(object.color).to_array();
            let first = vertices.len() as u32;
            for c in bounds.corners() {
                vertices.push(HwVertex {
                    clip: (view_proj * c.extend(1.0)).to_array(),
                    normal: (c - bounds.center()).normalize_or_zero().extend(0.0).to_array(),
                    color: [0.0; 4],
                    base,
                });
            }
            indices.extend(Aabb::TRIANGLES.iter().flatten().map(|&i| first + i));
        }
        Self::upload(gpu, &vertices, &indices, camera, settings)
    }

    fn upload(
        gpu: &Gpu,
        vertices: &[HwVertex],
        indices: &[u32],
        camera: &Camera,
        settings: &Settings,
    ) -> Result<Self, OitError> {
        gpu.check_storage("the clip-space vertices", std::mem::size_of_val(vertices) as u64)?;
        gpu.check_storage("the triangle indices", std::mem::size_of_val(indices) as u64)?;
        let device = &gpu.device;
        let storage = |label: &str, bytes: &[u8]| {
            let padded: Vec<u8> = if bytes.is_empty() { vec![0; 64] } else { bytes.to_vec() };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &padded,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let vertex_buf = storage("clip-space vertices", bytemuck::cast_slice(vertices));
        let index_buf = storage("triangle indices", bytemuck::cast_slice(indices));
        let shading = settings.shading.code();
        let f: Vec4 = camera.forward.extend(0.0);
        let uniform: [u32; 8] =
            [shading, 0, 0, 0, f.x.to_bits(), f.y.to_bits(), f.z.to_bits(), f.w.to_bits()];
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hardware raster uniform"),
            contents: bytemuck::cast_slice(&uniform),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let entry = |binding: u32, visibility: wgpu::ShaderStages, ty: wgpu::BufferBindingType| {
            wgpu::BindGroupLayoutEntry {
                binding,
                visibility,
                ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
                count: None,
            }
        };
        let layout1 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hardware raster"),
            entries: &[
                entry(0, wgpu::ShaderStages::VERTEX, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(1, wgpu::ShaderStages::VERTEX, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(2, wgpu::ShaderStages::VERTEX_FRAGMENT, wgpu::BufferBindingType::Uniform),
            ],
        });
        let group1 = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hardware raster"),
            layout: &layout1,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: vertex_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: index_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: uniform.as_entire_binding() },
            ],
        });
        let vertex_count = u32::try_from(indices.len())
            .map_err(|_| OitError::Device("over 2^32 vertices in one draw".into()))?;
        let stage = SceneStage { layout: layout1.clone(), group: group1.clone(), vertex_count };
        let pipeline_device = device.clone();
        let pipeline = move |capture: &CaptureShader<'_>| {
            let device = &pipeline_device;
            scene_pipeline(
                device,
                "hardware raster",
                &format!("{}\n{RASTER_WGSL}", capture.wgsl),
                &[capture.bind_group_layout, &layout1],
                "hw_fs",
                &[Some(capture.count_target.clone())],
                None,
            )
        };
        let draw = move |rpass: &mut wgpu::RenderPass<'_>, _: &GeometryPass<'_>| {
            rpass.set_bind_group(1, &group1, &[]);
            if vertex_count > 0 {
                rpass.draw(0..vertex_count, 0..1);
            }
        };
        let driver = RenderDriver::new(
            gpu,
            settings.width,
            settings.height,
            "hardware",
            Box::new(pipeline),
            Box::new(draw),
        );
        Ok(HardwareRaster { driver, stage })
    }
}

impl Driver for HardwareRaster {
    fn path(&self) -> RasterPath {
        RasterPath::Hardware
    }

    fn geometry_pass(
        &self,
        ctx: &mut GpuCtx<'_>,
        source: &str,
        layout0: &wgpu::BindGroupLayout,
        group0: &wgpu::BindGroup,
    ) -> Result<u64, OitError> {
        self.driver.geometry_pass(ctx, source, layout0, group0)
    }

    fn scene_stage(&self) -> Option<&SceneStage> {
        Some(&self.stage)
    }
}

/// A render pipeline over oit's scene vertex stage: `hw_vs` of `source` as the vertex stage (no
/// vertex buffers, no culling), `fs_entry` of it as the fragment stage, `layouts` as its bind
/// groups. The hardware raster and the blend captures (`technique::{bdp_blend, dp_depth,
/// ddp_blend}`) build theirs with it.
pub(crate) fn scene_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
    fs_entry: &str,
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("hw_vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(fs_entry),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}
