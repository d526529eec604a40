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

use oit_core::{Effect, OitError};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init, TECHNIQUE_PRELUDE};
use crate::gpu::COMMON_WGSL;
use crate::technique::bdp_blend::{check_texture_size, count_fragments, key, scene_stage, unsupported};

const WGSL: &str = include_str!("ddp_blend.wgsl");
const DDP_WGSL: &str = include_str!("ddp.wgsl");
const RANGE: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let effect = ctx.settings.effect;
    if !matches!(effect, Effect::Transparency | Effect::Complexity) {
        return Err(unsupported(&format!(
            "the {effect:?} effect with ddp: the far layers it peels would have to be replayed nearest first from a per-pixel stack, which the GPU resolve does not keep; use dp, fabs, mlp or adp (or the cpu backend)"
        )));
    }
    let stage = scene_stage(drivers)?;
    if !ctx.gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err(unsupported("MAX blending into an Rg32Float target: the device lacks FLOAT32_BLENDABLE"));
    }
    check_texture_size(ctx, "the ddp range targets")?;
    if ctx.fragments.is_none() {
        count_fragments(ctx, drivers)?;
    }
    let px = u64::from(ctx.pixels);
    let near = ctx.buffer("ddp near", px * 2, Init::Fill(u32::MAX))?;
    let far = ctx.buffer("ddp far", px * 2, Init::Zero)?;
    let range = ctx.buffer("ddp range", px * 2, Init::Zero)?;
    let peeled = ctx.buffer("ddp peeled count", 1, Init::Zero)?;
    ctx.storage_bytes -= 4;
    let buffers = [&near, &far, &range, &peeled];
    ctx.pixel_kernel(DDP_WGSL, "ddp_init_main", &buffers, 0, 0)?;

    let device = ctx.gpu.device.clone();
    let (w, h) = (ctx.settings.width, ctx.settings.height);
    let targets: Vec<wgpu::Texture> = (0..2)
        .map(|i| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&format!("ddp range target {i}")),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: RANGE,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        })
        .collect();
    ctx.storage_bytes += px * 16;
    let views: Vec<wgpu::TextureView> = targets.iter().map(|t| t.create_view(&Default::default())).collect();
    let occlusion = device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("ddp pass occlusion"),
        ty: wgpu::QueryType::Occlusion,
        count: 1,
    });
    let occlusion_buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("ddp pass occlusion"),
        size: 8,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    // group 2: the previous pass's range; pass p renders into views[p % 2] and reads the other
    let previous_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("ddp previous range"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
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

    let module_source = format!("{COMMON_WGSL}\n{TECHNIQUE_PRELUDE}{WGSL}\n{}", stage.wgsl());
    let max = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Max,
    };
    let limit = ctx.settings.max_peels.unwrap_or(u32::MAX);
    let mut pass = 0u32;
    loop {
        let slot = (pass % 2) as usize;
        let (layout0, group0) = ctx.group0(&buffers, pass, 0);
        let pipeline = ctx.gpu.render_pipeline(key(&module_source, "ddp blend"), "ddp blend", || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("ddp blend"),
                source: wgpu::ShaderSource::Wgsl(module_source.as_str().into()),
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("ddp blend"),
                bind_group_layouts: &[Some(&layout0), Some(stage.layout()), Some(&previous_layout)],
                immediate_size: 0,
            });
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("ddp blend"),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("hw_vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("ddp_peel_fs"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: RANGE,
                        blend: Some(wgpu::BlendState { color: max, alpha: max }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        })?;
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("ddp blend pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &views[slot],
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r: -2.0, g: -2.0, b: 0.0, a: 0.0 }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: ctx.render_timestamps(),
                occlusion_query_set: Some(&occlusion),
                multiview_mask: None,
            });
            rpass.set_pipeline(&pipeline);
            rpass.set_bind_group(0, &group0, &[]);
            rpass.set_bind_group(2, &previous_groups[slot], &[]);
            rpass.begin_occlusion_query(0);
            stage.draw(&mut rpass);
            rpass.end_occlusion_query();
        }
        encoder.resolve_query_set(&occlusion, 0..1, &occlusion_buf, 0);
        ctx.finish_timed("geometry", encoder)?;
        ctx.passes += 1;
        if pass > 0 {
            // the pair the previous pass found, handed over in this one
            ctx.pixel_kernel(DDP_WGSL, "resolve_main", &buffers, pass, 0)?;
        }
        // zero or not is all the occlusion query promises on every backend
        let left = ctx.gpu.read_u32(&occlusion_buf)?;
        if left.iter().all(|&s| s == 0) || pass >= limit {
            break;
        }
        pass += 1;
    }
    Ok(())
}
