//! The vertex stage of the hardware path for the blend captures, which build their own render
//! pipelines, with the render targets and the occlusion query it keeps for them. Below the
//! context: a [`Driver`](crate::ctx::Driver) hands its stage to a frame, and the blend captures
//! (`technique/`) draw through it.

use std::cell::RefCell;
use std::rc::Rc;

/// The vertex stage of [`HardwareRaster`] for techniques that build their own render pipelines
/// (`technique::{bdp_blend, dp_depth}`): put [`SceneStage::wgsl`] after the technique's group 0
/// declarations, add [`SceneStage::layout`] as group 1, use `hw_vs` as the vertex entry point
/// (its output `HwOut`, and `shade`, serve the fragment stage), and call [`SceneStage::draw`].
#[derive(Clone)]
pub struct SceneStage {
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) group: wgpu::BindGroup,
    pub(crate) vertex_count: u32,
    /// The image size of the rasterizer this stage belongs to, and the render targets its
    /// captures drew into, kept for the next frame of that size ([`SceneStage::target_sampled`]).
    pub(crate) size: (u32, u32),
    pub(crate) targets: Rc<RefCell<Vec<KeptTarget>>>,
    pub(crate) occlusion: Rc<RefCell<Option<Occlusion>>>,
}

/// A render target a [`SceneStage`] keeps: its label, format, samples a pixel and view.
type KeptTarget = (&'static str, wgpu::TextureFormat, u32, wgpu::TextureView);

impl SceneStage {
    /// raster_hardware.wgsl without its fragment entry point (`hw_fs`, which calls the atomics
    /// capture): the group 1 bindings, `HwOut` and `hw_vs`; then `hw_dropped`, the test every
    /// blend capture's fragment stage makes first (oit-shaders' `blend_stage`).
    pub(crate) fn wgsl(&self) -> &'static str {
        oit_shaders::blend_stage()
    }

    /// The layout of group 1 (the vertices, triangles, shading uniform and instances).
    pub(crate) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The render target `label` of `format` and `samples` samples a pixel (one but for a
    /// multisampled blend capture's) at this rasterizer's image size (sampled by a resolve as
    /// well), made on first use and kept: a frame of a size seen before makes none.
    pub(crate) fn target_sampled(
        &self,
        device: &wgpu::Device,
        label: &'static str,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> wgpu::TextureView {
        let mut targets = self.targets.borrow_mut();
        if let Some((.., view)) = targets.iter().find(|(l, f, n, _)| (*l, *f, *n) == (label, format, samples))
        {
            return view.clone();
        }
        let (width, height) = self.size;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        targets.push((label, format, samples, view.clone()));
        view
    }

    /// [`SceneStage::draw`] from indirect arguments (a gated pass's: every triangle, or none).
    pub(crate) fn draw_indirect(&self, rpass: &mut wgpu::RenderPass<'_>, args: &wgpu::Buffer) {
        rpass.set_bind_group(1, &self.group, &[]);
        rpass.draw_indirect(args, 0);
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
    /// A second colour attachment, cleared to 0 (dp's per-sample primitive target).
    pub second: Option<&'a wgpu::TextureView>,
    pub depth: Option<&'a wgpu::TextureView>,
}

/// An occlusion query over one pass, and the buffer its result resolves into (storage too: a
/// gated peel loop folds it into a flag on the device). Made once per [`SceneStage`] and kept.
#[derive(Clone)]
pub(crate) struct Occlusion {
    pub(crate) set: wgpu::QuerySet,
    pub(crate) buffer: wgpu::Buffer,
}

impl Occlusion {
    pub(crate) fn new(device: &wgpu::Device) -> Occlusion {
        let label = "blend capture occlusion";
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some(label),
            ty: wgpu::QueryType::Occlusion,
            count: 1,
        });
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Occlusion { set, buffer }
    }

    /// The last pass's result, resolved on the device.
    pub(crate) fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }
}

impl SceneStage {
    /// This stage's occlusion query and its result buffer, made on first use and kept.
    pub(crate) fn occlusion(&self, device: &wgpu::Device) -> Occlusion {
        self.occlusion.borrow_mut().get_or_insert_with(|| Occlusion::new(device)).clone()
    }
}
