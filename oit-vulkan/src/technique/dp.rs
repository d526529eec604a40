//! `dp` (see oit-wgpu's `technique/dp.rs`): per peel a geometry pass (u64 atomicMin strictly
//! behind the previous layer) and a resolve kernel counting the pixels it peeled; the loop
//! (`technique::peel`) ends after the pass that peels nothing, or after `--max-peels`.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let px = u64::from(ctx.pixels);
    let nearest = ctx.buffer("dp nearest", px * 2, Init::Fill(u32::MAX))?;
    let previous = ctx.buffer("dp previous depth", px, Init::Zero)?;
    let peeled = ctx.buffer("dp peeled count", 1, Init::Zero)?;
    ctx.storage_bytes -= 4;
    let buffers = [&*nearest, &*previous, &*peeled];
    super::peel(ctx, &drivers.scene, "dp", &buffers, &peeled, 0, 0)
}
