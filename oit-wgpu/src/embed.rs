//! The embeddable pass: oit's capture, storage, clear and resolve inside a wgpu user's own frame.
//!
//! Contract:
//! - The user keeps their device, vertex buffers, the vertex stage of their pipelines and their
//!   draw calls. oit supplies a WGSL module to put in front of the user's shader
//!   ([`CaptureShader::wgsl`]), the layout of bind group 0 ([`CaptureShader::bind_group_layout`])
//!   and its bind group (set by oit before the user's draws; [`GeometryPass::bind_group`] if the
//!   user needs to set it again), and the colour target of the pipeline
//!   ([`CaptureShader::count_target`]).
//! - The user's fragment shader ends in `return oit_capture(position.xy, position.z, colour,
//!   prim);` (or `oit_capture_full(.., normal, prim)` for the Fresnel effect), writing its result
//!   to `@location(0)`: `position` is `@builtin(position)`, `colour` straight-alpha linear RGBA,
//!   `prim` a primitive id (equal depths are ordered by it). The draws must not cull what should
//!   be seen through and must cover the `width × height` target oit renders into (the viewport is
//!   oit's count target, of the settings' size).
//! - [`OitPass::frame`] runs the technique: for each geometry pass it asks the user for the
//!   pipeline of that pass's capture module (once per module: cached in the pass) and calls the
//!   user's draw closure inside a render pass; multi-pass techniques (`dp`, or a counting pass
//!   first when a size is not given, as in `reference` and `fabs` without K) call it once per
//!   geometry pass (`dfb` and `ll` count first too). Then the resolve: the image is returned in the [`Frame`] and, when a target is
//!   given, written into it.
//! - oit submits its own command buffers on the queue (techniques read back between passes:
//!   counts to size storage, a peel's occlusion), so it takes no encoder: submit what the draws
//!   depend on before calling `frame`.
//! - Supported: every technique whose geometry passes draw the scene itself (`reference`, `fabs`,
//!   `mdts64`, `mlp`, `wavg`, `wsum`, `dp`, `ddp`, `dfb`, `ll`; `plain` by sorting each pixel's
//!   fragments by primitive id, as the compute path does, since the blend units of the user's
//!   pipeline are not oit's; `mdts` when `Settings::alpha` is set, since its
//!   32-bit words store no alpha and the pass does not know the caller's); `bdp`, `bdp:P` and
//!   `adp` when the pass has the instances' bounding boxes. Their bounds pass (Liu et al., HPG
//!   2009: each pixel's depth range from the rendered depths of the instances' boxes) draws
//!   boxes, not the user's geometry: the user gives their instances' world-space boxes once
//!   ([`OitPass::with_instance_boxes`]; [`OitPass::with_scene_geometry`] takes an oit
//!   [`Scene`]'s) and oit draws them itself, 12 triangles each with its hardware path's vertex
//!   stage, through `camera.view_proj()` (so the camera must be the one the user's draws use).
//!   Without boxes they fail with [`OitError::Unsupported`] naming that method, as `mdts` does
//!   without an alpha (or set `Settings::bounds` to `BoundsMode::Exact`: then the bounds pass
//!   draws the user's geometry like any other pass).
//!
//! `Backend::render` on the hardware path is a client of the same code: [`crate::HardwareRaster`]
//! is this pass's driver with oit's own vertex stage (`shaders/raster_hardware.wgsl`) and draws.
//! A user who draws an oit [`Scene`] (the `oit view` window does) can take that vertex stage and
//! its upload instead of writing their own: [`SceneGeometry`] holds the scene on the device in
//! the hardware path's format and [`SceneGeometry::WGSL`] is its shader, so the pass's image equals
//! `Backend::render`'s on the hardware path.
//!
//! The module oit supplies defines many unprefixed names (`Fragment`, `capture`, `fu`, `state`,
//! `shade`, ...), and uses group 0: keep the user's names distinct and their bindings in groups
//! 1 and up. It needs `SHADER_INT64` and the 64-bit atomics on the device
//! ([`crate::required_features`]).
//!
//! ```no_run
//! use oit_core::{Camera, Settings, Technique};
//! use oit_wgpu::OitPass;
//!
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue, target: &wgpu::TextureView,
//! #         vertices: &wgpu::Buffer, layouts: &[Option<wgpu::VertexBufferLayout<'static>>]) -> Result<(), oit_core::OitError> {
//! const MY_WGSL: &str = r#"
//! struct V { @builtin(position) pos: vec4<f32>, @location(0) color: vec4<f32>, @location(1) @interpolate(flat) prim: u32 }
//! @vertex fn my_vs(@location(0) p: vec4<f32>, @location(1) c: vec4<f32>, @builtin(vertex_index) i: u32) -> V {
//!     return V(p, c, i / 3u);
//! }
//! @fragment fn my_fs(v: V) -> @location(0) vec4<f32> {
//!     return oit_capture(v.pos.xy, v.pos.z, v.color, v.prim);
//! }
//! "#;
//! let settings = Settings { width: 256, height: 256, technique: Technique::Fabs { k: Some(8) }, ..Settings::default() };
//! let camera = Camera::look_at([0.0, 0.0, 3.0].into(), glam::Vec3::ZERO, 45.0, 1.0, 0.1, 10.0);
//! let pass = OitPass::new(device, queue, settings, camera)?;
//! let frame = pass.frame(
//!     Some(target),
//!     |capture| {
//!         let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
//!             label: Some("mine + oit"),
//!             source: wgpu::ShaderSource::Wgsl(format!("{}\n{MY_WGSL}", capture.wgsl).into()),
//!         });
//!         let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
//!             label: None,
//!             bind_group_layouts: &[Some(capture.bind_group_layout)],
//!             immediate_size: 0,
//!         });
//!         device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
//!             label: Some("mine"),
//!             layout: Some(&layout),
//!             vertex: wgpu::VertexState { module: &module, entry_point: Some("my_vs"), compilation_options: Default::default(), buffers: layouts },
//!             primitive: wgpu::PrimitiveState::default(),
//!             depth_stencil: None,
//!             multisample: Default::default(),
//!             fragment: Some(wgpu::FragmentState {
//!                 module: &module,
//!                 entry_point: Some("my_fs"),
//!                 compilation_options: Default::default(),
//!                 targets: &[Some(capture.count_target.clone())],
//!             }),
//!             multiview_mask: None,
//!             cache: None,
//!         })
//!     },
//!     |rpass, _pass| {
//!         rpass.set_vertex_buffer(0, vertices.slice(..));
//!         rpass.draw(0..6, 0..1);
//!     },
//! )?;
//! println!("{} fragments, {} geometry passes", frame.stats.fragments, frame.stats.geometry_passes);
//! # Ok(()) }
//! ```

use std::cell::RefCell;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Instant;

use glam::{Vec3, Vec4};
use oit_core::{
    Aabb, BoundsMode, Camera, Frame, Instance, Mesh, OitError, RasterPath, Scene, Settings, Technique,
};

use crate::ctx::{Driver, Generated, GpuCtx};
use crate::gpu::{COMMON_WGSL, Gpu};
use crate::hardware::{HwGeometry, RASTER_WGSL};

/// The fragment side every render-pipeline geometry pass shares (`oit_capture`).
pub const CAPTURE_RENDER_WGSL: &str = include_str!("shaders/capture_render.wgsl");
const COUNT_SUM_WGSL: &str = include_str!("shaders/count_sum.wgsl");

/// What the user's pipeline for one capture module is built from.
pub struct CaptureShader<'a> {
    /// oit's WGSL: the shared rules, the technique's storage (group 0) and `capture`, and
    /// `oit_capture` / `oit_capture_full`. Put it in front of the user's own WGSL.
    pub wgsl: &'a str,
    /// The layout of group 0 (first in the user's pipeline layout).
    pub bind_group_layout: &'a wgpu::BindGroupLayout,
    /// The pipeline's colour target 0: oit's fragment counter (one channel, additive blending).
    pub count_target: wgpu::ColorTargetState,
    /// Which module of the technique this is (passes with the same module share a pipeline).
    pub key: u64,
}

/// One geometry pass, as the user's draw closure sees it.
pub struct GeometryPass<'a> {
    /// 0 for the first geometry pass of the frame, then 1, 2, ...
    pub index: u32,
    /// Group 0 of this pass (already set at index 0 when the closure is called).
    pub bind_group: &'a wgpu::BindGroup,
}

type PipelineFn<'a> = Box<dyn FnMut(&CaptureShader<'_>) -> wgpu::RenderPipeline + 'a>;
type DrawFn<'a> = Box<dyn FnMut(&mut wgpu::RenderPass<'_>, &GeometryPass<'_>) + 'a>;

/// A geometry pass on a render pipeline: the user's (or oit's own hardware raster's) pipeline
/// over the capture module, drawn into a one-channel count target. The [`Driver`] both the
/// hardware path and the embedded pass run.
pub(crate) struct RenderDriver<'a> {
    salt: &'static str,
    format: wgpu::TextureFormat,
    count_view: wgpu::TextureView,
    sum_layout: wgpu::BindGroupLayout,
    sum_group: wgpu::BindGroup,
    total: wgpu::Buffer,
    size: (u32, u32),
    pipeline: RefCell<PipelineFn<'a>>,
    draw: RefCell<DrawFn<'a>>,
}

impl<'a> RenderDriver<'a> {
    /// The buffers and textures [`RenderDriver::new`] creates (the count target and the
    /// counter it is summed into), for the counters of prepared scenes.
    pub(crate) const CREATES: u64 = 2;

    /// A driver for `width × height`; `salt` keeps its pipelines apart in the device's cache.
    pub(crate) fn new(
        gpu: &Gpu,
        width: u32,
        height: u32,
        salt: &'static str,
        pipeline: PipelineFn<'a>,
        draw: DrawFn<'a>,
    ) -> RenderDriver<'a> {
        // R16Float counts exactly up to 2048 fragments per pixel and pass; R32Float (blendable
        // only with FLOAT32_BLENDABLE) up to 2^24.
        let format = if gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            wgpu::TextureFormat::R32Float
        } else {
            wgpu::TextureFormat::R16Float
        };
        let device = &gpu.device;
        let count = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("fragment counts"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let count_view = count.create_view(&Default::default());
        let total = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("generated"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sum_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("count sum"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let sum_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("count sum"),
            layout: &sum_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&count_view),
                },
                wgpu::BindGroupEntry { binding: 1, resource: total.as_entire_binding() },
            ],
        });
        RenderDriver {
            salt,
            format,
            count_view,
            sum_layout,
            sum_group,
            total,
            size: (width, height),
            pipeline: RefCell::new(pipeline),
            draw: RefCell::new(draw),
        }
    }
}

/// The colour target a capture pipeline writes: the fragment counter.
fn count_target(format: wgpu::TextureFormat) -> wgpu::ColorTargetState {
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState { color: add, alpha: add }),
        write_mask: wgpu::ColorWrites::RED,
    }
}

impl Driver for RenderDriver<'_> {
    fn path(&self) -> RasterPath {
        RasterPath::Hardware
    }

    fn geometry_pass(
        &self,
        ctx: &mut GpuCtx<'_>,
        source: &str,
        layout0: &wgpu::BindGroupLayout,
        group0: &wgpu::BindGroup,
    ) -> Result<Generated, OitError> {
        let wgsl = format!("{COMMON_WGSL}\n{source}\n{CAPTURE_RENDER_WGSL}");
        let mut h = DefaultHasher::new();
        wgsl.hash(&mut h);
        let module_key = h.finish();
        self.salt.hash(&mut h);
        self.format.hash(&mut h);
        let pipeline = ctx.gpu.render_pipeline(h.finish(), self.salt, || {
            (self.pipeline.borrow_mut())(&CaptureShader {
                wgsl: &wgsl,
                bind_group_layout: layout0,
                count_target: count_target(self.format),
                key: module_key,
            })
        })?;
        let mut encoder = ctx.gpu.device.create_command_encoder(&Default::default());
        {
            let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("geometry"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.count_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: ctx.render_timestamps(),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rpass.set_pipeline(&pipeline);
            rpass.set_bind_group(0, group0, &[]);
            (self.draw.borrow_mut())(&mut rpass, &GeometryPass { index: ctx.passes, bind_group: group0 });
        }
        ctx.finish_timed("geometry", encoder)?;
        let sum = ctx.gpu.compute_pipeline(COUNT_SUM_WGSL, "count_sum_main", &[&self.sum_layout])?;
        let mut encoder = ctx.gpu.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.total, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&sum);
            pass.set_bind_group(0, &self.sum_group, &[]);
            pass.dispatch_workgroups(self.size.0.div_ceil(8), self.size.1.div_ceil(8), 1);
        }
        ctx.gpu.queue.submit([encoder.finish()]);
        Ok(Generated(self.total.clone()))
    }
}

/// oit's capture and resolve, embedded in a wgpu user's frame (see the module docs).
pub struct OitPass {
    gpu: Gpu,
    settings: Settings,
    camera: Camera,
    scene: Scene,
    /// The instances' bounding boxes on the device, for the bounds pass of bdp and adp.
    boxes: Option<HwGeometry>,
}

/// A stand-in scene for the frame: what `GpuCtx` reads from a scene (its bounds, which scale the
/// translucency absorption, and the objects' absorption), without triangles.
fn stand_in(bounds: Aabb, absorption: f32) -> Scene {
    let mesh = Mesh::new("bounds of the embedding scene", vec![bounds.min, bounds.max], Vec::new());
    let mut scene = Scene::from_meshes("embedded", vec![mesh], Vec4::ONE);
    scene.objects[0].absorption = absorption;
    scene.instances = vec![Instance { object: 0, transform: glam::Mat4::IDENTITY }];
    scene
}

impl OitPass {
    /// A pass on the user's device for `settings` (size, technique, effect, background; shading
    /// and the raster path are the user's own business) and `camera` (its near/far and forward
    /// direction are what the resolve needs). Checks the device's features.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: Settings,
        camera: Camera,
    ) -> Result<OitPass, OitError> {
        settings.validate()?;
        let gpu = Gpu::from_device(device.clone(), queue.clone())?;
        Ok(OitPass {
            gpu,
            settings,
            camera,
            scene: stand_in(Aabb { min: -Vec3::ONE, max: Vec3::ONE }, 1.0),
            boxes: None,
        })
    }

    /// The world-space bounding boxes of the user's instances, for the bounds pass of `bdp` and
    /// `adp` (with `Settings::bounds` at its default, `BoundsMode::Boxes`): uploaded once, and
    /// drawn by oit in each frame of those techniques with `camera.view_proj()`, box `i`'s 12
    /// triangles as primitives `12·i ..` (`Aabb::TRIANGLES`), as `Backend::render` draws an oit
    /// scene's `Scene::instance_bounds` on the hardware path. A box must hold finite corners,
    /// `min ≤ max` on each axis. Replaces the boxes given before.
    pub fn with_instance_boxes(mut self, boxes: &[Aabb]) -> Result<OitPass, OitError> {
        if let Some((i, b)) = boxes
            .iter()
            .enumerate()
            .find(|(_, b)| !(b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all()))
        {
            return Err(OitError::InvalidSettings(format!(
                "instance box {i} is {:?} .. {:?}: a box needs finite corners with min <= max on each axis",
                b.min.to_array(),
                b.max.to_array()
            )));
        }
        self.boxes = Some(HwGeometry::boxes(&self.gpu, boxes, &std::cell::Cell::new(0))?);
        Ok(self)
    }

    /// What the pass needs of an oit [`Scene`] drawn through `geometry`: its instances' bounding
    /// boxes (uploaded with the geometry, shared, not uploaded again), and its world bounds and
    /// the objects' mean absorption ([`OitPass::with_scene_bounds`]), so every technique's image
    /// equals `Backend::render`'s on the hardware path. `geometry` must be on the pass's device.
    pub fn with_scene_geometry(mut self, geometry: &SceneGeometry) -> OitPass {
        self.scene = stand_in(geometry.bounds, geometry.absorption);
        self.boxes = Some(geometry.boxes.clone());
        self
    }

    /// The world bounds of the user's scene and its absorption coefficient, for the translucency
    /// effect (absorption is per 1/8 of the bounds' radius, as for oit's own scenes). Default: the
    /// box ±1, absorption 1.
    pub fn with_scene_bounds(mut self, bounds: Aabb, absorption: f32) -> OitPass {
        self.scene = stand_in(bounds, absorption);
        self
    }

    /// The settings of the pass.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Changes the settings and camera of the next frames (a new view, a new window size, another
    /// technique), keeping what the pass has compiled on the device (its pipelines and the user's,
    /// cached per module). Checks the settings as [`OitPass::new`] does.
    pub fn set_view(&mut self, settings: Settings, camera: Camera) -> Result<(), OitError> {
        settings.validate()?;
        self.settings = settings;
        self.camera = camera;
        Ok(())
    }

    /// One frame: the technique's geometry passes (the user's `draw` in each, on the pipeline
    /// `pipeline` builds for that pass's capture module; built once per module and kept), its
    /// resolve, and the image written into `target` when given (an `Rgba8Unorm`, `Rgba8UnormSrgb`,
    /// `Bgra8Unorm` or `Bgra8UnormSrgb` texture at least `width × height`, with `COPY_DST`; the
    /// bytes are sRGB-encoded, as in the PNG oit writes). Returns the frame with its stats.
    pub fn frame(
        &self,
        target: Option<&wgpu::TextureView>,
        pipeline: impl FnMut(&CaptureShader<'_>) -> wgpu::RenderPipeline,
        draw: impl FnMut(&mut wgpu::RenderPass<'_>, &GeometryPass<'_>),
    ) -> Result<Frame, OitError> {
        let start = Instant::now();
        if let Some(view) = target {
            self.check_target(view.texture())?;
        }
        let (w, h) = (self.settings.width, self.settings.height);
        let driver = RenderDriver::new(&self.gpu, w, h, "embedded", Box::new(pipeline), Box::new(draw));
        let boxes_driver = || -> Result<Box<dyn Driver>, OitError> {
            let Some(boxes) = &self.boxes else {
                return Err(self.no_boxes());
            };
            boxes.write_boxes_frame(&self.gpu, &self.camera, &self.settings);
            Ok(Box::new(boxes.raster(&self.gpu, w, h, &std::cell::Cell::new(0))))
        };
        let drivers = crate::Drivers { scene: Box::new(driver), boxes: Box::new(boxes_driver) };
        // refused before any pass runs, not at the bounds pass
        if self.boxes.is_none()
            && self.settings.bounds == BoundsMode::Boxes
            && matches!(self.settings.technique, Technique::Bdp { .. } | Technique::Adp)
        {
            return Err(self.no_boxes());
        }
        // mdts's 32-bit words hold no alpha: oit's own scenes give it the objects' mean alpha; an
        // embedded pass does not know the caller's alphas, so it must be told, not guess
        if matches!(self.settings.technique, Technique::Mdts { .. }) && self.settings.alpha.is_none() {
            return Err(OitError::Unsupported {
                backend: "wgpu (embedded pass)".into(),
                what: "mdts: its 32-bit words store no alpha and the embedded pass does not know your \
                       scene's; set `Settings::alpha`, or use mdts64, which stores it"
                    .into(),
            });
        }
        let mut ctx = GpuCtx::new(&self.gpu, &self.scene, &self.camera, &self.settings)?;
        let layers = crate::run_technique(&mut ctx, &drivers)?;
        let mut frame = ctx.finish(RasterPath::Hardware)?;
        frame.layers = layers;
        if let Some(view) = target {
            self.write_target(view.texture(), &frame)?;
        }
        frame.stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(frame)
    }

    /// bdp or adp without the instances' boxes: the error naming what to call.
    fn no_boxes(&self) -> OitError {
        OitError::Unsupported {
            backend: "wgpu (embedded pass)".into(),
            what: format!(
                "{}: its bounds pass draws the instances' bounding boxes, which this pass was not given: \
                 call `OitPass::with_instance_boxes` (or `OitPass::with_scene_geometry` for an oit Scene), \
                 or set `Settings::bounds` to `BoundsMode::Exact`",
                self.settings.technique
            ),
        }
    }

    fn check_target(&self, texture: &wgpu::Texture) -> Result<(), OitError> {
        use wgpu::TextureFormat as F;
        let ok_format =
            matches!(texture.format(), F::Rgba8Unorm | F::Rgba8UnormSrgb | F::Bgra8Unorm | F::Bgra8UnormSrgb);
        let big = texture.width() >= self.settings.width && texture.height() >= self.settings.height;
        if !ok_format || !big || !texture.usage().contains(wgpu::TextureUsages::COPY_DST) {
            return Err(OitError::Device(format!(
                "the target texture is {:?} {}×{} with {:?}: it must be Rgba8/Bgra8 (Unorm or UnormSrgb), at least {}×{}, with COPY_DST",
                texture.format(),
                texture.width(),
                texture.height(),
                texture.usage(),
                self.settings.width,
                self.settings.height
            )));
        }
        Ok(())
    }

    fn write_target(&self, texture: &wgpu::Texture, frame: &Frame) -> Result<(), OitError> {
        let bgra =
            matches!(texture.format(), wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
        let bytes: Vec<u8> = frame
            .image
            .pixels
            .iter()
            .flat_map(|p| if bgra { [p[2], p[1], p[0], p[3]] } else { *p })
            .collect();
        self.gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(frame.image.width * 4),
                rows_per_image: Some(frame.image.height),
            },
            wgpu::Extent3d { width: frame.image.width, height: frame.image.height, depth_or_array_layers: 1 },
        );
        self.gpu.queue.submit([]);
        Ok(())
    }
}

/// An oit [`Scene`] on the user's device in the hardware path's format, for drawing it through an
/// [`OitPass`] with oit's own vertex stage (the shading and transform of `Backend::render` on the
/// hardware path, so the images agree).
///
/// Upload: each mesh's vertices once (position, normal, vertex colour) and per triangle its three
/// vertex indices and its instance, in primitive order, read from storage buffers by vertex index
/// (no vertex buffers); per frame, [`SceneGeometry::write_frame`] writes each instance's
/// `camera.view_proj() · transform`, normal matrix and base colour, and the shading uniform.
///
/// The instances' bounding boxes are uploaded with it too (8 corners and 12 triangles each), for
/// the bounds pass of `bdp` and `adp`: [`OitPass::with_scene_geometry`] hands them (and the
/// scene's bounds and absorption) to a pass, which draws them itself.
///
/// Use: the pipeline's module is `capture.wgsl` followed by [`SceneGeometry::WGSL`], vertex entry
/// point `hw_vs`, fragment entry point `hw_fs`, no vertex buffers, no culling; its layout is the
/// capture's group 0 then [`SceneGeometry::bind_group_layout`] as group 1. In the draw closure, set
/// [`SceneGeometry::bind_group`] at index 1 and draw `0..vertex_count()`.
pub struct SceneGeometry {
    gpu: Gpu,
    geometry: HwGeometry,
    boxes: HwGeometry,
    bounds: Aabb,
    absorption: f32,
}

impl SceneGeometry {
    /// The hardware path's shader (`shaders/raster_hardware.wgsl`): its group 1 bindings, the
    /// vertex stage `hw_vs` (vertex pulled by index, transformed as oit-cpu's setup does) and the
    /// fragment stage `hw_fs` (shading as `Shading::shade`, then `oit_capture_full`).
    pub const WGSL: &'static str = RASTER_WGSL;

    /// Uploads `scene`'s meshes and triangles, and its instances' bounding boxes, to the device
    /// (which must have [`crate::required_features`]).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene) -> Result<SceneGeometry, OitError> {
        let gpu = Gpu::from_device(device.clone(), queue.clone())?;
        let made = std::cell::Cell::new(0);
        let geometry = HwGeometry::new(&gpu, scene, false, &made)?;
        let boxes = HwGeometry::new(&gpu, scene, true, &made)?;
        let absorption = if scene.objects.is_empty() {
            1.0
        } else {
            scene.objects.iter().map(|o| o.absorption).sum::<f32>() / scene.objects.len() as f32
        };
        Ok(SceneGeometry { gpu, geometry, boxes, bounds: scene.bounds(), absorption })
    }

    /// Writes one frame's instance data and shading uniform (`scene` is the one uploaded; the
    /// settings' shading, alpha and colours apply) on the queue.
    pub fn write_frame(&self, scene: &Scene, camera: &Camera, settings: &Settings) {
        self.geometry.write_frame(&self.gpu, scene, camera, settings);
    }

    /// The layout of group 1 of the pipeline.
    pub fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        self.geometry.layout()
    }

    /// Group 1 of the draw.
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        self.geometry.group()
    }

    /// The vertices of the one draw: three per triangle (primitive `t` of the draw is the scene's
    /// primitive `t`).
    pub fn vertex_count(&self) -> u32 {
        self.geometry.vertex_count()
    }
}
