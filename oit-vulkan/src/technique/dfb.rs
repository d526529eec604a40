//! `dfb` (see oit-wgpu's `technique/dfb.rs` and `dfb.wgsl`): a counting pass, the exclusive
//! prefix sum of the counts on the GPU (`scan.wgsl`, as oit-wgpu; the fragment buffer sized from the
//! total's size class, `VkCtx::fragment_capacity`), a fill pass, and a
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
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    let total = u64::from(ctx.plan.check_fragments(u64::from(total))?);
    let keys = ctx.buffer("dfb keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("dfb payloads", total, Init::Zero)?;
    let buffers = [&*counts, &*offsets, &*keys, &*payloads];
    ctx.geometry_pass(&drivers.scene, "dfb", &buffers, 0, 0)?;
    ctx.pixel_kernel("dfb", "resolve_main", &buffers, 0, 0)
}
