//! What only the wgpu backend does of a technique's frame: the hardware path's own captures
//! under `--hardware-capture blend` (the blender, MAX blending, the depth test; one file each).
//! Every technique's frame otherwise is oit-gpu's (`oit_gpu::technique`), run on [`GpuCtx`]'s
//! implementation of the frame contract (`crate::frame`).

pub(crate) mod bdp_blend;
pub(crate) mod blend;
pub(crate) mod ddp_blend;
pub(crate) mod dp_depth;

use oit_core::{HardwareCapture, OitError, RasterPath, Technique};

use crate::ctx::{Driver, Drivers, Gate, GpuCtx, Init};
use crate::stage::{Occlusion, PassTarget, SceneStage};

/// Runs the frame's technique (geometry passes through `drivers`, kernels, resolve into the
/// state; the reference leaves its per-pixel fragment counts to be read with the frame's end).
/// `Backend::render` and the embedded pass (`embed::OitPass::frame`) both run this.
pub(crate) fn run(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let hardware = drivers.scene.path() == RasterPath::Hardware;
    // the papers' graphics-pipeline capture of bdp and dp, when asked for on the hardware path
    let blend = hardware && ctx.settings.hardware_capture == HardwareCapture::Blend;
    // the blender composites one draw in primitive order: plain's definition, where the draws
    // are oit's own
    let blender = hardware && drivers.scene.scene_stage().is_some();
    let own = match ctx.settings.technique {
        Technique::Dp | Technique::Ddp | Technique::Bdp { .. } => blend,
        Technique::WeightedAverage | Technique::WeightedSum => blend,
        Technique::Plain => blender,
        // kbuf is refused by the frame's context with the plan's reason (Plan::refuse_interlock)
        _ => false,
    };
    if !own {
        return oit_gpu::technique::render(ctx, drivers);
    }
    oit_core::plan::refuse_multisampled_own_capture("wgpu", ctx.settings)?;
    // the opaque pass first, as every frame: the captures' fragment stages cut at its depth
    oit_gpu::technique::opaque_first(ctx, drivers)?;
    match ctx.settings.technique {
        Technique::Dp => dp_depth::render(ctx, drivers),
        Technique::Ddp => ddp_blend::render(ctx, drivers),
        Technique::Bdp { .. } => bdp_blend::render(ctx, drivers),
        Technique::Plain => {
            let stage = bdp_blend::scene_stage(drivers)?;
            counted_apart(ctx, drivers)?;
            blend::plain(ctx, stage)
        }
        // wavg and wsum
        _ => {
            let stage = bdp_blend::scene_stage(drivers)?;
            counted_apart(ctx, drivers)?;
            blend::weighted(ctx, stage)
        }
    }
}

/// The frame's fragments counted by the hardware driver's count-only draw, apart from the
/// blender's own count (`captured`) of `plain`, `wavg` and `wsum` on the blend unit, with those
/// the opaque cut holds back (`occluded`): `captured + occluded` must equal them, and the frame's
/// accounting check sees it where they do not (issue 41.10).
fn counted_apart(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    if ctx.fragments == crate::ctx::Fragments::Unset {
        bdp_blend::count_fragments(ctx, drivers)?;
    }
    Ok(())
}

/// The pass count of the blend captures' peel loops (`dp_depth`, `ddp_blend`), which end at the
/// first pass whose occlusion query saw no sample. As [`peel`] does for the atomics captures:
/// where the frame has a speculated pass count and the raster a gate, that many passes are
/// recorded with no round trip, each after the first gated on the query of the one before
/// (folded into a flag on the device), and the last pass's query checked at the frame's end (a
/// frame that needed more passes runs again). Else the query is read after each pass and the
/// count kept for the next frame.
pub(crate) struct OcclusionPeel {
    /// The most passes the loop may run.
    cap: u32,
    /// The speculated count, the flag folded from the last query and the raster's gate.
    speculated: Option<(u32, wgpu::Buffer, Gate)>,
}

impl OcclusionPeel {
    pub(crate) fn new(ctx: &mut GpuCtx<'_>, driver: &dyn Driver, cap: u32) -> Result<Self, OitError> {
        let speculated = match (ctx.speculated_peels.take().filter(|&s| s >= 1), driver.gate()) {
            (Some(s), Some(gate)) => {
                let flag = ctx.scratch("peel gate", 1, Init::Zero)?;
                Some((s.min(cap), flag, gate))
            }
            _ => None,
        };
        Ok(OcclusionPeel { cap, speculated })
    }

    /// Before pass `run` (from 0): the gated draw arguments it draws with, where it is gated.
    pub(crate) fn gate(&self, ctx: &mut GpuCtx<'_>, run: u32) -> Result<Option<wgpu::Buffer>, OitError> {
        match &self.speculated {
            Some((_, flag, gate)) if run > 0 => {
                ctx.open_gate(flag, gate)?;
                Ok(Some(gate.to.clone()))
            }
            _ => Ok(None),
        }
    }

    /// After `run` passes, the last one's query in `occlusion`: whether the loop goes on.
    pub(crate) fn go_on(
        &self,
        ctx: &mut GpuCtx<'_>,
        occlusion: &Occlusion,
        run: u32,
    ) -> Result<bool, OitError> {
        match &self.speculated {
            Some((s, flag, _)) => {
                ctx.fold_occlusion(occlusion.buffer(), flag)?;
                if run < *s {
                    return Ok(true);
                }
                if run < self.cap {
                    // the last speculated pass must have seen nothing
                    ctx.check_at_end(flag, 0);
                }
                Ok(false)
            }
            None => {
                let drew = run < self.cap && drew(occlusion, ctx)?;
                if !drew {
                    ctx.peels_seen = Some(run);
                }
                Ok(drew)
            }
        }
    }
}

/// Group 1 of a resolve that reads a blend capture's render targets: `views` as unfilterable
/// float textures at bindings `first`, `first + 1`, ... (bdp's 8 bucket targets, plain's and the
/// weighted blends' colour and count targets), multisampled textures where `multisampled`.
pub(crate) fn targets_group(
    device: &wgpu::Device,
    label: &str,
    first: u32,
    views: &[&wgpu::TextureView],
    multisampled: bool,
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0..views.len() as u32)
        .map(|i| wgpu::BindGroupLayoutEntry {
            binding: first + i,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled,
            },
            count: None,
        })
        .collect();
    let layout = device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &views
            .iter()
            .enumerate()
            .map(|(i, view)| wgpu::BindGroupEntry {
                binding: first + i as u32,
                resource: wgpu::BindingResource::TextureView(view),
            })
            .collect::<Vec<_>>(),
    });
    (layout, group)
}

/// A colour attachment of a blend capture's pass: `view`, cleared to `clear`, stored.
pub(crate) fn cleared(view: &wgpu::TextureView, clear: wgpu::Color) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
    }
}

/// One geometry pass of a blend capture (`technique::{dp_depth, ddp_blend}`): `pipeline`
/// draws the scene into `target` with `groups` set as groups 0 and 2, inside `occlusion`'s
/// query, resolved into its buffer; timed and counted as a geometry pass. `gated`: the draw's
/// indirect arguments, where a gate left them (every triangle, or none).
pub(crate) fn occlusion_pass(
    stage: &SceneStage,
    ctx: &mut GpuCtx<'_>,
    pipeline: &wgpu::RenderPipeline,
    groups: (&wgpu::BindGroup, &wgpu::BindGroup),
    target: PassTarget<'_>,
    occlusion: &Occlusion,
    gated: Option<&wgpu::Buffer>,
) -> Result<(), OitError> {
    let mut encoder = ctx.take_encoder();
    {
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(target.label),
            color_attachments: &[
                Some(cleared(target.color, target.clear)),
                target.second.map(|view| cleared(view, wgpu::Color::TRANSPARENT)),
            ][..1 + usize::from(target.second.is_some())],
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
        ctx.window_viewport(&mut rpass);
        rpass.set_pipeline(pipeline);
        rpass.set_bind_group(0, groups.0, &[]);
        rpass.set_bind_group(2, groups.1, &[]);
        rpass.begin_occlusion_query(0);
        match gated {
            Some(args) => stage.draw_indirect(&mut rpass, args),
            None => stage.draw(&mut rpass),
        }
        rpass.end_occlusion_query();
    }
    encoder.resolve_query_set(&occlusion.set, 0..1, &occlusion.buffer, 0);
    ctx.finish_timed("geometry", encoder)?;
    ctx.passes += 1;
    Ok(())
}

/// Whether any sample of the last pass passed: read back now (a round trip).
pub(crate) fn drew(occlusion: &Occlusion, ctx: &mut GpuCtx<'_>) -> Result<bool, OitError> {
    Ok(ctx.read_u32(&occlusion.buffer)?.iter().any(|&s| s != 0))
}
