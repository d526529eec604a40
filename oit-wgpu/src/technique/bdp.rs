//! `bdp` and `bdp:P` on the GPU: bucket depth peeling (Liu et al., HPG 2009, section 3.2), the
//! same passes, storage and resolve as oit-cpu's `technique/bdp.rs` (see its docs), in `bdp.wgsl`.
//! Also the per-pixel depth bounds pass bdp and adp share (`bounds.wgsl`).
//!
//! One difference in layout, not in result: the depth mode's per-pass arrays sit back to back in
//! one buffer (so one binding serves any P, and pass p reads pass p − 1's array from it).

use oit_core::{BoundsMode, OitError};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("bdp.wgsl");
const BOUNDS_WGSL: &str = include_str!("bounds.wgsl");

/// `capture`'s param in `bdp.wgsl`.
const MODE_COLOR: u32 = 0;
const MODE_DEPTH: u32 = 1;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let color_mode = ctx.plan.bdp_color;
    let bounds = depth_bounds(ctx, drivers)?;
    if color_mode { color(ctx, drivers, &bounds) } else { depth(ctx, drivers, &bounds) }
}

/// Per-pixel [zNear, zFar] (two words of depth bits per pixel) from one geometry pass over the
/// instances' bounding boxes or the scene (`settings.bounds`), as oit-cpu's `Ctx::depth_bounds`;
/// pixels nothing reached get [0, 1]. 8 bytes a pixel, as the plan's `depth bounds` array.
pub(crate) fn depth_bounds(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<wgpu::Buffer, OitError> {
    let bounds = ctx.buffer("depth bounds", 2 * u64::from(ctx.pixels), Init::Zero)?;
    ctx.pixel_kernel(BOUNDS_WGSL, "bounds_init_main", &[&bounds], 0, 0)?;
    match ctx.settings.bounds {
        BoundsMode::Exact => {
            ctx.geometry_pass(drivers.scene.as_ref(), BOUNDS_WGSL, &[&bounds], 0, 0)?;
        }
        BoundsMode::Boxes => {
            let boxes = (drivers.boxes)()?;
            let fragments = ctx.fragments;
            ctx.geometry_pass(boxes.as_ref(), BOUNDS_WGSL, &[&bounds], 0, 0)?;
            // fragments counts the scene's, not the boxes'
            ctx.fragments = fragments;
        }
    }
    ctx.pixel_kernel(BOUNDS_WGSL, "bounds_finish_main", &[&bounds], 0, 0)?;
    Ok(bounds)
}

/// A small buffer bound where a pass's WGSL declares a buffer it does not use (not storage).
fn unused(ctx: &GpuCtx<'_>) -> wgpu::Buffer {
    ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("unused binding"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

fn color(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>, bounds: &wgpu::Buffer) -> Result<(), OitError> {
    let n = u64::from(oit_core::rules::BDP_COLOR_SUBINTERVALS);
    let colors = ctx.buffer("bdp colour buckets", u64::from(ctx.pixels) * n, Init::Zero)?;
    let arrays = unused(ctx);
    let buffers = [bounds, &colors, &arrays];
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 0, MODE_COLOR)?;
    ctx.pixel_kernel(WGSL, "color_resolve_main", &buffers, 0, 0)
}

fn depth(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>, bounds: &wgpu::Buffer) -> Result<(), OitError> {
    // one array per capture pass run: P, or fewer under --max-peels (the plan's stop rule)
    let run = ctx.plan.bdp_capture_passes();
    // 16 × (min, max) u64 per pixel per pass
    let words = u64::from(ctx.pixels) * 2 * u64::from(oit_core::rules::BDP_DEPTH_SUBINTERVALS) * 2;
    let arrays = ctx.buffer("bdp depth buckets", words * u64::from(run), Init::Zero)?;
    let pairs = words * u64::from(run) / 4;
    let colors = unused(ctx);
    let buffers = [bounds, &colors, &arrays];
    ctx.kernel_over(WGSL, "depth_init_main", &buffers, pairs, 0, 0, "depth_init_main")?;
    for p in 0..run {
        ctx.last_pass(p + 1 == run);
        ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, p, MODE_DEPTH)?;
        ctx.pixel_kernel(WGSL, "depth_settle_main", &buffers, p, MODE_DEPTH)?;
    }
    ctx.last_pass(false);
    ctx.pixel_kernel(WGSL, "depth_resolve_main", &buffers, 0, run)
}
