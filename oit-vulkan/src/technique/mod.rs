//! One file per technique, each the twin of oit-wgpu's `src/technique/*.rs`: the same buffers,
//! passes, kernels and readbacks, on the same WGSL (compiled to SPIR-V by `build.rs`; the module
//! names here are `build.rs`'s).

pub(crate) mod adp;
pub(crate) mod bdp;
pub(crate) mod blend;
pub(crate) mod ddp;
pub(crate) mod dfb;
pub(crate) mod dp;
pub(crate) mod fabs;
pub(crate) mod kbuf;
pub(crate) mod ll;
pub(crate) mod mdts;
pub(crate) mod mlp;
pub(crate) mod plain;
pub(crate) mod reference;
pub(crate) mod weighted;

use std::rc::Rc;

use oit_core::OitError;

use crate::ctx::{Init, VkCtx};
use crate::device::Buffer;
use crate::raster::Raster;

/// The buffers of `tail.wgsl` (`--overflow tail`), as oit-wgpu's `tail_buffers`: the tail sums
/// and two bookkeeping words, or placeholders where the plan has no tail.
pub(crate) fn tail_buffers(ctx: &mut VkCtx<'_>) -> Result<(Rc<Buffer>, Rc<Buffer>), OitError> {
    if !ctx.plan.tail {
        return Ok((ctx.placeholder()?, ctx.placeholder()?));
    }
    let sums = ctx.buffer("tail sums", u64::from(ctx.pixels) * 5 * 2, Init::Zero)?;
    let words = ctx.buffer("tail words", 2, Init::Zero)?;
    ctx.storage_bytes -= 8;
    Ok((sums, words))
}

/// A peel loop (dp, ddp, mlp), as oit-wgpu's `technique::peel`: per pass `module`'s geometry pass
/// (pass index p) and its `resolve_main` (pass index p + `resolve_step`), with `flag` cleared
/// before each pass and set by it where the pass found more to peel; the loop ends after the pass
/// that leaves it clear, or at the plan's peel limit.
///
/// With no speculated count the flag is read back after each pass (one round trip a peel), and
/// the count found is kept for the next frame (`ctx::ReadBack`). With one (an earlier frame's
/// count), every pass after the first is gated on the device by its predecessor's flag
/// (`VkCtx::geometry_pass_if`: a closed gate runs nothing and counts no pass), and the last
/// speculated pass's flag is checked at the frame's end: set, the frame ran too few passes and
/// runs again without speculating. A raster without a gate (the host's setup) always reads back.
pub(crate) fn peel(
    ctx: &mut VkCtx<'_>,
    raster: &Raster,
    module: &'static str,
    buffers: &[&Buffer],
    flag: &Rc<Buffer>,
    param: u32,
    resolve_step: u32,
) -> Result<(), OitError> {
    let limit = ctx.plan.peel_limit;
    let gate = raster.gate().is_some();
    let speculated = ctx.speculated.peels.take().filter(|&s| s >= 1 && gate).map(|s| s.min(limit));
    let previous = match speculated {
        Some(_) => {
            let b = ctx.buffer("peel gate", 1, Init::Zero)?;
            // bookkeeping, not per-pixel storage
            ctx.storage_bytes -= 4;
            Some(b)
        }
        None => {
            if gate {
                ctx.make_gate_pipeline()?;
            }
            None
        }
    };
    let mut p = 0;
    while p < limit {
        ctx.last_pass(p + 1 == limit);
        match &previous {
            Some(prev) if p > 0 => {
                ctx.copy(flag, prev, 4);
                ctx.fill(flag, 0);
                ctx.geometry_pass_if(raster, module, buffers, p, param, prev)?;
            }
            _ => {
                ctx.fill(flag, 0);
                ctx.geometry_pass(raster, module, buffers, p, param)?;
            }
        }
        ctx.pixel_kernel(module, "resolve_main", buffers, p + resolve_step, param)?;
        p += 1;
        match speculated {
            Some(s) if p == s => {
                if p < limit {
                    // the last speculated pass must have found nothing more
                    ctx.check_at_end(flag);
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
        ctx.note_peels(p);
    }
    ctx.last_pass(false);
    Ok(())
}

/// Fragments per pixel from one counting pass (the buffer), and the deepest pixel's count (an
/// earlier frame's where it speculates, checked at the end: `VkCtx::deepest`).
pub(crate) fn count(ctx: &mut VkCtx<'_>, raster: &Raster) -> Result<(Rc<Buffer>, u32), OitError> {
    let counts = ctx.buffer("fragment counts", u64::from(ctx.pixels), Init::Zero)?;
    let max = ctx.buffer("max count", 1, Init::Zero)?;
    ctx.geometry_pass(raster, "count", &[&counts, &max], 0, 0)?;
    ctx.pixel_kernel("count", "max_main", &[&counts, &max], 0, 0)?;
    // sizing storage is not the technique's: oit-cpu does not count it either
    ctx.storage_bytes -= u64::from(ctx.pixels) * 4 + 4;
    let m = ctx.deepest(&max)?;
    Ok((counts, m))
}

/// Words of one block of `scan.wgsl` (64 invocations × 4 words).
const SCAN_BLOCK: u64 = 256;

/// An exclusive prefix sum of the first `n` words of `words`, in place, on the GPU (`scan.wgsl`,
/// as oit-wgpu's `technique::scan`: each block scanned in its workgroup, the block totals scanned
/// the same way, one level per 256× fewer words, then added back); returns the buffer whose word
/// 0 holds the total (the top level's one block total), on the device.
pub(crate) fn scan(ctx: &mut VkCtx<'_>, words: &Buffer, n: u64) -> Result<Rc<Buffer>, OitError> {
    let blocks = n.div_ceil(SCAN_BLOCK).max(1);
    let param = u32::try_from(n).map_err(|_| OitError::Device(format!("a prefix sum over {n} words")))?;
    let sums = ctx.buffer("scan block sums", blocks, Init::Zero)?;
    ctx.storage_bytes -= blocks * 4;
    ctx.kernel_over("scan", "scan_main", &[words, &sums], blocks * 64, 0, param, "scan")?;
    if blocks == 1 {
        return Ok(sums);
    }
    let total = scan(ctx, &sums, blocks)?;
    ctx.kernel_over("scan", "add_main", &[words, &sums], blocks * 64, 0, param, "scan")?;
    Ok(total)
}
