//! The graphics pipeline's own captures on the hardware path: oit-wgpu's blend captures
//! (`technique/{blend, bdp_blend, dp_depth, ddp_blend}.rs`, the same WGSL) and, beyond them, adp's
//! histogram by logic-op OR, which wgpu cannot express (`shaders/adp_logic.wgsl`).
//!
//! - `plain` always blends on the hardware path (the over operator in one draw, primitive order);
//!   `wavg`/`wsum` with `--hardware-capture blend` (additive blending of the 8-bit integers,
//!   exact while a sum stays below 2^24). Two targets: colour (`--blend-target`: RGBA32F, RGBA16F,
//!   or RGBA8 for plain) and an additive fragment count.
//! - `bdp` (colour mode) with `--hardware-capture blend`: MAX blending into 8 ×
//!   `R32G32B32A32_SFLOAT` (Liu et al., HPG 2009), then a resolve reading the targets.
//! - `dp` with `--hardware-capture blend`: Everitt's depth peeling (2001) with a depth test into a
//!   `D32_SFLOAT` attachment, the previous peel's depth read by pixel, and an occlusion query per
//!   peel that ends the loop.
//! - `ddp` with `--hardware-capture blend`: Bavoil and Myers' dual depth peeling (2008), (−d, d)
//!   MAX-blended into `R32G32_SFLOAT`, an occlusion query per pass.
//! - `adp` with `--hardware-capture blend`: the histogram pass by logic-op OR into 8 ×
//!   `R32G32B32A32_UINT` (the HPG 2009 paper's capture), copied into the storage histogram; the
//!   bucket passes are the atomics capture's.
//!
//! At several samples a pixel `plain`, `wavg`/`wsum` and `bdp` draw multisampled targets
//! (oit-wgpu's, the same `_ms` entry points: docs/msaa.md, "The blend captures at several
//! samples"), and `dp` and `ddp` peel each sample into multisampled depth, layer and range
//! targets (their own `dp_depth_samples.wgsl`, `ddp_blend_samples.wgsl`).
//!
//! The blend unit returns no previous value, so these captures cannot count where they lose a
//! fragment: their `lost` is `fragments − captured − occluded` (as on oit-wgpu); adp's is still
//! counted (its bucket passes are atomics). Where that count could be wrong they refuse the frame,
//! as oit-wgpu does: `dp` and `ddp` at several samples under `--max-peels` before they run, and
//! `ddp` at several samples at the frame's end where two fragments met at one end of a sample's
//! range (`oit_gpu::technique::ddp_blend_sample_state`).
//!
//! Every one of them runs after the opaque pass (`oit_gpu::technique::opaque_first`), and its
//! fragment stage first drops what `hw_dropped` drops (oit-shaders' `core/blend_stage.wgsl`: back
//! faces, and fragments at or behind the opaque depth); the count-only draw counts the latter
//! (`occluded`).

use std::rc::Rc;

use ash::vk;
use oit_core::{BlendTarget, OitError};

use crate::ctx::{BlendPass, Init, VkCtx};
use crate::device::{Blend, Buffer, DepthTest, GpuImage};
use crate::hardware::HardwareRaster;
use crate::raster::{Drivers, Raster};

const RGBA32F: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const RGBA32U: vk::Format = vk::Format::R32G32B32A32_UINT;
const RG32F: vk::Format = vk::Format::R32G32_SFLOAT;
const RG32U: vk::Format = vk::Format::R32G32_UINT;
const R32F: vk::Format = vk::Format::R32_SFLOAT;
const R32U: vk::Format = vk::Format::R32_UINT;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;

fn unsupported(what: String) -> OitError {
    OitError::Unsupported { backend: "vulkan".into(), what }
}

/// The frame's hardware rasterizer (the blend captures draw oit's own vertex stage).
fn hardware<'d>(drivers: &'d Drivers<'_>) -> Result<&'d HardwareRaster, OitError> {
    hardware_raster(&drivers.scene)
}

/// The hardware raster `raster` is, or a refusal.
fn hardware_raster(raster: &Raster) -> Result<&HardwareRaster, OitError> {
    match raster {
        Raster::Hardware(h) => Ok(h),
        Raster::Compute(_) => Err(unsupported("a blend capture on the compute path".into())),
    }
}

/// Refuses a sample count one of the blend targets' `formats` does not take (nothing at one).
fn check_samples(ctx: &VkCtx<'_>, formats: &[vk::Format]) -> Result<(), OitError> {
    let samples = ctx.settings.samples;
    match formats.iter().find(|&&f| !ctx.gpu.takes_samples(f, samples)) {
        None => Ok(()),
        Some(f) => Err(unsupported(format!(
            "{} on the hardware path at --samples {samples}: '{}' has no {samples}-sample {f:?} render target; use --raster compute",
            ctx.settings.technique, ctx.gpu.info.name
        ))),
    }
}

/// Refuses a target format the device cannot blend into (or render to) before anything is made.
fn check_blendable(ctx: &VkCtx<'_>, format: vk::Format, what: &str) -> Result<(), OitError> {
    if ctx.gpu.blendable(format) {
        return Ok(());
    }
    Err(unsupported(format!(
        "{what}: '{}' cannot blend into {format:?}; use --hardware-capture atomics",
        ctx.gpu.info.name
    )))
}

fn clear_f(v: [f32; 4]) -> vk::ClearValue {
    vk::ClearValue { color: vk::ClearColorValue { float32: v } }
}

/// `plain` on the blender (`blend.wgsl`'s `plain_blend_fs`): the over operator, primitive order,
/// into `--blend-target`'s colour target.
pub(crate) fn plain(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let colour = colour_target(ctx.settings.blend_target);
    check_blendable(ctx, colour.0, "plain's blending")?;
    // at several samples each sample blended (`plain_blend_ms_fs`)
    ctx.per_sample_blend = ctx.settings.samples > 1;
    draw_and_resolve(
        ctx,
        drivers,
        colour,
        Blend::Over,
        [0.0, 0.0, 0.0, 1.0],
        ("plain_blend_fs", "plain_blend_resolve_main"),
        0,
    )
}

/// `--blend-target`'s colour format and its bytes a texel.
fn colour_target(target: BlendTarget) -> (vk::Format, u64) {
    match target {
        BlendTarget::F32 => (RGBA32F, 16),
        BlendTarget::F16 => (vk::Format::R16G16B16A16_SFLOAT, 8),
        BlendTarget::Unorm8 => (vk::Format::R8G8B8A8_UNORM, 4),
    }
}

/// `wavg` or `wsum` by additive blending (`blend.wgsl`'s `weighted_blend_fs`): the 8-bit integers
/// into RGBA32F, or α·c and α in [0, 1] into RGBA16F ([`BlendTarget::weighted_param`]).
pub(crate) fn weighted(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let param = ctx.settings.blend_target.weighted_param(ctx.settings.technique)?;
    let colour = colour_target(ctx.settings.blend_target);
    check_blendable(ctx, colour.0, "additive blending for wavg/wsum")?;
    draw_and_resolve(
        ctx,
        drivers,
        colour,
        Blend::Add,
        [0.0; 4],
        ("weighted_blend_fs", "weighted_blend_resolve_main"),
        param,
    )
}

/// One draw into a colour target (`colour`: format and bytes a texel; `color` blending, cleared
/// to `clear`) and an additive count target, then the resolve `entries.1` reading both
/// (blend.wgsl's bindings 8 and 9).
fn draw_and_resolve(
    ctx: &mut VkCtx<'_>,
    drivers: &Drivers<'_>,
    colour: (vk::Format, u64),
    color: Blend,
    clear: [f32; 4],
    entries: (&str, &str),
    param: u32,
) -> Result<(), OitError> {
    let raster = hardware(drivers)?;
    let samples = ctx.settings.samples;
    check_samples(ctx, &[colour.0, R32F])?;
    // at several samples the `_ms` entry points (blend.wgsl), into multisampled targets
    let entries = (oit_gpu::blend_entry(entries.0, samples), oit_gpu::blend_entry(entries.1, samples));
    let color_target = ctx.target_sampled(colour.0, colour.1, false, samples)?;
    let count_target = ctx.target_sampled(R32F, 4, false, samples)?;
    // the frame's fragments counted apart from the blender's count (`captured`, losses counted
    // as 0): the count-only draw the other blend captures run, so that the frame's accounting
    // check can fail where the two disagree (issue 41.10), not `fragments := captured`
    ctx.count_fragments(&drivers.scene)?;
    ctx.blend_pass(
        raster,
        BlendPass {
            module: "blend",
            fs: &entries.0,
            targets: &[&color_target, &count_target],
            blends: &[color, Blend::AddRed],
            clears: &[clear_f(clear), clear_f([0.0; 4])],
            depth: DepthTest::Off,
            previous: &[],
            occlusion: false,
            gated: false,
            pass_index: 0,
            param,
        },
        &[],
    )?;
    let first = if samples > 1 { 10 } else { 8 };
    ctx.image_kernel(
        "blend",
        &entries.1,
        &[],
        &[(first, &color_target), (first + 1, &count_target)],
        0,
        param,
    )
}

/// `bdp`'s colour mode by MAX blending into 8 × `R32G32B32A32_SFLOAT` (`bdp_blend.wgsl`).
pub(crate) fn bdp(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    ctx.counts_losses = false;
    if !ctx.plan.bdp_color {
        return Err(unsupported(
            "bdp's depth mode with --hardware-capture blend (float blending holds depths, not the (depth, colour) pairs): use --hardware-capture atomics".into(),
        ));
    }
    check_blendable(ctx, RGBA32F, "bdp's MAX blending")?;
    let raster = hardware(drivers)?;
    let limit = ctx.gpu.info.limits.max_color_attachments;
    if limit < 8 {
        return Err(unsupported(format!("8 colour targets for bdp: maxColorAttachments is {limit}")));
    }
    let mut storage = oit_gpu::technique::Storage::new(ctx, 0);
    let bounds = oit_gpu::technique::depth_bounds(ctx, drivers, &mut storage)?;
    ctx.count_fragments(&drivers.scene)?;
    // the plan's colour buckets, in the targets (counted as each target is made, a sample each:
    // `Plan::blend_targets`)
    let samples = ctx.settings.samples;
    storage.attachments("colour buckets", 8 * 16 * u64::from(samples))?;
    storage.finish()?;
    check_samples(ctx, &[RGBA32F])?;
    // at several samples each fragment at its first sample, the buckets' MAX over the samples
    // taken by the resolve (`bdp_blend_ms_fs`)
    let targets: Vec<Rc<GpuImage>> =
        (0..8).map(|_| ctx.target_sampled(RGBA32F, 16, false, samples)).collect::<Result<_, _>>()?;
    let views: Vec<&GpuImage> = targets.iter().map(|t| &**t).collect();
    let fs = oit_gpu::blend_entry("bdp_blend_fs", samples);
    ctx.blend_pass(
        raster,
        BlendPass {
            module: "bdp_blend",
            fs: &fs,
            targets: &views,
            blends: &[Blend::Max; 8],
            clears: &[clear_f([0.0; 4]); 8],
            depth: DepthTest::Off,
            previous: &[],
            occlusion: false,
            gated: false,
            pass_index: 0,
            param: 0,
        },
        &[&bounds],
    )?;
    let first = if samples > 1 { 11 } else { 3 };
    let images: Vec<(u32, &GpuImage)> =
        views.iter().enumerate().map(|(i, t)| (first + i as u32, *t)).collect();
    let resolve = oit_gpu::blend_entry("bdp_blend_resolve_main", samples);
    ctx.image_kernel("bdp_blend", &resolve, &[&bounds], &images, 0, 0)
}

/// The pass count of the occlusion-query peel loops (dp, ddp), as oit-wgpu's `OcclusionPeel`:
/// where the frame has a speculated count (an earlier frame's), that many passes are recorded
/// with no round trip, each after the first drawn through the raster's gate, opened by the
/// query of the pass before it (folded into a flag on the device), and the last pass's flag is
/// checked at the frame's end (set: the frame needed more passes and runs again). Else each
/// pass's query is read back, and the count kept for the next frame.
struct OcclusionPeel {
    /// The most passes the loop may run.
    cap: u32,
    /// The speculated count, the flag folded from the last query, and the query's 8 bytes.
    speculated: Option<(u32, Rc<Buffer>, Rc<Buffer>)>,
}

impl OcclusionPeel {
    fn new(ctx: &mut VkCtx<'_>, cap: u32) -> Result<Self, OitError> {
        let speculated = match ctx.speculated.peels.take().filter(|&s| s >= 1) {
            Some(s) => {
                let flag = ctx.scratch("peel gate", 1, Init::Zero)?;
                let query = ctx.scratch("peel query", 2, Init::Zero)?;
                Some((s.min(cap), flag, query))
            }
            None => {
                // the next frame gates: its pipelines made now
                ctx.make_gate_pipeline()?;
                None
            }
        };
        Ok(OcclusionPeel { cap, speculated })
    }

    /// Before pass `run` (from 0): whether it is gated (its gate opened here).
    fn gate(&self, ctx: &mut VkCtx<'_>, raster: &HardwareRaster, run: u32) -> Result<bool, OitError> {
        match &self.speculated {
            Some((_, flag, _)) if run > 0 => {
                ctx.open_gate(raster, flag)?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// After `run` passes, the last one's query recorded: whether the loop goes on.
    fn go_on(&self, ctx: &mut VkCtx<'_>, run: u32) -> Result<bool, OitError> {
        match &self.speculated {
            Some((s, flag, query)) => {
                ctx.fold_occlusion(query, flag)?;
                if run < *s {
                    return Ok(true);
                }
                if run < self.cap {
                    // the last speculated pass must have seen nothing
                    ctx.check_at_end(flag);
                }
                Ok(false)
            }
            None => {
                let drew = run < self.cap && ctx.read_occlusion()? != 0;
                if !drew {
                    ctx.note_peels(run);
                }
                Ok(drew)
            }
        }
    }
}

/// `dp` by Everitt's depth peeling: a depth test into `D32_SFLOAT` against the previous peel's
/// depth (read by pixel, `dp_depth.wgsl`), the layer composited by a kernel; the loop ends at the
/// first peel whose occlusion query sees nothing ([`OcclusionPeel`]).
///
/// At several samples a pixel (per-sample coverage) the targets are multisampled and
/// `dp_depth_samples.wgsl` peels each sample (oit-wgpu's `dp_depth`, the same WGSL): each
/// sample's layer composited into its own accumulator, every pixel finished after the last peel.
pub(crate) fn dp(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    ctx.counts_losses = false;
    let raster = hardware(drivers)?;
    ctx.count_fragments(&drivers.scene)?;
    let samples = ctx.settings.samples;
    let ms = samples > 1;
    // at several samples: the targets a sample (counted as each is made) and each sample's
    // accumulator, at peel_samples.wgsl's binding 5 (2 to 4 unused), the plan's arrays
    let mut buffers: Vec<Rc<Buffer>> = Vec::new();
    if ms {
        check_peel_samples(ctx)?;
        let mut storage = oit_gpu::technique::Storage::new(ctx, 0);
        storage.attachments("peel depths", 8 * u64::from(samples))?;
        storage.attachments("peeled layer", 8 * u64::from(samples))?;
        storage.attachments("peeled primitives", 8 * u64::from(samples))?;
        let acc = storage.buffer(ctx, "sample accumulators", Init::Zero)?;
        storage.finish()?;
        buffers = vec![ctx.placeholder()?, ctx.placeholder()?, ctx.placeholder()?, acc];
    }
    let buffers: Vec<&Buffer> = buffers.iter().map(|b| &**b).collect();
    let (module, peel_fs, composite) = if ms {
        ("dp_depth_samples", "dp_peel_ms_fs", "dp_composite_ms_main")
    } else {
        ("dp_depth", "dp_peel_fs", "dp_composite_main")
    };
    let depths = [ctx.target_sampled(DEPTH, 4, true, samples)?, ctx.target_sampled(DEPTH, 4, true, samples)?];
    let layer = ctx.target_sampled(RG32U, 8, false, samples)?;
    // at several samples: the peeled primitive a sample, ping-ponged as the depths are
    let prims = if ms {
        Some([ctx.target_sampled(R32U, 4, false, samples)?, ctx.target_sampled(R32U, 4, false, samples)?])
    } else {
        None
    };
    // the first peel's "previous" depth is never read, but is bound: readable, if undefined
    ctx.make_readable(&depths[1]);
    if let Some(prims) = &prims {
        ctx.make_readable(&prims[1]);
    }
    let limit = ctx.plan.peel_limit;
    let control = OcclusionPeel::new(ctx, limit)?;
    let mut run = 0;
    loop {
        let slot = (run % 2) as usize;
        let gated = control.gate(ctx, raster, run)?;
        let clear = vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } };
        // at several samples the primitive targets beside the layer, and the depth test that
        // keeps the first drawn of equal depths (ties peeled in primitive order)
        let (targets, previous, depth) = match &prims {
            Some(p) => (
                vec![&*layer, &*p[slot], &*depths[slot]],
                vec![(0, &*depths[1 - slot]), (1, &*p[1 - slot])],
                DepthTest::WriteLess,
            ),
            None => (vec![&*layer, &*depths[slot]], vec![(0, &*depths[1 - slot])], DepthTest::Write),
        };
        let colours = targets.len() - 1;
        ctx.blend_pass(
            raster,
            BlendPass {
                module,
                fs: peel_fs,
                targets: &targets,
                blends: &[Blend::Replace, Blend::Replace][..colours],
                clears: &[clear, clear][..colours],
                depth,
                previous: &previous,
                occlusion: true,
                gated,
                pass_index: run,
                param: 0,
            },
            &buffers,
        )?;
        // a peel that drew nothing left its layer clear: its composite adds nothing
        ctx.image_kernel(module, composite, &buffers, &[(3, &layer), (4, &depths[slot])], run, 0)?;
        run += 1;
        if !control.go_on(ctx, run)? {
            break;
        }
    }
    if ms {
        // every pixel's samples finished over what lies behind them
        ctx.pixel_kernel(module, "dp_finish_ms_main", &buffers, run, 0)?;
    }
    Ok(())
}

/// Refuses a sample count dp's multisampled depth peel cannot take: its `D32_SFLOAT` depth
/// targets and `R32G32_UINT` layer, attached and read back as sampled images (the device's
/// framebuffer and sampled-image sample counts).
fn check_peel_samples(ctx: &VkCtx<'_>) -> Result<(), OitError> {
    let samples = ctx.settings.samples;
    let limits = &ctx.gpu.info.limits;
    let flag = crate::device::sample_count_flags(samples);
    let counts = [
        ("depth attachment", limits.framebuffer_depth_sample_counts),
        ("colour attachment", limits.framebuffer_color_sample_counts),
        ("sampled depth image", limits.sampled_image_depth_sample_counts),
        ("sampled integer image", limits.sampled_image_integer_sample_counts),
    ];
    match counts.iter().find(|(_, c)| !c.contains(flag)) {
        None => Ok(()),
        Some((what, _)) => Err(unsupported(format!(
            "dp with --hardware-capture blend at --samples {samples}: '{}' has no {samples}-sample {what}; use --hardware-capture atomics or --raster compute",
            ctx.gpu.info.name
        ))),
    }
}

/// `ddp` by MAX blending of (−d, d) and occlusion queries (`ddp_blend.wgsl`), its layers
/// composited by `ddp.wgsl`'s resolve; the loop ends after the first pass whose query sees
/// nothing, or after pass `limit` ([`OcclusionPeel`]).
///
/// At several samples a pixel (per-sample coverage) the range targets are multisampled and
/// `ddp_blend_samples.wgsl` peels each sample (oit-wgpu's `ddp_blend`, the same WGSL): each
/// sample's two layers handed over a sample and composited into its own accumulators, every
/// pixel finished after the last pass.
pub(crate) fn ddp(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    ctx.counts_losses = false;
    oit_gpu::technique::check_ddp_effect("vulkan", ctx.settings.effect)?;
    check_blendable(ctx, RG32F, "ddp's MAX blending")?;
    let raster = hardware(drivers)?;
    ctx.count_fragments(&drivers.scene)?;
    let samples = ctx.settings.samples;
    let ms = samples > 1;
    let owned: Vec<Rc<Buffer>> = if ms {
        // per sample: the hand-overs a sample, the count a pixel, the accumulators a sample (the
        // plan's arrays; the range targets counted as each is made)
        check_samples(ctx, &[RG32F])?;
        oit_gpu::technique::ddp_blend_sample_state(ctx)?.into()
    } else {
        oit_gpu::technique::ddp_state(ctx)?.into()
    };
    let buffers: Vec<&Buffer> = owned.iter().map(|b| &**b).collect();
    let (module, peel_fs, resolve) = if ms {
        ("ddp_blend_samples", "ddp_peel_ms_fs", "ddp_resolve_ms_main")
    } else {
        ("ddp_blend", "ddp_peel_fs", "resolve_main")
    };
    if ms {
        ctx.pixel_kernel(module, "ddp_init_ms_main", &buffers, 0, 0)?;
    }
    let ranges =
        [ctx.target_sampled(RG32F, 8, false, samples)?, ctx.target_sampled(RG32F, 8, false, samples)?];
    ctx.make_readable(&ranges[1]);
    let limit = ctx.plan.peel_limit;
    let control = OcclusionPeel::new(ctx, limit.saturating_add(1))?;
    let mut pass = 0u32;
    loop {
        let slot = (pass % 2) as usize;
        let gated = control.gate(ctx, raster, pass)?;
        ctx.blend_pass(
            raster,
            BlendPass {
                module,
                fs: peel_fs,
                targets: &[&ranges[slot]],
                blends: &[Blend::Max],
                clears: &[clear_f([-2.0, -2.0, 0.0, 0.0])],
                depth: DepthTest::Off,
                previous: &[(0, &ranges[1 - slot])],
                occlusion: true,
                gated,
                pass_index: pass,
                param: 0,
            },
            &buffers,
        )?;
        if pass > 0 {
            ctx.pixel_kernel(if ms { module } else { "ddp" }, resolve, &buffers, pass, 0)?;
        }
        if !control.go_on(ctx, pass + 1)? {
            break;
        }
        pass += 1;
    }
    if ms {
        // every pixel's samples finished over what lies behind them
        ctx.pixel_kernel(module, "ddp_finish_ms_main", &buffers, pass, 0)?;
    }
    Ok(())
}

/// `adp`'s histogram pass by logic-op OR into 8 × `R32G32B32A32_UINT` (`adp_logic.wgsl`), copied
/// into `hist`; the caller runs the bucket passes as the atomics capture does.
pub(crate) fn adp_histogram(
    ctx: &mut VkCtx<'_>,
    raster: &Raster,
    buffers: &[&crate::device::Buffer],
) -> Result<(), OitError> {
    let scene = raster;
    let raster = hardware_raster(raster)?;
    if !ctx.gpu.info.logic_op {
        return Err(unsupported(format!(
            "adp's histogram by logic-op OR: '{}' lacks the logicOp feature; use --hardware-capture atomics",
            ctx.gpu.info.name
        )));
    }
    let limit = ctx.gpu.info.limits.max_color_attachments;
    if limit < 8 {
        return Err(unsupported(format!(
            "8 colour targets for adp's histogram: maxColorAttachments is {limit}"
        )));
    }
    // the frame's fragments (and what the opaque cut holds back), which the logic-op pass cannot
    // count, where no pass has counted them yet (`--bounds boxes`): not left to the first bucket
    // pass, which a frame whose every fragment lies behind the opaque depth does not run
    ctx.count_fragments(scene)?;
    let targets: Vec<Rc<GpuImage>> =
        (0..8).map(|_| ctx.target(RGBA32U, 16, false)).collect::<Result<_, _>>()?;
    let views: Vec<&GpuImage> = targets.iter().map(|t| &**t).collect();
    ctx.blend_pass(
        raster,
        BlendPass {
            module: "adp_logic",
            fs: "adp_hist_fs",
            targets: &views,
            blends: &[Blend::LogicOr; 8],
            clears: &[vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } }; 8],
            depth: DepthTest::Off,
            previous: &[],
            occlusion: false,
            gated: false,
            pass_index: 0,
            param: 0,
        },
        buffers,
    )?;
    let images: Vec<(u32, &GpuImage)> = views.iter().enumerate().map(|(i, t)| (3 + i as u32, *t)).collect();
    ctx.image_kernel("adp_logic", "adp_hist_copy_main", buffers, &images, 0, 0)
}
