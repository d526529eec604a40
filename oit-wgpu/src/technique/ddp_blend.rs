//! `ddp` on the hardware path with `--hardware-capture blend`: dual depth peeling as Bavoil and
//! Myers (2008) built it, on the blend unit, in `ddp_blend.wgsl`. Each pass MAX-blends (−d, d)
//! of the fragments strictly inside the previous pass's range into an Rg32Float target (two,
//! ping-ponged: one is this pass's target, the other the previous pass's range, read by pixel);
//! the fragments on the previous range's two ends hand their payloads over with the atomics
//! capture's keys, and `ddp.wgsl`'s resolve composites them (near layer to the front, far layer
//! to the back). An occlusion query over each pass, read back after it, says whether anything is
//! left inside the range.
//!
//! Against the atomics capture (`ddp.rs`): the same layers, keys, losses and image; the same
//! ⌈N/2⌉ + 1 geometry passes when peeling runs to the end, and one more under
//! `settings.max_peels` (the payloads of the pairs a pass finds arrive in the next pass). Needs
//! `FLOAT32_BLENDABLE` (MAX blending of 32-bit floats).
//!
//! Storage per pixel: the atomics capture's 24 bytes (near and far keys, range) and the two
//! Rg32Float targets, 16 bytes.
//!
//! At several samples a pixel (`--samples 4|8`, per-sample coverage; docs/msaa.md, "The blend
//! captures at several samples") the same loop peels each sample: the range targets are
//! multisampled, `ddp_blend_samples.wgsl`'s `ddp_peel_ms_fs` blends each fragment at the samples
//! it keeps inside that sample's previous range and hands it over where it lies on one of the
//! sample's ends, and its resolve composites each sample's two layers into that sample's front
//! and back accumulators; a last kernel finishes every pixel's samples over their opaque colours.
//! Storage: the plan's (`Plan::blend_targets`): the two range targets a sample, the near and far
//! hand-overs and the accumulators a sample, and a count a pixel.

use oit_core::OitError;

use crate::ctx::{Drivers, GpuCtx, TECHNIQUE_PRELUDE};
use crate::gpu::COMMON_WGSL;
use crate::hardware::scene_pipeline_with;
use crate::stage::PassTarget;
use crate::technique::OcclusionPeel;
use crate::technique::bdp_blend::{check_texture_size, count_fragments, key, scene_stage, unsupported};

const WGSL: &str = oit_shaders::text("technique/ddp_blend.wgsl");
/// ddp.wgsl, whose resolve composites the layers the blend capture peels.
const DDP_WGSL: &str = oit_shaders::text("technique/ddp.wgsl");
/// At several samples: the per-sample accumulators, then the per-sample dual peel.
const SAMPLES_WGSL: [&str; 2] =
    [oit_shaders::text("technique/peel_samples.wgsl"), oit_shaders::text("technique/ddp_blend_samples.wgsl")];
const RANGE: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // the blend unit returns no previous value to count a loss by where it happens: `lost` is
    // derived, fragments − captured − occluded, and says nothing of where (no `lost_pixels`).
    // Exact, as the resolve counts what it composites; at several samples each fragment counts
    // itself handed over, which a tie at a sample's range end would make wrong, so a frame that
    // meets one fails at its end (`oit_gpu::technique::ddp_blend_sample_state`), and
    // `--max-peels` there is refused before this runs
    ctx.counts_losses = false;
    oit_gpu::technique::check_ddp_effect("wgpu", ctx.settings.effect)?;
    let stage = scene_stage(drivers)?;
    if !ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err(unsupported("MAX blending into an Rg32Float target: the device lacks FLOAT32_BLENDABLE"));
    }
    check_texture_size(ctx, "the ddp range targets")?;
    if ctx.fragments == crate::ctx::Fragments::Unset {
        count_fragments(ctx, drivers)?;
    }
    let samples = ctx.settings.samples;
    let ms = samples > 1;
    let owned: Vec<wgpu::Buffer> = if ms {
        // per sample: the hand-overs a sample, the count a pixel, the accumulators a sample
        // (the plan's arrays; the range targets counted below)
        super::blend::check_samples(ctx, &[RANGE])?;
        oit_gpu::technique::ddp_blend_sample_state(ctx)?.into()
    } else {
        oit_gpu::technique::ddp_state(ctx)?.into()
    };
    let buffers: Vec<&wgpu::Buffer> = owned.iter().collect();
    let technique = if ms { SAMPLES_WGSL.join("\n") } else { WGSL.to_string() };
    // the kernels' text: the technique's and the vertex stage's (`hw_kept` is the stage's)
    let kernels = format!("{technique}\n{}", stage.wgsl());
    if ms {
        ctx.pixel_kernel(&kernels, "ddp_init_ms_main", &buffers, 0, 0)?;
    }

    let device = ctx.gpu.device.clone();
    // kept by the stage: a frame of a size seen before makes none
    let views = [
        ctx.target(stage, "ddp range 0", RANGE, samples)?,
        ctx.target(stage, "ddp range 1", RANGE, samples)?,
    ];
    let occlusion = stage.occlusion(&device);
    // group 2: the previous pass's range; pass p renders into views[p % 2] and reads the other
    let previous_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("ddp previous range"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: ms,
            },
            count: None,
        }],
    });
    let previous_groups: Vec<wgpu::BindGroup> = (0..2)
        .map(|p| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ddp previous range"),
                layout: &previous_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&views[(p + 1) % 2]),
                }],
            })
        })
        .collect();

    let module_source = format!("{COMMON_WGSL}\n{TECHNIQUE_PRELUDE}{technique}\n{}", stage.wgsl());
    let (peel_fs, resolve) =
        if ms { ("ddp_peel_ms_fs", "ddp_resolve_ms_main") } else { ("ddp_peel_fs", "resolve_main") };
    let max = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Max,
    };
    // the loop ends after the first pass whose query saw nothing, or after pass `limit`
    let limit = ctx.plan.peel_limit;
    let control = OcclusionPeel::new(ctx, drivers.scene.as_ref(), limit.saturating_add(1))?;
    let mut pass = 0u32;
    loop {
        let slot = (pass % 2) as usize;
        let (layout0, group0) = ctx.group0(&buffers, pass, 0);
        let pipeline = ctx.gpu.render_pipeline(
            key(&module_source, &format!("ddp blend {samples}")),
            "ddp blend",
            || {
                scene_pipeline_with(
                    &device,
                    "ddp blend",
                    &module_source,
                    &[&layout0, stage.layout(), &previous_layout],
                    peel_fs,
                    &[Some(wgpu::ColorTargetState {
                        format: RANGE,
                        blend: Some(wgpu::BlendState { color: max, alpha: max }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                    None,
                    samples,
                )
            },
        )?;
        let gated = control.gate(ctx, pass)?;
        super::occlusion_pass(
            stage,
            ctx,
            &pipeline,
            (&group0, &previous_groups[slot]),
            PassTarget {
                label: "ddp blend pass",
                color: &views[slot],
                clear: wgpu::Color { r: -2.0, g: -2.0, b: 0.0, a: 0.0 },
                second: None,
                depth: None,
            },
            &occlusion,
            gated.as_ref(),
        )?;
        if pass > 0 {
            // the pair the previous pass found, handed over in this one
            let source = if ms { kernels.as_str() } else { DDP_WGSL };
            ctx.pixel_kernel(source, resolve, &buffers, pass, 0)?;
        }
        if !control.go_on(ctx, &occlusion, pass + 1)? {
            break;
        }
        pass += 1;
    }
    if ms {
        // every pixel's samples finished over what lies behind them
        ctx.pixel_kernel(&kernels, "ddp_finish_ms_main", &buffers, pass, 0)?;
    }
    Ok(())
}
