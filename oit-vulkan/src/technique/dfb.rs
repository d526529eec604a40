//! `dfb` (see oit-wgpu's `technique/dfb.rs` and `dfb.wgsl`): a counting pass, the exclusive
//! prefix sum of the counts on the GPU (`scan.wgsl`, as oit-wgpu: the total is the one word read
//! back, to size the fragment buffer), a fill pass into exactly the frame's fragments, and a
//! per-pixel sort by (depth, primitive id) and composite.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels) + 1;
    // fragments per pixel; the last entry stays 0, so the offsets end in the total
    let counts = ctx.buffer("dfb counts", entries, Init::Zero)?;
    ctx.geometry_pass(&drivers.scene, "dfb_count", &[&counts], 0, 0)?;
    let offsets = ctx.buffer("dfb offsets", entries, Init::Zero)?;
    ctx.copy(&counts, &offsets, entries * 4);
    let total = super::scan(ctx, &offsets, entries)?;
    let total = u64::from(ctx.plan.check_fragments(total)?);
    let keys = ctx.buffer("dfb keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("dfb payloads", total, Init::Zero)?;
    let buffers = [&*counts, &*offsets, &*keys, &*payloads];
    ctx.geometry_pass(&drivers.scene, "dfb", &buffers, 0, 0)?;
    ctx.pixel_kernel("dfb", "resolve_main", &buffers, 0, 0)
}
