//! `dfb`: the dynamic fragment buffer (Maule et al., "Memory-Efficient Order-Independent
//! Transparency with Dynamic Fragment Buffer", SIBGRAPI 2012). Exact allocation: a counting pass
//! gives each pixel its fragment count, an exclusive prefix sum turns the counts into per-pixel
//! offsets into one buffer of exactly the frame's fragments, a fill pass writes each fragment into
//! its pixel's range, and the resolve sorts each range by (depth, primitive id) and composites it.
//!
//! Storage, all of it sized from the count: a count and an offset a pixel (each array one entry
//! longer: the offsets end in the total), and 12 bytes a fragment, the 64-bit key (depth bits,
//! primitive id) and the 32-bit payload, as `fabs`'s slots. So ties come out in primitive order,
//! as the reference orders them, and `tied` stays 0.
//!
//! The fill takes each fragment's entry by atomic decrement of its pixel's count, filling the
//! range from its end: the counts double as the fill cursors, and a pixel that met more fragments
//! in the fill than in the count (a rasterizer that is not repeatable) finds its count spent and
//! counts the fragment in `lost`, where it happens, instead of writing into its neighbour's range.
//! One that met fewer leaves the start of its range unwritten; the resolve skips it. Neither
//! happens with oit's rasterizers, whose passes are repeatable; `captured + lost == fragments`
//! (`tests/tests/accounting.rs`) would catch both.
//!
//! oit-wgpu's `technique/dfb.rs` runs the same passes, with the prefix sum on the GPU.

use oit_core::Compositor as _;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use oit_core::plan::Counted;
use oit_core::rules::{depth_bits, depth_from_bits};
use oit_core::{Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use crate::storage::sort_keys;

/// Pixels per chunk of the parallel prefix sum.
const SCAN_CHUNK: usize = 1 << 16;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let entries = ctx.pixels as u64 + 1;
    // pass 1: fragments per pixel (the last entry stays 0)
    let counts = ctx.words32(entries, 0)?;
    ctx.pass(|f| {
        counts[f.pixel as usize].fetch_add(1, Relaxed);
    });
    // the exclusive prefix sum: offsets[px] is the first entry of pixel px, offsets[pixels] the total
    let offsets = ctx.words32(entries, 0)?;
    let total = ctx.plan.check_fragments(exclusive_prefix_sum(&counts, &offsets))?;
    let deepest = counts.iter().map(|c| c.load(Relaxed)).max().unwrap_or(0);
    ctx.check_counted(Counted { deepest, fragments: u64::from(total) })?;
    let keys = ctx.words64(u64::from(total), 0)?;
    let payloads = ctx.words32(u64::from(total), 0)?;
    // pass 2: each fragment takes the last free entry of its pixel's range
    ctx.pass_lossy(|f, ctx| {
        let px = f.pixel as usize;
        let left = counts[px].fetch_sub(1, Relaxed);
        // read as signed, as dfb.wgsl does: a spent count goes below zero
        if left as i32 <= 0 {
            // no entry left for this fragment
            ctx.lose(px);
            return;
        }
        let entry = (offsets[px].load(Relaxed) + left - 1) as usize;
        keys[entry].store(u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim), Relaxed);
        payloads[entry].store(ctx.payload(f), Relaxed);
    });
    let resolve = &ctx.resolve;
    Ok(super::finish_with(ctx, |px, list: &mut Vec<u128>, s| {
        // entries the fill did not reach (a count it did not spend) are left out
        let unfilled = (counts[px].load(Relaxed) as i32).max(0) as u32;
        let start = (offsets[px].load(Relaxed) + unfilled) as usize;
        let end = offsets[px + 1].load(Relaxed) as usize;
        list.clear();
        // (depth bits, primitive id) above the payload: one primitive has one fragment a pixel,
        // so the payload never decides
        list.extend(
            (start..end)
                .map(|i| u128::from(keys[i].load(Relaxed)) << 32 | u128::from(payloads[i].load(Relaxed))),
        );
        sort_keys(list);
        for &key in list.iter() {
            resolve.push(s, depth_from_bits((key >> 64) as u32), key as u32);
        }
    }))
}

/// Writes the exclusive prefix sum of `counts` into `offsets` (the same length) and returns the
/// total: chunk totals in parallel, their prefix serially, then each chunk's offsets in parallel.
/// A total past 32 bits is returned, not written: the caller refuses it
/// ([`oit_core::plan::Plan::check_fragments`]).
fn exclusive_prefix_sum(counts: &[AtomicU32], offsets: &[AtomicU32]) -> u64 {
    let sums: Vec<u64> =
        counts.par_chunks(SCAN_CHUNK).map(|c| c.iter().map(|n| u64::from(n.load(Relaxed))).sum()).collect();
    let mut starts = Vec::with_capacity(sums.len());
    let mut total = 0u64;
    for s in sums {
        starts.push(total);
        total += s;
    }
    if total <= u64::from(u32::MAX) {
        counts.par_chunks(SCAN_CHUNK).zip(offsets.par_chunks(SCAN_CHUNK)).zip(starts).for_each(
            |((counts, offsets), start)| {
                let mut run = start as u32;
                for (n, o) in counts.iter().zip(offsets) {
                    o.store(run, Relaxed);
                    run += n.load(Relaxed);
                }
            },
        );
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix_sum_is_exclusive_and_spans_chunks() {
        let n = SCAN_CHUNK * 2 + 3;
        let counts: Vec<AtomicU32> = (0..n).map(|i| AtomicU32::new((i % 5) as u32)).collect();
        let offsets: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(7)).collect();
        let total = exclusive_prefix_sum(&counts, &offsets);
        let mut run = 0u32;
        for (i, offset) in offsets.iter().enumerate() {
            assert_eq!(offset.load(Relaxed), run, "entry {i}");
            run += (i % 5) as u32;
        }
        assert_eq!(total, u64::from(run));
    }
}
