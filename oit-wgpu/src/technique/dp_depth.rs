//! `dp` on the hardware path with `--hardware-capture blend`: Everitt's depth peeling (2001) with
//! the graphics pipeline's own means, in `dp_depth.wgsl`: per peel, a render pass with a depth
//! test (LESS_EQUAL against a fresh Depth32Float attachment cleared to 1) whose fragment stage
//! discards what lies at or in front of the previous peel's depth (two depth textures,
//! ping-ponged: one is this peel's attachment, the other the previous peel's, read by pixel),
//! writing the surviving fragment's payload to an Rg32Uint target; an occlusion query over the
//! pass ends the loop at the first peel that draws nothing (N + 1 passes as oit-cpu, or
//! `settings.max_peels`): read back after each pass, or, where a prepared scene's frame knows
//! the last frame's count, gated on the device with no round trip ([`OcclusionPeel`]). A compute
//! step composites each peeled layer under the layers before (`push`, depth from the attachment).
//! The textures and the query are kept by the frame's rasterizer.
//!
//! The same layers, passes and losses as the atomics capture (`dp.rs`); equal depths within a
//! pixel keep the last drawn fragment here and the smallest payload there (the other is lost in
//! both). The depth test kills the fragments behind before any colour write, so the pass cannot
//! count the fragments generated: one count-only draw of the scene (the hardware driver's
//! additive counter, no capture, not a geometry pass) counts them first.
//!
//! Storage per pixel: two Depth32Float textures and the Rg32Uint layer, 16 bytes (the atomics
//! capture and oit-cpu count 12: an 8-byte nearest key and a 4-byte previous depth).
//!
//! At several samples a pixel (`--samples 4|8`, per-sample coverage; docs/msaa.md, "Depth
//! peeling per sample on the blender") the same loop peels each sample: the depth textures and
//! the layer are multisampled, `dp_depth_samples.wgsl`'s `dp_peel_ms_fs` writes the fragment's
//! one depth to the samples it keeps behind the previous peel's depth there, the composite puts
//! each sample's layer into that sample's accumulator (the plan's "sample accumulators") and a
//! last kernel finishes every pixel's samples over their opaque colours. Ties are peeled in
//! primitive order there: the depth test is LESS (of equal depths the first drawn, the smallest
//! primitive id), and a multisampled R32Uint target, ping-ponged as the depths are, keeps each
//! sample's peeled primitive id + 1, so the next peel keeps a fragment at a sample where its
//! (depth, primitive id) lies strictly behind the previous peel's: a tie is two layers, none lost,
//! the per-sample reference exactly (`blend_peels_count_coplanar_ties`, tests/tests/ties.rs). At one
//! sample the tie keeps the last drawn and the other is never peeled: `lost`, derived as fragments
//! less captured and occluded, counts it. Storage: the targets a sample and the accumulators
//! (`Plan::blend_targets`).

use oit_core::OitError;

use crate::ctx::{Drivers, GpuCtx, Init, TECHNIQUE_PRELUDE};
use crate::gpu::COMMON_WGSL;
use crate::hardware::scene_pipeline_with;
use crate::stage::PassTarget;
use crate::technique::OcclusionPeel;
use crate::technique::bdp_blend::{check_texture_size, count_fragments, key, scene_stage};

const WGSL: &str = oit_shaders::text("technique/dp_depth.wgsl");
/// At several samples: the per-sample accumulators, then the per-sample peel.
const SAMPLES_WGSL: [&str; 2] =
    [oit_shaders::text("technique/peel_samples.wgsl"), oit_shaders::text("technique/dp_depth_samples.wgsl")];
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const LAYER: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;
/// At several samples: the peeled fragment's primitive id + 1 a sample (0: none).
const PRIM: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // the blend unit returns no previous value to count a loss by where it happens: `lost` is
    // derived, fragments − captured − occluded, and says nothing of where (no `lost_pixels`).
    // Exact, as a fragment counts itself captured where it is peeled (at several samples, once,
    // at its lowest kept sample, and `--max-peels` there is refused before this runs:
    // `oit_core::plan::refuse_multisampled_own_capture`)
    ctx.counts_losses = false;
    let stage = scene_stage(drivers)?;
    check_texture_size(ctx, "the dp depth and layer textures")?;
    if ctx.fragments == crate::ctx::Fragments::Unset {
        count_fragments(ctx, drivers)?;
    }
    let device = ctx.gpu.device.clone();
    let samples = ctx.settings.samples;
    let ms = samples > 1;
    // at several samples: the targets a sample and each sample's accumulator (the plan's arrays)
    let acc = if ms {
        super::blend::check_samples(ctx, &[DEPTH, LAYER, PRIM])?;
        let mut storage = oit_gpu::technique::Storage::new(ctx, 0);
        storage.attachments("peel depths", 8 * u64::from(samples))?;
        storage.attachments("peeled layer", 8 * u64::from(samples))?;
        storage.attachments("peeled primitives", 8 * u64::from(samples))?;
        // set by the first peel's composite
        let acc = storage.buffer(ctx, "sample accumulators", Init::Zero)?;
        storage.finish()?;
        Some(acc)
    } else {
        None
    };
    // kept by the stage: a frame of a size seen before makes none
    let depth_views =
        [ctx.target(stage, "dp depth 0", DEPTH, samples)?, ctx.target(stage, "dp depth 1", DEPTH, samples)?];
    let layer_view = ctx.target(stage, "dp layer", LAYER, samples)?;
    // at several samples: the peeled primitive a sample, ping-ponged as the depths are
    let prim_views = if ms {
        Some([ctx.target(stage, "dp prim 0", PRIM, samples)?, ctx.target(stage, "dp prim 1", PRIM, samples)?])
    } else {
        None
    };
    let occlusion = stage.occlusion(&device);
    // group 0's buffers: the accumulators at peel_samples.wgsl's binding 5 (2 to 4 unused)
    let buffers: Vec<wgpu::Buffer> = match &acc {
        Some(acc) => vec![ctx.placeholder(), ctx.placeholder(), ctx.placeholder(), acc.clone()],
        None => Vec::new(),
    };
    let buffers: Vec<&wgpu::Buffer> = buffers.iter().collect();
    let (peel_fs, composite_entry) =
        if ms { ("dp_peel_ms_fs", "dp_composite_ms_main") } else { ("dp_peel_fs", "dp_composite_main") };

    let depth_entry = |binding: u32, visibility| wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Depth,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: ms,
        },
        count: None,
    };
    // group 2 of the peel: the previous depth (and at several samples the previous primitive);
    // peel p renders into depths[p % 2] and reads the other
    let prim_entry = wgpu::BindGroupLayoutEntry {
        binding: 1,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: true,
        },
        count: None,
    };
    let previous_entries = [depth_entry(0, wgpu::ShaderStages::FRAGMENT), prim_entry];
    let previous_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("dp previous depth"),
        entries: &previous_entries[..if ms { 2 } else { 1 }],
    });
    let previous_groups: Vec<wgpu::BindGroup> = (0..2)
        .map(|p| {
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&depth_views[(p + 1) % 2]),
            }];
            if let Some(prims) = &prim_views {
                entries.push(wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&prims[(p + 1) % 2]),
                });
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("dp previous depth"),
                layout: &previous_layout,
                entries: &entries,
            })
        })
        .collect();
    // group 1 of the composite: the layer and this peel's depth
    let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("dp composite"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: ms,
                },
                count: None,
            },
            depth_entry(4, wgpu::ShaderStages::COMPUTE),
        ],
    });
    let composite_groups: Vec<wgpu::BindGroup> = (0..2)
        .map(|p| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("dp composite"),
                layout: &composite_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(&layer_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(&depth_views[p]),
                    },
                ],
            })
        })
        .collect();

    let technique = if ms { SAMPLES_WGSL.join("\n") } else { WGSL.to_string() };
    let module_source = format!("{COMMON_WGSL}\n{TECHNIQUE_PRELUDE}{technique}\n{}", stage.wgsl());
    let composite_source = format!("{TECHNIQUE_PRELUDE}{technique}\n{}", stage.wgsl());
    let (x, y) = crate::ctx::dispatch_size(u64::from(ctx.pixels));
    // the loop ends at the first peel that draws nothing (N + 1 passes), or at the limit
    let limit = ctx.plan.peel_limit;
    let control = OcclusionPeel::new(ctx, drivers.scene.as_ref(), limit)?;
    let mut run = 0;
    loop {
        let slot = (run % 2) as usize;
        let (layout0, group0) = ctx.group0(&buffers, run, 0);
        let pipeline = ctx.gpu.render_pipeline(
            key(&module_source, &format!("dp depth peel {samples}")),
            "dp depth peel",
            || {
                scene_pipeline_with(
                    &device,
                    "dp depth peel",
                    &module_source,
                    &[&layout0, stage.layout(), &previous_layout],
                    peel_fs,
                    &[
                        Some(wgpu::ColorTargetState {
                            format: LAYER,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        }),
                        Some(wgpu::ColorTargetState {
                            format: PRIM,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        }),
                    ][..if ms { 2 } else { 1 }],
                    Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: Some(true),
                        // at several samples the first drawn of equal depths, the smallest
                        // primitive id: ties peeled in primitive order
                        depth_compare: Some(if ms {
                            wgpu::CompareFunction::Less
                        } else {
                            wgpu::CompareFunction::LessEqual
                        }),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    samples,
                )
            },
        )?;
        let gated = control.gate(ctx, run)?;
        super::occlusion_pass(
            stage,
            ctx,
            &pipeline,
            (&group0, &previous_groups[slot]),
            PassTarget {
                label: "dp depth peel",
                color: &layer_view,
                clear: wgpu::Color::TRANSPARENT,
                second: prim_views.as_ref().map(|prims| &prims[slot]),
                depth: Some(&depth_views[slot]),
            },
            &occlusion,
            gated.as_ref(),
        )?;
        run += 1;
        // a peel that drew nothing left its layer clear: its composite adds nothing
        let (layout0, group0) = ctx.group0(&buffers, run - 1, 0);
        let composite =
            ctx.gpu.compute_pipeline(&composite_source, composite_entry, &[&layout0, &composite_layout])?;
        let group1 = &composite_groups[slot];
        ctx.timed(composite_entry, |encoder, timestamps| {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("dp composite"),
                timestamp_writes: timestamps,
            });
            pass.set_pipeline(&composite);
            pass.set_bind_group(0, &group0, &[]);
            pass.set_bind_group(1, group1, &[]);
            pass.dispatch_workgroups(x, y, 1);
        })?;
        if !control.go_on(ctx, &occlusion, run)? {
            break;
        }
    }
    if ms {
        // every pixel's samples finished over what lies behind them
        let (layout0, group0) = ctx.group0(&buffers, run, 0);
        let finish = ctx.gpu.compute_pipeline(&composite_source, "dp_finish_ms_main", &[&layout0])?;
        ctx.timed("dp_finish_ms_main", |encoder, timestamps| {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("dp finish"),
                timestamp_writes: timestamps,
            });
            pass.set_pipeline(&finish);
            pass.set_bind_group(0, &group0, &[]);
            pass.dispatch_workgroups(x, y, 1);
        })?;
    }
    Ok(())
}
