//! [`GpuCtx`] as oit-gpu's frame contract: every technique's frame (`oit_gpu::technique`) runs on
//! it, its modules' WGSL taken from oit-shaders' manifest by name.

use std::collections::HashMap;
use std::sync::OnceLock;

use oit_core::plan::Plan;
use oit_core::{GpuFragments, OitError, Settings};
use oit_gpu::{Frame, Init};

use crate::ctx::{Driver, GpuCtx};

/// The technique source of oit-shaders' module `name` (its sources joined; the context puts the
/// prelude before it and the rasterizer after), made once per process.
pub(crate) fn module_source(name: &str) -> Result<&'static str, OitError> {
    static SOURCES: OnceLock<HashMap<&'static str, String>> = OnceLock::new();
    SOURCES
        .get_or_init(|| oit_shaders::MODULES.iter().map(|m| (m.name, mutated(m.name, m.source()))).collect())
        .get(name)
        .map(String::as_str)
        .ok_or_else(|| OitError::Device(format!("oit-shaders has no module '{name}'")))
}

/// `source` of module `name` as this process compiles it: as written, or broken by a test hook
/// ([`oit_core::mutation`]): `OIT_MUTATION=wgpu-fabs-lose-uncounted` drops fabs's loss count
/// (a fragment past K vanishes uncounted: the frame's own `Stats::check_accounting` must refuse
/// it), `wgpu-fabs-ties-reversed` complements the primitive id in fabs's key (equal depths in
/// descending primitive order, uncounted: `checks::exact` on a scene of ties must fail).
/// `tests/tests/mutations.rs` runs under each and requires the failure.
fn mutated(name: &str, source: String) -> String {
    let swap = |from: &str, to: &str| {
        assert!(source.contains(from), "the mutation's text is gone from module {name}: {from}");
        source.replacen(from, to, 1)
    };
    match (name, oit_core::mutation::current()) {
        ("fabs", Some("wgpu-fabs-lose-uncounted")) => swap("            lose(f.pixel);\n", "\n"),
        ("fabs", Some("wgpu-fabs-ties-reversed")) => {
            swap("<< 32u) | u64(f.prim);", "<< 32u) | u64(~f.prim);")
        }
        _ => source,
    }
}

impl<'d> Frame<dyn Driver + 'd> for GpuCtx<'_> {
    type Buffer = wgpu::Buffer;

    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn settings(&self) -> &Settings {
        self.settings
    }

    fn pixels(&self) -> u32 {
        self.pixels
    }

    fn backend(&self) -> &'static str {
        "wgpu"
    }

    fn array(&mut self, label: &str, words: u64, init: Init) -> Result<wgpu::Buffer, OitError> {
        self.buffer(label, words, init)
    }

    fn scratch(&mut self, label: &str, words: u64, init: Init) -> Result<wgpu::Buffer, OitError> {
        GpuCtx::scratch(self, label, words, init)
    }

    fn placeholder(&mut self) -> Result<wgpu::Buffer, OitError> {
        Ok(GpuCtx::placeholder(self))
    }

    fn fill(&mut self, buffer: &wgpu::Buffer, value: u32) -> Result<(), OitError> {
        GpuCtx::fill(self, buffer, value)
    }

    fn copy(&mut self, src: &wgpu::Buffer, dst: &wgpu::Buffer, bytes: u64) -> Result<(), OitError> {
        self.encoder().copy_buffer_to_buffer(src, 0, dst, 0, bytes);
        Ok(())
    }

    fn read_u32(&mut self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, OitError> {
        GpuCtx::read_u32(self, buffer)
    }

    fn last_pass(&mut self, last: bool) {
        GpuCtx::last_pass(self, last);
    }

    fn cut(&mut self, on: bool) {
        GpuCtx::cut(self, on);
    }

    fn note_opaque(&mut self, count: &wgpu::Buffer) {
        GpuCtx::note_opaque(self, count);
    }

    fn geometry_pass(
        &mut self,
        raster: &(dyn Driver + 'd),
        module: &'static str,
        buffers: &[&wgpu::Buffer],
        pass: u32,
        param: u32,
    ) -> Result<(), OitError> {
        let source = module_source(module)?;
        labelled(self, module, |ctx| GpuCtx::geometry_pass(ctx, raster, source, buffers, pass, param))
    }

    fn geometry_pass_counted(
        &mut self,
        raster: &(dyn Driver + 'd),
        module: &'static str,
        buffers: &[&wgpu::Buffer],
        pass: u32,
        param: u32,
    ) -> Result<wgpu::Buffer, OitError> {
        let source = module_source(module)?;
        labelled(self, module, |ctx| ctx.geometry_pass_with_count(raster, source, buffers, pass, param))
    }

    fn geometry_pass_if(
        &mut self,
        raster: &(dyn Driver + 'd),
        module: &'static str,
        buffers: &[&wgpu::Buffer],
        pass: u32,
        param: u32,
        flag: &wgpu::Buffer,
    ) -> Result<(), OitError> {
        let source = module_source(module)?;
        labelled(self, module, |ctx| {
            GpuCtx::geometry_pass_if(ctx, raster, source, buffers, pass, param, flag)
        })
    }

    fn fragments(&self) -> GpuFragments {
        self.fragments
    }

    fn set_fragments(&mut self, fragments: GpuFragments) {
        self.fragments = fragments;
    }

    fn kernel_over(
        &mut self,
        module: &'static str,
        entry: &'static str,
        buffers: &[&wgpu::Buffer],
        invocations: u64,
        pass: u32,
        param: u32,
        label: &'static str,
    ) -> Result<(), OitError> {
        GpuCtx::kernel_over(self, module_source(module)?, entry, buffers, invocations, pass, param, label)
    }

    fn deepest_alike(
        &mut self,
        max: &wgpu::Buffer,
        alike: Box<dyn Fn(u32, u32) -> bool>,
    ) -> Result<u32, OitError> {
        GpuCtx::deepest_alike(self, max, alike)
    }

    fn fragment_capacity(&mut self, count: &wgpu::Buffer, bytes: u64) -> Result<u32, OitError> {
        GpuCtx::fragment_capacity(self, count, bytes)
    }

    /// A driver without a gate (the user's draws, in the embedded pass) still speculates: its
    /// gated passes read their flag back, or, in a recorded frame, run whatever the flag
    /// ([`GpuCtx::geometry_pass_if`]).
    fn take_speculated_peels(&mut self) -> Result<Option<u32>, OitError> {
        Ok(self.speculated_peels.take())
    }

    fn note_peels(&mut self, peels: u32) {
        self.peels_seen = Some(peels);
    }

    fn check_at_end(&mut self, flag: &wgpu::Buffer) {
        GpuCtx::check_at_end(self, flag, 0);
    }

    fn refuse_at_end(&mut self, flag: &wgpu::Buffer, what: String) {
        GpuCtx::refuse_at_end(self, flag, what);
    }

    fn note_merged(&mut self, words: &wgpu::Buffer) {
        GpuCtx::note_merged(self, words);
    }

    fn note_layers(&mut self, counts: &wgpu::Buffer) {
        self.layers_from = Some(counts.clone());
    }
}

/// Runs `pass` (a geometry pass of `module`) with its GPU time labelled as
/// [`oit_gpu::geometry_label`] names it, then puts the default label back.
fn labelled<T>(ctx: &mut GpuCtx<'_>, module: &str, pass: impl FnOnce(&mut GpuCtx<'_>) -> T) -> T {
    ctx.geometry_label = oit_gpu::geometry_label(module);
    let out = pass(ctx);
    ctx.geometry_label = "geometry";
    out
}
