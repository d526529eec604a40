//! `mlp:M` (see oit-wgpu's `technique/mlp.rs`): per pass a geometry pass of atomic-min insertion
//! into M u64 words per pixel, strictly behind the previous pass's deepest, and a resolve kernel;
//! the loop (`technique::peel`) ends after the pass that leaves the "overflowed" flag clear.

use oit_core::{OitError, Technique};

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let m = match ctx.settings.technique {
        Technique::Mlp { m } => m,
        other => return Err(OitError::InvalidSettings(format!("{other} is not mlp"))),
    };
    if m == 0 {
        return Err(OitError::InvalidSettings("mlp:0 holds no layer: use mlp:M with M ≥ 1".into()));
    }
    let px = u64::from(ctx.pixels);
    let slots = ctx.buffer("mlp slots", px * u64::from(m) * 2, Init::Fill(u32::MAX))?;
    let deepest = ctx.buffer("mlp deepest", px, Init::Zero)?;
    let overflowed = ctx.buffer("mlp overflowed", 1, Init::Zero)?;
    ctx.storage_bytes -= 4;
    let buffers = [&*slots, &*deepest, &*overflowed];
    super::peel(ctx, &drivers.scene, "mlp", &buffers, &overflowed, m, 1)
}
