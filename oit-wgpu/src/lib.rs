//! oit-wgpu: oit's techniques on wgpu, headless, on two capture paths:
//!
//! - **compute** (`RasterPath::Compute`): the papers' CUDA rasterizer as a compute shader, with
//!   oit-cpu's fixed-point setup and rules, so its fragments equal oit-cpu's;
//! - **hardware** (`RasterPath::Hardware`): the GPU's own rasterizer.
//!
//! [`WgpuBackend::prepare`] gives a [`WgpuPrepared`]: what does not depend on the camera is made
//! once and kept, and a steady-state frame creates no buffer for its geometry or storage. On the
//! hardware path the scene's meshes and triangles are uploaded once and a frame writes only the
//! instances' matrices and the shading uniform (`hardware`); on the compute path likewise, and
//! setup kernels transform, clip, snap and bin the triangles on the GPU into buffers the prepared
//! scene keeps (`raster`); per-pixel storage comes from a pool (`pool`).
//!
//! Each technique's WGSL sits next to its Rust in `src/technique/`; the rules shared with oit-core
//! are in oit-shaders' `wgsl/core/common.wgsl`.
//!
//! A frame on each path, read back with its numbers. Without a Vulkan adapter
//! [`backend_or_skip`] prints one `skipped …` line naming what to install and the example stops
//! there, so it runs everywhere (with `OIT_REQUIRE_GPU=1` a missing adapter is a panic instead):
//!
//! ```
//! use oit_core::{load_scene, Backend, Camera, RasterPath, Settings, Technique, View};
//!
//! let Some(backend) = oit_wgpu::backend_or_skip("oit-wgpu's crate example") else { return };
//! let scene = load_scene("planes:4").unwrap();
//! let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
//! for raster in [RasterPath::Hardware, RasterPath::Compute] {
//!     let settings = Settings {
//!         width: 32,
//!         height: 32,
//!         technique: Technique::Fabs { k: None },
//!         raster: Some(raster),
//!         ..Settings::default()
//!     };
//!     let frame = backend.render(&scene, &camera, &settings).unwrap();
//!     // sized from the scene's deepest pixel: every fragment captured, none lost
//!     assert_eq!(frame.stats.captured, frame.stats.fragments);
//!     assert_eq!(frame.stats.lost, 0);
//!     assert_eq!(frame.image.pixels.len(), 32 * 32);
//! }
//! ```
//!
//! To draw into your own renderer instead (your device, vertex buffers and draw calls), see
//! [`OitPass`] and `examples/embed.rs`.

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod ctx;
pub mod embed;
mod frame;
mod gpu;
mod hardware;
mod pool;
mod raster;
mod stage;
mod technique;

use std::cell::{Cell, RefCell};
use std::sync::OnceLock;
use std::time::Instant;

use oit_core::{
    Backend, Camera, Capabilities, Frame, OitError, Prepared, RasterPath, Scene, Settings, Technique,
    TechniqueKind,
};

pub use crate::ctx::{
    Driver, Drivers, Enc, Finishing, Fragments, FrameUniform, Gate, Generated, GpuCtx, Init, RecordedBuffers,
    SetupCheck, TECHNIQUE_PRELUDE, size_class,
};
pub use crate::embed::{CaptureShader, GeometryPass, OitPass, Recorded};
pub use crate::gpu::{
    COMMON_WGSL, Gpu, MIN_STORAGE_BUFFERS, Reading, TIMESTAMP_QUERIES, adapters, required_features,
};
pub use crate::hardware::HardwareRaster;
pub use crate::pool::BufferPool;
pub use crate::raster::{ComputeRaster, setup_site};

use crate::hardware::HardwareScene;
use crate::raster::ComputeBuffers;

/// The wgpu backend. The device opens on first use.
#[derive(Default)]
pub struct WgpuBackend {
    /// Adapter name filter (substring); `None` reads `OIT_ADAPTER`, else prefers a discrete GPU.
    pub adapter: Option<String>,
    gpu: OnceLock<Result<Gpu, String>>,
}

impl WgpuBackend {
    /// A backend for the adapter whose name contains `filter`.
    pub fn new(adapter: Option<String>) -> Self {
        WgpuBackend { adapter, gpu: OnceLock::new() }
    }

    /// The device, opened on first use.
    pub fn gpu(&self) -> Result<&Gpu, OitError> {
        self.gpu
            .get_or_init(|| {
                Gpu::new(self.adapter.as_deref()).map_err(|e| match e {
                    // keep the bare message: it is wrapped in `Device` again below
                    OitError::Device(message) => message,
                    other => other.to_string(),
                })
            })
            .as_ref()
            .map_err(|e| OitError::Device(e.clone()))
    }

    /// The raster path `settings` run on: theirs, or where they name none the technique's
    /// [`WgpuBackend::default_path`], except at several samples a pixel, which the compute
    /// rasterizer alone computes coverage masks for (docs/msaa.md).
    pub fn path_of(settings: &Settings) -> RasterPath {
        match settings.raster {
            Some(path) => path,
            None if settings.samples > 1 => RasterPath::Compute,
            None => WgpuBackend::default_path(settings.technique),
        }
    }

    /// The raster path a technique runs on when the settings name none: the graphics pipeline for
    /// the techniques the papers wrote for it, the compute rasterizer for the CUDA-rasterizer ones.
    pub fn default_path(technique: Technique) -> RasterPath {
        match technique.kind() {
            TechniqueKind::Mdts
            | TechniqueKind::Mdts64
            | TechniqueKind::Fabs
            | TechniqueKind::Mlp
            | TechniqueKind::Dfb
            | TechniqueKind::Ll => RasterPath::Compute,
            _ => RasterPath::Hardware,
        }
    }

    /// [`Backend::prepare`] as its own type, whose [`WgpuPrepared::geometry_allocations`] a
    /// caller can read apart from the per-pixel storage's.
    pub fn prepare_scene<'s>(&'s self, scene: &'s Scene) -> Result<WgpuPrepared<'s>, OitError> {
        scene.validate()?;
        let gpu = self.gpu()?;
        Ok(WgpuPrepared {
            gpu,
            scene,
            pool: BufferPool::default(),
            geometry_made: Cell::new(0),
            hardware: None,
            hardware_opaque: None,
            compute: RefCell::new(None),
            compute_boxes: RefCell::new(None),
            compute_opaque: RefCell::new(None),
            layers: oit_core::LayersCache::default(),
            deepest: RefCell::default(),
            supersample: RefCell::new(None),
        })
    }
}

impl Backend for WgpuBackend {
    fn name(&self) -> &str {
        "wgpu"
    }

    fn capabilities(&self) -> Capabilities {
        match self.gpu() {
            Ok(gpu) => Capabilities {
                device: format!("{} ({:?}, {})", gpu.info.name, gpu.info.device_type, gpu.info.driver),
                // WGSL has no fragment shader interlock
                techniques: TechniqueKind::ALL.into_iter().filter(|t| !t.needs_interlock()).collect(),
                raster_paths: vec![RasterPath::Hardware, RasterPath::Compute],
                limits: vec![
                    ("max_buffer_size".into(), gpu.limits.max_buffer_size.to_string()),
                    (
                        "max_storage_buffer_binding_size".into(),
                        gpu.limits.max_storage_buffer_binding_size.to_string(),
                    ),
                    ("max_texture_dimension_2d".into(), gpu.limits.max_texture_dimension_2d.to_string()),
                    ("timestamps".into(), gpu.has_timestamps().to_string()),
                    (
                        "FLOAT32_BLENDABLE".into(),
                        gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE).to_string(),
                    ),
                ],
            },
            Err(e) => Capabilities { device: format!("none: {e}"), ..Default::default() },
        }
    }

    fn raster_path(&self, settings: &Settings) -> RasterPath {
        WgpuBackend::path_of(settings)
    }

    fn prepare<'s>(&'s self, scene: &'s Scene) -> Result<Box<dyn Prepared + 's>, OitError> {
        Ok(Box::new(self.prepare_scene(scene)?))
    }

    /// One counting geometry pass (oit-gpu's `technique::count`) on the settings' raster path, timed with
    /// the GPU timestamps of its geometry pass (wall time of the pass and its readback where the
    /// device has no timestamps). Two passes run and the second is timed, so that nothing paid
    /// once per frame is counted. (On the H100's hardware path this pass, one `atomicAdd` per
    /// fragment, reads 12.9 ms on `grid:4x4:bunny` at 1024², the first pass and the second alike,
    /// while dp's 13 peels take 63 ms in all: the model's K there overstates dp's cost.)
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        settings.validate()?;
        scene.validate()?;
        let gpu = self.gpu()?;
        let path = WgpuBackend::path_of(settings);
        let driver: Box<dyn Driver> = match path {
            RasterPath::Compute => Box::new(ComputeRaster::new(gpu, scene, camera, settings, false)?),
            RasterPath::Hardware => Box::new(HardwareRaster::new(gpu, scene, camera, settings)?),
            other => {
                return Err(OitError::Unsupported {
                    backend: "wgpu".into(),
                    what: format!("the {other} raster path"),
                });
            }
        };
        let mut ctx = GpuCtx::new(gpu, scene, camera, settings)?;
        oit_gpu::technique::count(&mut ctx, driver.as_ref())?;
        let first = ctx.pass_ms("geometry");
        let start = Instant::now();
        oit_gpu::technique::count(&mut ctx, driver.as_ref())?;
        let wall = start.elapsed().as_secs_f64() * 1e3;
        let second = ctx.pass_ms("geometry") - first;
        let timed = gpu.has_timestamps();
        ctx.finish(path)?;
        Ok(if timed { second } else { wall })
    }
}

/// A scene prepared on the wgpu backend: checked once; the per-pixel storage, resolve state and
/// image buffers of one frame are kept and reused by the next of the same size; pipelines are
/// cached on the device.
///
/// Geometry, on the first frame of each raster path: on the hardware path the scene's meshes
/// (positions, normals, vertex colours, each mesh once) and its triangles (three vertex indices
/// and an instance each, in primitive order) are uploaded once, and each frame writes only the
/// instances' `view_proj · transform`, normal matrices and base colours and the shading uniform;
/// the instances' bounding boxes likewise, on first use; the count target and counter of the
/// geometry passes are kept per image size. On the compute path the meshes are uploaded once too
/// (and the boxes' corners on first use); each frame writes the instances' matrices and a
/// uniform and the setup kernels write triangles and work list into buffers kept here, grown
/// only when a frame needs more.
///
/// [`Prepared::storage_allocations`] counts every buffer (and count texture) this prepared scene
/// created: the per-pixel storage of [`BufferPool::allocations`] and the geometry's,
/// [`WgpuPrepared::geometry_allocations`]. A frame at a view and size seen before adds nothing.
pub struct WgpuPrepared<'s> {
    gpu: &'s Gpu,
    scene: &'s Scene,
    pool: BufferPool,
    /// Buffers and textures created for the geometry so far.
    geometry_made: Cell<u64>,
    /// The hardware path's geometry, uploaded on its first frame.
    hardware: Option<HardwareScene>,
    /// The compute path's buffers for the scene's triangles, made on its first frame.
    compute: RefCell<Option<ComputeBuffers>>,
    /// The same for the instances' bounding boxes, made on first use.
    compute_boxes: RefCell<Option<ComputeBuffers>>,
    /// The hardware path's geometry of the scene's opaque part, uploaded on its first frame.
    hardware_opaque: Option<HardwareScene>,
    /// The compute path's buffers for the opaque part's triangles.
    compute_opaque: RefCell<Option<ComputeBuffers>>,
    /// The scene split for its frames ([`Scene::layers`]): the opaque part, drawn first, and the
    /// transparent part the technique captures, made once per alpha override. The geometry above
    /// is the parts' (their meshes do not depend on the override).
    layers: oit_core::LayersCache<'s>,
    /// The deepest pixel the last frame's counting pass found, by technique, size, window and
    /// path: the next such frame sizes its storage from it without waiting for its own counting
    /// pass, and runs again if that pass finds otherwise ([`GpuCtx::speculated_deepest`]); and
    /// (key + " peels") the passes its peel loop ran, which the next frame records without a
    /// round trip between them ([`GpuCtx::speculated_peels`]).
    deepest: RefCell<std::collections::HashMap<String, u32>>,
    /// While a supersampled reference runs ([`WgpuPrepared::supersampled`]): its running sums,
    /// and which sample's frame of how many is being made.
    supersample: RefCell<Option<(wgpu::Buffer, u32, u32)>>,
}

impl<'s> WgpuPrepared<'s> {
    /// The scene's layers for `settings`' alpha override, made the first time it is asked for.
    fn layers(&self, settings: &Settings) -> std::sync::Arc<oit_core::Layers<'s>> {
        self.layers.get(self.scene, settings.alpha)
    }

    /// Uploads the hardware path's geometry (the transparent part's, and the opaque part's where
    /// there is one) on its first frame.
    fn upload_hardware(&mut self, settings: &Settings) -> Result<(), OitError> {
        hardware::check_samples(self.gpu, settings.samples.max(1))?;
        if self.hardware.is_some() {
            return Ok(());
        }
        let layers = self.layers(settings);
        self.hardware = Some(HardwareScene::new(self.gpu, &layers.transparent, &self.geometry_made)?);
        if let Some(opaque) = &layers.opaque {
            self.hardware_opaque = Some(HardwareScene::new(self.gpu, opaque, &self.geometry_made)?);
        }
        Ok(())
    }

    /// Buffers and textures created so far for the geometry: uploads, per-instance and uniform
    /// buffers, the compute rasterizer's triangles and work lists (each time one grows), and the
    /// hardware path's count targets and counters (one pair per image size).
    pub fn geometry_allocations(&self) -> u64 {
        self.geometry_made.get()
    }

    /// The compute rasterizer of this frame, through the kept buffers in `cell`.
    fn compute_raster(
        &self,
        cell: &RefCell<Option<ComputeBuffers>>,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
    ) -> Result<ComputeRaster, OitError> {
        let mut kept = cell.borrow_mut();
        let buffers = kept.get_or_insert_with(|| ComputeBuffers::new(self.gpu, &self.geometry_made));
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
        let (gpu, made) = (self.gpu, &self.geometry_made);
        let (mut kept, mut kept_opaque) = (self.compute.borrow_mut(), self.compute_opaque.borrow_mut());
        let buffers = kept.get_or_insert_with(|| ComputeBuffers::new(gpu, made));
        let opaque_buffers = kept_opaque.get_or_insert_with(|| ComputeBuffers::new(gpu, made));
        if buffers.sets_up_on_host(gpu, part) && opaque_buffers.sets_up_on_host(gpu, opaque) {
            let started = std::time::Instant::now();
            let parts = [(buffers.host(), part), (opaque_buffers.host(), opaque)];
            oit_gpu::HostSetup::run_both(parts, camera, settings);
            return Ok((
                buffers.host_set_up(gpu, camera, settings, made, started)?,
                Some(opaque_buffers.host_set_up(gpu, camera, settings, made, started)?),
            ));
        }
        Ok((
            buffers.frame(gpu, part, camera, settings, false, made)?,
            Some(opaque_buffers.frame(gpu, opaque, camera, settings, false, made)?),
        ))
    }
}

impl Prepared for WgpuPrepared<'_> {
    /// One frame, in screen tiles where its storage does not fit the budget or the device's
    /// limits ([`oit_core::tiling`]).
    fn frame(&mut self, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        let scene = self.scene;
        oit_core::tiling::run("wgpu", scene, settings, |s| self.frame_with(camera, s, true))
    }

    /// A frame without the image's readback; a frame that needs tiles (`--memory`, or over the
    /// device's limits) runs through [`Prepared::frame`], image and all.
    fn frame_stats(&mut self, camera: &Camera, settings: &Settings) -> Result<oit_core::Stats, OitError> {
        oit_core::tiling::frame_stats(
            settings,
            self,
            |p| p.frame_with(camera, settings, false),
            |p| p.frame(camera, settings),
        )
    }

    /// Frames in flight ([`FRAMES_IN_FLIGHT`]): each frame is recorded and submitted while the
    /// device runs the one before, and its counters are waited for only then. A frame whose end
    /// finds a speculation wrong (a sizing count or a peel count that changed with the view, a
    /// compute setup that outgrew its buffers) runs again on its own after the others, and
    /// `done` hears of it last; windows (`--memory`, a region) run one at a time.
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
        let path = WgpuBackend::path_of(settings);
        if path == RasterPath::Hardware {
            self.upload_hardware(settings)?;
        }
        let this = &*self;
        let end = oit_core::frames_in_flight(
            cameras,
            settings,
            FRAMES_IN_FLIGHT,
            |camera| this.frame_start(camera, settings, path, false, Instant::now()),
            |f| Ok(this.frame_end(f)?.map(|frame| frame.stats)),
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

impl WgpuPrepared<'_> {
    /// One frame or one window of a frame (`settings.region`: the compute path's setup shifts
    /// the window in fixed point; the hardware path maps it onto its viewport in clip space,
    /// `Region::clip_matrix`); the image and per-pixel losses read back only when `readback`
    /// ([`GpuCtx::finish_with`]).
    fn frame_with(
        &mut self,
        camera: &Camera,
        settings: &Settings,
        readback: bool,
    ) -> Result<Frame, OitError> {
        settings.validate()?;
        if oit_core::msaa::is_supersampled(settings) {
            return self.supersampled(camera, settings, readback);
        }
        let gpu = self.gpu;
        let start = Instant::now();
        let path = WgpuBackend::path_of(settings);
        let window_camera;
        // a window the hardware rasterizer cannot draw through the full frame's viewport (a
        // full frame over the device's largest one) maps onto its own in clip space
        let max_side = gpu.limits.max_texture_dimension_2d;
        let camera = match settings.region {
            Some(region) if path == RasterPath::Hardware && region.viewport(max_side).is_none() => {
                let proj = region.clip_matrix(settings.width, settings.height) * camera.proj;
                window_camera = Camera { proj, ..*camera };
                &window_camera
            }
            _ => camera,
        };
        if path == RasterPath::Hardware {
            self.upload_hardware(settings)?;
        }
        // a frame whose setup check (left to its end) finds the setup did not fit runs again,
        // waiting for the setup this time and growing its buffers first
        for _ in 0..2 {
            if let Some(frame) = self.frame_once(camera, settings, path, readback, start)? {
                return Ok(frame);
            }
            for cell in [&self.compute, &self.compute_boxes] {
                if let Some(buffers) = cell.borrow_mut().as_mut() {
                    buffers.trusted = false;
                }
            }
        }
        Err(OitError::Device("the compute path's setup did not fit its buffers twice in a row".into()))
    }

    /// The supersampled reference (`--supersample`, docs/msaa.md) of a frame or window: oit-core's
    /// frames ([`oit_core::msaa::supersample_frames`]: one single-sample reference frame a sample
    /// position, under a projection moved so that the position falls on the pixels' centres),
    /// each on the frame's raster path (the hardware path's rasterizer snaps the moved vertices in
    /// its own precision), each frame's end adding its linear colours into running sums on the
    /// device instead of writing its own (`supersample.wgsl`), the last frame's image their mean;
    /// the frames' stats added up as oit-core's [`oit_core::msaa::SupersampleTotals`] says.
    fn supersampled(
        &mut self,
        camera: &Camera,
        settings: &Settings,
        readback: bool,
    ) -> Result<Frame, OitError> {
        let path = WgpuBackend::path_of(settings);
        let bytes = u64::from(settings.width * settings.height).max(1) * oit_gpu::SUPERSAMPLE_SUM_BYTES;
        self.gpu.check_storage("the supersampled reference's running sums", bytes)?;
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let sums = self.pool.take(&self.gpu.device, "supersample sums", bytes, usage);
        let result = oit_gpu::supersampled(camera, settings, path, |i, n, sample_camera, single| {
            *self.supersample.borrow_mut() = Some((sums.clone(), i, n));
            self.frame_with(sample_camera, single, readback)
        });
        *self.supersample.borrow_mut() = None;
        self.pool.give_back([sums]);
        result
    }

    /// One attempt at a frame ([`GpuCtx::finish_checked`]): `None` where the setup must run again.
    fn frame_once(
        &self,
        camera: &Camera,
        settings: &Settings,
        path: RasterPath,
        readback: bool,
        start: Instant,
    ) -> Result<Option<Frame>, OitError> {
        let flight = self.frame_start(camera, settings, path, readback, start)?;
        self.frame_end(flight)
    }

    /// The first half of [`WgpuPrepared::frame_once`]: the frame recorded and submitted, its
    /// readback under way ([`GpuCtx::finish_start`]).
    fn frame_start<'c>(
        &'c self,
        camera: &'c Camera,
        settings: &'c Settings,
        path: RasterPath,
        readback: bool,
        start: Instant,
    ) -> Result<InFlight<'c>, OitError> {
        let (gpu, scene) = (self.gpu, self.scene);
        let this = self;
        // as oit-cpu: the technique captures the transparent part, under the layers' settings;
        // the opaque part is drawn first; the plan is the whole scene's
        let layers = this.layers(settings);
        let drawn = layers.settings(settings);
        let (part, drawn): (&Scene, &Settings) = (&layers.transparent, &drawn);
        let drivers = match (path, &this.hardware) {
            (RasterPath::Compute, _) => {
                let (scene, opaque) = this.compute_rasters(part, layers.opaque.as_ref(), camera, drawn)?;
                Drivers {
                    scene: Box::new(scene),
                    boxes: Box::new(move || {
                        Ok(Box::new(this.compute_raster(&this.compute_boxes, part, camera, drawn, true)?)
                            as Box<dyn Driver>)
                    }),
                    opaque: opaque.map(|o| Box::new(o) as Box<dyn Driver>),
                }
            }
            (RasterPath::Hardware, Some(hw)) => {
                let made = &this.geometry_made;
                Drivers {
                    scene: Box::new(hw.raster(gpu, part, camera, drawn, false, made)?),
                    boxes: Box::new(move || {
                        Ok(Box::new(hw.raster(gpu, part, camera, drawn, true, made)?) as Box<dyn Driver>)
                    }),
                    opaque: match (&layers.opaque, &this.hardware_opaque) {
                        (Some(o), Some(ohw)) => {
                            Some(Box::new(ohw.raster(gpu, o, camera, drawn, false, made)?))
                        }
                        _ => None,
                    },
                }
            }
            (other, _) => {
                return Err(OitError::Unsupported {
                    backend: "wgpu".into(),
                    what: format!("the {other} raster path"),
                });
            }
        };
        let mut ctx = GpuCtx::with_pool(gpu, scene, camera, settings, Some(&this.pool))?;
        let key = format!(
            "{:?} {}x{} {:?} {path:?}",
            settings.technique, settings.width, settings.height, settings.region
        );
        ctx.speculated_deepest = this.deepest.borrow().get(&key).copied();
        ctx.speculated_peels = this.deepest.borrow().get(&format!("{key} peels")).copied();
        ctx.speculated_fragments = this.deepest.borrow().get(&format!("{key} fragments")).copied();
        technique::run(&mut ctx, &drivers)?;
        ctx.supersample = this.supersample.borrow().clone();
        let seen = [ctx.deepest_seen, ctx.peels_seen, ctx.fragments_seen];
        let finishing = ctx.finish_start(path, readback)?;
        Ok(InFlight { finishing, key, seen, start })
    }

    /// The second half of [`WgpuPrepared::frame_once`]: waits for the frame's readback and
    /// keeps what it counted for the next frame's speculation.
    fn frame_end(&self, flight: InFlight<'_>) -> Result<Option<Frame>, OitError> {
        let InFlight { finishing, key, seen, start } = flight;
        // the deepest pixel, the peel count, the fragment total
        let keys = [key.clone(), format!("{key} peels"), format!("{key} fragments")];
        let Some(mut frame) = finishing.wait()? else {
            // counted otherwise than speculated (or the setup did not fit): the next attempt
            // waits for its counting pass, reads its peel loop's flag after each pass and reads
            // its fragment total
            for k in &keys {
                self.deepest.borrow_mut().remove(k);
            }
            return Ok(None);
        };
        // a frame that speculated its fragment total (dfb, ll) and fitted keeps the capacity for
        // the next (the views it fits take the same buffers), unless its own total fell under
        // half of it: then the next frame is sized from this one's (a smaller class, made once)
        let fragments = match seen[2] {
            None => self.deepest.borrow().get(&keys[2]).copied().and_then(|earlier| {
                let counted = u32::try_from(frame.stats.fragments).ok()?;
                (u64::from(counted) * 2 < u64::from(ctx::size_class(earlier))).then_some(counted)
            }),
            other => other,
        };
        for (k, seen) in keys.into_iter().zip([seen[0], seen[1], fragments]) {
            if let Some(v) = seen {
                self.deepest.borrow_mut().insert(k, v);
            }
        }
        frame.stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Some(frame))
    }
}

/// Frames [`WgpuPrepared`]'s frame loop keeps submitted at once: the host records one while the
/// device runs the other.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// A frame submitted and not yet waited for.
struct InFlight<'c> {
    finishing: Finishing<'c>,
    /// The frame's speculation key (technique, size, window, path).
    key: String,
    /// What the frame read back instead of speculating: the deepest pixel, the peel count, the
    /// fragment total.
    seen: [Option<u32>; 3],
    start: Instant,
}

/// For test suites and examples: the backend when a Vulkan adapter can be opened, else `None`
/// after one line on stderr (past the test harness's capture) naming the test and what to install.
///
/// With `OIT_REQUIRE_GPU=1` in the environment (CI sets it after installing lavapipe) a missing
/// adapter is a panic instead: there, a skip would hide a broken GPU backend.
pub fn backend_or_skip(test: &str) -> Option<WgpuBackend> {
    let backend = WgpuBackend::default();
    match backend.gpu() {
        Ok(_) => Some(backend),
        Err(e) if gpu_required() => {
            panic!("{test}: OIT_REQUIRE_GPU=1 but no Vulkan adapter could be opened: {e}")
        }
        Err(e) => {
            // Written to the stream itself, not through `eprintln!`, which the test harness
            // captures: a skip must be seen in a passing run.
            use std::io::Write as _;
            let _ = writeln!(
                std::io::stderr(),
                "skipped {test}: {e} (set OIT_REQUIRE_GPU=1 to make this a failure)"
            );
            None
        }
    }
}

/// True when `OIT_REQUIRE_GPU` is set to `1` (or `true`): GPU tests must not skip.
pub fn gpu_required() -> bool {
    std::env::var("OIT_REQUIRE_GPU").is_ok_and(|v| v == "1" || v.eq_ignore_ascii_case("true"))
}
