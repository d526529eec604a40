//! One frame on Vulkan: the frame uniform, the per-pixel resolve state, storage buffers checked
//! against the limits, geometry passes through either rasterizer, per-pixel kernels and the final
//! image, on the same WGSL as oit-wgpu's `GpuCtx` (as SPIR-V). It is the frame contract every
//! technique's frame is written against (`oit_gpu::Frame`, implemented in `frame.rs`).

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use ash::vk;
use oit_core::plan::Plan;
use oit_core::{Camera, Frame, Image, OitError, Scene, Settings, Stats};

use crate::device::{
    Blend, Buffer, DepthTest, Framebuffer, Gpu, GpuImage, GraphicsDesc, PassKey, SetKind, early_pass_key,
    storage_usage,
};
use crate::hardware::HardwareRaster;
use crate::raster::{ComputeRaster, Raster};
use crate::record::SetData;
use crate::record::{Recorder, Vertices};
use oit_gpu::dispatch_size;

pub(crate) use oit_gpu::{ACCT_BINDING, FrameUniform};
use oit_gpu::{MIN_BUFFER_WORDS, OPAQUE_KEYS_BINDING, OPAQUE_RGB_BINDING, STATE_WORDS};

/// A framebuffer the pool keeps: its render pass, its images (in attachment order), itself.
type KeptFramebuffer = (vk::RenderPass, Vec<vk::Image>, Rc<Framebuffer>);

/// Per-pixel buffers and render targets kept between the frames of a prepared scene, by size,
/// format and usage, and the framebuffers made of those targets.
#[derive(Default)]
pub struct BufferPool {
    /// Dropped before the images they are made of (fields drop in order).
    framebuffers: RefCell<Vec<KeptFramebuffer>>,
    free: RefCell<Vec<Rc<Buffer>>>,
    free_images: RefCell<Vec<Rc<GpuImage>>>,
    allocations: Cell<u64>,
}

impl BufferPool {
    /// Gives a buffer taken apart from a frame ([`BufferPool::take`]) back for the next.
    pub(crate) fn give_back(&self, buffer: Rc<Buffer>) {
        self.free.borrow_mut().push(buffer);
    }

    /// Buffers created so far.
    pub fn allocations(&self) -> u64 {
        self.allocations.get()
    }

    /// A device-local buffer of `size` bytes and `usage`, free or new; its contents are whatever
    /// the last frame left.
    pub(crate) fn take(
        &self,
        gpu: &Gpu,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> Result<Rc<Buffer>, OitError> {
        Ok(self.take_marked(gpu, size, usage)?.0)
    }

    /// [`BufferPool::take`], and whether the buffer is new (its contents undefined).
    pub(crate) fn take_marked(
        &self,
        gpu: &Gpu,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> Result<(Rc<Buffer>, bool), OitError> {
        let mut free = self.free.borrow_mut();
        if let Some(i) = free.iter().position(|b| b.size == size && b.usage == usage) {
            return Ok((free.swap_remove(i), false));
        }
        self.allocations.set(self.allocations.get() + 1);
        Ok((Rc::new(gpu.buffer(size, usage, false)?), true))
    }

    /// A free image of `size`, `layers`, `format` and `usage`, else a new one from `make`.
    fn take_image_with(
        &self,
        (size, layers, format, usage, samples): ((u32, u32), u32, vk::Format, vk::ImageUsageFlags, u32),
        make: impl FnOnce() -> Result<GpuImage, OitError>,
    ) -> Result<Rc<GpuImage>, OitError> {
        let mut free = self.free_images.borrow_mut();
        let fits = |i: &Rc<GpuImage>| {
            i.extent == (size.0.max(1), size.1.max(1))
                && i.layers == layers.max(1)
                && i.format == format
                && i.usage == usage
                && i.samples == samples.max(1)
        };
        if let Some(i) = free.iter().position(fits) {
            return Ok(free.swap_remove(i));
        }
        self.allocations.set(self.allocations.get() + 1);
        Ok(Rc::new(make()?))
    }

    /// A render target of `size`, `format` and `usage`, free or new.
    fn take_image(
        &self,
        gpu: &Gpu,
        size: (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: u32,
    ) -> Result<Rc<GpuImage>, OitError> {
        self.take_image_with((size, 1, format, usage, samples), || {
            gpu.image_sampled(size, format, usage, samples)
        })
    }

    /// A storage image of `size`, `layers` and `format` ([`Gpu::storage_image`]), free or new.
    fn take_storage_image(
        &self,
        gpu: &Gpu,
        what: &str,
        size: (u32, u32),
        layers: u32,
        format: vk::Format,
    ) -> Result<Rc<GpuImage>, OitError> {
        self.take_image_with((size, layers, format, crate::device::STORAGE_IMAGE_USAGE, 1), || {
            gpu.storage_image(what, size, layers, format)
        })
    }

    /// The framebuffer of `images` in `pass`, made on first use (the pool keeps the images).
    fn framebuffer(
        &self,
        gpu: &Gpu,
        pass: vk::RenderPass,
        images: &[&GpuImage],
    ) -> Result<Rc<Framebuffer>, OitError> {
        let handles: Vec<vk::Image> = images.iter().map(|i| i.image).collect();
        let mut made = self.framebuffers.borrow_mut();
        if let Some((.., fb)) = made.iter().find(|(p, h, _)| *p == pass && *h == handles) {
            return Ok(fb.clone());
        }
        let fb = Rc::new(gpu.framebuffer(pass, images)?);
        made.push((pass, handles, fb.clone()));
        Ok(fb)
    }
}

/// What the frame knows of the fragments it generates (oit-core's rule, as on oit-wgpu): a
/// frame's count is its first geometry pass's (over the scene), kept on the device in the frame's
/// first-count word and read with the totals at the end, so a pass needs no wait of its own.
pub(crate) use oit_core::GpuFragments as Fragments;

/// One geometry pass of a blend capture ([`VkCtx::blend_pass`]).
pub(crate) struct BlendPass<'b> {
    /// The `build.rs` module (with the vertex stage) and its fragment entry point.
    pub module: &'b str,
    pub fs: &'b str,
    /// The colour targets, then the depth target when `depth`.
    pub targets: &'b [&'b GpuImage],
    /// One per colour target.
    pub blends: &'b [Blend],
    /// One per colour target.
    pub clears: &'b [vk::ClearValue],
    /// A depth test ([`DepthTest::Write`] or [`DepthTest::WriteLess`]) against the last target,
    /// cleared to 1; [`DepthTest::Off`]: none.
    pub depth: DepthTest,
    /// Images the fragment stage reads, as group 2.
    pub previous: &'b [(u32, &'b GpuImage)],
    /// Whether to count the samples that pass in the recorder's occlusion query, for
    /// [`VkCtx::read_occlusion`] (a round trip) or [`VkCtx::fold_occlusion`] (none).
    pub occlusion: bool,
    /// A pass of a speculated peel loop after its first: drawn from the hardware raster's gated
    /// arguments (the gate [`VkCtx::open_gate`] left: every triangle, or none) and counted on the
    /// device where it runs, not here.
    pub gated: bool,
    /// The frame uniform's pass index and parameter for the draw.
    pub pass_index: u32,
    pub param: u32,
}

pub(crate) use oit_gpu::Init;

/// Everything a technique needs for one frame.
pub(crate) struct VkCtx<'a> {
    pub(crate) gpu: &'a Gpu,
    pub(crate) settings: &'a Settings,
    pub(crate) plan: Plan,
    pub(crate) pixels: u32,
    pub(crate) passes: u32,
    pub(crate) fragments: Fragments,
    pub(crate) storage_bytes: u64,
    /// Fragments merged into pixels' tails (`--overflow tail`), read back by the technique.
    pub(crate) merged: u64,
    /// Whether the technique's capture counts its losses; the blend captures do not (as on
    /// oit-wgpu: the blend unit returns no previous value to count by), and their `lost` is
    /// `fragments − captured − occluded`, with no per-pixel losses.
    pub(crate) counts_losses: bool,
    /// Whether the frame composited each sample where its settings alone say the coverage
    /// fraction (plain's blender at several samples, `technique::blend`): its
    /// `Stats::coverage` says `sample`.
    pub(crate) per_sample_blend: bool,
    uniform: FrameUniform,
    state: Rc<Buffer>,
    image: Rc<Buffer>,
    totals: Rc<Buffer>,
    acct: Rc<Buffer>,
    /// The opaque pass's keys and colours (prelude.wgsl's `opaque_keys`, `opaque_rgb`), bound at
    /// group 0's [`OPAQUE_KEYS_BINDING`] and [`OPAQUE_RGB_BINDING`] in every command: the frame's
    /// storage where its plan has an opaque part, else small placeholders.
    opaque: (Rc<Buffer>, Rc<Buffer>),
    /// Where the opaque pass counted its fragments ([`VkCtx::note_opaque`]).
    opaque_from: Option<Rc<Buffer>>,
    /// The first geometry pass's fragment count ([`Fragments::OnDevice`]) in word 0; the opaque
    /// pass's fragments, masked and occluded counts in words 1–3, copied there at the end.
    first_count: Rc<Buffer>,
    pool: &'a BufferPool,
    lent: Vec<Rc<Buffer>>,
    lent_images: Vec<Rc<GpuImage>>,
    /// The frame's storage images (binding, image), bound in group 0 of every command from
    /// their creation on ([`VkCtx::storage_image`]).
    images: Vec<(u32, Rc<GpuImage>)>,
    rec: Recorder<'a>,
    validation_before: u64,
    /// The compute path's setup checks left to the frame's end (`raster::SetupCheck`).
    setup_checks: Vec<crate::raster::SetupCheck>,
    /// What an earlier frame of the same settings read back, taken instead of waiting (each
    /// value once); set by the prepared scene before the technique runs.
    pub(crate) speculated: ReadBack,
    /// What this frame read back where it speculated nothing.
    seen: ReadBack,
    /// Counts on the device that must fit the capacity sized from them, and the bytes an element
    /// takes ([`VkCtx::fragment_capacity`]).
    capacity_checks: Vec<(Rc<Buffer>, u32, u64)>,
    /// Where a gated tail pass counts the fragments it merged (word 1), read at the end
    /// ([`VkCtx::note_merged`]).
    merged_from: Option<Rc<Buffer>>,
    /// Whether the geometry pass being recorded is gated ([`VkCtx::geometry_pass_if`]).
    gated_pass: bool,
    /// Word 5: the gated geometry passes whose gate was open (`gate.wgsl`), read at the end.
    /// Per-pixel fragment counts the frame hands the caller as its `layers` (the reference's),
    /// read back with the image at the end.
    pub(crate) layers_from: Option<Rc<Buffer>>,
    gated_counter: Rc<Buffer>,
    /// Words 0 that must pass their test at the frame's end ([`VkCtx::check_at_end`]).
    end_checks: Vec<EndCheck>,
    /// Flags whose word 0 must be 0 at the frame's end, else the frame fails with
    /// [`OitError::Unsupported`] saying the text ([`VkCtx::refuse_at_end`]).
    refusals: Vec<(Rc<Buffer>, String)>,
    /// Where the frame is sample i of n's frame of the supersampled reference: the running sums
    /// (`supersample.wgsl`), i and n; its end adds its colours there instead of writing its own.
    pub(crate) supersample: Option<(Rc<Buffer>, u32, u32)>,
}

impl Drop for VkCtx<'_> {
    fn drop(&mut self) {
        self.pool.free.borrow_mut().append(&mut self.lent);
        self.pool.free_images.borrow_mut().append(&mut self.lent_images);
    }
}

impl<'a> VkCtx<'a> {
    /// Sets up the frame: uniform, resolve state (initialized), image, totals, loss accounting.
    pub(crate) fn new(
        gpu: &'a Gpu,
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &'a Settings,
        pool: &'a BufferPool,
    ) -> Result<Self, OitError> {
        let plan = Plan::new("vulkan", scene, settings)?;
        let pixels = settings.width * settings.height;
        let state_bytes = u64::from(pixels) * STATE_WORDS * 4;
        gpu.check_storage("the per-pixel resolve state", state_bytes)?;
        // the whole frame's storage against the device's budget, before anything is allocated
        let budget = settings.memory_budget(gpu.memory_budget());
        plan.check_budget(u64::from(pixels), oit_core::plan::Counted::default(), (&budget.0, budget.1))?;
        let uniform = FrameUniform::new(scene, camera, settings, &plan);
        let mut lent = Vec::new();
        let mut take = |bytes: u64| -> Result<Rc<Buffer>, OitError> {
            let b = pool.take(gpu, bytes, storage_usage())?;
            lent.push(b.clone());
            Ok(b)
        };
        let state = take(state_bytes.max(4))?;
        let image = take(u64::from(pixels).max(1) * 4)?;
        let acct = take(u64::from(pixels).max(1) * 12)?;
        let totals = take(16)?;
        let first_count = take(16)?;
        let gated_counter = take(32)?;
        let opaque_bytes = plan.opaque_bytes() * u64::from(pixels);
        let has_opaque = plan.opaque;
        let opaque = if has_opaque {
            gpu.check_storage("the opaque pass's image", opaque_bytes)?;
            let (keys, rgb) = oit_gpu::opaque_words(settings.width, settings.height, settings.samples);
            (take(keys * 4)?, take(rgb * 4)?)
        } else {
            (take(16)?, take(16)?)
        };
        let mut rec = Recorder::new(gpu)?;
        rec.window = settings.region.and_then(|r| r.viewport(crate::hardware::max_viewport_side(gpu)));
        let mut ctx = VkCtx {
            gpu,
            settings,
            plan,
            pixels,
            passes: 0,
            fragments: Fragments::Unset,
            storage_bytes: if has_opaque { opaque_bytes } else { 0 },
            merged: 0,
            counts_losses: true,
            per_sample_blend: false,
            uniform,
            state,
            image,
            totals,
            acct,
            opaque,
            opaque_from: None,
            first_count,
            pool,
            lent,
            lent_images: Vec::new(),
            images: Vec::new(),
            rec,
            validation_before: crate::device::validation_errors(),
            setup_checks: Vec::new(),
            speculated: ReadBack::default(),
            seen: ReadBack::default(),
            capacity_checks: Vec::new(),
            merged_from: None,
            gated_pass: false,
            gated_counter,
            layers_from: None,
            end_checks: Vec::new(),
            refusals: Vec::new(),
            supersample: None,
        };
        let (acct, gated_counter) = (ctx.acct.clone(), ctx.gated_counter.clone());
        ctx.rec.fill(&acct, 0);
        ctx.rec.fill(&gated_counter, 0);
        if has_opaque {
            let (keys, rgb) = ctx.opaque.clone();
            ctx.rec.fill(&keys, u32::MAX);
            ctx.rec.fill(&rgb, 0);
        }
        // all zeros is a pixel's starting resolve state (resolve.wgsl's `PixelState`)
        let state = ctx.state.clone();
        ctx.rec.fill(&state, 0);
        Ok(ctx)
    }

    /// Checks the frame's storage so far, its resolve state and `bytes` more against the memory
    /// budget (`--memory`, else the device's), before they are allocated.
    fn check_budget(&self, bytes: u64) -> Result<(), OitError> {
        let budget = self.settings.memory_budget(self.gpu.memory_budget());
        oit_core::plan::check_total(
            &format!("{} storage of a frame of {} pixels", self.settings.technique, self.pixels),
            self.storage_bytes
                .saturating_add(u64::from(self.pixels) * STATE_WORDS * 4)
                .saturating_add(bytes)
                .saturating_add(self.plan.output_bytes(u64::from(self.pixels))),
            (&budget.0, budget.1),
        )
    }

    /// A storage buffer of `words` 32-bit words for the technique, checked against the limits and
    /// counted in `storage_bytes`.
    pub(crate) fn buffer(&mut self, label: &str, words: u64, init: Init) -> Result<Rc<Buffer>, OitError> {
        self.make_buffer(label, words, init, true)
    }

    /// A storage buffer of `words` words of bookkeeping (a flag, a counter, a sizing count),
    /// checked against the device's limits but not counted in `storage_bytes` (oit-cpu counts
    /// none).
    pub(crate) fn scratch(&mut self, label: &str, words: u64, init: Init) -> Result<Rc<Buffer>, OitError> {
        self.make_buffer(label, words, init, false)
    }

    /// [`VkCtx::buffer`] (`counted`) or [`VkCtx::scratch`].
    fn make_buffer(
        &mut self,
        label: &str,
        words: u64,
        init: Init,
        counted: bool,
    ) -> Result<Rc<Buffer>, OitError> {
        let bytes = words.max(MIN_BUFFER_WORDS) * 4;
        self.gpu.check_storage(label, bytes)?;
        if counted {
            self.check_budget(bytes)?;
            self.storage_bytes += words * 4;
        }
        let (buffer, fresh) = self.pool.take_marked(self.gpu, bytes, storage_usage())?;
        self.lent.push(buffer.clone());
        // a pooled buffer holds the last frame's words, a new one garbage: initialise, unless
        // the frame writes every word it reads (`Init::Unwritten`, a new one marked)
        if let Some(word) = init.fill(fresh) {
            self.rec.fill(&buffer, word);
        }
        Ok(buffer)
    }

    /// A storage image of the frame's size with `layers` layers of `format` (`R32_UINT` or
    /// `R64_UINT`) for the technique's atomics, bound at `binding` of group 0 of every command
    /// from now on: checked against the limits, counted in `storage_bytes` (`texel` bytes a pixel
    /// and layer), from the pool (a steady frame makes none), and every texel set to `fill` in
    /// each of its 32-bit halves.
    pub(crate) fn storage_image(
        &mut self,
        label: &str,
        binding: u32,
        layers: u32,
        format: vk::Format,
        fill: u32,
    ) -> Result<Rc<GpuImage>, OitError> {
        let texel: u64 = if format == vk::Format::R64_UINT { 8 } else { 4 };
        let bytes = u64::from(self.pixels) * u64::from(layers) * texel;
        self.check_budget(bytes)?;
        let image = self.pool.take_storage_image(
            self.gpu,
            label,
            (self.settings.width, self.settings.height),
            layers,
            format,
        )?;
        self.storage_bytes += bytes;
        self.lent_images.push(image.clone());
        self.rec.clear_image(&image, fill);
        self.images.push((binding, image.clone()));
        Ok(image)
    }

    /// The bindings of the frame's storage images (group 0's layout).
    fn image_bindings(&self) -> Vec<u32> {
        self.images.iter().map(|(b, _)| *b).collect()
    }

    /// A small buffer bound where a mode's WGSL declares an array it does not use (not storage).
    pub(crate) fn placeholder(&mut self) -> Result<Rc<Buffer>, OitError> {
        let buffer = self.pool.take(self.gpu, 64, storage_usage())?;
        self.lent.push(buffer.clone());
        Ok(buffer)
    }

    /// Sets every word of `buffer` to `value`.
    pub(crate) fn fill(&mut self, buffer: &Buffer, value: u32) {
        self.rec.fill(buffer, value);
    }

    /// Copies the first `bytes` of `src` to the start of `dst` (in the frame's command stream).
    pub(crate) fn copy(&mut self, src: &Buffer, dst: &Buffer, bytes: u64) {
        self.rec.copy(src, dst, bytes);
    }

    /// Reads a buffer back (waits for everything recorded so far).
    pub(crate) fn read_u32(&mut self, buffer: &Buffer) -> Result<Vec<u32>, OitError> {
        let words = self.rec.read_u32(buffer)?;
        self.check_validation()?;
        Ok(words)
    }

    /// Marks the passes that follow as the last capture pass the plan allows (or not).
    pub(crate) fn last_pass(&mut self, last: bool) {
        self.uniform.last_pass = u32::from(last);
    }

    /// Whether the geometry passes that follow cut their fragments at the opaque pass's depth
    /// (only where the frame has an opaque part).
    pub(crate) fn cut(&mut self, on: bool) {
        self.uniform.opaque[0] = u32::from(on && self.plan.opaque);
    }

    /// Where the opaque pass counted its fragments: copied beside the first count at the end.
    pub(crate) fn note_opaque(&mut self, count: &Rc<Buffer>) {
        self.opaque_from = Some(count.clone());
    }

    /// The buffers every command binds in group 0: the state, acct, the opaque keys and colours.
    fn held(&self) -> [Rc<Buffer>; 4] {
        [self.state.clone(), self.acct.clone(), self.opaque.0.clone(), self.opaque.1.clone()]
    }

    /// Group 0's (binding, buffer) list: the state, the technique's buffers from 2, acct at 15,
    /// the opaque image at 16 and 17.
    fn storage<'b>(held: &'b [Rc<Buffer>; 4], buffers: &[&'b Buffer]) -> Vec<(u32, &'b Buffer)> {
        let [state, acct, keys, rgb] = held;
        let mut out = vec![
            (1, &**state),
            (ACCT_BINDING, &**acct),
            (OPAQUE_KEYS_BINDING, &**keys),
            (OPAQUE_RGB_BINDING, &**rgb),
        ];
        out.extend(buffers.iter().enumerate().map(|(i, b)| (i as u32 + 2, *b)));
        out
    }

    /// One geometry pass of `module`'s `capture` through the frame's rasterizer (either path),
    /// recorded without a wait: the first pass over the scene leaves its fragment count on the
    /// device for the end of the frame ([`Fragments::OnDevice`]).
    pub(crate) fn geometry_pass(
        &mut self,
        raster: &Raster,
        module: &'static str,
        buffers: &[&Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<(), OitError> {
        self.scene_pass(raster, module, buffers, pass_index, param, false).map(|_| ())
    }

    /// [`VkCtx::geometry_pass`], its fragments counted also where it is not the first (`count`);
    /// returns the word that counts them.
    fn scene_pass<'r>(
        &mut self,
        raster: &'r Raster,
        module: &'static str,
        buffers: &[&Buffer],
        pass_index: u32,
        param: u32,
        count: bool,
    ) -> Result<&'r Buffer, OitError> {
        let first = self.fragments == Fragments::Unset;
        // the frame's first scene pass counts the fragments the opaque cut holds back
        self.uniform.opaque[1] = u32::from(first && self.uniform.opaque[0] != 0);
        let generated = self.record_pass(raster, module, buffers, pass_index, param, first || count);
        self.uniform.opaque[1] = 0;
        let generated = generated?;
        self.passes += 1;
        if first {
            self.keep_first_count(generated);
        }
        Ok(generated)
    }

    /// A geometry pass that has work only where word 0 of `flag` (written by the frame's earlier
    /// passes) is not zero, with no round trip: `gate.wgsl` copies the raster's arguments into
    /// their gated copy (zeros where the flag is clear) and counts the pass on the device where it
    /// runs; the pass dispatches or draws from the gated copy ([`Raster::gate`]); the first
    /// geometry pass of a frame is never gated.
    pub(crate) fn geometry_pass_if(
        &mut self,
        raster: &Raster,
        module: &'static str,
        buffers: &[&Buffer],
        pass_index: u32,
        param: u32,
        flag: &Buffer,
    ) -> Result<(), OitError> {
        let (from, to, words) = raster.gate();
        debug_assert_ne!(self.fragments, Fragments::Unset, "the first pass is ungated");
        let counter = self.gated_counter.clone();
        self.kernel_over("gate", "gate_main", &[flag, &counter, from, to], 64, 0, words, "gate")?;
        self.gated_pass = true;
        let run = self.record_pass(raster, module, buffers, pass_index, param, false);
        self.gated_pass = false;
        run.map(|_| ())
    }

    /// Where a gated tail pass counted the fragments it merged (word 1 of `words`, 0 where it did
    /// not run): read back with the frame's end into [`VkCtx::merged`].
    pub(crate) fn note_merged(&mut self, words: &Rc<Buffer>) {
        self.merged_from = Some(words.clone());
    }

    /// Opens the hardware raster's gate for the blend pass recorded next ([`BlendPass::gated`])
    /// where word 0 of `flag` is set, and counts that pass on the device, as
    /// [`VkCtx::geometry_pass_if`] does for a geometry pass.
    pub(crate) fn open_gate(&mut self, raster: &HardwareRaster, flag: &Buffer) -> Result<(), OitError> {
        let (from, to, words) = raster.gate();
        let counter = self.gated_counter.clone();
        self.kernel_over("gate", "gate_main", &[flag, &counter, from, to], 64, 0, words, "gate")
    }

    /// Folds the occlusion query of the last blend pass into word 0 of `flag` on the device (1
    /// where any sample passed, else 0), through `scratch` (8 bytes). No readback.
    pub(crate) fn fold_occlusion(&mut self, scratch: &Buffer, flag: &Buffer) -> Result<(), OitError> {
        self.rec.copy_occlusion(scratch);
        let counter = self.gated_counter.clone();
        self.kernel_over("gate", "occlusion_main", &[flag, &counter, scratch], 1, 0, 0, "gate")
    }

    /// Makes the gate's pipeline ([`VkCtx::geometry_pass_if`]) where it is not yet cached: a frame
    /// that reads its peels back makes it, so the next one, which gates, creates no pipeline.
    pub(crate) fn make_gate_pipeline(&self) -> Result<(), OitError> {
        self.gpu.compute("gate", "gate_main", &[SetKind::Frame(4, self.image_bindings())])?;
        // and the blend captures' fold of their occlusion queries
        self.gpu.compute("gate", "occlusion_main", &[SetKind::Frame(3, self.image_bindings())]).map(|_| ())
    }

    /// The peel count a peel loop found by reading its flags back, for the next frame.
    pub(crate) fn note_peels(&mut self, peels: u32) {
        self.seen.peels = Some(peels);
    }

    /// Leaves word 0 of `flag` to be checked at the frame's end: a frame where it is not 0 ran
    /// on a wrong speculation and must run again ([`Ended::missed`]).
    pub(crate) fn check_at_end(&mut self, flag: &Rc<Buffer>) {
        self.end_checks.push((flag.clone(), Box::new(|word| word == 0)));
    }

    /// Leaves word 0 of `flag` to be checked at the frame's end: where it is not 0 the frame met
    /// what its capture cannot render honestly, and it fails with [`OitError::Unsupported`]
    /// saying `what` (`oit_gpu::Frame::refuse_at_end`).
    pub(crate) fn refuse_at_end(&mut self, flag: &Rc<Buffer>, what: String) {
        self.refusals.push((flag.clone(), what));
    }

    /// The deepest pixel of a counting pass whose count lies in word 0 of `max` (as
    /// `oit_gpu::Frame::deepest_alike`), for a count the frame uses only through a coarser figure: a speculated
    /// value passes the end's check where `alike(speculated, counted)` (adp's batch count, the
    /// same for every set-bin count of a batch of 32), not only where the two are equal.
    pub(crate) fn deepest_alike(
        &mut self,
        max: &Rc<Buffer>,
        alike: impl Fn(u32, u32) -> bool + 'static,
    ) -> Result<u32, OitError> {
        if let Some(d) = self.speculated.deepest.take() {
            self.end_checks.push((max.clone(), Box::new(move |counted| alike(d, counted))));
            return Ok(d);
        }
        let m = self.read_u32(max)?[0];
        self.seen.deepest = Some(m);
        Ok(m)
    }

    /// The capacity, in elements of `bytes` bytes, of arrays sized by a count in word 0 of `count`
    /// on the device (`dfb`'s and `ll`'s fragment total), as oit-wgpu's: the count rounded up to
    /// its size class (`oit_core::plan::size_class`: at most 1/8 more, so nearby views take the
    /// same buffers from the pool; [`Plan::fragment_capacity`] is the rule). Where the frame
    /// speculates the count is an earlier frame's, not waited for; else it is read back now.
    /// Either way it is read again at the frame's end: a count over the capacity makes the frame
    /// run again. The frame's `storage_bytes` are what it allocated: the capacity, not the count.
    pub(crate) fn fragment_capacity(&mut self, count: &Rc<Buffer>, bytes: u64) -> Result<u32, OitError> {
        let counted = match self.speculated.fragments.take() {
            Some(earlier) => earlier,
            None => {
                let n = self.read_u32(count)?[0];
                self.seen.fragments = Some(n);
                n
            }
        };
        let capacity = u32::try_from(self.plan.fragment_capacity(u64::from(counted))).unwrap_or(u32::MAX);
        self.capacity_checks.push((count.clone(), capacity, bytes));
        Ok(capacity)
    }

    /// [`VkCtx::geometry_pass`] counting its fragments into a word of its own, left on the device
    /// for [`VkCtx::fragment_capacity`] (ll's sizing pass).
    pub(crate) fn geometry_pass_kept_count(
        &mut self,
        raster: &Raster,
        module: &'static str,
        buffers: &[&Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<Rc<Buffer>, OitError> {
        let kept = self.scratch("pass fragment count", 1, Init::Zero)?;
        let generated = self.scene_pass(raster, module, buffers, pass_index, param, true)?;
        self.rec.copy(generated, &kept, 4);
        Ok(kept)
    }

    /// Counts the scene's fragments with one count-only draw (a capture that keeps nothing,
    /// `vulkan/no_capture.wgsl`) where no pass has yet, for captures whose passes cannot count
    /// them (a depth test kills fragments before the counter), and those the opaque cut holds
    /// back (`occluded`), as a frame's first scene pass does; not a geometry pass of the
    /// technique.
    pub(crate) fn count_fragments(&mut self, raster: &Raster) -> Result<(), OitError> {
        if self.fragments == Fragments::Unset {
            self.uniform.opaque[1] = self.uniform.opaque[0];
            let generated = self.record_pass(raster, "nothing", &[], 0, 0, true);
            self.uniform.opaque[1] = 0;
            self.keep_first_count(generated?);
        }
        Ok(())
    }

    /// Copies the frame's first pass's fragment count aside, for the end of the frame.
    fn keep_first_count(&mut self, generated: &Buffer) {
        let first_count = self.first_count.clone();
        self.rec.copy(generated, &first_count, 4);
        self.fragments = Fragments::OnDevice;
    }

    /// Records one draw or dispatch of the scene (the caller counts it as a geometry pass or not),
    /// counting its fragments (on the hardware path: the count
    /// image's copy and sum) only when `count`; returns the word that counts them.
    fn record_pass<'r>(
        &mut self,
        raster: &'r Raster,
        module: &'static str,
        buffers: &[&Buffer],
        pass_index: u32,
        param: u32,
        count: bool,
    ) -> Result<&'r Buffer, OitError> {
        self.uniform.pass_index = pass_index;
        self.uniform.param = param;
        // the compute rasterizer's work-item marks: written by the frame's first scene pass, read
        // by the later ones (raster_compute.wgsl's `ITEM_SPENT`)
        self.uniform.opaque[3] = oit_gpu::item_marks(self.fragments == Fragments::Unset);
        let generated = match raster {
            Raster::Compute(r) => self.compute_pass(r, module, buffers),
            Raster::Hardware(r) => self.hardware_pass(r, module, buffers, count),
        };
        self.uniform.opaque[3] = 0;
        generated
    }

    /// Records a geometry pass through the compute rasterizer; returns the word that counts its
    /// fragments.
    fn compute_pass<'r>(
        &mut self,
        raster: &'r ComputeRaster,
        module: &'static str,
        buffers: &[&Buffer],
    ) -> Result<&'r Buffer, OitError> {
        // as oit-wgpu: a workgroup per (triangle, tile) item on GPUs, an invocation per item on a
        // CPU device (lavapipe), where 64 invocations of one small triangle mostly test nothing
        let per_pixel = oit_gpu::raster_per_pixel(self.gpu.is_cpu());
        let entry = if per_pixel { "raster_main" } else { "raster_loop_main" };
        let bindings = self.image_bindings();
        let pipeline = self.gpu.pipeline(module, entry, buffers.len(), &bindings)?;
        let classify = if oit_gpu::classifies_items(&self.uniform) {
            Some(self.gpu.pipeline(module, "classify_main", buffers.len(), &bindings)?)
        } else {
            None
        };
        if let Some(check) = raster.upload(&mut self.rec)? {
            self.setup_checks.push(check);
        }
        self.rec.fill(&raster.generated, 0);
        let held = self.held();
        let storage = Self::storage(&held, buffers);
        let raster_set = raster.bindings();
        let uniform = self.uniform;
        let sets = [
            SetData::Frame { uniform: bytemuck::bytes_of(&uniform), storage: &storage, images: &self.images },
            SetData::Raster { storage: &raster_set, uniform: &raster.uniform },
        ];
        if let Some(classify) = &classify {
            // an invocation an item, before the pass (`oit_gpu::classifies_items`)
            raster.dispatch(&mut self.rec, "classify", classify, &sets, false, false)?;
        }
        let label = oit_gpu::geometry_label(module);
        raster.dispatch(&mut self.rec, label, &pipeline, &sets, per_pixel, self.gated_pass)?;
        Ok(&raster.generated)
    }

    /// Records a geometry pass through the GPU's rasterizer (a draw into the count image, its
    /// copy, and the kernel that sums it); returns the word that counts its fragments.
    fn hardware_pass<'r>(
        &mut self,
        raster: &'r HardwareRaster,
        module: &'static str,
        buffers: &[&Buffer],
        count: bool,
    ) -> Result<&'r Buffer, OitError> {
        let bindings = self.image_bindings();
        let samples = raster.samples();
        // over the opaque depth (one sample): the pass fills a depth attachment from the opaque
        // keys, the frame's first scene pass counts untested, and the capture runs behind the
        // fixed-function test (`core/raster_hardware_early.wgsl`; oit-wgpu's `EarlyDepth`); the
        // interlocked k-buffer keeps its one entry point and tests in its stage
        let early = self.uniform.opaque[0] != 0 && samples == 1 && module != "kbuf";
        let mut draws = Vec::new();
        // whether the pass draws the count-only draw, which counts its fragments in a counter of
        // the opaque colours' buffer (`oit_gpu::opaque_drawn_offset`), not in the count image
        let drawn = early && self.uniform.opaque[1] != 0;
        let (render_pass, framebuffer, clear) = if early {
            draws.push((
                self.gpu.early_pipeline(module, buffers.len(), &bindings, "depth_fs")?,
                Vertices::Count(3),
            ));
            if drawn {
                draws.push((
                    self.gpu.early_pipeline(module, buffers.len(), &bindings, "hw_fs_count")?,
                    self.scene_vertices(raster),
                ));
            }
            draws.push((
                // its count is read only where the pass wants one and has no count-only draw
                self.gpu.early_pipeline(
                    module,
                    buffers.len(),
                    &bindings,
                    if count && !drawn { "hw_fs_early_counted" } else { "hw_fs_early" },
                )?,
                self.scene_vertices(raster),
            ));
            let depth_clear =
                vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } };
            (
                self.gpu.render_pass(&early_pass_key())?,
                raster.early_framebuffer(self.gpu)?,
                vec![vk::ClearValue::default(), depth_clear],
            )
        } else {
            draws.push((
                self.gpu.render_pipeline(module, buffers.len(), &bindings, samples)?,
                self.scene_vertices(raster),
            ));
            (
                self.gpu.render_pass(&crate::device::count_pass_key(samples))?,
                raster.framebuffer(),
                vec![vk::ClearValue::default()],
            )
        };
        raster.upload(&mut self.rec)?;
        let held = self.held();
        let storage = Self::storage(&held, buffers);
        let raster_set = raster.bindings();
        let uniform = self.uniform;
        self.rec.draws(
            oit_gpu::geometry_label(module),
            render_pass,
            framebuffer,
            &clear,
            &[
                SetData::Frame {
                    uniform: bytemuck::bytes_of(&uniform),
                    storage: &storage,
                    images: &self.images,
                },
                SetData::Raster { storage: &raster_set, uniform: raster.uniform() },
            ],
            &draws,
            false,
        )?;
        let (counts, generated) = raster.counters();
        if !count {
            return Ok(generated);
        }
        if drawn {
            // the count image holds nothing of this pass (its capture adds 0 in a frame's first
            // pass): the count-only draw's counter is the pass's count
            let rgb = self.opaque.1.clone();
            let offset = oit_gpu::opaque_drawn_offset(u64::from(self.pixels), self.settings.samples);
            self.rec.fill(generated, 0);
            self.rec.copy_at(&rgb, offset, generated, 0, 4);
            return Ok(generated);
        }
        let (w, h) = raster.target().extent;
        if samples > 1 {
            // every sample of the multisampled count image, read where it lies
            self.rec.fill(generated, 0);
            let invocations = u64::from(w) * u64::from(h);
            let image = [(0, raster.target())];
            self.kernel_with(
                "count_sum_ms",
                "count_sum_main",
                &[generated],
                &image,
                invocations,
                "count sum",
            )?;
            return Ok(generated);
        }
        self.rec.copy_image(raster.target(), counts);
        self.rec.fill(generated, 0);
        self.kernel_over(
            "count_sum",
            "count_sum_main",
            &[counts, generated],
            u64::from(w) * u64::from(h),
            0,
            0,
            "count sum",
        )?;
        Ok(generated)
    }

    /// The scene's draw through `raster`: its vertices, or in a gated pass the gated arguments.
    fn scene_vertices<'r>(&self, raster: &'r HardwareRaster) -> Vertices<'r> {
        if self.gated_pass {
            Vertices::Indirect(raster.gate().1)
        } else {
            Vertices::Count(raster.vertex_count())
        }
    }

    /// Runs compute `entry` of `module` once per pixel (its GPU time under `entry`).
    pub(crate) fn pixel_kernel(
        &mut self,
        module: &'static str,
        entry: &str,
        buffers: &[&Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<(), OitError> {
        self.kernel_over(module, entry, buffers, u64::from(self.pixels), pass_index, param, entry)
    }

    /// Runs compute `entry` of `module` over `invocations` (in 2D rows of 64 × 65535 when needed),
    /// its GPU time under `label` (oit-wgpu's labels: the entry, or "resolve"...).
    #[expect(clippy::too_many_arguments, reason = "a dispatch is that many things, as on oit-wgpu")]
    pub(crate) fn kernel_over(
        &mut self,
        module: &'static str,
        entry: &str,
        buffers: &[&Buffer],
        invocations: u64,
        pass_index: u32,
        param: u32,
        label: &str,
    ) -> Result<(), OitError> {
        self.uniform.pass_index = pass_index;
        self.uniform.param = param;
        self.kernel_with(module, entry, buffers, &[], invocations, label)
    }

    /// Runs compute `entry` of `module` once per pixel with `images` (binding, image) as group 1
    /// (a blend capture's targets, read by `textureLoad`).
    pub(crate) fn image_kernel(
        &mut self,
        module: &'static str,
        entry: &str,
        buffers: &[&Buffer],
        images: &[(u32, &GpuImage)],
        pass_index: u32,
        param: u32,
    ) -> Result<(), OitError> {
        self.uniform.pass_index = pass_index;
        self.uniform.param = param;
        self.kernel_with(module, entry, buffers, images, u64::from(self.pixels), entry)
    }

    /// A dispatch over `invocations` with group 0 and, when any, `images` as group 1.
    fn kernel_with(
        &mut self,
        module: &'static str,
        entry: &str,
        buffers: &[&Buffer],
        images: &[(u32, &GpuImage)],
        invocations: u64,
        label: &str,
    ) -> Result<(), OitError> {
        let bindings = self.image_bindings();
        let mut kinds = vec![SetKind::Frame(buffers.len(), bindings)];
        if !images.is_empty() {
            kinds.push(SetKind::Images(images.iter().map(|(b, _)| *b).collect()));
        }
        let pipeline = self.gpu.compute(module, entry, &kinds)?;
        let held = self.held();
        let storage = Self::storage(&held, buffers);
        let uniform = self.uniform;
        let groups = dispatch_size(invocations);
        let frame =
            SetData::Frame { uniform: bytemuck::bytes_of(&uniform), storage: &storage, images: &self.images };
        if images.is_empty() {
            self.rec.dispatch(label, &pipeline, &[frame], groups)
        } else {
            self.rec.dispatch(label, &pipeline, &[frame, SetData::Images(images)], groups)
        }
    }

    /// A render target of the frame's size for a blend capture, from the pool (a steady frame
    /// makes none), readable by kernels afterwards; counted in `storage_bytes` (`texel` bytes a
    /// pixel).
    pub(crate) fn target(
        &mut self,
        format: vk::Format,
        texel: u64,
        depth: bool,
    ) -> Result<Rc<GpuImage>, OitError> {
        self.target_sampled(format, texel, depth, 1)
    }

    /// [`VkCtx::target`] of `samples` samples a pixel (a multisampled blend capture's colour
    /// target; `texel` bytes a sample).
    pub(crate) fn target_sampled(
        &mut self,
        format: vk::Format,
        texel: u64,
        depth: bool,
        samples: u32,
    ) -> Result<Rc<GpuImage>, OitError> {
        let attachment = if depth {
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        } else {
            vk::ImageUsageFlags::COLOR_ATTACHMENT
        };
        let usage = attachment | vk::ImageUsageFlags::SAMPLED;
        let size = (self.settings.width, self.settings.height);
        let image = self.pool.take_image(self.gpu, size, format, usage, samples)?;
        self.lent_images.push(image.clone());
        self.storage_bytes += u64::from(self.pixels) * texel * u64::from(samples);
        Ok(image)
    }

    /// Leaves `image` in the layout kernels and fragment stages read it in (its contents
    /// undefined): for a target bound before anything rendered into it.
    pub(crate) fn make_readable(&mut self, image: &GpuImage) {
        self.rec.make_readable(image);
    }

    /// One geometry pass of a blend capture: `pass.fs` of `pass.module` over the scene (the
    /// hardware raster's vertex stage) into `pass.targets` (colour attachments, then the depth
    /// attachment when `pass.depth` is a test), with `pass.blends`, group 0's `buffers` and, as group 2,
    /// `pass.previous` (images the fragment stage reads); inside an occlusion query when
    /// `pass.occlusion`. Counted as a geometry pass. Returns the samples that passed (a wait),
    /// or `None` without the query.
    pub(crate) fn blend_pass(
        &mut self,
        raster: &HardwareRaster,
        pass: BlendPass<'_>,
        buffers: &[&Buffer],
    ) -> Result<(), OitError> {
        let has_depth = pass.depth != DepthTest::Off;
        let colors: Vec<vk::Format> =
            pass.targets.iter().take(pass.targets.len() - usize::from(has_depth)).map(|i| i.format).collect();
        let key = PassKey {
            colors,
            depth: has_depth.then(|| pass.targets.last().map(|i| i.format)).flatten(),
            final_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            // the targets' own (a multisampled blend capture's: all alike)
            samples: pass.targets.first().map_or(1, |i| i.samples),
        };
        let bindings = self.image_bindings();
        let mut kinds = vec![SetKind::Frame(buffers.len(), bindings), SetKind::HwRaster];
        if !pass.previous.is_empty() {
            kinds.push(SetKind::Images(pass.previous.iter().map(|(b, _)| *b).collect()));
        }
        let pipeline = self.gpu.graphics(&GraphicsDesc {
            module: pass.module,
            fs: pass.fs,
            sets: &kinds,
            pass: &key,
            blends: pass.blends,
            depth: pass.depth,
        })?;
        let render_pass = self.gpu.render_pass(&key)?;
        let framebuffer = self.pool.framebuffer(self.gpu, render_pass, pass.targets)?;
        self.uniform.pass_index = pass.pass_index;
        self.uniform.param = pass.param;
        raster.upload(&mut self.rec)?;
        let held = self.held();
        let storage = Self::storage(&held, buffers);
        let raster_set = raster.bindings();
        let uniform = self.uniform;
        let mut sets = vec![
            SetData::Frame { uniform: bytemuck::bytes_of(&uniform), storage: &storage, images: &self.images },
            SetData::Raster { storage: &raster_set, uniform: raster.uniform() },
        ];
        if !pass.previous.is_empty() {
            sets.push(SetData::Images(pass.previous));
        }
        let mut clear: Vec<vk::ClearValue> = pass.clears.to_vec();
        if has_depth {
            clear.push(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 },
            });
        }
        // timed under its fragment entry point (`adp_hist_fs`, `bdp_blend_fs`...), so each
        // capture's pass can be told apart from the rest of its frame
        self.rec.draw(
            pass.fs,
            &pipeline,
            render_pass,
            &framebuffer,
            &clear,
            &sets,
            if pass.gated {
                Vertices::Indirect(raster.gate().1)
            } else {
                Vertices::Count(raster.vertex_count())
            },
            pass.occlusion,
        )?;
        if !pass.gated {
            self.passes += 1;
        }
        Ok(())
    }

    /// The samples that passed in the last blend pass with `occlusion`: waits for it (a round
    /// trip inside the frame).
    pub(crate) fn read_occlusion(&mut self) -> Result<u64, OitError> {
        let samples = self.rec.occlusion()?;
        self.check_validation()?;
        Ok(samples)
    }

    /// A validation error since the frame began fails it (`OIT_VULKAN_VALIDATION=1`).
    fn check_validation(&self) -> Result<(), OitError> {
        let now = crate::device::validation_errors();
        if now > self.validation_before {
            return Err(OitError::Device(format!(
                "the Vulkan validation layer reported {} error(s) in this frame (printed above)",
                now - self.validation_before
            )));
        }
        Ok(())
    }

    /// Resolves the state into the frame and its stats, reading back the image and the per-pixel
    /// losses only when `readback` (one wait either way): without, the frame's image is empty
    /// (0 × 0) and `lost_pixels` `None`, as oit-wgpu's `GpuCtx::finish_with` gives them.
    #[cfg(test)]
    pub(crate) fn finish_with(self, readback: bool) -> Result<Frame, OitError> {
        self.finish_start(readback)?.wait()?.frame.ok_or_else(|| {
            OitError::Device("the compute path's setup outgrew its buffers in mid-frame".into())
        })
    }

    /// Records the frame's resolve and its one readback (the totals, the first pass's count, the
    /// setup's counters; the image and per-pixel losses when `readback`) and submits them without
    /// waiting: the frame is in flight until [`Finishing::wait`].
    pub(crate) fn finish_start(mut self, readback: bool) -> Result<Finishing<'a>, OitError> {
        let (image_buf, totals) = (self.image.clone(), self.totals.clone());
        self.rec.fill(&totals, 0);
        let px = u64::from(self.pixels);
        match self.supersample.clone() {
            Some((sums, i, n)) => {
                self.kernel_over("finish", "totals_main", &[&image_buf, &totals], px, 0, 0, "resolve")?;
                self.kernel_over(
                    "supersample",
                    "supersample_main",
                    &[&image_buf, &totals, &sums],
                    px,
                    n,
                    i,
                    "resolve",
                )?;
            }
            None => {
                for entry in oit_gpu::finish_kernels(self.settings.effect) {
                    self.kernel_over("finish", entry, &[&image_buf, &totals], px, 0, 0, "resolve")?;
                }
            }
        }
        let acct_buf = self.acct.clone();
        let first_count = self.first_count.clone();
        if let Some(count) = self.opaque_from.take() {
            let rgb = self.opaque.1.clone();
            self.rec.copy_at(&count, 0, &first_count, 4, 4);
            let counters = oit_gpu::opaque_counters_offset(u64::from(self.pixels), self.settings.samples);
            self.rec.copy_at(&rgb, counters, &first_count, 8, 8);
        }
        let checks = std::mem::take(&mut self.setup_checks);
        let (gated_counter, end_checks) = (self.gated_counter.clone(), std::mem::take(&mut self.end_checks));
        let mut read = vec![&*totals, &*first_count, &*gated_counter];
        read.extend(end_checks.iter().map(|(b, _)| &**b));
        let capacities = std::mem::take(&mut self.capacity_checks);
        read.extend(capacities.iter().map(|(b, _, _)| &**b));
        let merged_from = self.merged_from.take();
        read.extend(merged_from.as_deref());
        let refusals = std::mem::take(&mut self.refusals);
        read.extend(refusals.iter().map(|(b, _)| &**b));
        read.extend(checks.iter().map(|c| &*c.counters));
        let layers_buf = self.layers_from.clone();
        if readback {
            read.push(&*image_buf);
            read.push(&*acct_buf);
            read.extend(layers_buf.as_deref());
        }
        let reading = self.rec.read_start(&read)?;
        let end_checks = end_checks.into_iter().map(|(_, test)| test).collect();
        let capacities = capacities.into_iter().map(|(_, capacity, bytes)| (capacity, bytes)).collect();
        let merged = merged_from.is_some();
        let refusals = refusals.into_iter().map(|(_, what)| what).collect();
        Ok(Finishing { ctx: self, reading, checks, end_checks, capacities, merged, refusals, readback })
    }
}

/// How a frame ended ([`Finishing::wait`]).
pub(crate) struct Ended {
    /// The frame; `None` where it is incomplete (its compute setup outgrew its buffers, or a
    /// speculation missed) and must run again.
    pub(crate) frame: Option<Frame>,
    /// A speculated count was wrong ([`VkCtx::check_at_end`]): the next frame must not speculate.
    pub(crate) missed: bool,
    /// What the frame read back where it speculated nothing.
    pub(crate) seen: ReadBack,
    /// Its first timed command's start and last one's end on the device, in nanoseconds, with
    /// timestamps ([`crate::record::Recorder::gpu_span_ns`]).
    pub(crate) span_ns: Option<(f64, f64)>,
    /// The device's untimed milliseconds before each timed command, by its label, with
    /// timestamps ([`crate::record::Recorder::gpu_gaps`]).
    pub(crate) gaps: Vec<(String, f64)>,
    /// The commands it recorded, by kind.
    pub(crate) counts: crate::record::CommandCounts,
}

/// The counts a frame reads back that the next frame of the same settings may take instead of
/// waiting for them, each checked at that frame's end: a peel loop's pass count
/// (oit-gpu's peel loop), a counting pass's deepest pixel ([`VkCtx::deepest`]) and a fragment total
/// ([`VkCtx::fragment_capacity`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ReadBack {
    pub(crate) peels: Option<u32>,
    pub(crate) deepest: Option<u32>,
    pub(crate) fragments: Option<u32>,
}

impl ReadBack {
    /// What the next frame of these settings takes after a frame that ended fitting (`self`: what
    /// was kept): each value it read back replaces the kept one. A speculated fragment total that
    /// fitted keeps its capacity (the views it fits take the same buffers) unless the frame's own
    /// `fragments` fell under half of it: then the next frame is sized from this one's.
    pub(crate) fn after(self, seen: ReadBack, fragments: Option<u64>) -> ReadBack {
        let shrunk = match (seen.fragments, self.fragments, fragments) {
            (None, Some(earlier), Some(counted)) => u32::try_from(counted)
                .ok()
                .filter(|&c| u64::from(c) * 2 < u64::from(oit_core::plan::size_class(earlier))),
            _ => None,
        };
        ReadBack {
            peels: seen.peels.or(self.peels),
            deepest: seen.deepest.or(self.deepest),
            fragments: seen.fragments.or(shrunk).or(self.fragments),
        }
    }
}

/// A word the frame's end reads back and tests ([`VkCtx::check_at_end`], [`VkCtx::deepest`]).
type EndCheck = (Rc<Buffer>, Box<dyn Fn(u32) -> bool>);

/// A frame submitted with its one readback and not yet waited for ([`VkCtx::finish_start`]): its
/// context (the storage it borrowed from the pool, its recorder) stays with it until the wait.
pub(crate) struct Finishing<'a> {
    ctx: VkCtx<'a>,
    reading: crate::record::Reading,
    checks: Vec<crate::raster::SetupCheck>,
    /// The tests of the words [`VkCtx::check_at_end`] and [`VkCtx::deepest`] left, read after
    /// the gated counter.
    end_checks: Vec<Box<dyn Fn(u32) -> bool>>,
    /// The capacities [`VkCtx::fragment_capacity`] sized, with their element bytes, read after
    /// the end checks.
    capacities: Vec<(u32, u64)>,
    /// Whether [`VkCtx::note_merged`]'s words are read, after the capacities.
    merged: bool,
    /// What the frame refuses where a flag [`VkCtx::refuse_at_end`] left is set, read after the
    /// merged words.
    refusals: Vec<String>,
    readback: bool,
}

impl Finishing<'_> {
    /// Waits for the frame and makes its [`Frame`]; reads the compute path's setup counters left
    /// to the frame's end (`raster::SetupCheck`) in the same wait: `None` where they did not fit
    /// the buffers the frame was set up into (the frame is incomplete; the caller runs it again,
    /// and its setup then sizes first).
    pub(crate) fn wait(self) -> Result<Ended, OitError> {
        let Finishing { mut ctx, reading, checks, end_checks, capacities, merged, refusals, readback } = self;
        let mut words = ctx.rec.read_wait(reading)?;
        ctx.check_validation()?;
        // totals, first count, gated counter, the end checks, the capacities, the merged words,
        // the refusals' flags, then the rest in order
        let flags: Vec<Vec<u32>> = words.drain(3..3 + end_checks.len()).collect();
        let mut missed = flags.iter().zip(&end_checks).any(|(f, test)| f.first().is_none_or(|&w| !test(w)));
        for (counted, &(capacity, _)) in words.drain(3..3 + capacities.len()).zip(&capacities) {
            let counted = counted.first().copied().unwrap_or(u32::MAX);
            missed |= counted > capacity;
        }
        if merged {
            let words = words.remove(3);
            ctx.merged = u64::from(words.get(1).copied().unwrap_or(0));
        }
        // a frame its capture cannot render honestly fails, whether or not it fitted (what it met
        // lies in the scene, and a rerun meets it again)
        for (flag, what) in words.drain(3..3 + refusals.len()).zip(refusals) {
            if flag.first().is_none_or(|&w| w != 0) {
                return Err(OitError::Unsupported { backend: "vulkan".into(), what });
            }
        }
        let gated_ran = words[2].get(5).copied().unwrap_or(0);
        words.remove(2);
        let seen = ctx.seen;
        // every check runs (one that does not fit clears its buffers' trust for the next frame)
        let fits = checks.iter().enumerate().fold(true, |ok, (i, c)| {
            let fit = c.fits(words.get(2 + i).map_or(&[][..], |w| w.as_slice()));
            fit && ok
        });
        let frame = if missed || !fits {
            None
        } else {
            Some(ctx.resolve_counts(words, checks.len(), readback, gated_ran)?)
        };
        let gaps = ctx.rec.gpu_gaps().to_vec();
        Ok(Ended { frame, missed, seen, span_ns: ctx.rec.gpu_span_ns(), gaps, counts: ctx.rec.counts })
    }
}

impl VkCtx<'_> {
    /// The frame's [`Frame`] from its end-of-frame readback's `words` (in
    /// [`VkCtx::finish_start`]'s order).
    fn resolve_counts(
        &self,
        words: Vec<Vec<u32>>,
        checks: usize,
        readback: bool,
        gated_ran: u32,
    ) -> Result<Frame, OitError> {
        let mut words = words.into_iter();
        let t = words.next().unwrap_or_default();
        let first = words.next().unwrap_or_default();
        let mut words = words.skip(checks);
        let (image, acct) = if readback {
            let pixels = words.next().unwrap_or_default();
            let image = Image {
                width: self.settings.width,
                height: self.settings.height,
                pixels: pixels[..self.pixels as usize].iter().map(|w| w.to_le_bytes()).collect(),
            };
            (image, words.next())
        } else {
            (Image { width: 0, height: 0, pixels: Vec::new() }, None)
        };
        let layers = (readback && self.layers_from.is_some()).then(|| words.next()).flatten().map(|mut l| {
            l.truncate(self.pixels as usize);
            l
        });
        // every dispatch's submission has been flushed (the readbacks above), so this is the
        // whole frame's device time
        let (gpu_ms, gpu_pass_ms) = match self.rec.gpu_times() {
            Some((total, passes)) => (Some(total), passes.to_vec()),
            None => (None, Vec::new()),
        };
        let captured = u64::from(t[0]);
        // words 1-3 of the first count are the opaque pass's, where the frame has one
        let opaque_word =
            |w: usize| if self.plan.opaque { first.get(w).copied().map_or(0, u64::from) } else { 0 };
        // derived where `counts_losses` is off (the blend captures): `oit_core::GpuTotals`
        let (fragments, lost, lost_pixels) = oit_core::GpuTotals {
            fragments: self.fragments,
            on_device: u64::from(first[0]),
            captured,
            counted_lost: self.counts_losses.then(|| u64::from(t[3])),
            occluded: opaque_word(3),
            acct: acct.as_deref(),
            pixels: self.pixels as usize,
        }
        .counts();
        let frame = Frame {
            image,
            layers,
            lost_pixels,
            stats: Stats {
                geometry_passes: self.passes + gated_ran,
                fragments,
                captured,
                lost,
                merged: self.merged,
                tied: u64::from(t[2]),
                // set where the frame ends (`Stats::count_packing`)
                quantized: 0,
                storage_bytes: self.storage_bytes,
                wall_ms: 0.0,
                gpu_ms,
                max_layers: t[1],
                gpu_pass_ms,
                tiles: 1,
                opaque_fragments: opaque_word(1),
                masked: opaque_word(2),
                occluded: opaque_word(3),
                // set where the frame ends (`Stats::count_packing`), kept there where it is
                // plain's blender's
                coverage: self.per_sample_blend.then_some(oit_core::msaa::Coverage::Sample),
            },
        };
        if self.counts_losses {
            frame.stats.check_accounting("vulkan")?;
        }
        Ok(frame)
    }
}

#[cfg(test)]
mod tests {
    use oit_core::{Camera, Settings, View, load_scene};

    use super::{BufferPool, VkCtx};

    /// More dispatches than a submission's uniform slots (and timestamp pairs) without a readback:
    /// the recorder flushes in the middle, and the frame's GPU time still adds up.
    #[test]
    fn more_dispatches_than_slots_flush_and_add_up() {
        let Some(vk) = crate::backend_or_skip("more_dispatches_than_slots_flush_and_add_up") else {
            return;
        };
        let gpu = vk.gpu().unwrap();
        let scene = load_scene("planes:4").unwrap();
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        let settings = Settings { width: 8, height: 8, ..Settings::default() };
        let pool = BufferPool::default();
        let mut ctx = VkCtx::new(gpu, &scene, &camera, &settings, &pool).unwrap();
        let (image, totals) = (ctx.image.clone(), ctx.totals.clone());
        let n = 2 * crate::record::SLOTS + 44;
        for _ in 0..n {
            // the frame's totals of an empty state: adds nothing, so the frame stays an empty one
            ctx.kernel_over("finish", "totals_main", &[&image, &totals], 64, 0, 0, "again").unwrap();
        }
        let stats = ctx.finish_with(true).unwrap().stats;
        assert_eq!((stats.fragments, stats.captured, stats.lost), (0, 0, 0));
        println!("timestamps {}: {:?} {:?}", gpu.has_timestamps(), stats.gpu_ms, stats.gpu_pass_ms);
        if gpu.has_timestamps() {
            let total = stats.gpu_ms.unwrap();
            let sum: f64 = stats.gpu_pass_ms.iter().map(|(_, ms)| ms).sum();
            assert!(total > 0.0 && (total - sum).abs() <= 1e-9 * total, "{total} vs {sum}");
            let labels: Vec<&str> = stats.gpu_pass_ms.iter().map(|(l, _)| l.as_str()).collect();
            assert_eq!(labels, ["again", "resolve"]);
        } else {
            assert_eq!(stats.gpu_ms, None);
            assert!(stats.gpu_pass_ms.is_empty());
        }
    }
}
