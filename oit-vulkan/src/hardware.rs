//! The hardware-raster path: the GPU's own rasterizer through a graphics pipeline, on the WGSL
//! oit-wgpu's hardware path runs (`raster_hardware.wgsl`'s `hw_vs` and `hw_fs` after the
//! technique's `capture`, compiled to SPIR-V by `build.rs` as `<module>_hw`).
//!
//! What is uploaded once, and what per frame, as on oit-wgpu: the scene's geometry for vertex
//! pulling ([`oit_core::pulled::PulledGeometry`]: each mesh's vertices once, per triangle its
//! vertices and instance, in primitive order) when a prepared scene first draws on this path;
//! per frame only the instances' matrices and the shading uniform, uploaded by the frame's first
//! geometry pass in its command stream. The instances' bounding boxes (for the bounds passes of
//! bdp and adp) are a second geometry, uploaded on first use.
//!
//! A geometry pass is one draw of every triangle in a render pass whose one colour attachment
//! counts fragments by additive blending ([`crate::device::COUNT_FORMAT`]); the count image is
//! copied into a buffer and summed by a kernel (`shaders/count_sum.wgsl`) into the pass's
//! fragment count. At several samples a pixel (docs/msaa.md) the pass is multisampled, its
//! fragments carry `sample_mask` into the capture (`hw_fs_masked`) and add 1 at one sample, and
//! `vulkan/count_sum_ms.wgsl` sums the multisampled image's samples. The viewport's height is negative, so pixel rows, depth range and clip space
//! are wgpu's, and the fragments are those of oit-wgpu's hardware path on the same driver; against
//! oit-cpu only pixels on triangle edges may differ (the GPU's sub-pixel precision and clipping).

use std::cell::{Cell, OnceCell, RefCell};
use std::rc::Rc;

use ash::vk;
use oit_core::pulled::PulledGeometry;
use oit_core::{Camera, OitError, Scene, Settings};

use crate::device::{
    Buffer, COUNT_FORMAT, EARLY_DEPTH_FORMAT, Framebuffer, Gpu, GpuImage, count_pass_key, early_pass_key,
    storage_usage,
};
use crate::record::Recorder;

/// What to try when the geometry does not fit in one storage binding.
const GEOMETRY_HINT: &str = "use fewer triangles or instances, or the cpu backend";

/// A scene's (or its instances' boxes') geometry on the GPU: uploaded once, with the per-frame
/// instance buffer and uniform.
struct HwGeometry {
    boxes: bool,
    instances: usize,
    vertices: Rc<Buffer>,
    triangles: Rc<Buffer>,
    instance_buf: Rc<Buffer>,
    uniform: Rc<Buffer>,
    vertex_count: u32,
    /// The one draw's indirect arguments ([vertices, 1, 0, 0]) and their gated copy, for gated
    /// passes (`Raster::gate`).
    draw_args: Buffer,
    gated_args: Buffer,
    /// Group 1's binding 4 (raster_hardware.wgsl's `hw_tex`): a textured scene's textures packed
    /// from word 0 ([`oit_gpu::TextureRegion`], uploaded once), then one word a triangle, its
    /// level's descriptor (written each frame); a placeholder elsewhere.
    tex: Rc<Buffer>,
    /// A textured scene's region (its words dropped once uploaded) and the word where the
    /// per-triangle levels start.
    textures: Option<(oit_gpu::TextureRegion, u32)>,
}

fn geometry_usage() -> vk::BufferUsageFlags {
    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST
}

impl HwGeometry {
    /// Uploads the scene's meshes and triangles (`boxes`: its instances' bounding boxes), waiting
    /// for the upload; `made` counts the buffers created.
    fn new(gpu: &Gpu, scene: &Scene, boxes: bool, made: &Cell<u64>) -> Result<HwGeometry, OitError> {
        let g = PulledGeometry::new(scene, boxes)?;
        let vertex_bytes: &[u8] = bytemuck::cast_slice(&g.vertices);
        let triangle_bytes: &[u8] = bytemuck::cast_slice(&g.triangles);
        gpu.check_storage_hint("the meshes' vertices", vertex_bytes.len() as u64, GEOMETRY_HINT)?;
        gpu.check_storage_hint("the triangles' indices", triangle_bytes.len() as u64, GEOMETRY_HINT)?;
        gpu.check_storage_hint("the instances' matrices", g.instance_bytes(), GEOMETRY_HINT)?;
        // a binding may not be empty
        let sized = |bytes: usize| (bytes as u64).max(64);
        let vertices = Rc::new(gpu.buffer(sized(vertex_bytes.len()), geometry_usage(), false)?);
        let triangles = Rc::new(gpu.buffer(sized(triangle_bytes.len()), geometry_usage(), false)?);
        let instance_buf = Rc::new(gpu.buffer(g.instance_bytes(), geometry_usage(), false)?);
        let uniform = Rc::new(gpu.buffer(
            32,
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            false,
        )?);
        let indirect = storage_usage() | vk::BufferUsageFlags::INDIRECT_BUFFER;
        let draw_args = gpu.buffer(16, indirect, false)?;
        let gated_args = gpu.buffer(16, indirect, false)?;
        let region =
            (!boxes && oit_gpu::is_textured(scene)).then(|| oit_gpu::TextureRegion::new(&scene.textures, 0));
        let tex_bytes = match &region {
            Some(r) => (r.words.len() + g.triangles.len()) as u64 * 4,
            None => 64,
        };
        gpu.check_storage_hint("the textures", tex_bytes, "use smaller textures, or the cpu backend")?;
        let tex = Rc::new(gpu.buffer(tex_bytes, geometry_usage(), false)?);
        made.set(made.get() + 7);
        let mut rec = Recorder::new(gpu)?;
        let textures = match region {
            Some(mut r) => {
                rec.upload(&tex, bytemuck::cast_slice(&r.words))?;
                let levels = r.words.len() as u32;
                r.words = Vec::new();
                Some((r, levels))
            }
            None => None,
        };
        rec.upload(&vertices, vertex_bytes)?;
        rec.upload(&triangles, triangle_bytes)?;
        rec.upload(&draw_args, bytemuck::cast_slice(&[g.vertex_count(), 1, 0, 0]))?;
        rec.flush()?;
        Ok(HwGeometry {
            boxes,
            instances: g.instances,
            vertices,
            triangles,
            instance_buf,
            uniform,
            vertex_count: g.vertex_count(),
            draw_args,
            gated_args,
            tex,
            textures,
        })
    }
}

/// A hardware-raster geometry pass's fragment counter: the count image (with its framebuffer),
/// the buffer it is copied into, and the word the kernel sums it into.
struct CountTarget {
    /// The pass over the opaque depth's framebuffer (the count image and a depth image), made on
    /// first use ([`HardwareRaster::early_framebuffer`]); dropped before both images.
    early: OnceCell<(Framebuffer, GpuImage)>,
    /// Dropped before the image it is made of (fields drop in order).
    framebuffer: Framebuffer,
    image: GpuImage,
    counts: Buffer,
    generated: Buffer,
    /// Samples a pixel: above 1 a multisampled pass (docs/msaa.md), whose fragments each add 1
    /// at one sample (the first they cover), so the samples add up to fragments.
    samples: u32,
}

impl CountTarget {
    /// Objects a count target makes (for the prepared scene's allocation counter).
    const CREATES: u64 = 3;

    /// A count target of `size` and `samples` samples a pixel: at one sample copied into a
    /// buffer of a word a pixel for `count_sum`, at several read as a multisampled image by
    /// `count_sum_ms` (its buffer then a word).
    fn new(gpu: &Gpu, size: (u32, u32), samples: u32) -> Result<CountTarget, OitError> {
        let read = if samples > 1 { vk::ImageUsageFlags::SAMPLED } else { vk::ImageUsageFlags::TRANSFER_SRC };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | read;
        let image = gpu.image_sampled(size, COUNT_FORMAT, usage, samples)?;
        let framebuffer = gpu.framebuffer(gpu.render_pass(&count_pass_key(samples))?, &[&image])?;
        let (w, h) = image.extent;
        let counts_bytes = if samples > 1 { 16 } else { u64::from(w) * u64::from(h) * 4 };
        gpu.check_storage("the hardware raster's fragment counts", counts_bytes)?;
        Ok(CountTarget {
            early: OnceCell::new(),
            framebuffer,
            counts: gpu.buffer(counts_bytes, storage_usage(), false)?,
            generated: gpu.buffer(16, storage_usage(), false)?,
            image,
            samples,
        })
    }
}

/// The scene (or its boxes) on the GPU's rasterizer for one frame: handles to its geometry and to
/// a count target of the frame's size, and the frame's instance data until uploaded.
pub(crate) struct HardwareRaster {
    geometry: Rc<HwGeometry>,
    target: Rc<CountTarget>,
    /// The frame's instance data, uniform and per-triangle texture levels, until uploaded.
    pending: RefCell<Option<[Vec<u8>; 3]>>,
}

impl HardwareRaster {
    /// Group 1's storage bindings (the uniform, binding 2, is bound apart).
    pub(crate) fn bindings(&self) -> Vec<(u32, &Buffer)> {
        let g = &*self.geometry;
        vec![(0, &*g.vertices), (1, &*g.triangles), (3, &*g.instance_buf), (4, &*g.tex)]
    }

    /// The vertex and fragment stages' uniform.
    pub(crate) fn uniform(&self) -> &Buffer {
        &self.geometry.uniform
    }

    /// The vertices of the one draw.
    pub(crate) fn vertex_count(&self) -> u32 {
        self.geometry.vertex_count
    }

    /// The draw's indirect arguments, their gated copy, and their words (`Raster::gate`).
    pub(crate) fn gate(&self) -> (&Buffer, &Buffer, u32) {
        (&self.geometry.draw_args, &self.geometry.gated_args, 4)
    }

    /// The count image the draw renders into.
    pub(crate) fn target(&self) -> &GpuImage {
        &self.target.image
    }

    /// Samples a pixel of the count image (and of the pass).
    pub(crate) fn samples(&self) -> u32 {
        self.target.samples
    }

    /// The count image's framebuffer.
    pub(crate) fn framebuffer(&self) -> &Framebuffer {
        &self.target.framebuffer
    }

    /// The framebuffer of a pass over the opaque depth ([`crate::device::early_pass_key`]): the
    /// count image and a `D32_SFLOAT` image the pass fills from the opaque keys and tests
    /// against; made on first use (one sample a pixel).
    pub(crate) fn early_framebuffer(&self, gpu: &Gpu) -> Result<&Framebuffer, OitError> {
        if let Some((framebuffer, _)) = self.target.early.get() {
            return Ok(framebuffer);
        }
        // left readable by the pass (as every depth attachment of oit-vulkan)
        let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let depth = gpu.image(self.target.image.extent, EARLY_DEPTH_FORMAT, usage)?;
        let render_pass = gpu.render_pass(&early_pass_key())?;
        let framebuffer = gpu.framebuffer(render_pass, &[&self.target.image, &depth])?;
        Ok(&self.target.early.get_or_init(|| (framebuffer, depth)).0)
    }

    /// The buffer the count image is copied into, and the word it is summed into.
    pub(crate) fn counters(&self) -> (&Buffer, &Buffer) {
        (&self.target.counts, &self.target.generated)
    }

    /// Records the upload of this frame's instance data and uniform, once.
    pub(crate) fn upload(&self, rec: &mut Recorder<'_>) -> Result<(), OitError> {
        if let Some([instances, uniform, levels]) = self.pending.borrow_mut().take() {
            rec.upload(&self.geometry.instance_buf, &instances)?;
            rec.upload(&self.geometry.uniform, &uniform)?;
            if let Some((_, at)) = &self.geometry.textures {
                rec.upload_at(&self.geometry.tex, u64::from(*at) * 4, &levels)?;
            }
        }
        Ok(())
    }
}

/// A count target a prepared scene keeps: for the boxes or the scene, its size, its samples,
/// itself.
type KeptTarget = (bool, (u32, u32), u32, Rc<CountTarget>);

/// The hardware path's part of a prepared scene: the scene's geometry (uploaded when made), the
/// boxes' (on first use), and count targets by (boxes, size), so a frame of a size seen before
/// creates nothing.
pub(crate) struct HardwareScene {
    scene: Rc<HwGeometry>,
    boxes: OnceCell<Rc<HwGeometry>>,
    targets: RefCell<Vec<KeptTarget>>,
}

impl HardwareScene {
    /// Uploads the scene's geometry; `made` counts what is created.
    pub(crate) fn new(gpu: &Gpu, scene: &Scene, made: &Cell<u64>) -> Result<HardwareScene, OitError> {
        Ok(HardwareScene {
            scene: Rc::new(HwGeometry::new(gpu, scene, false, made)?),
            boxes: OnceCell::new(),
            targets: RefCell::new(Vec::new()),
        })
    }

    /// The frame's rasterizer of the scene (`boxes`: of its instances' bounding boxes), with this
    /// frame's instance data to upload and a count target of its size.
    pub(crate) fn raster(
        &self,
        gpu: &Gpu,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        boxes: bool,
        made: &Cell<u64>,
    ) -> Result<HardwareRaster, OitError> {
        let geometry = if boxes {
            match self.boxes.get() {
                Some(g) => g.clone(),
                None => {
                    let g = Rc::new(HwGeometry::new(gpu, scene, true, made)?);
                    self.boxes.get_or_init(|| g).clone()
                }
            }
        } else {
            self.scene.clone()
        };
        debug_assert_eq!(geometry.boxes, boxes);
        debug_assert_eq!(geometry.instances, scene.instances.len());
        let size = (settings.width, settings.height);
        let samples = settings.samples.max(1);
        let target = {
            let mut targets = self.targets.borrow_mut();
            match targets.iter().find(|(b, s, n, _)| (*b, *s, *n) == (boxes, size, samples)) {
                Some((.., t)) => t.clone(),
                None => {
                    let t = Rc::new(CountTarget::new(gpu, size, samples)?);
                    made.set(made.get() + CountTarget::CREATES);
                    targets.push((boxes, size, samples, t.clone()));
                    t
                }
            }
        };
        let instances = oit_core::pulled::instance_data(scene, camera, settings, boxes);
        let mut uniform = oit_core::pulled::raster_uniform(camera, settings);
        let mut levels = Vec::new();
        if let Some((region, at)) = &geometry.textures {
            levels = oit_gpu::triangle_levels(scene, camera, settings, region);
            (uniform[1], uniform[2]) = (1, *at);
        }
        Ok(HardwareRaster {
            geometry,
            target,
            pending: RefCell::new(Some([
                bytemuck::cast_slice(&instances).to_vec(),
                bytemuck::cast_slice(&uniform).to_vec(),
                bytemuck::cast_slice(&levels).to_vec(),
            ])),
        })
    }
}

/// The largest full frame a window may draw through its viewport ([`oit_core::Region::viewport`]):
/// the device's largest viewport side. Its viewport bounds reach at least twice that either way
/// (the Vulkan specification's minimum), which a window's offset never passes.
pub(crate) fn max_viewport_side(gpu: &Gpu) -> u32 {
    let [w, h] = gpu.info.limits.max_viewport_dimensions;
    w.min(h)
}
