//! `mdts:K` and `mdts64:K` on the GPU: the multi-depth test, the same pass, storage and loss
//! accounting as oit-cpu's `technique/mdts.rs` (see its docs), in `mdts.wgsl`: one geometry pass
//! of atomic-min insertion into K sorted words per pixel (two u32 arrays of the paper's 20 + 12-bit
//! packing for `mdts`, one u64 array for `mdts64`), then a resolve kernel. K omitted: sized by a
//! counting pass to the deepest pixel, as oit-cpu does.
//!
//! The arrays end as the K smallest words inserted, sorted, whatever the arrival order, so the
//! result equals oit-cpu's exactly (mdts's packing losses included).

use oit_core::{Effect, OitError, Technique};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("mdts.wgsl");

/// The modes of `mdts.wgsl` (low byte of pass_index).
const MDTS_32: u32 = 0;
const MDTS_64: u32 = 1;

/// A small buffer bound where the mode's WGSL declares an array it does not use (not storage).
fn placeholder(ctx: &GpuCtx<'_>) -> wgpu::Buffer {
    ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("unused binding"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let (k, wide) = match ctx.settings.technique {
        Technique::Mdts { k } => (k, false),
        Technique::Mdts64 { k } => (k, true),
        other => return Err(OitError::InvalidSettings(format!("{other} is not mdts or mdts64"))),
    };
    if !wide && ctx.settings.effect == Effect::Fresnel {
        return Err(OitError::Unsupported {
            backend: "wgpu".into(),
            what: "fresnel with mdts: its 12 + 12 spare bits hold RGB only; use mdts64".into(),
        });
    }
    let k = match k {
        Some(k) => k,
        None => super::count(ctx, drivers.scene.as_ref())?.1.max(1),
    };
    let words = u64::from(ctx.pixels) * u64::from(k);
    if wide {
        let (high, low) = (placeholder(ctx), placeholder(ctx));
        let slots = ctx.buffer("mdts64 slots", words * 2, Init::Fill(u32::MAX))?;
        let buffers = [&high, &low, &slots];
        ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, MDTS_64, k)?;
        return ctx.pixel_kernel(WGSL, "resolve_main", &buffers, MDTS_64, k);
    }
    // alpha is not stored: the scene's (the override, else the mean of the objects' alphas)
    let alpha = match ctx.settings.alpha {
        Some(a) => a,
        None => {
            let objects = &ctx.scene.objects;
            objects.iter().map(|o| o.color.w).sum::<f32>() / objects.len().max(1) as f32
        }
    };
    let alpha8 = (alpha.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
    let high = ctx.buffer("mdts high words", words, Init::Fill(u32::MAX))?;
    let low = ctx.buffer("mdts low words", words, Init::Fill(u32::MAX))?;
    let slots = placeholder(ctx);
    let buffers = [&high, &low, &slots];
    let mode = MDTS_32 | alpha8 << 8;
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, mode, k)?;
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, mode, k)
}
