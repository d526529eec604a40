//! A test hook, not a user setting: `OIT_MUTATION=<name>` makes one named piece of production
//! code deliberately wrong for the whole process, so that the conformance checks can be shown to
//! fail on a real capture bug rather than on a doctored frame. `tests/tests/mutations.rs` (and
//! `tests/tests/hardware_covered.rs`) run their own test binary again under each name and require
//! the named check to fail; nothing else sets it.
//!
//! The variable is read once per process; unset (every real run), [`active`] is one load of an
//! initialised `OnceLock` and a `None` check. The names, each at the code it breaks:
//!
//! | name | where | the defect |
//! |---|---|---|
//! | `cpu-fabs-lose-uncounted` | oit-cpu `technique/fabs.rs` | a fragment past K dropped without counting it lost |
//! | `cpu-fabs-ties-reversed` | oit-cpu `technique/fabs.rs` | equal depths ordered by descending primitive id |
//! | `cpu-losses-at-pixel-zero` | oit-cpu `technique/mod.rs` (`frame`) | every per-pixel loss reported at pixel 0 |
//! | `wgpu-fabs-lose-uncounted` | oit-wgpu `frame.rs` (fabs.wgsl) | as `cpu-fabs-lose-uncounted`, in the shader |
//! | `wgpu-fabs-ties-reversed` | oit-wgpu `frame.rs` (fabs.wgsl) | as `cpu-fabs-ties-reversed`, in the shader |
//! | `wgpu-blend-count-half` | oit-wgpu `technique/blend.rs` (blend.wgsl) | the blender counts every other primitive's fragments |
//! | `wgpu-capacity-doubled` | oit-wgpu `ctx.rs` (`fragment_capacity`) | dfb's, ll's and the reference's arrays twice their size class |
//! | `wgpu-storage-short` | oit-wgpu `ctx.rs` (`reported_storage`) | a frame reports a word less storage than it allocated |
//! | `hardware-drop-third` | oit-wgpu `hardware.rs` | the hardware raster drops every third primitive |
//!
//! (oit-vulkan compiles its shaders when it is built, so its shaders have no such hook.)

use std::sync::OnceLock;

/// The environment variable naming the mutation.
pub const VAR: &str = "OIT_MUTATION";

/// The mutation this process runs under, if any (read once).
pub fn current() -> Option<&'static str> {
    static NAME: OnceLock<Option<String>> = OnceLock::new();
    NAME.get_or_init(|| std::env::var(VAR).ok().filter(|v| !v.is_empty())).as_deref()
}

/// Whether this process runs under the mutation `name`.
#[inline]
pub fn active(name: &str) -> bool {
    current() == Some(name)
}
