//! `kbuf[:K]`, the ordered k-buffer (`shaders/kbuf.wgsl`): K sorted (depth key, primitive id)
//! slots and payloads a pixel, updated by a plain read-modify-write inside the fragment stage's
//! ordered interlock (`VK_EXT_fragment_shader_interlock`, added to the `kbuf_hw` module's SPIR-V
//! by `build.rs`). One geometry pass on the hardware raster path (after a counting pass where K
//! is not given), then a resolve that walks the sorted slots. The frame refuses it before
//! anything is allocated on the compute raster path (it has no fragment stage) and on a device
//! without `fragmentShaderPixelInterlock` (lavapipe).

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let deepest = if ctx.plan.needs_count() { super::count(ctx, &drivers.scene)?.1 } else { 0 };
    let k = ctx.plan.slots(deepest);
    let px = u64::from(ctx.pixels);
    let slots = ctx.buffer("kbuf slots", px * u64::from(k) * 2, Init::Fill(u32::MAX))?;
    let payloads = ctx.buffer("kbuf payloads", px * u64::from(k), Init::Zero)?;
    let buffers = [&*slots, &*payloads];
    ctx.geometry_pass(&drivers.scene, "kbuf", &buffers, 0, k)?;
    ctx.pixel_kernel("kbuf", "resolve_main", &buffers, 0, k)?;
    Ok(())
}
