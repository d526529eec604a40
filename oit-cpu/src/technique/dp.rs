//! `dp`: classical depth peeling (Everitt 2001; front-to-back under blending as in Bavoil & Myers
//! 2008). Each geometry pass keeps, per pixel, the nearest fragment strictly behind the layer the
//! previous pass peeled — an atomic min on (depth, colour) stands in for the depth test against
//! the previous depth buffer — and composites it under the layers before. The pass that peels
//! nothing plays the role of the occlusion query that ends the loop: N + 1 passes for N layers.
//!
//! Strictly behind means that of two fragments at one depth, one is peeled and the other never
//! is: the loss is counted in `lost`. (The one peeled is the smaller payload, not the smaller
//! primitive id; the resolve would count consecutive equal depths in `tied`, but dp never peels
//! two.)

use oit_core::Compositor as _;
use std::sync::atomic::Ordering::Relaxed;

use oit_core::rules::{depth_bits, depth_key64, split_key64};
use oit_core::{Frame, OitError};
use rayon::prelude::*;

use super::Ctx;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    if ctx.plan.sample_peel {
        return render_samples(ctx);
    }
    const EMPTY: u64 = u64::MAX;
    let nearest = ctx.alloc64(1, EMPTY)?;
    // Depth bits of the last peeled layer; u64 so "nothing peeled yet" sits below every depth.
    let mut previous: Vec<i64> = vec![-1; ctx.pixels];
    ctx.storage_bytes += ctx.pixels as u64 * 4; // the previous pass's depth buffer
    // Per pixel, fragments of a pass at the depth the pass before peeled.
    let at_prev = ctx.pool.u32s(ctx.pixels, 0);
    let mut states = ctx.states();
    let limit = ctx.plan.peel_limit;
    let mut peels = 0;
    loop {
        if peels == limit {
            break;
        }
        let prev = &previous;
        let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
        let raster = ctx.raster;
        let last = peels + 1 == limit;
        let at_prev = &at_prev;
        let lost = &*ctx;
        let generated = raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            let d = i64::from(depth_bits(f.depth));
            if d > prev[px] {
                // A key's depth bits are its high word: a fragment deeper than the pixel's nearest
                // so far cannot lower it, whatever its payload, and is not shaded (the slot only
                // falls, so a stale read errs toward shading, never toward a wrong skip).
                let held = nearest[px].load(Relaxed);
                let old = if (d as u64) << 32 > held {
                    held
                } else {
                    nearest[px].fetch_min(depth_key64(f.depth, payload(f)), Relaxed)
                };
                // the last peel allowed: of two fragments one is left behind for good
                if last && old != EMPTY {
                    lost.lose(px);
                }
            } else if d == prev[px] {
                // at the depth just peeled: the peeled one, or a coplanar tie the `>` skips
                at_prev[px].fetch_add(1, Relaxed);
            }
        });
        ctx.ran_pass(generated);
        let resolve = &ctx.resolve;
        let ctx_ref = &*ctx;
        let peeled: u64 = states
            .par_iter_mut()
            .zip(previous.par_iter_mut())
            .zip(nearest.par_iter())
            .enumerate()
            .map(|(px, ((s, prev), slot))| {
                if *prev == i64::MAX {
                    // done: no depth is above it or equal to it, so the pass touched nothing here
                    return 0;
                }
                if (0..i64::MAX).contains(prev) {
                    ctx_ref.settle_ties(px, crate::storage::take_u32(&at_prev[px], 0), 1);
                }
                let key = crate::storage::take_u64(slot, EMPTY);
                if key == EMPTY {
                    // nothing behind: done (no depth matches i64::MAX, so no tie is counted twice)
                    *prev = i64::MAX;
                    return 0;
                }
                let (d, p) = split_key64(key);
                resolve.push(s, d, p);
                *prev = i64::from(depth_bits(d));
                1
            })
            .sum();
        if peeled == 0 {
            break;
        }
        peels += 1;
    }
    Ok(super::finish(ctx, states))
}

/// `dp` per sample (several samples, docs/msaa.md): each pass walks the multisampled fragments
/// and keeps, per pixel, the smallest (depth bits, primitive id, lowest sample) key (`msaa::peel_key`) strictly behind the layer the
/// pass before peeled, so every fragment is one layer and ties come in the reference's order
/// (none lost). The peeled layer's payload and coverage mask are fetched by the next pass (its
/// one fragment whose key is the one peeled) and composited into the covered samples'
/// accumulators ([`super::msaa::SampleAccumulators`]); the pass that finds nothing fetches the
/// last layer, so the passes are the layers and one. Where the peel limit stops it first, one
/// more pass fetches the last layer and counts what lies behind it lost.
fn render_samples(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    use super::msaa::{accumulate, finish_accumulated, peel_key};
    const EMPTY: u64 = u64::MAX;
    // key + 1 of the layer the last pass peeled: 0 none yet, DONE nothing left
    const DONE: u64 = u64::MAX;
    let samples = ctx.settings.samples;
    let nearest = ctx.alloc64(1, EMPTY)?;
    let mut previous = vec![0u64; ctx.pixels];
    ctx.storage_bytes += ctx.pixels as u64 * 8;
    // the peeled layer's payload and mask
    let layer = ctx.alloc32(2, 0)?;
    let mut acc = super::msaa::SampleAccumulators::new(ctx, 1)?;
    let mut captured = vec![0u32; ctx.pixels];
    let limit = ctx.plan.peel_limit.saturating_add(1);
    let mut passes = 0;
    while passes < limit {
        let last = passes + 1 == limit;
        let (prev, shared) = (&previous, &*ctx);
        let generated = shared.raster.for_each_masked_fragment(samples, |f, mask| {
            let px = f.pixel as usize;
            let k = peel_key(f, mask) + 1;
            if k > prev[px] {
                if last {
                    // behind the last layer the limit allows
                    shared.lose(px);
                } else {
                    nearest[px].fetch_min(k - 1, Relaxed);
                }
            } else if k == prev[px] {
                layer[2 * px].store(shared.payload(f), Relaxed);
                layer[2 * px + 1].store(u32::from(mask), Relaxed);
            }
        });
        ctx.ran_pass(generated);
        let shared = &*ctx;
        let peeled: u64 = previous
            .par_iter_mut()
            .zip(acc.pixels_mut())
            .zip(captured.par_iter_mut())
            .enumerate()
            .map(|(px, ((prev, a), n))| {
                if *prev == DONE {
                    return 0;
                }
                if *prev != 0 {
                    let (payload, mask) = (layer[2 * px].load(Relaxed), layer[2 * px + 1].load(Relaxed));
                    accumulate(shared, a, 1, payload, mask as u8, false);
                    *n += 1;
                }
                let k = crate::storage::take_u64(&nearest[px], EMPTY);
                if k == EMPTY {
                    *prev = DONE;
                    return 0;
                }
                *prev = k + 1;
                1
            })
            .sum();
        passes += 1;
        if peeled == 0 {
            break;
        }
    }
    Ok(finish_accumulated(ctx, &acc, &captured))
}
