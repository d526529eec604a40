//! `dp` on the GPU: classical depth peeling, the same passes, storage and loss accounting as
//! oit-cpu's `technique/dp.rs` (see its docs), in `dp.wgsl`. Each peel is a geometry pass (u64
//! atomicMin of (depth, payload) strictly behind the previous layer) and a resolve kernel that
//! counts the pixels it peeled; one readback of that count per peel ends the loop after the pass
//! that peels nothing (N + 1 passes), or after `settings.max_peels` peels.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("dp.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let px = u64::from(ctx.pixels);
    let nearest = ctx.buffer("dp nearest", px * 2, Init::Fill(u32::MAX))?;
    // the previous pass's depth buffer (oit-cpu counts 4 bytes a pixel too)
    let previous = ctx.buffer("dp previous depth", px, Init::Zero)?;
    let peeled = ctx.buffer("dp peeled count", 1, Init::Zero)?;
    // the loop's counter is not per-pixel storage
    ctx.storage_bytes -= 4;
    let buffers = [&nearest, &previous, &peeled];
    super::peel(ctx, drivers.scene.as_ref(), WGSL, &buffers, &peeled, 0, 0)
}
