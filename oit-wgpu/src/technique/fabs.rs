//! `fabs:K` on the GPU (see oit-cpu's `technique/fabs.rs` and `fabs.wgsl`): slots of a 64-bit
//! (depth bits, primitive id) key and a 32-bit payload, 12 bytes as oit-cpu's, sorted by key, so
//! ties come out in primitive order as the reference's do. A pixel that overflows keeps its K
//! smallest keys, so the same input gives the same image (see `fabs.wgsl`). `--overflow tail` adds
//! one pass where a pixel overflowed, merging what lies behind its K into a tail (`tail.wgsl`).

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = concat!(
    include_str!("fabs_counters.wgsl"),
    "\n",
    include_str!("fabs.wgsl"),
    "\n",
    include_str!("tail.wgsl")
);

/// The passes of `fabs.wgsl` (pass_index).
const FABS_CAPTURE: u32 = 0;
const FABS_KEYS: u32 = 1;
const FABS_PAYLOADS: u32 = 2;
const FABS_TAIL: u32 = 3;
/// The resolve's pass_index when the plan has a tail.
const FABS_WITH_TAIL: u32 = 1;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // slots per pixel by the plan: K, or the deepest pixel's count from a counting pass
    let deepest = if ctx.plan.needs_count() { super::count(ctx, drivers.scene.as_ref())?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let counters = ctx.buffer("fabs counters", px, Init::Zero)?;
    let slots = ctx.buffer("fabs slots", px * u64::from(k) * 2, Init::Zero)?;
    let payloads = ctx.buffer("fabs payloads", px * u64::from(k), Init::Zero)?;
    let overflowed = ctx.buffer("fabs overflowed", 1, Init::Zero)?;
    // the flag is bookkeeping, not per-pixel storage (oit-cpu counts none either)
    ctx.storage_bytes -= 4;
    let (tail, tail_words) = super::tail_buffers(ctx)?;
    let buffers = [&counters, &slots, &payloads, &overflowed, &tail, &tail_words];
    let scene = drivers.scene.as_ref();
    ctx.geometry_pass(scene, WGSL, &buffers, FABS_CAPTURE, k)?;
    // sized from the counting pass, no pixel can overflow: no check
    if !ctx.plan.needs_count() {
        ctx.pixel_kernel(WGSL, "overflow_main", &buffers, FABS_CAPTURE, k)?;
        // where a pixel overflowed (the flag stays on the device: the passes are gated by it),
        // the K smallest (depth, primitive) keys of each overflowing pixel, then their payloads
        ctx.geometry_pass_if(scene, WGSL, &buffers, FABS_KEYS, k, &overflowed)?;
        ctx.geometry_pass_if(scene, WGSL, &buffers, FABS_PAYLOADS, k, &overflowed)?;
        if ctx.plan.tail {
            ctx.geometry_pass_if(scene, WGSL, &buffers, FABS_TAIL, k, &overflowed)?;
            ctx.note_merged(&tail_words);
        }
    }
    let resolve = if ctx.plan.tail { FABS_WITH_TAIL } else { 0 };
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, resolve, k)
}
