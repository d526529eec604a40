//! The device: adapter choice, the features and limits oit asks for, and small helpers (shader
//! modules with the shared WGSL prepended, storage buffers checked against the limits, blocking
//! readback, a pipeline cache).

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use oit_core::OitError;

/// The WGSL every module starts with: oit-core's rules and the fragment contract.
pub const COMMON_WGSL: &str = oit_shaders::COMMON;

/// Features oit needs on every adapter.
pub fn required_features() -> wgpu::Features {
    wgpu::Features::SHADER_INT64
        | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
        | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS
}

/// Features used when the adapter has them.
pub fn optional_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::FLOAT32_BLENDABLE
        // 8 samples a pixel on the hardware path, where the adapter's count target format takes
        // them (WebGPU guarantees 4)
        | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
        // the hardware path's fixed-function test at the opaque depth before the fragment stage
        // (`core/raster_hardware_early.wgsl`); without it the stage tests the depth itself
        | wgpu::Features::SHADER_EARLY_DEPTH_TEST
}

/// The format of the hardware path's count target on a device with `features`: R16Float counts
/// exactly up to 2048 fragments per pixel and pass; R32Float (blendable only with
/// FLOAT32_BLENDABLE) up to 2^24.
pub(crate) fn count_format(features: wgpu::Features) -> wgpu::TextureFormat {
    if features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        wgpu::TextureFormat::R32Float
    } else {
        wgpu::TextureFormat::R16Float
    }
}

/// The formats of the blend captures' render targets (`technique/`), whose sample counts an
/// adapter is asked for where oit opens the device ([`Gpu::takes_samples`]): dp's depth peel's
/// layer and depth targets among them.
const BLEND_FORMATS: [wgpu::TextureFormat; 7] = [
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::R32Float,
    wgpu::TextureFormat::R16Float,
    wgpu::TextureFormat::Rg32Uint,
    wgpu::TextureFormat::Depth32Float,
];

/// The most storage buffers one of oit's pipelines binds in a shader stage: group 0's resolve
/// state, up to 6 technique arrays, the loss counts and the opaque image's key and colour (10),
/// and group 1's geometry (3: the compute rasterizer's triangles, work items and count, the
/// triangle buffer holding a textured frame's textures too; the hardware path's vertex stage
/// reads its vertices, triangles, instances and textures (4), its fragment stage group 0's and
/// the textures (11)).
pub const MIN_STORAGE_BUFFERS: u32 = 13;

/// An open device with what oit learned about it.
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself.
    pub info: wgpu::AdapterInfo,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    /// Limits of the device (the adapter's own, requested in full).
    pub limits: wgpu::Limits,
    /// Whether the hardware path's count target takes 8 samples a pixel (the adapter's format
    /// features, where the device has `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`; false for a
    /// device oit did not open).
    pub eight_samples: bool,
    /// The sample counts the blend captures' target formats take as multisampled render targets
    /// (the adapter's format features, where the device has
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`; empty for a device oit did not open, which then
    /// gets WebGPU's guarantees: [`Gpu::takes_samples`]).
    multisampled: Vec<(wgpu::TextureFormat, wgpu::TextureFormatFeatureFlags)>,
    pipelines: Mutex<HashMap<u64, Arc<wgpu::ComputePipeline>>>,
    render_pipelines: Mutex<HashMap<u64, Arc<wgpu::RenderPipeline>>>,
    /// Mappable readback buffers, kept for the next readback of the same size.
    staging: Mutex<Vec<wgpu::Buffer>>,
    /// Timestamp query sets, kept for the next frame.
    queries: Mutex<Vec<wgpu::QuerySet>>,
    /// Readbacks so far (each a CPU–GPU round trip).
    readbacks: std::sync::atomic::AtomicU64,
    /// Group 0's layouts by technique-buffer count (`GpuCtx::layout0`), made once.
    layouts: Mutex<HashMap<usize, wgpu::BindGroupLayout>>,
}

/// Queries in one timestamp query set: two a timed pass, so a frame records 2,048 passes before
/// it reads their times back (wgpu's most queries in a set is 4,096).
pub const TIMESTAMP_QUERIES: u32 = 4096;

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    desc.backends = wgpu::Backends::VULKAN;
    wgpu::Instance::new(desc)
}

/// Every Vulkan adapter wgpu finds.
pub fn adapters() -> Vec<wgpu::Adapter> {
    pollster::block_on(instance().enumerate_adapters(wgpu::Backends::VULKAN))
}

impl Gpu {
    /// Opens an adapter: the first whose name contains `filter` (case-insensitive), else the one
    /// `OIT_ADAPTER` names, else the first discrete GPU, else any.
    pub fn new(filter: Option<&str>) -> Result<Gpu, OitError> {
        let env = std::env::var("OIT_ADAPTER").ok();
        let filter = filter.map(str::to_owned).or(env);
        let all = adapters();
        if all.is_empty() {
            return Err(OitError::Device(
                "no Vulkan adapter found: install a Vulkan driver (e.g. `apt-get install mesa-vulkan-drivers` for lavapipe)".into(),
            ));
        }
        let names: Vec<String> = all.iter().map(|a| a.get_info().name).collect();
        let adapter = match &filter {
            Some(f) => {
                let f = f.to_lowercase();
                all.into_iter().find(|a| a.get_info().name.to_lowercase().contains(&f)).ok_or_else(|| {
                    OitError::Device(format!(
                        "no adapter matches '{f}'; adapters found: {}",
                        names.join(", ")
                    ))
                })?
            }
            None => {
                let discrete =
                    all.iter().position(|a| a.get_info().device_type == wgpu::DeviceType::DiscreteGpu);
                all.into_iter().nth(discrete.unwrap_or(0)).expect("non-empty")
            }
        };
        let info = adapter.get_info();
        let missing = required_features() - adapter.features();
        if !missing.is_empty() {
            return Err(OitError::Device(format!(
                "adapter '{}' lacks {missing:?}, which oit-wgpu needs",
                info.name
            )));
        }
        let features = required_features() | (optional_features() & adapter.features());
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("oit"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| OitError::Device(format!("cannot open '{}': {e}", info.name)))?;
        let eight_samples = features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
            && adapter.get_texture_format_features(count_format(features)).flags.sample_count_supported(8);
        let mut gpu = Gpu::wrap(device, queue, info, features, limits);
        gpu.eight_samples = eight_samples;
        if features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
            gpu.multisampled =
                BLEND_FORMATS.iter().map(|&f| (f, adapter.get_texture_format_features(f).flags)).collect();
        }
        Ok(gpu)
    }

    /// A `Gpu` of an open device, its pipeline caches empty.
    fn wrap(
        device: wgpu::Device,
        queue: wgpu::Queue,
        info: wgpu::AdapterInfo,
        features: wgpu::Features,
        limits: wgpu::Limits,
    ) -> Gpu {
        Gpu {
            device,
            queue,
            info,
            features,
            limits,
            eight_samples: false,
            multisampled: Vec::new(),
            pipelines: Mutex::new(HashMap::new()),
            render_pipelines: Mutex::new(HashMap::new()),
            staging: Mutex::new(Vec::new()),
            queries: Mutex::new(Vec::new()),
            readbacks: Default::default(),
            layouts: Mutex::new(HashMap::new()),
        }
    }

    /// Whether `format` takes `samples` samples a pixel as a render target (always at one): the
    /// adapter's format features where oit opened the device, else WebGPU's guarantee (4 samples
    /// for the formats it lists as multisampled: not `Rgba32Float`).
    pub(crate) fn takes_samples(&self, format: wgpu::TextureFormat, samples: u32) -> bool {
        if samples <= 1 {
            return true;
        }
        match self.multisampled.iter().find(|(f, _)| *f == format) {
            Some((_, flags)) => flags.sample_count_supported(samples),
            None => samples == 4 && format != wgpu::TextureFormat::Rgba32Float,
        }
    }

    /// Wraps a device the caller opened (the embedded pass, `crate::embed`). It must have
    /// [`required_features`]; its limits are whatever the caller requested.
    /// (A device opened with wgpu's default limits, 8 storage buffers a stage, is refused here by
    /// name rather than by a validation panic at the first pipeline: see [`MIN_STORAGE_BUFFERS`].)
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue) -> Result<Gpu, OitError> {
        let info = device.adapter_info();
        let features = device.features();
        let missing = required_features() - features;
        if !missing.is_empty() {
            return Err(OitError::Device(format!(
                "the device on '{}' lacks {missing:?}: request `oit_wgpu::required_features()` when opening it",
                info.name
            )));
        }
        let limits = device.limits();
        if limits.max_storage_buffers_per_shader_stage < MIN_STORAGE_BUFFERS {
            return Err(OitError::Device(format!(
                "the device on '{}' was opened with {} storage buffers a shader stage, and oit's pipelines bind up to \
                 {MIN_STORAGE_BUFFERS} (group 0's state, up to 6 technique arrays, the loss counts and the opaque \
                 image; group 1's geometry): open it with `adapter.limits()` (or at least that many)",
                info.name, limits.max_storage_buffers_per_shader_stage
            )));
        }
        Ok(Gpu::wrap(device, queue, info, features, limits))
    }

    /// The render pipeline cached under `key` (a hash of everything it is built from), else the
    /// one `build` makes, built inside a validation error scope so a bad shader is an error.
    pub fn render_pipeline(
        &self,
        key: u64,
        what: &str,
        build: impl FnOnce() -> wgpu::RenderPipeline,
    ) -> Result<Arc<wgpu::RenderPipeline>, OitError> {
        let cache =
            || self.render_pipelines.lock().map_err(|_| OitError::Device("pipeline cache poisoned".into()));
        if let Some(p) = cache()?.get(&key) {
            return Ok(p.clone());
        }
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = build();
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(OitError::Device(format!("render pipeline '{what}' failed to build: {e}")));
        }
        let p = Arc::new(pipeline);
        cache()?.insert(key, p.clone());
        Ok(p)
    }

    /// Pipelines (compute and render) created on this device so far: every one is kept in the
    /// caches, so their sizes count them. A steady-state frame adds none (`tests/tests/prepared.rs`).
    pub fn pipelines_created(&self) -> u64 {
        let compute = self.pipelines.lock().map_or(0, |c| c.len());
        let render = self.render_pipelines.lock().map_or(0, |c| c.len());
        (compute + render) as u64
    }

    /// True when GPU timestamps can be taken and mean device time. Not on a CPU device: lavapipe
    /// has the feature, but its compute passes read as well under 1 % of their wall time (dp on
    /// the bunny at 512²: 1.2 ms of GPU time in a 318 ms frame), so `gpu_ms` there would mislead;
    /// wall time is the measure on such devices.
    pub fn has_timestamps(&self) -> bool {
        // off on CPU devices (lavapipe's timestamps cover under 1 % of a frame's wall time);
        // OIT_GPU_TIMESTAMPS turns them on or off anywhere
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
            && oit_gpu::timestamps_wanted(self.info.device_type == wgpu::DeviceType::Cpu)
    }

    /// A compute pipeline for `entry` of `COMMON_WGSL + source`, cached by source and entry.
    pub fn compute_pipeline(
        &self,
        source: &str,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
    ) -> Result<Arc<wgpu::ComputePipeline>, OitError> {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        source.hash(&mut h);
        entry.hash(&mut h);
        layouts.len().hash(&mut h);
        let key = h.finish();
        if let Some(p) =
            self.pipelines.lock().map_err(|_| OitError::Device("pipeline cache poisoned".into()))?.get(&key)
        {
            return Ok(p.clone());
        }
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(entry),
            source: wgpu::ShaderSource::Wgsl(format!("{COMMON_WGSL}\n{source}").into()),
        });
        let layout = self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry),
            bind_group_layouts: &layouts.iter().map(|l| Some(*l)).collect::<Vec<_>>(),
            immediate_size: 0,
        });
        let pipeline = self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(OitError::Device(format!("shader '{entry}' failed to build: {e}")));
        }
        let p = Arc::new(pipeline);
        self.pipelines
            .lock()
            .map_err(|_| OitError::Device("pipeline cache poisoned".into()))?
            .insert(key, p.clone());
        Ok(p)
    }

    /// The layout kept under `key`, else the one `make` creates (kept): a frame binds dozens of
    /// groups, and creating (and validating) their layout each time was host time per pass.
    pub fn layout(&self, key: usize, make: impl FnOnce() -> wgpu::BindGroupLayout) -> wgpu::BindGroupLayout {
        let mut layouts = self.layouts.lock().unwrap_or_else(|e| e.into_inner());
        layouts.entry(key).or_insert_with(make).clone()
    }

    /// Checks a storage buffer of `bytes` against the device's limits before allocating it.
    pub fn check_storage(&self, what: &str, bytes: u64) -> Result<(), OitError> {
        self.check_storage_hint(
            what,
            bytes,
            "use a smaller --size (storage grows with pixels), a smaller K, or the cpu backend",
        )
    }

    /// The budget of one frame's storage, all buffers together (issue 13.9): wgpu reports no
    /// device memory size, so 16 × `max_storage_buffer_binding_size` (lavapipe 2 GiB, the H200
    /// 32 GiB), and no more than half the host's available memory on a CPU device (lavapipe).
    pub fn memory_budget(&self) -> (String, u64) {
        let fixed = self.limits.max_storage_buffer_binding_size.saturating_mul(16);
        let name = format!("16 × max_storage_buffer_binding_size of '{}'", self.info.name);
        if self.info.device_type == wgpu::DeviceType::Cpu {
            let (host_name, host) = oit_core::plan::host_memory_budget();
            if host < fixed {
                return (host_name.to_string(), host);
            }
        }
        (name, fixed)
    }

    /// [`Gpu::check_storage`] for a buffer that grows with the scene, not the image (the compute
    /// rasterizer's triangles).
    pub fn check_scene_storage(&self, what: &str, bytes: u64) -> Result<(), OitError> {
        self.check_storage_hint(
            what,
            bytes,
            "use --raster hardware (its triangles take 16 bytes each, the compute rasterizer's 176), fewer triangles or instances, or the cpu backend",
        )
    }

    /// [`Gpu::check_storage`] with `hint` saying what helps.
    pub(crate) fn check_storage_hint(&self, what: &str, bytes: u64, hint: &str) -> Result<(), OitError> {
        let binding = self.limits.max_storage_buffer_binding_size;
        let buffer = self.limits.max_buffer_size;
        let (limit_name, limit) = if binding < buffer {
            ("max_storage_buffer_binding_size", binding)
        } else {
            ("max_buffer_size", buffer)
        };
        if bytes > limit {
            return Err(OitError::TooLarge {
                what: what.into(),
                needed: bytes,
                limit_name: format!("{limit_name} of '{}'", self.info.name),
                limit,
                hint: format!("{hint}; {:.0}% of this would fit", 100.0 * limit as f64 / bytes as f64),
            });
        }
        Ok(())
    }

    /// Reads a buffer back as u32 words (blocking).
    pub fn read_u32(&self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, OitError> {
        let mut words = self.read_u32s(&[buffer])?;
        Ok(words.pop().unwrap_or_default())
    }

    /// Reads several buffers back as u32 words with one copy submission and one wait (blocking),
    /// in the order given: a frame's last readback takes its counters, timestamps and image
    /// together. The staging buffer comes from a small per-device cache, so a steady-state
    /// readback creates no buffer.
    pub fn read_u32s(&self, buffers: &[&wgpu::Buffer]) -> Result<Vec<Vec<u32>>, OitError> {
        self.start_read(buffers).wait(self)
    }

    /// The first half of [`Gpu::read_u32s`]: the copies into a staging buffer submitted and its
    /// map asked for, nothing waited for. The host can record and submit more work (the next
    /// frame of a frame loop) before [`Reading::wait`] collects the words.
    pub fn start_read(&self, buffers: &[&wgpu::Buffer]) -> Reading {
        self.readbacks.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        // each buffer at an offset aligned for both the copy and the map
        let mut ranges = Vec::with_capacity(buffers.len());
        let mut total = 0u64;
        for b in buffers {
            ranges.push((total, b.size()));
            total += b.size().next_multiple_of(wgpu::MAP_ALIGNMENT);
        }
        let size = total.max(wgpu::MAP_ALIGNMENT).next_power_of_two();
        let staging = self.staging(size);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        for (b, &(offset, len)) in buffers.iter().zip(&ranges) {
            encoder.copy_buffer_to_buffer(b, 0, &staging, offset, len);
        }
        let index = self.queue.submit([encoder.finish()]);
        let mapped_len = total.max(wgpu::MAP_ALIGNMENT);
        // The words are read only once the map callback has said they are there (and has not
        // failed), not merely after a wait on the queue.
        let mapped = std::sync::Arc::new(std::sync::Mutex::new(None));
        let signal = mapped.clone();
        staging.slice(..mapped_len).map_async(wgpu::MapMode::Read, move |result| {
            if let Ok(mut slot) = signal.lock() {
                *slot = Some(result);
            }
        });
        Reading { staging, ranges, mapped_len, index, mapped }
    }

    /// Milliseconds between the two timestamps of pair `pair` in `words`, a resolved query set
    /// read back as u32 words (each timestamp two words, low first).
    pub fn pair_ms(&self, words: &[u32], pair: usize) -> f64 {
        let at = |q: usize| u64::from(words[2 * q + 1]) << 32 | u64::from(words[2 * q]);
        let ticks = at(2 * pair + 1).saturating_sub(at(2 * pair));
        ticks as f64 * f64::from(self.queue.get_timestamp_period()) * 1e-6
    }

    /// How many readbacks ([`Gpu::read_u32s`], each a wait for the GPU) this device has made: a
    /// frame's round trips are the difference across it.
    pub fn readbacks(&self) -> u64 {
        self.readbacks.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// A mappable staging buffer of `size` bytes from the cache, or new.
    fn staging(&self, size: u64) -> wgpu::Buffer {
        let found = self.staging.lock().ok().and_then(|mut free| {
            let i = free.iter().position(|b| b.size() == size)?;
            Some(free.swap_remove(i))
        });
        found.unwrap_or_else(|| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })
    }

    /// A timestamp query set of [`TIMESTAMP_QUERIES`] queries from the per-device cache, or
    /// new; [`Gpu::give_back_queries`] returns it.
    pub fn take_queries(&self) -> wgpu::QuerySet {
        let found = self.queries.lock().ok().and_then(|mut free| free.pop());
        found.unwrap_or_else(|| {
            self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: TIMESTAMP_QUERIES,
            })
        })
    }

    /// Returns a query set taken with [`Gpu::take_queries`].
    pub fn give_back_queries(&self, set: wgpu::QuerySet) {
        if let Ok(mut free) = self.queries.lock() {
            free.push(set);
        }
    }
}

/// A readback under way ([`Gpu::start_read`]): the copies are submitted and the staging buffer's
/// map asked for.
pub struct Reading {
    staging: wgpu::Buffer,
    /// Each buffer's offset in the staging buffer and its length, in bytes.
    ranges: Vec<(u64, u64)>,
    mapped_len: u64,
    index: wgpu::SubmissionIndex,
    mapped: std::sync::Arc<std::sync::Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>,
}

impl Reading {
    /// Waits for the copies (only their submission and those before it, not work submitted
    /// since) and returns each buffer's words, in the order [`Gpu::start_read`] was given them.
    pub fn wait(self, gpu: &Gpu) -> Result<Vec<Vec<u32>>, OitError> {
        loop {
            // this submission's index every time: without one, a wait is for the latest
            // submission, which may be a later frame's
            gpu.device
                .poll(wgpu::PollType::Wait { submission_index: Some(self.index.clone()), timeout: None })
                .map_err(|e| OitError::Device(format!("waiting for the GPU failed: {e}")))?;
            let done =
                self.mapped.lock().map_err(|_| OitError::Device("readback flag poisoned".into()))?.take();
            match done {
                Some(Ok(())) => break,
                Some(Err(e)) => return Err(OitError::Device(format!("reading a buffer back failed: {e}"))),
                None => std::thread::yield_now(),
            }
        }
        let slice = self.staging.slice(..self.mapped_len);
        let words = {
            let data =
                slice.get_mapped_range().map_err(|e| OitError::Device(format!("readback failed: {e}")))?;
            self.ranges
                .iter()
                .map(|&(offset, len)| {
                    bytemuck::cast_slice(&data[offset as usize..(offset + len) as usize]).to_vec()
                })
                .collect()
        };
        self.staging.unmap();
        if let Ok(mut free) = gpu.staging.lock() {
            free.push(self.staging);
        }
        Ok(words)
    }
}
