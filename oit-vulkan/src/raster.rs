//! The compute-raster path: oit-wgpu's compute rasterizer (`raster_compute.wgsl`, compiled into
//! every technique's SPIR-V module by `build.rs`) on Vulkan. Setup (transform, clipping, snapping,
//! triangle setup, binning into 8×8 tiles) follows oit-core's `setup` rule for rule, so the
//! triangles are the same bits and the fragments equal oit-cpu's.
//!
//! Where setup runs ([`setup_site`], `oit_gpu::SetupSite`), as on oit-wgpu:
//! - **on the GPU** (the default on a GPU, save parts of at most `oit_gpu::HOST_SETUP_TRIANGLES`
//!   triangles, such as a wall's quad, whose setup the host does in microseconds): oit-wgpu's `setup.wgsl` over its integer f32
//!   (`softfloat.wgsl`), compiled to SPIR-V in `build.rs`. A prepared scene uploads its
//!   world-space geometry once (oit-core's [`SetupGeometry`]: the layout shared with oit-wgpu);
//!   a frame uploads the instance table and records `vertex_main`, `setup_main` and
//!   `setup_finish_main`, which writes the raster kernel's indirect arguments; the item count is
//!   copied into the raster uniform on the device, and every geometry pass dispatches indirectly.
//!   The frame does no per-triangle work on the host. The setup's counters (pieces, work items)
//!   are read back before the frame's passes only while the kept buffers have not yet been seen
//!   to fit (a scene's first frame, or after a miss); a later frame reads them with the frame's
//!   end and runs again with grown buffers the rare time they did not fit ([`SetupCheck`]);
//! - **on the host** for those small parts, for textured parts, and on a CPU device (lavapipe), where the integer f32 costs many times the host's
//!   float unit: oit-core's `TriangleSetup`, its words uploaded through a staging buffer by the
//!   frame's first geometry pass, behind a barrier. `OIT_HOST_SETUP=1` forces the host's setup,
//!   `OIT_HOST_SETUP=0` the GPU's, on any device; `VulkanBackend::gpu_setup` says it per backend.
//!
//! A prepared scene keeps the buffers ([`ComputeBuffers`]), grown only when a frame needs more.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use ash::vk;
use oit_core::gpu_setup::{ARGS_ITEMS, ARGS_PER_ITEM, ARGS_WORDS, COUNTER_WORDS, SetupGeometry, VERT_WORDS};
use oit_core::setup::TRIANGLE_WORDS;
use oit_core::{Camera, OitError, Scene, Settings};

use crate::device::{Buffer, Gpu, SetKind, storage_usage};
use crate::record::{Recorder, SetData};
use oit_gpu::dispatch_size;

/// Bytes of the smallest triangle and work-list buffers (a binding may not be empty).
const MIN_BYTES: u64 = 256;

/// Where the compute path sets triangles up ([`oit_gpu::SetupSite`]): `choice` where the backend
/// says (`true`: on the GPU, whatever the part), else as `OIT_HOST_SETUP` and the device say
/// (module docs).
pub(crate) fn setup_site(gpu: &Gpu, choice: Option<bool>) -> oit_gpu::SetupSite {
    match choice {
        Some(true) => oit_gpu::SetupSite::Device,
        Some(false) => oit_gpu::SetupSite::Host,
        None => oit_gpu::setup_site(gpu.is_cpu()),
    }
}

/// A frame's rasterizer of the scene (or of its instances' bounding boxes), on either path.
pub(crate) enum Raster {
    /// The compute rasterizer (this module).
    Compute(ComputeRaster),
    /// The GPU's own (`crate::hardware`).
    Hardware(crate::hardware::HardwareRaster),
}

impl Raster {
    /// Where this frame's gated geometry passes take their arguments: (the ungated pass's
    /// arguments, their gated copy, words), copied by `gate.wgsl` (zeros where the gate is
    /// closed). A compute raster set up on the host (a textured frame) uploads its arguments
    /// (`oit_gpu::raster_args`), so its passes gate on the device too, as oit-wgpu's do (they
    /// read each peel back before, about a millisecond a frame of dp on an H200).
    pub(crate) fn gate(&self) -> (&Buffer, &Buffer, u32) {
        match self {
            Raster::Compute(r) => (&*r.args, &*r.gated, ARGS_WORDS as u32),
            Raster::Hardware(r) => r.gate(),
        }
    }
}

/// The setup's capacity check left to the end of a frame: the counters, the capacities they were
/// set up against, and the flag to clear (so the next frame sizes first) when they did not fit.
pub(crate) struct SetupCheck {
    pub(crate) counters: Rc<Buffer>,
    tri_capacity: u64,
    item_capacity: u64,
    trusted: Rc<Cell<bool>>,
}

impl SetupCheck {
    /// Whether the counters read back (`words`) fit; where not, the buffers are no longer trusted.
    pub(crate) fn fits(&self, words: &[u32]) -> bool {
        let pieces = u64::from(words.first().copied().unwrap_or(u32::MAX));
        let items = u64::from(words.get(1).copied().unwrap_or(u32::MAX));
        let fits = pieces <= self.tri_capacity && items <= self.item_capacity;
        if !fits {
            self.trusted.set(false);
        }
        fits
    }
}

/// What the first geometry pass of a frame records before its dispatch.
enum Pending {
    /// The host's triangle words, work items, raster uniform and indirect arguments
    /// (`oit_gpu::raster_args`), to upload.
    Host([Vec<u8>; 4]),
    /// The GPU's setup: the instance table and the raster uniform to upload, the setup's uniform.
    Gpu {
        instances: Vec<u8>,
        raster_uniform: Vec<u8>,
        setup_uniform: [u32; oit_core::gpu_setup::SETUP_UNIFORM_WORDS],
        check: Option<SetupCheck>,
    },
}

/// One frame's triangles and work list, on the GPU once the first geometry pass sets them up or
/// uploads them.
pub(crate) struct ComputeRaster {
    tris: Rc<Buffer>,
    item_list: Rc<Buffer>,
    pub(crate) uniform: Rc<Buffer>,
    pub(crate) generated: Rc<Buffer>,
    args: Rc<Buffer>,
    gated: Rc<Buffer>,
    setup: Option<Rc<SetupBuffers>>,
    pending: RefCell<Option<Pending>>,
}

impl ComputeRaster {
    /// Group 1's storage bindings (the uniform, binding 2, is bound apart).
    pub(crate) fn bindings(&self) -> Vec<(u32, &Buffer)> {
        vec![(0, &*self.tris), (1, &*self.item_list), (3, &*self.generated)]
    }

    /// Records, once, what this frame's passes need first: the upload of the host's words, or
    /// the GPU's setup. Returns the setup's end-of-frame check, where it left one.
    pub(crate) fn upload(&self, rec: &mut Recorder<'_>) -> Result<Option<SetupCheck>, OitError> {
        match self.pending.borrow_mut().take() {
            Some(Pending::Host([tris, items, uniform, args])) => {
                rec.upload(&self.tris, &tris)?;
                rec.upload(&self.item_list, &items)?;
                rec.upload(&self.uniform, &uniform)?;
                rec.upload(&self.args, &args)?;
                Ok(None)
            }
            Some(Pending::Gpu { instances, raster_uniform, setup_uniform, check }) => {
                let s = self.setup.as_ref().expect("a GPU setup has its buffers");
                rec.upload(&self.uniform, &raster_uniform)?;
                record_setup(rec, s, &self.tris, &self.item_list, &self.args, &instances, &setup_uniform)?;
                // the raster uniform's item count, from the arguments kernel
                rec.copy_at(&self.args, ARGS_ITEMS, &self.uniform, 0, 4);
                Ok(check)
            }
            None => Ok(None),
        }
    }

    /// Records the geometry pass's dispatch of `pipeline` (`raster_main`, a workgroup per item,
    /// where `per_pixel`; else `raster_loop_main`, an invocation per item) with `sets`, its GPU
    /// time under `label`.
    pub(crate) fn dispatch(
        &self,
        rec: &mut Recorder<'_>,
        label: &str,
        pipeline: &crate::device::Pipeline,
        sets: &[SetData<'_>],
        per_pixel: bool,
        gated: bool,
    ) -> Result<(), OitError> {
        rec.dispatch_indirect(
            label,
            pipeline,
            sets,
            if gated { &self.gated } else { &self.args },
            if per_pixel { 0 } else { ARGS_PER_ITEM },
        )
    }
}

/// What the GPU setup keeps besides its outputs: the geometry (uploaded once), the instance
/// table, the counters and the vertex cache.
struct SetupBuffers {
    layout: SetupGeometry,
    geometry: Buffer,
    instances: Buffer,
    counters: Rc<Buffer>,
    verts: Buffer,
    use_verts: bool,
}

/// Records the setup kernels into `rec`: the instance table's upload, the counters cleared, then
/// `vertex_main` (with the vertex cache), `setup_main`, `setup_count_main`, `setup_items_main`
/// and `setup_finish_main`, each behind the recorder's barrier. Binding order is setup.wgsl's group 0.
/// Their device time counts as one pass, `setup`; with `OIT_SETUP_PASSES=1` each kernel's counts
/// apart, as `setup <entry point>`.
fn record_setup(
    rec: &mut Recorder<'_>,
    s: &SetupBuffers,
    tris: &Buffer,
    items: &Buffer,
    args: &Buffer,
    instances: &[u8],
    uniform: &[u32; oit_core::gpu_setup::SETUP_UNIFORM_WORDS],
) -> Result<(), OitError> {
    rec.upload(&s.instances, instances)?;
    rec.fill(&s.counters, 0);
    let storage: [(u32, &Buffer); 10] = [
        (1, &s.instances),
        (2, &s.geometry),
        (3, tris),
        (4, items),
        (5, &s.counters),
        (6, args),
        (7, &s.verts),
        // group 0's layout always has the accounting binding; setup.wgsl does not use it
        (oit_gpu::ACCT_BINDING, &s.counters),
        (oit_gpu::OPAQUE_KEYS_BINDING, &s.counters),
        (oit_gpu::OPAQUE_RGB_BINDING, &s.counters),
    ];
    let gpu = rec.gpu();
    let sets = [SetData::Frame { uniform: bytemuck::cast_slice(uniform), storage: &storage, images: &[] }];
    let kinds = [SetKind::Frame(6, Vec::new())];
    let split = std::env::var("OIT_SETUP_PASSES").is_ok_and(|v| v == "1");
    let mut run = |entry: &str, groups: (u32, u32)| -> Result<(), OitError> {
        let pipeline = gpu.compute("setup", entry, &kinds)?;
        let label = if split { format!("setup {entry}") } else { "setup".to_string() };
        rec.dispatch(&label, &pipeline, &sets, groups)
    };
    if s.use_verts {
        run("vertex_main", dispatch_size(s.layout.vertex_total()))?;
    }
    run("setup_main", dispatch_size(u64::from(s.layout.tasks)))?;
    // the large pieces' work items, a workgroup a piece: counted, then written in order
    let spread = s.layout.spread_groups();
    run("setup_count_main", (spread, 1))?;
    run("setup_items_main", (spread, 1))?;
    run("setup_finish_main", (1, 1))
}

/// The compute rasterizer's buffers, kept between the frames of a prepared scene.
pub(crate) struct ComputeBuffers {
    tris: Rc<Buffer>,
    items: Rc<Buffer>,
    uniform: Rc<Buffer>,
    generated: Rc<Buffer>,
    args: Rc<Buffer>,
    /// The gated copy of `args`, for gated passes ([`Raster::gate`]).
    gated: Rc<Buffer>,
    setup: Option<Rc<SetupBuffers>>,
    site: oit_gpu::SetupSite,
    /// Whether an earlier frame's setup was seen to fit these buffers: then a frame does not read
    /// the counters before its passes but checks them at its end.
    trusted: Rc<Cell<bool>>,
    /// The host's setup, kept for the next frame set up on the host.
    host: oit_gpu::HostSetup,
}

fn geometry_usage() -> vk::BufferUsageFlags {
    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST
}

impl ComputeBuffers {
    /// Small buffers (grown by the first frame that needs more); `made` counts the buffers.
    /// Setup runs where [`setup_site`] says (`choice`: the backend's).
    pub(crate) fn new(gpu: &Gpu, choice: Option<bool>, made: &Cell<u64>) -> Result<ComputeBuffers, OitError> {
        made.set(made.get() + 6);
        let args = || {
            gpu.buffer(ARGS_WORDS as u64 * 4, storage_usage() | vk::BufferUsageFlags::INDIRECT_BUFFER, false)
        };
        Ok(ComputeBuffers {
            tris: Rc::new(gpu.buffer(MIN_BYTES, geometry_usage(), false)?),
            items: Rc::new(gpu.buffer(MIN_BYTES, geometry_usage(), false)?),
            uniform: Rc::new(gpu.buffer(
                32,
                vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                false,
            )?),
            generated: Rc::new(gpu.buffer(16, storage_usage(), false)?),
            args: Rc::new(args()?),
            gated: Rc::new(args()?),
            setup: None,
            site: setup_site(gpu, choice),
            trusted: Rc::new(Cell::new(false)),
            host: oit_gpu::HostSetup::default(),
        })
    }

    /// Grows the triangle and work-list buffers to hold `tri_bytes` and `item_bytes` (counted in
    /// `made`), after checking both against the device's limits; true when one was made.
    fn reserve(
        &mut self,
        gpu: &Gpu,
        tri_bytes: u64,
        item_bytes: u64,
        made: &Cell<u64>,
    ) -> Result<bool, OitError> {
        gpu.check_storage_hint(
            "the triangles",
            tri_bytes,
            "use fewer triangles or instances (176 bytes each on the compute rasterizer), or the cpu backend",
        )?;
        gpu.check_storage("the raster work list", item_bytes)?;
        let limit = u64::from(gpu.info.limits.max_storage_buffer_range);
        let grown = |old: u64, needed: u64| needed.max(old.saturating_mul(2).min(limit)).next_multiple_of(4);
        let mut grew = false;
        if tri_bytes > self.tris.size || item_bytes > self.items.size {
            // a frame in flight (`Prepared::frame_loop`) may still read the buffers replaced here
            gpu.queue_idle()?;
        }
        if tri_bytes > self.tris.size {
            self.tris = Rc::new(gpu.buffer(grown(self.tris.size, tri_bytes), geometry_usage(), false)?);
            made.set(made.get() + 1);
            grew = true;
        }
        if item_bytes > self.items.size {
            self.items = Rc::new(gpu.buffer(grown(self.items.size, item_bytes), geometry_usage(), false)?);
            made.set(made.get() + 1);
            grew = true;
        }
        Ok(grew)
    }

    /// This frame's triangles of the scene (or of its instances' bounding boxes): set up on the
    /// GPU or the host (module docs), growing a buffer first where they do not fit.
    pub(crate) fn frame(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<ComputeRaster, OitError> {
        let raster_uniform = raster_uniform(camera, settings);
        if self.sets_up_on_host(scene) {
            self.host.run(scene, camera, settings, boxes);
            return self.host_frame(gpu, made, raster_uniform);
        }
        if self.setup.as_ref().is_none_or(|s| s.layout.boxes != boxes) {
            self.trusted.set(false);
            self.setup = Some(Rc::new(Self::setup_buffers(gpu, scene, boxes, made)?));
            let s = self.setup.as_ref().expect("made above");
            let limit = u64::from(gpu.info.limits.max_storage_buffer_range);
            let (tris, items) = s.layout.first_guess(limit);
            let (tris, items) = (tris.max(self.tris.size), items.max(self.items.size));
            self.reserve(gpu, tris, items, made)?;
        }
        let s = self.setup.clone().expect("made above");
        let instances = bytemuck::cast_slice(&s.layout.instance_words(scene, camera, settings)).to_vec();
        let capacities = |b: &Self| (b.tris.size / (TRIANGLE_WORDS as u64 * 4), b.items.size / 8);
        // until these buffers were seen to fit, set up and read the counters before the frame:
        // one round trip, grown and set up again while short
        while !self.trusted.get() {
            let (tri_capacity, item_capacity) = capacities(self);
            let uniform = s.layout.uniform_words(settings, tri_capacity, item_capacity, s.use_verts);
            let mut rec = Recorder::new(gpu)?;
            record_setup(&mut rec, &s, &self.tris, &self.items, &self.args, &instances, &uniform)?;
            let counts = rec.read_u32(&s.counters)?;
            let (pieces, items) = (u64::from(counts[0]), u64::from(counts[1]));
            if pieces <= tri_capacity && items <= item_capacity {
                self.trusted.set(true);
            } else if !self.reserve(gpu, pieces * TRIANGLE_WORDS as u64 * 4, items * 8, made)? {
                return Err(OitError::Device(format!(
                    "the compute path's setup needs {pieces} triangles and {items} work items, more than its buffers hold"
                )));
            }
        }
        let (tri_capacity, item_capacity) = capacities(self);
        let check = SetupCheck {
            counters: s.counters.clone(),
            tri_capacity,
            item_capacity,
            trusted: self.trusted.clone(),
        };
        Ok(ComputeRaster {
            tris: self.tris.clone(),
            item_list: self.items.clone(),
            uniform: self.uniform.clone(),
            generated: self.generated.clone(),
            args: self.args.clone(),
            gated: self.gated.clone(),
            pending: RefCell::new(Some(Pending::Gpu {
                instances,
                raster_uniform: raster_uniform(0),
                setup_uniform: s.layout.uniform_words(settings, tri_capacity, item_capacity, s.use_verts),
                check: Some(check),
            })),
            setup: Some(s),
        })
    }

    /// The setup's own buffers for the scene (or its boxes), its geometry uploaded.
    fn setup_buffers(
        gpu: &Gpu,
        scene: &Scene,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<SetupBuffers, OitError> {
        let mut layout = SetupGeometry::new(scene, boxes)?;
        let words = std::mem::take(&mut layout.words);
        let bytes = (words.len() as u64 * 4).max(MIN_BYTES);
        gpu.check_storage_hint(
            "the scene's geometry for the compute path's setup",
            bytes,
            "use a smaller mesh, or the cpu backend",
        )?;
        let limit = u64::from(gpu.info.limits.max_storage_buffer_range);
        let vert_bytes = layout.vertex_total() * VERT_WORDS as u64 * 4;
        let use_verts = vert_bytes > 0 && vert_bytes <= limit;
        made.set(made.get() + 4);
        let geometry = gpu.buffer(bytes, geometry_usage(), false)?;
        {
            let mut rec = Recorder::new(gpu)?;
            rec.upload(&geometry, bytemuck::cast_slice(&words))?;
            rec.flush()?;
        }
        Ok(SetupBuffers {
            instances: gpu.buffer(layout.instance_bytes(), geometry_usage(), false)?,
            counters: Rc::new(gpu.buffer(COUNTER_WORDS as u64 * 4, storage_usage(), false)?),
            verts: gpu.buffer(
                if use_verts { vert_bytes } else { 16 },
                vk::BufferUsageFlags::STORAGE_BUFFER,
                false,
            )?,
            use_verts,
            geometry,
            layout,
        })
    }

    /// Whether a frame of `scene` is set up on the host (`oit_gpu::sets_up_on_host`).
    pub(crate) fn sets_up_on_host(&self, scene: &Scene) -> bool {
        oit_gpu::sets_up_on_host(self.site, scene)
    }

    /// The kept host setup ([`ComputeBuffers::host_frame`] uploads what it holds).
    pub(crate) fn host(&mut self) -> &mut oit_gpu::HostSetup {
        &mut self.host
    }

    /// A frame whose host setup ([`ComputeBuffers::host`]) has run: its words and work list
    /// to upload.
    pub(crate) fn host_set_up(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        settings: &Settings,
        made: &Cell<u64>,
    ) -> Result<ComputeRaster, OitError> {
        self.host_frame(gpu, made, raster_uniform(camera, settings))
    }

    /// The host's setup (oit-core's `TriangleSetup`, run into `self.host`), its words and work
    /// list to upload.
    fn host_frame(
        &mut self,
        gpu: &Gpu,
        made: &Cell<u64>,
        raster_uniform: impl Fn(u32) -> Vec<u8>,
    ) -> Result<ComputeRaster, OitError> {
        let (word_count, item_count) = (self.host.words.len(), self.host.items.len());
        self.reserve(gpu, word_count as u64 * 4, item_count as u64 * 8, made)?;
        let (words, items) = (&self.host.words, &self.host.items);
        Ok(ComputeRaster {
            tris: self.tris.clone(),
            item_list: self.items.clone(),
            uniform: self.uniform.clone(),
            generated: self.generated.clone(),
            args: self.args.clone(),
            gated: self.gated.clone(),
            setup: None,
            pending: RefCell::new(Some(Pending::Host([
                bytemuck::cast_slice(words).to_vec(),
                bytemuck::cast_slice(items).to_vec(),
                raster_uniform(items.len() as u32),
                bytemuck::cast_slice(&oit_gpu::raster_args(items.len() as u64)).to_vec(),
            ]))),
        })
    }
}

/// The raster uniform's maker for a frame of `camera` and `settings`: its bytes for a count of
/// work items.
fn raster_uniform<'a>(camera: &'a Camera, settings: &'a Settings) -> impl Fn(u32) -> Vec<u8> + 'a {
    move |items: u32| bytemuck::cast_slice(&oit_gpu::raster_uniform(camera, settings, items)).to_vec()
}

/// The rasterizers of one frame: the scene's, and (made on demand) the instances' bounding boxes'.
pub(crate) struct Drivers<'a> {
    pub(crate) scene: Raster,
    pub(crate) boxes: Box<dyn Fn() -> Result<Raster, OitError> + 'a>,
    /// Rasterizes the frame's opaque part, where it has one (oit-gpu's `technique::opaque_pass`).
    pub(crate) opaque: Option<Raster>,
}

impl oit_gpu::Rasters<Raster> for Drivers<'_> {
    fn scene(&self) -> &Raster {
        &self.scene
    }

    fn with_boxes(&self, pass: &mut dyn FnMut(&Raster) -> Result<(), OitError>) -> Result<(), OitError> {
        pass(&(self.boxes)()?)
    }

    fn opaque(&self) -> Option<&Raster> {
        self.opaque.as_ref()
    }
}
