//! `bdp` on the hardware path with `--hardware-capture blend`: the HPG 2009 capture itself, MAX
//! blending into 8 `Rgba32Float` render targets (32 buckets = 8 targets × 4 channels), in
//! `bdp_blend.wgsl`. The same buckets, resolve and storage as the atomics capture (`bdp.rs`,
//! integer `atomicMax` into a storage buffer), so the image and the losses are the same wherever
//! float MAX orders the packed colours as integer MAX does (see `bdp_blend.wgsl`: alpha ≥ 254
//! with blue ≥ 128 packs to an Inf or NaN, alpha ≤ 1 to a denormal; blending those is not exact).
//!
//! Passes: the depth bounds (`bdp::depth_bounds`, shared with the atomics capture), one geometry
//! pass on a render pipeline of oit's scene vertex stage (`hardware::SceneStage`) and the
//! `bdp_blend_fs` fragment stage, then a compute resolve reading the targets. The 8 targets take
//! 128 bytes a sample, every colour attachment byte there is: no room for the fragment counter
//! the other hardware passes blend into, so with `--bounds boxes` (where the bounds pass draws
//! boxes, not the scene) the fragments generated are counted by one extra count-only draw of the
//! scene (additive blending into one channel, no capture; not counted as a geometry pass).
//!
//! Only the colour mode: the depth mode (`bdp:P`, or any effect but transparency) keeps
//! (depth, payload) per subinterval, which float blending cannot carry in one channel; the paper's
//! form (16 pairs (1 − d, d) in 8 targets, MAX-blended) gives depths only, and fetching each
//! subinterval's colours takes a second geometry pass per array matching those depths, which is
//! not built: it is reported as unsupported (the atomics capture runs it).

use oit_core::OitError;

use crate::ctx::{Drivers, GpuCtx, TECHNIQUE_PRELUDE};
use crate::gpu::COMMON_WGSL;
use crate::hardware::scene_pipeline_with;
use crate::stage::SceneStage;

const WGSL: &str = oit_shaders::text("technique/bdp_blend.wgsl");
const TARGETS: u32 = 8;

/// The targets' labels (the stage keeps a target by its label).
const LABELS: [&str; TARGETS as usize] = [
    "bdp bucket target 0",
    "bdp bucket target 1",
    "bdp bucket target 2",
    "bdp bucket target 3",
    "bdp bucket target 4",
    "bdp bucket target 5",
    "bdp bucket target 6",
    "bdp bucket target 7",
];
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // the blend unit returns no previous value to count a collision by where it happens: `lost`
    // is derived, fragments − captured − occluded (the resolve counts the buckets it composites),
    // and says nothing of where (no `lost_pixels`)
    ctx.counts_losses = false;
    let oit_core::Technique::Bdp { passes } = ctx.settings.technique else {
        return Err(OitError::InvalidSettings(format!("{} is not bdp", ctx.settings.technique)));
    };
    let color_mode = ctx.settings.bdp_color_mode(passes)?;
    if !color_mode {
        return Err(unsupported(
            "bdp's depth mode with --hardware-capture blend (float blending holds depths, not the (depth, colour) pairs): use --hardware-capture atomics",
        ));
    }
    let stage = scene_stage(drivers)?;
    if !ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err(unsupported("MAX blending into Rgba32Float targets: the device lacks FLOAT32_BLENDABLE"));
    }
    let per_sample = TARGETS * 16;
    if ctx.gpu.limits.max_color_attachment_bytes_per_sample < per_sample {
        return Err(unsupported(&format!(
            "8 Rgba32Float targets: max_color_attachment_bytes_per_sample is {}, they need {per_sample}",
            ctx.gpu.limits.max_color_attachment_bytes_per_sample
        )));
    }
    check_texture_size(ctx, "the bdp bucket targets")?;
    let samples = ctx.settings.samples;
    super::blend::check_samples(ctx, &[FORMAT])?;
    let mut storage = oit_gpu::technique::Storage::new(ctx, 0);
    let bounds = oit_gpu::technique::depth_bounds(ctx, drivers, &mut storage)?;
    if ctx.fragments == crate::ctx::Fragments::Unset {
        count_fragments(ctx, drivers)?;
    }

    // the plan's colour buckets, in the targets (a pixel's, times its samples: each sample holds
    // the buckets of the fragments written there; `Plan::blend_targets`), kept by the stage: a
    // frame of a size seen before makes none
    let bytes = u64::from(per_sample) * u64::from(samples);
    storage.attachments("colour buckets", bytes)?;
    storage.finish()?;
    let views =
        LABELS.iter().map(|l| ctx.target(stage, l, FORMAT, samples)).collect::<Result<Vec<_>, _>>()?;
    let device = &ctx.gpu.device;
    let (fs, resolve) = (
        oit_gpu::blend_entry("bdp_blend_fs", samples),
        oit_gpu::blend_entry("bdp_blend_resolve_main", samples),
    );

    // the geometry pass
    let (layout0, group0) = ctx.group0(&[&bounds], 0, 0);
    let module_source = format!("{COMMON_WGSL}\n{TECHNIQUE_PRELUDE}{WGSL}\n{}", stage.wgsl());
    let max = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Max,
    };
    let target = wgpu::ColorTargetState {
        format: FORMAT,
        blend: Some(wgpu::BlendState { color: max, alpha: max }),
        write_mask: wgpu::ColorWrites::ALL,
    };
    let pipeline =
        ctx.gpu.render_pipeline(key(&module_source, &format!("bdp blend {samples}")), "bdp blend", || {
            let targets: Vec<Option<wgpu::ColorTargetState>> =
                (0..TARGETS).map(|_| Some(target.clone())).collect();
            scene_pipeline_with(
                device,
                "bdp blend",
                &module_source,
                &[&layout0, stage.layout()],
                &fs,
                &targets,
                None,
                samples,
            )
        })?;
    let mut encoder = ctx.take_encoder();
    {
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment<'_>>> =
            views.iter().map(|view| Some(super::cleared(view, wgpu::Color::TRANSPARENT))).collect();
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("bdp blend"),
            color_attachments: &attachments,
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
    let first = if samples > 1 { 11 } else { 3 };
    let (layout1, group1) = super::targets_group(
        device,
        "bdp bucket targets",
        first,
        &views.iter().collect::<Vec<_>>(),
        samples > 1,
    );
    let (layout0, group0) = ctx.group0(&[&bounds], 0, 0);
    let source = format!("{TECHNIQUE_PRELUDE}{WGSL}\n{}", stage.wgsl());
    let pipeline = ctx.gpu.compute_pipeline(&source, &resolve, &[&layout0, &layout1])?;
    let (x, y) = crate::ctx::dispatch_size(u64::from(ctx.pixels));
    ctx.timed(&resolve, |encoder, timestamps| {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bdp blend resolve"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group0, &[]);
        pass.set_bind_group(1, &group1, &[]);
        pass.dispatch_workgroups(x, y, 1);
    })
}

/// The error for what the blend capture does not do.
pub(crate) fn unsupported(what: &str) -> OitError {
    OitError::Unsupported { backend: "wgpu".into(), what: what.into() }
}

/// oit's own vertex stage of the scene, which the blend capture's pipelines need.
pub(crate) fn scene_stage<'d>(drivers: &'d Drivers<'_>) -> Result<&'d SceneStage, OitError> {
    drivers.scene.scene_stage().ok_or_else(|| {
        unsupported(
            "--hardware-capture blend without oit's own vertex stage (the embedded pass): its pipelines are oit's; use atomics",
        )
    })
}

/// Checks the image size against the texture limit before render targets are made.
pub(crate) fn check_texture_size(ctx: &GpuCtx<'_>, what: &str) -> Result<(), OitError> {
    let limit = ctx.gpu.limits.max_texture_dimension_2d;
    let side = ctx.settings.width.max(ctx.settings.height);
    if side > limit {
        return Err(OitError::TooLarge {
            what: format!(
                "{what} ({}×{} texels; the side counted as bytes)",
                ctx.settings.width, ctx.settings.height
            ),
            needed: u64::from(side),
            limit_name: format!("max_texture_dimension_2d of '{}'", ctx.gpu.info.name),
            limit: u64::from(limit),
            hint: format!(
                "use --size with sides up to {limit}, or --hardware-capture atomics (storage buffers, no textures)"
            ),
        });
    }
    Ok(())
}

/// Counts the scene's fragments with one count-only draw of the hardware driver (its additive
/// fragment counter; the capture does nothing), for passes that cannot count themselves, and
/// those the opaque cut holds back (`occluded`), as a frame's first scene pass does. Not a
/// geometry pass of the technique.
pub(crate) fn count_fragments(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let (layout, group) = ctx.scene_group0(&[], 0, 0);
    let source = format!("{TECHNIQUE_PRELUDE}fn capture(f: Fragment) {{}}\n");
    let generated = drivers.scene.geometry_pass(ctx, &source, &layout, &group)?;
    ctx.note_generated(&generated);
    Ok(())
}

/// A pipeline cache key from the module's source and a name.
pub(crate) fn key(source: &str, name: &str) -> u64 {
    use std::hash::{DefaultHasher, Hash, Hasher};
    let mut h = DefaultHasher::new();
    source.hash(&mut h);
    name.hash(&mut h);
    h.finish()
}
