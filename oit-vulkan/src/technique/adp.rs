//! `adp` (see oit-wgpu's `technique/adp.rs`) by storage-buffer atomics on the compute path: bounds
//! pass, histogram pass (atomicOr), the deepest pixel's set-bin count (`VkCtx::deepest_alike`) for the
//! number of batches, then one bucket pass and one resolve per batch of 32. On the hardware path
//! with `--hardware-capture blend`, the histogram pass is the paper's own: logic-op OR into 8 ×
//! R32G32B32A32_UINT targets (`technique::blend::adp_histogram`), copied into the same histogram.

use oit_core::OitError;
use oit_core::rules::{BUCKETS, HISTOGRAM_WORDS};

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>, logic_or: bool) -> Result<(), OitError> {
    let bounds = super::bdp::depth_bounds(ctx, drivers)?;
    let px = u64::from(ctx.pixels);
    let hist = ctx.buffer("adp histogram", px * HISTOGRAM_WORDS as u64, Init::Zero)?;
    let max_bins = ctx.buffer("adp deepest pixel", 1, Init::Zero)?;
    ctx.storage_bytes -= 4;
    let buckets = ctx.buffer("adp buckets", px * BUCKETS as u64 * 2, Init::Zero)?;
    let nearest = ctx.buffer("adp nearest", px * BUCKETS as u64 * 2, Init::Fill(u32::MAX))?;
    let buffers = [&*bounds, &*hist, &*buckets, &*max_bins, &*nearest];
    if logic_or {
        super::blend::adp_histogram(ctx, drivers, &buffers)?;
    } else {
        ctx.geometry_pass(&drivers.scene, "adp", &buffers, 0, 0)?;
    }
    ctx.pixel_kernel("adp", "count_main", &buffers, 0, 0)?;
    // an earlier frame's count where it makes as many batches (checked at the end), else read back
    let plan = ctx.plan.clone();
    let bins = ctx.deepest_alike(&max_bins, move |a, b| plan.adp_batches(a) == plan.adp_batches(b))?;
    let batches = ctx.plan.adp_batches(bins);
    for batch in 0..batches {
        ctx.last_pass(batch + 1 == batches);
        ctx.geometry_pass(&drivers.scene, "adp", &buffers, 1, batch)?;
        ctx.pixel_kernel("adp", "resolve_main", &buffers, 1, batch)?;
    }
    ctx.last_pass(false);
    Ok(())
}
