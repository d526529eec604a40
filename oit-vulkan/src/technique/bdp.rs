//! `bdp` and `bdp:P` (see oit-wgpu's `technique/bdp.rs`) by storage-buffer atomics on either
//! path, and the per-pixel depth bounds pass bdp and adp share (`bounds.wgsl`). The paper's
//! capture, MAX blending into 8 × R32G32B32A32_SFLOAT targets, is `technique::blend::bdp`
//! (`--hardware-capture blend` on the hardware path).

use std::rc::Rc;

use oit_core::{BoundsMode, OitError};

use crate::Drivers;
use crate::ctx::{Init, VkCtx};
use crate::device::Buffer;

const MODE_COLOR: u32 = 0;
const MODE_DEPTH: u32 = 1;

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let color_mode = ctx.plan.bdp_color;
    let bounds = depth_bounds(ctx, drivers)?;
    if color_mode { color(ctx, drivers, &bounds) } else { depth(ctx, drivers, &bounds) }
}

/// Per-pixel [zNear, zFar] from one geometry pass over the instances' bounding boxes or the
/// scene (`settings.bounds`), as oit-wgpu's `depth_bounds`.
pub(crate) fn depth_bounds(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<Rc<Buffer>, OitError> {
    let bounds = ctx.buffer("depth bounds", 2 * u64::from(ctx.pixels), Init::Zero)?;
    ctx.pixel_kernel("bounds", "bounds_init_main", &[&bounds], 0, 0)?;
    match ctx.settings.bounds {
        BoundsMode::Exact => {
            ctx.geometry_pass(&drivers.scene, "bounds", &[&bounds], 0, 0)?;
        }
        BoundsMode::Boxes => {
            let boxes = (drivers.boxes)()?;
            let fragments = ctx.fragments;
            ctx.geometry_pass(&boxes, "bounds", &[&bounds], 0, 0)?;
            // fragments counts the scene's, not the boxes'
            ctx.fragments = fragments;
        }
    }
    ctx.pixel_kernel("bounds", "bounds_finish_main", &[&bounds], 0, 0)?;
    Ok(bounds)
}

fn color(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>, bounds: &Buffer) -> Result<(), OitError> {
    let n = u64::from(oit_core::rules::BDP_COLOR_SUBINTERVALS);
    let colors = ctx.buffer("bdp colour buckets", u64::from(ctx.pixels) * n, Init::Zero)?;
    let arrays = ctx.placeholder()?;
    let buffers = [bounds, &*colors, &*arrays];
    ctx.geometry_pass(&drivers.scene, "bdp", &buffers, 0, MODE_COLOR)?;
    ctx.pixel_kernel("bdp", "color_resolve_main", &buffers, 0, 0)
}

fn depth(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>, bounds: &Buffer) -> Result<(), OitError> {
    let run = ctx.plan.bdp_capture_passes();
    let words = u64::from(ctx.pixels) * 2 * u64::from(oit_core::rules::BDP_DEPTH_SUBINTERVALS) * 2;
    let arrays = ctx.buffer("bdp depth buckets", words * u64::from(run), Init::Zero)?;
    let pairs = words * u64::from(run) / 4;
    let colors = ctx.placeholder()?;
    let buffers = [bounds, &*colors, &*arrays];
    ctx.kernel_over("bdp", "depth_init_main", &buffers, pairs, 0, 0, "depth_init_main")?;
    for p in 0..run {
        ctx.last_pass(p + 1 == run);
        ctx.geometry_pass(&drivers.scene, "bdp", &buffers, p, MODE_DEPTH)?;
        ctx.pixel_kernel("bdp", "depth_settle_main", &buffers, p, MODE_DEPTH)?;
    }
    ctx.last_pass(false);
    ctx.pixel_kernel("bdp", "depth_resolve_main", &buffers, 0, run)
}
