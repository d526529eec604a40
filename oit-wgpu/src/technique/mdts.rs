//! `mdts:K` and `mdts64:K` on the GPU: the multi-depth test, the same pass, storage and loss
//! accounting as oit-cpu's `technique/mdts.rs` (see its docs), in `mdts.wgsl`: one geometry pass
//! of atomic-min insertion into K sorted words per pixel (two u32 arrays of the paper's 20 + 12-bit
//! packing for `mdts`, one u64 array for `mdts64`), then a resolve kernel. K omitted: sized by a
//! counting pass to the deepest pixel, as oit-cpu does.
//!
//! The arrays end as the K smallest words inserted, sorted, whatever the arrival order, so the
//! result equals oit-cpu's exactly (mdts's packing losses included).

use oit_core::{OitError, Technique};

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
    let wide = match ctx.settings.technique {
        Technique::Mdts { .. } => false,
        Technique::Mdts64 { .. } => true,
        other => return Err(OitError::InvalidSettings(format!("{other} is not mdts or mdts64"))),
    };
    // the plan refuses Fresnel with the 32-bit words (no room for a normal)
    let deepest = if ctx.plan.needs_count() { super::count(ctx, drivers.scene.as_ref())?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let words = u64::from(ctx.pixels) * u64::from(k);
    if wide {
        let (high, low) = (placeholder(ctx), placeholder(ctx));
        let slots = ctx.buffer("mdts64 slots", words * 2, Init::Fill(u32::MAX))?;
        let buffers = [&high, &low, &slots];
        ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, MDTS_64, k)?;
        return ctx.pixel_kernel(WGSL, "resolve_main", &buffers, MDTS_64, k);
    }
    // alpha is not stored: the plan's (the override, else the mean of the objects' alphas)
    let alpha8 = ctx.plan.mdts_alpha8;
    let high = ctx.buffer("mdts high words", words, Init::Fill(u32::MAX))?;
    let low = ctx.buffer("mdts low words", words, Init::Fill(u32::MAX))?;
    let slots = placeholder(ctx);
    let buffers = [&high, &low, &slots];
    let mode = MDTS_32 | alpha8 << 8;
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, mode, k)?;
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, mode, k)
}
