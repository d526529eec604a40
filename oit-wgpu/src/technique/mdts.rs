//! `mdts:K` and `mdts64:K` on the GPU: the multi-depth test, the same pass, storage and loss
//! accounting as oit-cpu's `technique/mdts.rs` (see its docs), in `mdts.wgsl`: one geometry pass
//! of atomic-min insertion into K sorted words per pixel (two u32 arrays of the paper's 20 + 12-bit
//! packing for `mdts`, one u64 array for `mdts64`), then a resolve kernel. K omitted: sized by a
//! counting pass to the deepest pixel, as oit-cpu does.
//!
//! The arrays end as the K smallest words inserted, sorted, whatever the arrival order, so the
//! result equals oit-cpu's exactly (mdts's packing losses included). `--overflow tail` adds one
//! pass where a pixel overflowed (gated on the device by the flag the capture raises), merging
//! what lies behind the K into a tail (`tail.wgsl`).

use oit_core::{OitError, Technique};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

const WGSL: &str = concat!(
    include_str!("mdts_words.wgsl"),
    "\n",
    include_str!("mdts_keys.wgsl"),
    "\n",
    include_str!("mdts.wgsl"),
    "\n",
    include_str!("tail.wgsl")
);

/// The modes of `mdts.wgsl` (low byte of pass_index).
const MDTS_32: u32 = 0;
const MDTS_64: u32 = 1;
/// Flags of pass_index: the plan has a tail; this pass is the tail pass.
const MDTS_WITH_TAIL: u32 = 0x10000;
const MDTS_TAIL_PASS: u32 = 0x20000;

/// The capture in `mode`, then (where the plan has a tail and a pixel overflowed) the tail pass,
/// then the resolve: `buffers` are the mode's three arrays.
fn passes(
    ctx: &mut GpuCtx<'_>,
    drivers: &Drivers<'_>,
    arrays: [&wgpu::Buffer; 3],
    mode: u32,
    k: u32,
) -> Result<(), OitError> {
    let (tail, tail_words) = super::tail_buffers(ctx)?;
    let unused = ctx.placeholder();
    let buffers = [arrays[0], arrays[1], arrays[2], &unused, &tail, &tail_words];
    let mode = if ctx.plan.tail { mode | MDTS_WITH_TAIL } else { mode };
    ctx.geometry_pass(drivers.scene.as_ref(), WGSL, &buffers, mode, k)?;
    if ctx.plan.tail {
        // gated by the overflow word the capture raised (on the device, no readback)
        ctx.geometry_pass_if(drivers.scene.as_ref(), WGSL, &buffers, mode | MDTS_TAIL_PASS, k, &tail_words)?;
        ctx.note_merged(&tail_words);
    }
    ctx.pixel_kernel(WGSL, "resolve_main", &buffers, mode, k)
}

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let wide = match ctx.settings.technique {
        Technique::Mdts { .. } => false,
        Technique::Mdts64 { .. } => true,
        other => return Err(OitError::InvalidSettings(format!("{other} is not mdts or mdts64"))),
    };
    // the plan refuses Fresnel with the 32-bit words (no room for a normal)
    let deepest = if ctx.plan.needs_count() { super::count(ctx, drivers.scene.as_ref())?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let words = u64::from(ctx.pixels) * u64::from(k);
    if wide {
        let (high, low) = (ctx.placeholder(), ctx.placeholder());
        let slots = ctx.buffer("mdts64 slots", words * 2, Init::Fill(u32::MAX))?;
        return passes(ctx, drivers, [&high, &low, &slots], MDTS_64, k);
    }
    // alpha is not stored: the plan's (the override, else the mean of the objects' alphas)
    let alpha8 = ctx.plan.mdts_alpha8;
    let high = ctx.buffer("mdts high words", words, Init::Fill(u32::MAX))?;
    let low = ctx.buffer("mdts low words", words, Init::Fill(u32::MAX))?;
    let slots = ctx.placeholder();
    passes(ctx, drivers, [&high, &low, &slots], MDTS_32 | alpha8 << 8, k)
}
