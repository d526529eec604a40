//! oit-vulkan: oit's techniques on raw Vulkan through [ash](https://docs.rs/ash).
//!
//! **What runs today.** Every technique of the catalogue (`reference`, `plain`, `dp`, `ddp`,
//! `wavg`, `wsum`, `bdp`/`bdp:P`, `adp`, `mdts:K`, `mdts64:K`, `fabs:K`, `mlp:M`, `dfb`, `ll`) on
//! both raster paths, on oit-wgpu's WGSL compiled to SPIR-V by naga in `build.rs`:
//! - the **compute-raster path** (`RasterPath::Compute`, the default here): oit-wgpu's compute
//!   rasterizer after oit-core's setup, run on the GPU by oit-wgpu's `setup.wgsl` (bit for bit
//!   the host's; on the host on a CPU device, see `raster`'s docs and
//!   [`VulkanBackend::with_gpu_setup`]), so the fragments equal oit-cpu's and the images
//!   oit-wgpu's compute path's;
//! - the **hardware-raster path** (`RasterPath::Hardware`, where the device has a graphics queue,
//!   `fragmentStoresAndAtomics` and a blendable `R32_SFLOAT`): a graphics pipeline over the
//!   scene's vertices pulled from storage (`oit_core::pulled`), oit-wgpu's `hw_vs`/`hw_fs`, a
//!   render pass whose one attachment counts fragments by additive blending, and a negative
//!   viewport height for wgpu's conventions, so the fragments are oit-wgpu's hardware path's on
//!   the same driver (against oit-cpu, only pixels on triangle edges may differ).
//!
//! Captures use storage-buffer atomics, as on wgpu; with `--atomic-storage image`
//! ([`oit_core::AtomicStorage::Image`]) mdts, mdts64 and fabs use the papers' storage-image
//! atomics instead (see `oit_gpu::technique`'s mdts and fabs, and `frame.rs`'s `storage_image`). With `--hardware-capture blend` on the
//! hardware path, the papers' own operations (`technique::blend`): MAX blending into 8 ×
//! `R32G32B32A32_SFLOAT` for bdp, a depth test into `D32_SFLOAT` with occlusion queries for dp,
//! MAX blending of (−d, d) into `R32G32_SFLOAT` with occlusion queries for ddp, additive float
//! blending for wavg/wsum, and, beyond wgpu, adp's histogram by logic-op OR into 8 ×
//! `R32G32B32A32_UINT`. `plain` always blends on the hardware path (the over operator in one draw).
//! Beyond the papers and wgpu, `kbuf[:K]` on the hardware path (oit-gpu's kbuf frame; its interlock is `build.rs`'s rewrite): the ordered
//! k-buffer, whose fragment stage runs in `VK_EXT_fragment_shader_interlock`'s ordered per-pixel
//! critical section (WGSL cannot say it: `build.rs` adds it to the SPIR-V of `kbuf_hw`'s `hw_fs` and
//! `hw_fs_masked`, the multisampled capture).
//!
//! **GPU time.** Where the device has timestamps ([`Gpu::has_timestamps`]: not on a CPU device
//! such as lavapipe unless `OIT_GPU_TIMESTAMPS=1`, and nowhere with `OIT_GPU_TIMESTAMPS=0`, as on
//! oit-wgpu) every dispatch and draw is
//! timed by a pair of timestamp queries, and a frame's `gpu_ms` is their sum, `gpu_pass_ms` the
//! same by label (oit-wgpu's: "geometry", the kernel's entry point, "resolve"; the opaque
//! pass's two geometry passes under "opaque" and `classify_main` under "classify",
//! `oit_gpu::geometry_label`; a blend capture's draw under its fragment entry point); fills,
//! copies and uploads are not timed.
//!
//! **What is refused** (`OitError::Unsupported`, naming what is missing): the hardware path on a
//! device without what it needs; a blend capture into a format the device cannot blend into, or
//! without `logicOp` / `independentBlend` / 8 colour attachments; mdts64 on storage images
//! without `VK_EXT_shader_image_atomic_int64`'s 64-bit image atomics (lavapipe); `kbuf` on the
//! compute path (no fragment stage) and on a device without `fragmentShaderPixelInterlock`
//! (lavapipe), before anything is allocated.
//!
//! **Starting without Vulkan.** The entry is loaded at run time (`ash::Entry::load`, feature
//! `loaded`): a binary runs on a machine without `libvulkan.so.1` and [`VulkanBackend::gpu`]
//! says what to install. The device: the adapter whose name contains the filter (or
//! `OIT_ADAPTER`), else a discrete GPU, else integrated, else any (lavapipe); it needs Vulkan 1.2,
//! `shaderInt64` and `shaderBufferInt64Atomics`, and one compute queue (graphics and compute for
//! the hardware path).
//!
//! **Correctness aids.** `OIT_VULKAN_VALIDATION=1` enables `VK_LAYER_KHRONOS_validation` with
//! synchronization validation and a debug-utils messenger; any error it reports fails the frame.
//! Every `unsafe` block carries a `// SAFETY:` comment; Vulkan objects are owned by types that
//! destroy them in `Drop`, newest first (see `device`).
//!
//! A frame on the compute path, its fragments equal to oit-cpu's. Without a Vulkan device
//! [`backend_or_skip`] prints one `skipped …` line naming what to install and the example stops
//! there, so it runs everywhere (with `OIT_REQUIRE_GPU=1` a missing device is a panic instead):
//!
//! ```
//! use oit_core::{load_scene, Backend, Camera, Settings, Technique, View};
//!
//! let Some(vulkan) = oit_vulkan::backend_or_skip("oit-vulkan's crate example") else { return };
//! let scene = load_scene("planes:4").unwrap();
//! let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
//! let settings = Settings { width: 32, height: 32, technique: Technique::Dp, ..Settings::default() };
//! let frame = vulkan.render(&scene, &camera, &settings).unwrap();
//! let cpu = oit_cpu::CpuBackend::default().render(&scene, &camera, &settings).unwrap();
//! assert_eq!(frame.stats.fragments, cpu.stats.fragments);
//! assert_eq!(frame.stats.lost, 0);
//! assert_eq!(frame.stats.geometry_passes, 5); // 4 layers + the pass that finds none left
//! ```

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod ctx;
mod device;
mod frame;
mod hardware;
mod raster;
mod record;
mod technique;

use std::cell::{Cell, RefCell};
use std::sync::OnceLock;
use std::time::Instant;

use oit_core::{
    Backend, Camera, Capabilities, Frame, HardwareCapture, OitError, Prepared, RasterPath, Scene, Settings,
    Technique, TechniqueKind,
};

pub use crate::ctx::BufferPool;
pub use crate::device::{
    DeviceInfo, Gpu, PAPER_EXTENSIONS, spirv_modules, validation_errors, validation_requested,
};

use crate::ctx::{ReadBack, VkCtx};
use crate::hardware::HardwareScene;
use crate::raster::{ComputeBuffers, ComputeRaster, Drivers, Raster};

/// The Vulkan backend. The device opens on first use.
#[derive(Default)]
pub struct VulkanBackend {
    /// Adapter name filter (substring); `None` reads `OIT_ADAPTER`, else prefers a discrete GPU.
    pub adapter: Option<String>,
    /// Where the compute path sets triangles up: `Some(true)` on the GPU (whatever a part's size),
    /// `Some(false)` on the host; `None` reads `OIT_HOST_SETUP`, else the GPU unless the device is
    /// a CPU (lavapipe) or the part is small (`oit_gpu::SetupSite`).
    pub gpu_setup: Option<bool>,
    gpu: OnceLock<Result<Gpu, String>>,
}

impl VulkanBackend {
    /// A backend for the adapter whose name contains `filter`.
    pub fn new(adapter: Option<String>) -> Self {
        VulkanBackend { adapter, gpu_setup: None, gpu: OnceLock::new() }
    }

    /// This backend with the compute path's setup on the GPU (`true`) or the host (`false`),
    /// whatever the device and `OIT_HOST_SETUP` say.
    pub fn with_gpu_setup(mut self, on_gpu: bool) -> Self {
        self.gpu_setup = Some(on_gpu);
        self
    }

    /// The device, opened on first use.
    pub fn gpu(&self) -> Result<&Gpu, OitError> {
        self.gpu
            .get_or_init(|| {
                Gpu::new(self.adapter.as_deref()).map_err(|e| match e {
                    OitError::Device(message) => message,
                    other => other.to_string(),
                })
            })
            .as_ref()
            .map_err(|e| OitError::Device(e.clone()))
    }
}

impl Backend for VulkanBackend {
    fn name(&self) -> &str {
        "vulkan"
    }

    fn capabilities(&self) -> Capabilities {
        let gpu = match self.gpu() {
            Ok(gpu) => gpu,
            Err(e) => return Capabilities { device: format!("none: {e}"), ..Default::default() },
        };
        let info = &gpu.info;
        let l = &info.limits;
        let yes = |b: bool| if b { "present" } else { "absent" }.to_string();
        let mut limits = vec![
            ("api_version".into(), DeviceInfo::version(info.api_version)),
            ("driver_version".into(), format!("{:#x}", info.driver_version)),
        ];
        limits.extend(info.extensions.iter().map(|(name, present)| (name.clone(), yes(*present))));
        limits.extend([
            ("maxStorageBufferRange".into(), l.max_storage_buffer_range.to_string()),
            ("maxComputeWorkGroupCount".into(), format!("{:?}", l.max_compute_work_group_count)),
            ("maxColorAttachments".into(), l.max_color_attachments.to_string()),
            ("logicOp".into(), info.logic_op.to_string()),
            ("R32_UINT image atomics".into(), info.image_atomics_32.to_string()),
            ("R64_UINT image atomics".into(), info.image_atomics_64.to_string()),
            ("fragmentShaderPixelInterlock (kbuf)".into(), info.interlock.to_string()),
            (
                "hardware raster path".into(),
                info.hardware_missing.as_ref().map_or("yes".into(), |m| format!("no: lacks {m}")),
            ),
            ("device_local_heap".into(), info.device_heap.to_string()),
            ("timestamps".into(), gpu.has_timestamps().to_string()),
            ("validation".into(), info.validation.to_string()),
        ]);
        Capabilities {
            device: format!("{} ({:?}, {})", info.name, info.device_type, info.driver),
            // what needs an ordered fragment-stage interlock only where the device has one
            techniques: TechniqueKind::ALL
                .into_iter()
                .filter(|t| !t.needs_interlock() || info.interlock)
                .collect(),
            raster_paths: if info.hardware_missing.is_none() {
                vec![RasterPath::Compute, RasterPath::Hardware]
            } else {
                vec![RasterPath::Compute]
            },
            limits,
        }
    }

    fn raster_path(&self, settings: &Settings) -> RasterPath {
        settings.raster.unwrap_or(RasterPath::Compute)
    }

    fn prepare<'s>(&'s self, scene: &'s Scene) -> Result<Box<dyn Prepared + 's>, OitError> {
        scene.validate()?;
        let gpu = self.gpu()?;
        Ok(Box::new(VulkanPrepared {
            gpu,
            scene,
            pool: BufferPool::default(),
            geometry_made: Cell::new(0),
            compute: RefCell::new(None),
            compute_boxes: RefCell::new(None),
            hardware: RefCell::new(None),
            compute_opaque: RefCell::new(None),
            hardware_opaque: RefCell::new(None),
            layers: oit_core::LayersCache::default(),
            gpu_setup: self.gpu_setup,
            read_back: Default::default(),
            supersample: RefCell::new(None),
        }))
    }
}

/// A scene prepared on the Vulkan backend: per-pixel storage from a pool, reused by the next
/// frame of the same size; the compute rasterizer's buffers kept and grown only when needed; the
/// hardware path's geometry uploaded on its first frame and its count targets kept by size;
/// pipelines cached on the device. [`Prepared::storage_allocations`] counts them all.
pub struct VulkanPrepared<'s> {
    gpu: &'s Gpu,
    scene: &'s Scene,
    pool: BufferPool,
    geometry_made: Cell<u64>,
    compute: RefCell<Option<ComputeBuffers>>,
    compute_boxes: RefCell<Option<ComputeBuffers>>,
    hardware: RefCell<Option<HardwareScene>>,
    /// The compute path's buffers for the opaque part's triangles.
    compute_opaque: RefCell<Option<ComputeBuffers>>,
    /// The hardware path's geometry of the opaque part, uploaded on its first frame.
    hardware_opaque: RefCell<Option<HardwareScene>>,
    /// The scene split for its frames ([`Scene::layers`]): the opaque part, drawn first, and the
    /// transparent part the technique captures, made once per alpha override. The geometry above
    /// is the parts' (their meshes do not depend on the override).
    layers: oit_core::LayersCache<'s>,
    /// `VulkanBackend::gpu_setup`.
    gpu_setup: Option<bool>,
    /// What an earlier frame read back, by its settings (`ctx::ReadBack`): the next frame of
    /// those settings runs that many peels gated on the device instead of reading a flag back per
    /// peel (oit-gpu's peel loop), sizes from that deepest pixel instead of waiting for its counting
    /// pass (`VkCtx::deepest`) and its fragment arrays from that total
    /// (`VkCtx::fragment_capacity`); each checked at its end.
    read_back: RefCell<std::collections::HashMap<String, ReadBack>>,
    /// While a supersampled reference runs ([`VulkanPrepared::supersampled`]): its running sums,
    /// and which sample's frame of how many is being made.
    supersample: RefCell<Option<(std::rc::Rc<crate::device::Buffer>, u32, u32)>>,
}

impl<'s> VulkanPrepared<'s> {
    /// The scene's layers for `settings`' alpha override, made the first time it is asked for.
    fn layers(&self, settings: &Settings) -> std::sync::Arc<oit_core::Layers<'s>> {
        self.layers.get(self.scene, settings.alpha)
    }

    fn compute_raster(
        &self,
        cell: &RefCell<Option<ComputeBuffers>>,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
    ) -> Result<ComputeRaster, OitError> {
        let mut kept = cell.borrow_mut();
        if kept.is_none() {
            *kept = Some(ComputeBuffers::new(self.gpu, self.gpu_setup, &self.geometry_made)?);
        }
        let buffers = kept.as_mut().expect("just made");
        buffers.frame(self.gpu, scene, camera, settings, boxes, &self.geometry_made)
    }

    /// The compute rasters of a frame's transparent part and of its opaque part, where it has
    /// one. Where both are set up on the host (a textured scene with opaque parts), the two
    /// setups run side by side (`oit_gpu::HostSetup::run_both`).
    fn compute_rasters(
        &self,
        part: &Scene,
        opaque: Option<&Scene>,
        camera: &Camera,
        settings: &Settings,
    ) -> Result<(ComputeRaster, Option<ComputeRaster>), OitError> {
        let Some(opaque) = opaque else {
            return Ok((self.compute_raster(&self.compute, part, camera, settings, false)?, None));
        };
        let (mut kept, mut kept_opaque) = (self.compute.borrow_mut(), self.compute_opaque.borrow_mut());
        for k in [&mut kept, &mut kept_opaque] {
            if k.is_none() {
                **k = Some(ComputeBuffers::new(self.gpu, self.gpu_setup, &self.geometry_made)?);
            }
        }
        let (buffers, opaque_buffers) =
            (kept.as_mut().expect("just made"), kept_opaque.as_mut().expect("just made"));
        let made = &self.geometry_made;
        if buffers.sets_up_on_host(part) && opaque_buffers.sets_up_on_host(opaque) {
            let parts = [(buffers.host(), part), (opaque_buffers.host(), opaque)];
            oit_gpu::HostSetup::run_both(parts, camera, settings);
            return Ok((
                buffers.host_set_up(self.gpu, camera, settings, made)?,
                Some(opaque_buffers.host_set_up(self.gpu, camera, settings, made)?),
            ));
        }
        Ok((
            buffers.frame(self.gpu, part, camera, settings, false, made)?,
            Some(opaque_buffers.frame(self.gpu, opaque, camera, settings, false, made)?),
        ))
    }
}

impl Prepared for VulkanPrepared<'_> {
    /// One frame, in screen tiles where its storage does not fit the budget or the device's
    /// limits ([`oit_core::tiling`]).
    fn frame(&mut self, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        let scene = self.scene;
        oit_core::tiling::run("vulkan", scene, settings, |s| self.frame_whole(camera, s, true))
    }

    /// A frame without the image's readback (only its counters come back); a frame that needs
    /// tiles (`--memory`, or over the device's limits) runs through [`Prepared::frame`].
    fn frame_stats(&mut self, camera: &Camera, settings: &Settings) -> Result<oit_core::Stats, OitError> {
        oit_core::tiling::frame_stats(
            settings,
            self,
            |p| p.frame_whole(camera, settings, false),
            |p| p.frame(camera, settings),
        )
    }

    /// Frames in flight ([`FRAMES_IN_FLIGHT`]): each frame is recorded and submitted while the
    /// device runs the one before, and waited for only then. A frame whose end finds its compute
    /// setup outgrew its buffers runs again on its own after the others, and `done` hears of it
    /// last; windows (`--memory`, a region) and frames over the device's limits run one at a time.
    /// A technique that reads a count back in mid-frame (a peel's stop, a sizing pass) still
    /// waits there, for the frames before it too.
    fn frame_loop(
        &mut self,
        cameras: &[Camera],
        settings: &Settings,
        done: &mut dyn FnMut(usize, oit_core::Stats),
    ) -> Result<(), OitError> {
        settings.validate()?;
        if oit_core::msaa::is_supersampled(settings) {
            // several frames each, one after the other
            return oit_core::frames_one_at_a_time(self, cameras, settings, done);
        }
        let this = &*self;
        let end = oit_core::frames_in_flight(
            cameras,
            settings,
            FRAMES_IN_FLIGHT,
            |camera| this.frame_start(camera, settings, false, Instant::now()),
            |f| Ok(f.end()?.map(|frame| frame.stats)),
            done,
        )?;
        end.finish(self, cameras, settings, done)
    }

    fn frames_in_flight(&self) -> usize {
        FRAMES_IN_FLIGHT
    }

    fn storage_allocations(&self) -> u64 {
        self.pool.allocations() + self.geometry_made.get()
    }

    fn pipelines_created(&self) -> Option<u64> {
        Some(self.gpu.pipelines_created())
    }
}

impl VulkanPrepared<'_> {
    /// One frame or one window of a frame (`settings.region`, shifted by setup in fixed point);
    /// the image and per-pixel losses read back only when `readback`.
    fn frame_whole(
        &mut self,
        camera: &Camera,
        settings: &Settings,
        readback: bool,
    ) -> Result<Frame, OitError> {
        if oit_core::msaa::is_supersampled(settings) {
            return self.supersampled(camera, settings, readback);
        }
        // a frame whose GPU setup outgrew the kept buffers (seen at its end) runs again: its
        // setup then reads the counters first and grows them
        match self.frame_once(camera, settings, readback)? {
            Some(frame) => Ok(frame),
            None => self.frame_once(camera, settings, readback)?.ok_or_else(|| {
                OitError::Device("the compute path's setup outgrew its buffers twice in a row".into())
            }),
        }
    }

    /// The supersampled reference (`--supersample`, docs/msaa.md) of a frame or window, as
    /// oit-wgpu makes it: oit-core's frames ([`oit_core::msaa::supersample_frames`]: one
    /// single-sample reference frame a sample position, under a projection moved so that the
    /// position falls on the pixels' centres), each on the frame's raster path (the hardware
    /// path's rasterizer snaps the moved vertices in its own precision), each frame's end adding
    /// its linear colours into running sums on the device instead of writing its own
    /// (`supersample.wgsl`), the last frame's image their mean; the frames' stats added up as
    /// [`oit_core::msaa::SupersampleTotals`] says.
    fn supersampled(
        &mut self,
        camera: &Camera,
        settings: &Settings,
        readback: bool,
    ) -> Result<Frame, OitError> {
        let path = settings.raster.unwrap_or(RasterPath::Compute);
        let bytes = u64::from(settings.width * settings.height).max(1) * oit_gpu::SUPERSAMPLE_SUM_BYTES;
        self.gpu.check_storage("the supersampled reference's running sums", bytes)?;
        let sums = self.pool.take(self.gpu, bytes, crate::device::storage_usage())?;
        let result = oit_gpu::supersampled(camera, settings, path, |i, n, sample_camera, single| {
            *self.supersample.borrow_mut() = Some((sums.clone(), i, n));
            self.frame_whole(sample_camera, single, readback)
        });
        *self.supersample.borrow_mut() = None;
        self.pool.give_back(sums);
        result
    }

    /// [`VulkanPrepared::frame_whole`] once: `None` where the setup did not fit.
    fn frame_once(
        &mut self,
        camera: &Camera,
        settings: &Settings,
        readback: bool,
    ) -> Result<Option<Frame>, OitError> {
        let started = self.frame_start(camera, settings, readback, Instant::now())?;
        started.end()
    }

    /// Records and submits one frame (its one readback included) without waiting for it:
    /// [`InFlight::end`] waits.
    fn frame_start<'c>(
        &'c self,
        camera: &'c Camera,
        settings: &'c Settings,
        readback: bool,
        start: Instant,
    ) -> Result<InFlight<'c>, OitError> {
        settings.validate()?;
        let path = settings.raster.unwrap_or(RasterPath::Compute);
        let this = self;
        // kbuf's interlock, refused before the frame's setup and storage
        let plan = oit_core::plan::Plan::new("vulkan", this.scene, settings)?;
        if path != RasterPath::Hardware {
            plan.refuse_interlock(
                "vulkan",
                "the compute raster path has no fragment stage; use --raster hardware",
            )?;
        }
        if !this.gpu.info.interlock {
            let why = format!("'{}' lacks fragmentShaderPixelInterlock", this.gpu.info.name);
            plan.refuse_interlock("vulkan", &why)?;
        }
        // as oit-cpu: the technique captures the transparent part, under the layers' settings;
        // the opaque part is drawn first; the plan is the whole scene's
        let layers = this.layers(settings);
        let drawn = layers.settings(settings);
        let (part, drawn): (&Scene, &Settings) = (&layers.transparent, &drawn);
        let drivers = match path {
            RasterPath::Compute => {
                let (scene, opaque) = this.compute_rasters(part, layers.opaque.as_ref(), camera, drawn)?;
                Drivers {
                    scene: Raster::Compute(scene),
                    boxes: Box::new(move || {
                        Ok(Raster::Compute(this.compute_raster(
                            &this.compute_boxes,
                            part,
                            camera,
                            drawn,
                            true,
                        )?))
                    }),
                    opaque: opaque.map(Raster::Compute),
                }
            }
            RasterPath::Hardware => {
                this.gpu.check_samples(settings.samples)?;
                // a window of the frame (tiles) draws the full frame's viewport into its target
                // (the recorder's window), or, where the full frame is over the device's largest
                // viewport, maps onto its own in clip space
                let camera = match settings.region {
                    Some(region) if region.viewport(hardware::max_viewport_side(this.gpu)).is_none() => {
                        Camera {
                            proj: region.clip_matrix(settings.width, settings.height) * camera.proj,
                            ..*camera
                        }
                    }
                    _ => *camera,
                };
                if let Some(missing) = &this.gpu.info.hardware_missing {
                    return Err(OitError::Unsupported {
                        backend: "vulkan".into(),
                        what: format!(
                            "the hardware raster path on '{}' (it lacks {missing}): use --raster compute",
                            this.gpu.info.name
                        ),
                    });
                }
                if this.hardware.borrow().is_none() {
                    let made = HardwareScene::new(this.gpu, part, &this.geometry_made)?;
                    *this.hardware.borrow_mut() = Some(made);
                }
                let upload = this.hardware_opaque.borrow().is_none();
                if let (Some(o), true) = (&layers.opaque, upload) {
                    let made = HardwareScene::new(this.gpu, o, &this.geometry_made)?;
                    *this.hardware_opaque.borrow_mut() = Some(made);
                }
                let hw = || -> std::cell::Ref<'_, HardwareScene> {
                    std::cell::Ref::map(this.hardware.borrow(), |h| h.as_ref().expect("made above"))
                };
                let (gpu, made) = (this.gpu, &this.geometry_made);
                let opaque = match (&layers.opaque, &*this.hardware_opaque.borrow()) {
                    (Some(o), Some(ohw)) => {
                        Some(Raster::Hardware(ohw.raster(gpu, o, &camera, drawn, false, made)?))
                    }
                    _ => None,
                };
                Drivers {
                    scene: Raster::Hardware(hw().raster(gpu, part, &camera, drawn, false, made)?),
                    boxes: Box::new(move || {
                        Ok(Raster::Hardware(hw().raster(gpu, part, &camera, drawn, true, made)?))
                    }),
                    opaque,
                }
            }
            other => {
                return Err(OitError::Unsupported {
                    backend: "vulkan".into(),
                    what: format!("the {other} raster path"),
                });
            }
        };
        let mut ctx = VkCtx::new(this.gpu, this.scene, camera, settings, &this.pool)?;
        // every setting can change what a frame reads back (the camera too: checked at its end)
        let key = format!("{settings:?}");
        ctx.speculated = this.read_back.borrow().get(&key).copied().unwrap_or_default();
        run_technique(&mut ctx, &drivers)?;
        ctx.supersample = this.supersample.borrow().clone();
        let finishing = ctx.finish_start(readback)?;
        let technique = settings.technique;
        Ok(InFlight {
            finishing,
            start,
            recorded: start.elapsed(),
            technique,
            read_back: (&this.read_back, key),
        })
    }
}

/// Frames [`VulkanPrepared`]'s frame loop keeps submitted at once: the host records one while the
/// device runs the other.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// A frame submitted and not yet waited for ([`VulkanPrepared::frame_start`]).
struct InFlight<'c> {
    finishing: ctx::Finishing<'c>,
    start: Instant,
    /// From `start` to the frame's submission (recording it, its setup on the host included).
    recorded: std::time::Duration,
    /// For `OIT_HOST_TIMES`'s line.
    technique: Technique,
    /// The prepared scene's read-back counts, and this frame's key in them.
    read_back: (&'c RefCell<std::collections::HashMap<String, ReadBack>>, String),
}

impl InFlight<'_> {
    /// Waits for the frame: `None` where its compute setup did not fit the buffers it was set up
    /// into (the next setup sizes first), or where it ran too few speculated peels (the next
    /// frame of its settings reads its peels back): the frame must run again.
    fn end(self) -> Result<Option<Frame>, OitError> {
        let waiting = Instant::now();
        let ended = self.finishing.wait()?;
        if oit_gpu::host_times() {
            host_times_line(self.technique, self.recorded, waiting.elapsed(), &ended);
        }
        let (kept, key) = self.read_back;
        let mut kept = kept.borrow_mut();
        if ended.missed {
            // the frame runs again reading back what it speculated
            kept.remove(&key);
        } else {
            let fragments = ended.frame.as_ref().map(|f| f.stats.fragments);
            let entry = kept.entry(key).or_default();
            *entry = entry.after(ended.seen, fragments);
        }
        drop(kept);
        let Some(mut frame) = ended.frame else { return Ok(None) };
        frame.stats.wall_ms = self.start.elapsed().as_secs_f64() * 1e3;
        Ok(Some(frame))
    }
}

/// `oit_gpu::host_times`'s line of one Vulkan frame: recording and submitting it (from its start
/// to its submission), the wait at its end, and with timestamps its span on the device (its first
/// timed command's start to its last one's end) and the device's idle time before it (from the
/// last frame's span's end to this one's start: a frame loop that keeps the device busy has
/// little), the device's time within the span that no command timed (fills, copies, barriers:
/// the gaps between one timed command's end and the next one's start) and those gaps by the label
/// of the command after them; and the barriers, transfers and submissions it recorded. A
/// diagnostic (issue 38's steady wall over summed pass times).
fn host_times_line(
    technique: Technique,
    recorded: std::time::Duration,
    waited: std::time::Duration,
    ended: &ctx::Ended,
) {
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    // the last frame's span's end (f64 bits; 0 before any)
    static LAST_END: AtomicU64 = AtomicU64::new(0);
    let mut line = format!(
        "oit host times: {technique} record+submit {:.3} ms, end readback {:.3} ms",
        recorded.as_secs_f64() * 1e3,
        waited.as_secs_f64() * 1e3
    );
    let c = ended.counts;
    line += &format!(", {} barriers, {} transfers, {} submissions", c.barriers, c.transfers, c.submissions);
    if let Some((start, end)) = ended.span_ns {
        let last = f64::from_bits(LAST_END.swap(end.to_bits(), Relaxed));
        line += &format!(", device span {:.3} ms", (end - start) / 1e6);
        if last > 0.0 && start >= last {
            line += &format!(", device idle before {:.3} ms", (start - last) / 1e6);
        }
        let untimed: f64 = ended.gaps.iter().map(|(_, ms)| ms).sum();
        line += &format!(", untimed in span {untimed:.3} ms");
        for (label, ms) in &ended.gaps {
            line += &format!(", before {label} {ms:.3} ms");
        }
    }
    eprintln!("{line}");
}

/// Runs the frame's technique (the reference leaves its per-pixel fragment counts to be read with
/// the frame's end).
fn run_technique(ctx: &mut VkCtx<'_>, drivers: &Drivers<'_>) -> Result<(), OitError> {
    let hardware = matches!(drivers.scene, Raster::Hardware(_));
    // the graphics pipeline's own captures, asked for on the hardware path
    let blend = hardware && ctx.settings.hardware_capture == HardwareCapture::Blend;
    let own = match ctx.settings.technique {
        Technique::Dp | Technique::Ddp | Technique::Bdp { .. } => blend,
        Technique::WeightedAverage | Technique::WeightedSum => blend,
        // the blender composites one draw in primitive order: plain's definition
        Technique::Plain => hardware,
        // the rest (adp's histogram by logic-op OR included: `Frame::histogram_capture`) as
        // every GPU backend runs them
        _ => false,
    };
    if !own {
        return oit_gpu::technique::render(ctx, drivers);
    }
    oit_core::plan::refuse_multisampled_own_capture("vulkan", ctx.settings)?;
    // the opaque pass first, as every frame: the captures' fragment stages cut at its depth
    oit_gpu::technique::opaque_first(ctx, drivers)?;
    match ctx.settings.technique {
        Technique::Plain => technique::blend::plain(ctx, drivers),
        Technique::Dp => technique::blend::dp(ctx, drivers),
        Technique::Ddp => technique::blend::ddp(ctx, drivers),
        Technique::Bdp { .. } => technique::blend::bdp(ctx, drivers),
        // wavg and wsum
        _ => technique::blend::weighted(ctx, drivers),
    }
}

/// For test suites: the backend when a Vulkan device can be opened, else `None` after one line on
/// stderr naming the test and what to install. With `OIT_REQUIRE_GPU=1` a missing device panics.
pub fn backend_or_skip(test: &str) -> Option<VulkanBackend> {
    let backend = VulkanBackend::default();
    match backend.gpu() {
        Ok(_) => Some(backend),
        Err(e) if gpu_required() => {
            panic!("{test}: OIT_REQUIRE_GPU=1 but no Vulkan device could be opened: {e}")
        }
        Err(e) => {
            // to the stream itself: the test harness captures `eprintln!`
            use std::io::Write as _;
            let _ = writeln!(
                std::io::stderr(),
                "skipped {test} on vulkan: {e} (set OIT_REQUIRE_GPU=1 to make this a failure)"
            );
            None
        }
    }
}

/// True when `OIT_REQUIRE_GPU` is set to `1` (or `true`): GPU tests must not skip.
pub fn gpu_required() -> bool {
    std::env::var("OIT_REQUIRE_GPU").is_ok_and(|v| v == "1" || v.eq_ignore_ascii_case("true"))
}
