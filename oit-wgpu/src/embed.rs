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
//! - Two ways to run a frame. [`OitPass::frame`] submits its own command buffers on the queue
//!   and reads the image and stats back (every technique: some read back between passes, counts
//!   to size storage, a peel's stop), so submit what the draws depend on before calling it.
//!   [`OitPass::record`] records the whole frame into the caller's `CommandEncoder` and draws
//!   the image into the caller's target, submitting and reading nothing (the techniques whose
//!   schedule is known up front: `fabs:K`, `mdts:K`, `mdts64:K`, `wavg`, `wsum`, `bdp`, `bdp:P`);
//!   this is the one for a frame loop (`examples/embed.rs` runs one with an orbiting camera and
//!   prints frames per second), and [`OitPass::read_stats`] reads its stats after the submit when
//!   wanted. The pass keeps its storage between frames of a size ([`OitPass::allocations`]).
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
//!   draws the user's geometry like any other pass; the default, `BoundsMode::Auto`, is exact
//!   where the pass has the caller's opaque depth).
//!
//! - The caller's opaque geometry: [`OitPass::with_opaque`] takes the caller's depth buffer
//!   (read, not written) and colour target; every geometry pass cuts the fragments not strictly
//!   in front of that depth (counted in `Stats::occluded`) and the resolve composites over that
//!   colour, as behind oit's own opaque pass. [`SceneGeometry`] takes a scene with opaque parts:
//!   it captures the transparent part and draws the opaque part itself for `with_opaque`
//!   ([`SceneGeometry::draw_opaque`], [`SceneGeometry::draw_opaque_for`]).
//! - Several samples a pixel (`Settings::samples` 4, or 8 where [`OitPass::with_adapter`] finds
//!   the device draws them; docs/msaa.md): oit's count target is then multisampled, and the
//!   user's pipeline takes [`CaptureShader::multisample`] as its multisample state and ends its
//!   fragment shader in `return oit_capture_samples(position.xy, position.z, colour, normal,
//!   prim, mask);` with `mask` its `@builtin(sample_mask)` input (the fragment is shaded once; the
//!   technique composites it into the samples it covers, and its count is written at the first of
//!   them). The techniques and scenes `Backend::render` takes at several samples, the pass takes
//!   (`reference`, `fabs`, `dfb`, `ll`; no opaque image yet); the others are refused by name.
//! - The device needs [`crate::required_features`] and more than wgpu's default 8 storage buffers
//!   a shader stage (ask for the adapter's limits).
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

use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Instant;

use glam::{Vec3, Vec4};
use oit_core::{
    Aabb, BoundsMode, Camera, Frame, Instance, Mesh, OitError, RasterPath, Scene, Settings, Stats, Technique,
};

use crate::ctx::{Driver, GpuCtx};
use crate::gpu::Gpu;
pub use crate::hardware::{CAPTURE_RENDER_WGSL, CaptureShader, GeometryPass};
use crate::hardware::{CountTarget, DrawFn, HwGeometry, PipelineFn, RASTER_WGSL, RenderDriver};
use crate::pool::BufferPool;

const BLIT_WGSL: &str = oit_shaders::text("core/blit.wgsl");
const OPAQUE_LOAD_WGSL: &str = oit_shaders::text("core/opaque_load.wgsl");

/// The caller's opaque image ([`OitPass::with_opaque`]): their depth buffer and, where given, the
/// colour the transparent layers composite over.
struct CallerOpaque {
    depth: wgpu::TextureView,
    color: Option<wgpu::TextureView>,
}

/// oit's capture and resolve, embedded in a wgpu user's frame (see the module docs).
pub struct OitPass {
    gpu: Gpu,
    settings: Settings,
    camera: Camera,
    scene: Scene,
    /// The bounds and absorption the stand-in scene is made of ([`OitPass::with_scene_bounds`]).
    bounds: (Aabb, f32),
    /// The caller's depth and colour, loaded into the frame's opaque image before its passes.
    opaque: Option<CallerOpaque>,
    /// Group 0 of the load of the caller's opaque image, its uniform, a word of zeros (the
    /// opaque fragments oit drew: none) and a 1×1 texture bound where no colour is given.
    load_layout: wgpu::BindGroupLayout,
    load_uniform: wgpu::Buffer,
    zero: wgpu::Buffer,
    no_color: wgpu::TextureView,
    /// The instances' bounding boxes on the device, for the bounds pass of bdp and adp.
    boxes: Option<HwGeometry>,
    /// Per-pixel storage kept between frames: a frame of a size seen before creates none.
    pool: BufferPool,
    /// The count targets of the current size (the scene's, the boxes'), kept between frames.
    target: Mutex<Option<CountTarget>>,
    boxes_target: Mutex<Option<CountTarget>>,
    /// Buffers and textures made outside the pool (count targets, the stats buffer).
    made: AtomicU64,
    /// Where [`OitPass::record`] leaves the totals of its frame, for [`OitPass::read_stats`],
    /// and what that frame counted on the host (passes run whatever, storage bytes).
    stats: wgpu::Buffer,
    recorded: Mutex<Option<(u32, u64)>>,
    /// Group 0 of the image blit of [`OitPass::record`].
    blit_layout: wgpu::BindGroupLayout,
}

/// What [`OitPass::record`] recorded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Recorded {
    /// Geometry passes recorded (the user's draw closure was called this many times).
    pub geometry_passes: u32,
    /// Of those, the passes that have work only where the frame finds it (fabs's overflow passes,
    /// the tails'): [`OitPass::read_stats`] says how many did.
    pub gated_passes: u32,
    /// Bytes of per-pixel storage the frame uses.
    pub storage_bytes: u64,
}

/// A stand-in scene for the frame: what `GpuCtx` reads from a scene (its bounds, which scale the
/// translucency absorption, and the objects' absorption), without triangles; with `opaque`, an
/// opaque object too, so that the frame's plan holds an opaque image (loaded from the caller's,
/// [`OitPass::with_opaque`]) and its passes cut at its depth.
fn stand_in((bounds, absorption): (Aabb, f32), opaque: bool) -> Scene {
    let mesh = Mesh::new("bounds of the embedding scene", vec![bounds.min, bounds.max], Vec::new());
    let mut scene = Scene::from_meshes("embedded", vec![mesh], Vec4::ONE);
    scene.objects[0].absorption = absorption;
    scene.instances = vec![Instance { object: 0, transform: glam::Mat4::IDENTITY }];
    if opaque {
        scene.objects.push(scene.objects[0].clone().opaque());
        scene.instances.push(Instance { object: 1, transform: glam::Mat4::IDENTITY });
    }
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
        let stats = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("recorded totals"),
            size: crate::ctx::TOTALS_BYTES,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let blit_layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("oit image blit"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
            ],
        });
        let compute = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let buffer = |ty| wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None };
        let texture = |sample_type| wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        let load_layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("oit opaque load"),
            entries: &[
                compute(0, buffer(wgpu::BufferBindingType::Uniform)),
                compute(1, texture(wgpu::TextureSampleType::Depth)),
                compute(2, texture(wgpu::TextureSampleType::Float { filterable: false })),
                compute(3, buffer(wgpu::BufferBindingType::Storage { read_only: false })),
                compute(4, buffer(wgpu::BufferBindingType::Storage { read_only: false })),
            ],
        });
        let load_uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("oit opaque load"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // new buffers are zeroed
        let zero = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("no opaque fragments"),
            size: 16,
            usage: wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let no_color = gpu
            .device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("no caller colour"),
                size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&Default::default());
        let bounds = (Aabb { min: -Vec3::ONE, max: Vec3::ONE }, 1.0);
        Ok(OitPass {
            gpu,
            settings,
            camera,
            scene: stand_in(bounds, false),
            bounds,
            opaque: None,
            load_layout,
            load_uniform,
            zero,
            no_color,
            boxes: None,
            pool: BufferPool::default(),
            target: Mutex::new(None),
            boxes_target: Mutex::new(None),
            made: AtomicU64::new(4),
            stats,
            recorded: Mutex::new(None),
            blit_layout,
        })
    }

    /// The world-space bounding boxes of the user's instances, for the bounds pass of `bdp` and
    /// `adp` (with `Settings::bounds` at `BoundsMode::Boxes`, or at its default, `BoundsMode::Auto`,
    /// without the caller's opaque depth): uploaded once, and
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
        self.bounds = (geometry.bounds, geometry.absorption);
        self.scene = stand_in(self.bounds, self.opaque.is_some());
        self.boxes = Some(geometry.boxes.clone());
        self
    }

    /// The world bounds of the user's scene and its absorption coefficient, for the translucency
    /// effect (absorption is per 1/8 of the bounds' radius, as for oit's own scenes). Default: the
    /// box ±1, absorption 1.
    pub fn with_scene_bounds(mut self, bounds: Aabb, absorption: f32) -> OitPass {
        self.bounds = (bounds, absorption);
        self.scene = stand_in(self.bounds, self.opaque.is_some());
        self
    }

    /// The caller's opaque geometry, drawn before the pass: `depth`, a view of their
    /// `Depth32Float` depth buffer, which every geometry pass of the technique tests each
    /// fragment against (a fragment goes on only strictly in front of it, as behind oit's own
    /// opaque pass; what it holds back is counted in `Stats::occluded`), and `color`, their
    /// colour target, which the resolve composites the transparent layers over instead of the
    /// settings' background (without it, over the background, still cut at the depth).
    ///
    /// The depth must be oit's convention, NDC z in [0, 1] with smaller nearer (a standard
    /// `Less` depth test cleared to 1.0, not reversed-Z), drawn with the same `view_proj` as the
    /// camera given to the pass and the user's capture draws, over the same `width × height`
    /// pixels (texel (x, y) is pixel (x, y); the texture may be larger). A pixel the caller left
    /// at the cleared 1.0 cuts only fragments at exactly 1.0, as a `Less` test would. The colour
    /// is read as linear RGB: a `…Srgb` texture is decoded by the load, any other float format
    /// (`Rgba8Unorm`, `Rgba16Float`, `Rgba32Float`, ...) is taken as it is; alpha is ignored.
    ///
    /// Both are read, never written: each frame starts by loading them (a compute pass,
    /// `textureLoad` texel for texel) into the frame's opaque image, the buffers oit's own opaque
    /// pass fills, so every technique's cut and composite run unchanged. They need
    /// `TEXTURE_BINDING` and one sample. The colour may be the texture [`OitPass::record`] then
    /// draws the image into (the copy is taken first): the frame's image replaces the caller's
    /// colour with the transparent layers over it. (Later, a read-only depth attachment with the
    /// hardware depth test could cut fragments before the fragment shader.)
    ///
    /// Views of the caller's textures are kept, so recreate the pass's inputs with
    /// [`OitPass::set_opaque`] when those textures are recreated (a resize).
    ///
    /// ```no_run
    /// # fn demo(device: &wgpu::Device, queue: &wgpu::Queue, settings: oit_core::Settings,
    /// #         camera: oit_core::Camera) -> Result<(), oit_core::OitError> {
    /// let (w, h) = (settings.width, settings.height);
    /// let texture = |format, usage| {
    ///     device.create_texture(&wgpu::TextureDescriptor {
    ///         label: None,
    ///         size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    ///         mip_level_count: 1,
    ///         sample_count: 1,
    ///         dimension: wgpu::TextureDimension::D2,
    ///         format,
    ///         usage,
    ///         view_formats: &[],
    ///     })
    /// };
    /// let both = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    /// let depth = texture(wgpu::TextureFormat::Depth32Float, both).create_view(&Default::default());
    /// let color = texture(wgpu::TextureFormat::Rgba8UnormSrgb, both).create_view(&Default::default());
    /// // ... draw the opaque geometry into `color` and `depth` (depth compare Less, cleared to
    /// // 1.0), submit, then run the pass's frames:
    /// let pass = oit_wgpu::OitPass::new(device, queue, settings, camera)?.with_opaque(&depth, Some(&color))?;
    /// # let _ = pass; Ok(()) }
    /// ```
    pub fn with_opaque(
        mut self,
        depth: &wgpu::TextureView,
        color: Option<&wgpu::TextureView>,
    ) -> Result<OitPass, OitError> {
        self.set_opaque(Some(depth), color)?;
        Ok(self)
    }

    /// Sets (or, with `depth` `None`, removes) the caller's opaque depth and colour of the next
    /// frames, as [`OitPass::with_opaque`] does.
    pub fn set_opaque(
        &mut self,
        depth: Option<&wgpu::TextureView>,
        color: Option<&wgpu::TextureView>,
    ) -> Result<(), OitError> {
        self.opaque = match depth {
            None => None,
            Some(depth) => {
                let opaque = CallerOpaque { depth: depth.clone(), color: color.cloned() };
                self.check_opaque(&opaque)?;
                Some(opaque)
            }
        };
        self.scene = stand_in(self.bounds, self.opaque.is_some());
        Ok(())
    }

    /// What the pass knows of the device's texture formats from `adapter` (the one the device was
    /// opened on, with `wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`): whether its
    /// count target takes 8 samples a pixel ([`OitPass::max_samples`]). Without it, or without
    /// that feature, a pass draws at most 4 (what WebGPU guarantees).
    pub fn with_adapter(mut self, adapter: &wgpu::Adapter) -> OitPass {
        let format = crate::gpu::count_format(self.gpu.features);
        self.gpu.eight_samples =
            self.gpu.features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
                && adapter.get_texture_format_features(format).flags.sample_count_supported(8);
        self
    }

    /// The most samples a pixel the pass draws (`Settings::samples`): 4, or 8 where
    /// [`OitPass::with_adapter`] found the count target's format takes them.
    pub fn max_samples(&self) -> u32 {
        if self.gpu.eight_samples { 8 } else { 4 }
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

    /// The caller's textures against the pass's size and what the load reads.
    fn check_opaque(&self, opaque: &CallerOpaque) -> Result<(), OitError> {
        let (w, h) = (self.settings.width, self.settings.height);
        let check = |what: &str, texture: &wgpu::Texture, ok_format: bool, want: &str| {
            let big = texture.width() >= w && texture.height() >= h;
            let usage = texture.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING);
            if ok_format && big && usage && texture.sample_count() == 1 {
                return Ok(());
            }
            Err(OitError::InvalidSettings(format!(
                "the opaque {what} texture is {:?} {}×{} with {:?}, {} sample(s): it must be {want}, at least {w}×{h}, single-sampled, with TEXTURE_BINDING",
                texture.format(),
                texture.width(),
                texture.height(),
                texture.usage(),
                texture.sample_count()
            )))
        };
        let depth = opaque.depth.texture();
        check("depth", depth, depth.format() == wgpu::TextureFormat::Depth32Float, "Depth32Float")?;
        if let Some(color) = &opaque.color {
            let texture = color.texture();
            let float = matches!(
                texture.format().sample_type(None, None),
                Some(wgpu::TextureSampleType::Float { .. })
            );
            check(
                "colour",
                texture,
                float,
                "a float colour format (Rgba8Unorm[Srgb], Bgra8Unorm[Srgb], Rgba16Float, Rgba32Float, ...)",
            )?;
        }
        Ok(())
    }

    /// Records the load of the caller's opaque image into `ctx`'s frame, before its passes.
    fn load_opaque(&self, ctx: &mut GpuCtx<'_>) -> Result<(), OitError> {
        let Some(opaque) = &self.opaque else {
            return Ok(());
        };
        self.check_opaque(opaque)?;
        let (w, h) = (self.settings.width, self.settings.height);
        let mut uniform = [0u32; 8];
        uniform[..3].copy_from_slice(&[w, h, u32::from(opaque.color.is_some())]);
        for (word, c) in uniform[4..7].iter_mut().zip(self.settings.background.to_array()) {
            *word = c.to_bits();
        }
        self.gpu.queue.write_buffer(&self.load_uniform, 0, bytemuck::cast_slice(&uniform));
        let pipeline =
            self.gpu.compute_pipeline(OPAQUE_LOAD_WGSL, "opaque_load_main", &[&self.load_layout])?;
        let (keys, rgb) = ctx.opaque_image();
        let color = opaque.color.as_ref().unwrap_or(&self.no_color);
        let group = self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("oit opaque load"),
            layout: &self.load_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.load_uniform.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&opaque.depth),
                },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(color) },
                wgpu::BindGroupEntry { binding: 3, resource: keys.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: rgb.as_entire_binding() },
            ],
        });
        {
            let mut cpass = ctx.encoder().begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("oit opaque load"),
                timestamp_writes: None,
            });
            cpass.set_pipeline(&pipeline);
            cpass.set_bind_group(0, &group, &[]);
            cpass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        // oit drew no opaque fragment; the frame's end copies the occluded count beside this
        ctx.note_opaque(&self.zero);
        Ok(())
    }

    /// One frame: the technique's geometry passes (the user's `draw` in each, on the pipeline
    /// `pipeline` builds for that pass's capture module; built once per module and kept), its
    /// resolve, and the image written into `target` when given (an `Rgba8Unorm`, `Rgba8UnormSrgb`,
    /// `Bgra8Unorm` or `Bgra8UnormSrgb` texture at least `width × height`, with `COPY_DST`; the
    /// bytes are sRGB-encoded, as in the PNG oit writes). Returns the frame with its stats, read
    /// back (every technique runs here; see [`OitPass::record`] for a frame that reads nothing).
    pub fn frame(
        &self,
        target: Option<&wgpu::TextureView>,
        pipeline: impl FnMut(&CaptureShader<'_>) -> wgpu::RenderPipeline,
        draw: impl FnMut(&mut wgpu::RenderPass<'_>, &GeometryPass<'_>),
    ) -> Result<Frame, OitError> {
        let start = Instant::now();
        if let Some(view) = target {
            self.check_target(view.texture(), wgpu::TextureUsages::COPY_DST)?;
        }
        self.check_technique()?;
        let drivers = self.drivers(Box::new(pipeline), Box::new(draw));
        let mut ctx =
            GpuCtx::with_pool(&self.gpu, &self.scene, &self.camera, &self.settings, Some(&self.pool))?;
        self.load_opaque(&mut ctx)?;
        crate::technique::run(&mut ctx, &drivers)?;
        let mut frame = ctx.finish(RasterPath::Hardware)?;
        if let Some(view) = target {
            self.write_target(view.texture(), &frame)?;
        }
        frame.stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        // what every backend's frame says where it ends: the packing, the coverage taken
        frame.stats.count_packing(&self.settings);
        Ok(frame)
    }

    /// One frame recorded into the caller's `encoder`, for a real frame loop: the technique's
    /// geometry passes (the user's `draw` in each, as in [`OitPass::frame`]), its resolve, and a
    /// draw of the image into `target` (the first `width × height` texels of an `Rgba8Unorm`,
    /// `Rgba8UnormSrgb`, `Bgra8Unorm` or `Bgra8UnormSrgb` texture with `RENDER_ATTACHMENT`; the
    /// rest is kept). It submits nothing and reads nothing back: submit the encoder as usual, then,
    /// if wanted, [`OitPass::read_stats`]. The image equals [`OitPass::frame`]'s (a `…Srgb`
    /// target stores the same bytes: the draw decodes them and the target encodes them again).
    ///
    /// A frame with no round trip is one whose schedule is known before it runs: `fabs:K`,
    /// `mdts:K` (with `Settings::alpha`), `mdts64:K`, `wavg`, `wsum`, and `bdp`/`bdp:P` (with the
    /// instances' boxes). Where such a frame has work that only some frames have (fabs's two
    /// overflow passes, where a pixel holds more than K fragments; the passes of
    /// `--overflow tail`), those passes are recorded every frame: oit cannot make the user's draws
    /// conditional, so they are drawn, and each fragment of a pixel without such work leaves at
    /// once (the stats count them only where they had work, as oit-cpu does). Every other
    /// technique sizes storage, stops peeling or picks batches from what an earlier pass found,
    /// and is refused with [`OitError::Unsupported`]: use [`OitPass::frame`] for those.
    ///
    /// Queue writes (the frame's uniforms) take effect at the next submission: submit one recorded
    /// frame before recording, or rendering, the next with this pass, as with any uniform written
    /// through `Queue::write_buffer`.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        pipeline: impl FnMut(&CaptureShader<'_>) -> wgpu::RenderPipeline,
        draw: impl FnMut(&mut wgpu::RenderPass<'_>, &GeometryPass<'_>),
    ) -> Result<Recorded, OitError> {
        self.check_target(target.texture(), wgpu::TextureUsages::RENDER_ATTACHMENT)?;
        self.check_technique()?;
        self.check_recordable()?;
        let format = target.texture().format();
        let blit = self.blit_pipeline(format)?;
        let drivers = self.drivers(Box::new(pipeline), Box::new(draw));
        let done = {
            let mut ctx = GpuCtx::recording(
                &self.gpu,
                &self.scene,
                &self.camera,
                &self.settings,
                Some(&self.pool),
                encoder,
            )?;
            self.load_opaque(&mut ctx)?;
            crate::technique::run(&mut ctx, &drivers)?;
            ctx.finish_recorded()?
        };
        // every word: the opaque pass's counters (occluded) lie after the first eight
        encoder.copy_buffer_to_buffer(&done.totals, 0, &self.stats, 0, crate::ctx::TOTALS_BYTES);
        let group = self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("oit image blit"),
            layout: &self.blit_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &done.uniform,
                        offset: 0,
                        size: std::num::NonZeroU64::new(16),
                    }),
                },
                wgpu::BindGroupEntry { binding: 1, resource: done.image.as_entire_binding() },
            ],
        });
        {
            let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("oit image"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let (w, h) = (self.settings.width, self.settings.height);
            rpass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
            rpass.set_scissor_rect(0, 0, w, h);
            rpass.set_pipeline(&blit);
            rpass.set_bind_group(0, &group, &[]);
            rpass.draw(0..3, 0..1);
        }
        let recorded = Recorded {
            geometry_passes: done.passes + done.gated_passes,
            gated_passes: done.gated_passes,
            storage_bytes: done.storage_bytes,
        };
        if let Ok(mut last) = self.recorded.lock() {
            *last = Some((done.passes, done.storage_bytes));
        }
        Ok(recorded)
    }

    /// The stats of the last frame [`OitPass::record`] recorded, once the caller has submitted
    /// it: its totals read back (one round trip, which the frame itself did not make). Wall and
    /// GPU times are not measured in a recorded frame; `lost_pixels` is not kept.
    pub fn read_stats(&self) -> Result<Stats, OitError> {
        let Some((passes, storage_bytes)) = self.recorded.lock().ok().and_then(|r| *r) else {
            return Err(OitError::InvalidSettings("no frame has been recorded with this pass".into()));
        };
        let t = self.gpu.read_u32(&self.stats)?;
        let mut stats = crate::ctx::totals_stats(&t, passes, storage_bytes);
        stats.count_packing(&self.settings);
        stats.check_accounting("wgpu (recorded pass)")?;
        Ok(stats)
    }

    /// Buffers and textures this pass has created for its frames: its per-pixel storage (a
    /// [`BufferPool`]'s), its count targets (the scene's, the boxes'), its stats buffer, and the
    /// uniform, zero word and placeholder texture of the load of [`OitPass::with_opaque`]. A frame
    /// of a size and technique seen before adds none.
    pub fn allocations(&self) -> u64 {
        self.pool.allocations() + self.made.load(Relaxed)
    }

    /// The count target of the pass's size and samples, kept or made.
    fn count_target(&self) -> CountTarget {
        self.kept_target(&self.target, self.settings.width, self.settings.height)
    }

    /// The count target of `kept` if it is `w × h` at the settings' samples a pixel, else a new
    /// one kept there.
    fn kept_target(&self, kept: &Mutex<Option<CountTarget>>, w: u32, h: u32) -> CountTarget {
        let samples = self.settings.samples.max(1);
        let mut kept = kept.lock().unwrap_or_else(|e| e.into_inner());
        match &*kept {
            Some(t) if t.size() == (w, h) && t.samples() == samples => t.clone(),
            _ => {
                self.made.fetch_add(RenderDriver::CREATES, Relaxed);
                let t = CountTarget::with_samples(&self.gpu, w, h, samples);
                *kept = Some(t.clone());
                t
            }
        }
    }

    /// The drivers of a frame: the user's pipeline and draws for the scene, and oit's own draws
    /// of the instances' boxes (made when a bounds pass asks).
    fn drivers<'p>(&'p self, pipeline: PipelineFn<'p>, draw: DrawFn<'p>) -> crate::Drivers<'p> {
        let (w, h) = (self.settings.width, self.settings.height);
        let driver = RenderDriver::with_target(self.count_target(), "embedded", pipeline, draw);
        let boxes_driver = move || -> Result<Box<dyn Driver>, OitError> {
            let Some(boxes) = &self.boxes else {
                return Err(self.no_boxes());
            };
            boxes.write_boxes_frame(&self.gpu, &self.camera, &self.settings);
            Ok(Box::new(boxes.raster_into(&self.gpu, self.kept_target(&self.boxes_target, w, h))))
        };
        crate::Drivers { scene: Box::new(driver), boxes: Box::new(boxes_driver), opaque: None }
    }

    /// The techniques the pass refuses whatever the frame: bdp and adp without boxes, mdts
    /// without an alpha. Checked before any pass runs.
    fn check_technique(&self) -> Result<(), OitError> {
        let samples = self.settings.samples.max(1);
        if samples > self.max_samples() {
            return Err(OitError::Unsupported {
                backend: "wgpu (embedded pass)".into(),
                what: format!(
                    "--samples {samples}: this pass's count target takes {} samples a pixel at most \
                     (WebGPU guarantees 4; 8 where the adapter's format takes them, which \
                     `OitPass::with_adapter` tells the pass)",
                    self.max_samples()
                ),
            });
        }
        if samples > 1 && self.opaque.is_some() {
            // the opaque image is kept a sample above one (docs/msaa.md); the caller's depth and
            // colour are loaded a pixel
            return Err(OitError::Unsupported {
                backend: "wgpu (embedded pass)".into(),
                what: format!(
                    "the caller's opaque depth (`OitPass::with_opaque`) at --samples {samples}: not yet \
                     done (a multisampled depth is not loaded a sample); draw at one sample, or let \
                     oit draw the opaque part (`Backend::render`)"
                ),
            });
        }
        if self.boxes.is_none()
            && self.settings.bounds.resolve(self.scene.has_opaque()) == BoundsMode::Boxes
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
        Ok(())
    }

    /// The techniques whose frames this pass's scene and settings record in one go (fixed K where
    /// a K is taken).
    fn recordable(&self) -> Vec<String> {
        Technique::all()
            .into_iter()
            .map(|t| match t {
                Technique::Fabs { k: None } => Technique::Fabs { k: Some(8) },
                Technique::Mdts { k: None } => Technique::Mdts { k: Some(8) },
                Technique::Mdts64 { k: None } => Technique::Mdts64 { k: Some(8) },
                t => t,
            })
            .filter(|&technique| {
                let settings = Settings { technique, ..self.settings.clone() };
                oit_core::plan::Plan::new("wgpu", &self.scene, &settings)
                    .is_ok_and(|p| p.mid_frame_readback().is_none() && p.refuse_interlock("wgpu", "").is_ok())
            })
            .map(|t| t.to_string())
            .collect()
    }

    /// Whether the technique's frame can be recorded without a round trip ([`OitPass::record`]).
    fn check_recordable(&self) -> Result<(), OitError> {
        let plan = oit_core::plan::Plan::new("wgpu", &self.scene, &self.settings)?;
        plan.refuse_image_atomics("wgpu")?;
        plan.refuse_interlock("wgpu", "WGSL has no fragment shader interlock")?;
        let why = plan.mid_frame_readback();
        match why {
            None => Ok(()),
            Some(why) => Err(OitError::Unsupported {
                backend: "wgpu (recorded pass)".into(),
                what: format!(
                    "{}: {why}, which a frame recorded into your encoder cannot do; use `OitPass::frame`, \
                     or one that records in one go: {}",
                    self.settings.technique,
                    self.recordable().join(", ")
                ),
            }),
        }
    }

    /// The render pipeline drawing the image into a target of `format` (cached per device).
    fn blit_pipeline(
        &self,
        format: wgpu::TextureFormat,
    ) -> Result<std::sync::Arc<wgpu::RenderPipeline>, OitError> {
        let mut h = DefaultHasher::new();
        BLIT_WGSL.hash(&mut h);
        format.hash(&mut h);
        let device = &self.gpu.device;
        let srgb = format.is_srgb();
        self.gpu.render_pipeline(h.finish(), "oit image blit", || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("oit image blit"),
                source: wgpu::ShaderSource::Wgsl(BLIT_WGSL.into()),
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("oit image blit"),
                bind_group_layouts: &[Some(&self.blit_layout)],
                immediate_size: 0,
            });
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("oit image blit"),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("blit_vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(if srgb { "blit_srgb_fs" } else { "blit_fs" }),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        })
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

    fn check_target(&self, texture: &wgpu::Texture, usage: wgpu::TextureUsages) -> Result<(), OitError> {
        use wgpu::TextureFormat as F;
        let ok_format =
            matches!(texture.format(), F::Rgba8Unorm | F::Rgba8UnormSrgb | F::Bgra8Unorm | F::Bgra8UnormSrgb);
        let big = texture.width() >= self.settings.width && texture.height() >= self.settings.height;
        if !ok_format || !big || !texture.usage().contains(usage) || texture.sample_count() != 1 {
            return Err(OitError::Device(format!(
                "the target texture is {:?} {}×{} with {:?}: it must be Rgba8/Bgra8 (Unorm or UnormSrgb), at least {}×{}, single-sampled, with {usage:?}",
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

/// The fragment stage of [`SceneGeometry::draw_opaque`]: a capture that holds nothing back and
/// hands back the shaded colour (clamped to [0, 1], as the captures store it), so `hw_fs`
/// compiles, and an entry point that drops a masked-away fragment (its alpha, the texture's
/// sample included, under its cutoff: `Scene::layers`, `oit_core::pulled::instance_cutoff`) and
/// writes the shaded colour, opaque.
const OPAQUE_DRAW_WGSL: &str = "
fn oit_held_back(xy: vec2<f32>, depth: f32) -> bool {
    return false;
}
fn oit_capture_shaded(xy: vec2<f32>, depth: f32, color: vec4<f32>, normal: vec3<f32>, prim: u32, cutoff: f32, mask: u32) -> vec4<f32> {
    return clamp(color, vec4<f32>(0.0), vec4<f32>(1.0));
}
";
const OPAQUE_FS_WGSL: &str = "
@fragment
fn hw_opaque_fs(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    if (hw_culled(in, front)) {
        discard;
    }
    // as oit's opaque pass (core/opaque.wgsl): the shaded colour, its texture sampled first
    // (`hw_color`), clamped as the capture clamps it; a fragment whose alpha is under its
    // instance's cutoff is masked away (a textured masked object's cutoff, one half for an
    // untextured masked one, whose alpha is 1 or 0; 0 for an opaque one: nothing)
    let color = clamp(hw_color(in), vec4<f32>(0.0), vec4<f32>(1.0));
    if (color.w < in.cutoff) {
        discard;
    }
    return vec4<f32>(color.xyz, 1.0);
}
";

/// The colour format of the opaque part's image ([`SceneGeometry::draw_opaque`]): 32-bit floats,
/// so the colours the pass composites over are the ones oit's own opaque pass keeps.
pub const OPAQUE_COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The opaque part of a scene drawn by [`SceneGeometry::draw_opaque`]: views of its
/// `Depth32Float` depth and [`OPAQUE_COLOR_FORMAT`] colour, of the settings' size, for
/// [`OitPass::with_opaque`] / [`OitPass::set_opaque`]. The textures are the geometry's, kept for
/// the next frames of that size (each draw clears and redraws them).
#[derive(Clone, Debug)]
pub struct OpaqueImage {
    /// The depth (`Less`, cleared to 1.0).
    pub depth: wgpu::TextureView,
    /// The shaded colour (cleared to the settings' background).
    pub color: wgpu::TextureView,
}

/// A scene's opaque part on the device: its geometry, the pipeline that draws it, and the depth
/// and colour of the last size drawn.
struct OpaqueLayer {
    geometry: HwGeometry,
    pipeline: wgpu::RenderPipeline,
    empty_group: wgpu::BindGroup,
    image: Mutex<Option<(u32, u32, OpaqueImage)>>,
}

/// An oit [`Scene`] on the user's device in the hardware path's format, for drawing it through an
/// [`OitPass`] with oit's own vertex stage (the shading and transform of `Backend::render` on the
/// hardware path, so the images agree).
///
/// Upload: each mesh's vertices once (position, normal, vertex colour, texture coordinates) and
/// per triangle its three vertex indices and its instance, in primitive order, read from storage
/// buffers by vertex index (no vertex buffers), and a textured scene's textures (group 1's binding
/// 4); per frame, [`SceneGeometry::write_frame`] writes each instance's
/// `camera.view_proj() · transform`, normal matrix, base colour and cutoff, the shading uniform,
/// and, where the scene is textured, each triangle's texture level (chosen on the host as
/// oit-core's setup chooses it, so it sets the frame's triangles up: a host cost per frame that an
/// untextured scene does not pay).
///
/// A scene with opaque or masked objects is split as every backend splits it
/// ([`Scene::layers`]): its transparent part is the geometry the pass captures (the bind group,
/// the vertex count), and its opaque part is uploaded beside it and drawn by
/// [`SceneGeometry::draw_opaque`] (or [`SceneGeometry::draw_opaque_for`]) into a depth and
/// colour of the geometry's own, which the pass cuts at and composites over
/// ([`OitPass::with_opaque`]): the frame then equals `Backend::render`'s of the whole scene.
///
/// The instances' bounding boxes are uploaded with it too (8 corners and 12 triangles each, the
/// transparent part's), for the bounds pass of `bdp` and `adp`: [`OitPass::with_scene_geometry`]
/// hands them (and the scene's bounds and absorption) to a pass, which draws them itself.
///
/// Use: the pipeline's module is `capture.wgsl` followed by [`SceneGeometry::WGSL`] (and
/// [`SceneGeometry::WGSL_MASKED`] for a multisampled pass), vertex entry point `hw_vs`, fragment
/// entry point [`SceneGeometry::fragment_entry`] (`hw_fs`, or `hw_fs_masked` at several samples),
/// multisample state `capture.multisample`, no vertex buffers, no culling; its layout is the
/// capture's group 0 then [`SceneGeometry::bind_group_layout`] as group 1. In the draw closure, set
/// [`SceneGeometry::bind_group`] at index 1 and draw `0..vertex_count()`.
pub struct SceneGeometry {
    gpu: Gpu,
    geometry: HwGeometry,
    boxes: HwGeometry,
    bounds: Aabb,
    absorption: f32,
    /// Whether the scene has materials: each frame's instance data is then the layers'.
    split: bool,
    /// A textured scene's layers (transparent, opaque) with their meshes, for each frame's
    /// per-triangle texture levels (`oit_gpu::triangle_levels` sets the triangles up on the
    /// host): only where the scene is split and textured; each frame puts its objects and
    /// instances in.
    textured_layers: Option<Mutex<(Scene, Option<Scene>)>>,
    opaque: Option<OpaqueLayer>,
}

impl SceneGeometry {
    /// The hardware path's shader (`shaders/raster_hardware.wgsl`): its group 1 bindings, the
    /// vertex stage `hw_vs` (vertex pulled by index, transformed as oit-cpu's setup does) and the
    /// fragment stage `hw_fs` (where the opaque pass does not hold the fragment back,
    /// `oit_held_back`, shading as `Shading::shade`, then `oit_capture_shaded`).
    pub const WGSL: &'static str = RASTER_WGSL;

    /// The multisampled fragment stage `hw_fs_masked` (core/raster_hardware_masked.wgsl, oit's
    /// own hardware path's), to put after [`SceneGeometry::WGSL`] for a pass at several samples a
    /// pixel ([`CaptureShader::multisample`]): it hands the capture the fragment's
    /// `@builtin(sample_mask)` and writes the count at the first sample it covers.
    pub const WGSL_MASKED: &'static str = oit_shaders::HARDWARE_RASTER_MASKED;

    /// The fragment entry point of a pipeline over `capture`: `hw_fs`, or `hw_fs_masked` (from
    /// [`SceneGeometry::WGSL_MASKED`]) where the pass is multisampled.
    pub fn fragment_entry(capture: &CaptureShader<'_>) -> &'static str {
        if capture.multisample.count > 1 { "hw_fs_masked" } else { "hw_fs" }
    }

    /// Uploads `scene`'s meshes and triangles, and its instances' bounding boxes, to the device
    /// (which must have [`crate::required_features`]).
    ///
    /// A scene with opaque or masked objects or a transmission ([`Scene::has_materials`]) is
    /// uploaded as its layers (`scene.layers(None)`): the transparent part is what the pass's
    /// draws capture, the opaque part what [`SceneGeometry::draw_opaque`] draws.
    ///
    /// A textured scene's textures are uploaded with the part that draws them (packed as the
    /// hardware path packs them, [`oit_gpu::TextureRegion`]), and both stages sample them as
    /// `Backend::render`'s hardware path does: each fragment's colour is its object's base
    /// colour factor times the sample at its texture coordinates, with oit-core's filter, at the
    /// level oit-core's setup chooses per triangle (written each frame by
    /// [`SceneGeometry::write_frame`]); a masked object's fragment under its cutoff is dropped
    /// from the opaque part.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene) -> Result<SceneGeometry, OitError> {
        let gpu = Gpu::from_device(device.clone(), queue.clone())?;
        let made = std::cell::Cell::new(0);
        let layers = scene.layers(None);
        let geometry = HwGeometry::new(&gpu, &layers.transparent, false, &made)?;
        let boxes = HwGeometry::new(&gpu, &layers.transparent, true, &made)?;
        let opaque = match &layers.opaque {
            Some(part) => Some(OpaqueLayer::new(&gpu, HwGeometry::new(&gpu, part, false, &made)?)),
            None => None,
        };
        let absorption = if scene.objects.is_empty() {
            1.0
        } else {
            scene.objects.iter().map(|o| o.absorption).sum::<f32>() / scene.objects.len() as f32
        };
        let textured_layers = (layers.baked && oit_gpu::is_textured(scene))
            .then(|| Mutex::new((layers.transparent.clone().into_owned(), layers.opaque.clone())));
        Ok(SceneGeometry {
            gpu,
            geometry,
            boxes,
            bounds: scene.bounds(),
            absorption,
            split: layers.baked,
            textured_layers,
            opaque,
        })
    }

    /// Writes one frame's instance data and shading uniform (`scene` is the one uploaded; the
    /// settings' shading, alpha and colours apply) on the queue: the transparent part's and,
    /// where the scene has one, the opaque part's. `Settings::alpha` overrides the blended
    /// objects' alpha only, as [`Scene::layers`] does.
    pub fn write_frame(&self, scene: &Scene, camera: &Camera, settings: &Settings) {
        if !self.split {
            self.geometry.write_frame(&self.gpu, scene, camera, settings);
            return;
        }
        // the layers of the scene's objects and instances, without copying its meshes: only the
        // objects' colours and the instances' transforms go into a frame
        let skeleton = Scene {
            name: scene.name.clone(),
            meshes: vec![Mesh::default(); scene.meshes.len()],
            objects: scene.objects.clone(),
            instances: scene.instances.clone(),
            ..Scene::default()
        };
        let layers = skeleton.layers(settings.alpha);
        let drawn = layers.settings(settings);
        if let Some(kept) = &self.textured_layers {
            // the per-triangle texture levels set the triangles up: the layers with their meshes
            // (the same parts, meshes and order as the skeleton's: one split of one scene),
            // this frame's objects and instances put in
            let mut kept = kept.lock().unwrap_or_else(|e| e.into_inner());
            let (transparent, opaque) = &mut *kept;
            let frame_of = |kept: &mut Scene, part: &Scene| {
                kept.objects.clone_from(&part.objects);
                kept.instances.clone_from(&part.instances);
            };
            frame_of(transparent, &layers.transparent);
            self.geometry.write_frame(&self.gpu, transparent, camera, &drawn);
            if let (Some(layer), Some(kept), Some(part)) = (&self.opaque, opaque, &layers.opaque) {
                frame_of(kept, part);
                layer.geometry.write_frame(&self.gpu, kept, camera, &drawn);
            }
            return;
        }
        self.geometry.write_frame(&self.gpu, &layers.transparent, camera, &drawn);
        if let (Some(layer), Some(part)) = (&self.opaque, &layers.opaque) {
            layer.geometry.write_frame(&self.gpu, part, camera, &drawn);
        }
    }

    /// Whether the scene has an opaque part ([`SceneGeometry::draw_opaque`] draws something).
    pub fn has_opaque(&self) -> bool {
        self.opaque.is_some()
    }

    /// Records the draw of the scene's opaque part into `encoder`, at the instance data
    /// [`SceneGeometry::write_frame`] wrote last: oit's vertex stage and shading, into a
    /// `Depth32Float` depth (compare `Less`, cleared to 1.0: the hardware test keeps the first of
    /// equal depths, the lowest primitive id, as oit's opaque pass does) and an
    /// [`OPAQUE_COLOR_FORMAT`] colour (cleared to the settings' background), both of the
    /// settings' size and kept for the next frames of that size. A masked object below its
    /// cutoff is drawn into neither. Returns their views for [`OitPass::with_opaque`], or `None`
    /// where the scene has no opaque part.
    ///
    /// The pass reads them in its frame: [`OitPass::record`] into the same encoder after this;
    /// [`OitPass::frame`] after this encoder is submitted ([`SceneGeometry::draw_opaque_for`]
    /// does both steps for it).
    pub fn draw_opaque(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        settings: &Settings,
    ) -> Option<OpaqueImage> {
        let layer = self.opaque.as_ref()?;
        let image = layer.image(&self.gpu, settings.width.max(1), settings.height.max(1));
        let bg = settings.background.as_dvec3();
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("oit opaque part"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &image.color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r: bg.x, g: bg.y, b: bg.z, a: 1.0 }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &image.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rpass.set_pipeline(&layer.pipeline);
        rpass.set_bind_group(0, &layer.empty_group, &[]);
        rpass.set_bind_group(1, layer.geometry.group(), &[]);
        rpass.draw(0..layer.geometry.vertex_count(), 0..1);
        drop(rpass);
        Some(image)
    }

    /// The opaque part for `pass`'s next [`OitPass::frame`]: drawn at the pass's settings
    /// ([`SceneGeometry::draw_opaque`]), submitted, and given to the pass
    /// ([`OitPass::set_opaque`]); a scene without one removes the pass's opaque image. Call
    /// [`SceneGeometry::write_frame`] first, as for the pass's draws.
    pub fn draw_opaque_for(&self, pass: &mut OitPass) -> Result<(), OitError> {
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("oit opaque part") });
        let image = self.draw_opaque(&mut encoder, pass.settings());
        match image {
            Some(image) => {
                self.gpu.queue.submit([encoder.finish()]);
                pass.set_opaque(Some(&image.depth), Some(&image.color))
            }
            None => pass.set_opaque(None, None),
        }
    }

    /// The layout of group 1 of the pipeline.
    pub fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        self.geometry.layout()
    }

    /// Group 1 of the draw (the transparent part's).
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        self.geometry.group()
    }

    /// The vertices of the one draw: three per triangle of the transparent part (primitive `t` of
    /// the draw is its primitive `t`).
    pub fn vertex_count(&self) -> u32 {
        self.geometry.vertex_count()
    }
}

impl OpaqueLayer {
    fn new(gpu: &Gpu, geometry: HwGeometry) -> OpaqueLayer {
        let device = &gpu.device;
        let empty =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[] });
        let empty_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &empty,
            entries: &[],
        });
        let source = format!("{}\n{OPAQUE_DRAW_WGSL}{RASTER_WGSL}{OPAQUE_FS_WGSL}", crate::gpu::COMMON_WGSL);
        let pipeline = crate::hardware::scene_pipeline(
            device,
            "oit opaque part",
            &source,
            &[&empty, geometry.layout()],
            "hw_opaque_fs",
            &[Some(OPAQUE_COLOR_FORMAT.into())],
            Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
        );
        OpaqueLayer { geometry, pipeline, empty_group, image: Mutex::new(None) }
    }

    /// The depth and colour of `w × h`, kept or made.
    fn image(&self, gpu: &Gpu, w: u32, h: u32) -> OpaqueImage {
        let mut kept = self.image.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((kw, kh, image)) = &*kept
            && (*kw, *kh) == (w, h)
        {
            return image.clone();
        }
        let texture = |label, format| {
            gpu.device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let image = OpaqueImage {
            depth: texture("oit opaque depth", wgpu::TextureFormat::Depth32Float),
            color: texture("oit opaque colour", OPAQUE_COLOR_FORMAT),
        };
        *kept = Some((w, h, image.clone()));
        image
    }
}
