//! `reference` on the GPU: a counting pass, a prefix sum (on the host: one readback), a fill pass
//! into exactly-sized per-pixel lists, a per-pixel sort by (depth, primitive id) and composite.

use oit_core::OitError;
use wgpu::util::DeviceExt;

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

/// The technique, and the in-place sort its resolve calls.
const WGSL: &str = concat!(include_str!("reference.wgsl"), "\n", include_str!("sort_entries.wgsl"));

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<Vec<u32>, OitError> {
    let (counts, _) = super::count(ctx, drivers.scene.as_ref())?;
    let counts = ctx.read_u32(&counts)?;
    let mut offsets = Vec::with_capacity(counts.len() + 1);
    let mut total = 0u64;
    for &c in &counts {
        offsets.push(u32::try_from(total).map_err(|_| OitError::Device("over 2^32 fragments".into()))?);
        total += u64::from(c);
    }
    offsets.push(u32::try_from(total).map_err(|_| OitError::Device("over 2^32 fragments".into()))?);
    ctx.gpu.check_storage("the reference's fragment lists", total * 8)?;
    let offsets_buf = ctx.gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("reference offsets"),
        contents: bytemuck::cast_slice(&offsets),
        usage: wgpu::BufferUsages::STORAGE,
    });
    ctx.storage_bytes += offsets.len() as u64 * 4;
    let cursor = ctx.buffer("reference cursor", u64::from(ctx.pixels), Init::Zero)?;
    let keys = ctx.buffer("reference keys", total * 2, Init::Zero)?;
    let payloads = ctx.buffer("reference payloads", total, Init::Zero)?;
    let buffers = [&offsets_buf, &cursor, &keys, &payloads];
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, 0, 0)?;
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, 0, 0)?;
    Ok(counts)
}
