//! `dfb` (see oit-wgpu's `technique/dfb.rs` and `dfb.wgsl`): a counting pass, the exclusive
//! prefix sum of the counts (here on the host, after one readback, as this backend's reference
//! does; oit-wgpu scans on the GPU), a fill pass into exactly the frame's fragments, and a
//! per-pixel sort by (depth, primitive id) and composite.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels) + 1;
    // fragments per pixel; the last entry stays 0
    let counts = ctx.buffer("dfb counts", entries, Init::Zero)?;
    ctx.geometry_pass(&drivers.scene, "dfb_count", &[&counts], 0, 0)?;
    let read = ctx.read_u32(&counts)?;
    let mut offsets = Vec::with_capacity(entries as usize);
    let mut total = 0u64;
    for &c in &read[..entries as usize] {
        offsets.push(u32::try_from(total).map_err(|_| OitError::Device("over 2^32 fragments".into()))?);
        total += u64::from(c);
    }
    let total = u64::from(ctx.plan.check_fragments(total)?);
    let offsets_buf = ctx.buffer("dfb offsets", entries, Init::Zero)?;
    ctx.upload(&offsets_buf, bytemuck::cast_slice(&offsets))?;
    let keys = ctx.buffer("dfb keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("dfb payloads", total, Init::Zero)?;
    let buffers = [&*counts, &*offsets_buf, &*keys, &*payloads];
    ctx.geometry_pass(&drivers.scene, "dfb", &buffers, 0, 0)?;
    ctx.pixel_kernel("dfb", "resolve_main", &buffers, 0, 0)
}
