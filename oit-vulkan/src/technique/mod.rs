//! What only raw Vulkan does of a technique's frame: the hardware path's own captures
//! (`blend.rs`: the blender, MAX blending into eight targets, the depth test, logic-op OR). Every
//! technique's frame otherwise is oit-gpu's (`oit_gpu::technique`), run on [`VkCtx`]'s
//! implementation of the frame contract (`crate::frame`); the ordered k-buffer's interlock is
//! its module's SPIR-V rewrite in `build.rs`.
//!
//! [`VkCtx`]: crate::ctx::VkCtx

pub(crate) mod blend;
