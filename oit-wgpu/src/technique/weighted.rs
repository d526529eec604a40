//! `wavg` and `wsum` on the GPU: one geometry pass of unordered sums, the same pass, storage and
//! result as oit-cpu's `technique/weighted.rs` (see its docs), in `weighted.wgsl`. The sums are u64
//! integers of the RGBA8 colour (5 words of 64 bits per pixel, as oit-cpu's), added with 64-bit
//! atomicAdd: exact and independent of arrival order at any depth complexity. A kernel composites
//! them and leaves the final colour in the resolve state, so the common finish (and the heat map
//! of the complexity effect) works unchanged.

use oit_core::{OitError, Technique};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("weighted.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let average = match ctx.settings.technique {
        Technique::WeightedAverage => true,
        Technique::WeightedSum => false,
        other => return Err(OitError::InvalidSettings(format!("{other} is not wavg or wsum"))),
    };
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    // r, g, b premultiplied sums, alpha sum, count: u64 each
    let sums = ctx.buffer("weighted sums", u64::from(ctx.pixels) * 5 * 2, Init::Zero)?;
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &[&sums], 0, 0)?;
    ctx.pixel_kernel(WGSL, "composite_main", &[&sums], 0, u32::from(average))
}
