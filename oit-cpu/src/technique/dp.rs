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
