//! `fabs:K` (see oit-wgpu's `technique/fabs.rs` and `fabs.wgsl`): slots of a 64-bit (depth bits,
//! primitive id) key and a 32-bit payload, sorted by key; an overflowing pixel keeps its K
//! smallest keys, so the same input gives the same image.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

const FABS_CAPTURE: u32 = 0;
const FABS_KEYS: u32 = 1;
const FABS_PAYLOADS: u32 = 2;

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let deepest = if ctx.plan.needs_count() { super::count(ctx, &drivers.scene)?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let counters = ctx.buffer("fabs counters", px, Init::Zero)?;
    let slots = ctx.buffer("fabs slots", px * u64::from(k) * 2, Init::Zero)?;
    let payloads = ctx.buffer("fabs payloads", px * u64::from(k), Init::Zero)?;
    let overflowed = ctx.buffer("fabs overflowed", 1, Init::Zero)?;
    // the flag is bookkeeping, not per-pixel storage (oit-cpu counts none either)
    ctx.storage_bytes -= 4;
    let buffers = [&*counters, &*slots, &*payloads, &*overflowed];
    ctx.geometry_pass(&drivers.scene, "fabs", &buffers, FABS_CAPTURE, k)?;
    // sized from the counting pass, no pixel can overflow: no check, no readback
    if !ctx.plan.needs_count() {
        ctx.pixel_kernel("fabs", "overflow_main", &buffers, FABS_CAPTURE, k)?;
        if ctx.read_u32(&overflowed)?[0] != 0 {
            ctx.geometry_pass(&drivers.scene, "fabs", &buffers, FABS_KEYS, k)?;
            ctx.geometry_pass(&drivers.scene, "fabs", &buffers, FABS_PAYLOADS, k)?;
        }
    }
    ctx.pixel_kernel("fabs", "resolve_main", &buffers, 0, k)
}
