//! `dfb` on the GPU (see oit-cpu's `technique/dfb.rs` and `dfb.wgsl`): a counting pass, the
//! exclusive prefix sum of the counts on the GPU (`scan.wgsl`, whose total sizes the fragment
//! buffer: read back on a first frame, an earlier frame's where a prepared scene has one,
//! [`GpuCtx::fragment_capacity`]), a fill pass into the frame's fragments, and a per-pixel sort by
//! (depth, primitive id) and composite.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const COUNT_WGSL: &str = include_str!("dfb_count.wgsl");
/// The technique, and the in-place sort its resolve calls.
const WGSL: &str = concat!(include_str!("dfb.wgsl"), "\n", include_str!("sort_entries.wgsl"));

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels) + 1;
    // fragments per pixel; the last entry stays 0, so the offsets end in the total
    let counts = ctx.buffer("dfb counts", entries, Init::Zero)?;
    ctx.geometry_pass(drivers.scene.as_ref(), COUNT_WGSL, &[&counts], 0, 0)?;
    let offsets = ctx.buffer("dfb offsets", entries, Init::Zero)?;
    ctx.encoder().copy_buffer_to_buffer(&counts, 0, &offsets, 0, entries * 4);
    let total = super::scan(ctx, &offsets, entries)?;
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    let total = u64::from(ctx.plan.check_fragments(u64::from(total))?);
    let keys = ctx.buffer("dfb keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("dfb payloads", total, Init::Zero)?;
    let buffers = [&counts, &offsets, &keys, &payloads];
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 0, 0)?;
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, 0, 0)
}
