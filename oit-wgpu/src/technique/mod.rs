//! One file per technique, next to its WGSL: the same passes, storage and resolve as oit-cpu's
//! `technique/*.rs`, on GPU buffers.

pub(crate) mod adp;
pub(crate) mod bdp;
pub(crate) mod bdp_blend;
pub(crate) mod blend;
pub(crate) mod ddp;
pub(crate) mod ddp_blend;
pub(crate) mod dfb;
pub(crate) mod dp;
pub(crate) mod dp_depth;
pub(crate) mod fabs;
pub(crate) mod ll;
pub(crate) mod mdts;
pub(crate) mod mlp;
pub(crate) mod plain;
pub(crate) mod reference;
pub(crate) mod weighted;

use oit_core::OitError;

use crate::ctx::{Driver, Gate, GpuCtx, Init};
use crate::hardware::Occlusion;

const COUNT_WGSL: &str = include_str!("count.wgsl");
const SCAN_WGSL: &str = include_str!("scan.wgsl");
/// Words one workgroup of `scan.wgsl` scans.
const SCAN_BLOCK: u64 = 256;

/// The buffers of `tail.wgsl` (`--overflow tail`), bound at 6 and 7: the tail sums (5 u64 a pixel,
/// `Plan::arrays`'s "tail sums") and two bookkeeping words (overflowed, merged; not storage);
/// placeholders where the plan has no tail.
pub(crate) fn tail_buffers(ctx: &mut GpuCtx<'_>) -> Result<(wgpu::Buffer, wgpu::Buffer), OitError> {
    if !ctx.plan.tail {
        return Ok((ctx.placeholder(), ctx.placeholder()));
    }
    let sums = ctx.buffer("tail sums", u64::from(ctx.pixels) * 5 * 2, Init::Zero)?;
    let words = ctx.buffer("tail words", 2, Init::Zero)?;
    ctx.storage_bytes -= 8;
    Ok((sums, words))
}

/// The peel loop of dp, ddp and mlp: until a pass leaves word 0 of `flag` at zero (nothing
/// peeled, or for mlp nothing overflowed) or the plan's limit, each pass `flag` cleared, the
/// geometry pass (pass index p, `param`), then the resolve kernel (pass index `p + resolve_step`).
///
/// Where the frame has a speculated pass count (a prepared scene's last frame of this view's
/// kind, [`GpuCtx::speculated_peels`]) it records that many passes with no round trip: each after
/// the first gated on the flag its predecessor left (a pass that would not have run does
/// nothing, and is not counted), and the flag checked at the frame's end, where a frame that
/// needed more passes runs again. Without one, the flag is read after each pass, and the count
/// kept for the next frame ([`GpuCtx::peels_seen`]).
pub(crate) fn peel(
    ctx: &mut GpuCtx<'_>,
    driver: &dyn Driver,
    wgsl: &str,
    buffers: &[&wgpu::Buffer],
    flag: &wgpu::Buffer,
    param: u32,
    resolve_step: u32,
) -> Result<(), OitError> {
    let limit = ctx.plan.peel_limit;
    let speculated = ctx.speculated_peels.take().filter(|&s| s >= 1).map(|s| s.min(limit));
    let previous = match speculated {
        Some(_) => Some(ctx.buffer("peel gate", 1, Init::Zero)?),
        None => None,
    };
    if previous.is_some() {
        // bookkeeping, not per-pixel storage
        ctx.storage_bytes -= 4;
    }
    let mut p = 0;
    while p < limit {
        ctx.last_pass(p + 1 == limit);
        match (&previous, speculated) {
            (Some(prev), Some(_)) if p > 0 => {
                ctx.encoder().copy_buffer_to_buffer(flag, 0, prev, 0, 4);
                ctx.fill(flag, 0)?;
                ctx.geometry_pass_if(driver, wgsl, buffers, p, param, prev)?;
            }
            _ => {
                ctx.fill(flag, 0)?;
                ctx.geometry_pass(driver, wgsl, buffers, p, param)?;
            }
        }
        ctx.pixel_kernel(wgsl, "resolve_main", buffers, p + resolve_step, param)?;
        p += 1;
        match speculated {
            Some(s) if p == s => {
                if p < limit {
                    // the last speculated pass must have found nothing more
                    ctx.check_at_end(flag, 0);
                }
                break;
            }
            Some(_) => {}
            None => {
                if ctx.read_u32(flag)?[0] == 0 {
                    break;
                }
            }
        }
    }
    if speculated.is_none() {
        ctx.peels_seen = Some(p);
    }
    ctx.last_pass(false);
    Ok(())
}

/// The pass count of the blend captures' peel loops (`dp_depth`, `ddp_blend`), which end at the
/// first pass whose occlusion query saw no sample. As [`peel`] does for the atomics captures:
/// where the frame has a speculated pass count and the raster a gate, that many passes are
/// recorded with no round trip, each after the first gated on the query of the one before
/// (folded into a flag on the device), and the last pass's query checked at the frame's end (a
/// frame that needed more passes runs again). Else the query is read after each pass and the
/// count kept for the next frame.
pub(crate) struct OcclusionPeel {
    /// The most passes the loop may run.
    cap: u32,
    /// The speculated count, the flag folded from the last query and the raster's gate.
    speculated: Option<(u32, wgpu::Buffer, Gate)>,
}

impl OcclusionPeel {
    pub(crate) fn new(ctx: &mut GpuCtx<'_>, driver: &dyn Driver, cap: u32) -> Result<Self, OitError> {
        let speculated = match (ctx.speculated_peels.take().filter(|&s| s >= 1), driver.gate()) {
            (Some(s), Some(gate)) => {
                let flag = ctx.buffer("peel gate", 1, Init::Zero)?;
                // bookkeeping, not per-pixel storage
                ctx.storage_bytes -= 4;
                Some((s.min(cap), flag, gate))
            }
            _ => None,
        };
        Ok(OcclusionPeel { cap, speculated })
    }

    /// Before pass `run` (from 0): the gated draw arguments it draws with, where it is gated.
    pub(crate) fn gate(&self, ctx: &mut GpuCtx<'_>, run: u32) -> Result<Option<wgpu::Buffer>, OitError> {
        match &self.speculated {
            Some((_, flag, gate)) if run > 0 => {
                ctx.open_gate(flag, gate)?;
                Ok(Some(gate.to.clone()))
            }
            _ => Ok(None),
        }
    }

    /// After `run` passes, the last one's query in `occlusion`: whether the loop goes on.
    pub(crate) fn go_on(
        &self,
        ctx: &mut GpuCtx<'_>,
        occlusion: &Occlusion,
        run: u32,
    ) -> Result<bool, OitError> {
        match &self.speculated {
            Some((s, flag, _)) => {
                ctx.fold_occlusion(occlusion.buffer(), flag)?;
                if run < *s {
                    return Ok(true);
                }
                if run < self.cap {
                    // the last speculated pass must have seen nothing
                    ctx.check_at_end(flag, 0);
                }
                Ok(false)
            }
            None => {
                let drew = run < self.cap && occlusion.drew(ctx)?;
                if !drew {
                    ctx.peels_seen = Some(run);
                }
                Ok(drew)
            }
        }
    }
}

/// Fragments per pixel from one counting pass (the buffer), and the deepest pixel's count.
pub(crate) fn count(ctx: &mut GpuCtx<'_>, driver: &dyn Driver) -> Result<(wgpu::Buffer, u32), OitError> {
    let counts = ctx.buffer("fragment counts", u64::from(ctx.pixels), Init::Zero)?;
    let max = ctx.buffer("max count", 1, Init::Zero)?;
    ctx.geometry_pass(driver, COUNT_WGSL, &[&counts, &max], 0, 0)?;
    ctx.pixel_kernel(COUNT_WGSL, "max_main", &[&counts, &max], 0, 0)?;
    // sizing storage is not the technique's: oit-cpu does not count it either
    ctx.storage_bytes -= u64::from(ctx.pixels) * 4 + 4;
    let m = ctx.deepest(&max)?;
    Ok((counts, m))
}

/// The exclusive prefix sum of the first `n` words of `words`, in place, on the GPU
/// (`scan.wgsl`): each block of 256 words scanned by one workgroup, the blocks' totals scanned
/// the same way one level up, and added back. Returns the buffer whose word 0 holds the total
/// (the top level's one block total), on the device: [`GpuCtx::fragment_capacity`] sizes from it
/// without a round trip where an earlier frame counted. The block totals are bookkeeping, not
/// counted in `storage_bytes` (the plan's figure leaves them out likewise).
pub(crate) fn scan(ctx: &mut GpuCtx<'_>, words: &wgpu::Buffer, n: u64) -> Result<wgpu::Buffer, OitError> {
    let blocks = n.div_ceil(SCAN_BLOCK).max(1);
    let param = u32::try_from(n).map_err(|_| OitError::Device(format!("a prefix sum over {n} words")))?;
    let sums = ctx.buffer("scan block sums", blocks, Init::Zero)?;
    ctx.storage_bytes -= blocks * 4;
    ctx.kernel_over(SCAN_WGSL, "scan_main", &[words, &sums], blocks * 64, 0, param, "scan")?;
    if blocks == 1 {
        return Ok(sums);
    }
    let total = scan(ctx, &sums, blocks)?;
    ctx.kernel_over(SCAN_WGSL, "add_main", &[words, &sums], blocks * 64, 0, param, "scan")?;
    Ok(total)
}

/// Group 1 of a resolve that reads a blend capture's render targets: `views` as unfilterable
/// float textures at bindings `first`, `first + 1`, ... (bdp's 8 bucket targets, plain's and the
/// weighted blends' colour and count targets).
pub(crate) fn targets_group(
    device: &wgpu::Device,
    label: &str,
    first: u32,
    views: &[&wgpu::TextureView],
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0..views.len() as u32)
        .map(|i| wgpu::BindGroupLayoutEntry {
            binding: first + i,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        })
        .collect();
    let layout = device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &views
            .iter()
            .enumerate()
            .map(|(i, view)| wgpu::BindGroupEntry {
                binding: first + i as u32,
                resource: wgpu::BindingResource::TextureView(view),
            })
            .collect::<Vec<_>>(),
    });
    (layout, group)
}
