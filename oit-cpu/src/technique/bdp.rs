//! `bdp` and `bdp:P`: bucket depth peeling (Liu et al., HPG 2009, section 3.2).
//!
//! A bounds pass gives each pixel's [zNear, zFar]; a capture pass routes every fragment by its
//! depth to one of the pixel's buckets, updated with MAX so concurrent fragments never race.
//!
//! - **Colour mode** (one pass, transparency): 32 uniform subintervals, each bucket keeping the
//!   MAX of [`bdp_pack_color`] — a collision keeps one fragment (the most opaque), the rest are
//!   lost. 32 words per pixel.
//! - **Depth mode**: 16 uniform subintervals, each a pair of buckets keeping the nearest and the
//!   farthest fragment (the paper's MAX of (1 − d, d), eq. 2–4). The paper stores the bare depths;
//!   here each bucket is 64 bits, the depth's bits above the fragment's payload word, so the colour
//!   (or normal) of the kept fragment travels with it. Pass p of `bdp:P` discards fragments with
//!   d ≤ dmin or d ≥ dmax of their subinterval in pass p − 1 (eq. 5) and so keeps the next
//!   nearest and farthest; after P passes subinterval k reads min₁ … min_P, max_P … max₁.
//!   A min and max of equal depth (two colours) are ordered by colour: counted in `tied`.

use oit_core::Compositor as _;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use oit_core::rules::{
    BDP_COLOR_SUBINTERVALS, BDP_DEPTH_SUBINTERVALS, BDP_EMPTY_MIN, bdp_eq5_next, bdp_pack_color,
    bdp_unpack_color, bucket_index, bucket_midpoint, depth_bits, depth_key64, split_key64,
};
use oit_core::{BucketArray, Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use crate::storage::Buckets;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let color_mode = ctx.plan.bdp_color;
    let bounds = ctx.depth_bounds()?;
    if color_mode { color(ctx, &bounds) } else { depth(ctx, &bounds) }
}

fn color(ctx: &mut Ctx<'_>, bounds: &[(f32, f32)]) -> Result<Frame, OitError> {
    let n = BDP_COLOR_SUBINTERVALS as usize;
    let mut buckets = Buckets::new(ctx.alloc32(n, 0)?, n);
    // colour mode is transparency's: every fragment's colour is read, so made ahead; each
    // pixel's 32 buckets (two cache lines) asked for a few fragments before their turn
    let ahead = |px: u32| crate::raster::prefetch(buckets.of_pixel(px as usize));
    let shared = &*ctx;
    let generated = ctx.raster.for_each_shaded_fragment_ahead(&ahead, |f| {
        let px = f.pixel as usize;
        let (zn, zf) = bounds[px];
        let k = bucket_index(f.depth, zn, zf, BDP_COLOR_SUBINTERVALS) as usize;
        let word = bdp_pack_color(oit_core::rules::pack_rgba8(f.color()));
        // a full bucket: one of the two fragments is gone; a zero word is never read back
        if buckets.update_max(px, k, word) != 0 || word == 0 {
            shared.lose(px);
        }
    });
    ctx.ran_pass(generated);
    let mut states = ctx.states();
    let resolve = &ctx.resolve;
    // each pixel's buckets read and emptied whole, by plain loads and stores several at a time
    // (most pixels' are all empty: nothing else is done for them), so the next frame lends the
    // array without a sweep
    states.par_iter_mut().zip(bounds.par_iter()).zip(buckets.words_mut().par_chunks_mut(n)).for_each(
        |((s, &(zn, zf)), words)| {
            let mut taken = [0u32; BDP_COLOR_SUBINTERVALS as usize];
            for (t, w) in taken.iter_mut().zip(words.iter_mut()) {
                *t = *w.get_mut();
            }
            if taken.iter().fold(0, |any, &v| any | v) == 0 {
                return;
            }
            for w in words.iter_mut() {
                *w.get_mut() = 0;
            }
            for (k, &v) in taken.iter().enumerate() {
                if v != 0 {
                    // The bucket's subinterval midpoint stands for its depth.
                    let d = bucket_midpoint(k as u32, n as u32, zn, zf);
                    resolve.push(s, d, bdp_unpack_color(v));
                }
            }
        },
    );
    buckets.mark_empty();
    Ok(super::finish(ctx, states))
}

fn depth(ctx: &mut Ctx<'_>, bounds: &[(f32, f32)]) -> Result<Frame, OitError> {
    let n = BDP_DEPTH_SUBINTERVALS as usize;
    // One bucket array per pass, as the paper allocates new MRTs per pass: [min, max] per subinterval.
    let mut arrays: Vec<crate::pool::Pooled<'_, AtomicU64>> = Vec::new();
    // P passes, or fewer under --max-peels: the plan's stop rule
    let passes = ctx.plan.bdp_capture_passes();
    // Per pixel: fragments a pass skipped at the depths the previous pass kept (ties), plus, in the
    // last pass, those it routed to a subinterval (all but the kept min and max stay behind).
    let seen = ctx.pool.u32s(ctx.pixels, 0);
    // Fragments an array kept for a pixel: a min, and a max unless it is the same key.
    let kept = |array: &[AtomicU64], px: usize| -> u32 {
        (0..n)
            .map(|k| {
                let slot = px * 2 * n + 2 * k;
                let (lo, hi) = (array[slot].load(Relaxed), array[slot + 1].load(Relaxed));
                if lo == BDP_EMPTY_MIN {
                    0
                } else if hi == lo {
                    1
                } else {
                    2
                }
            })
            .sum()
    };
    for pass in 0..passes {
        let last = pass + 1 == passes;
        let array = ctx.alloc_min_max(2 * n)?;
        {
            let previous = arrays.last();
            let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
            let generated = ctx.raster.for_each_fragment(|f| {
                let px = f.pixel as usize;
                let (zn, zf) = bounds[px];
                let k = bucket_index(f.depth, zn, zf, BDP_DEPTH_SUBINTERVALS) as usize;
                let slot = px * 2 * n + 2 * k;
                if let Some(prev) = previous {
                    let (lo, hi) = (prev[slot].load(Relaxed), prev[slot + 1].load(Relaxed));
                    let d = depth_bits(f.depth);
                    // eq. 5: what the previous pass kept, or anything outside its range, is done
                    if !bdp_eq5_next(d, lo, hi) {
                        // at a depth the previous pass kept: kept then, or a tie eq. 5 skips
                        if lo != BDP_EMPTY_MIN && (d == (lo >> 32) as u32 || d == (hi >> 32) as u32) {
                            seen[px].fetch_add(1, Relaxed);
                        }
                        return;
                    }
                }
                let key = depth_key64(f.depth, payload(f));
                array[slot].fetch_min(key, Relaxed);
                array[slot + 1].fetch_max(key, Relaxed);
                if last {
                    seen[px].fetch_add(1, Relaxed);
                }
            });
            ctx.ran_pass(generated);
            let ctx_ref = &*ctx;
            (0..ctx.pixels).into_par_iter().with_min_len(1 << 12).for_each(|px| {
                // nothing seen, nothing lost: the buckets of most pixels are not read
                let seen = crate::storage::take_u32(&seen[px], 0);
                if seen > 0 {
                    let taken =
                        previous.map_or(0, |prev| kept(prev, px)) + if last { kept(&array, px) } else { 0 };
                    ctx_ref.settle_ties(px, seen, taken);
                }
            });
        }
        arrays.push(array);
    }
    let resolve = &ctx.resolve;
    // one list of back layers per rayon task, not one per pixel and bucket; each pair read is
    // reset to empty while in cache, so the next frame takes the arrays without a sweep (a pass
    // writes a subinterval only where the previous pass's is written (eq. 5), so the first empty
    // pair of the passes ends the written ones)
    let frame = super::finish_with(ctx, |px, backs: &mut Vec<(f32, u32)>, s| {
        for k in 0..n {
            let slot = px * 2 * n + 2 * k;
            backs.clear();
            for array in &arrays {
                let (lo, hi) = (array[slot].load(Relaxed), array[slot + 1].load(Relaxed));
                if lo == BDP_EMPTY_MIN {
                    break;
                }
                array[slot].store(BDP_EMPTY_MIN, Relaxed);
                array[slot + 1].store(0, Relaxed);
                let (d, p) = split_key64(lo);
                resolve.push(s, d, p);
                if hi != lo {
                    backs.push(split_key64(hi));
                }
            }
            for &(d, p) in backs.iter().rev() {
                resolve.push(s, d, p);
            }
        }
    });
    for array in &mut arrays {
        array.mark_clean(crate::pool::Clean::EmptyMinMax);
    }
    Ok(frame)
}
