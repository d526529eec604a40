//! `reference` on the GPU: a counting pass, the exclusive prefix sum of the counts on the GPU
//! (`scan.wgsl`, as dfb: the fragment lists sized from the total's size class,
//! [`GpuCtx::fragment_capacity`], so a steady frame waits for nothing), a fill pass into per-pixel
//! lists, a per-pixel sort by (depth, primitive id) and composite. The per-pixel counts are the
//! frame's `layers`, read back with its image at the end.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

/// The technique, and the in-place sort its resolve calls.
const WGSL: &str = concat!(include_str!("reference.wgsl"), "\n", include_str!("sort_entries.wgsl"));
/// The counting pass (dfb's: fragments per pixel).
const COUNT_WGSL: &str = include_str!("dfb_count.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels) + 1;
    // fragments per pixel; the last entry stays 0, so the offsets end in the total
    let counts = ctx.buffer("reference counts", entries, Init::Zero)?;
    ctx.geometry_pass(drivers.scene.as_ref(), COUNT_WGSL, &[&counts], 0, 0)?;
    // the counts are the frame's layers, not the technique's storage (oit-cpu counts none)
    ctx.storage_bytes -= entries * 4;
    ctx.layers_from = Some(counts.clone());
    let offsets = ctx.buffer("reference offsets", entries, Init::Zero)?;
    ctx.encoder().copy_buffer_to_buffer(&counts, 0, &offsets, 0, entries * 4);
    let total = super::scan(ctx, &offsets, entries)?;
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    let total = u64::from(ctx.plan.check_fragments(u64::from(total))?);
    let cursor = ctx.buffer("reference cursor", u64::from(ctx.pixels), Init::Zero)?;
    let keys = ctx.buffer("reference keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("reference payloads", total, Init::Zero)?;
    let buffers = [&offsets, &cursor, &keys, &payloads];
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 0, 0)?;
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, 0, 0)
}
