//! `wavg` and `wsum` (see oit-wgpu's `technique/weighted.rs`): one geometry pass of unordered
//! u64 sums of the RGBA8 colour, a kernel that composites them into the resolve state.

use oit_core::{OitError, Technique};

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let average = match ctx.settings.technique {
        Technique::WeightedAverage => true,
        Technique::WeightedSum => false,
        other => return Err(OitError::InvalidSettings(format!("{other} is not wavg or wsum"))),
    };
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let sums = ctx.buffer("weighted sums", u64::from(ctx.pixels) * 5 * 2, Init::Zero)?;
    ctx.geometry_pass(&drivers.scene, "weighted", &[&sums], 0, 0)?;
    ctx.pixel_kernel("weighted", "composite_main", &[&sums], 0, u32::from(average))
}
