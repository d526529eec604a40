//! `bdp` on the GPU — being ported from oit-cpu's `technique/bdp.rs`.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::GpuCtx;

pub(crate) fn render(ctx: &mut GpuCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let _ = drivers;
    Err(OitError::Unsupported {
        backend: "wgpu".into(),
        what: format!("{} (not ported yet)", ctx.settings.technique),
    })
}
