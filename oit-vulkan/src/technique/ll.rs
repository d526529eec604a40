//! `ll` (see oit-wgpu's `technique/ll.rs` and `ll.wgsl`): a sizing pass that stores nothing (the
//! geometry pass counts its fragments), a pool of nodes sized from its count's size class
//! (`VkCtx::fragment_capacity`), the capture by atomic
//! counter and head exchange, and a per-pixel walk, sort by (depth, primitive id) and composite.

use oit_core::OitError;

use crate::Drivers;
use crate::ctx::{Init, VkCtx};

/// `LL_END` of `ll.wgsl`: an empty list's head, a last node's link.
const END: u32 = u32::MAX;

pub(crate) fn render(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let generated = ctx.geometry_pass_kept_count(&drivers.scene, "ll_size", &[], 0, 0)?;
    // a u64 key, a u32 payload and a u32 link a node
    let nodes = ctx.fragment_capacity(&generated, 16)?;
    let nodes = ctx.plan.check_fragments(u64::from(nodes))?;
    let heads = ctx.buffer("ll heads", u64::from(ctx.pixels), Init::Fill(END))?;
    let counter = ctx.buffer("ll node counter", 1, Init::Zero)?;
    let keys = ctx.buffer("ll keys", u64::from(nodes) * 2, Init::Zero)?;
    let payloads = ctx.buffer("ll payloads", u64::from(nodes), Init::Zero)?;
    let links = ctx.buffer("ll links", u64::from(nodes), Init::Fill(END))?;
    let buffers = [&*heads, &*counter, &*keys, &*payloads, &*links];
    ctx.geometry_pass(&drivers.scene, "ll", &buffers, 0, nodes)?;
    ctx.pixel_kernel("ll", "resolve_main", &buffers, 0, nodes)
}
