//! `reference`: a counting pass, a prefix sum (on the host: one readback), a fill pass into
//! exactly-sized per-pixel lists, a per-pixel sort by (depth, primitive id) and composite.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<Vec<u32>, OitError> {
    let (counts, _) = super::count(ctx, &drivers.scene)?;
    let counts = ctx.read_u32(&counts)?;
    let counts = &counts[..ctx.pixels as usize];
    let mut offsets = Vec::with_capacity(counts.len() + 1);
    let mut total = 0u64;
    let too_many = || OitError::Device("over 2^32 fragments".into());
    for &c in counts {
        offsets.push(u32::try_from(total).map_err(|_| too_many())?);
        total += u64::from(c);
    }
    offsets.push(u32::try_from(total).map_err(|_| too_many())?);
    ctx.gpu.check_storage("the reference's fragment lists", total * 8)?;
    let offsets_buf = ctx.buffer("reference offsets", offsets.len() as u64, Init::Zero)?;
    ctx.upload(&offsets_buf, bytemuck::cast_slice(&offsets))?;
    let cursor = ctx.buffer("reference cursor", u64::from(ctx.pixels), Init::Zero)?;
    let keys = ctx.buffer("reference keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("reference payloads", total, Init::Zero)?;
    let buffers = [&*offsets_buf, &*cursor, &*keys, &*payloads];
    ctx.geometry_pass(&drivers.scene, "reference", &buffers, 0, 0)?;
    ctx.pixel_kernel("reference", "resolve_main", &buffers, 0, 0)?;
    Ok(counts.to_vec())
}
