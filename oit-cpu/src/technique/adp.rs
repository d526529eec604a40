//! `adp`: adaptive bucket depth peeling (Liu et al., HPG 2009, section 3.3).
//!
//! 1. Bounds pass: each pixel's [zNear, zFar].
//! 2. Histogram pass: 1024 uniform bins over the range, one presence bit each (32 × u32 per
//!    pixel, set with atomic OR — the paper's logic-op OR into 8 RGBA32UI targets).
//! 3. Equalization: the set bins, in depth order, become the subintervals; the fragment in the
//!    j-th set bin goes to bucket j mod 32 of batch ⌊j/32⌋ ([`histogram_rank`]).
//! 4. One bucket pass per batch of 32 subintervals, until every set bin was captured: passes =
//!    2 + ⌈bins/32⌉ for the deepest pixel.
//!
//! Two fragments closer than 1/1024 of the range can share a bin (the paper keeps one: MAX on the
//! 64-bit (depth, payload) word). Here each bucket also keeps the MIN of its bin's words in the
//! same pass (issue 11.5, the two ends of a subinterval as HPG 2009's depth mode of `bdp` keeps
//! them, eq. 2–4): a bin of two fragments is captured whole, nearest first; of three or more, the
//! ones between its nearest and farthest are counted in `lost` (each fragment that finds its
//! bucket's MAX already filled is counted lost at capture; the resolve takes one back where the MIN
//! holds a second fragment). Two fragments of one bin at equal depths come out by payload, not by
//! primitive id: the resolve counts them in `tied`.

use oit_core::Compositor as _;
use oit_core::rules::{BUCKETS, HISTOGRAM_WORDS, depth_key64, histogram_bin, split_key64};
use oit_core::{BucketArray, DepthHistogram, Frame, OitError};
use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;

use super::Ctx;
use crate::storage::{Buckets, Histogram};

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let bounds = ctx.depth_bounds()?;
    let mut histogram = Histogram::new(ctx.alloc32(HISTOGRAM_WORDS, 0)?);
    // Each pixel's set bins, counted as they are set: the batches come from the deepest pixel,
    // and batch b fills buckets 0 .. min(32, bins − 32·b) of a pixel and no other, so each
    // batch's resolve reads those and skips the rest (most pixels have a few bins, the
    // background none: reading all 32 buckets and 32 nearest keys of every pixel was 128 MiB a
    // batch). The histogram stays where the pass set it (a copy was a fresh 32 MiB every frame,
    // faulted in page by page).
    let bins = ctx.pool.u32s(ctx.pixels, 0);
    ctx.pass(|f| {
        let px = f.pixel as usize;
        let (zn, zf) = bounds[px];
        if histogram.set(px, histogram_bin(f.depth, zn, zf)) {
            bins[px].fetch_add(1, Relaxed);
        }
    });
    let deepest = bins.par_iter().map(|n| n.load(Relaxed)).max().unwrap_or(0);
    let batches = ctx.plan.adp_batches(deepest);
    let mut buckets = Buckets::new(ctx.alloc64(BUCKETS, 0)?, BUCKETS);
    let mut nearest = ctx.alloc64(BUCKETS, u64::MAX)?;
    let mut states = ctx.states();
    for batch in 0..batches {
        let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
        let histogram = &histogram;
        let lost = &*ctx;
        let generated = ctx.raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            let (zn, zf) = bounds[px];
            let rank = histogram.rank(px, histogram_bin(f.depth, zn, zf));
            if rank / BUCKETS as u32 == batch {
                let bucket = (rank % BUCKETS as u32) as usize;
                let key = depth_key64(f.depth, payload(f));
                // bit 63 marks a full bucket, so a fragment at depth 0 with payload 0 is not empty
                let old = buckets.update_max(px, bucket, key | 1 << 63);
                // the nearest of the bin (a depth key never has all bits set: depths are ≤ 1)
                nearest[px * BUCKETS + bucket].fetch_min(key, Relaxed);
                // two fragments in one bin: the MAX kept one (the resolve takes one back where
                // the MIN kept another)
                if old != 0 {
                    lost.lose(px);
                }
            } else if rank / BUCKETS as u32 >= batches && batch + 1 == batches {
                // beyond the last batch the plan allows (--max-peels)
                lost.lose(px);
            }
        });
        ctx.ran_pass(generated);
        let resolve = &ctx.resolve;
        let buckets = &buckets;
        let (nearest, lost) = (&nearest, &ctx.lost);
        let bins = &bins;
        states.par_iter_mut().enumerate().for_each(|(px, s)| {
            let filled = bins[px].load(Relaxed).saturating_sub(batch * BUCKETS as u32).min(BUCKETS as u32);
            for k in 0..filled as usize {
                let key = buckets.take(px, k);
                let near = crate::storage::take_u64(&nearest[px * BUCKETS + k], u64::MAX);
                if key != 0 {
                    let far = key & !(1 << 63);
                    if near != far {
                        // a second fragment of the bin, in front of the farthest: captured after all
                        let (d, p) = split_key64(near);
                        resolve.push(s, d, p);
                        lost[px].fetch_sub(1, Relaxed);
                    }
                    let (d, p) = split_key64(far);
                    resolve.push(s, d, p);
                }
            }
        });
    }
    // the histograms emptied where a bin was set, so the next frame lends the array without a
    // sweep
    (0..ctx.pixels).into_par_iter().with_min_len(1 << 12).for_each(|px| {
        if bins[px].load(Relaxed) > 0 {
            histogram.take(px);
        }
    });
    histogram.mark_empty();
    // every batch's resolve took every bucket and every nearest key its batch could have
    // written (and with no batch none was written): both are as they were lent
    buckets.mark_empty();
    nearest.mark_clean(crate::pool::Clean::Word(u64::MAX));
    Ok(super::finish(ctx, states))
}
