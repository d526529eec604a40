//! Command recording: one command buffer at a time, submitted and waited for when the host needs
//! a result (a readback) or when the frame ends.
//!
//! Synchronization: one `VkMemoryBarrier` from every stage's writes to every stage's (and the
//! host's) reads and writes, recorded before a command that may race with what came since the
//! last one. A global memory barrier covers every buffer the commands before it touched (Khronos
//! recommends it over per-buffer barriers when many buffers are involved); it orders
//! read-after-write, write-after-write and (by its execution dependency) write-after-read.
//! Before every dispatch and draw there is one when anything was recorded since the last (a
//! kernel's buffers are all read-write, so any earlier command may race with it); fills and copies
//! name the buffers they read and write ([`Pending`]), so a run of them on distinct buffers (a
//! frame's clears, its readback copies) shares one. Every submission ends with one, behind which
//! the host reads results after the fence (its `HOST_READ`). The host writes uniforms and staging
//! buffers before the submission that reads them (made visible by the submission itself).
//! Each barrier waits for the whole device; recording half as many changed no frame's time on an
//! H100 (`bench/results/h100/fills-barriers-1024`), so a simpler rule would do as well there.
//!
//! A hardware-raster geometry pass is one render pass (its own dependencies order it after and
//! before everything, `Gpu::count_pass`) holding one draw, with the same barriers around it.
//!
//! GPU time: where the device has timestamps ([`Gpu::has_timestamps`]) a query pool of two
//! timestamps per uniform slot, reset at the start of every recording (outside any render pass)
//! and written once each per recording, outside render passes: before dispatch or draw `i`
//! (query `2i`) and after it (query `2i + 1`), before any barrier after it. The flush reads the pairs written after the fence and adds each one's
//! time to its label's total and the frame's, as oit-wgpu's `pass_ms` does.

use std::rc::Rc;

use ash::vk;
use oit_core::OitError;

use crate::device::{Buffer, Framebuffer, Gpu, GpuImage, Parts, Pipeline};

/// Uniform slots (and dispatches) per submission before a flush.
pub(crate) const SLOTS: u32 = 256;
/// Bytes between uniform slots (≥ every device's `minUniformBufferOffsetAlignment`).
const SLOT_BYTES: u64 = 256;
/// Descriptor sets per submission: up to three per command (group 0, a rasterizer's, images).
const MAX_SETS: u32 = 3 * SLOTS;
/// Sampled images of one set at most (bdp's 8 bucket targets).
const MAX_IMAGES_PER_SET: u32 = 8;
/// Storage images of one set at most (group 0 under `--atomic-storage image`: mdts's two).
const MAX_STORAGE_IMAGES_PER_SET: u32 = 2;
/// Storage bindings of one set at most (group 0: state, up to 6 technique buffers, acct).
const MAX_STORAGE_PER_SET: u32 = 16;
/// How long a submission may run before it counts as hung.
const TIMEOUT_NS: u64 = 120_000_000_000;

/// Nanoseconds in a millisecond.
const NS_PER_MS: f64 = 1e6;

/// What one descriptor set of a command holds.
pub(crate) enum SetData<'b> {
    /// Group 0: the frame uniform (copied into the next slot of the ring, bound at 0), the
    /// storage buffers (binding, buffer) and the storage images (binding, image; each in
    /// `GENERAL`, [`Recorder::clear_image`]).
    Frame { uniform: &'b [u8], storage: &'b [(u32, &'b Buffer)], images: &'b [(u32, Rc<GpuImage>)] },
    /// A rasterizer's group 1: storage (binding, buffer) and its uniform at binding 2.
    Raster { storage: &'b [(u32, &'b Buffer)], uniform: &'b Buffer },
    /// Sampled images (binding, image), each in `SHADER_READ_ONLY_OPTIMAL`.
    Images(&'b [(u32, &'b GpuImage)]),
}

/// The frame's timestamp queries: two per uniform slot.
struct Timestamps {
    pool: vk::QueryPool,
    /// `timestampValidBits` as a mask of a timestamp's meaningful bits.
    mask: u64,
    /// `timestampPeriod`: nanoseconds per tick.
    period: f64,
    /// The label of each dispatch of the current recording (dispatch `i`: queries `2i`, `2i + 1`).
    labels: Vec<String>,
    /// Device milliseconds of the frame's dispatches so far.
    total_ms: f64,
    /// The same by label, in the order the labels were first seen.
    pass_ms: Vec<(String, f64)>,
    /// The frame's first start and last end so far, in device nanoseconds (`OIT_HOST_TIMES`'s
    /// span and the device's idle time between frames).
    span_ns: Option<(f64, f64)>,
    /// Device milliseconds between a timed command's start and the end of the one timed before
    /// it in the same submission (the untimed fills, copies and barriers recorded between them,
    /// and the pipeline's drain), by the later one's label, in the order first seen
    /// (`OIT_HOST_TIMES`'s untimed time within the span).
    gap_ms: Vec<(String, f64)>,
}

/// Adds `ms` to `label`'s total in `totals`, a new entry where it has none.
fn add_to(totals: &mut Vec<(String, f64)>, label: &str, ms: f64) {
    match totals.iter_mut().find(|(l, _)| l == label) {
        Some((_, total)) => *total += ms,
        None => totals.push((label.to_string(), ms)),
    }
}

impl Timestamps {
    /// Adds the pairs of the labels recorded (`ticks`: two per label, as read back), and starts
    /// the labels over.
    fn add(&mut self, ticks: &[u64]) {
        let mut last_end: Option<u64> = None;
        for (label, pair) in self.labels.drain(..).zip(ticks.chunks_exact(2)) {
            let (start, end) = (pair[0] & self.mask, pair[1] & self.mask);
            // a counter that wrapped within its valid bits between the two still subtracts right
            let ticks_ms =
                |from: u64, to: u64| (to.wrapping_sub(from) & self.mask) as f64 * self.period / NS_PER_MS;
            let ms = ticks_ms(start, end);
            self.total_ms += ms;
            let (s, e) = (start as f64 * self.period, end as f64 * self.period);
            self.span_ns = Some(self.span_ns.map_or((s, e), |(s0, e0)| (s0.min(s), e0.max(e))));
            if let Some(before) = last_end {
                add_to(&mut self.gap_ms, &label, ticks_ms(before, start));
            }
            last_end = Some(end);
            add_to(&mut self.pass_ms, &label, ms);
        }
    }
}

/// Commands of a frame's recordings, by kind ([`Recorder::counts`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CommandCounts {
    pub(crate) barriers: u32,
    pub(crate) transfers: u32,
    pub(crate) submissions: u32,
}

/// What the commands recorded since the last barrier touched: the buffers fills and copies read
/// and wrote, or anything at all (`all`: a dispatch, a draw, an image command, whose accesses
/// are not tracked). A command that may race with them needs a barrier first.
#[derive(Debug, Default)]
struct Pending {
    all: bool,
    reads: Vec<vk::Buffer>,
    writes: Vec<vk::Buffer>,
}

impl Pending {
    /// Nothing recorded since the last barrier.
    fn is_empty(&self) -> bool {
        !self.all && self.reads.is_empty() && self.writes.is_empty()
    }

    /// Whether a transfer reading `reads` and writing `writes` may race with what is pending: it
    /// reads what they write, writes what they read or write, or they are not tracked.
    fn conflicts(&self, reads: &[vk::Buffer], writes: &[vk::Buffer]) -> bool {
        self.all
            || reads.iter().any(|b| self.writes.contains(b))
            || writes.iter().any(|b| self.writes.contains(b) || self.reads.contains(b))
    }

    /// Adds a transfer's buffers.
    fn add(&mut self, reads: &[vk::Buffer], writes: &[vk::Buffer]) {
        self.reads.extend_from_slice(reads);
        self.writes.extend_from_slice(writes);
    }

    /// After a barrier: nothing.
    fn clear(&mut self) {
        self.all = false;
        self.reads.clear();
        self.writes.clear();
    }
}

/// Spare host buffers a recorder's parts keep at most.
const MAX_SPARE: usize = 32;

/// The recorder of one frame: its [`Parts`] (taken from the device's cache or made), and the
/// frame's uniform ring contents, descriptor and timestamp bookkeeping.
pub(crate) struct Recorder<'g> {
    gpu: &'g Gpu,
    /// Given back to the device's cache by `drop` (taken out there, never used after).
    p: std::mem::ManuallyDrop<Parts>,
    /// The ring's contents, written to `uniforms` before each submission.
    uniform_bytes: Vec<u8>,
    slot: u32,
    sets: u32,
    /// Buffers a recorded command uses that nothing else keeps alive (staging), until the flush.
    keep: Vec<Rc<Buffer>>,
    /// The timestamp queries, where the device has them.
    timestamps: Option<Timestamps>,
    /// A submission is on the queue that no wait has collected (`submit` without `wait`).
    submitted: bool,
    /// What the commands since the last barrier touched.
    pending: Pending,
    /// The barriers, transfers (fills, copies, uploads, image clears) and submissions recorded
    /// so far (`OIT_HOST_TIMES`'s counts).
    pub(crate) counts: CommandCounts,
    /// The full frame's viewport `[x, y, width, height]` where the frame is a window of it
    /// ([`oit_core::Region::viewport`]), for every draw.
    pub(crate) window: Option<[f32; 4]>,
}

impl Drop for Recorder<'_> {
    fn drop(&mut self) {
        // SAFETY: `p` is taken once, here, and the recorder is not used after.
        let mut parts = unsafe { std::mem::ManuallyDrop::take(&mut self.p) };
        parts.spare.append(&mut self.keep);
        // SAFETY: the parts are this device's; after the wait for their own submission (not the
        // whole queue's: another frame may be in flight) nothing they hold is in flight, so the
        // pools may be reset (the command buffer back to its initial state, every set freed) and
        // handed to the next recorder. A failed wait falls back to the queue's idle, and the
        // parts are not reused.
        let reset = unsafe {
            let d = &self.gpu.raw.device;
            let idle = !self.submitted || d.wait_for_fences(&[parts.fence], true, TIMEOUT_NS).is_ok();
            if self.submitted {
                self.gpu.count_in_flight(false);
            }
            if !idle {
                let _ = d.queue_wait_idle(self.gpu.queue);
            }
            idle && d.reset_command_pool(parts.pool, vk::CommandPoolResetFlags::empty()).is_ok()
                && d.reset_descriptor_pool(parts.descriptors, vk::DescriptorPoolResetFlags::empty()).is_ok()
                && d.reset_fences(&[parts.fence]).is_ok()
        };
        if reset {
            self.gpu.give_recorder_parts(parts);
        }
    }
}

fn vk_err(what: &'static str) -> impl Fn(vk::Result) -> OitError {
    move |e| match e {
        vk::Result::ERROR_DEVICE_LOST => {
            OitError::Device(format!("{what}: the Vulkan device was lost (driver reset or crash)"))
        }
        vk::Result::TIMEOUT => OitError::Device(format!(
            "{what}: the GPU did not finish within {} s; use a smaller scene or --size",
            TIMEOUT_NS / 1_000_000_000
        )),
        other => OitError::Device(format!("{what}: {other}")),
    }
}

impl<'g> Recorder<'g> {
    /// A recorder, recording: on the parts of an earlier one where the device kept them.
    pub(crate) fn new(gpu: &'g Gpu) -> Result<Self, OitError> {
        let parts = match gpu.take_recorder_parts() {
            Some(parts) => parts,
            None => Self::make_parts(gpu)?,
        };
        let timestamps = parts.ts_pool.map(|pool| {
            let bits = gpu.info.timestamp_valid_bits;
            Timestamps {
                pool,
                mask: if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 },
                period: f64::from(gpu.info.limits.timestamp_period),
                labels: Vec::new(),
                total_ms: 0.0,
                pass_ms: Vec::new(),
                span_ns: None,
                gap_ms: Vec::new(),
            }
        });
        let r = Recorder {
            gpu,
            p: std::mem::ManuallyDrop::new(parts),
            uniform_bytes: vec![0; (u64::from(SLOTS) * SLOT_BYTES) as usize],
            slot: 0,
            sets: 0,
            keep: Vec::new(),
            timestamps,
            submitted: false,
            pending: Pending::default(),
            counts: CommandCounts::default(),
            window: None,
        };
        r.begin()?;
        Ok(r)
    }

    /// New parts: every object made, each destroyed by `Parts`' drop (also when a later one
    /// fails: null handles are skipped).
    fn make_parts(gpu: &Gpu) -> Result<Parts, OitError> {
        let d = &gpu.raw.device;
        let uniforms =
            gpu.buffer(u64::from(SLOTS) * SLOT_BYTES, vk::BufferUsageFlags::UNIFORM_BUFFER, true)?;
        let mut parts = Parts {
            raw: gpu.raw.clone(),
            pool: vk::CommandPool::null(),
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            descriptors: vk::DescriptorPool::null(),
            uniforms,
            ts_pool: None,
            occlusion: vk::QueryPool::null(),
            spare: Vec::new(),
        };
        let pool_info = vk::CommandPoolCreateInfo::default().queue_family_index(gpu.family);
        let sizes = [
            vk::DescriptorPoolSize { ty: vk::DescriptorType::UNIFORM_BUFFER, descriptor_count: MAX_SETS },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_BUFFER,
                descriptor_count: MAX_SETS * MAX_STORAGE_PER_SET,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::SAMPLED_IMAGE,
                descriptor_count: MAX_SETS * MAX_IMAGES_PER_SET,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_IMAGE,
                descriptor_count: MAX_SETS * MAX_STORAGE_IMAGES_PER_SET,
            },
        ];
        let dp_info = vk::DescriptorPoolCreateInfo::default().max_sets(MAX_SETS).pool_sizes(&sizes);
        let occlusion =
            vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::OCCLUSION).query_count(1);
        // SAFETY: valid create infos on a live device; each object is stored in `parts` as soon
        // as it is made, so `Parts`' drop destroys what was made should a later step fail.
        unsafe {
            parts.pool =
                d.create_command_pool(&pool_info, None).map_err(vk_err("creating a command pool"))?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(parts.pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            parts.cmd = d.allocate_command_buffers(&alloc).map_err(vk_err("allocating a command buffer"))?[0];
            parts.fence =
                d.create_fence(&vk::FenceCreateInfo::default(), None).map_err(vk_err("creating a fence"))?;
            parts.descriptors =
                d.create_descriptor_pool(&dp_info, None).map_err(vk_err("creating a descriptor pool"))?;
            parts.occlusion =
                d.create_query_pool(&occlusion, None).map_err(vk_err("creating an occlusion query pool"))?;
            if gpu.has_timestamps() {
                let info = vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::TIMESTAMP)
                    .query_count(2 * SLOTS);
                parts.ts_pool =
                    Some(d.create_query_pool(&info, None).map_err(vk_err("creating a query pool"))?);
            }
        }
        Ok(parts)
    }

    /// A host-visible buffer of at least `size` bytes and `usage`: a spare one of about that size,
    /// or a new one.
    fn host_buffer(&mut self, size: u64, usage: vk::BufferUsageFlags) -> Result<Rc<Buffer>, OitError> {
        let fits = |b: &Rc<Buffer>| b.usage == usage && b.size >= size && b.size <= size.max(4096) * 2;
        if let Some(i) = self.p.spare.iter().rposition(fits) {
            return Ok(self.p.spare.swap_remove(i));
        }
        Ok(Rc::new(self.gpu.buffer(size, usage, true)?))
    }

    /// Gives host buffers back for reuse (the oldest dropped past [`MAX_SPARE`]).
    fn spare(&mut self, buffers: impl IntoIterator<Item = Rc<Buffer>>) {
        self.p.spare.extend(buffers);
        let over = self.p.spare.len().saturating_sub(MAX_SPARE);
        self.p.spare.drain(..over);
    }

    /// The device this recorder records for.
    pub(crate) fn gpu(&self) -> &'g Gpu {
        self.gpu
    }

    /// Starts recording, and resets the timestamp queries before anything can write them.
    fn begin(&self) -> Result<(), OitError> {
        let info = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        let d = &self.gpu.raw.device;
        // SAFETY: the command buffer is in the initial state (new, or its pool was just reset).
        unsafe { d.begin_command_buffer(self.p.cmd, &info) }.map_err(vk_err("recording"))?;
        if let Some(ts) = &self.timestamps {
            // SAFETY: recording, outside any render pass (none is ever begun); the pool holds
            // 2 × SLOTS queries, none in use by a pending submission (recording begins only
            // after the last submission's wait).
            unsafe { d.cmd_reset_query_pool(self.p.cmd, ts.pool, 0, 2 * SLOTS) };
        }
        Ok(())
    }

    /// The frame's device time so far, in total and by label (in the order first seen), with
    /// timestamps; `None` without. Complete once the last dispatch's submission was flushed.
    pub(crate) fn gpu_times(&self) -> Option<(f64, &[(String, f64)])> {
        self.timestamps.as_ref().map(|ts| (ts.total_ms, ts.pass_ms.as_slice()))
    }

    /// The device nanoseconds of the frame's first timed command's start and its last one's end,
    /// with timestamps and once one was read (a counter that wrapped between them is not
    /// corrected: a diagnostic's, `OIT_HOST_TIMES`).
    pub(crate) fn gpu_span_ns(&self) -> Option<(f64, f64)> {
        self.timestamps.as_ref().and_then(|ts| ts.span_ns)
    }

    /// The device milliseconds before each timed command that no command timed (see
    /// `Timestamps::gap_ms`), by its label, with timestamps and once one was read.
    pub(crate) fn gpu_gaps(&self) -> &[(String, f64)] {
        self.timestamps.as_ref().map_or(&[], |ts| &ts.gap_ms)
    }

    /// The barrier (see the module docs): everything recorded before it is done and visible to
    /// everything after, and to the host.
    fn barrier(&mut self) {
        self.counts.barriers += 1;
        self.pending.clear();
        let barrier =
            vk::MemoryBarrier::default().src_access_mask(vk::AccessFlags::MEMORY_WRITE).dst_access_mask(
                vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE | vk::AccessFlags::HOST_READ,
            );
        // SAFETY: the command buffer is recording, outside a render pass; ALL_COMMANDS is valid
        // on any queue.
        unsafe {
            self.gpu.raw.device.cmd_pipeline_barrier(
                self.p.cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS | vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            );
        }
    }

    /// A barrier where anything was recorded since the last: before a command whose accesses
    /// are not tracked (a dispatch, a draw), and at the end of a submission.
    fn settle(&mut self) {
        if !self.pending.is_empty() {
            self.barrier();
        }
    }

    /// Before a fill or copy that reads `reads` and writes `writes`: a barrier where it may race
    /// with what is pending, then it joins what is pending.
    fn transfer(&mut self, reads: &[vk::Buffer], writes: &[vk::Buffer]) {
        self.counts.transfers += 1;
        if self.pending.conflicts(reads, writes) {
            self.barrier();
        }
        self.pending.add(reads, writes);
    }

    /// Submits what was recorded, waits for it, and starts recording again.
    pub(crate) fn flush(&mut self) -> Result<(), OitError> {
        self.submit()?;
        self.wait()
    }

    /// Ends recording and submits what was recorded, without waiting for it: [`Recorder::wait`]
    /// does (a frame in flight is a recorder submitted and not yet waited for).
    fn submit(&mut self) -> Result<(), OitError> {
        // the host reads results behind it, and the next submission's commands start after it
        self.settle();
        let d = &self.gpu.raw.device;
        self.p.uniforms.write(&self.uniform_bytes[..(u64::from(self.slot) * SLOT_BYTES) as usize])?;
        let cmds = [self.p.cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // SAFETY: the command buffer was recorded on this device and everything it references
        // is alive (the frame's buffers, `keep`, the cached pipelines, the query pool) until the
        // wait; the fence is unsignalled (reset by the last wait, or new).
        unsafe {
            d.end_command_buffer(self.p.cmd).map_err(vk_err("recording"))?;
            d.queue_submit(self.gpu.queue, &submit, self.p.fence).map_err(vk_err("submitting work"))?;
        }
        self.submitted = true;
        self.counts.submissions += 1;
        self.gpu.count_in_flight(true);
        Ok(())
    }

    /// Waits for the last submission, reads its timestamps, and starts recording again.
    fn wait(&mut self) -> Result<(), OitError> {
        let d = &self.gpu.raw.device;
        // SAFETY: the fence belongs to the submission `submit` made; after the wait nothing is in
        // flight, so the pools may be reset and the queries read: `ticks` holds 2 × labels u64
        // results, queries 0.. of those written.
        unsafe {
            d.wait_for_fences(&[self.p.fence], true, TIMEOUT_NS).map_err(vk_err("waiting for the GPU"))?;
            self.submitted = false;
            self.gpu.count_in_flight(false);
            if let Some(ts) = self.timestamps.as_mut().filter(|ts| !ts.labels.is_empty()) {
                // the submission reset every query and then wrote each of these once; it has
                // completed (the fence), so WAIT returns at once
                let mut ticks = vec![0u64; 2 * ts.labels.len()];
                d.get_query_pool_results(
                    ts.pool,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
                .map_err(vk_err("reading timestamps"))?;
                ts.add(&ticks);
            }
            d.reset_fences(&[self.p.fence]).map_err(vk_err("resetting a fence"))?;
            d.reset_command_pool(self.p.pool, vk::CommandPoolResetFlags::empty())
                .map_err(vk_err("resetting a command pool"))?;
            d.reset_descriptor_pool(self.p.descriptors, vk::DescriptorPoolResetFlags::empty())
                .map_err(vk_err("resetting a descriptor pool"))?;
        }
        self.slot = 0;
        self.sets = 0;
        let kept = std::mem::take(&mut self.keep);
        self.spare(kept);
        self.begin()
    }

    /// Room for a dispatch with `sets` descriptor sets, flushing first when the ring is full.
    fn room(&mut self, sets: u32) -> Result<(), OitError> {
        if self.slot >= SLOTS || self.sets + sets > MAX_SETS {
            self.flush()?;
        }
        Ok(())
    }

    fn allocate(&mut self, layout: vk::DescriptorSetLayout) -> Result<vk::DescriptorSet, OitError> {
        let layouts = [layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.p.descriptors)
            .set_layouts(&layouts);
        self.sets += 1;
        // SAFETY: the pool has room (`room`) and the layout is alive (cached in the Gpu).
        Ok(unsafe { self.gpu.raw.device.allocate_descriptor_sets(&info) }
            .map_err(vk_err("allocating descriptors"))?[0])
    }

    /// Writes `buffers` (binding, buffer) into `set`, and the uniform slot at binding 0 when given.
    fn write_set(
        &self,
        set: vk::DescriptorSet,
        uniform: Option<(u32, &Buffer, u64)>,
        buffers: &[(u32, &Buffer)],
    ) {
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|(_, b)| [vk::DescriptorBufferInfo { buffer: b.buffer, offset: 0, range: vk::WHOLE_SIZE }])
            .collect();
        let uniform_info = uniform.map(|(_, b, offset)| {
            [vk::DescriptorBufferInfo { buffer: b.buffer, offset, range: SLOT_BYTES.min(b.size) }]
        });
        let mut writes: Vec<vk::WriteDescriptorSet<'_>> = buffers
            .iter()
            .zip(&infos)
            .map(|((binding, _), info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(*binding)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        if let (Some((binding, _, _)), Some(info)) = (uniform, uniform_info.as_ref()) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                    .buffer_info(info),
            );
        }
        // SAFETY: the set is allocated and not in use by a pending submission (sets are reset
        // only after a wait); every buffer is alive and has the usage its descriptor type needs.
        unsafe { self.gpu.raw.device.update_descriptor_sets(&writes, &[]) };
    }

    /// Writes `images` (binding, image) into `set` as descriptors of `kind`, each image in
    /// `layout` when the command runs.
    fn write_images<'i>(
        &self,
        set: vk::DescriptorSet,
        images: impl Iterator<Item = (u32, &'i GpuImage)>,
        kind: vk::DescriptorType,
        layout: vk::ImageLayout,
    ) {
        let images: Vec<(u32, [vk::DescriptorImageInfo; 1])> = images
            .map(|(binding, image)| {
                (binding, [vk::DescriptorImageInfo::default().image_view(image.view).image_layout(layout)])
            })
            .collect();
        if images.is_empty() {
            return;
        }
        let writes: Vec<vk::WriteDescriptorSet<'_>> = images
            .iter()
            .map(|(binding, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(*binding)
                    .descriptor_type(kind)
                    .image_info(info)
            })
            .collect();
        // SAFETY: as in `write_set`; the callers' images have the usage `kind` needs and are in
        // `layout` when the command runs: a sampled image in SHADER_READ_ONLY_OPTIMAL (its
        // render pass left it so), a storage image in GENERAL (`clear_image` put it there, first
        // of the frame's commands that use it).
        unsafe { self.gpu.raw.device.update_descriptor_sets(&writes, &[]) };
    }

    /// Records `image` (a storage image of the frame) taken to `GENERAL`, its contents
    /// discarded, then every texel of every layer set to `value` in each 32 bits (all ones or
    /// zero: the same in any texel width); a barrier comes before what may race with it.
    pub(crate) fn clear_image(&mut self, image: &GpuImage, value: u32) {
        self.counts.transfers += 1;
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(image.layers);
        let to_general = vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::GENERAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.image)
            .subresource_range(range);
        let color = vk::ClearColorValue { uint32: [value; 4] };
        self.counts.barriers += 1;
        // SAFETY: recording, outside a render pass; the image is alive (the frame's), has
        // TRANSFER_DST usage and is in GENERAL for the clear (the barrier before it, which also
        // orders it after every earlier use of the image: a pooled image's last frame).
        unsafe {
            let d = &self.gpu.raw.device;
            d.cmd_pipeline_barrier(
                self.p.cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[to_general],
            );
            d.cmd_clear_color_image(self.p.cmd, image.image, vk::ImageLayout::GENERAL, &color, &[range]);
        }
        self.pending.all = true;
    }

    /// Allocates and writes a command's descriptor sets, one per entry of `sets`, in set order
    /// (see [`SetData`]).
    fn sets(
        &mut self,
        pipeline: &Pipeline,
        sets: &[SetData<'_>],
    ) -> Result<Vec<vk::DescriptorSet>, OitError> {
        debug_assert_eq!(pipeline.sets.len(), sets.len(), "one SetData per set of the pipeline");
        self.room(sets.len() as u32)?;
        let mut out = Vec::with_capacity(sets.len());
        for (data, &layout) in sets.iter().zip(&pipeline.sets) {
            let set = self.allocate(layout)?;
            match data {
                SetData::Frame { uniform, storage, images } => {
                    let offset = u64::from(self.slot) * SLOT_BYTES;
                    self.uniform_bytes[offset as usize..offset as usize + uniform.len()]
                        .copy_from_slice(uniform);
                    self.slot += 1;
                    self.write_set(set, Some((0, &self.p.uniforms, offset)), storage);
                    self.write_images(
                        set,
                        images.iter().map(|(b, i)| (*b, &**i)),
                        vk::DescriptorType::STORAGE_IMAGE,
                        vk::ImageLayout::GENERAL,
                    );
                }
                SetData::Raster { storage, uniform } => {
                    self.write_set(set, None, storage);
                    // the raster uniform is a whole (small) buffer of its own
                    let info = [vk::DescriptorBufferInfo {
                        buffer: uniform.buffer,
                        offset: 0,
                        range: vk::WHOLE_SIZE,
                    }];
                    let write = vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                        .buffer_info(&info);
                    // SAFETY: as in `write_set`.
                    unsafe { self.gpu.raw.device.update_descriptor_sets(&[write], &[]) };
                }
                SetData::Images(images) => self.write_images(
                    set,
                    images.iter().copied(),
                    vk::DescriptorType::SAMPLED_IMAGE,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
            }
            out.push(set);
        }
        Ok(out)
    }

    /// The next timestamp pair of this recording, counted under `label` (with timestamps): the
    /// pairs written are 0..labels, read by the flush; at most one per uniform slot taken, so
    /// below SLOTS (`room`).
    fn timed(&mut self, label: &str) -> Option<(vk::QueryPool, u32)> {
        self.timestamps.as_mut().map(|ts| {
            ts.labels.push(label.to_string());
            (ts.pool, ts.labels.len() as u32 - 1)
        })
    }

    /// Writes query `2 × pair + end` of `timed` (outside any render pass).
    fn stamp(&self, timed: Option<(vk::QueryPool, u32)>, end: u32) {
        if let Some((pool, pair)) = timed {
            // SAFETY: recording; the query (< 2 × SLOTS) was reset at `begin` and is written once
            // in this recording (pairs start over only after a flush).
            unsafe {
                self.gpu.raw.device.cmd_write_timestamp(
                    self.p.cmd,
                    vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                    pool,
                    2 * pair + end,
                );
            }
        }
    }

    /// Records one dispatch of `pipeline` with `sets`. With timestamps, its time counts under
    /// `label`. A barrier comes before what may race with it.
    pub(crate) fn dispatch(
        &mut self,
        label: &str,
        pipeline: &Pipeline,
        sets: &[SetData<'_>],
        groups: (u32, u32),
    ) -> Result<(), OitError> {
        let sets = self.sets(pipeline, sets)?;
        self.settle();
        let timed = self.timed(label);
        self.stamp(timed, 0);
        let d = &self.gpu.raw.device;
        // SAFETY: recording; the pipeline's layout matches the sets bound (made from its set
        // layouts); the group counts are within maxComputeWorkGroupCount (x ≤ 65535).
        unsafe {
            d.cmd_bind_pipeline(self.p.cmd, vk::PipelineBindPoint::COMPUTE, pipeline.pipeline);
            d.cmd_bind_descriptor_sets(
                self.p.cmd,
                vk::PipelineBindPoint::COMPUTE,
                pipeline.layout,
                0,
                &sets,
                &[],
            );
            if groups.0 > 0 && groups.1 > 0 {
                d.cmd_dispatch(self.p.cmd, groups.0, groups.1, 1);
            }
        }
        self.stamp(timed, 1);
        self.pending.all = true;
        Ok(())
    }

    /// Records one dispatch of `pipeline` with `sets` whose group counts the device reads from
    /// `args` at byte `offset` (three u32, written by an earlier command: the compute path's
    /// setup). With timestamps, its time counts under `label`. A barrier comes before what may race with it.
    pub(crate) fn dispatch_indirect(
        &mut self,
        label: &str,
        pipeline: &Pipeline,
        sets: &[SetData<'_>],
        args: &Buffer,
        offset: u64,
    ) -> Result<(), OitError> {
        let sets = self.sets(pipeline, sets)?;
        self.settle();
        let timed = self.timed(label);
        self.stamp(timed, 0);
        let d = &self.gpu.raw.device;
        // SAFETY: recording; the pipeline's layout matches the sets bound; `args` has
        // INDIRECT_BUFFER usage and holds three u32 at `offset` (a multiple of 4), made visible to
        // the indirect read by the barrier after the command that wrote them (MEMORY_WRITE to
        // MEMORY_READ, which includes INDIRECT_COMMAND_READ, over ALL_COMMANDS); the kernel
        // that writes them keeps each count within maxComputeWorkGroupCount (x ≤ 65535).
        unsafe {
            d.cmd_bind_pipeline(self.p.cmd, vk::PipelineBindPoint::COMPUTE, pipeline.pipeline);
            d.cmd_bind_descriptor_sets(
                self.p.cmd,
                vk::PipelineBindPoint::COMPUTE,
                pipeline.layout,
                0,
                &sets,
                &[],
            );
            d.cmd_dispatch_indirect(self.p.cmd, args.buffer, offset);
        }
        self.stamp(timed, 1);
        self.pending.all = true;
        Ok(())
    }

    /// Records one draw of `vertices` (a count, or indirect arguments the device reads) by the graphics `pipeline` (made in
    /// `render_pass`) into `target`, its attachments cleared to `clear`, with `sets`, inside the
    /// recorder's occlusion query when `occlusion` (read by [`Recorder::occlusion`] after a
    /// flush); the viewport has a negative height, so row 0 is the top as on wgpu (NDC y up).
    /// With timestamps, its time counts under `label`. A barrier comes before what may race with it.
    #[expect(clippy::too_many_arguments, reason = "a draw is that many things")]
    pub(crate) fn draw(
        &mut self,
        label: &str,
        pipeline: &Pipeline,
        render_pass: vk::RenderPass,
        target: &Framebuffer,
        clear: &[vk::ClearValue],
        sets: &[SetData<'_>],
        vertices: Vertices<'_>,
        occlusion: bool,
    ) -> Result<(), OitError> {
        self.draws(label, render_pass, target, clear, sets, &[(pipeline.clone(), vertices)], occlusion)
    }

    /// [`Recorder::draw`] of several pipelines in turn in one render pass, each drawing its
    /// vertices; their layouts are one (the same sets), bound once. At least one draw.
    #[expect(clippy::too_many_arguments, reason = "a draw is that many things")]
    pub(crate) fn draws(
        &mut self,
        label: &str,
        render_pass: vk::RenderPass,
        target: &Framebuffer,
        clear: &[vk::ClearValue],
        sets: &[SetData<'_>],
        draws: &[(Pipeline, Vertices<'_>)],
        occlusion: bool,
    ) -> Result<(), OitError> {
        let Some((pipeline, _)) = draws.first() else {
            return Err(OitError::Device("a render pass with no draw".into()));
        };
        debug_assert!(draws.iter().all(|(p, _)| p.layout == pipeline.layout), "one layout");
        let sets = self.sets(pipeline, sets)?;
        self.settle();
        let timed = self.timed(label);
        self.stamp(timed, 0);
        let (w, h) = target.extent;
        let area =
            vk::Rect2D { offset: vk::Offset2D { x: 0, y: 0 }, extent: vk::Extent2D { width: w, height: h } };
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(render_pass)
            .framebuffer(target.framebuffer)
            .render_area(area)
            .clear_values(clear);
        // a window draws the full frame's viewport, shifted: its fragments are the untiled frame's
        let [x, y, vw, vh] = self.window.unwrap_or([0.0, 0.0, w as f32, h as f32]);
        let viewport = vk::Viewport { x, y: y + vh, width: vw, height: -vh, min_depth: 0.0, max_depth: 1.0 };
        let d = &self.gpu.raw.device;
        // SAFETY: recording, outside a render pass; the framebuffer was made for a render pass
        // compatible with `render_pass` at its extent, with one clear value per attachment; the
        // pipeline was made in that render pass, its layout matches the sets; a negative
        // viewport height is core since Vulkan 1.1; the occlusion query is reset (outside the
        // render pass) before it begins, and ends inside the same subpass.
        unsafe {
            if occlusion {
                d.cmd_reset_query_pool(self.p.cmd, self.p.occlusion, 0, 1);
            }
            d.cmd_begin_render_pass(self.p.cmd, &begin, vk::SubpassContents::INLINE);
            // the first pipeline bound before the state that follows (lavapipe faults on a pass
            // whose state was set with no pipeline bound and nothing drawn)
            d.cmd_bind_pipeline(self.p.cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.pipeline);
            d.cmd_bind_descriptor_sets(
                self.p.cmd,
                vk::PipelineBindPoint::GRAPHICS,
                pipeline.layout,
                0,
                &sets,
                &[],
            );
            d.cmd_set_viewport(self.p.cmd, 0, &[viewport]);
            d.cmd_set_scissor(self.p.cmd, 0, &[area]);
            if occlusion {
                d.cmd_begin_query(self.p.cmd, self.p.occlusion, 0, vk::QueryControlFlags::empty());
            }
            for (i, (pipeline, vertices)) in draws.iter().enumerate() {
                if i > 0 {
                    d.cmd_bind_pipeline(self.p.cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.pipeline);
                }
                match vertices {
                    Vertices::Count(0) => {}
                    Vertices::Count(n) => d.cmd_draw(self.p.cmd, *n, 1, 0, 0),
                    // the arguments' buffer has INDIRECT_BUFFER usage and holds four u32
                    // (vertices, 1, 0, 0, or zeros), made visible by the barrier after the
                    // command that wrote them
                    Vertices::Indirect(args) => d.cmd_draw_indirect(self.p.cmd, args.buffer, 0, 1, 16),
                }
            }
            if occlusion {
                d.cmd_end_query(self.p.cmd, self.p.occlusion, 0);
            }
            d.cmd_end_render_pass(self.p.cmd);
        }
        self.stamp(timed, 1);
        self.pending.all = true;
        Ok(())
    }

    /// Records a transition of `image` from an undefined layout to `SHADER_READ_ONLY_OPTIMAL`
    /// (its contents discarded), after everything before it.
    pub(crate) fn make_readable(&mut self, image: &GpuImage) {
        let barrier = vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.image)
            .subresource_range(
                vk::ImageSubresourceRange::default()
                    .aspect_mask(crate::device::aspect(image.format))
                    .level_count(1)
                    .layer_count(1),
            );
        self.counts.barriers += 1;
        // SAFETY: recording, outside a render pass; the image is alive (the frame's) and no
        // command after this reads it before a command that writes it or this transition.
        unsafe {
            self.gpu.raw.device.cmd_pipeline_barrier(
                self.p.cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[barrier],
            );
        }
    }

    /// The samples that passed in the last draw with an occlusion query: flushes first (waits).
    pub(crate) fn occlusion(&mut self) -> Result<u64, OitError> {
        self.flush()?;
        let mut samples = [0u64; 1];
        // SAFETY: the query was reset, begun and ended in the submission just waited for
        // (a draw with `occlusion` came before this call), so its result is available.
        unsafe {
            self.gpu.raw.device.get_query_pool_results(
                self.p.occlusion,
                0,
                &mut samples,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vk_err("reading an occlusion query"))?;
        Ok(samples[0])
    }

    /// Records a copy of the occlusion query's 64-bit result (the last draw with `occlusion` began
    /// and ended it, earlier in this recorder's order) into the first 8 bytes of `dst`, waiting on
    /// the device for it to be available; a barrier comes before what may race with it. No host
    /// wait.
    pub(crate) fn copy_occlusion(&mut self, dst: &Buffer) {
        self.transfer(&[], &[dst.buffer]);
        // SAFETY: recording, outside a render pass; the query of this recorder's pool was reset,
        // begun and ended by an earlier command; dst has TRANSFER_DST usage and holds 8 bytes.
        unsafe {
            self.gpu.raw.device.cmd_copy_query_pool_results(
                self.p.cmd,
                self.p.occlusion,
                0,
                1,
                dst.buffer,
                0,
                8,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            );
        }
    }

    /// Records a copy of `image` (in `TRANSFER_SRC_OPTIMAL`, one 32-bit texel per pixel) into the
    /// start of `dst`, row by row; a barrier comes before what may race with it.
    pub(crate) fn copy_image(&mut self, image: &GpuImage, dst: &Buffer) {
        let (width, height) = image.extent;
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
            )
            .image_extent(vk::Extent3D { width, height, depth: 1 })];
        // the image was last written by a draw, which is not tracked: a barrier comes first
        self.transfer(&[], &[dst.buffer]);
        // SAFETY: recording, outside a render pass; the image has TRANSFER_SRC usage and is in
        // that layout (its render pass's final layout); `dst` has TRANSFER_DST usage and holds
        // width × height × 4 bytes.
        unsafe {
            self.gpu.raw.device.cmd_copy_image_to_buffer(
                self.p.cmd,
                image.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.buffer,
                &region,
            );
        }
    }

    /// Records setting every word of `buffer` to `value`; a barrier comes before what may race
    /// with it.
    pub(crate) fn fill(&mut self, buffer: &Buffer, value: u32) {
        self.transfer(&[], &[buffer.buffer]);
        // SAFETY: recording; the buffer has TRANSFER_DST usage and a size that is a multiple of 4.
        unsafe { self.gpu.raw.device.cmd_fill_buffer(self.p.cmd, buffer.buffer, 0, vk::WHOLE_SIZE, value) };
    }

    /// Records a copy of `bytes` from the start of `src` to the start of `dst`; a barrier comes
    /// before what may race with it.
    pub(crate) fn copy(&mut self, src: &Buffer, dst: &Buffer, bytes: u64) {
        if bytes == 0 {
            return;
        }
        self.transfer(&[src.buffer], &[dst.buffer]);
        let region = [vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes }];
        // SAFETY: recording; src has TRANSFER_SRC, dst TRANSFER_DST usage, both hold `bytes`.
        unsafe { self.gpu.raw.device.cmd_copy_buffer(self.p.cmd, src.buffer, dst.buffer, &region) };
    }

    /// Records a copy of `bytes` from byte `src_offset` of `src` to byte `dst_offset` of `dst`;
    /// a barrier comes before what may race with it.
    pub(crate) fn copy_at(
        &mut self,
        src: &Buffer,
        src_offset: u64,
        dst: &Buffer,
        dst_offset: u64,
        bytes: u64,
    ) {
        self.transfer(&[src.buffer], &[dst.buffer]);
        let region = [vk::BufferCopy { src_offset, dst_offset, size: bytes }];
        // SAFETY: recording; src has TRANSFER_SRC, dst TRANSFER_DST usage, and each holds the
        // range copied (the callers' offsets are within their fixed layouts).
        unsafe { self.gpu.raw.device.cmd_copy_buffer(self.p.cmd, src.buffer, dst.buffer, &region) };
    }

    /// Records an upload of `bytes` into `dst` through a staging buffer kept until the flush.
    pub(crate) fn upload(&mut self, dst: &Buffer, bytes: &[u8]) -> Result<(), OitError> {
        if bytes.is_empty() {
            return Ok(());
        }
        let staging = self.host_buffer(bytes.len() as u64, vk::BufferUsageFlags::TRANSFER_SRC)?;
        staging.write(bytes)?;
        self.copy(&staging, dst, bytes.len() as u64);
        self.keep.push(staging);
        Ok(())
    }

    /// Records an upload of `bytes` into `dst` from byte `offset` on (through a staging buffer).
    pub(crate) fn upload_at(&mut self, dst: &Buffer, offset: u64, bytes: &[u8]) -> Result<(), OitError> {
        if bytes.is_empty() {
            return Ok(());
        }
        let staging = self.host_buffer(bytes.len() as u64, vk::BufferUsageFlags::TRANSFER_SRC)?;
        staging.write(bytes)?;
        self.copy_at(&staging, 0, dst, offset, bytes.len() as u64);
        self.keep.push(staging);
        Ok(())
    }

    /// Reads `buffer` back as u32 words: a copy to a staging buffer, a flush, a map.
    pub(crate) fn read_u32(&mut self, buffer: &Buffer) -> Result<Vec<u32>, OitError> {
        Ok(self.read_u32s(&[buffer])?.pop().unwrap_or_default())
    }

    /// Reads several buffers back with one flush (one wait): a copy of each to a staging buffer
    /// of its own, then the maps, in the order given.
    pub(crate) fn read_u32s(&mut self, buffers: &[&Buffer]) -> Result<Vec<Vec<u32>>, OitError> {
        let reading = self.read_start(buffers)?;
        self.read_wait(reading)
    }

    /// Starts reading `buffers` back: records a copy of each to a staging buffer of its own and
    /// submits, without waiting ([`Recorder::read_wait`] waits and maps). Nothing may be recorded
    /// in between.
    pub(crate) fn read_start(&mut self, buffers: &[&Buffer]) -> Result<Reading, OitError> {
        let mut staging = Vec::with_capacity(buffers.len());
        for b in buffers {
            let s = self.host_buffer(b.size, vk::BufferUsageFlags::TRANSFER_DST)?;
            self.copy(b, &s, b.size);
            staging.push((s, b.size));
        }
        self.submit()?;
        Ok(Reading { staging })
    }

    /// Waits for a [`Recorder::read_start`]'s submission and maps its copies, in the order given.
    pub(crate) fn read_wait(&mut self, reading: Reading) -> Result<Vec<Vec<u32>>, OitError> {
        self.wait()?;
        let words = reading
            .staging
            .iter()
            .map(|(s, size)| {
                // a spare staging buffer may be larger than what was copied into it
                s.read_u32().map(|mut w| {
                    w.truncate((size / 4) as usize);
                    w
                })
            })
            .collect();
        self.spare(reading.staging.into_iter().map(|(s, _)| s));
        words
    }
}

/// The vertices of a draw ([`Recorder::draw`]).
#[derive(Clone, Copy)]
pub(crate) enum Vertices<'b> {
    /// This many, one instance.
    Count(u32),
    /// Four u32 indirect draw arguments in the buffer (a gated pass's: every vertex, or none).
    Indirect(&'b Buffer),
}

/// A readback submitted and not yet waited for ([`Recorder::read_start`]): the staging buffers
/// and how many bytes of each were copied.
pub(crate) struct Reading {
    staging: Vec<(Rc<Buffer>, u64)>,
}

#[cfg(test)]
mod tests {
    use ash::vk::Handle;

    use super::*;

    fn buffers() -> [vk::Buffer; 3] {
        [1, 2, 3].map(vk::Buffer::from_raw)
    }

    #[test]
    fn transfers_on_distinct_buffers_share_a_barrier() {
        let [a, b, c] = buffers();
        let mut p = Pending::default();
        assert!(p.is_empty());
        // a frame's clears: each writes its own buffer
        for w in [a, b, c] {
            assert!(!p.conflicts(&[], &[w]));
            p.add(&[], &[w]);
        }
        assert!(!p.is_empty());
        let mut p = Pending::default();
        p.add(&[a], &[b]);
        // readback copies out of buffers only read since
        assert!(!p.conflicts(&[a], &[c]));
    }

    #[test]
    fn every_hazard_needs_a_barrier() {
        let [a, b, c] = buffers();
        let mut p = Pending::default();
        p.add(&[a], &[b]);
        assert!(p.conflicts(&[b], &[c]), "read after write");
        assert!(p.conflicts(&[], &[b]), "write after write");
        assert!(p.conflicts(&[c], &[a]), "write after read");
        p.clear();
        assert!(p.is_empty() && !p.conflicts(&[b], &[a]), "a barrier settles them");
        // a dispatch or draw: its accesses are not tracked
        p.all = true;
        assert!(p.conflicts(&[], &[c]) && !p.is_empty());
    }
}
