//! The compute-raster path: the papers' "CUDA rasterizer" as a compute shader. Setup (vertex
//! transform, clipping, snapping, triangle setup) follows oit-core's `setup` rule for rule, so the
//! triangles are the same bits as oit-cpu's; the kernel in `shaders/raster_compute.wgsl` walks each
//! triangle's pixels with the same integer edge functions and f32 interpolation, which makes the
//! fragment sets equal oit-cpu's by construction.
//!
//! Setup runs on the GPU (`shaders/setup.wgsl` over `shaders/softfloat.wgsl`): a prepared scene
//! uploads its world-space geometry once ([`GpuGeometry`]: positions, normals, colours and
//! indices of each mesh, and for the bounds passes each instance's box corners), and a frame
//! writes only the per-instance matrices and colours and a uniform, then records the setup kernel
//! (transform, clip, snap, set up, bin into 8×8 tiles), a kernel that writes the work items of the
//! large pieces a workgroup each (`setup_count_main` counts them, `setup_items_main` writes them
//! in order), and a one-invocation kernel that writes the
//! raster kernel's indirect dispatch arguments and item count. Every float operation of the setup
//! kernel is done in integers (softfloat.wgsl says why), so its triangles equal
//! `TriangleSetup::triangle_words`' bit for bit; `tests/gpu_setup.rs` checks that on several scenes.
//!
//! One read-back remains per frame: the two counters (pieces, work items), so that a frame whose
//! triangles or work list outgrow the kept buffers grows them and sets up again (the first frame
//! of a scene, and a view that needs more room than any before). The raster kernel itself is
//! dispatched indirectly from the GPU-written arguments.
//!
//! Where setup runs ([`setup_site`], `oit_gpu::SetupSite`): on the GPU, except for a part of at most
//! `oit_gpu::HOST_SETUP_TRIANGLES` triangles (a wall's quad: the host sets it up in microseconds,
//! the GPU's five setup kernels take a fixed 0.2 ms), and on a CPU device (lavapipe), where the
//! "GPU" is the host's own cores and the integer f32 costs many times the host's float unit
//! (`oit bench --backend wgpu --raster compute --techniques fabs --size 512x512` on lavapipe:
//! bunny 1,826 ms a frame with the GPU's setup against 750 with the host's, `grid:3x3:bunny`
//! 12,126 against 1,781): there oit-core's `TriangleSetup` runs on the host and its words are
//! uploaded each frame, as before the GPU setup. `OIT_HOST_SETUP=1` forces the host's setup,
//! `OIT_HOST_SETUP=0` the GPU's, on any device. A textured frame sets up on the host on every
//! device: a triangle's level of detail is chosen in f64 (`oit_core::texture::level_for`), which
//! the GPU's setup does not port; the host packs the textures and each textured triangle's record
//! after the triangles (`oit_gpu::host_setup`), and the raster kernel samples them with oit-core's
//! sampler in integers (`texture.wgsl`), so its fragments' colours are oit-cpu's.

use std::cell::Cell;

use oit_core::gpu_setup::{ARGS_ITEMS, ARGS_PER_ITEM, ARGS_WORDS, COUNTER_WORDS, SetupGeometry, VERT_WORDS};
use oit_core::setup::{TRIANGLE_WORDS, TriangleSetup};
use oit_core::{Camera, OitError, RasterPath, Scene, Settings};

use crate::ctx::{Driver, Gate, Generated, GpuCtx, SetupCheck, dispatch_size};
use crate::gpu::Gpu;

const RASTER_WGSL: &str = oit_shaders::COMPUTE_RASTER;
/// The setup kernels: softfloat.wgsl's integer f32, then setup.wgsl.
pub const SETUP_WGSL: &str = oit_shaders::SETUP;
/// Bytes of the smallest triangle and work-list buffers (a binding may not be empty).
const MIN_BYTES: u64 = 256;
/// Bytes of the indirect-argument buffer: the per-pixel and per-item raster dispatches (4 words
/// each) and the item count.
const ARGS_BYTES: u64 = ARGS_WORDS as u64 * 4;

/// Where the compute path sets triangles up ([`oit_gpu::SetupSite`]): as `OIT_HOST_SETUP` says,
/// else on the host on a CPU device and on the GPU (save small parts) on any other (module docs).
pub fn setup_site(gpu: &Gpu) -> oit_gpu::SetupSite {
    oit_gpu::setup_site(gpu.info.device_type == wgpu::DeviceType::Cpu)
}

/// Triangles on the GPU and the (triangle, tile) work list of the compute rasterizer, for one
/// frame: handles to a `ComputeBuffers`' buffers.
pub struct ComputeRaster {
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    generated: wgpu::Buffer,
    args: wgpu::Buffer,
    /// The gated copy of `args`, for gated passes.
    gated: wgpu::Buffer,
    /// Device milliseconds of this frame's setup kernels (GPU setup on a device with
    /// timestamps), handed to the frame's first geometry pass ([`Driver::take_setup_ms`]).
    setup_ms: Cell<Option<f64>>,
    /// The setup's capacity check, left to the end of the frame ([`Driver::take_setup_check`]).
    check: std::cell::RefCell<Option<SetupCheck>>,
}

impl ComputeRaster {
    /// Sets up the scene's triangles (or its instances' bounding boxes) for compute raster, in
    /// buffers of its own (a prepared scene keeps a `ComputeBuffers` instead).
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
    ) -> Result<Self, OitError> {
        let made = Cell::new(0);
        ComputeBuffers::new(gpu, &made).frame(gpu, scene, camera, settings, boxes, &made)
    }
}

impl ComputeRaster {
    /// The triangles the compute path sets up for this view, as `TriangleSetup::triangle_words`
    /// lays them out, and the work list ((triangle, tile) pairs), read back: the GPU's setup
    /// (`on_gpu`, on any device; through its vertex cache when `vertex_cache`, else a transform
    /// per triangle corner), or the host's. The GPU's come in an order of its choosing. For
    /// tests.
    pub fn setup_words(
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        on_gpu: bool,
        vertex_cache: bool,
    ) -> Result<(Vec<u32>, Vec<[u32; 2]>), OitError> {
        let made = Cell::new(0);
        let mut buffers = ComputeBuffers::new(gpu, &made);
        buffers.vertex_cache = vertex_cache;
        if on_gpu {
            buffers.gpu_frame(gpu, scene, camera, settings, boxes, &made)?;
        } else {
            let started = std::time::Instant::now();
            buffers.host.run(scene, camera, settings, boxes);
            buffers.host_frame(gpu, camera, settings, &made, started)?;
        }
        let args = gpu.read_u32(&buffers.args)?;
        let items = args[8] as usize;
        let pieces = match &buffers.setup {
            Some(s) if on_gpu => gpu.read_u32(&s.counters)?[0] as usize,
            _ if boxes => TriangleSetup::bounding_boxes(scene, camera, settings).triangles.len(),
            _ => TriangleSetup::new(scene, camera, settings).triangles.len(),
        };
        let mut tris = gpu.read_u32(&buffers.tris)?;
        tris.truncate(pieces * TRIANGLE_WORDS);
        let list = gpu.read_u32(&buffers.items)?;
        let list = list.chunks_exact(2).take(items).map(|c| [c[0], c[1]]).collect();
        Ok((tris, list))
    }
}

/// A scene's world-space geometry on the GPU for the setup kernel, uploaded once
/// ([`SetupGeometry`]'s words; the layout is oit-core's, shared with oit-vulkan).
pub(crate) struct GpuGeometry {
    buffer: wgpu::Buffer,
    layout: SetupGeometry,
}

impl GpuGeometry {
    fn new(gpu: &Gpu, scene: &Scene, boxes: bool, made: &Cell<u64>) -> Result<GpuGeometry, OitError> {
        let mut layout = SetupGeometry::new(scene, boxes)?;
        let words = std::mem::take(&mut layout.words);
        let bytes = (words.len() as u64 * 4).max(MIN_BYTES);
        gpu.check_scene_storage("the scene's geometry for the compute path's setup", bytes)?;
        let buffer = storage_buffer(gpu, "setup geometry", bytes, made);
        gpu.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&words));
        Ok(GpuGeometry { buffer, layout })
    }
}

/// The compute rasterizer's buffers, kept between the frames of a prepared scene: the set-up
/// triangles and the work list (grown, never shrunk, when a frame needs more), the raster uniform,
/// the `generated` counter, and the setup kernel's geometry (uploaded once), instance table,
/// uniform, counters and indirect arguments. A frame that fits creates no buffer.
pub(crate) struct ComputeBuffers {
    tris: wgpu::Buffer,
    items: wgpu::Buffer,
    uniform: wgpu::Buffer,
    generated: wgpu::Buffer,
    args: wgpu::Buffer,
    /// The gated copy of `args` ([`GpuCtx::geometry_pass_if`]).
    gated: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    setup: Option<SetupBuffers>,
    /// Whether the GPU setup may use its vertex cache (`SetupBuffers::use_verts`): on unless
    /// `OIT_SETUP_VERTS=0`.
    vertex_cache: bool,
    /// Whether an earlier frame's setup fitted these buffers: then a frame does not wait for the
    /// setup's counters before its passes but checks them at its end (`SetupCheck`).
    pub(crate) trusted: bool,
    /// The host's setup, kept for the next frame set up on the host.
    host: oit_gpu::HostSetup,
}

/// What the GPU setup keeps besides the outputs.
struct SetupBuffers {
    geometry: GpuGeometry,
    instances: wgpu::Buffer,
    uniform: wgpu::Buffer,
    counters: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    /// Bound to the current triangle and work-list buffers (remade when one grows).
    group: Option<wgpu::BindGroup>,
    /// The setup pass's two timestamps and their resolve buffer, where the device has them.
    timestamps: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    /// The vertex cache (setup.wgsl's `verts`), or a placeholder where it is off.
    verts: wgpu::Buffer,
    /// Whether the setup transforms each vertex once into the cache (`vertex_main`) rather than
    /// each triangle's three: on unless the cache would exceed the device's binding limit, or
    /// `OIT_SETUP_VERTS=0` turns it off (to measure the two side by side).
    use_verts: bool,
}

/// Bytes of one vertex-cache record (setup.wgsl's `VERT_WORDS`).
const VERT_BYTES: u64 = VERT_WORDS as u64 * 4;

fn storage_buffer(gpu: &Gpu, label: &str, size: u64, made: &Cell<u64>) -> wgpu::Buffer {
    use wgpu::BufferUsages as U;
    buffer(gpu, label, size, U::STORAGE | U::COPY_DST | U::COPY_SRC, made)
}

fn buffer(gpu: &Gpu, label: &str, size: u64, usage: wgpu::BufferUsages, made: &Cell<u64>) -> wgpu::Buffer {
    made.set(made.get() + 1);
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

/// The size a buffer of `old` bytes grows to when `needed` bytes do not fit: at least double, so
/// that views needing a little more each time do not create a buffer each frame, but never over
/// the device's limit (`needed` was checked against it).
fn grown(gpu: &Gpu, old: u64, needed: u64) -> u64 {
    let limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
    needed.max(old.saturating_mul(2).min(limit)).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
}

fn layout_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

fn bind(gpu: &Gpu, layout: &wgpu::BindGroupLayout, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("compute raster"),
        layout,
        entries: &entries,
    })
}

impl ComputeBuffers {
    /// Empty buffers (grown by the first frame that needs more); `made` counts the buffers created.
    pub(crate) fn new(gpu: &Gpu, made: &Cell<u64>) -> ComputeBuffers {
        use wgpu::BufferUsages as U;
        let device = &gpu.device;
        let tris = storage_buffer(gpu, "triangles", MIN_BYTES, made);
        let items = storage_buffer(gpu, "raster items", MIN_BYTES, made);
        let uniform = buffer(gpu, "raster uniform", 32, U::UNIFORM | U::COPY_DST, made);
        let generated = buffer(gpu, "generated", 16, U::STORAGE | U::COPY_SRC | U::COPY_DST, made);
        let args = buffer(
            gpu,
            "raster dispatch",
            ARGS_BYTES,
            U::STORAGE | U::INDIRECT | U::COPY_SRC | U::COPY_DST,
            made,
        );
        let gated = buffer(gpu, "gated raster dispatch", ARGS_BYTES, U::STORAGE | U::INDIRECT, made);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("compute raster"),
            entries: &[
                layout_entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
                layout_entry(1, wgpu::BufferBindingType::Storage { read_only: false }),
                layout_entry(2, wgpu::BufferBindingType::Uniform),
                layout_entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
            ],
        });
        let group = bind(gpu, &layout, &[&tris, &items, &uniform, &generated]);
        let vertex_cache =
            !std::env::var("OIT_SETUP_VERTS").is_ok_and(|v| v == "0" || v.eq_ignore_ascii_case("false"));
        ComputeBuffers {
            tris,
            items,
            uniform,
            generated,
            args,
            gated,
            layout,
            group,
            setup: None,
            vertex_cache,
            trusted: false,
            host: oit_gpu::HostSetup::default(),
        }
    }

    /// Grows the triangle and work-list buffers to hold `tri_bytes` and `item_bytes` (counted in
    /// `made`); true when one was made.
    fn reserve(
        &mut self,
        gpu: &Gpu,
        tri_bytes: u64,
        item_bytes: u64,
        made: &Cell<u64>,
    ) -> Result<bool, OitError> {
        gpu.check_scene_storage("the triangles", tri_bytes)?;
        gpu.check_storage("the raster work list", item_bytes)?;
        let mut rebind = false;
        if tri_bytes > self.tris.size() {
            self.tris = storage_buffer(gpu, "triangles", grown(gpu, self.tris.size(), tri_bytes), made);
            rebind = true;
        }
        if item_bytes > self.items.size() {
            self.items = storage_buffer(gpu, "raster items", grown(gpu, self.items.size(), item_bytes), made);
            rebind = true;
        }
        if rebind {
            self.group = bind(gpu, &self.layout, &[&self.tris, &self.items, &self.uniform, &self.generated]);
            if let Some(s) = &mut self.setup {
                s.group = None;
            }
        }
        Ok(rebind)
    }

    /// The raster uniform with `items` work items (the GPU setup overwrites the count).
    fn write_uniform(&self, gpu: &Gpu, camera: &Camera, settings: &Settings, items: u32) {
        let uniform = oit_gpu::raster_uniform(camera, settings, items);
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(&uniform));
    }

    /// Sets up this frame's triangles of the scene (or of its instances' bounding boxes) and their
    /// work list into the kept buffers: on the GPU, or on the host where [`setup_site`] says.
    pub(crate) fn frame(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<ComputeRaster, OitError> {
        let (setup_ms, check) = if self.sets_up_on_host(gpu, scene) {
            let started = std::time::Instant::now();
            self.host.run(scene, camera, settings, boxes);
            self.host_frame(gpu, camera, settings, made, started)?;
            (None, None)
        } else {
            self.gpu_frame(gpu, scene, camera, settings, boxes, made)?
        };
        Ok(self.raster(setup_ms, check))
    }

    /// Whether a frame of `scene` is set up on the host (`oit_gpu::sets_up_on_host`, at the site
    /// [`setup_site`] says).
    pub(crate) fn sets_up_on_host(&self, gpu: &Gpu, scene: &Scene) -> bool {
        oit_gpu::sets_up_on_host(setup_site(gpu), scene)
    }

    /// The kept host setup ([`ComputeBuffers::host_set_up`] uploads what it holds).
    pub(crate) fn host(&mut self) -> &mut oit_gpu::HostSetup {
        &mut self.host
    }

    /// The frame whose host setup ([`ComputeBuffers::host`]) has run, `started` at `started`:
    /// its words and work list uploaded.
    pub(crate) fn host_set_up(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        settings: &Settings,
        made: &Cell<u64>,
        started: std::time::Instant,
    ) -> Result<ComputeRaster, OitError> {
        self.host_frame(gpu, camera, settings, made, started)?;
        Ok(self.raster(None, None))
    }

    /// This frame's raster through the kept buffers.
    fn raster(&self, setup_ms: Option<f64>, check: Option<SetupCheck>) -> ComputeRaster {
        ComputeRaster {
            layout: self.layout.clone(),
            group: self.group.clone(),
            generated: self.generated.clone(),
            args: self.args.clone(),
            gated: self.gated.clone(),
            setup_ms: Cell::new(setup_ms),
            check: std::cell::RefCell::new(check),
        }
    }

    /// The host's setup (oit-core's `TriangleSetup`, run into `self.host` from `started` on):
    /// its words and work list uploaded.
    fn host_frame(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        settings: &Settings,
        made: &Cell<u64>,
        started: std::time::Instant,
    ) -> Result<(), OitError> {
        let set_up = started.elapsed();
        let (word_count, item_count) = (self.host.words.len(), self.host.items.len());
        self.reserve(gpu, word_count as u64 * 4, item_count as u64 * 8, made)?;
        let (words, items) = (&self.host.words, &self.host.items);
        let queue = &gpu.queue;
        if !words.is_empty() {
            queue.write_buffer(&self.tris, 0, bytemuck::cast_slice(words));
        }
        if !items.is_empty() {
            queue.write_buffer(&self.items, 0, bytemuck::cast_slice(items));
        }
        self.write_uniform(gpu, camera, settings, items.len() as u32);
        queue.write_buffer(&self.args, 0, bytemuck::cast_slice(&oit_gpu::raster_args(items.len() as u64)));
        if oit_gpu::host_times() {
            eprintln!(
                "oit host times: host setup {:.3} ms ({} triangle words, {} items), upload {:.3} ms",
                set_up.as_secs_f64() * 1e3,
                words.len(),
                items.len(),
                (started.elapsed() - set_up).as_secs_f64() * 1e3
            );
        }
        Ok(())
    }

    /// The GPU's setup: the instance table and uniform written, the setup kernel and the
    /// arguments kernel recorded and run, the counters read back; set up again into grown
    /// buffers when they did not fit. Returns the setup's device milliseconds, where the device
    /// has timestamps (read back with the counters).
    fn gpu_frame(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<(Option<f64>, Option<SetupCheck>), OitError> {
        use wgpu::BufferUsages as U;
        if self.setup.as_ref().is_none_or(|s| s.geometry.layout.boxes != boxes) {
            self.trusted = false;
            let geometry = GpuGeometry::new(gpu, scene, boxes, made)?;
            let instance_bytes = geometry.layout.instance_bytes();
            let layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("setup"),
                entries: &[
                    layout_entry(0, wgpu::BufferBindingType::Uniform),
                    layout_entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
                    layout_entry(2, wgpu::BufferBindingType::Storage { read_only: true }),
                    layout_entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
                    layout_entry(4, wgpu::BufferBindingType::Storage { read_only: false }),
                    layout_entry(5, wgpu::BufferBindingType::Storage { read_only: false }),
                    layout_entry(6, wgpu::BufferBindingType::Storage { read_only: false }),
                    layout_entry(7, wgpu::BufferBindingType::Storage { read_only: false }),
                ],
            });
            // a first guess at the room the pieces and the work list need (grown if short)
            let limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
            let (guess_tris, guess_items) = geometry.layout.first_guess(limit);
            let vert_bytes = geometry.layout.vertex_total() * VERT_BYTES;
            let use_verts = self.vertex_cache && vert_bytes > 0 && vert_bytes <= limit;
            let verts =
                storage_buffer(gpu, "setup vertex cache", if use_verts { vert_bytes } else { 16 }, made);
            self.setup = Some(SetupBuffers {
                geometry,
                instances: storage_buffer(gpu, "setup instances", instance_bytes, made),
                uniform: buffer(
                    gpu,
                    "setup uniform",
                    4 * oit_core::gpu_setup::SETUP_UNIFORM_WORDS as u64,
                    U::UNIFORM | U::COPY_DST,
                    made,
                ),
                counters: buffer(
                    gpu,
                    "setup counters",
                    COUNTER_WORDS as u64 * 4,
                    U::STORAGE | U::COPY_SRC | U::COPY_DST,
                    made,
                ),
                layout,
                group: None,
                verts,
                use_verts,
                timestamps: gpu.has_timestamps().then(|| {
                    let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                        label: Some("setup timestamps"),
                        ty: wgpu::QueryType::Timestamp,
                        count: 2,
                    });
                    (set, buffer(gpu, "setup timestamps", 16, U::QUERY_RESOLVE | U::COPY_SRC, made))
                }),
            });
            self.reserve(gpu, guess_tris.max(self.tris.size()), guess_items.max(self.items.size()), made)?;
        }
        let setup_pipeline = {
            let s = self.setup.as_ref().expect("made above");
            gpu.compute_pipeline(SETUP_WGSL, "setup_main", &[&s.layout])?
        };
        let count_pipeline = {
            let s = self.setup.as_ref().expect("made above");
            gpu.compute_pipeline(SETUP_WGSL, "setup_count_main", &[&s.layout])?
        };
        let items_pipeline = {
            let s = self.setup.as_ref().expect("made above");
            gpu.compute_pipeline(SETUP_WGSL, "setup_items_main", &[&s.layout])?
        };
        let finish_pipeline = {
            let s = self.setup.as_ref().expect("made above");
            gpu.compute_pipeline(SETUP_WGSL, "setup_finish_main", &[&s.layout])?
        };
        let vertex_pipeline = {
            let s = self.setup.as_ref().expect("made above");
            gpu.compute_pipeline(SETUP_WGSL, "vertex_main", &[&s.layout])?
        };
        {
            let s = self.setup.as_ref().expect("made above");
            let words = s.geometry.layout.instance_words(scene, camera, settings);
            gpu.queue.write_buffer(&s.instances, 0, bytemuck::cast_slice(&words));
        }
        self.write_uniform(gpu, camera, settings, 0);
        loop {
            let tri_capacity = self.tris.size() / (TRIANGLE_WORDS as u64 * 4);
            let item_capacity = self.items.size() / 8;
            let s = self.setup.as_mut().expect("made above");
            let uniform = s.geometry.layout.uniform_words(settings, tri_capacity, item_capacity, s.use_verts);
            gpu.queue.write_buffer(&s.uniform, 0, bytemuck::cast_slice(&uniform));
            let group = s.group.get_or_insert_with(|| {
                bind(
                    gpu,
                    &s.layout,
                    &[
                        &s.uniform,
                        &s.instances,
                        &s.geometry.buffer,
                        &self.tris,
                        &self.items,
                        &s.counters,
                        &self.args,
                        &s.verts,
                    ],
                )
            });
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&s.counters, 0, None);
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("setup"),
                    timestamp_writes: s.timestamps.as_ref().map(|(set, _)| {
                        wgpu::ComputePassTimestampWrites {
                            query_set: set,
                            beginning_of_pass_write_index: Some(0),
                            end_of_pass_write_index: Some(1),
                        }
                    }),
                });
                pass.set_bind_group(0, &*group, &[]);
                if s.use_verts {
                    let (x, y) = dispatch_size(s.geometry.layout.vertex_total());
                    if x > 0 {
                        pass.set_pipeline(&vertex_pipeline);
                        pass.dispatch_workgroups(x, y, 1);
                    }
                }
                let (x, y) = dispatch_size(u64::from(s.geometry.layout.tasks));
                if x > 0 {
                    pass.set_pipeline(&setup_pipeline);
                    pass.dispatch_workgroups(x, y, 1);
                    // the large pieces' work items, a workgroup a piece: counted, then written
                    // in order
                    let spread = s.geometry.layout.spread_groups();
                    pass.set_pipeline(&count_pipeline);
                    pass.dispatch_workgroups(spread, 1, 1);
                    pass.set_pipeline(&items_pipeline);
                    pass.dispatch_workgroups(spread, 1, 1);
                }
                pass.set_pipeline(&finish_pipeline);
                pass.dispatch_workgroups(1, 1, 1);
            }
            // the raster uniform's item count, from the arguments kernel
            encoder.copy_buffer_to_buffer(&self.args, ARGS_ITEMS, &self.uniform, 0, 4);
            if let Some((set, resolve)) = &s.timestamps {
                encoder.resolve_query_set(set, 0..2, resolve, 0);
            }
            gpu.queue.submit([encoder.finish()]);
            if self.trusted {
                // an earlier frame fitted: check at the end of this one, not now
                let check = SetupCheck {
                    counters: s.counters.clone(),
                    stamps: s.timestamps.as_ref().map(|(_, resolve)| resolve.clone()),
                    tri_capacity,
                    item_capacity,
                };
                return Ok((None, Some(check)));
            }
            // the counters (and the setup's timestamps) in one readback: a round trip before the
            // frame's passes, to check the pieces fit (the first frame, and after a miss)
            let mut read = vec![&s.counters];
            read.extend(s.timestamps.as_ref().map(|(_, resolve)| resolve));
            let words = gpu.read_u32s(&read)?;
            let counts = &words[0];
            let (pieces, items) = (u64::from(counts[0]), u64::from(counts[1]));
            if pieces <= tri_capacity && items <= item_capacity {
                self.trusted = true;
                let ms = words.get(1).map(|t| gpu.pair_ms(t, 0));
                return Ok((ms, None));
            }
            let grew = self.reserve(gpu, pieces * TRIANGLE_WORDS as u64 * 4, items * 8, made)?;
            if !grew {
                return Err(OitError::Device(format!(
                    "the compute path's setup needs {pieces} triangles and {items} work items, more than its buffers hold"
                )));
            }
        }
    }
}

impl Driver for ComputeRaster {
    fn path(&self) -> RasterPath {
        RasterPath::Compute
    }

    fn take_setup_ms(&self) -> Option<f64> {
        self.setup_ms.take()
    }

    fn take_setup_check(&self) -> Option<SetupCheck> {
        self.check.borrow_mut().take()
    }

    fn gate(&self) -> Option<Gate> {
        let words = (self.args.size() / 4) as u32;
        Some(Gate { from: self.args.clone(), to: self.gated.clone(), words })
    }

    fn geometry_pass(
        &self,
        ctx: &mut GpuCtx<'_>,
        source: &str,
        layout0: &wgpu::BindGroupLayout,
        group0: &wgpu::BindGroup,
    ) -> Result<Generated, OitError> {
        // A workgroup per item spreads a large triangle over the GPU (measured on the H100, fabs on
        // planes:64 at 1024²: 7.5 ms of GPU time a frame, 2.7 of them the two geometry passes,
        // against 10.9 ms with one invocation walking each 16×16 tile); on a CPU device (lavapipe)
        // it tests 64 pixels for each small triangle and ran the conformance tests 7× slower, so
        // there one invocation walks an item.
        let per_pixel = oit_gpu::raster_per_pixel(ctx.gpu.info.device_type == wgpu::DeviceType::Cpu);
        let entry = if per_pixel { "raster_main" } else { "raster_loop_main" };
        let module = format!("{source}\n{RASTER_WGSL}");
        let pipeline = ctx.gpu.compute_pipeline(&module, entry, &[layout0, &self.layout])?;
        let classify = if ctx.classify_items {
            Some(ctx.gpu.compute_pipeline(&module, "classify_main", &[layout0, &self.layout])?)
        } else {
            None
        };
        let args = if ctx.gated_pass { &self.gated } else { &self.args };
        let label = ctx.geometry_label;
        let mut encoder = ctx.take_encoder();
        encoder.clear_buffer(&self.generated, 0, None);
        let writes = ctx.render_timestamps().map(|w| wgpu::ComputePassTimestampWrites {
            query_set: w.query_set,
            beginning_of_pass_write_index: w.beginning_of_pass_write_index,
            end_of_pass_write_index: w.end_of_pass_write_index,
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: writes,
            });
            pass.set_bind_group(0, group0, &[]);
            pass.set_bind_group(1, &self.group, &[]);
            // arguments written by the setup (or the host's): the per-pixel dispatch, then the
            // per-item one (`classify_main`'s too)
            if let Some(classify) = &classify {
                pass.set_pipeline(classify);
                pass.dispatch_workgroups_indirect(args, ARGS_PER_ITEM);
            }
            pass.set_pipeline(&pipeline);
            pass.dispatch_workgroups_indirect(args, if per_pixel { 0 } else { ARGS_PER_ITEM });
        }
        ctx.finish_timed(label, encoder)?;
        Ok(Generated(self.generated.clone()))
    }
}
