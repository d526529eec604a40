//! `plain` (see oit-wgpu's `technique/plain.rs` and `plain.wgsl`): on the compute path no blender
//! keeps submission order, so each pixel's fragments are kept in K slots (K from a counting pass)
//! and sorted by primitive id, the highest on top, as oit-cpu does.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let deepest = super::count(ctx, &drivers.scene)?.1;
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let counters = ctx.buffer("plain counters", px, Init::Zero)?;
    let slots = ctx.buffer("plain slots", px * u64::from(k) * 2, Init::Zero)?;
    let buffers = [&*counters, &*slots];
    ctx.geometry_pass(&drivers.scene, "plain", &buffers, 0, k)?;
    ctx.pixel_kernel("plain", "plain_resolve_main", &buffers, 0, k)
}
