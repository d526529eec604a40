//! `fabs:K` on the GPU (see oit-cpu's `technique/fabs.rs` and `fabs.wgsl`): slots of a 64-bit
//! (depth bits, primitive id) key and a 32-bit payload, 12 bytes as oit-cpu's, sorted by key, so
//! ties come out in primitive order as the reference's do.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("fabs.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // slots per pixel by the plan: K, or the deepest pixel's count from a counting pass
    let deepest = if ctx.plan.needs_count() { super::count(ctx, drivers.scene.as_ref())?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let counters = ctx.buffer("fabs counters", px, Init::Zero)?;
    let slots = ctx.buffer("fabs slots", px * u64::from(k) * 2, Init::Zero)?;
    let payloads = ctx.buffer("fabs payloads", px * u64::from(k), Init::Zero)?;
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &[&counters, &slots, &payloads], 0, k)?;
    ctx.pixel_kernel(WGSL, "resolve_main", &[&counters, &slots, &payloads], 0, k)
}
