//! The hardware-raster path: the GPU's own rasterizer, through the embeddable pass
//! ([`crate::embed`]) with oit as its user.
//!
//! What is uploaded once, and what per frame: [`HwGeometry`] holds the scene's geometry in its own
//! spaces, uploaded when a prepared scene first draws on this path — each mesh's positions,
//! normals and vertex colours once however many instances place it, and per triangle its three
//! vertex indices and its instance, laid out in primitive order (`scene.primitive_bases()`), so
//! triangle `t` of the one draw is primitive `t`. Per frame only the instances' data is written:
//! `camera.view_proj() * instance.transform`, the normal matrix (`oit_core::setup::normal_matrix`)
//! and the material's base colour (`settings.material_color`), with the shading uniform. The
//! vertex stage (`shaders/raster_hardware.wgsl`) pulls a vertex by vertex index and transforms it
//! with the same matrices, in the same order of operations, as oit-cpu's setup; the fragment
//! stage shades like `Shading::shade` (a texture sampled first) and calls the shared
//! `oit_capture_cut`. The instances'
//! bounding boxes (12 triangles each, for the bounds passes of bdp and adp) are a second
//! [`HwGeometry`] of world-space corners, uploaded on first use, whose per-frame matrix is the
//! view-projection itself; the embedded pass draws the boxes its user gives it
//! (`OitPass::with_instance_boxes`, `OitPass::with_scene_geometry`) with the same upload
//! ([`HwGeometry::boxes`]) and vertex stage. A prepared scene keeps one [`HardwareRaster`] (count
//! target and counter) per image size.
//!
//! The GPU's rasterizer has its own sub-pixel precision and clipping, and the GPU may round the
//! vertex transform differently (a fused multiply-add), so against oit-cpu (and the compute path)
//! only pixels on triangle edges may differ; no culling, no depth test, wgpu's viewport (row 0 at
//! the top, depth in [0, 1]).

use std::cell::{Cell, OnceCell, RefCell};
use std::hash::{DefaultHasher, Hash, Hasher};
use std::rc::Rc;

use oit_core::pulled::{PulledGeometry, PulledInstance};
use oit_core::{Aabb, Camera, OitError, RasterPath, Scene, Settings};
use wgpu::util::DeviceExt;

use crate::ctx::{Driver, Fragments, Gate, Generated, GpuCtx};
use crate::gpu::{COMMON_WGSL, Gpu, count_format};
use crate::stage::SceneStage;

pub(crate) const RASTER_WGSL: &str = oit_shaders::HARDWARE_RASTER;

/// The hardware raster's WGSL as the internal path compiles it (after the capture), its
/// multisampled entry point appended (`HARDWARE_RASTER_MASKED`): oit-shaders' as written, or, where
/// the process runs with `OIT_MUTATION=hardware-drop-third` (a test hook, not a user setting),
/// with a capture that drops every third primitive's fragments: a hardware capture gone wrong by
/// a layer or more, which the conformance checks must catch (`tests/tests/hardware_covered.rs`
/// runs itself under it and requires the failure). Read once per process.
fn raster_wgsl() -> &'static str {
    static WGSL: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    WGSL.get_or_init(|| raster_capture_wgsl() + "\n" + oit_shaders::HARDWARE_RASTER_MASKED)
}

/// [`RASTER_WGSL`], or its mutation ([`raster_wgsl`]).
fn raster_capture_wgsl() -> String {
    match std::env::var("OIT_MUTATION").as_deref() {
        Ok("hardware-drop-third") => {
            // the capture's guard, made to skip every third primitive too; a hook whose pattern
            // is gone would leave the shader as written and the test that needs it passing, so
            // it stops here instead
            let guard = "    if (!hw_culled(in, front)) {";
            assert!(RASTER_WGSL.contains(guard), "hardware-drop-third: the capture guard moved");
            RASTER_WGSL.replacen(guard, "    if (!hw_culled(in, front) && in.prim % 3u != 0u) {", 1)
        }
        _ => RASTER_WGSL.to_owned(),
    }
}
/// What to try when the geometry does not fit in one storage binding.
const GEOMETRY_HINT: &str = "use fewer triangles or instances, or the cpu backend";

/// The fragment side every render-pipeline geometry pass shares (`oit_capture`).
pub const CAPTURE_RENDER_WGSL: &str = oit_shaders::CAPTURE_RENDER;
const COUNT_SUM_WGSL: &str = oit_shaders::text("core/count_sum_texture.wgsl");
/// The same sum over a multisampled count target (every sample of every pixel).
const COUNT_SUM_MS_WGSL: &str = oit_shaders::text("core/count_sum_texture_ms.wgsl");

/// What the user's pipeline for one capture module is built from.
pub struct CaptureShader<'a> {
    /// oit's WGSL: the shared rules, the technique's storage (group 0) and `capture`, and
    /// `oit_capture` / `oit_capture_full`. Put it in front of the user's own WGSL.
    pub wgsl: &'a str,
    /// The layout of group 0 (first in the user's pipeline layout).
    pub bind_group_layout: &'a wgpu::BindGroupLayout,
    /// The pipeline's colour target 0: oit's fragment counter (one channel, additive blending).
    pub count_target: wgpu::ColorTargetState,
    /// The pipeline's multisample state: the count target's samples a pixel (the settings'
    /// `samples`). Above one, the pass is multisampled (docs/msaa.md): the fragment stage takes
    /// `@builtin(sample_mask)` and returns `oit_capture_samples(.., mask)` (its count written at
    /// the first sample it covers, so the target's samples add up to fragments).
    pub multisample: wgpu::MultisampleState,
    /// Which module of the technique this is (passes with the same module share a pipeline).
    pub key: u64,
}

/// One geometry pass, as the user's draw closure sees it.
pub struct GeometryPass<'a> {
    /// 0 for the first geometry pass of the frame, then 1, 2, ...
    pub index: u32,
    /// Group 0 of this pass (already set at index 0 when the closure is called).
    pub bind_group: &'a wgpu::BindGroup,
    /// oit's own draws of a gated pass draw from these indirect arguments (the user's draws,
    /// which oit cannot gate, ignore them: see [`OitPass::record`]).
    pub(crate) indirect: Option<&'a wgpu::Buffer>,
}

pub(crate) type PipelineFn<'a> = Box<dyn FnMut(&CaptureShader<'_>) -> wgpu::RenderPipeline + 'a>;
/// oit's own pipelines of a pass over the opaque depth ([`EarlyDepth`]): the capture's, over
/// `capture.wgsl`, with fragment entry point `depth_fs`, `hw_fs_count` or `hw_fs_early`.
pub(crate) type EarlyPipelineFn<'a> =
    Box<dyn FnMut(&CaptureShader<'_>, &'static str) -> wgpu::RenderPipeline + 'a>;
pub(crate) type DrawFn<'a> = Box<dyn FnMut(&mut wgpu::RenderPass<'_>, &GeometryPass<'_>) + 'a>;

/// A geometry pass on a render pipeline: the user's (or oit's own hardware raster's) pipeline
/// over the capture module, drawn into a one-channel count target. The [`Driver`] both the
/// hardware path and the embedded pass run.
pub(crate) struct RenderDriver<'a> {
    salt: &'static str,
    target: CountTarget,
    pipeline: RefCell<PipelineFn<'a>>,
    draw: RefCell<DrawFn<'a>>,
    /// The indirect draw arguments of oit's own draws (the hardware path's), for gated passes.
    gate: Option<Gate>,
    /// oit's own pipelines over the opaque depth in the fixed-function test (the hardware path's
    /// at one sample, where the device takes `@early_depth_test`; see [`EarlyDepth`]).
    early: Option<RefCell<EarlyPipelineFn<'a>>>,
}

impl<'a> RenderDriver<'a> {
    /// The buffers and textures a [`CountTarget`] is (the count target and the counter it is
    /// summed into), for the counters of prepared scenes.
    pub(crate) const CREATES: u64 = 2;

    /// A driver drawing into `target` (kept by its owner between frames of its size); `salt`
    /// keeps its pipelines apart in the device's cache.
    pub(crate) fn with_target(
        target: CountTarget,
        salt: &'static str,
        pipeline: PipelineFn<'a>,
        draw: DrawFn<'a>,
    ) -> RenderDriver<'a> {
        RenderDriver {
            salt,
            target,
            pipeline: RefCell::new(pipeline),
            draw: RefCell::new(draw),
            gate: None,
            early: None,
        }
    }

    /// The driver testing the opaque depth in the fixed-function unit ([`EarlyDepth`]) with
    /// `early`'s pipelines, where its passes cut at it (oit's own draws: the hardware path).
    pub(crate) fn with_early_depth(mut self, early: EarlyPipelineFn<'a>) -> Self {
        self.early = Some(RefCell::new(early));
        self
    }

    /// The driver drawing from `gate.to` in gated passes (oit's own draws: the hardware path).
    pub(crate) fn with_gate(mut self, gate: Gate) -> Self {
        self.gate = Some(gate);
        self
    }
}

/// A render-pipeline geometry pass's count target (one channel, additive blending) and the
/// counter it is summed into: [`RenderDriver::CREATES`] objects, kept between frames of a size.
#[derive(Clone)]
pub(crate) struct CountTarget {
    format: wgpu::TextureFormat,
    count_view: wgpu::TextureView,
    sum_layout: wgpu::BindGroupLayout,
    sum_group: wgpu::BindGroup,
    total: wgpu::Buffer,
    size: (u32, u32),
    /// Samples a pixel: above 1 a multisampled pass (docs/msaa.md), whose fragments each add 1
    /// at one sample (the first they cover), so the samples add up to fragments.
    samples: u32,
    /// The opaque depth of this size ([`EarlyDepth`]), made on first use.
    depth: Rc<OnceCell<EarlyDepth>>,
}

impl CountTarget {
    /// Its size.
    pub(crate) fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Its samples a pixel.
    pub(crate) fn samples(&self) -> u32 {
        self.samples
    }

    /// A count target of `width × height` and `samples` samples a pixel (1, or a count
    /// [`check_samples`] accepts).
    pub(crate) fn with_samples(gpu: &Gpu, width: u32, height: u32, samples: u32) -> CountTarget {
        let format = count_format(gpu.features);
        let device = &gpu.device;
        let count = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("fragment counts"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: samples,
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
                        multisampled: samples > 1,
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
        CountTarget {
            format,
            count_view,
            sum_layout,
            sum_group,
            total,
            size: (width, height),
            samples,
            depth: Rc::default(),
        }
    }
}

/// Whether the hardware path can draw `samples` samples a pixel on `gpu` (`Ok` at one sample):
/// WebGPU guarantees 4; 8 where the adapter's count target format takes it
/// ([`Gpu::eight_samples`]). Refused by name otherwise.
pub(crate) fn check_samples(gpu: &Gpu, samples: u32) -> Result<(), OitError> {
    let format = count_format(gpu.features);
    let ok = match samples {
        1 | 4 => true,
        8 => gpu.eight_samples,
        _ => false,
    };
    if ok {
        return Ok(());
    }
    Err(OitError::Unsupported {
        backend: "wgpu".into(),
        what: format!(
            "the hardware raster path at --samples {samples}: this adapter's {format:?} count target \
             takes no {samples} samples (WebGPU guarantees 4); use --samples 4 or --raster compute"
        ),
    })
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

/// The opaque pass's depth in the GPU's fixed-function depth test (issue 38): a `Depth32Float`
/// attachment of a count target's size, bound to the hardware path's passes that cut at the
/// opaque depth. Each such pass first draws each pixel's opaque depth into it from the opaque
/// keys (`depth_vs`/`depth_fs` of `core/raster_hardware_early.wgsl`: one triangle, 1.0 where no
/// opaque fragment fell), then its capture (`hw_fs_early`, `@early_depth_test(force)`) tests
/// `LessEqual` against it before the fragment stage, so a fragment behind the opaque depth is
/// neither shaded nor captured; the stage holds back the ties itself, the cut being strict. The
/// frame's first scene pass draws a count-only draw (`hw_fs_count`, behind the opposite test,
/// `Greater`) between the two: it counts the fragments the capture's test drops, and the capture
/// those it passes, each fragment once, with those the cut holds back, by atomic adds to counters
/// of the opaque colours' buffer ([`GpuCtx::drawn_counter`]) and not into the count target,
/// whose blending of every fragment was the dearer part of it. The depths are
/// the keys' high words, the bits of the depth the opaque pass kept, so the test and
/// `opaque_cut` compare the same numbers.
pub(crate) struct EarlyDepth {
    view: wgpu::TextureView,
}

impl EarlyDepth {
    const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

    fn new(gpu: &Gpu, (width, height): (u32, u32)) -> EarlyDepth {
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("opaque depth"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: Self::FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        EarlyDepth { view: texture.create_view(&Default::default()) }
    }

    /// The depth state of the draw of `entry`: the capture's test (`LessEqual`, read only), the
    /// count-only draw's none, the depth draw's write.
    fn state(entry: &str) -> wgpu::DepthStencilState {
        let (write, compare) = match entry {
            "hw_fs_early" | "hw_fs_early_counted" => (false, wgpu::CompareFunction::LessEqual),
            // the count-only draw: what the capture's test drops
            "hw_fs_count" => (false, wgpu::CompareFunction::Greater),
            "depth_fs" => (true, wgpu::CompareFunction::Always),
            _ => (false, wgpu::CompareFunction::Always),
        };
        wgpu::DepthStencilState {
            format: Self::FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }
    }

    /// The depth draw's pipeline over `source` (a capture module with the early entry points),
    /// its group 0 `layout0`: no colour written.
    fn pipeline(
        device: &wgpu::Device,
        source: &str,
        layout0: &wgpu::BindGroupLayout,
        count: wgpu::ColorTargetState,
    ) -> wgpu::RenderPipeline {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("opaque depth"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("opaque depth"),
            bind_group_layouts: &[Some(layout0)],
            immediate_size: 0,
        });
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("opaque depth"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("depth_vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(Self::state("depth_fs")),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("depth_fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState { write_mask: wgpu::ColorWrites::empty(), ..count })],
            }),
            multiview_mask: None,
            cache: None,
        })
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
        self.target.format.hash(&mut h);
        self.target.samples.hash(&mut h);
        let capture = |wgsl| CaptureShader {
            wgsl,
            bind_group_layout: layout0,
            count_target: count_target(self.target.format),
            multisample: wgpu::MultisampleState { count: self.target.samples, ..Default::default() },
            key: module_key,
        };
        // over the opaque depth: the fixed-function test drops what lies behind it before the
        // fragment stage; the frame's first scene pass draws its count-only draw first
        let early = self.early.as_ref().filter(|_| ctx.cuts_at_opaque() && self.target.samples == 1);
        let mut pipelines = Vec::new();
        // whether the pass draws the count-only draw, which counts its fragments in a counter
        // of the opaque colours' buffer rather than in the count target
        let mut drawn = false;
        match early {
            None => {
                pipelines.push(ctx.gpu.render_pipeline(h.finish(), self.salt, || {
                    (self.pipeline.borrow_mut())(&capture(&wgsl))
                })?)
            }
            Some(early) => {
                let early_wgsl = format!("{wgsl}\n{}", oit_shaders::HARDWARE_RASTER_EARLY);
                let mut entries = vec!["depth_fs"];
                if ctx.fragments == Fragments::Unset {
                    entries.push("hw_fs_count");
                    drawn = true;
                }
                // the capture writes its count only where the pass's count is read and no
                // count-only draw counted it
                entries.push(if ctx.count_wanted && !drawn { "hw_fs_early_counted" } else { "hw_fs_early" });
                for entry in entries {
                    let mut e = DefaultHasher::new();
                    (h.finish(), entry).hash(&mut e);
                    pipelines.push(ctx.gpu.render_pipeline(e.finish(), self.salt, || {
                        (early.borrow_mut())(&capture(&early_wgsl), entry)
                    })?);
                }
                self.target.depth.get_or_init(|| EarlyDepth::new(ctx.gpu, self.target.size));
            }
        }
        let depth = early.and_then(|_| self.target.depth.get());
        let index = ctx.passes;
        let indirect = if ctx.gated_pass { self.gate.as_ref().map(|g| &g.to) } else { None };
        let label = ctx.geometry_label;
        let mut encoder = ctx.take_encoder();
        {
            let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.target.count_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                // the opaque depth, drawn by the pass's first draw and tested by its capture
                depth_stencil_attachment: depth.map(|d| wgpu::RenderPassDepthStencilAttachment {
                    view: &d.view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: ctx.render_timestamps(),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            ctx.window_viewport(&mut rpass);
            let mut geometry = pipelines.as_slice();
            if depth.is_some() {
                // the depth draw: one triangle over the whole viewport (a window's viewport holds
                // the target)
                rpass.set_pipeline(&pipelines[0]);
                rpass.set_bind_group(0, group0, &[]);
                rpass.draw(0..3, 0..1);
                geometry = &pipelines[1..];
            }
            for pipeline in geometry {
                rpass.set_pipeline(pipeline);
                rpass.set_bind_group(0, group0, &[]);
                (self.draw.borrow_mut())(&mut rpass, &GeometryPass { index, bind_group: group0, indirect });
            }
        }
        ctx.finish_timed(label, encoder)?;
        if ctx.fragments != Fragments::Unset && !ctx.count_wanted {
            // nothing reads this pass's count (a later pass of the frame, not sized from it): its
            // counter is left as it was, unsummed, as oit-vulkan's passes leave theirs
            return Ok(Generated(self.target.total.clone()));
        }
        if drawn {
            // the count target holds nothing of this pass (its capture adds 0 in a frame's first
            // pass): the count-only draw's counter is the pass's count
            let (rgb, offset) = ctx.drawn_counter();
            let encoder = ctx.encoder();
            encoder.clear_buffer(&self.target.total, 0, None);
            encoder.copy_buffer_to_buffer(&rgb, offset, &self.target.total, 0, 4);
            return Ok(Generated(self.target.total.clone()));
        }
        let sum_wgsl = if self.target.samples > 1 { COUNT_SUM_MS_WGSL } else { COUNT_SUM_WGSL };
        let sum = ctx.gpu.compute_pipeline(sum_wgsl, "count_sum_main", &[&self.target.sum_layout])?;
        let encoder = ctx.encoder();
        encoder.clear_buffer(&self.target.total, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&sum);
            pass.set_bind_group(0, &self.target.sum_group, &[]);
            pass.dispatch_workgroups(self.target.size.0.div_ceil(8), self.target.size.1.div_ceil(8), 1);
        }
        Ok(Generated(self.target.total.clone()))
    }

    fn gate(&self) -> Option<Gate> {
        self.gate.as_ref().map(|g| Gate { from: g.from.clone(), to: g.to.clone(), words: g.words })
    }
}

/// The scene (or its instances' bounding boxes) on the GPU's rasterizer, for one frame: handles
/// to an `HwGeometry`'s buffers and a count target of the frame's size.
#[derive(Clone)]
pub struct HardwareRaster {
    driver: Rc<RenderDriver<'static>>,
    stage: SceneStage,
}

impl HardwareRaster {
    /// Uploads the scene's geometry and sets it up for one frame at `camera` and `settings`, in
    /// buffers of its own (a prepared scene keeps its `HwGeometry` instead).
    pub fn new(gpu: &Gpu, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Self, OitError> {
        let samples = settings.samples.max(1);
        check_samples(gpu, samples)?;
        let made = Cell::new(0);
        let geometry = HwGeometry::new(gpu, scene, false, &made)?;
        geometry.write_frame(gpu, scene, camera, settings);
        Ok(geometry.raster_sampled(gpu, settings.width, settings.height, samples, &made))
    }

    /// The 12 triangles of each instance's world bounding box (`Aabb::TRIANGLES` over the corners
    /// of `scene.instance_bounds`), triangle `t` of instance `i` primitive `12·i + t`, as oit-cpu's
    /// `TriangleSetup::bounding_boxes`: for the bounds passes of bdp and adp.
    pub fn boxes(gpu: &Gpu, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Self, OitError> {
        let made = Cell::new(0);
        let geometry = HwGeometry::new(gpu, scene, true, &made)?;
        geometry.write_frame(gpu, scene, camera, settings);
        Ok(geometry.raster(gpu, settings.width, settings.height, &made))
    }
}

/// The geometry of a scene (or of its instances' bounding boxes) on the GPU, uploaded once (see
/// the module docs): vertices and triangles that never change, and the per-instance buffer and
/// shading uniform that [`HwGeometry::write_frame`] writes each frame.
///
/// Only wgpu handles (no per-size state: that is each [`HardwareRaster`]'s), so it can be shared
/// (`Clone`) and sent between threads, as the embedded pass and [`crate::embed::SceneGeometry`]
/// hold it.
#[derive(Clone)]
pub(crate) struct HwGeometry {
    boxes: bool,
    /// The instances the per-instance buffer holds (one per box for the boxes).
    instance_count: usize,
    instances: wgpu::Buffer,
    uniform: wgpu::Buffer,
    /// Group 1 of the vertex stage and its layout, and the vertices of the one draw.
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    vertex_count: u32,
    /// The one draw's indirect arguments ([vertices, 1, 0, 0]) and their gated copy, for the
    /// gated geometry passes ([`GpuCtx::geometry_pass_if`]).
    draw_args: wgpu::Buffer,
    gated_args: wgpu::Buffer,
    /// A textured scene's textures and per-triangle levels (group 1's binding 4), else `None`
    /// (a placeholder is bound).
    textures: Option<HwTextures>,
}

/// A textured scene's group 1 binding 4 (`hw_tex` in raster_hardware.wgsl): its textures packed
/// from word 0 ([`oit_gpu::TextureRegion`]), uploaded once, then one word a triangle, its
/// level's descriptor, written each frame ([`oit_gpu::triangle_levels`]).
#[derive(Clone)]
struct HwTextures {
    buffer: wgpu::Buffer,
    /// The region, its words dropped once uploaded (what names a level's descriptor).
    region: oit_gpu::TextureRegion,
    /// The word where the per-triangle levels start.
    levels: u32,
}

/// A buffer holding `bytes` (at least 64 bytes: a binding may not be empty), counted in `made`.
fn buffer_init(
    gpu: &Gpu,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
    made: &Cell<u64>,
) -> wgpu::Buffer {
    made.set(made.get() + 1);
    let padded: Vec<u8> = if bytes.is_empty() { vec![0; 64] } else { bytes.to_vec() };
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &padded,
        usage,
    })
}

impl HwGeometry {
    /// Uploads the scene's meshes and triangles (`boxes`: its instances' bounding boxes) and
    /// makes the per-frame buffers; `made` counts the buffers created.
    pub(crate) fn new(gpu: &Gpu, scene: &Scene, boxes: bool, made: &Cell<u64>) -> Result<Self, OitError> {
        let textures = (!boxes && oit_gpu::is_textured(scene)).then_some(&scene.textures[..]);
        HwGeometry::upload(gpu, &PulledGeometry::new(scene, boxes)?, textures, made)
    }

    /// The 12 triangles of each of `bounds` (world-space boxes, one per instance), as
    /// [`PulledGeometry::boxes`] lays them out; `made` counts the buffers created.
    pub(crate) fn boxes(gpu: &Gpu, bounds: &[Aabb], made: &Cell<u64>) -> Result<Self, OitError> {
        HwGeometry::upload(gpu, &PulledGeometry::boxes(bounds)?, None, made)
    }

    /// Uploads `geometry`'s vertices and triangles, and `textures` where the scene samples them
    /// (with room for the per-triangle levels), and makes the per-frame buffers.
    fn upload(
        gpu: &Gpu,
        geometry: &PulledGeometry,
        textures: Option<&[oit_core::Texture]>,
        made: &Cell<u64>,
    ) -> Result<Self, OitError> {
        let (vertices, triangles) = (&geometry.vertices[..], &geometry.triangles[..]);
        let vertex_count = geometry.vertex_count();
        let instance_bytes = geometry.instance_bytes();
        gpu.check_storage_hint("the meshes' vertices", size_of_val(vertices) as u64, GEOMETRY_HINT)?;
        gpu.check_storage_hint("the triangles' indices", size_of_val(triangles) as u64, GEOMETRY_HINT)?;
        gpu.check_storage_hint("the instances' matrices", instance_bytes, GEOMETRY_HINT)?;
        let device = &gpu.device;
        let storage = wgpu::BufferUsages::STORAGE;
        let vertex_buf = buffer_init(gpu, "mesh vertices", bytemuck::cast_slice(vertices), storage, made);
        let triangle_buf = buffer_init(gpu, "triangles", bytemuck::cast_slice(triangles), storage, made);
        made.set(made.get() + 2);
        let instances = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: instance_bytes,
            usage: storage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hardware raster uniform"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = |binding: u32, visibility: wgpu::ShaderStages, ty: wgpu::BufferBindingType| {
            wgpu::BindGroupLayoutEntry {
                binding,
                visibility,
                ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
                count: None,
            }
        };
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hardware raster"),
            entries: &[
                entry(0, wgpu::ShaderStages::VERTEX, read),
                entry(1, wgpu::ShaderStages::VERTEX, read),
                entry(2, wgpu::ShaderStages::VERTEX_FRAGMENT, wgpu::BufferBindingType::Uniform),
                entry(3, wgpu::ShaderStages::VERTEX, read),
                entry(4, wgpu::ShaderStages::VERTEX_FRAGMENT, read),
            ],
        });
        let textures = match textures {
            Some(textures) => {
                let mut region = oit_gpu::TextureRegion::new(textures, 0);
                let levels = region.words.len() as u32;
                let bytes = (region.words.len() + geometry.triangles.len()) as u64 * 4;
                gpu.check_storage_hint("the textures", bytes, "use smaller textures, or the cpu backend")?;
                made.set(made.get() + 1);
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("textures"),
                    size: bytes,
                    usage: storage | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                gpu.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&region.words));
                region.words = Vec::new();
                Some(HwTextures { buffer, region, levels })
            }
            None => None,
        };
        let placeholder;
        let tex_buf = match &textures {
            Some(t) => &t.buffer,
            None => {
                placeholder = buffer_init(gpu, "no textures", &[], storage, made);
                &placeholder
            }
        };
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hardware raster"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: vertex_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: triangle_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: instances.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: tex_buf.as_entire_binding() },
            ],
        });
        let args = [vertex_count, 1, 0, 0];
        let draw_args = buffer_init(gpu, "draw arguments", bytemuck::cast_slice(&args), storage, made);
        let gated_args = buffer_init(
            gpu,
            "gated draw arguments",
            bytemuck::cast_slice(&args),
            storage | wgpu::BufferUsages::INDIRECT,
            made,
        );
        Ok(HwGeometry {
            boxes: geometry.boxes,
            instance_count: geometry.instances,
            instances,
            uniform,
            layout,
            group,
            vertex_count,
            draw_args,
            gated_args,
            textures,
        })
    }

    /// The layout of the vertex stage's group 1.
    pub(crate) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The vertex stage's group 1 (the vertices, triangles, shading uniform and instances).
    pub(crate) fn group(&self) -> &wgpu::BindGroup {
        &self.group
    }

    /// The vertices of the one draw (three per triangle).
    pub(crate) fn vertex_count(&self) -> u32 {
        self.vertex_count
    }

    /// Writes the frame's instance data (`view_proj · transform`, the normal matrix, the base
    /// colour; for the boxes, whose corners are in world space, `view_proj` and the identity) and
    /// the shading uniform: all a frame sends of the geometry.
    pub(crate) fn write_frame(&self, gpu: &Gpu, scene: &Scene, camera: &Camera, settings: &Settings) {
        debug_assert_eq!(self.instance_count, scene.instances.len(), "the scene uploaded");
        let data = oit_core::pulled::instance_data(scene, camera, settings, self.boxes);
        let mut uniform = oit_core::pulled::raster_uniform(camera, settings);
        if let Some(t) = &self.textures {
            let levels = oit_gpu::triangle_levels(scene, camera, settings, &t.region);
            if !levels.is_empty() {
                gpu.queue.write_buffer(&t.buffer, u64::from(t.levels) * 4, bytemuck::cast_slice(&levels));
            }
            (uniform[1], uniform[2]) = (1, t.levels);
        }
        self.write_instances(gpu, &data, &uniform);
    }

    /// Writes the frame's instance data of boxes uploaded by [`HwGeometry::boxes`] without their
    /// scene ([`oit_core::pulled::boxes_data`]).
    pub(crate) fn write_boxes_frame(&self, gpu: &Gpu, camera: &Camera, settings: &Settings) {
        debug_assert!(self.boxes, "boxes uploaded");
        let data = oit_core::pulled::boxes_data(self.instance_count, camera, settings);
        self.write_instances(gpu, &data, &oit_core::pulled::raster_uniform(camera, settings));
    }

    /// Writes `data` into the per-instance buffer and `uniform` into the shading uniform.
    fn write_instances(&self, gpu: &Gpu, data: &[PulledInstance], uniform: &[u32; 8]) {
        if !data.is_empty() {
            gpu.queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(data));
        }
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(uniform));
    }

    /// A rasterizer of this geometry into a `width × height` count target (a texture and a
    /// counter buffer, counted in `made`), drawn with whatever [`HwGeometry::write_frame`] wrote
    /// last.
    pub(crate) fn raster(&self, gpu: &Gpu, width: u32, height: u32, made: &Cell<u64>) -> HardwareRaster {
        self.raster_sampled(gpu, width, height, 1, made)
    }

    /// [`HwGeometry::raster`] at `samples` samples a pixel (a multisampled pass: docs/msaa.md).
    pub(crate) fn raster_sampled(
        &self,
        gpu: &Gpu,
        width: u32,
        height: u32,
        samples: u32,
        made: &Cell<u64>,
    ) -> HardwareRaster {
        made.set(made.get() + RenderDriver::CREATES);
        self.raster_into(gpu, CountTarget::with_samples(gpu, width, height, samples))
    }

    /// [`HwGeometry::raster`] into a count target its owner keeps (of the frame's size).
    pub(crate) fn raster_into(&self, gpu: &Gpu, target: CountTarget) -> HardwareRaster {
        let (width, height) = target.size();
        // the stage of this size, with render targets of its own
        let stage = SceneStage {
            layout: self.layout.clone(),
            group: self.group.clone(),
            vertex_count: self.vertex_count,
            size: (width, height),
            targets: Rc::default(),
            occlusion: Rc::default(),
        };
        let layout1 = stage.layout.clone();
        let pipeline_device = gpu.device.clone();
        let samples = target.samples();
        let pipeline = move |capture: &CaptureShader<'_>| {
            let device = &pipeline_device;
            scene_pipeline_with(
                device,
                "hardware raster",
                &format!("{}\n{}", capture.wgsl, raster_wgsl()),
                &[capture.bind_group_layout, &layout1],
                // a multisampled pass's fragments carry the samples they cover
                if samples > 1 { "hw_fs_masked" } else { "hw_fs" },
                &[Some(capture.count_target.clone())],
                None,
                samples,
            )
        };
        let draw_stage = stage.clone();
        let draw = move |rpass: &mut wgpu::RenderPass<'_>, pass: &GeometryPass<'_>| match pass.indirect {
            Some(args) => draw_stage.draw_indirect(rpass, args),
            None => draw_stage.draw(rpass),
        };
        let gate = Gate { from: self.draw_args.clone(), to: self.gated_args.clone(), words: 4 };
        let mut driver =
            RenderDriver::with_target(target, "hardware", Box::new(pipeline), Box::new(draw)).with_gate(gate);
        if samples == 1 && gpu.features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST) {
            let layout1 = stage.layout.clone();
            let device = gpu.device.clone();
            let early = move |capture: &CaptureShader<'_>, entry: &'static str| {
                let source = format!("{}\n{}", capture.wgsl, raster_wgsl());
                if entry == "depth_fs" {
                    return EarlyDepth::pipeline(
                        &device,
                        &source,
                        capture.bind_group_layout,
                        capture.count_target.clone(),
                    );
                }
                // the count-only draw counts by atomic adds, not into the count target, and the
                // capture's count is that draw's (or not read) unless it is the counted one
                let mut target = capture.count_target.clone();
                if entry == "hw_fs_count" || entry == "hw_fs_early" {
                    target.write_mask = wgpu::ColorWrites::empty();
                }
                scene_pipeline_with(
                    &device,
                    "hardware raster over the opaque depth",
                    &source,
                    &[capture.bind_group_layout, &layout1],
                    entry,
                    &[Some(target)],
                    Some(EarlyDepth::state(entry)),
                    1,
                )
            };
            driver = driver.with_early_depth(Box::new(early));
        }
        HardwareRaster { driver: Rc::new(driver), stage }
    }
}

/// A raster a prepared scene keeps: for the boxes or the scene, its width, height and samples,
/// itself.
type KeptRaster = (bool, u32, u32, u32, HardwareRaster);

/// The hardware path's part of a prepared scene: the scene's [`HwGeometry`] (uploaded when made),
/// the boxes' (uploaded on first use), and a [`HardwareRaster`] per (geometry, image size), so a
/// frame of a size seen before creates no buffer or texture.
pub(crate) struct HardwareScene {
    scene: HwGeometry,
    boxes: OnceCell<HwGeometry>,
    rasters: RefCell<Vec<KeptRaster>>,
}

impl HardwareScene {
    /// Uploads the scene's geometry; `made` counts the buffers created.
    pub(crate) fn new(gpu: &Gpu, scene: &Scene, made: &Cell<u64>) -> Result<Self, OitError> {
        Ok(HardwareScene {
            scene: HwGeometry::new(gpu, scene, false, made)?,
            boxes: OnceCell::new(),
            rasters: RefCell::new(Vec::new()),
        })
    }

    /// The frame's rasterizer of the scene (`boxes`: of its instances' bounding boxes): this
    /// frame's instance data and uniform written, the count target of its size kept or made.
    pub(crate) fn raster(
        &self,
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<HardwareRaster, OitError> {
        let geometry = match (boxes, self.boxes.get()) {
            (false, _) => &self.scene,
            (true, Some(made_before)) => made_before,
            (true, None) => {
                let geometry = HwGeometry::new(gpu, scene, true, made)?;
                self.boxes.get_or_init(|| geometry)
            }
        };
        geometry.write_frame(gpu, scene, camera, settings);
        let (w, h, n) = (settings.width, settings.height, settings.samples.max(1));
        if n > 1 {
            check_samples(gpu, n)?;
        }
        let mut rasters = self.rasters.borrow_mut();
        if let Some((.., raster)) =
            rasters.iter().find(|(b, rw, rh, rn, _)| (*b, *rw, *rh, *rn) == (boxes, w, h, n))
        {
            return Ok(raster.clone());
        }
        let raster = geometry.raster_sampled(gpu, w, h, n, made);
        rasters.push((boxes, w, h, n, raster.clone()));
        Ok(raster)
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
    ) -> Result<Generated, OitError> {
        self.driver.geometry_pass(ctx, source, layout0, group0)
    }

    fn gate(&self) -> Option<Gate> {
        self.driver.gate()
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
    scene_pipeline_with(device, label, source, layouts, fs_entry, targets, depth_stencil, 1)
}

/// [`scene_pipeline`] at `samples` samples a pixel.
#[expect(clippy::too_many_arguments, reason = "a render pipeline's state is that many things")]
pub(crate) fn scene_pipeline_with(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
    fs_entry: &str,
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: Option<wgpu::DepthStencilState>,
    samples: u32,
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
        multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
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
