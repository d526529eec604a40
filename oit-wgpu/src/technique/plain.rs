//! `plain`: unsorted alpha blending in submission order, the speed baseline (see oit-cpu's
//! `technique/plain.rs`: submission order is primitive order, the highest primitive on top).
//! On the hardware path with oit's own vertex stage the blender does it in the one draw
//! ([`super::blend::plain`]). Where no blender keeps that order — the compute rasterizer, whose
//! work items reach a pixel in no fixed order, and the embedded pass, whose pipelines are the
//! user's — each pixel's fragments are kept and sorted by primitive id as oit-cpu does
//! (`plain.wgsl`): a counting pass sizes K slots a pixel, a capture pass fills them, the resolve
//! sorts and composites.

use oit_core::{OitError, RasterPath};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("plain.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    if drivers.scene.path() == RasterPath::Hardware
        && let Some(stage) = drivers.scene.scene_stage()
    {
        return super::blend::plain(ctx, stage);
    }
    let deepest = super::count(ctx, drivers.scene.as_ref())?.1;
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let counters = ctx.buffer("plain counters", px, Init::Zero)?;
    let slots = ctx.buffer("plain slots", px * u64::from(k) * 2, Init::Zero)?;
    let buffers = [&counters, &slots];
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 0, k)?;
    ctx.pixel_kernel(WGSL, "plain_resolve_main", &buffers, 0, k)
}
