//! One file per technique, next to its WGSL: the same passes, storage and resolve as oit-cpu's
//! `technique/*.rs`, on GPU buffers.

pub(crate) mod adp;
pub(crate) mod bdp;
pub(crate) mod bdp_blend;
pub(crate) mod ddp;
pub(crate) mod ddp_blend;
pub(crate) mod dp;
pub(crate) mod dp_depth;
pub(crate) mod fabs;
pub(crate) mod mdts;
pub(crate) mod mlp;
pub(crate) mod reference;
pub(crate) mod weighted;

use oit_core::OitError;

use crate::ctx::{Driver, GpuCtx, Init};

const COUNT_WGSL: &str = include_str!("count.wgsl");

/// Fragments per pixel from one counting pass (the buffer), and the deepest pixel's count.
pub(crate) fn count(ctx: &mut GpuCtx<'_>, driver: &dyn Driver) -> Result<(wgpu::Buffer, u32), OitError> {
    let counts = ctx.buffer("fragment counts", u64::from(ctx.pixels), Init::Zero)?;
    let max = ctx.buffer("max count", 1, Init::Zero)?;
    ctx.geometry_pass(driver, COUNT_WGSL, &[&counts, &max], 0, 0)?;
    ctx.pixel_kernel(COUNT_WGSL, "max_main", &[&counts, &max], 0, 0)?;
    // sizing storage is not the technique's: oit-cpu does not count it either
    ctx.storage_bytes -= u64::from(ctx.pixels) * 4 + 4;
    let m = ctx.gpu.read_u32(&max)?[0];
    Ok((counts, m))
}
