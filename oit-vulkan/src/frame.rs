//! [`VkCtx`] as oit-gpu's frame contract: every technique's frame (`oit_gpu::technique`) runs on
//! it. What only raw Vulkan does is chosen through the contract: storage-image atomics
//! ([`Frame::storage_image`]) and adp's histogram by logic-op OR ([`Frame::histogram_capture`]).

use std::rc::Rc;

use ash::vk;
use oit_core::plan::Plan;
use oit_core::{GpuFragments, HardwareCapture, OitError, Settings};
use oit_gpu::{Frame, ImageFormat, Init};

use crate::ctx::VkCtx;
use crate::device::Buffer;
use crate::raster::Raster;

/// The buffers of a binding list, as the recorder takes them.
fn plain<'b>(buffers: &[&'b Rc<Buffer>]) -> Vec<&'b Buffer> {
    buffers.iter().map(|b| &***b).collect()
}

impl Frame<Raster> for VkCtx<'_> {
    type Buffer = Rc<Buffer>;

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
        "vulkan"
    }

    fn array(&mut self, label: &str, words: u64, init: Init) -> Result<Rc<Buffer>, OitError> {
        self.buffer(label, words, init)
    }

    fn scratch(&mut self, label: &str, words: u64, init: Init) -> Result<Rc<Buffer>, OitError> {
        VkCtx::scratch(self, label, words, init)
    }

    fn placeholder(&mut self) -> Result<Rc<Buffer>, OitError> {
        VkCtx::placeholder(self)
    }

    fn fill(&mut self, buffer: &Rc<Buffer>, value: u32) -> Result<(), OitError> {
        VkCtx::fill(self, buffer, value);
        Ok(())
    }

    fn copy(&mut self, src: &Rc<Buffer>, dst: &Rc<Buffer>, bytes: u64) -> Result<(), OitError> {
        VkCtx::copy(self, src, dst, bytes);
        Ok(())
    }

    fn read_u32(&mut self, buffer: &Rc<Buffer>) -> Result<Vec<u32>, OitError> {
        VkCtx::read_u32(self, buffer)
    }

    fn storage_image(
        &mut self,
        label: &str,
        binding: u32,
        layers: u32,
        format: ImageFormat,
        fill: u32,
    ) -> Result<(), OitError> {
        let info = &self.gpu.info;
        let (has, what, vk_format) = match format {
            ImageFormat::R32Uint => {
                (info.image_atomics_32, "storage-image atomics on R32_UINT", vk::Format::R32_UINT)
            }
            ImageFormat::R64Uint => (
                info.image_atomics_64,
                "64-bit storage-image atomics (VK_EXT_shader_image_atomic_int64's shaderImageInt64Atomics on R64_UINT)",
                vk::Format::R64_UINT,
            ),
        };
        if !has {
            return Err(OitError::Unsupported {
                backend: "vulkan".into(),
                what: format!(
                    "--atomic-storage image for {}: '{}' lacks {what}; use --atomic-storage buffer",
                    self.settings.technique, info.name
                ),
            });
        }
        VkCtx::storage_image(self, label, binding, layers, vk_format, fill).map(|_| ())
    }

    fn last_pass(&mut self, last: bool) {
        VkCtx::last_pass(self, last);
    }

    fn cut(&mut self, on: bool) {
        VkCtx::cut(self, on);
    }

    fn note_opaque(&mut self, count: &Rc<Buffer>) {
        VkCtx::note_opaque(self, count);
    }

    fn geometry_pass(
        &mut self,
        raster: &Raster,
        module: &'static str,
        buffers: &[&Rc<Buffer>],
        pass: u32,
        param: u32,
    ) -> Result<(), OitError> {
        VkCtx::geometry_pass(self, raster, module, &plain(buffers), pass, param)
    }

    fn geometry_pass_counted(
        &mut self,
        raster: &Raster,
        module: &'static str,
        buffers: &[&Rc<Buffer>],
        pass: u32,
        param: u32,
    ) -> Result<Rc<Buffer>, OitError> {
        self.geometry_pass_kept_count(raster, module, &plain(buffers), pass, param)
    }

    fn geometry_pass_if(
        &mut self,
        raster: &Raster,
        module: &'static str,
        buffers: &[&Rc<Buffer>],
        pass: u32,
        param: u32,
        flag: &Rc<Buffer>,
    ) -> Result<(), OitError> {
        VkCtx::geometry_pass_if(self, raster, module, &plain(buffers), pass, param, flag)
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
        buffers: &[&Rc<Buffer>],
        invocations: u64,
        pass: u32,
        param: u32,
        label: &'static str,
    ) -> Result<(), OitError> {
        VkCtx::kernel_over(self, module, entry, &plain(buffers), invocations, pass, param, label)
    }

    fn deepest_alike(
        &mut self,
        max: &Rc<Buffer>,
        alike: Box<dyn Fn(u32, u32) -> bool>,
    ) -> Result<u32, OitError> {
        VkCtx::deepest_alike(self, max, alike)
    }

    fn fragment_capacity(&mut self, count: &Rc<Buffer>, bytes: u64) -> Result<u32, OitError> {
        VkCtx::fragment_capacity(self, count, bytes)
    }

    /// Where the frame reads back (nothing speculated yet), the gate's pipeline is made now, so
    /// the next frame, which gates, creates none.
    fn take_speculated_peels(&mut self) -> Result<Option<u32>, OitError> {
        let speculated = self.speculated.peels.take();
        if speculated.is_none() {
            self.make_gate_pipeline()?;
        }
        Ok(speculated)
    }

    fn note_peels(&mut self, peels: u32) {
        VkCtx::note_peels(self, peels);
    }

    fn check_at_end(&mut self, flag: &Rc<Buffer>) {
        VkCtx::check_at_end(self, flag);
    }

    fn refuse_at_end(&mut self, flag: &Rc<Buffer>, what: String) {
        VkCtx::refuse_at_end(self, flag, what);
    }

    fn note_merged(&mut self, words: &Rc<Buffer>) {
        VkCtx::note_merged(self, words);
    }

    fn note_layers(&mut self, counts: &Rc<Buffer>) {
        self.layers_from = Some(counts.clone());
    }

    /// Under `--hardware-capture blend` on the hardware path: logic-op OR into 8 ×
    /// `R32G32B32A32_UINT` (`technique::blend::adp_histogram`).
    fn histogram_capture(&mut self, raster: &Raster, buffers: &[&Rc<Buffer>]) -> Result<bool, OitError> {
        let blend =
            matches!(raster, Raster::Hardware(_)) && self.settings.hardware_capture == HardwareCapture::Blend;
        if !blend {
            return Ok(false);
        }
        crate::technique::blend::adp_histogram(self, raster, &plain(buffers))?;
        Ok(true)
    }
}
