//! `adp` on the GPU: adaptive bucket depth peeling (Liu et al., HPG 2009, section 3.3), the same
//! passes, storage and resolve as oit-cpu's `technique/adp.rs` (see its docs), in `adp.wgsl`:
//! bounds pass, histogram pass (atomicOr), the deepest pixel's set-bin count for the number of
//! batches (read back on a first frame; an earlier frame's, checked at the end, where a prepared
//! scene has one), then one bucket pass and one resolve per batch of 32. Each bucket keeps its
//! bin's farthest (MAX) and nearest (MIN) words, so a bin of two fragments is captured whole.

use oit_core::OitError;
use oit_core::rules::{BUCKETS, HISTOGRAM_WORDS};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("adp.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let bounds = super::bdp::depth_bounds(ctx, drivers)?;
    let px = u64::from(ctx.pixels);
    let hist = ctx.buffer("adp histogram", px * HISTOGRAM_WORDS as u64, Init::Zero)?;
    let max_bins = ctx.buffer("adp deepest pixel", 1, Init::Zero)?;
    // sizing the batches is not per-pixel storage: oit-cpu does not count it either
    ctx.storage_bytes -= 4;
    // oit-cpu allocates the buckets after the histogram pass; the bytes are the same
    let buckets = ctx.buffer("adp buckets", px * BUCKETS as u64 * 2, Init::Zero)?;
    let nearest = ctx.buffer("adp nearest", px * BUCKETS as u64 * 2, Init::Fill(u32::MAX))?;
    let buffers = [&bounds, &hist, &buckets, &max_bins, &nearest];
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 0, 0)?;
    ctx.pixel_kernel(WGSL, "count_main", &buffers, 0, 0)?;
    // the last frame's count where a prepared scene has one, checked at the end by the batches
    // it makes
    let plan = ctx.plan.clone();
    let bins = ctx.deepest_alike(&max_bins, move |a, b| plan.adp_batches(a) == plan.adp_batches(b))?;
    let batches = ctx.plan.adp_batches(bins);
    for batch in 0..batches {
        ctx.last_pass(batch + 1 == batches);
        ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 1, batch)?;
        ctx.pixel_kernel(WGSL, "resolve_main", &buffers, 1, batch)?;
    }
    ctx.last_pass(false);
    Ok(())
}
