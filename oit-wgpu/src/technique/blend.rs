//! `plain`, `wavg` and `wsum` through the blend unit, on the hardware path (`blend.wgsl`): the form
//! these techniques take in real renderers. One draw of oit's scene vertex stage
//! ([`SceneStage`]) into two float render targets, a colour target and an additive fragment
//! count, then a compute resolve reading both into the resolve state for the common finish.
//!
//! - `plain` always blends on the hardware path: the blender composites one draw in primitive
//!   order, which is the definition of its submission order (oit-cpu's `technique/plain.rs`), so
//!   there is nothing to sort; `--hardware-capture` does not apply. The colour target is
//!   `--blend-target`'s: `Rgba32Float` by default (with `FLOAT32_BLENDABLE`, else `Rgba16Float`),
//!   `Rgba16Float` or `Rgba8Unorm` (an 8-bit colour buffer, the speed baseline users know). The
//!   over operator in f32, back to front, against oit-cpu's f32 resolve front to back: the same
//!   sum in another association, equal up to f32 rounding (within 1 in 8 bits;
//!   `tests/tests/plain.rs`); the narrower targets' rounding is bounded in
//!   `tests/tests/blend_target.rs`.
//! - `wavg` and `wsum` blend with `--hardware-capture blend` (the atomics capture, 64-bit integer
//!   atomics, stays the default where bit-equality with oit-cpu matters). Additive blending of the
//!   8-bit integers α·r, α·g, α·b and α into `Rgba32Float` (needs `FLOAT32_BLENDABLE`): every
//!   addend is an integer up to 255² and every partial sum an integer, exact in f32 while below
//!   2^24, so up to 258 full-alpha white layers at a pixel the sums equal the atomics capture's
//!   whatever order the blender adds them in, and so does the image. Beyond, each addition rounds
//!   by at most half an ulp: the relative error of a pixel's sum is below n · 2^-24 for n layers.
//!   `--blend-target f16` adds α·c and α in [0, 1] into `Rgba16Float` instead, the accumulation
//!   target of McGuire & Bavoil's weighted blended OIT (JCGT 2013): a relative error below
//!   n · 2^-11 a sum.
//!
//! At several samples a pixel (`--samples 4|8`; docs/msaa.md, "The blend captures at several
//! samples") the targets are multisampled and blend.wgsl's `_ms` entry points run
//! ([`oit_gpu::blend_entry`]): `wavg`/`wsum` write each fragment at the first sample it keeps and
//! the resolve sums the samples (the single target's sums: the coverage fraction exactly);
//! `plain` blends each sample at full alpha and the resolve takes the samples' mean
//! (`coverage: sample`).
//!
//! Storage per pixel: the two targets (20 bytes in f32; 8 + 4 with RGBA16F or RGBA8 colour). The blender loses no
//! fragment: every fragment drawn is counted in the count target and composited (`captured`,
//! losses counted as 0). The frame's fragments are counted apart from it, by the hardware
//! driver's count-only draw the other blend captures run (`bdp_blend::count_fragments`, not a
//! geometry pass of the technique; it counts what the opaque cut holds back as well, which the
//! fragment stage discards uncounted), so `captured + lost + occluded = fragments` is a check the
//! frame can fail (issue 41.10), not `fragments := captured`; both are read with the totals at
//! the end of the frame (no readback between the draws and the resolve). The targets are kept by
//! the frame's rasterizer ([`SceneStage::target_sampled`]), made once per image size.

use oit_core::{BlendTarget, OitError, Technique};

use crate::ctx::{GpuCtx, TECHNIQUE_PRELUDE};
use crate::gpu::COMMON_WGSL;
use crate::hardware::scene_pipeline_with;
use crate::stage::SceneStage;
use crate::technique::bdp_blend::{check_texture_size, key, unsupported};

const WGSL: &str = oit_shaders::text("technique/blend.wgsl");
const WEIGHTED_WGSL: &str = oit_shaders::text("technique/weighted.wgsl");

/// blend.wgsl as this process compiles it: as written, or, under the test hook
/// `OIT_MUTATION=wgpu-blend-count-half` ([`oit_core::mutation`]), with a fragment stage that
/// counts only the even primitives' fragments into the count target: `captured` then falls short
/// of the fragments the count-only draw counted, and the frame's `Stats::check_accounting` must
/// refuse it (the accounting of the blend captures is no longer `fragments := captured`).
fn blend_wgsl() -> std::borrow::Cow<'static, str> {
    const COUNT: &str = "    (*out).count = vec4<f32>(1.0, 0.0, 0.0, 0.0);\n";
    if oit_core::mutation::active("wgpu-blend-count-half") {
        assert!(WGSL.contains(COUNT), "the mutation's text is gone from blend.wgsl");
        let half =
            "    if (in.prim % 2u == 0u) {\n        (*out).count = vec4<f32>(1.0, 0.0, 0.0, 0.0);\n    }\n";
        return WGSL.replacen(COUNT, half, 1).into();
    }
    WGSL.into()
}

/// `plain` on the blender, into the colour target `--blend-target` names.
pub(crate) fn plain(ctx: &mut GpuCtx<'_>, stage: &SceneStage) -> Result<(), OitError> {
    let formats = (colour_target(ctx, "plain's blending")?, count_target(ctx));
    let over = wgpu::BlendState {
        color: wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        },
        alpha: wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        },
    };
    let clear = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 };
    if ctx.settings.samples > 1 {
        // each sample blended (`plain_blend_ms_fs`), its count split over the samples in f32
        if !ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err(unsupported(
                "plain's blender at several samples counts into an R32Float target: the device lacks FLOAT32_BLENDABLE; use --raster compute",
            ));
        }
        ctx.per_sample_blend = true;
    }
    draw_and_resolve(ctx, stage, formats, over, clear, ("plain_blend_fs", "plain_blend_resolve_main"), 0)
}

/// The colour target of `--blend-target`. RGBA32F needs `FLOAT32_BLENDABLE`; without it
/// `plain` falls back to RGBA16F (as it always has) and `wavg`/`wsum` refuse.
fn colour_target(ctx: &GpuCtx<'_>, what: &str) -> Result<wgpu::TextureFormat, OitError> {
    let f32_blend = ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE);
    Ok(match ctx.settings.blend_target {
        BlendTarget::F32 if f32_blend => wgpu::TextureFormat::Rgba32Float,
        BlendTarget::F32 if ctx.settings.technique == Technique::Plain => wgpu::TextureFormat::Rgba16Float,
        BlendTarget::F32 => {
            return Err(unsupported(&format!(
                "{what} into Rgba32Float targets: the device lacks FLOAT32_BLENDABLE; use --blend-target f16 or --hardware-capture atomics"
            )));
        }
        BlendTarget::F16 => wgpu::TextureFormat::Rgba16Float,
        BlendTarget::Unorm8 => wgpu::TextureFormat::Rgba8Unorm,
    })
}

/// The per-pixel fragment count: R32F (exact to 2^24 a pixel) where the device blends f32, else
/// R16F (exact to 2048).
fn count_target(ctx: &GpuCtx<'_>) -> wgpu::TextureFormat {
    if ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        wgpu::TextureFormat::R32Float
    } else {
        wgpu::TextureFormat::R16Float
    }
}

/// `wavg` or `wsum` on the blender, its parameter from [`BlendTarget::weighted_param`]:
/// RGBA32F adds the 8-bit integers, RGBA16F α·c and α in [0, 1], the form weighted blended OIT
/// uses. Either way the count is R32F, exact to 2^24 a pixel (the composite reads it): a device
/// without `FLOAT32_BLENDABLE` is refused rather than given an R16F count that stops at 2048.
pub(crate) fn weighted(ctx: &mut GpuCtx<'_>, stage: &SceneStage) -> Result<(), OitError> {
    let param = ctx.settings.blend_target.weighted_param(ctx.settings.technique)?;
    if !ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err(unsupported(
            "additive blending of wavg/wsum's count into an R32Float target: the device lacks FLOAT32_BLENDABLE; use --hardware-capture atomics",
        ));
    }
    let colour = colour_target(ctx, "additive blending for wavg/wsum")?;
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    draw_and_resolve(
        ctx,
        stage,
        (colour, count_target(ctx)),
        wgpu::BlendState { color: add, alpha: add },
        wgpu::Color::TRANSPARENT,
        ("weighted_blend_fs", "weighted_blend_resolve_main"),
        param,
    )
}

/// Refuses a sample count one of the blend targets' `formats` does not take (nothing at one).
pub(crate) fn check_samples(ctx: &GpuCtx<'_>, formats: &[wgpu::TextureFormat]) -> Result<(), OitError> {
    let samples = ctx.settings.samples;
    match formats.iter().find(|&&f| !ctx.gpu.takes_samples(f, samples)) {
        None => Ok(()),
        Some(f) => Err(unsupported(&format!(
            "{} on the hardware path at --samples {samples}: '{}' has no {samples}-sample {f:?} render target; use --raster compute",
            ctx.settings.technique, ctx.gpu.info.name
        ))),
    }
}

/// The draw into the colour and count targets, and the resolve `entries.1` reading them; at
/// several samples a pixel, `entries`' `_ms` twins into multisampled targets (blend.wgsl).
fn draw_and_resolve(
    ctx: &mut GpuCtx<'_>,
    stage: &SceneStage,
    formats: (wgpu::TextureFormat, wgpu::TextureFormat),
    blend: wgpu::BlendState,
    clear: wgpu::Color,
    entries: (&str, &str),
    param: u32,
) -> Result<(), OitError> {
    check_texture_size(ctx, "the blend targets")?;
    let samples = ctx.settings.samples;
    check_samples(ctx, &[formats.0, formats.1])?;
    // at several samples the `_ms` entry points (blend.wgsl): multisampled targets
    let entries = (oit_gpu::blend_entry(entries.0, samples), oit_gpu::blend_entry(entries.1, samples));
    let device = ctx.gpu.device.clone();
    let color = ctx.target(stage, "blend colour", formats.0, samples)?;
    let count = ctx.target(stage, "blend count", formats.1, samples)?;

    let (layout0, group0) = ctx.group0(&[], 0, param);
    let body = format!("{TECHNIQUE_PRELUDE}{WEIGHTED_WGSL}\n{}\n{}", blend_wgsl(), stage.wgsl());
    let module_source = format!("{COMMON_WGSL}\n{body}");
    let targets = [
        Some(wgpu::ColorTargetState {
            format: formats.0,
            blend: Some(blend),
            write_mask: wgpu::ColorWrites::ALL,
        }),
        Some(wgpu::ColorTargetState {
            format: formats.1,
            blend: Some(wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent::REPLACE,
            }),
            write_mask: wgpu::ColorWrites::RED,
        }),
    ];
    let name = format!("{} {:?} {:?} {samples}", entries.0, formats.0, formats.1);
    let pipeline = ctx.gpu.render_pipeline(key(&module_source, &name), "blend capture", || {
        scene_pipeline_with(
            &device,
            "blend capture",
            &module_source,
            &[&layout0, stage.layout()],
            &entries.0,
            &targets,
            None,
            samples,
        )
    })?;
    let mut encoder = ctx.take_encoder();
    {
        let attachment = |view, clear| Some(super::cleared(view, clear));
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("blend capture"),
            color_attachments: &[attachment(&color, clear), attachment(&count, wgpu::Color::TRANSPARENT)],
            depth_stencil_attachment: None,
            timestamp_writes: ctx.render_timestamps(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        ctx.window_viewport(&mut rpass);
        rpass.set_pipeline(&pipeline);
        rpass.set_bind_group(0, &group0, &[]);
        stage.draw(&mut rpass);
    }
    ctx.finish_timed("geometry", encoder)?;
    ctx.passes += 1;

    // the resolve, reading the targets
    let first = if samples > 1 { 10 } else { 8 };
    let (layout1, group1) =
        super::targets_group(&device, "blend targets", first, &[&color, &count], samples > 1);
    let (layout0, group0) = ctx.group0(&[], 0, param);
    let pipeline = ctx.gpu.compute_pipeline(&body, &entries.1, &[&layout0, &layout1])?;
    let (x, y) = crate::ctx::dispatch_size(u64::from(ctx.pixels));
    ctx.timed(&entries.1, |encoder, timestamps| {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("blend resolve"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group0, &[]);
        pass.set_bind_group(1, &group1, &[]);
        if x > 0 {
            pass.dispatch_workgroups(x, y, 1);
        }
    })
}
