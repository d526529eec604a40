//! `ddp` on the GPU: dual depth peeling, the same passes, storage and loss accounting as oit-cpu's
//! `technique/ddp.rs` (see its docs), in `ddp.wgsl`: per peel a geometry pass (u64 atomicMin and
//! atomicMax strictly inside each pixel's open range) and a resolve kernel that counts the pixels
//! it peeled; the loop ends after the pass that peels nothing (⌈N/2⌉ + 1 passes) or after
//! `settings.max_peels` peels.
//!
//! Effects: transparency (the far layer is over-blended into the back colour) and complexity
//! (both layers counted). oit-cpu replays the back layers of the other effects from a per-pixel
//! stack at the end; the GPU resolve state has no stack, so translucency and Fresnel are refused.

use oit_core::{Effect, OitError};

use crate::Drivers;
use crate::ctx::{GpuCtx, Init};

pub(crate) const WGSL: &str = include_str!("ddp.wgsl");

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    check_effect(ctx)?;
    let state = Peel::new(ctx)?;
    let buffers = state.buffers();
    super::peel(ctx, drivers.scene.as_ref(), WGSL, &buffers, &state.peeled, 0, 0)
}

/// The effects ddp resolves on the GPU (for both captures, atomics and blend).
pub(crate) fn check_effect(ctx: &GpuCtx<'_>) -> Result<(), OitError> {
    let effect = ctx.settings.effect;
    if matches!(effect, Effect::Transparency | Effect::Complexity) {
        return Ok(());
    }
    Err(OitError::Unsupported {
        backend: "wgpu".into(),
        what: format!(
            "the {effect:?} effect with ddp: the far layers it peels would have to be replayed nearest first from a per-pixel stack, which the GPU resolve does not keep; use dp, fabs, mlp or adp (or the cpu backend)"
        ),
    })
}

/// ddp.wgsl's storage (group 0, bindings 2 to 5), allocated and initialised.
pub(crate) struct Peel {
    near: wgpu::Buffer,
    far: wgpu::Buffer,
    /// The open depth range left by the previous pass (oit-cpu counts 8 bytes a pixel too).
    range: wgpu::Buffer,
    /// Pixels that peeled a layer in the last pass.
    pub(crate) peeled: wgpu::Buffer,
}

impl Peel {
    pub(crate) fn new(ctx: &mut GpuCtx<'_>) -> Result<Peel, OitError> {
        let px = u64::from(ctx.pixels);
        let near = ctx.buffer("ddp near", px * 2, Init::Fill(u32::MAX))?;
        let far = ctx.buffer("ddp far", px * 2, Init::Zero)?;
        let range = ctx.buffer("ddp range", px * 2, Init::Zero)?;
        let peeled = ctx.buffer("ddp peeled count", 1, Init::Zero)?;
        // the loop's counter is not per-pixel storage
        ctx.storage_bytes -= 4;
        let state = Peel { near, far, range, peeled };
        ctx.pixel_kernel(WGSL, "ddp_init_main", &state.buffers(), 0, 0)?;
        Ok(state)
    }

    /// The buffers in binding order.
    pub(crate) fn buffers(&self) -> [&wgpu::Buffer; 4] {
        [&self.near, &self.far, &self.range, &self.peeled]
    }
}
