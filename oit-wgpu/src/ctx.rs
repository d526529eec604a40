//! One frame on the GPU: the frame uniform, the per-pixel resolve state, storage buffers checked
//! against the limits, geometry passes through a [`Driver`] (compute or hardware rasterizer),
//! per-pixel kernels, GPU timestamps, and the final image — the GPU twin of oit-cpu's `Ctx`.

use oit_core::plan::Plan;
use oit_core::{Camera, Frame, Image, OitError, Scene, Settings, Stats};

use crate::gpu::Gpu;
use crate::pool::BufferPool;

/// The buffers a frame took from a pool, given back when the frame's context goes.
struct Lent<'a> {
    pool: Option<&'a BufferPool>,
    buffers: Vec<wgpu::Buffer>,
}

impl Drop for Lent<'_> {
    fn drop(&mut self) {
        if let Some(pool) = self.pool {
            pool.give_back(self.buffers.drain(..));
        }
    }
}

/// A frame's GPU timestamps: each timed pass writes its own pair of queries, and the pairs are
/// resolved and read back together at the end of the frame (or when the set is full), not
/// after each pass: a readback per pass was a CPU–GPU round trip per pass (issue 10).
struct Timestamps<'a> {
    gpu: &'a Gpu,
    set: Option<wgpu::QuerySet>,
    resolve: wgpu::Buffer,
    /// The label of each pair written so far (pair i is queries 2i and 2i + 1).
    labels: Vec<String>,
}

impl Timestamps<'_> {
    fn set(&self) -> &wgpu::QuerySet {
        // present from creation until drop
        self.set.as_ref().expect("a frame's timestamp set lives as long as the frame")
    }
}

impl Drop for Timestamps<'_> {
    fn drop(&mut self) {
        if let Some(set) = self.set.take() {
            self.gpu.give_back_queries(set);
        }
    }
}

/// Where the fragments of the frame's first scene pass are known (`GpuCtx::fragments`): oit-core's
/// rule, shared with oit-vulkan.
pub use oit_core::GpuFragments as Fragments;

/// The command encoder a frame records into: its own (submitted where the frame must read
/// something back, and at its end), or the caller's ([`GpuCtx::recording`]: the embedded pass's
/// `OitPass::record`, which submits nothing and reads nothing back).
pub enum Enc<'a> {
    /// The frame's own, created on first use.
    Own(wgpu::CommandEncoder),
    /// The caller's.
    Caller(&'a mut wgpu::CommandEncoder),
}

impl std::ops::Deref for Enc<'_> {
    type Target = wgpu::CommandEncoder;
    fn deref(&self) -> &wgpu::CommandEncoder {
        match self {
            Enc::Own(e) => e,
            Enc::Caller(e) => e,
        }
    }
}

impl std::ops::DerefMut for Enc<'_> {
    fn deref_mut(&mut self) -> &mut wgpu::CommandEncoder {
        match self {
            Enc::Own(e) => e,
            Enc::Caller(e) => e,
        }
    }
}

/// Slots of the frame uniform's ring: each pass binds its own slot, so the passes of one
/// submission see their own pass index and parameter (a frame with more passes submits what it
/// has recorded and starts the ring over).
const UNIFORM_SLOTS: u64 = 64;
/// Bytes between slots: the largest `min_uniform_buffer_offset_alignment` wgpu allows.
const UNIFORM_STRIDE: u64 = 256;

/// The totals' word counting the gated geometry passes that ran ([`GpuCtx::geometry_pass_if`]).
const GATED_WORD: u64 = 5;
/// The totals' word holding the fragments merged into tails ([`GpuCtx::note_merged`]).
const MERGED_WORD: u64 = 6;
/// The totals' words holding the opaque pass's fragments ([`GpuCtx::note_opaque`]), then its
/// masked and occluded counters (copied from the opaque colours' buffer at the frame's end).
const OPAQUE_WORD: u64 = 8;
/// Bytes of the totals: 12 words.
pub(crate) const TOTALS_BYTES: u64 = 48;

/// Where a geometry pass leaves its count of generated fragments: word 0 of this buffer, written
/// by the pass's submission (a [`Driver`] returns it instead of reading it back, so a pass costs
/// no round trip; [`GpuCtx::geometry_pass_with_count`] keeps it for a technique that sizes from it).
pub struct Generated(pub wgpu::Buffer);

/// The compute path's setup, not yet checked: it wrote at most `tri_capacity` pieces and
/// `item_capacity` work items, and counted how many it needed in `counters` (words 0 and 1). A
/// prepared scene whose earlier frame fitted does not wait for these mid-frame; the frame reads
/// them back at its end with everything else ([`GpuCtx::finish_checked`]) and runs again, with
/// grown buffers, the rare time they did not fit.
pub struct SetupCheck {
    /// The setup's counters (pieces, work items).
    pub counters: wgpu::Buffer,
    /// The setup pass's resolved timestamps (two u64), where the device has them.
    pub stamps: Option<wgpu::Buffer>,
    /// Pieces the triangle buffer holds.
    pub tri_capacity: u64,
    /// Work items the work list holds.
    pub item_capacity: u64,
}

/// The totals' word that holds the first scene pass's fragments (after finish.wgsl's four).
const FRAGMENTS_WORD: u64 = 4;

/// WGSL every technique module starts with (after `COMMON_WGSL`): bindings 0 and 1 of group 0 and
/// the resolve functions.
pub const TECHNIQUE_PRELUDE: &str = oit_shaders::PRELUDE;

const FINISH_WGSL: &str = oit_shaders::text("core/finish.wgsl");
const SUPERSAMPLE_WGSL: &str = oit_shaders::text("core/supersample.wgsl");
const FILL_WGSL: &str = oit_shaders::text("core/fill.wgsl");

use oit_gpu::{ACCT_BINDING, MIN_BUFFER_WORDS, OPAQUE_KEYS_BINDING, OPAQUE_RGB_BINDING, STATE_WORDS};

pub use oit_gpu::FrameUniform;

/// A rasterizer that runs one geometry pass: every fragment of the scene calls the technique's
/// `capture` function (WGSL in `source`, which starts with [`TECHNIQUE_PRELUDE`]'s bindings).
pub trait Driver {
    /// Which path this is.
    fn path(&self) -> oit_core::RasterPath;
    /// Runs one geometry pass (submitted, not waited for); returns where it counted the
    /// fragments it generated. A render-pipeline pass counts them only where the count is read
    /// (a frame's first scene pass, a pass of [`GpuCtx::geometry_pass_with_count`]); elsewhere
    /// word 0 of what it returns is left as it was.
    fn geometry_pass(
        &self,
        ctx: &mut GpuCtx<'_>,
        source: &str,
        layout0: &wgpu::BindGroupLayout,
        group0: &wgpu::BindGroup,
    ) -> Result<Generated, OitError>;

    /// Device milliseconds of the work this driver did for the frame before its first pass
    /// (the compute path's GPU setup), once: the next call gives `None`. The frame adds it to its
    /// GPU time as `setup`.
    fn take_setup_ms(&self) -> Option<f64> {
        None
    }

    /// The setup's capacity check this driver left to the end of the frame, once.
    fn take_setup_check(&self) -> Option<SetupCheck> {
        None
    }

    /// Where this driver's gated passes take their arguments ([`GpuCtx::geometry_pass_if`]);
    /// `None` where its draws are not oit's to gate (the user's, in the embedded pass).
    fn gate(&self) -> Option<Gate> {
        None
    }

    /// oit's own vertex stage of the scene, for techniques with their own render pipelines
    /// (`--hardware-capture blend`); `None` where the draws are not oit's (the compute
    /// rasterizer, the embedded pass).
    fn scene_stage(&self) -> Option<&crate::stage::SceneStage> {
        None
    }
}

/// The rasterizers of one frame: the scene's, and (made on demand) one for the instances'
/// bounding boxes, on the same path (bdp and adp render boxes for each pixel's depth range).
pub struct Drivers<'a> {
    /// Rasterizes the scene.
    pub scene: Box<dyn Driver + 'a>,
    /// Makes a rasterizer of the instances' bounding boxes.
    pub boxes: Box<dyn Fn() -> Result<Box<dyn Driver + 'a>, OitError> + 'a>,
    /// Rasterizes the frame's opaque part, where it has one (oit-gpu's `technique::opaque_pass`).
    pub opaque: Option<Box<dyn Driver + 'a>>,
}

impl<'a> oit_gpu::Rasters<dyn Driver + 'a> for Drivers<'a> {
    fn scene(&self) -> &(dyn Driver + 'a) {
        self.scene.as_ref()
    }

    fn with_boxes(
        &self,
        pass: &mut dyn FnMut(&(dyn Driver + 'a)) -> Result<(), OitError>,
    ) -> Result<(), OitError> {
        pass((self.boxes)()?.as_ref())
    }

    fn opaque(&self) -> Option<&(dyn Driver + 'a)> {
        self.opaque.as_deref()
    }
}

/// A driver's indirect arguments for gated passes: `words` words copied from `from` to `to`
/// where the gate is open, zeros where it is closed; the driver's gated passes dispatch or draw
/// from `to`.
pub struct Gate {
    /// The arguments of an ungated pass.
    pub from: wgpu::Buffer,
    /// The gated copy (`STORAGE | INDIRECT`).
    pub to: wgpu::Buffer,
    /// Words of arguments.
    pub words: u32,
}

pub use oit_gpu::Init;

/// Everything a technique needs for one frame on the GPU.
pub struct GpuCtx<'a> {
    /// The device.
    pub gpu: &'a Gpu,
    /// The scene.
    pub scene: &'a Scene,
    /// The camera.
    pub camera: &'a Camera,
    /// The settings.
    pub settings: &'a Settings,
    /// The frame's plan: refusals, sizing and stop rules, oit-core's.
    pub plan: Plan,
    /// Pixels in the image.
    pub pixels: u32,
    /// Geometry passes so far.
    pub passes: u32,
    /// Fragments one pass generates (the first scene pass's).
    pub fragments: Fragments,
    /// Bytes of per-pixel storage allocated (state excluded, as oit-cpu's count excludes its own).
    pub storage_bytes: u64,
    uniform_buffer: wgpu::Buffer,
    uniform: FrameUniform,
    /// The per-pixel resolve state.
    pub state: wgpu::Buffer,
    timestamps: Option<Timestamps<'a>>,
    image: wgpu::Buffer,
    totals: wgpu::Buffer,
    /// Loss accounting, 3 words a pixel (prelude.wgsl's `acct`): fragments lost, counted where
    /// each is lost; fragments a pass saw at the depths the previous pass peeled; and how many
    /// of those that pass captured. Bound at group 0, binding 15, in every module.
    acct: wgpu::Buffer,
    /// The opaque pass's keys and colours (prelude.wgsl's `opaque_keys`, `opaque_rgb`), bound at
    /// group 0's [`OPAQUE_KEYS_BINDING`] and [`OPAQUE_RGB_BINDING`] in every module: the frame's
    /// storage where its plan has an opaque part, else placeholders.
    opaque: (wgpu::Buffer, wgpu::Buffer),
    /// Where the opaque pass counted its fragments ([`GpuCtx::note_opaque`]).
    opaque_from: Option<wgpu::Buffer>,
    /// Whether the technique's capture counts its losses where they happen; the
    /// `--hardware-capture blend` captures do not (the blend unit returns no previous value): their
    /// `lost` is `fragments − captured − occluded`, with no per-pixel losses.
    pub counts_losses: bool,
    /// Whether the frame composited each sample where its settings alone say the coverage
    /// fraction (plain's blender at several samples, `technique::blend`): its
    /// `Stats::coverage` says `sample`.
    pub per_sample_blend: bool,
    /// The setup checks the frame's drivers left to its end.
    checks: Vec<SetupCheck>,
    /// The deepest pixel an earlier frame of this prepared scene counted at this size and
    /// technique: the counting pass's result is taken to be this without waiting for it, and
    /// checked at the frame's end (the frame runs again where it differs).
    pub speculated_deepest: Option<u32>,
    /// The deepest pixel this frame's counting pass read back (none when it was speculated).
    pub deepest_seen: Option<u32>,
    /// The passes an earlier frame of this prepared scene's peel loop ran at this view's kind:
    /// this frame records as many without reading back in between, and checks at its end
    /// (oit-gpu's peel loop).
    pub speculated_peels: Option<u32>,
    /// The passes this frame's peel loop ran, reading back (none when speculated).
    pub peels_seen: Option<u32>,
    /// Speculated counts to check at the end: the buffer holding the count, and the value used.
    sizing_checks: Vec<(wgpu::Buffer, SizeCheck)>,
    /// The fragment total an earlier frame of this prepared scene counted at this size,
    /// technique and view kind: `dfb`'s and `ll`'s arrays are sized from it without waiting for
    /// this frame's count ([`GpuCtx::fragment_capacity`]).
    pub speculated_fragments: Option<u32>,
    /// The fragment total this frame read back (none when speculated).
    pub fragments_seen: Option<u32>,
    /// Capacities to check at the end ([`GpuCtx::fragment_capacity`]): the buffer holding the
    /// count, the capacity allocated, and the bytes a counted element takes.
    capacity_checks: Vec<(wgpu::Buffer, u32, u64)>,
    /// Flags to check at the end ([`GpuCtx::refuse_at_end`]): where word 0 of the buffer is not
    /// 0, the frame fails with [`OitError::Unsupported`] saying the text.
    refusals: Vec<(wgpu::Buffer, String)>,
    gpu_ms: f64,
    pass_ms: Vec<(String, f64)>,
    lent: Lent<'a>,
    /// What the frame has recorded and not yet submitted (or the caller's encoder).
    encoder: Option<Enc<'a>>,
    /// Whether the frame records into the caller's encoder: nothing is submitted or read back.
    pub recording: bool,
    /// The next free slot of the uniform ring.
    uniform_slot: u64,
    /// Geometry passes recorded behind a gate ([`GpuCtx::geometry_pass_if`]): whether each ran
    /// is counted on the device, in the totals.
    gated_passes: u32,
    /// Set where a recorded frame ran out of uniform slots (its commands are then wrong).
    ring_full: bool,
    /// Whether the geometry pass being recorded is gated: its driver draws or dispatches from
    /// its gated arguments.
    pub gated_pass: bool,
    /// The GPU time label of the geometry pass being recorded ([`oit_gpu::geometry_label`]:
    /// `"opaque"` for the opaque pass's, else `"geometry"`).
    pub geometry_label: &'static str,
    /// Whether the compute raster's pass being recorded runs `classify_main` first
    /// ([`oit_gpu::classifies_items`], set with the scene pass's group 0).
    pub classify_items: bool,
    /// Whether the geometry pass being recorded must leave its fragment count in its counter
    /// ([`GpuCtx::geometry_pass_with_count`]), as a frame's first scene pass always does: a
    /// render-pipeline pass sums its count target only then ([`Driver::geometry_pass`]).
    pub(crate) count_wanted: bool,
    /// Where the frame's tail pass left the merged count, copied into the totals at the end.
    merged_from: Option<wgpu::Buffer>,
    /// Per-pixel fragment counts the frame hands the caller as its `layers` (the reference's),
    /// read back with the image at the end.
    pub(crate) layers_from: Option<wgpu::Buffer>,
    /// Where the frame is sample i of n's frame of the supersampled reference: the running sums
    /// (`supersample.wgsl`), i and n; its end adds its colours there instead of writing its own.
    pub(crate) supersample: Option<(wgpu::Buffer, u32, u32)>,
    /// When the frame began on the host (for `OIT_HOST_TIMES`).
    started: std::time::Instant,
}

impl<'a> GpuCtx<'a> {
    /// Sets up the frame: uniform and resolve state (initialized). Every buffer is new.
    pub fn new(
        gpu: &'a Gpu,
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &'a Settings,
    ) -> Result<Self, OitError> {
        GpuCtx::with_pool(gpu, scene, camera, settings, None)
    }

    /// [`GpuCtx::with_pool`] recording into `encoder`, the caller's: the frame submits nothing
    /// and reads nothing back (a step that would, a sizing or a peel's stop, is an error), and
    /// measures no GPU time. [`GpuCtx::finish_recorded`] ends it.
    pub fn recording(
        gpu: &'a Gpu,
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &'a Settings,
        pool: Option<&'a BufferPool>,
        encoder: &'a mut wgpu::CommandEncoder,
    ) -> Result<Self, OitError> {
        GpuCtx::make_ctx(gpu, scene, camera, settings, pool, Some(encoder))
    }

    /// A buffer from the pool (or new without one), given back when the frame ends.
    fn make(&mut self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.make_marked(label, size, usage).0
    }

    /// [`GpuCtx::make`], and whether the buffer is new (zeroed, as wgpu makes every buffer; else
    /// it holds an earlier frame's words).
    fn make_marked(&mut self, label: &str, size: u64, usage: wgpu::BufferUsages) -> (wgpu::Buffer, bool) {
        let (buffer, fresh) = match self.lent.pool {
            Some(pool) => pool.take_marked(&self.gpu.device, label, size, usage),
            None => {
                let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                });
                (buffer, true)
            }
        };
        self.lent.buffers.push(buffer.clone());
        (buffer, fresh)
    }

    /// A 16-byte storage buffer for a binding the frame does not use, from the pool where the
    /// frame has one.
    pub(crate) fn placeholder(&mut self) -> wgpu::Buffer {
        self.make("unused binding", 16, wgpu::BufferUsages::STORAGE)
    }

    /// [`GpuCtx::new`] taking its buffers from `pool` (a prepared scene's), where there is one.
    pub fn with_pool(
        gpu: &'a Gpu,
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &'a Settings,
        pool: Option<&'a BufferPool>,
    ) -> Result<Self, OitError> {
        GpuCtx::make_ctx(gpu, scene, camera, settings, pool, None)
    }

    fn make_ctx(
        gpu: &'a Gpu,
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &'a Settings,
        pool: Option<&'a BufferPool>,
        caller: Option<&'a mut wgpu::CommandEncoder>,
    ) -> Result<Self, OitError> {
        let recording = caller.is_some();
        let plan = Plan::new("wgpu", scene, settings)?;
        plan.refuse_image_atomics("wgpu")?;
        plan.refuse_interlock("wgpu", "WGSL has no fragment shader interlock")?;
        let pixels = settings.width * settings.height;
        let state_bytes = u64::from(pixels) * STATE_WORDS * 4;
        gpu.check_storage("the per-pixel resolve state", state_bytes)?;
        // the whole frame's storage against the device's budget, before anything is allocated
        // (sizes from a counting pass are checked again in `buffer`)
        let budget = settings.memory_budget(gpu.memory_budget());
        plan.check_budget(u64::from(pixels), oit_core::plan::Counted::default(), (&budget.0, budget.1))?;
        let uniform = FrameUniform::new(scene, camera, settings, &plan);
        let mut lent = Lent { pool, buffers: Vec::new() };
        let mut make = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            let buffer = match pool {
                Some(pool) => pool.take(&gpu.device, label, size, usage),
                None => gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                }),
            };
            lent.buffers.push(buffer.clone());
            buffer
        };
        let uniform_buffer = make(
            "frame uniform",
            UNIFORM_SLOTS * UNIFORM_STRIDE,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        // the resolve state is cleared below (all zeros is a pixel's starting state), pooled or not
        let state = make(
            "resolve state",
            state_bytes.max(4),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let timestamps = (gpu.has_timestamps() && !recording).then(|| {
            let resolve = make(
                "timestamps",
                u64::from(crate::gpu::TIMESTAMP_QUERIES) * 8,
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            );
            Timestamps { gpu, set: Some(gpu.take_queries()), resolve, labels: Vec::new() }
        });
        let image = make(
            "image",
            u64::from(pixels).max(1) * 4,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let acct = make(
            "loss accounting",
            u64::from(pixels).max(1) * 12,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let totals = make(
            "totals",
            TOTALS_BYTES,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let storage =
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let opaque_bytes = plan.opaque_bytes() * u64::from(pixels);
        let has_opaque = plan.opaque;
        let opaque = if has_opaque {
            gpu.check_storage("the opaque pass's image", opaque_bytes)?;
            let (keys, rgb) = oit_gpu::opaque_words(settings.width, settings.height, settings.samples);
            (make("opaque keys", keys * 4, storage), make("opaque colours", rgb * 4, storage))
        } else {
            (make("unused binding", 16, storage), make("unused binding", 16, storage))
        };
        let mut ctx = GpuCtx {
            gpu,
            scene,
            camera,
            settings,
            plan,
            pixels,
            passes: 0,
            fragments: Fragments::Unset,
            storage_bytes: if has_opaque { opaque_bytes } else { 0 },
            uniform_buffer,
            uniform,
            state,
            timestamps,
            image,
            totals,
            acct,
            opaque,
            opaque_from: None,
            counts_losses: true,
            per_sample_blend: false,
            checks: Vec::new(),
            speculated_deepest: None,
            deepest_seen: None,
            speculated_peels: None,
            peels_seen: None,
            sizing_checks: Vec::new(),
            speculated_fragments: None,
            fragments_seen: None,
            capacity_checks: Vec::new(),
            refusals: Vec::new(),
            gpu_ms: 0.0,
            pass_ms: Vec::new(),
            lent,
            encoder: caller.map(Enc::Caller),
            recording,
            uniform_slot: 0,
            gated_passes: 0,
            gated_pass: false,
            geometry_label: "geometry",
            classify_items: false,
            count_wanted: false,
            merged_from: None,
            layers_from: None,
            supersample: None,
            ring_full: false,
            started: std::time::Instant::now(),
        };
        let totals = ctx.totals.clone();
        let acct = ctx.acct.clone();
        ctx.fill(&acct, 0)?;
        ctx.fill(&totals, 0)?;
        if ctx.plan.opaque {
            let (keys, rgb) = ctx.opaque.clone();
            ctx.fill(&keys, u32::MAX)?;
            ctx.fill(&rgb, 0)?;
        }
        // the gate's pipeline made with the frame, not at the first gated pass: a prepared scene's
        // first speculated frame (its second) then creates no pipeline (tests/tests/prepared.rs)
        let gate_layout = ctx.layout0(4);
        gpu.compute_pipeline(&format!("{TECHNIQUE_PRELUDE}{GATE_WGSL}"), "gate_main", &[&gate_layout])?;
        // all zeros is a pixel's starting resolve state (resolve.wgsl's `PixelState`)
        let state = ctx.state.clone();
        ctx.fill(&state, 0)?;
        Ok(ctx)
    }

    /// The encoder the frame records into (its own, made on first use, or the caller's).
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        let gpu = self.gpu;
        self.encoder.get_or_insert_with(|| Enc::Own(gpu.device.create_command_encoder(&Default::default())))
    }

    /// The frame's encoder, taken out to record a pass that also borrows the frame (its
    /// timestamp writes); give it back with [`GpuCtx::put_encoder`] or [`GpuCtx::finish_timed`].
    pub fn take_encoder(&mut self) -> Enc<'a> {
        match self.encoder.take() {
            Some(e) => e,
            None => Enc::Own(self.gpu.device.create_command_encoder(&Default::default())),
        }
    }

    /// Gives back what [`GpuCtx::take_encoder`] took.
    pub fn put_encoder(&mut self, encoder: Enc<'a>) {
        self.encoder = Some(encoder);
    }

    /// Submits what the frame has recorded: before a readback, and at the end. A frame recording
    /// into the caller's encoder cannot: the step that asked is refused (`OitPass::record`
    /// checks its techniques up front, so this is a guard, not a path).
    pub fn flush(&mut self) -> Result<(), OitError> {
        if self.recording {
            return Err(OitError::Unsupported {
                backend: "wgpu (recorded pass)".into(),
                what: format!(
                    "{}: this step reads a result back in mid-frame, which a frame recorded into your                      encoder cannot do; use `OitPass::frame`",
                    self.settings.technique
                ),
            });
        }
        if let Some(Enc::Own(e)) = self.encoder.take() {
            self.gpu.queue.submit([e.finish()]);
        }
        Ok(())
    }

    /// Word 0.. of `buffer`, read back after submitting what the frame recorded (a round trip).
    pub fn read_u32(&mut self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, OitError> {
        self.flush()?;
        self.gpu.read_u32(buffer)
    }

    /// A storage buffer of `words` 32-bit words for the technique, checked against the limits and
    /// counted in `storage_bytes`.
    pub fn buffer(&mut self, label: &str, words: u64, init: Init) -> Result<wgpu::Buffer, OitError> {
        self.make_buffer(label, words, init, true)
    }

    /// A storage buffer of `words` words of bookkeeping (a flag, a counter, a sizing count),
    /// checked against the device's limits but not counted in `storage_bytes` (oit-cpu counts
    /// none).
    pub fn scratch(&mut self, label: &str, words: u64, init: Init) -> Result<wgpu::Buffer, OitError> {
        self.make_buffer(label, words, init, false)
    }

    /// A render target of the frame's size and `samples`, kept by `stage` for the next frame of
    /// that size ([`SceneStage::target_sampled`](crate::stage::SceneStage::target_sampled)), its
    /// bytes counted in `storage_bytes` as a buffer's are (the blend captures' targets: what
    /// oit-vulkan's `VkCtx::target` counts for its own).
    pub(crate) fn target(
        &mut self,
        stage: &crate::stage::SceneStage,
        label: &'static str,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> Result<wgpu::TextureView, OitError> {
        let texel = format
            .block_copy_size(None)
            .or_else(|| format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)))
            .ok_or_else(|| {
                OitError::Device(format!("internal: no texel size for the target '{label}' ({format:?})"))
            })?;
        self.storage_bytes += u64::from(self.pixels) * u64::from(texel) * u64::from(samples);
        Ok(stage.target_sampled(&self.gpu.device, label, format, samples))
    }

    /// [`GpuCtx::buffer`] (`counted`) or [`GpuCtx::scratch`].
    fn make_buffer(
        &mut self,
        label: &str,
        words: u64,
        init: Init,
        counted: bool,
    ) -> Result<wgpu::Buffer, OitError> {
        // never smaller than the widest element a shader binds (u64 keys, vec4s, fabs' slots):
        // a frame with no fragments sizes its arrays to zero, and wgpu refuses a binding smaller
        // than one element ("bound with size 4 where the shader expects 8", issue 13.8)
        let bytes = words.max(MIN_BUFFER_WORDS) * 4;
        self.gpu.check_storage(label, bytes)?;
        if counted {
            let budget = self.settings.memory_budget(self.gpu.memory_budget());
            oit_core::plan::check_total(
                &format!("{} storage of a frame of {} pixels", self.settings.technique, self.pixels),
                self.storage_bytes
                    .saturating_add(u64::from(self.pixels) * STATE_WORDS * 4)
                    .saturating_add(bytes)
                    .saturating_add(self.plan.output_bytes(u64::from(self.pixels))),
                (&budget.0, budget.1),
            )?;
            self.storage_bytes += words * 4;
        }
        let (buffer, fresh) = self.make_marked(
            label,
            bytes,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        match init.fill(fresh) {
            // a new buffer is zeroed already; one from the pool holds the last frame's words
            Some(0) if fresh => {}
            Some(v) => self.fill(&buffer, v)?,
            None => {}
        }
        Ok(buffer)
    }

    /// Sets every word of `buffer` to `value` (a kernel; zero is a plain clear).
    pub fn fill(&mut self, buffer: &wgpu::Buffer, value: u32) -> Result<(), OitError> {
        if value == 0 {
            self.encoder().clear_buffer(buffer, 0, None);
            return Ok(());
        }
        self.kernel_over(FILL_WGSL, "fill_main", &[buffer], buffer.size() / 4, 0, value, "fill")
    }

    /// The layout of group 0 with `n` technique buffers after the uniform and the state.
    pub fn layout0(&self, n: usize) -> wgpu::BindGroupLayout {
        let visibility = wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT;
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }];
        let storage = |binding: u32| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        // the state and the technique's buffers, then the per-pixel loss counts and the opaque
        // pass's image
        entries.extend(
            (1..=(n as u32 + 1)).chain([ACCT_BINDING, OPAQUE_KEYS_BINDING, OPAQUE_RGB_BINDING]).map(storage),
        );
        self.gpu.layout(n, || {
            self.gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("group 0"),
                entries: &entries,
            })
        })
    }

    /// Marks the passes that follow as the last capture pass the plan allows (or not): the
    /// shaders count what such a pass leaves behind as lost.
    pub fn last_pass(&mut self, last: bool) {
        self.uniform.last_pass = u32::from(last);
    }

    /// Whether the geometry passes that follow cut their fragments at the opaque pass's depth
    /// (only where the frame has an opaque part).
    pub fn cut(&mut self, on: bool) {
        self.uniform.opaque[0] = u32::from(on && self.plan.opaque);
    }

    /// Whether the geometry pass recorded next cuts its fragments at the opaque pass's depth.
    pub(crate) fn cuts_at_opaque(&self) -> bool {
        self.uniform.opaque[0] != 0
    }

    /// Where the hardware path's count-only draw counts a first scene pass's fragments (in place
    /// of its count target): the opaque colours' buffer and the counter's byte offset in it
    /// ([`oit_gpu::opaque_drawn_offset`]).
    pub(crate) fn drawn_counter(&self) -> (wgpu::Buffer, u64) {
        (self.opaque.1.clone(), oit_gpu::opaque_drawn_offset(u64::from(self.pixels), self.settings.samples))
    }

    /// The frame's opaque image (keys, colours and counters), for the embedded pass to load the
    /// caller's depth and colour into ([`crate::OitPass::with_opaque`]): placeholders where the
    /// plan has no opaque part.
    pub(crate) fn opaque_image(&self) -> (wgpu::Buffer, wgpu::Buffer) {
        self.opaque.clone()
    }

    /// Where the opaque pass counted its fragments: copied into the totals at the frame's end.
    pub fn note_opaque(&mut self, count: &wgpu::Buffer) {
        self.opaque_from = Some(count.clone());
    }

    /// Group 0 for `buffers` (bound from binding 2), after writing the uniform with this pass's
    /// index and parameter.
    pub fn group0(
        &mut self,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
    ) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
        self.uniform.pass_index = pass_index;
        self.uniform.param = param;
        if self.uniform_slot == UNIFORM_SLOTS {
            // every slot is bound by a recorded pass: submit those, then write over them (a
            // queue write lands before the next submission, after the last). A recorded frame of
            // this many passes cannot: `OitPass::record` takes only short schedules.
            if self.recording {
                self.uniform_slot = 0;
                self.ring_full = true;
            } else {
                let _ = self.flush();
                self.uniform_slot = 0;
            }
        }
        let offset = self.uniform_slot * UNIFORM_STRIDE;
        self.uniform_slot += 1;
        self.gpu.queue.write_buffer(&self.uniform_buffer, offset, bytemuck::bytes_of(&self.uniform));
        let layout = self.layout0(buffers.len());
        let uniform = wgpu::BufferBinding {
            buffer: &self.uniform_buffer,
            offset,
            size: std::num::NonZeroU64::new(std::mem::size_of::<FrameUniform>() as u64),
        };
        let mut entries = vec![
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::Buffer(uniform) },
            wgpu::BindGroupEntry { binding: 1, resource: self.state.as_entire_binding() },
            wgpu::BindGroupEntry { binding: ACCT_BINDING, resource: self.acct.as_entire_binding() },
            wgpu::BindGroupEntry {
                binding: OPAQUE_KEYS_BINDING,
                resource: self.opaque.0.as_entire_binding(),
            },
            wgpu::BindGroupEntry { binding: OPAQUE_RGB_BINDING, resource: self.opaque.1.as_entire_binding() },
        ];
        for (i, b) in buffers.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry { binding: i as u32 + 2, resource: b.as_entire_binding() });
        }
        let group = self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &entries,
        });
        (layout, group)
    }

    /// One geometry pass of `source` (the technique's capture, after [`TECHNIQUE_PRELUDE`]),
    /// submitted, not waited for.
    pub fn geometry_pass(
        &mut self,
        driver: &dyn Driver,
        source: &str,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<(), OitError> {
        let generated = self.run_geometry_pass(driver, source, buffers, pass_index, param)?;
        self.note_generated(&generated);
        Ok(())
    }

    /// [`GpuCtx::geometry_pass`], its count of generated fragments left on the device, in word 0
    /// of the buffer returned (a copy the frame's later passes do not touch).
    pub fn geometry_pass_with_count(
        &mut self,
        driver: &dyn Driver,
        source: &str,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<wgpu::Buffer, OitError> {
        self.count_wanted = true;
        let generated = self.run_geometry_pass(driver, source, buffers, pass_index, param);
        self.count_wanted = false;
        let generated = generated?;
        self.note_generated(&generated);
        let count = self.scratch("fragment count", 1, Init::Zero)?;
        self.encoder().copy_buffer_to_buffer(&generated.0, 0, &count, 0, 4);
        Ok(count)
    }

    /// A geometry pass that has work only where word 0 of `flag` (written by the frame's earlier
    /// passes) is not zero, as fabs's overflow passes and the tails' pass: no round trip. Where
    /// the driver can gate its own draws or dispatches ([`Driver::gate`]), a kernel writes its
    /// arguments from the flag (zero work when it is clear) and counts the pass on the device;
    /// where it cannot (the user's draws in the embedded pass) the flag is read back, or, in a
    /// recorded frame, the pass is drawn whatever the flag (such passes leave the pixels without
    /// work untouched) and counted on the device only where the flag is set, as oit-cpu counts.
    pub fn geometry_pass_if(
        &mut self,
        driver: &dyn Driver,
        source: &str,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
        flag: &wgpu::Buffer,
    ) -> Result<(), OitError> {
        let gate = driver.gate();
        if gate.is_none() && !self.recording {
            if self.read_u32(flag)?[0] != 0 {
                self.geometry_pass(driver, source, buffers, pass_index, param)?;
            }
            return Ok(());
        }
        let totals = self.totals.clone();
        let (from, to, words) = match gate {
            Some(g) => (g.from, g.to, g.words),
            None => (self.placeholder(), self.placeholder(), 0),
        };
        self.kernel_over(GATE_WGSL, "gate_main", &[flag, &totals, &from, &to], 64, 0, words, "gate")?;
        let gate = words > 0;
        self.gated_pass = gate;
        let run = self.run_geometry_pass(driver, source, buffers, pass_index, param);
        self.gated_pass = false;
        let generated = run?;
        self.note_generated(&generated);
        self.gated_passes += 1;
        Ok(())
    }

    /// The blend captures' peel loops: folds `occlusion` (a query's 64-bit result, resolved on the
    /// device) into word 0 of `flag`, 1 where any sample passed, else 0. No readback.
    pub(crate) fn fold_occlusion(
        &mut self,
        occlusion: &wgpu::Buffer,
        flag: &wgpu::Buffer,
    ) -> Result<(), OitError> {
        let totals = self.totals.clone();
        self.kernel_over(GATE_WGSL, "occlusion_main", &[flag, &totals, occlusion], 1, 0, 0, "gate")
    }

    /// Opens `gate` for the pass recorded next where word 0 of `flag` is set (the arguments
    /// copied, else zeros: the pass does nothing) and counts that pass on the device where it
    /// runs, as [`GpuCtx::geometry_pass_if`] does; the pass counts itself in `passes` as usual.
    pub(crate) fn open_gate(&mut self, flag: &wgpu::Buffer, gate: &Gate) -> Result<(), OitError> {
        let totals = self.totals.clone();
        let buffers = [flag, &totals, &gate.from, &gate.to];
        self.kernel_over(GATE_WGSL, "gate_main", &buffers, 64, 0, gate.words, "gate")?;
        self.gated_passes += 1;
        Ok(())
    }

    /// Where a tail pass counted the fragments it merged (word 1 of `words`): copied into the
    /// totals at the end of the frame and read back with them.
    pub fn note_merged(&mut self, words: &wgpu::Buffer) {
        self.merged_from = Some(words.clone());
    }

    /// [`GpuCtx::group0`] for a draw of the scene: the frame's first (a geometry pass, or a blend
    /// capture's count-only draw) counts the fragments the opaque cut holds back (`occluded`).
    pub(crate) fn scene_group0(
        &mut self,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
    ) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
        let first = self.fragments == Fragments::Unset;
        self.uniform.opaque[1] = u32::from(self.uniform.opaque[0] != 0 && first);
        self.uniform.opaque[3] = oit_gpu::item_marks(first);
        self.classify_items = oit_gpu::classifies_items(&self.uniform);
        let group = self.group0(buffers, pass_index, param);
        self.uniform.opaque[1] = 0;
        self.uniform.opaque[3] = 0;
        group
    }

    /// The pass both of the above run: group 0 bound, the driver's setup time and check taken,
    /// the pass recorded and counted.
    fn run_geometry_pass(
        &mut self,
        driver: &dyn Driver,
        source: &str,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<Generated, OitError> {
        let (layout, group) = self.scene_group0(buffers, pass_index, param);
        let full = format!("{TECHNIQUE_PRELUDE}{source}");
        self.add_setup_ms(driver);
        let generated = driver.geometry_pass(self, &full, &layout, &group)?;
        self.passes += 1;
        if !self.recording {
            // submitted (not waited for) at each geometry pass, so the GPU works on this pass
            // while the host records the next: one submission for the whole frame left the GPU
            // idle until the frame's end (on the H200, bunny at 1024², hardware bdp's steady wall
            // went from 2.78 to 3.14 ms), a submission per kernel and clear cost one each
            self.flush()?;
        }
        Ok(generated)
    }

    /// Adds the driver's setup time (once per driver and frame) to the frame's GPU time.
    pub fn add_setup_ms(&mut self, driver: &dyn Driver) {
        if let Some(ms) = driver.take_setup_ms() {
            self.add_pass_ms("setup", ms);
        }
        self.checks.extend(driver.take_setup_check());
    }

    /// Adds `ms` of device time under `label`, where the frame measures device time.
    fn add_pass_ms(&mut self, label: &str, ms: f64) {
        if self.timestamps.is_none() {
            return;
        }
        self.gpu_ms += ms;
        match self.pass_ms.iter_mut().find(|(l, _)| l == label) {
            Some((_, total)) => *total += ms,
            None => self.pass_ms.push((label.to_string(), ms)),
        }
    }

    /// The deepest pixel of a counting pass whose count lies in word 0 of `max`: the speculated
    /// value where the frame has one (checked at its end), else read back now.
    pub fn deepest(&mut self, max: &wgpu::Buffer) -> Result<u32, OitError> {
        self.deepest_alike(max, |speculated, counted| speculated == counted)
    }

    /// [`GpuCtx::deepest`] for a count the frame uses only through a coarser figure: a speculated
    /// value passes the end's check where `alike(speculated, counted)` (adp's batch count, the
    /// same for every set-bin count of a batch of 32), not only where the two are equal.
    pub fn deepest_alike(
        &mut self,
        max: &wgpu::Buffer,
        alike: impl Fn(u32, u32) -> bool + 'static,
    ) -> Result<u32, OitError> {
        if let Some(d) = self.speculated_deepest.take() {
            self.sizing_checks.push((max.clone(), Box::new(move |counted| alike(d, counted))));
            return Ok(d);
        }
        let m = self.read_u32(max)?[0];
        self.deepest_seen = Some(m);
        Ok(m)
    }

    /// The capacity, in elements of `bytes` bytes, of arrays sized by a count that lies in word 0
    /// of `count` on the device (`dfb`'s and `ll`'s fragment total): the plan's
    /// ([`Plan::fragment_capacity`]: the count rounded up to its size class, at most 1/8 more, so
    /// the frames of one view, and the nearby views of a moving camera, take the same buffers
    /// from the pool). Where the frame speculates ([`GpuCtx::speculated_fragments`]) the count is
    /// the earlier frame's, not waited for, and checked at the end: a frame whose count exceeds
    /// the capacity runs again. Else it is read back now (a round trip). The frame's
    /// `storage_bytes` are what it allocated: the capacity, not the count.
    ///
    /// Under the test hook `OIT_MUTATION=wgpu-capacity-doubled` ([`oit_core::mutation`]) the
    /// capacity is twice the plan's: `tests/tests/plan.rs` must see the frame allocate past its
    /// plan.
    pub fn fragment_capacity(&mut self, count: &wgpu::Buffer, bytes: u64) -> Result<u32, OitError> {
        let counted = match self.speculated_fragments.take() {
            Some(earlier) => earlier,
            None => {
                let n = self.read_u32(count)?[0];
                self.fragments_seen = Some(n);
                n
            }
        };
        let mut capacity = u32::try_from(self.plan.fragment_capacity(u64::from(counted))).unwrap_or(u32::MAX);
        if oit_core::mutation::active("wgpu-capacity-doubled") {
            capacity = capacity.saturating_mul(2);
        }
        self.capacity_checks.push((count.clone(), capacity, bytes));
        Ok(capacity)
    }

    /// Word 0 of `buffer` must equal `expected` at the frame's end (read back with the totals);
    /// where it does not, the frame is incomplete and runs again without speculating.
    pub fn check_at_end(&mut self, buffer: &wgpu::Buffer, expected: u32) {
        self.sizing_checks.push((buffer.clone(), Box::new(move |counted| counted == expected)));
    }

    /// Word 0 of `flag` must be 0 at the frame's end (read back with the totals); where it is
    /// not, the frame met what its capture cannot render honestly, and it fails with
    /// [`OitError::Unsupported`] saying `what` (`oit_gpu::Frame::refuse_at_end`).
    pub fn refuse_at_end(&mut self, flag: &wgpu::Buffer, what: String) {
        self.refusals.push((flag.clone(), what));
    }

    /// Keeps the first scene pass's count of generated fragments: copied on the device into the
    /// frame's totals, read back with them when the frame ends.
    pub fn note_generated(&mut self, generated: &Generated) {
        if self.fragments != Fragments::Unset {
            return;
        }
        let totals = self.totals.clone();
        self.encoder().copy_buffer_to_buffer(&generated.0, 0, &totals, FRAGMENTS_WORD * 4, 4);
        self.fragments = Fragments::OnDevice;
    }

    /// Runs compute `entry` of `source` (after [`TECHNIQUE_PRELUDE`]) once per pixel.
    pub fn pixel_kernel(
        &mut self,
        source: &str,
        entry: &str,
        buffers: &[&wgpu::Buffer],
        pass_index: u32,
        param: u32,
    ) -> Result<(), OitError> {
        self.kernel_over(source, entry, buffers, u64::from(self.pixels), pass_index, param, entry)
    }

    /// Runs compute `entry` over `invocations` (in 2D rows of 64 × 65535 when needed).
    #[expect(clippy::too_many_arguments, reason = "a dispatch is that many things")]
    pub fn kernel_over(
        &mut self,
        source: &str,
        entry: &str,
        buffers: &[&wgpu::Buffer],
        invocations: u64,
        pass_index: u32,
        param: u32,
        label: &str,
    ) -> Result<(), OitError> {
        let (layout, group) = self.group0(buffers, pass_index, param);
        let full = format!("{TECHNIQUE_PRELUDE}{source}");
        let pipeline = self.gpu.compute_pipeline(&full, entry, &[&layout])?;
        let (x, y) = dispatch_size(invocations);
        self.timed(label, |encoder, timestamps| {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: timestamps,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            if x > 0 {
                pass.dispatch_workgroups(x, y, 1);
            }
        })
    }

    /// Device milliseconds so far under `label` (0 where none, or without timestamps).
    pub fn pass_ms(&self, label: &str) -> f64 {
        self.pass_ms.iter().find(|(l, _)| l == label).map_or(0.0, |(_, ms)| *ms)
    }

    /// Records one compute pass with `record`, submits it, and adds its GPU time.
    pub fn timed(
        &mut self,
        label: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder, Option<wgpu::ComputePassTimestampWrites<'_>>),
    ) -> Result<(), OitError> {
        let mut encoder = self.take_encoder();
        let writes = self.render_timestamps().map(|w| wgpu::ComputePassTimestampWrites {
            query_set: w.query_set,
            beginning_of_pass_write_index: w.beginning_of_pass_write_index,
            end_of_pass_write_index: w.end_of_pass_write_index,
        });
        record(&mut encoder, writes);
        self.finish_timed(label, encoder)
    }

    /// Gives back `encoder` (from [`GpuCtx::take_encoder`]), whose one pass wrote the timestamp
    /// pair [`GpuCtx::render_timestamps`] gave it, and labels that pair; its time is read back
    /// with the frame's others. Nothing is submitted here.
    pub fn finish_timed(&mut self, label: &str, encoder: Enc<'a>) -> Result<(), OitError> {
        self.put_encoder(encoder);
        let full = match &mut self.timestamps {
            Some(ts) => {
                ts.labels.push(label.to_string());
                ts.labels.len() as u32 * 2 >= crate::gpu::TIMESTAMP_QUERIES
            }
            None => false,
        };
        if full {
            // a frame of more than 2,048 timed passes (a deep peel): read these, go on
            let words = match self.resolve_timestamps() {
                Some(t) => Some(self.read_u32(&t)?),
                None => None,
            };
            self.add_timestamps(words.as_deref());
        }
        Ok(())
    }

    /// Records the resolve of the timestamp pairs written so far into the resolve buffer, and
    /// returns that buffer (to be read back); `None` without timestamps or with none written.
    fn resolve_timestamps(&mut self) -> Option<wgpu::Buffer> {
        let ts = self.timestamps.as_ref()?;
        if ts.labels.is_empty() {
            return None;
        }
        let (set, n, resolve) = (ts.set().clone(), ts.labels.len() as u32 * 2, ts.resolve.clone());
        self.encoder().resolve_query_set(&set, 0..n, &resolve, 0);
        Some(resolve)
    }

    /// Adds the pairs' times (the resolve buffer's words, read back) to the frame's GPU time and
    /// per-pass times, and starts the set over.
    fn add_timestamps(&mut self, words: Option<&[u32]>) {
        let (Some(ts), Some(t)) = (self.timestamps.as_mut(), words) else { return };
        for (i, label) in ts.labels.drain(..).enumerate() {
            let ms = self.gpu.pair_ms(t, i);
            self.gpu_ms += ms;
            match self.pass_ms.iter_mut().find(|(l, _)| *l == label) {
                Some((_, total)) => *total += ms,
                None => self.pass_ms.push((label, ms)),
            }
        }
    }

    /// Sets a render pass's viewport to the full frame's where this frame is a window of it
    /// ([`oit_core::Region::viewport`]): the window's fragments are then the untiled frame's.
    pub fn window_viewport(&self, rpass: &mut wgpu::RenderPass<'_>) {
        let max_side = self.gpu.limits.max_texture_dimension_2d;
        if let Some([x, y, w, h]) = self.settings.region.and_then(|r| r.viewport(max_side)) {
            rpass.set_viewport(x, y, w, h, 0.0, 1.0);
        }
    }

    /// Timestamp writes for the next timed pass (a render pass of the hardware driver, or a
    /// compute pass through [`GpuCtx::timed`]): its own pair of the frame's query set; or none.
    pub fn render_timestamps(&self) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.timestamps.as_ref().map(|ts| {
            let pair = ts.labels.len() as u32;
            wgpu::RenderPassTimestampWrites {
                query_set: ts.set(),
                beginning_of_pass_write_index: Some(2 * pair),
                end_of_pass_write_index: Some(2 * pair + 1),
            }
        })
    }

    /// Resolves the state into the frame and its stats.
    pub fn finish(self, path: oit_core::RasterPath) -> Result<Frame, OitError> {
        self.finish_with(path, true)
    }

    /// [`GpuCtx::finish`], reading back the image and per-pixel losses only when `readback`:
    /// without, the resolve still writes the image on the device and only the four totals (16
    /// bytes) come back; the frame's image is then empty (0 × 0) and `lost_pixels` `None`.
    pub fn finish_with(self, path: oit_core::RasterPath, readback: bool) -> Result<Frame, OitError> {
        self.finish_checked(path, readback)?.ok_or_else(|| {
            OitError::Device(
                "the compute path's setup needed more room than its buffers had: run the frame again".into(),
            )
        })
    }

    /// [`GpuCtx::finish_with`], or `None` where a setup check the drivers left to the end of the
    /// frame ([`SetupCheck`]) finds that the setup did not fit: the frame is incomplete and must
    /// run again, once its buffers have grown (a prepared scene does so).
    pub fn finish_checked(
        self,
        path: oit_core::RasterPath,
        readback: bool,
    ) -> Result<Option<Frame>, OitError> {
        self.finish_start(path, readback)?.wait()
    }

    /// The first half of [`GpuCtx::finish_checked`]: the frame's last kernels recorded, everything
    /// submitted and its one readback (totals, timestamps, the checks, and the image and losses
    /// when `readback`) under way, nothing waited for. [`Finishing::wait`] ends the frame; until
    /// then the frame keeps its buffers, so a frame recorded meanwhile (frames in flight) takes
    /// others from the pool.
    pub fn finish_start(
        mut self,
        path: oit_core::RasterPath,
        readback: bool,
    ) -> Result<Finishing<'a>, OitError> {
        let (image_buf, totals) = (self.image.clone(), self.totals.clone());
        self.record_finish()?;
        let _ = path;
        // one readback at the end of the frame: the totals, the timestamps, and (when asked)
        // the image and the per-pixel losses
        let stamps = self.resolve_timestamps();
        self.flush()?;
        let checks = std::mem::take(&mut self.checks);
        let sizing = std::mem::take(&mut self.sizing_checks);
        let mut read = vec![&totals];
        read.extend(stamps.as_ref());
        for c in &checks {
            read.push(&c.counters);
            read.extend(c.stamps.as_ref());
        }
        read.extend(sizing.iter().map(|(b, _)| b));
        let capacities = std::mem::take(&mut self.capacity_checks);
        read.extend(capacities.iter().map(|(b, _, _)| b));
        let refusals = std::mem::take(&mut self.refusals);
        read.extend(refusals.iter().map(|(b, _)| b));
        let layers_buf = self.layers_from.clone();
        if readback {
            read.push(&image_buf);
            if self.counts_losses {
                read.push(&self.acct);
            }
            read.extend(layers_buf.as_ref());
        }
        let recorded = self.started.elapsed();
        let reading = self.gpu.start_read(&read);
        let speculated = sizing.into_iter().map(|(_, check)| check).collect();
        Ok(Finishing {
            ctx: self,
            reading,
            stamped: stamps.is_some(),
            checks,
            speculated,
            capacities: capacities.into_iter().map(|(_, capacity, bytes)| (capacity, bytes)).collect(),
            refusals: refusals.into_iter().map(|(_, what)| what).collect(),
            readback,
            recorded,
        })
    }

    /// Records the frame's last kernels: the totals summed (into words 0–3, with the merged count
    /// copied beside them) and the image written.
    fn record_finish(&mut self) -> Result<(), OitError> {
        let (image, totals) = (self.image.clone(), self.totals.clone());
        // the four totals finish.wgsl sums (not the words after them)
        let encoder = self.encoder();
        encoder.clear_buffer(&totals, 0, Some(16));
        if let Some(words) = self.merged_from.take() {
            self.encoder().copy_buffer_to_buffer(&words, 4, &totals, MERGED_WORD * 4, 4);
        }
        if let Some(count) = self.opaque_from.take() {
            let rgb = self.opaque.1.clone();
            let counters = oit_gpu::opaque_counters_offset(u64::from(self.pixels), self.settings.samples);
            let encoder = self.encoder();
            encoder.copy_buffer_to_buffer(&count, 0, &totals, OPAQUE_WORD * 4, 4);
            encoder.copy_buffer_to_buffer(&rgb, counters, &totals, (OPAQUE_WORD + 1) * 4, 8);
        }
        let pixels = u64::from(self.pixels);
        match self.supersample.clone() {
            Some((sums, i, n)) => {
                self.kernel_over(FINISH_WGSL, "totals_main", &[&image, &totals], pixels, 0, 0, "resolve")?;
                self.kernel_over(
                    SUPERSAMPLE_WGSL,
                    "supersample_main",
                    &[&image, &totals, &sums],
                    pixels,
                    n,
                    i,
                    "resolve",
                )
            }
            None => {
                for entry in oit_gpu::finish_kernels(self.settings.effect) {
                    self.kernel_over(FINISH_WGSL, entry, &[&image, &totals], pixels, 0, 0, "resolve")?;
                }
                Ok(())
            }
        }
    }

    /// Ends a frame recorded into the caller's encoder ([`GpuCtx::recording`]): its last kernels
    /// recorded, nothing submitted. The image (one sRGB8 RGBA word a pixel) and the totals stay on
    /// the device in the returned buffers, to be drawn or copied by commands recorded after these.
    pub fn finish_recorded(mut self) -> Result<RecordedBuffers, OitError> {
        if let Some((_, what)) = self.refusals.first() {
            // a recorded frame reads nothing back, so its flag would go unseen: refused whatever
            // the scene (`OitPass::record` takes no technique that leaves one)
            return Err(OitError::Unsupported { backend: "wgpu".into(), what: what.clone() });
        }
        self.record_finish()?;
        if self.ring_full {
            return Err(OitError::Device(format!(
                "the recorded frame bound more than {UNIFORM_SLOTS} pass uniforms: its commands are wrong, do not submit them"
            )));
        }
        let uniform = self.uniform_buffer.clone();
        Ok(RecordedBuffers {
            image: self.image.clone(),
            totals: self.totals.clone(),
            uniform,
            passes: self.passes - self.gated_passes,
            gated_passes: self.gated_passes,
            storage_bytes: reported_storage(self.storage_bytes),
        })
    }

    /// The frame of `image`, the totals `t` and the per-pixel loss accounting (read back where
    /// the technique counts its losses and the caller wants them).
    fn frame_of(self, image: Image, t: &[u32], acct: Option<Vec<u32>>) -> Result<Frame, OitError> {
        // derived where `counts_losses` is off (the blend captures): `oit_core::GpuTotals`
        let (fragments, lost, lost_pixels) = oit_core::GpuTotals {
            fragments: self.fragments,
            on_device: u64::from(t[FRAGMENTS_WORD as usize]),
            captured: u64::from(t[0]),
            counted_lost: self.counts_losses.then(|| u64::from(t[3])),
            occluded: t.get(OPAQUE_WORD as usize + 2).copied().map_or(0, u64::from),
            acct: acct.as_deref(),
            pixels: self.pixels as usize,
        }
        .counts();
        let stats = Stats {
            fragments,
            lost,
            gpu_ms: self.timestamps.is_some().then_some(self.gpu_ms),
            gpu_pass_ms: self.pass_ms,
            // kept where the frame ends (`Stats::count_packing`)
            coverage: self.per_sample_blend.then_some(oit_core::msaa::Coverage::Sample),
            ..totals_stats(t, self.passes - self.gated_passes, reported_storage(self.storage_bytes))
        };
        let frame = Frame { image, layers: None, lost_pixels, stats };
        if self.counts_losses {
            frame.stats.check_accounting("wgpu")?;
        }
        Ok(frame)
    }
}

/// A frame submitted with its readback under way ([`GpuCtx::finish_start`]).
pub struct Finishing<'a> {
    ctx: GpuCtx<'a>,
    reading: crate::gpu::Reading,
    /// Whether the readback holds the frame's timestamps (after the totals).
    stamped: bool,
    checks: Vec<SetupCheck>,
    /// The checks of the frame's speculated sizes, in the order of their counts in the readback.
    speculated: Vec<SizeCheck>,
    /// The capacities the frame's counted totals took and the bytes an element takes, in the
    /// order of their counts in the readback, after the sizes'.
    capacities: Vec<(u32, u64)>,
    /// What the frame refuses where a flag [`GpuCtx::refuse_at_end`] left is set, in the order of
    /// the flags in the readback, after the capacities'.
    refusals: Vec<String>,
    readback: bool,
    /// Host time from the frame's start to its last submission.
    recorded: std::time::Duration,
}

impl Finishing<'_> {
    /// Waits for the frame's readback and makes the frame, or `None` where a check left to the
    /// end failed ([`GpuCtx::finish_checked`]).
    pub fn wait(self) -> Result<Option<Frame>, OitError> {
        let Finishing {
            mut ctx,
            reading,
            stamped,
            checks,
            speculated,
            capacities,
            refusals,
            readback,
            recorded,
        } = self;
        let waiting = std::time::Instant::now();
        let mut words = reading.wait(ctx.gpu)?.into_iter();
        if oit_gpu::host_times() {
            // where a frame's host time goes (issue 10's steady/GPU ratio): recording and
            // submitting, then waiting for the end-of-frame readback
            eprintln!(
                "oit host times: {} record+submit {:.3} ms, end readback {:.3} ms, {} passes",
                ctx.settings.technique,
                recorded.as_secs_f64() * 1e3,
                waiting.elapsed().as_secs_f64() * 1e3,
                ctx.passes
            );
        }
        let t = words.next().unwrap_or_default();
        let stamp_words = if stamped { words.next() } else { None };
        let mut fits = true;
        for c in &checks {
            let counts = words.next().unwrap_or_default();
            fits &= u64::from(counts[0]) <= c.tri_capacity && u64::from(counts[1]) <= c.item_capacity;
            if let Some(t) = c.stamps.as_ref().and_then(|_| words.next()) {
                ctx.add_pass_ms("setup", ctx.gpu.pair_ms(&t, 0));
            }
        }
        for check in &speculated {
            let counted = words.next().unwrap_or_default();
            fits &= counted.first().is_some_and(|&c| check(c));
        }
        for &(capacity, _) in &capacities {
            let counted = words.next().unwrap_or_default().first().copied().unwrap_or(u32::MAX);
            fits &= counted <= capacity;
        }
        // a frame its capture cannot render honestly fails, whether or not it fitted (what it met
        // lies in the scene, and a rerun meets it again)
        for what in refusals {
            if words.next().unwrap_or_default().first().is_none_or(|&w| w != 0) {
                return Err(OitError::Unsupported { backend: "wgpu".into(), what });
            }
        }
        if !fits {
            return Ok(None);
        }
        ctx.add_timestamps(stamp_words.as_deref());
        if !readback {
            return ctx.frame_of(Image { width: 0, height: 0, pixels: Vec::new() }, &t, None).map(Some);
        }
        let pixels = words.next().unwrap_or_default();
        let image = Image {
            width: ctx.settings.width,
            height: ctx.settings.height,
            pixels: pixels[..ctx.pixels as usize].iter().map(|w| w.to_le_bytes()).collect(),
        };
        let acct = if ctx.counts_losses { words.next() } else { None };
        let layers = ctx.layers_from.is_some().then(|| words.next()).flatten();
        let pixels = ctx.pixels as usize;
        let mut frame = ctx.frame_of(image, &t, acct)?;
        frame.layers = layers.map(|mut l| {
            l.truncate(pixels);
            l
        });
        Ok(Some(frame))
    }
}

/// A frame recorded into the caller's encoder ([`GpuCtx::finish_recorded`]): where its results
/// lie on the device once the caller has submitted it.
pub struct RecordedBuffers {
    /// The image: one RGBA8 word a pixel (sRGB-encoded, red in the low byte), row-major.
    pub image: wgpu::Buffer,
    /// The totals (words: captured, deepest captured, tied, lost, fragments, gated passes that
    /// ran, merged).
    pub totals: wgpu::Buffer,
    /// The frame uniform ring: slot 0 starts with the image's width and height.
    pub uniform: wgpu::Buffer,
    /// Geometry passes recorded that run whatever the frame finds.
    pub passes: u32,
    /// Geometry passes recorded behind a gate (whether each ran is counted in the totals).
    pub gated_passes: u32,
    /// Bytes of per-pixel storage the frame uses.
    pub storage_bytes: u64,
}

/// The stats the frame's totals words give (finish.wgsl's four, the first scene pass's fragments,
/// the gated passes that ran, the fragments merged), with `passes` geometry passes recorded
/// ungated and `storage_bytes` of per-pixel storage: what [`GpuCtx::finish_checked`] and a
/// recorded frame's `OitPass::read_stats` both read.
pub(crate) fn totals_stats(t: &[u32], passes: u32, storage_bytes: u64) -> Stats {
    let word = |w: u64| t.get(w as usize).copied().map_or(0, u64::from);
    Stats {
        geometry_passes: passes + t[GATED_WORD as usize],
        fragments: u64::from(t[FRAGMENTS_WORD as usize]),
        captured: u64::from(t[0]),
        lost: u64::from(t[3]),
        merged: u64::from(t[MERGED_WORD as usize]),
        tied: u64::from(t[2]),
        // set where the frame ends (`Stats::count_packing`)
        quantized: 0,
        storage_bytes,
        wall_ms: 0.0,
        gpu_ms: None,
        max_layers: t[1],
        gpu_pass_ms: Vec::new(),
        tiles: 1,
        opaque_fragments: word(OPAQUE_WORD),
        masked: word(OPAQUE_WORD + 1),
        occluded: word(OPAQUE_WORD + 2),
        // set where the frame ends (`Stats::count_packing`)
        coverage: None,
    }
}

/// The gate kernel of [`GpuCtx::geometry_pass_if`].
const GATE_WGSL: &str = oit_shaders::text("core/gate.wgsl");

pub use oit_gpu::dispatch_size;

/// A speculated size's check at the end of its frame: true where the count the frame made
/// sizes it as the speculated value did.
type SizeCheck = Box<dyn Fn(u32) -> bool>;

pub use oit_core::plan::size_class;
/// The storage a frame reports of `allocated` bytes: all of them, or, under the test hook
/// `OIT_MUTATION=wgpu-storage-short` ([`oit_core::mutation`]), a word less (a frame that misreports
/// what it holds: `checks::one_shot_storage` must refuse it, `tests/tests/mutations.rs`).
fn reported_storage(allocated: u64) -> u64 {
    if oit_core::mutation::active("wgpu-storage-short") { allocated.saturating_sub(4) } else { allocated }
}
