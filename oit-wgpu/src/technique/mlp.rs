//! `mlp:M` on the GPU: extended multi-layer peeling, the same passes, storage and loss accounting
//! as oit-cpu's `technique/mlp.rs` (see its docs), in `mlp.wgsl`: per pass a geometry pass of
//! atomic-min insertion into M u64 words per pixel, strictly behind the previous pass's deepest,
//! and a resolve kernel; one readback of the pass's "overflowed" flag ends the loop after the pass
//! where nothing fell off (⌈N/M⌉ passes), or after `settings.max_peels` passes.

use oit_core::{OitError, Technique};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = include_str!("mlp.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let m = match ctx.settings.technique {
        Technique::Mlp { m } => m,
        other => return Err(OitError::InvalidSettings(format!("{other} is not mlp"))),
    };
    if m == 0 {
        // every fragment would overflow an empty array, every pass
        return Err(OitError::InvalidSettings("mlp:0 holds no layer: use mlp:M with M ≥ 1".into()));
    }
    let px = u64::from(ctx.pixels);
    let slots = ctx.buffer("mlp slots", px * u64::from(m) * 2, Init::Fill(u32::MAX))?;
    // the previous pass's deepest depth (oit-cpu counts 4 bytes a pixel too)
    let deepest = ctx.buffer("mlp deepest", px, Init::Zero)?;
    let overflowed = ctx.buffer("mlp overflowed", 1, Init::Zero)?;
    // the loop's flag is not per-pixel storage
    ctx.storage_bytes -= 4;
    let buffers = [&slots, &deepest, &overflowed];
    super::peel(ctx, drivers.scene.as_ref(), WGSL, &buffers, &overflowed, m, 1)
}
