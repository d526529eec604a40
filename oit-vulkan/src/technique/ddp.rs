//! `ddp` (see oit-wgpu's `technique/ddp.rs`): per peel a geometry pass (u64 atomicMin and
//! atomicMax strictly inside each pixel's open range) and a resolve kernel; transparency and
//! complexity only (the resolve keeps no per-pixel stack to replay the far layers nearest first).

use std::rc::Rc;

use oit_core::{Effect, OitError};

use crate::Drivers;
use crate::ctx::{Init, VkCtx};
use crate::device::Buffer;

/// Refuses the effects ddp's resolve cannot do.
pub(crate) fn check_effect(ctx: &VkCtx<'_>) -> Result<(), OitError> {
    let effect = ctx.settings.effect;
    if matches!(effect, Effect::Transparency | Effect::Complexity) {
        return Ok(());
    }
    Err(OitError::Unsupported {
        backend: "vulkan".into(),
        what: format!(
            "the {effect:?} effect with ddp: the far layers it peels would have to be replayed nearest first from a per-pixel stack, which the GPU resolve does not keep; use dp, fabs, mlp or adp (or the cpu backend)"
        ),
    })
}

/// ddp.wgsl's storage (group 0, bindings 2 to 5), allocated and initialised.
pub(crate) struct Peel {
    near: Rc<Buffer>,
    far: Rc<Buffer>,
    range: Rc<Buffer>,
    /// Pixels that peeled a layer in the last pass.
    pub(crate) peeled: Rc<Buffer>,
}

impl Peel {
    pub(crate) fn new(ctx: &mut VkCtx<'_>) -> Result<Peel, OitError> {
        let px = u64::from(ctx.pixels);
        let near = ctx.buffer("ddp near", px * 2, Init::Fill(u32::MAX))?;
        let far = ctx.buffer("ddp far", px * 2, Init::Zero)?;
        let range = ctx.buffer("ddp range", px * 2, Init::Zero)?;
        let peeled = ctx.buffer("ddp peeled count", 1, Init::Zero)?;
        // the loop's counter is not per-pixel storage
        ctx.storage_bytes -= 4;
        let peel = Peel { near, far, range, peeled };
        ctx.pixel_kernel("ddp", "ddp_init_main", &peel.buffers(), 0, 0)?;
        Ok(peel)
    }

    pub(crate) fn buffers(&self) -> [&Buffer; 4] {
        [&self.near, &self.far, &self.range, &self.peeled]
    }
}

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    check_effect(ctx)?;
    let peel = Peel::new(ctx)?;
    let buffers = peel.buffers();
    super::peel(ctx, &drivers.scene, "ddp", &buffers, &peel.peeled, 0, 0)
}
