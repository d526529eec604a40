//! `fabs:K` (see oit-wgpu's `technique/fabs.rs` and `fabs.wgsl`): slots of a 64-bit (depth bits,
//! primitive id) key and a 32-bit payload, sorted by key; an overflowing pixel keeps its K
//! smallest keys, so the same input gives the same image; `--overflow tail` merges what lies
//! behind the K into a tail (`tail.wgsl`). With `--atomic-storage image` the counters are an
//! `R32_UINT` storage image bumped by `imageAtomicAdd` (module `fabs_image`: the same fabs.wgsl
//! over `shaders/fabs_counters_image.wgsl`); the slots stay in buffers.

use ash::vk;
use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

const FABS_CAPTURE: u32 = 0;
const FABS_KEYS: u32 = 1;
const FABS_PAYLOADS: u32 = 2;
const FABS_TAIL: u32 = 3;
const FABS_WITH_TAIL: u32 = 1;

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let deepest = if ctx.plan.needs_count() { super::count(ctx, &drivers.scene)?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let (module, counters) = if ctx.plan.image_atomics {
        if !ctx.gpu.info.image_atomics_32 {
            return Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!(
                    "--atomic-storage image for {}: '{}' lacks storage-image atomics on R32_UINT; use \
                     --atomic-storage buffer",
                    ctx.settings.technique, ctx.gpu.info.name
                ),
            });
        }
        ctx.storage_image("fabs counters", 8, 1, vk::Format::R32_UINT, 0)?;
        ("fabs_image", ctx.placeholder()?)
    } else {
        ("fabs", ctx.buffer("fabs counters", px, Init::Zero)?)
    };
    let slots = ctx.buffer("fabs slots", px * u64::from(k) * 2, Init::Zero)?;
    let payloads = ctx.buffer("fabs payloads", px * u64::from(k), Init::Zero)?;
    let overflowed = ctx.buffer("fabs overflowed", 1, Init::Zero)?;
    // the flag is bookkeeping, not per-pixel storage (oit-cpu counts none either)
    ctx.storage_bytes -= 4;
    let (tail, tail_words) = super::tail_buffers(ctx)?;
    let buffers = [&*counters, &*slots, &*payloads, &*overflowed, &*tail, &*tail_words];
    let mut tail_ran = false;
    ctx.geometry_pass(&drivers.scene, module, &buffers, FABS_CAPTURE, k)?;
    // sized from the counting pass, no pixel can overflow: no check
    if !ctx.plan.needs_count() {
        ctx.pixel_kernel(module, "overflow_main", &buffers, FABS_CAPTURE, k)?;
        if drivers.scene.gate().is_some() {
            // where a pixel overflowed (the flag stays on the device: the passes are gated by
            // it), the K smallest keys of each overflowing pixel, then their payloads
            for pass in [FABS_KEYS, FABS_PAYLOADS] {
                ctx.geometry_pass_if(&drivers.scene, module, &buffers, pass, k, &overflowed)?;
            }
            if ctx.plan.tail {
                ctx.geometry_pass_if(&drivers.scene, module, &buffers, FABS_TAIL, k, &overflowed)?;
                ctx.note_merged(&tail_words);
            }
        } else if ctx.read_u32(&overflowed)?[0] != 0 {
            // the host's setup: its work list cannot be gated, so the flag is read back
            ctx.geometry_pass(&drivers.scene, module, &buffers, FABS_KEYS, k)?;
            ctx.geometry_pass(&drivers.scene, module, &buffers, FABS_PAYLOADS, k)?;
            if ctx.plan.tail {
                ctx.geometry_pass(&drivers.scene, module, &buffers, FABS_TAIL, k)?;
                tail_ran = true;
            }
        }
    }
    let resolve = if ctx.plan.tail { FABS_WITH_TAIL } else { 0 };
    ctx.pixel_kernel(module, "resolve_main", &buffers, resolve, k)?;
    if tail_ran {
        ctx.merged = u64::from(ctx.read_u32(&tail_words)?[1]);
    }
    Ok(())
}
