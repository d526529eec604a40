//! The device: the runtime-loaded Vulkan entry, the instance (with the Khronos validation layer
//! and a debug-utils messenger when `OIT_VULKAN_VALIDATION=1`), the physical device choice, one
//! logical device with one compute queue, buffers with their own memory, the SPIR-V modules and a
//! pipeline cache.
//!
//! Ownership is the destruction order: [`RawDevice`] owns the `VkDevice` and, in a field dropped
//! after it, the [`RawInstance`]; every buffer holds an `Arc<RawDevice>`, so the device outlives
//! them; [`Gpu`]'s `Drop` destroys the pipelines, layouts and modules it made (newest first)
//! before its `Arc<RawDevice>` goes.

use std::collections::HashMap;
use std::ffi::{CStr, c_void};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};

use ash::vk;
use oit_core::OitError;

/// The SPIR-V `build.rs` compiled from oit-wgpu's WGSL: (module, words as bytes, entry points).
const MODULES: &[(&str, &[u8], &[&str])] = include!(concat!(env!("OUT_DIR"), "/modules.rs"));

/// Every SPIR-V module `build.rs` compiled (after its rewrites: image atomics' results, kbuf's
/// interlock), by name, with its entry points: for checking them with outside tools (the
/// `spirv` test runs `spirv-val` over each).
pub fn spirv_modules() -> impl Iterator<Item = (&'static str, &'static [u8], &'static [&'static str])> {
    MODULES.iter().copied()
}

/// The extensions the papers' raw operations need, reported by `oit info`.
pub const PAPER_EXTENSIONS: [&CStr; 4] = [
    c"VK_EXT_shader_atomic_float",
    c"VK_KHR_shader_atomic_int64",
    c"VK_EXT_shader_image_atomic_int64",
    c"VK_EXT_fragment_shader_interlock",
];

/// The hardware raster's fragment counter: one float per pixel, added up by blending (exact to
/// 2^24 fragments per pixel and pass).
pub(crate) const COUNT_FORMAT: vk::Format = vk::Format::R32_SFLOAT;

/// What to install when there is no Vulkan at all.
const INSTALL: &str = "install a Vulkan loader and driver: `apt-get install libvulkan1 mesa-vulkan-drivers` \
                       (lavapipe, a CPU Vulkan device) or your GPU's driver";

/// Validation errors the messenger has seen, over every instance of the process.
static VALIDATION_ERRORS: AtomicU64 = AtomicU64::new(0);

/// Validation errors reported so far in this process (0 without `OIT_VULKAN_VALIDATION=1`).
pub fn validation_errors() -> u64 {
    VALIDATION_ERRORS.load(Relaxed)
}

/// True when `OIT_VULKAN_VALIDATION` is `1` (or `true`): the instance enables
/// `VK_LAYER_KHRONOS_validation` with synchronization validation, and every error it reports
/// fails the frame that caused it.
pub fn validation_requested() -> bool {
    std::env::var("OIT_VULKAN_VALIDATION").is_ok_and(|v| v == "1" || v.eq_ignore_ascii_case("true"))
}

/// Prints a validation message and counts the errors.
unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes a valid callback-data struct for the duration of the call, whose
    // message is null or a NUL-terminated string.
    let message = unsafe {
        data.as_ref()
            .and_then(|d| d.message_as_c_str())
            .map_or_else(|| "(no message)".into(), CStr::to_string_lossy)
    };
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        VALIDATION_ERRORS.fetch_add(1, Relaxed);
        eprintln!("vulkan validation error: {message}");
    } else {
        eprintln!("vulkan validation: {message}");
    }
    vk::FALSE
}

fn vk_error(what: &str) -> impl Fn(vk::Result) -> OitError + '_ {
    move |e| match e {
        vk::Result::ERROR_DEVICE_LOST => {
            OitError::Device(format!("{what}: the Vulkan device was lost (driver reset or crash)"))
        }
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
            OitError::Device(format!("{what}: out of memory ({e}); use a smaller --size or K"))
        }
        other => OitError::Device(format!("{what}: {other}")),
    }
}

/// The instance and, when validation is on, its messenger.
pub(crate) struct RawInstance {
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) instance: ash::Instance,
    /// Kept so that the loader library stays open while the instance lives.
    _entry: ash::Entry,
}

impl Drop for RawInstance {
    fn drop(&mut self) {
        // SAFETY: the messenger was made from this instance, which nothing else uses any more
        // (the device, made from it, was destroyed first: `RawDevice` drops before its field).
        unsafe {
            if let Some((utils, messenger)) = self.debug.take() {
                utils.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// The logical device, destroyed before its instance (a field, dropped after `drop`).
pub(crate) struct RawDevice {
    pub(crate) device: ash::Device,
    /// Destroyed after the device (fields drop after `Drop::drop`).
    _instance: RawInstance,
}

impl Drop for RawDevice {
    fn drop(&mut self) {
        // SAFETY: every object made from the device holds an `Arc<RawDevice>` and is gone when
        // this runs; waiting for idle first leaves no work in flight.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
        }
    }
}

/// What oit learned about the physical device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// `deviceName`.
    pub name: String,
    /// Discrete, integrated, CPU...
    pub device_type: vk::PhysicalDeviceType,
    /// `apiVersion`.
    pub api_version: u32,
    /// `driverVersion` (vendor encoding).
    pub driver_version: u32,
    /// `driverName` and `driverInfo` (VkPhysicalDeviceDriverProperties).
    pub driver: String,
    /// [`PAPER_EXTENSIONS`], each present or not.
    pub extensions: Vec<(String, bool)>,
    /// The core limits (`timestampPeriod`: nanoseconds per timestamp tick).
    pub limits: vk::PhysicalDeviceLimits,
    /// `timestampValidBits` of the queue family oit uses (0: no timestamps on that queue).
    pub timestamp_valid_bits: u32,
    /// The `logicOp` feature (adp's histogram by logic-op OR needs it).
    pub logic_op: bool,
    /// The `independentBlend` feature (plain's and wavg's two targets blend differently).
    pub independent_blend: bool,
    /// The float formats the blend captures blend into that the device can blend into (optimal
    /// tiling, `COLOR_ATTACHMENT_BLEND` and `SAMPLED_IMAGE`).
    pub blendable: Vec<vk::Format>,
    /// The sample counts each of [`DeviceInfo::blendable`] takes as a sampled colour attachment
    /// (optimal tiling, 2D; the blend captures' multisampled targets: `Gpu::takes_samples`).
    pub multisampled: Vec<(vk::Format, vk::SampleCountFlags)>,
    /// Why the hardware-raster path cannot run here (`None`: it can): it needs a graphics queue,
    /// `fragmentStoresAndAtomics` and a blendable `R32_SFLOAT` colour attachment (the counter).
    pub hardware_missing: Option<String>,
    /// `R32_UINT` storage images with atomics (`STORAGE_IMAGE_ATOMIC`, mandatory in Vulkan):
    /// `--atomic-storage image` for mdts and fabs.
    pub image_atomics_32: bool,
    /// `R64_UINT` storage images with atomics: `VK_EXT_shader_image_atomic_int64`'s
    /// `shaderImageInt64Atomics` and the format's `STORAGE_IMAGE_ATOMIC` (the H200 has them,
    /// lavapipe not): `--atomic-storage image` for mdts64. Enabled at device creation when present.
    pub image_atomics_64: bool,
    /// An ordered fragment-stage critical section per pixel: `VK_EXT_fragment_shader_interlock`'s
    /// `fragmentShaderPixelInterlock` (the H200 has it, lavapipe not), with the hardware raster
    /// path: `kbuf`. Enabled at device creation when present.
    pub interlock: bool,
    /// The largest device-local heap, bytes.
    pub device_heap: u64,
    /// Whether the validation layer is on.
    pub validation: bool,
}

impl DeviceInfo {
    /// `major.minor.patch` of a Vulkan version number.
    pub fn version(v: u32) -> String {
        format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
    }
}

/// A buffer and its own memory, freed on drop.
pub struct Buffer {
    raw: Arc<RawDevice>,
    pub(crate) buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    /// Bytes.
    pub size: u64,
    /// How it may be used.
    pub usage: vk::BufferUsageFlags,
    host: bool,
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: the buffer and its memory were made from `raw`, which is alive (the Arc); every
        // command that used them has completed (each frame waits for its last submission). The
        // buffer, the memory's user, goes first.
        unsafe {
            self.raw.device.destroy_buffer(self.buffer, None);
            self.raw.device.free_memory(self.memory, None);
        }
    }
}

impl Buffer {
    /// Copies `bytes` into a host-visible buffer at offset 0.
    pub fn write(&self, bytes: &[u8]) -> Result<(), OitError> {
        assert!(self.host && bytes.len() as u64 <= self.size, "write to a host buffer that fits");
        if bytes.is_empty() {
            return Ok(());
        }
        // SAFETY: host-visible, host-coherent memory bound to this buffer, mapped for its whole
        // size; no submitted command accesses it (writes happen before a submission or after the
        // last one completed); the copy stays inside the mapping.
        unsafe {
            let ptr = self
                .raw
                .device
                .map_memory(self.memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
                .map_err(vk_error("mapping a buffer"))?;
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr.cast::<u8>(), bytes.len());
            self.raw.device.unmap_memory(self.memory);
        }
        Ok(())
    }

    /// The words of a host-visible buffer.
    pub fn read_u32(&self) -> Result<Vec<u32>, OitError> {
        assert!(self.host, "read of a host buffer");
        let mut out = vec![0u32; (self.size / 4) as usize];
        // SAFETY: as in `write`; the last submission that wrote the buffer completed (its fence
        // was waited for) behind a barrier that made transfer writes visible to the host.
        unsafe {
            let ptr = self
                .raw
                .device
                .map_memory(self.memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
                .map_err(vk_error("mapping a buffer"))?;
            std::ptr::copy_nonoverlapping(ptr.cast::<u8>(), out.as_mut_ptr().cast::<u8>(), out.len() * 4);
            self.raw.device.unmap_memory(self.memory);
        }
        Ok(out)
    }
}

/// A 2D image with its own memory and a view of it: destroyed in reverse (view, image, memory).
pub struct GpuImage {
    raw: Arc<RawDevice>,
    pub(crate) image: vk::Image,
    memory: vk::DeviceMemory,
    pub(crate) view: vk::ImageView,
    /// Width and height, pixels.
    pub extent: (u32, u32),
    /// Array layers (1 but for the storage images of `--atomic-storage image`: one a slot).
    pub layers: u32,
    /// Its format.
    pub format: vk::Format,
    /// How it may be used.
    pub usage: vk::ImageUsageFlags,
    /// Samples a pixel (1 but for the multisampled targets).
    pub samples: u32,
}

impl Drop for GpuImage {
    fn drop(&mut self) {
        // SAFETY: all made from `raw` (alive: the Arc); every command that used them has
        // completed (each frame waits for its last submission); users go before what they use.
        unsafe {
            let d = &self.raw.device;
            d.destroy_image_view(self.view, None);
            d.destroy_image(self.image, None);
            d.free_memory(self.memory, None);
        }
    }
}

/// The usage of the storage images of `--atomic-storage image` ([`Gpu::storage_image`]): atomics,
/// and clears by transfer.
pub(crate) const STORAGE_IMAGE_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::STORAGE.as_raw() | vk::ImageUsageFlags::TRANSFER_DST.as_raw(),
);

/// Pipelines and what they are made of, destroyed newest first by [`Gpu`]'s drop.
#[derive(Default)]
struct Cache {
    modules: HashMap<&'static str, vk::ShaderModule>,
    set_layouts: HashMap<SetKind, vk::DescriptorSetLayout>,
    layouts: HashMap<Vec<SetKind>, vk::PipelineLayout>,
    /// By (module, entry points and state, set kinds).
    pipelines: HashMap<(&'static str, String, Vec<SetKind>), vk::Pipeline>,
    render_passes: HashMap<PassKey, vk::RenderPass>,
}

/// What a descriptor set of a pipeline holds.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum SetKind {
    /// Group 0 of every module: the frame uniform (binding 0), the resolve state (1), `n`
    /// technique buffers (2..), the loss accounting (15) and storage images at these bindings
    /// (8.., `--atomic-storage image`; none elsewhere).
    Frame(usize, Vec<u32>),
    /// Group 1 of a rasterizer: storage at 0, 1 and 3, its uniform at 2 (the compute
    /// rasterizer's triangles, work list and counter; the hardware raster's vertices, triangles
    /// and instances).
    Raster,
    /// Group 1 of the hardware raster: [`SetKind::Raster`]'s, and its textures at 4
    /// (raster_hardware.wgsl's `hw_tex`).
    HwRaster,
    /// Sampled images (read with `textureLoad`) at these bindings: a blend capture's targets.
    Images(Vec<u32>),
}

/// A render pass's attachments: colour formats, an optional depth format, and the layout the
/// colour attachments are left in (`TRANSFER_SRC_OPTIMAL` to be copied out, else
/// `SHADER_READ_ONLY_OPTIMAL` to be read by a kernel; a depth attachment is always left
/// readable).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PassKey {
    pub colors: Vec<vk::Format>,
    pub depth: Option<vk::Format>,
    pub final_layout: vk::ImageLayout,
    /// Samples a pixel of every attachment (and of the pipelines drawn in the pass).
    pub samples: u32,
}

/// `samples` (1, 4 or 8) as Vulkan's flag.
pub(crate) fn sample_count_flags(samples: u32) -> vk::SampleCountFlags {
    match samples {
        8 => vk::SampleCountFlags::TYPE_8,
        4 => vk::SampleCountFlags::TYPE_4,
        _ => vk::SampleCountFlags::TYPE_1,
    }
}

/// How a graphics pipeline writes one colour attachment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Blend {
    /// No blending: the fragment's value replaces the texel's (every channel).
    Replace,
    /// src + dst, every channel.
    Add,
    /// src + dst into the red channel only (a fragment counter).
    AddRed,
    /// Nothing written (a draw that writes depth only: the opaque depth's fill).
    Nothing,
    /// The over operator on premultiplied colour: rgb `src + (1 − αs)·dst`, α `(1 − αs)·dst`
    /// (the product of transmittances).
    Over,
    /// max(src, dst), every channel.
    Max,
    /// No blending: the pipeline's logic op (OR) combines src and dst (integer formats).
    LogicOr,
}

/// A graphics pipeline over oit's scene vertex stage (`hw_vs` of the module, which pulls its
/// vertices: no vertex buffers), no culling, viewport and scissor set per draw.
#[derive(Clone, Debug)]
pub(crate) struct GraphicsDesc<'a> {
    /// The `build.rs` module.
    pub module: &'a str,
    /// Its fragment entry point.
    pub fs: &'a str,
    pub sets: &'a [SetKind],
    pub pass: &'a PassKey,
    /// One per colour attachment of `pass`.
    pub blends: &'a [Blend],
    /// The depth test against `pass`'s depth attachment (where it has one).
    pub depth: DepthTest,
}

/// A graphics pipeline's depth test.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum DepthTest {
    /// None.
    Off,
    /// LESS_OR_EQUAL, writing (the blend captures' depth peel at one sample: of equal depths,
    /// the last drawn).
    Write,
    /// LESS, writing (the depth peel at several samples: of equal depths, the first drawn, the
    /// smallest primitive id).
    WriteLess,
    /// LESS_OR_EQUAL, read only (the capture over the opaque depth: `hw_fs_early`).
    ReadOnly,
    /// GREATER, read only: the fragments behind the opaque depth, which the capture's test drops
    /// (the count-only draw, `hw_fs_count`).
    Behind,
    /// ALWAYS, writing: the draw that fills the opaque depth (`depth_vs`/`depth_fs`).
    Fill,
}

/// A compute or graphics pipeline and its layout (owned by the [`Gpu`]'s cache).
#[derive(Clone, Debug)]
pub struct Pipeline {
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    /// The layout of each set, in set order.
    pub(crate) sets: Vec<vk::DescriptorSetLayout>,
}

/// A framebuffer of some images in a render pass, destroyed on drop (before the images, which
/// its owner keeps alive).
pub(crate) struct Framebuffer {
    raw: Arc<RawDevice>,
    pub(crate) framebuffer: vk::Framebuffer,
    pub(crate) extent: (u32, u32),
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: made from `raw`; every command that used it has completed.
        unsafe { self.raw.device.destroy_framebuffer(self.framebuffer, None) };
    }
}

/// An open device.
pub struct Gpu {
    cache: Mutex<Cache>,
    /// Recorders' parts left by finished frames, for the next (see `record::Parts`).
    recorders: Mutex<Vec<Parts>>,
    /// Submissions on the queue that no wait has collected, and the most there have been at once
    /// ([`Gpu::most_in_flight`]).
    in_flight: (std::sync::atomic::AtomicUsize, std::sync::atomic::AtomicUsize),
    /// Waits for a submission ([`Gpu::waits`]).
    waits: std::sync::atomic::AtomicU64,
    /// What the device is.
    pub info: DeviceInfo,
    pub(crate) queue: vk::Queue,
    pub(crate) family: u32,
    memory: vk::PhysicalDeviceMemoryProperties,
    pub(crate) raw: Arc<RawDevice>,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        if let Ok(kept) = self.recorders.get_mut() {
            kept.clear();
        }
        let Ok(cache) = self.cache.get_mut() else { return };
        // SAFETY: every handle was made from this device; the wait leaves none in use; each is
        // destroyed once, pipelines before the layouts and modules they were made from.
        unsafe {
            let d = &self.raw.device;
            let _ = d.device_wait_idle();
            for (_, p) in cache.pipelines.drain() {
                d.destroy_pipeline(p, None);
            }
            for (_, l) in cache.layouts.drain() {
                d.destroy_pipeline_layout(l, None);
            }
            for (_, p) in cache.render_passes.drain() {
                d.destroy_render_pass(p, None);
            }
            for (_, l) in cache.set_layouts.drain() {
                d.destroy_descriptor_set_layout(l, None);
            }
            for (_, m) in cache.modules.drain() {
                d.destroy_shader_module(m, None);
            }
        }
    }
}

fn c_name(bytes: Result<&CStr, std::ffi::FromBytesUntilNulError>) -> String {
    bytes.map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// A candidate physical device and why it can or cannot serve.
struct Candidate {
    physical: vk::PhysicalDevice,
    name: String,
    device_type: vk::PhysicalDeviceType,
    family: Option<u32>,
    /// `timestampValidBits` of `family` (0 without one).
    timestamp_valid_bits: u32,
    /// Whether `family` does graphics as well (the hardware-raster path).
    graphics: bool,
    missing: Vec<&'static str>,
}

impl Gpu {
    /// Opens a device: the first whose name contains `filter` (case-insensitive), else the one
    /// `OIT_ADAPTER` names, else the first discrete GPU, else an integrated one, else any.
    pub fn new(filter: Option<&str>) -> Result<Gpu, OitError> {
        // SAFETY: loading the loader library runs its initialisers; nothing else in the process
        // loads or unloads libvulkan concurrently in a way that could conflict.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| OitError::Device(format!("no Vulkan loader (libvulkan.so.1): {e}; {INSTALL}")))?;
        let validation = validation_requested();
        let layer = c"VK_LAYER_KHRONOS_validation";
        let mut layers = Vec::new();
        let mut extensions = Vec::new();
        if validation {
            // SAFETY: a plain query of the loaded entry.
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .map_err(vk_error("listing Vulkan layers"))?;
            if !available.iter().any(|l| l.layer_name_as_c_str() == Ok(layer)) {
                return Err(OitError::Device(
                    "OIT_VULKAN_VALIDATION=1 but VK_LAYER_KHRONOS_validation is not installed: \
                     `apt-get install vulkan-validationlayers`"
                        .into(),
                ));
            }
            layers.push(layer.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let app = vk::ApplicationInfo::default()
            .application_name(c"oit")
            .engine_name(c"oit-vulkan")
            .api_version(vk::API_VERSION_1_2);
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut create = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            create = create.push_next(&mut features);
        }
        // SAFETY: the create info and everything it points to live until the call returns.
        let instance = unsafe { entry.create_instance(&create, None) }
            .map_err(|e| OitError::Device(format!("cannot create a Vulkan 1.2 instance ({e}): {INSTALL}")))?;
        let mut raw_instance = RawInstance { debug: None, instance, _entry: entry };
        if validation {
            let utils = ash::ext::debug_utils::Instance::new(&raw_instance._entry, &raw_instance.instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(on_message));
            // SAFETY: the instance has VK_EXT_debug_utils enabled; the callback is a plain
            // function that touches only a static counter and stderr.
            let messenger = unsafe { utils.create_debug_utils_messenger(&info, None) }
                .map_err(vk_error("creating the validation messenger"))?;
            raw_instance.debug = Some((utils, messenger));
        }
        let instance = &raw_instance.instance;
        // SAFETY: a plain query of a live instance.
        let physicals =
            unsafe { instance.enumerate_physical_devices() }.map_err(vk_error("listing Vulkan devices"))?;
        if physicals.is_empty() {
            return Err(OitError::Device(format!("no Vulkan device found: {INSTALL}")));
        }
        let candidates: Vec<Candidate> = physicals.iter().map(|&p| Self::candidate(instance, p)).collect();
        let env = std::env::var("OIT_ADAPTER").ok();
        let filter = filter.map(str::to_owned).or(env).map(|f| f.to_lowercase());
        let usable = |c: &&Candidate| c.missing.is_empty() && c.family.is_some();
        let describe = || {
            candidates
                .iter()
                .map(|c| {
                    if c.missing.is_empty() {
                        c.name.clone()
                    } else {
                        format!("{} (lacks {})", c.name, c.missing.join(", "))
                    }
                })
                .collect::<Vec<_>>()
                .join("; ")
        };
        let chosen = match &filter {
            Some(f) => {
                candidates.iter().filter(usable).find(|c| c.name.to_lowercase().contains(f)).ok_or_else(
                    || {
                        OitError::Device(format!(
                            "no usable Vulkan device matches '{f}'; devices: {}",
                            describe()
                        ))
                    },
                )?
            }
            None => {
                let rank = |t: vk::PhysicalDeviceType| match t {
                    vk::PhysicalDeviceType::DISCRETE_GPU => 0,
                    vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
                    vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
                    vk::PhysicalDeviceType::CPU => 3,
                    _ => 4,
                };
                candidates.iter().filter(usable).min_by_key(|c| rank(c.device_type)).ok_or_else(|| {
                    OitError::Device(format!("no Vulkan device oit-vulkan can use; devices: {}", describe()))
                })?
            }
        };
        let physical = chosen.physical;
        let family = chosen.family.expect("usable has a family");
        let info = Self::info(instance, physical, validation, chosen.timestamp_valid_bits, chosen.graphics);
        let priorities = [1.0f32];
        let queues =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let core = vk::PhysicalDeviceFeatures::default()
            .shader_int64(true)
            .fragment_stores_and_atomics(info.hardware_missing.is_none())
            .logic_op(info.logic_op)
            .independent_blend(info.independent_blend);
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(true);
        let mut int64_images =
            vk::PhysicalDeviceShaderImageAtomicInt64FeaturesEXT::default().shader_image_int64_atomics(true);
        let mut interlock = vk::PhysicalDeviceFragmentShaderInterlockFeaturesEXT::default()
            .fragment_shader_pixel_interlock(true);
        let mut extensions: Vec<*const std::ffi::c_char> = Vec::new();
        if info.image_atomics_64 {
            extensions.push(ash::ext::shader_image_atomic_int64::NAME.as_ptr());
        }
        if info.interlock {
            extensions.push(ash::ext::fragment_shader_interlock::NAME.as_ptr());
        }
        let mut create = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&core)
            .enabled_extension_names(&extensions)
            .push_next(&mut v12);
        if info.image_atomics_64 {
            create = create.push_next(&mut int64_images);
        }
        if info.interlock {
            create = create.push_next(&mut interlock);
        }
        // SAFETY: the physical device belongs to the instance; the features asked for were
        // checked present (`candidate`); the create info outlives the call.
        let device = unsafe { instance.create_device(physical, &create, None) }
            .map_err(vk_error(&format!("opening '{}'", info.name)))?;
        // SAFETY: a plain query; the family was created with one queue.
        let (queue, memory) = unsafe {
            (device.get_device_queue(family, 0), instance.get_physical_device_memory_properties(physical))
        };
        let raw = Arc::new(RawDevice { device, _instance: raw_instance });
        Ok(Gpu {
            cache: Mutex::new(Cache::default()),
            recorders: Mutex::new(Vec::new()),
            in_flight: Default::default(),
            waits: Default::default(),
            info,
            queue,
            family,
            memory,
            raw,
        })
    }

    fn candidate(instance: &ash::Instance, physical: vk::PhysicalDevice) -> Candidate {
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12);
        // SAFETY: plain queries of a physical device of this instance; `features` chains a
        // struct that lives across the call.
        let (props, families) = unsafe {
            instance.get_physical_device_features2(physical, &mut features);
            (
                instance.get_physical_device_properties(physical),
                instance.get_physical_device_queue_family_properties(physical),
            )
        };
        let core = features.features;
        let mut missing = Vec::new();
        if props.api_version < vk::API_VERSION_1_2 {
            missing.push("Vulkan 1.2");
        }
        if core.shader_int64 == vk::FALSE {
            missing.push("shaderInt64");
        }
        if v12.shader_buffer_int64_atomics == vk::FALSE {
            missing.push("shaderBufferInt64Atomics");
        }
        let compute = |f: &vk::QueueFamilyProperties| f.queue_flags.contains(vk::QueueFlags::COMPUTE);
        let both = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
        let family = families
            .iter()
            .position(|f| f.queue_flags.contains(both))
            .or_else(|| families.iter().position(compute))
            .map(|i| i as u32);
        let timestamp_valid_bits = family.map_or(0, |f| families[f as usize].timestamp_valid_bits);
        let graphics =
            family.is_some_and(|f| families[f as usize].queue_flags.contains(vk::QueueFlags::GRAPHICS));
        Candidate {
            physical,
            name: c_name(props.device_name_as_c_str()),
            device_type: props.device_type,
            family,
            timestamp_valid_bits,
            graphics,
            missing,
        }
    }

    fn info(
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        validation: bool,
        timestamp_valid_bits: u32,
        graphics: bool,
    ) -> DeviceInfo {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        // SAFETY: plain queries of a physical device of this instance, the chained struct alive.
        let (features, extensions, memory, counter) = unsafe {
            instance.get_physical_device_properties2(physical, &mut props2);
            (
                instance.get_physical_device_features(physical),
                instance.enumerate_device_extension_properties(physical).unwrap_or_default(),
                instance.get_physical_device_memory_properties(physical),
                instance.get_physical_device_format_properties(physical, COUNT_FORMAT),
            )
        };
        let atomic_format = |format: vk::Format| {
            // SAFETY: a plain query of a physical device of this instance.
            let props = unsafe { instance.get_physical_device_format_properties(physical, format) };
            props.optimal_tiling_features.contains(
                vk::FormatFeatureFlags::STORAGE_IMAGE | vk::FormatFeatureFlags::STORAGE_IMAGE_ATOMIC,
            )
        };
        // an extension's feature struct, queried only where the device lists the extension
        fn extension_feature<T: vk::ExtendsPhysicalDeviceFeatures2>(
            instance: &ash::Instance,
            physical: vk::PhysicalDevice,
            extensions: &[vk::ExtensionProperties],
            name: &CStr,
            mut feature: T,
        ) -> Option<T> {
            extensions.iter().any(|e| e.extension_name_as_c_str() == Ok(name)).then(|| {
                let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut feature);
                // SAFETY: a plain query; the extension is present, the chained struct alive.
                unsafe { instance.get_physical_device_features2(physical, &mut features2) };
                feature
            })
        }
        let image_int64_feature = extension_feature(
            instance,
            physical,
            &extensions,
            ash::ext::shader_image_atomic_int64::NAME,
            vk::PhysicalDeviceShaderImageAtomicInt64FeaturesEXT::default(),
        )
        .is_some_and(|f| f.shader_image_int64_atomics == vk::TRUE);
        let interlock_feature = extension_feature(
            instance,
            physical,
            &extensions,
            ash::ext::fragment_shader_interlock::NAME,
            vk::PhysicalDeviceFragmentShaderInterlockFeaturesEXT::default(),
        )
        .is_some_and(|f| f.fragment_shader_pixel_interlock == vk::TRUE);
        let counter_needs = vk::FormatFeatureFlags::COLOR_ATTACHMENT
            | vk::FormatFeatureFlags::COLOR_ATTACHMENT_BLEND
            | vk::FormatFeatureFlags::TRANSFER_SRC;
        let hardware_missing = [
            (!graphics).then_some("a queue family with graphics and compute"),
            (features.fragment_stores_and_atomics == vk::FALSE).then_some("fragmentStoresAndAtomics"),
            (!counter.optimal_tiling_features.contains(counter_needs))
                .then_some("a blendable R32_SFLOAT colour attachment"),
        ]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>();
        let hardware_missing_none = hardware_missing.is_empty();
        let hardware_missing = (!hardware_missing.is_empty()).then(|| hardware_missing.join(", "));
        let blend_needs =
            vk::FormatFeatureFlags::COLOR_ATTACHMENT_BLEND | vk::FormatFeatureFlags::SAMPLED_IMAGE;
        let blendable: Vec<vk::Format> = [
            vk::Format::R32G32B32A32_SFLOAT,
            vk::Format::R32G32_SFLOAT,
            vk::Format::R32_SFLOAT,
            vk::Format::R16G16B16A16_SFLOAT,
            vk::Format::R8G8B8A8_UNORM,
        ]
        .into_iter()
        .filter(|&f| {
            // SAFETY: a plain query of a physical device of this instance.
            let props = unsafe { instance.get_physical_device_format_properties(physical, f) };
            props.optimal_tiling_features.contains(blend_needs)
        })
        .collect();
        let multisampled = blendable
            .iter()
            .map(|&f| {
                // SAFETY: a plain query of a physical device of this instance.
                let props = unsafe {
                    instance.get_physical_device_image_format_properties(
                        physical,
                        f,
                        vk::ImageType::TYPE_2D,
                        vk::ImageTiling::OPTIMAL,
                        vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
                        vk::ImageCreateFlags::empty(),
                    )
                };
                (f, props.map_or(vk::SampleCountFlags::TYPE_1, |p| p.sample_counts))
            })
            .collect();
        let props = props2.properties;
        let names: Vec<String> = extensions.iter().map(|e| c_name(e.extension_name_as_c_str())).collect();
        let device_heap = memory.memory_heaps[..memory.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .max()
            .unwrap_or(0);
        DeviceInfo {
            name: c_name(props.device_name_as_c_str()),
            device_type: props.device_type,
            api_version: props.api_version,
            driver_version: props.driver_version,
            driver: format!(
                "{} {}",
                c_name(driver.driver_name_as_c_str()),
                c_name(driver.driver_info_as_c_str())
            )
            .trim()
            .to_string(),
            extensions: PAPER_EXTENSIONS
                .iter()
                .map(|e| {
                    let e = e.to_string_lossy().into_owned();
                    let present = names.contains(&e);
                    (e, present)
                })
                .collect(),
            limits: props.limits,
            timestamp_valid_bits,
            logic_op: features.logic_op == vk::TRUE,
            independent_blend: features.independent_blend == vk::TRUE,
            hardware_missing,
            blendable,
            multisampled,
            image_atomics_32: atomic_format(vk::Format::R32_UINT),
            image_atomics_64: image_int64_feature && atomic_format(vk::Format::R64_UINT),
            interlock: interlock_feature && hardware_missing_none,
            device_heap,
            validation,
        }
    }

    /// Whether the device blends into `format` (one of [`DeviceInfo::blendable`]'s candidates).
    pub fn blendable(&self, format: vk::Format) -> bool {
        self.info.blendable.contains(&format)
    }

    /// Whether a blend capture's target of `format` takes `samples` samples a pixel (always at
    /// one): the hardware raster's own limits ([`Gpu::check_samples`]) and the format's.
    pub(crate) fn takes_samples(&self, format: vk::Format, samples: u32) -> bool {
        samples <= 1
            || (self.check_samples(samples).is_ok()
                && self
                    .info
                    .multisampled
                    .iter()
                    .any(|&(f, counts)| f == format && counts.contains(sample_count_flags(samples))))
    }

    /// Waits until the queue has nothing in flight: before a kept buffer that a frame in flight
    /// may still read is replaced (its drop destroys it).
    pub(crate) fn queue_idle(&self) -> Result<(), OitError> {
        // SAFETY: the queue is this device's; the wait has no other requirement.
        unsafe { self.raw.device.queue_wait_idle(self.queue) }.map_err(vk_error("waiting for the GPU"))
    }

    /// A finished recorder's parts, if one left any.
    pub(crate) fn take_recorder_parts(&self) -> Option<Parts> {
        self.recorders.lock().ok()?.pop()
    }

    /// Keeps a finished recorder's (reset) parts for the next frame (a few at most).
    pub(crate) fn give_recorder_parts(&self, parts: Parts) {
        if let Ok(mut kept) = self.recorders.lock()
            && kept.len() < 4
        {
            kept.push(parts);
        }
    }

    /// True on a CPU device (lavapipe).
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == vk::PhysicalDeviceType::CPU
    }

    /// True when the queue can write timestamps that mean device time: `timestampValidBits > 0`
    /// and `timestampPeriod > 0`, and not on a CPU device (lavapipe), as oit-wgpu's
    /// `Gpu::has_timestamps`: there the compute passes' timestamps cover a sliver of the frame's
    /// wall time, so `gpu_ms` would mislead. `OIT_GPU_TIMESTAMPS` turns them on or off on any
    /// device ([`oit_gpu::timestamps_wanted`]).
    pub fn has_timestamps(&self) -> bool {
        self.info.timestamp_valid_bits > 0
            && self.info.limits.timestamp_period > 0.0
            && oit_gpu::timestamps_wanted(self.is_cpu())
    }

    /// A buffer of `size` bytes with its own memory: device-local, or host-visible and coherent
    /// when `host` (staging, readback, uniforms written by the host).
    pub fn buffer(&self, size: u64, usage: vk::BufferUsageFlags, host: bool) -> Result<Buffer, OitError> {
        let d = &self.raw.device;
        let info = vk::BufferCreateInfo::default()
            .size(size.max(4))
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: a valid create info on a live device; the buffer is destroyed by `Buffer`'s drop
        // (or just below, when no memory can be found for it).
        let buffer = unsafe { d.create_buffer(&info, None) }.map_err(vk_error("creating a buffer"))?;
        // SAFETY: a plain query of the buffer just made.
        let needs = unsafe { d.get_buffer_memory_requirements(buffer) };
        let wanted = if host {
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT
        } else {
            vk::MemoryPropertyFlags::DEVICE_LOCAL
        };
        let types = &self.memory.memory_types[..self.memory.memory_type_count as usize];
        let fits = |i: usize, flags: vk::MemoryPropertyFlags| {
            needs.memory_type_bits & (1 << i) != 0 && types[i].property_flags.contains(flags)
        };
        // host buffers are read back (images, counters) as well as written: cached memory where
        // the device has it (a read of uncached, write-combined memory runs at a small fraction
        // of memory speed: the H200 took 15–20 ms to read a 1024² frame's image and losses back)
        let cached =
            host.then(|| (0..types.len()).find(|&i| fits(i, wanted | vk::MemoryPropertyFlags::HOST_CACHED)));
        let Some(index) =
            cached.flatten().or_else(|| (0..types.len()).find(|&i| fits(i, wanted))).or_else(|| {
                (!host).then(|| (0..types.len()).find(|&i| needs.memory_type_bits & (1 << i) != 0)).flatten()
            })
        else {
            // SAFETY: the buffer was made above and never used.
            unsafe { d.destroy_buffer(buffer, None) };
            return Err(OitError::Device(format!("'{}' has no memory type for a buffer", self.info.name)));
        };
        let alloc =
            vk::MemoryAllocateInfo::default().allocation_size(needs.size).memory_type_index(index as u32);
        // SAFETY: the allocation info names a memory type the buffer accepts; the memory is bound
        // once, at offset 0, which satisfies any alignment.
        let memory = unsafe {
            match d.allocate_memory(&alloc, None) {
                Ok(m) => m,
                Err(e) => {
                    d.destroy_buffer(buffer, None);
                    return Err(vk_error(&format!("allocating {} bytes", needs.size))(e));
                }
            }
        };
        // SAFETY: both made above from this device; the memory is large enough (its requirements).
        if let Err(e) = unsafe { d.bind_buffer_memory(buffer, memory, 0) } {
            // SAFETY: neither is in use.
            unsafe {
                d.destroy_buffer(buffer, None);
                d.free_memory(memory, None);
            }
            return Err(vk_error("binding buffer memory")(e));
        }
        Ok(Buffer { raw: self.raw.clone(), buffer, memory, size, usage, host })
    }

    /// A device-local `width × height` image of `format` and `usage`, with a view.
    pub(crate) fn image(
        &self,
        (width, height): (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<GpuImage, OitError> {
        self.check_target_size((width, height))?;
        self.image_layers((width, height), 1, format, usage, 1)
    }

    /// A render target's size against `maxImageDimension2D` and the framebuffer limits.
    fn check_target_size(&self, (width, height): (u32, u32)) -> Result<(), OitError> {
        let limit = self.info.limits.max_image_dimension2_d;
        let max_fb = self.info.limits.max_framebuffer_width.min(self.info.limits.max_framebuffer_height);
        let side = width.max(height);
        if side > limit.min(max_fb) {
            return Err(OitError::TooLarge {
                what: format!("a {width}×{height} render target"),
                needed: u64::from(side),
                limit_name: format!("maxImageDimension2D / maxFramebufferWidth of '{}'", self.info.name),
                limit: u64::from(limit.min(max_fb)),
                hint: "use --memory to render in tiles, a smaller --size, or --raster compute".into(),
            });
        }
        Ok(())
    }

    /// [`Gpu::image`] of `samples` samples a pixel (the multisampled count target).
    pub(crate) fn image_sampled(
        &self,
        size: (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: u32,
    ) -> Result<GpuImage, OitError> {
        if samples <= 1 {
            return self.image(size, format, usage);
        }
        self.check_samples(samples)?;
        self.check_target_size(size)?;
        self.image_layers(size, 1, format, usage, samples)
    }

    /// Whether the hardware raster path can draw `samples` samples a pixel (`Ok` at one): the
    /// count target's samples as a colour attachment and as a sampled image, and the standard
    /// sample locations (oit-core's positions). Refused by name otherwise.
    pub(crate) fn check_samples(&self, samples: u32) -> Result<(), OitError> {
        if samples <= 1 {
            return Ok(());
        }
        let l = &self.info.limits;
        let flag = sample_count_flags(samples);
        let missing = if !l.framebuffer_color_sample_counts.contains(flag) {
            Some("framebufferColorSampleCounts")
        } else if !l.sampled_image_color_sample_counts.contains(flag) {
            Some("sampledImageColorSampleCounts")
        } else if l.standard_sample_locations == vk::FALSE {
            Some("standardSampleLocations")
        } else {
            None
        };
        match missing {
            None => Ok(()),
            Some(what) => Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!(
                    "the hardware raster path at --samples {samples} on '{}': its {what} does not \
                     allow it; use --raster compute",
                    self.info.name
                ),
            }),
        }
    }

    /// A device-local `width × height × layers` storage image of `format` for atomics (a 2D
    /// array, cleared by transfers), with its view; the size checked against
    /// `maxImageDimension2D` and the layers against `maxImageArrayLayers` first.
    pub(crate) fn storage_image(
        &self,
        what: &str,
        (width, height): (u32, u32),
        layers: u32,
        format: vk::Format,
    ) -> Result<GpuImage, OitError> {
        let l = &self.info.limits;
        let side = width.max(height);
        if side > l.max_image_dimension2_d {
            return Err(OitError::TooLarge {
                what: format!("{what}: a {width}×{height} storage image"),
                needed: u64::from(side),
                limit_name: format!("maxImageDimension2D of '{}'", self.info.name),
                limit: u64::from(l.max_image_dimension2_d),
                hint: "use --memory to render in tiles, a smaller --size, or --atomic-storage buffer".into(),
            });
        }
        if layers > l.max_image_array_layers {
            return Err(OitError::TooLarge {
                what: format!("{what}: {layers} slots a pixel, one image layer each"),
                needed: u64::from(layers),
                limit_name: format!("maxImageArrayLayers of '{}'", self.info.name),
                limit: u64::from(l.max_image_array_layers),
                hint: "use a smaller K or --atomic-storage buffer".into(),
            });
        }
        self.image_layers((width, height), layers.max(1), format, STORAGE_IMAGE_USAGE, 1)
    }

    /// The image of [`Gpu::image`] and [`Gpu::storage_image`]: `layers` of 2D, viewed as a 2D
    /// array where there are several or it is a storage image.
    fn image_layers(
        &self,
        (width, height): (u32, u32),
        layers: u32,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: u32,
    ) -> Result<GpuImage, OitError> {
        let d = &self.raw.device;
        let extent = vk::Extent3D { width: width.max(1), height: height.max(1), depth: 1 };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(extent)
            .mip_levels(1)
            .array_layers(layers)
            .samples(sample_count_flags(samples))
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: a valid create info on a live device (the size checked above); the image is
        // owned by the `GpuImage` below, or destroyed here when what follows fails.
        let image = unsafe { d.create_image(&info, None) }.map_err(vk_error("creating an image"))?;
        // SAFETY: a plain query of the image just made.
        let needs = unsafe { d.get_image_memory_requirements(image) };
        let types = &self.memory.memory_types[..self.memory.memory_type_count as usize];
        let index = (0..types.len())
            .find(|&i| {
                needs.memory_type_bits & (1 << i) != 0
                    && types[i].property_flags.contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
            })
            .or_else(|| (0..types.len()).find(|&i| needs.memory_type_bits & (1 << i) != 0));
        let Some(index) = index else {
            // SAFETY: made above, never used.
            unsafe { d.destroy_image(image, None) };
            return Err(OitError::Device(format!("'{}' has no memory type for an image", self.info.name)));
        };
        let alloc =
            vk::MemoryAllocateInfo::default().allocation_size(needs.size).memory_type_index(index as u32);
        // SAFETY: a memory type the image accepts, bound once at offset 0; on failure what was
        // made is destroyed before returning.
        let memory = unsafe {
            let memory = match d.allocate_memory(&alloc, None) {
                Ok(m) => m,
                Err(e) => {
                    d.destroy_image(image, None);
                    return Err(vk_error(&format!("allocating {} bytes", needs.size))(e));
                }
            };
            if let Err(e) = d.bind_image_memory(image, memory, 0) {
                d.destroy_image(image, None);
                d.free_memory(memory, None);
                return Err(vk_error("binding image memory")(e));
            }
            memory
        };
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(aspect(format))
            .level_count(1)
            .layer_count(layers);
        let array = layers > 1 || usage.contains(vk::ImageUsageFlags::STORAGE);
        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(if array { vk::ImageViewType::TYPE_2D_ARRAY } else { vk::ImageViewType::TYPE_2D })
            .format(format)
            .subresource_range(range);
        // SAFETY: the image is alive and has the format; on failure it is freed.
        let view = match unsafe { d.create_image_view(&view_info, None) } {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: made above, never used.
                unsafe {
                    d.destroy_image(image, None);
                    d.free_memory(memory, None);
                }
                return Err(vk_error("creating an image view")(e));
            }
        };
        Ok(GpuImage {
            raw: self.raw.clone(),
            image,
            memory,
            view,
            extent: (extent.width, extent.height),
            layers,
            format,
            usage,
            samples: samples.max(1),
        })
    }

    /// A framebuffer of `images` (all of one size, in `pass`'s attachment order) in `pass`.
    pub(crate) fn framebuffer(
        &self,
        pass: vk::RenderPass,
        images: &[&GpuImage],
    ) -> Result<Framebuffer, OitError> {
        let extent = images.first().map_or((1, 1), |i| i.extent);
        debug_assert!(images.iter().all(|i| i.extent == extent), "one size");
        let views: Vec<vk::ImageView> = images.iter().map(|i| i.view).collect();
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass)
            .attachments(&views)
            .width(extent.0)
            .height(extent.1)
            .layers(1);
        // SAFETY: the views are of images compatible with the pass's attachments (their formats,
        // one sample, in order: the caller's contract); the owner keeps the images alive longer.
        let framebuffer = unsafe { self.raw.device.create_framebuffer(&info, None) }
            .map_err(vk_error("creating a framebuffer"))?;
        Ok(Framebuffer { raw: self.raw.clone(), framebuffer, extent })
    }

    /// The most submissions this device has had on its queue at once, none yet waited for: 1 where
    /// every frame is waited for before the next is recorded, [`crate::FRAMES_IN_FLIGHT`] in a
    /// frame loop that keeps frames in flight. For tests and diagnostics.
    pub fn most_in_flight(&self) -> usize {
        self.in_flight.1.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// How many times the host has waited for a submission on this device (a frame's end, a
    /// readback in mid-frame, an upload): a steady frame whose technique reads nothing back in
    /// mid-frame waits once. For tests and diagnostics.
    pub fn waits(&self) -> u64 {
        self.waits.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// A recorder submitted (`up`) or its submission was waited for.
    pub(crate) fn count_in_flight(&self, up: bool) {
        use std::sync::atomic::Ordering::Relaxed;
        if up {
            let now = self.in_flight.0.fetch_add(1, Relaxed) + 1;
            self.in_flight.1.fetch_max(now, Relaxed);
        } else {
            self.in_flight.0.fetch_sub(1, Relaxed);
            self.waits.fetch_add(1, Relaxed);
        }
    }

    /// Pipelines (compute and graphics) created on this device so far (each is cached until the device drops,
    /// so the cache's size counts them): a steady-state frame adds none.
    pub fn pipelines_created(&self) -> u64 {
        self.cache.lock().map_or(0, |c| c.pipelines.len() as u64)
    }

    /// The compute pipeline of `entry` in `module` (a module of `build.rs`) whose group 0 has `n`
    /// technique buffers and storage images at `images`, and group 1 is the rasterizer's; made
    /// once, then cached.
    pub fn pipeline(
        &self,
        module: &'static str,
        entry: &str,
        n: usize,
        images: &[u32],
    ) -> Result<Pipeline, OitError> {
        self.compute(module, entry, &[SetKind::Frame(n, images.to_vec()), SetKind::Raster])
    }

    /// The compute pipeline of `entry` in `module` with descriptor sets `sets`; made once, then
    /// cached.
    pub(crate) fn compute(&self, module: &str, entry: &str, sets: &[SetKind]) -> Result<Pipeline, OitError> {
        let mut guard = self.cache.lock().map_err(|_| OitError::Device("pipeline cache poisoned".into()))?;
        let cache = &mut *guard;
        let (set_layouts, layout) = self.layouts(cache, sets)?;
        let (name, shader) = self.module(cache, module, &[entry])?;
        let key = (name, entry.to_string(), sets.to_vec());
        if let Some(&pipeline) = cache.pipelines.get(&key) {
            return Ok(Pipeline { pipeline, layout, sets: set_layouts });
        }
        let entry_c = std::ffi::CString::new(entry).map_err(|_| OitError::Device("bad entry name".into()))?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(shader)
            .name(&entry_c);
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
        // SAFETY: the module and layout are alive; the layout declares every binding the entry
        // point uses (the caller names the sets its module declares for it).
        let pipeline =
            unsafe { self.raw.device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) }
                .map_err(|(_, e)| vk_error(&format!("building '{module}::{entry}'"))(e))?[0];
        cache.pipelines.insert(key, pipeline);
        Ok(Pipeline { pipeline, layout, sets: set_layouts })
    }

    /// The hardware raster's pipeline for `module`'s capture (`build.rs`'s `<module>_hw`:
    /// `hw_vs`, then `hw_fs`, which calls the technique's `capture`), whose group 0 has `n`
    /// technique buffers and storage images at `images`: one colour attachment, the fragment
    /// counter (`R32_SFLOAT`), added to by blending.
    pub fn render_pipeline(
        &self,
        module: &'static str,
        n: usize,
        images: &[u32],
        samples: u32,
    ) -> Result<Pipeline, OitError> {
        self.graphics(&GraphicsDesc {
            module: &format!("{module}_hw"),
            // a multisampled pass's fragments carry the samples they cover (docs/msaa.md)
            fs: if samples > 1 { "hw_fs_masked" } else { "hw_fs" },
            sets: &[SetKind::Frame(n, images.to_vec()), SetKind::HwRaster],
            pass: &count_pass_key(samples),
            blends: &[Blend::AddRed],
            depth: DepthTest::Off,
        })
    }

    /// [`Gpu::render_pipeline`]'s draw `fs` over the opaque depth, at one sample, in
    /// `early_pass_key`'s pass (`core/raster_hardware_early.wgsl`): `depth_fs` fills the depth
    /// attachment (its vertex stage `depth_vs`, no colour), `hw_fs_count` counts what lies
    /// behind (GREATER; by atomic adds, no colour),
    /// `hw_fs_early` captures behind the LESS_OR_EQUAL test (no colour; `hw_fs_early_counted`
    /// the same, counting into the count image).
    pub fn early_pipeline(
        &self,
        module: &'static str,
        n: usize,
        images: &[u32],
        fs: &str,
    ) -> Result<Pipeline, OitError> {
        let (blend, depth) = match fs {
            "depth_fs" => (Blend::Nothing, DepthTest::Fill),
            // the capture behind the test: no colour (its count is the count-only draw's, or
            // not read), or counted where a pass's count is read without one
            "hw_fs_early" => (Blend::Nothing, DepthTest::ReadOnly),
            "hw_fs_early_counted" => (Blend::AddRed, DepthTest::ReadOnly),
            // counts by atomic adds (`oit_gpu::opaque_drawn_offset`'s counter), not into the
            // count image, the fragments the capture's test drops
            "hw_fs_count" => (Blend::Nothing, DepthTest::Behind),
            _ => (Blend::AddRed, DepthTest::Off),
        };
        self.graphics(&GraphicsDesc {
            module: &format!("{module}_hw"),
            fs,
            sets: &[SetKind::Frame(n, images.to_vec()), SetKind::HwRaster],
            pass: &early_pass_key(),
            blends: &[blend],
            depth,
        })
    }

    /// A graphics pipeline as `desc` says (see [`GraphicsDesc`]); made once, then cached.
    pub(crate) fn graphics(&self, desc: &GraphicsDesc<'_>) -> Result<Pipeline, OitError> {
        if let Some(missing) = &self.info.hardware_missing {
            return Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!("the hardware raster path on '{}' (it lacks {missing})", self.info.name),
            });
        }
        let logic_or = desc.blends.contains(&Blend::LogicOr);
        if logic_or && !self.info.logic_op {
            return Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!("logic-op OR on '{}': the device lacks the logicOp feature", self.info.name),
            });
        }
        if desc.blends.windows(2).any(|w| w[0] != w[1]) && !self.info.independent_blend {
            return Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!(
                    "targets blended differently in one pass on '{}': the device lacks the independentBlend feature; use --hardware-capture atomics",
                    self.info.name
                ),
            });
        }
        let render_pass = self.render_pass(desc.pass)?;
        let mut guard = self.cache.lock().map_err(|_| OitError::Device("pipeline cache poisoned".into()))?;
        let cache = &mut *guard;
        let (set_layouts, layout) = self.layouts(cache, desc.sets)?;
        let vs = if desc.fs == "depth_fs" { c"depth_vs" } else { c"hw_vs" };
        let vs_name = vs.to_str().map_err(|_| OitError::Device("bad entry name".into()))?;
        let (name, shader) = self.module(cache, desc.module, &[vs_name, desc.fs])?;
        let state = format!("{vs_name}+{} {:?} {:?} {:?}", desc.fs, desc.pass, desc.blends, desc.depth);
        let key = (name, state, desc.sets.to_vec());
        if let Some(&pipeline) = cache.pipelines.get(&key) {
            return Ok(Pipeline { pipeline, layout, sets: set_layouts });
        }
        let fs = std::ffi::CString::new(desc.fs).map_err(|_| OitError::Device("bad entry name".into()))?;
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(shader)
                .name(vs),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(shader)
                .name(&fs),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster_state = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(sample_count_flags(desc.pass.samples));
        let attachments: Vec<vk::PipelineColorBlendAttachmentState> =
            desc.blends.iter().map(|&b| blend_state(b)).collect();
        let mut blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        if logic_or {
            blend = blend.logic_op_enable(true).logic_op(vk::LogicOp::OR);
        }
        let (test, write, compare) = match desc.depth {
            DepthTest::Off => (false, false, vk::CompareOp::ALWAYS),
            DepthTest::Write => (true, true, vk::CompareOp::LESS_OR_EQUAL),
            DepthTest::WriteLess => (true, true, vk::CompareOp::LESS),
            DepthTest::ReadOnly => (true, false, vk::CompareOp::LESS_OR_EQUAL),
            DepthTest::Behind => (true, false, vk::CompareOp::GREATER),
            DepthTest::Fill => (true, true, vk::CompareOp::ALWAYS),
        };
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(test)
            .depth_write_enable(write)
            .depth_compare_op(compare);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let mut info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster_state)
            .multisample_state(&multisample)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .render_pass(render_pass)
            .subpass(0);
        if desc.pass.depth.is_some() {
            info = info.depth_stencil_state(&depth);
        }
        // SAFETY: the module, layout and render pass are alive (cached until the Gpu drops); the
        // layout declares every binding the entry points use (the caller's sets); the blend state
        // has one entry per colour attachment of the render pass's one subpass; logic ops only
        // where the device has the feature (enabled at device creation).
        let pipeline =
            unsafe { self.raw.device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
                .map_err(|(_, e)| vk_error(&format!("building '{}::{}'", desc.module, desc.fs))(e))?[0];
        cache.pipelines.insert(key, pipeline);
        Ok(Pipeline { pipeline, layout, sets: set_layouts })
    }

    /// The render pass of `key` (see [`PassKey`]): every attachment cleared at the start and
    /// stored; its dependencies order it after and before everything else, as the recorder's
    /// barriers do between commands. Made once, then cached.
    pub(crate) fn render_pass(&self, key: &PassKey) -> Result<vk::RenderPass, OitError> {
        let mut cache = self.cache.lock().map_err(|_| OitError::Device("pipeline cache poisoned".into()))?;
        if let Some(&p) = cache.render_passes.get(key) {
            return Ok(p);
        }
        let attachment = |format: vk::Format, final_layout: vk::ImageLayout| {
            vk::AttachmentDescription::default()
                .format(format)
                .samples(sample_count_flags(key.samples))
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .final_layout(final_layout)
        };
        let mut attachments: Vec<vk::AttachmentDescription> =
            key.colors.iter().map(|&f| attachment(f, key.final_layout)).collect();
        let color: Vec<vk::AttachmentReference> = (0..key.colors.len() as u32)
            .map(|i| {
                vk::AttachmentReference::default()
                    .attachment(i)
                    .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            })
            .collect();
        let depth_ref = key.depth.map(|f| {
            attachments.push(attachment(f, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL));
            vk::AttachmentReference::default()
                .attachment(key.colors.len() as u32)
                .layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
        });
        let mut subpass = vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&color);
        if let Some(d) = depth_ref.as_ref() {
            subpass = subpass.depth_stencil_attachment(d);
        }
        let subpasses = [subpass];
        let everything = vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE;
        let dependencies = [
            vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(vk::PipelineStageFlags::ALL_COMMANDS)
                .dst_stage_mask(vk::PipelineStageFlags::ALL_GRAPHICS)
                .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
                .dst_access_mask(everything),
            vk::SubpassDependency::default()
                .src_subpass(0)
                .dst_subpass(vk::SUBPASS_EXTERNAL)
                .src_stage_mask(vk::PipelineStageFlags::ALL_GRAPHICS)
                .dst_stage_mask(vk::PipelineStageFlags::ALL_COMMANDS)
                .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
                .dst_access_mask(everything),
        ];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        // SAFETY: a valid create info on a live device; cached and destroyed by `Gpu`'s drop.
        let pass = unsafe { self.raw.device.create_render_pass(&info, None) }
            .map_err(vk_error("creating a render pass"))?;
        cache.render_passes.insert(key.clone(), pass);
        Ok(pass)
    }

    /// The set layouts of `sets` and the pipeline layout of them; made once each, then cached.
    fn layouts(
        &self,
        cache: &mut Cache,
        sets: &[SetKind],
    ) -> Result<(Vec<vk::DescriptorSetLayout>, vk::PipelineLayout), OitError> {
        let mut set_layouts = Vec::with_capacity(sets.len());
        for kind in sets {
            let l = match cache.set_layouts.get(kind) {
                Some(&l) => l,
                None => {
                    let bindings: Vec<(u32, vk::DescriptorType)> = match kind {
                        SetKind::Frame(n, images) => std::iter::once((0, vk::DescriptorType::UNIFORM_BUFFER))
                            .chain(
                                (1..=*n as u32 + 1)
                                    .chain([
                                        oit_gpu::ACCT_BINDING,
                                        oit_gpu::OPAQUE_KEYS_BINDING,
                                        oit_gpu::OPAQUE_RGB_BINDING,
                                    ])
                                    .map(|b| (b, vk::DescriptorType::STORAGE_BUFFER)),
                            )
                            .chain(images.iter().map(|&b| (b, vk::DescriptorType::STORAGE_IMAGE)))
                            .collect(),
                        SetKind::Raster => vec![
                            (0, vk::DescriptorType::STORAGE_BUFFER),
                            (1, vk::DescriptorType::STORAGE_BUFFER),
                            (2, vk::DescriptorType::UNIFORM_BUFFER),
                            (3, vk::DescriptorType::STORAGE_BUFFER),
                        ],
                        SetKind::HwRaster => vec![
                            (0, vk::DescriptorType::STORAGE_BUFFER),
                            (1, vk::DescriptorType::STORAGE_BUFFER),
                            (2, vk::DescriptorType::UNIFORM_BUFFER),
                            (3, vk::DescriptorType::STORAGE_BUFFER),
                            (4, vk::DescriptorType::STORAGE_BUFFER),
                        ],
                        SetKind::Images(at) => {
                            at.iter().map(|&b| (b, vk::DescriptorType::SAMPLED_IMAGE)).collect()
                        }
                    };
                    let l = self.set_layout(&bindings)?;
                    cache.set_layouts.insert(kind.clone(), l);
                    l
                }
            };
            set_layouts.push(l);
        }
        let layout = match cache.layouts.get(sets) {
            Some(&l) => l,
            None => {
                let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
                // SAFETY: the set layouts are alive (cached until the Gpu drops).
                let l = unsafe { self.raw.device.create_pipeline_layout(&info, None) }
                    .map_err(vk_error("creating a pipeline layout"))?;
                cache.layouts.insert(sets.to_vec(), l);
                l
            }
        };
        Ok((set_layouts, layout))
    }

    /// The shader module `name` of `build.rs` (its static name, and the module made once), checked
    /// to have `entries`.
    fn module(
        &self,
        cache: &mut Cache,
        name: &str,
        entries: &[&str],
    ) -> Result<(&'static str, vk::ShaderModule), OitError> {
        let (module, bytes, has) = MODULES
            .iter()
            .find(|(n, _, _)| *n == name)
            .ok_or_else(|| OitError::Device(format!("no SPIR-V module '{name}' was built")))?;
        if let Some(missing) = entries.iter().find(|e| !has.contains(e)) {
            return Err(OitError::Device(format!("module '{name}' has no entry point '{missing}'")));
        }
        if let Some(&m) = cache.modules.get(module) {
            return Ok((module, m));
        }
        let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes))
            .map_err(|e| OitError::Device(format!("module '{name}': bad SPIR-V: {e}")))?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: the words are naga's output for a validated module.
        let m = unsafe { self.raw.device.create_shader_module(&info, None) }
            .map_err(vk_error("creating a shader module"))?;
        cache.modules.insert(module, m);
        Ok((module, m))
    }

    fn set_layout(
        &self,
        bindings: &[(u32, vk::DescriptorType)],
    ) -> Result<vk::DescriptorSetLayout, OitError> {
        let bindings: Vec<_> = bindings
            .iter()
            .map(|&(b, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    // the same layouts serve the compute kernels and the hardware raster's
                    // vertex and fragment stages
                    .stage_flags(
                        vk::ShaderStageFlags::COMPUTE
                            | vk::ShaderStageFlags::VERTEX
                            | vk::ShaderStageFlags::FRAGMENT,
                    )
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: a valid create info on a live device; cached and destroyed by `Gpu`'s drop.
        unsafe { self.raw.device.create_descriptor_set_layout(&info, None) }
            .map_err(vk_error("creating a descriptor set layout"))
    }

    /// Checks a storage buffer of `bytes` against `maxStorageBufferRange` before allocating it.
    pub fn check_storage(&self, what: &str, bytes: u64) -> Result<(), OitError> {
        self.check_storage_hint(
            what,
            bytes,
            "use a smaller --size (storage grows with pixels), a smaller K, or the cpu backend",
        )
    }

    /// [`Gpu::check_storage`] with `hint` saying what helps.
    pub fn check_storage_hint(&self, what: &str, bytes: u64, hint: &str) -> Result<(), OitError> {
        let limit = u64::from(self.info.limits.max_storage_buffer_range);
        if bytes > limit {
            return Err(OitError::TooLarge {
                what: what.into(),
                needed: bytes,
                limit_name: format!("maxStorageBufferRange of '{}'", self.info.name),
                limit,
                hint: format!("{hint}; {:.0}% of this would fit", 100.0 * limit as f64 / bytes as f64),
            });
        }
        Ok(())
    }

    /// The budget of one frame's storage, all buffers together: the largest device-local heap,
    /// and no more than half the host's available memory on a CPU device (lavapipe).
    pub fn memory_budget(&self) -> (String, u64) {
        let heap = (format!("the device-local memory heap of '{}'", self.info.name), self.info.device_heap);
        if self.is_cpu() {
            let (host_name, host) = oit_core::plan::host_memory_budget();
            if host < heap.1 {
                return (host_name.to_string(), host);
            }
        }
        heap
    }
}

/// The aspect of an image of `format`: depth for the depth formats oit uses, else colour.
pub(crate) fn aspect(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// The hardware raster's render pass at `samples` samples a pixel: one [`COUNT_FORMAT`]
/// counter, left to be copied out (one sample) or read by `count_sum_ms` (several).
/// The pass of a hardware geometry pass over the opaque depth (one sample): the count image and
/// a depth attachment its first draw fills ([`DepthTest::Fill`]).
pub(crate) fn early_pass_key() -> PassKey {
    PassKey { depth: Some(EARLY_DEPTH_FORMAT), ..count_pass_key(1) }
}

/// The opaque depth's format on the hardware path (a format every Vulkan device attaches).
pub(crate) const EARLY_DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub(crate) fn count_pass_key(samples: u32) -> PassKey {
    // one sample: copied out into a buffer; several: read by a kernel as a multisampled image
    let final_layout = if samples > 1 {
        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
    } else {
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL
    };
    PassKey { colors: vec![COUNT_FORMAT], depth: None, final_layout, samples }
}

/// The colour blend state of `blend`.
fn blend_state(blend: Blend) -> vk::PipelineColorBlendAttachmentState {
    use vk::BlendFactor as F;
    let all = vk::ColorComponentFlags::RGBA;
    let on = |color: (F, F), alpha: (F, F), op: vk::BlendOp| {
        vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(true)
            .src_color_blend_factor(color.0)
            .dst_color_blend_factor(color.1)
            .color_blend_op(op)
            .src_alpha_blend_factor(alpha.0)
            .dst_alpha_blend_factor(alpha.1)
            .alpha_blend_op(op)
            .color_write_mask(all)
    };
    let one = (F::ONE, F::ONE);
    match blend {
        Blend::Replace | Blend::LogicOr => {
            vk::PipelineColorBlendAttachmentState::default().blend_enable(false).color_write_mask(all)
        }
        Blend::Add => on(one, one, vk::BlendOp::ADD),
        Blend::AddRed => on(one, one, vk::BlendOp::ADD).color_write_mask(vk::ColorComponentFlags::R),
        Blend::Nothing => vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(false)
            .color_write_mask(vk::ColorComponentFlags::empty()),
        Blend::Over => {
            on((F::ONE, F::ONE_MINUS_SRC_ALPHA), (F::ZERO, F::ONE_MINUS_SRC_ALPHA), vk::BlendOp::ADD)
        }
        // the factors are ignored by MAX
        Blend::Max => on(one, one, vk::BlendOp::MAX),
    }
}

/// Usage of every storage buffer.
pub(crate) fn storage_usage() -> vk::BufferUsageFlags {
    vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST
}

/// What a recorder is made of on the device: a command pool and buffer, a fence, a descriptor
/// pool, the uniform ring, the query pools, and host buffers (staging, readback) free for reuse.
/// A recorder's drop leaves them, reset, in its [`Gpu`]'s cache for the next frame
/// (`Gpu::take_recorder_parts`; `record.rs`'s `Recorder` uses them), so a steady frame creates none; they are destroyed (newest first)
/// when the cache drops them.
pub(crate) struct Parts {
    pub(crate) raw: std::sync::Arc<RawDevice>,
    pub(crate) pool: vk::CommandPool,
    pub(crate) cmd: vk::CommandBuffer,
    pub(crate) fence: vk::Fence,
    pub(crate) descriptors: vk::DescriptorPool,
    pub(crate) uniforms: Buffer,
    /// The timestamp query pool, where the device has timestamps.
    pub(crate) ts_pool: Option<vk::QueryPool>,
    /// One occlusion query, for the draws that ask (`Recorder::draw`).
    pub(crate) occlusion: vk::QueryPool,
    /// Host-visible buffers free for reuse (staging and readback), newest last.
    pub(crate) spare: Vec<std::rc::Rc<Buffer>>,
}

impl Drop for Parts {
    fn drop(&mut self) {
        // SAFETY: all made from this device; nothing is in flight (a recorder waits for its
        // own submission before it gives its parts up, or idles the queue); destroying a null handle
        // is a no-op.
        unsafe {
            let d = &self.raw.device;
            if let Some(pool) = self.ts_pool {
                d.destroy_query_pool(pool, None);
            }
            d.destroy_query_pool(self.occlusion, None);
            d.destroy_descriptor_pool(self.descriptors, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
    }
}
