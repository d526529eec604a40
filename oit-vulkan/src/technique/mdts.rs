//! `mdts:K` and `mdts64:K` (see oit-wgpu's `technique/mdts.rs`): one geometry pass of atomic-min
//! insertion into K sorted words per pixel (the paper's 20 + 12-bit packing in two u32 arrays, or
//! one u64 array), then a resolve kernel. On storage buffers, or with `--atomic-storage image` on
//! the paper's storage images: two `R32_UINT` 2D arrays of K layers (`imageAtomicMin`), or one
//! `R64_UINT` where the device has `VK_EXT_shader_image_atomic_int64` (refused elsewhere, naming
//! it), in the modules `mdts_image` / `mdts64_image` (the same mdts.wgsl over
//! `shaders/mdts_*_image.wgsl`).

use ash::vk;
use oit_core::{OitError, Technique};

use crate::Drivers;
use crate::ctx::{Init, VkCtx};
use crate::device::Buffer;

const MDTS_32: u32 = 0;
const MDTS_64: u32 = 1;
const MDTS_WITH_TAIL: u32 = 0x10000;
const MDTS_TAIL_PASS: u32 = 0x20000;

/// The capture, the tail pass where the plan has a tail and a pixel overflowed, the resolve (as
/// oit-wgpu's `mdts.rs`).
fn passes(
    ctx: &mut VkCtx<'_>,
    drivers: &Drivers<'_>,
    module: &'static str,
    arrays: [&Buffer; 3],
    mode: u32,
    k: u32,
) -> Result<(), OitError> {
    let (tail, tail_words) = super::tail_buffers(ctx)?;
    let unused = ctx.placeholder()?;
    let buffers = [arrays[0], arrays[1], arrays[2], &*unused, &*tail, &*tail_words];
    let mode = if ctx.plan.tail { mode | MDTS_WITH_TAIL } else { mode };
    ctx.geometry_pass(&drivers.scene, module, &buffers, mode, k)?;
    let mut tail_ran = false;
    if ctx.plan.tail && drivers.scene.gate().is_some() {
        // gated by the overflow word the capture raised (on the device, no readback); the merged
        // count is read with the frame's end
        ctx.geometry_pass_if(&drivers.scene, module, &buffers, mode | MDTS_TAIL_PASS, k, &tail_words)?;
        ctx.note_merged(&tail_words);
    } else if ctx.plan.tail && ctx.read_u32(&tail_words)?[0] != 0 {
        // the host's setup: its work list cannot be gated, so the flag is read back
        ctx.geometry_pass(&drivers.scene, module, &buffers, mode | MDTS_TAIL_PASS, k)?;
        tail_ran = true;
    }
    ctx.pixel_kernel(module, "resolve_main", &buffers, mode, k)?;
    if tail_ran {
        ctx.merged = u64::from(ctx.read_u32(&tail_words)?[1]);
    }
    Ok(())
}

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let wide = match ctx.settings.technique {
        Technique::Mdts { .. } => false,
        Technique::Mdts64 { .. } => true,
        other => return Err(OitError::InvalidSettings(format!("{other} is not mdts or mdts64"))),
    };
    let deepest = if ctx.plan.needs_count() { super::count(ctx, &drivers.scene)?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let words = u64::from(ctx.pixels) * u64::from(k);
    let alpha8 = ctx.plan.mdts_alpha8;
    if ctx.plan.image_atomics {
        let info = &ctx.gpu.info;
        let (has, what) = if wide {
            (
                info.image_atomics_64,
                "64-bit storage-image atomics (VK_EXT_shader_image_atomic_int64's shaderImageInt64Atomics on R64_UINT)",
            )
        } else {
            (info.image_atomics_32, "storage-image atomics on R32_UINT")
        };
        if !has {
            return Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!(
                    "--atomic-storage image for {}: '{}' lacks {what}; use --atomic-storage buffer",
                    ctx.settings.technique, info.name
                ),
            });
        }
        let unused = [ctx.placeholder()?, ctx.placeholder()?, ctx.placeholder()?];
        let arrays = [&*unused[0], &*unused[1], &*unused[2]];
        if wide {
            ctx.storage_image("mdts64 keys", 8, k, vk::Format::R64_UINT, u32::MAX)?;
            return passes(ctx, drivers, "mdts64_image", arrays, MDTS_64, k);
        }
        ctx.storage_image("mdts high words", 8, k, vk::Format::R32_UINT, u32::MAX)?;
        ctx.storage_image("mdts low words", 9, k, vk::Format::R32_UINT, u32::MAX)?;
        return passes(ctx, drivers, "mdts_image", arrays, MDTS_32 | alpha8 << 8, k);
    }
    if wide {
        let (high, low) = (ctx.placeholder()?, ctx.placeholder()?);
        let slots = ctx.buffer("mdts64 slots", words * 2, Init::Fill(u32::MAX))?;
        return passes(ctx, drivers, "mdts", [&*high, &*low, &*slots], MDTS_64, k);
    }
    let high = ctx.buffer("mdts high words", words, Init::Fill(u32::MAX))?;
    let low = ctx.buffer("mdts low words", words, Init::Fill(u32::MAX))?;
    let slots = ctx.placeholder()?;
    passes(ctx, drivers, "mdts", [&*high, &*low, &*slots], MDTS_32 | alpha8 << 8, k)
}
