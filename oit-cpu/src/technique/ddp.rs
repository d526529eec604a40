//! `ddp`: dual depth peeling (Bavoil & Myers 2008). Each geometry pass peels, per pixel, the
//! nearest and the farthest fragment strictly inside the range left by the previous pass (MIN and
//! MAX on (depth, colour), the atomic analogue of the paper's MAX blending of (−d, d)); the near
//! layer is composited under the front, the far layer over the back. ⌈N/2⌉ + 1 passes.
//!
//! A pixel whose nearest and farthest remaining fragment is the same one composites it once; other
//! fragments that tie in depth with a peeled one are never peeled and are counted in `lost`.
//!
//! Ties: the MIN and MAX are on one 64-bit word, depth bits above the payload, with no room for
//! the primitive id the reference orders equal depths by; so where the front and the back meet at
//! one depth (the last pass finds nearest and farthest equal in depth, of two colours) their order
//! is by colour. The resolve counts both in `tied` (the join of the front and back runs,
//! `PixelState::tied`); the fragments between them at that depth are `lost`.

use oit_core::Compositor as _;
use std::sync::atomic::Ordering::Relaxed;

use oit_core::rules::{depth_bits, depth_key64, split_key64};
use oit_core::{Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use crate::storage::{take_u32, take_u64};

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    if ctx.plan.sample_peel {
        return render_samples(ctx);
    }
    const EMPTY_MIN: u64 = u64::MAX;
    let near = ctx.alloc64(1, EMPTY_MIN)?;
    let far = ctx.alloc64(1, 0)?;
    // Open depth range (exclusive) of what is left, as depth bits; the first pass takes all.
    let mut range: Vec<(i64, i64)> = vec![(-1, i64::MAX); ctx.pixels];
    ctx.storage_bytes += ctx.pixels as u64 * 8;
    // Per pixel: fragments seen at the depths the previous pass peeled (or, in the last pass the
    // plan allows, inside the range), and how many that pass peeled.
    let seen = ctx.pool.u32s(ctx.pixels, 0);
    let mut peeled_at = vec![0u32; ctx.pixels];
    let mut states = ctx.states();
    let limit = ctx.plan.peel_limit;
    let mut peels = 0;
    while peels < limit {
        let r = &range;
        let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
        let last = peels + 1 == limit;
        let (seen_r, at_r) = (&seen, &peeled_at);
        let generated = ctx.raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            let d = i64::from(depth_bits(f.depth));
            let (lo, hi) = r[px];
            if d > lo && d < hi {
                // A key's depth bits are its high word: a fragment strictly between the pixel's
                // nearest and farthest so far can lower neither, whatever its payload, and is not
                // shaded (near only falls and far only rises, so a stale read errs toward
                // shading, never toward a wrong skip).
                let (low, high) = ((d as u64) << 32, (d as u64) << 32 | u64::from(u32::MAX));
                if low <= near[px].load(Relaxed) || high >= far[px].load(Relaxed) {
                    let key = depth_key64(f.depth, payload(f));
                    near[px].fetch_min(key, Relaxed);
                    far[px].fetch_max(key, Relaxed);
                }
                if last {
                    // the last peel allowed: all but the one or two it peels stay behind
                    seen_r[px].fetch_add(1, Relaxed);
                }
            } else if at_r[px] > 0 && (d == lo || d == hi) {
                // at a depth just peeled: a peeled one, or a tie the strict range skips
                seen_r[px].fetch_add(1, Relaxed);
            }
        });
        ctx.ran_pass(generated);
        let resolve = &ctx.resolve;
        let ctx_ref = &*ctx;
        let peeled: u64 = states
            .par_iter_mut()
            .zip(range.par_iter_mut())
            .zip(near.par_iter().zip(far.par_iter()))
            .zip(peeled_at.par_iter_mut())
            .enumerate()
            .map(|(px, (((s, range), (n, f)), at))| {
                if *range == (0, 0) && *at == 0 {
                    // finished (or never reached): no fragment lies in an empty range, none was
                    // peeled at its depths, so the pass touched none of this pixel's words
                    return 0;
                }
                let (n, f) = (take_u64(n, EMPTY_MIN), take_u64(f, 0));
                let count = if n == EMPTY_MIN {
                    0
                } else if f != n {
                    2
                } else {
                    1
                };
                // ties at the previous pass's depths, or (last pass) what it left behind
                let taken = if last { count + *at } else { *at };
                ctx_ref.settle_ties(px, take_u32(&seen[px], 0), taken);
                *at = count;
                if n == EMPTY_MIN {
                    *range = (0, 0);
                    return 0;
                }
                let (dn, pn) = split_key64(n);
                resolve.push(s, dn, pn);
                if f != n {
                    let (df, pf) = split_key64(f);
                    resolve.push_back_over(s, df, pf, resolve.background_at(px));
                }
                *range = (i64::from(depth_bits(dn)), i64::from(depth_bits(split_key64(f).0)));
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

/// `ddp` per sample (several samples, docs/msaa.md): each pass walks the multisampled fragments
/// and keeps, per pixel, the smallest and the largest (depth bits, primitive id, lowest sample) key (`msaa::peel_key`) strictly
/// inside the open range the pass before left, so every fragment is one layer and ties come in
/// the reference's order (none lost). The peeled layers' payloads and coverage masks are fetched
/// by the next pass (the fragments whose keys are the ones peeled) and composited into the
/// covered samples' front and back accumulators ([`super::msaa::SampleAccumulators`]); the pass
/// that finds nothing fetches the last ones. Where the peel limit stops it first, one more pass
/// fetches the last layers and counts what lies between them lost.
fn render_samples(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    use super::msaa::{accumulate, finish_accumulated, peel_key};
    const EMPTY_MIN: u64 = u64::MAX;
    // nothing left: no key k has k + 1 > lo or k == hi
    const DONE: (u64, u64) = (u64::MAX, u64::MAX);
    let samples = ctx.settings.samples;
    let near = ctx.alloc64(1, EMPTY_MIN)?;
    let far = ctx.alloc64(1, 0)?;
    // per pixel (lo, hi): k lies inside where k + 1 > lo and k < hi; the near layer the last
    // pass peeled is lo − 1, the far one hi (where it peeled two; one where hi + 1 = lo)
    let mut range: Vec<(u64, u64)> = vec![(0, u64::MAX); ctx.pixels];
    ctx.storage_bytes += ctx.pixels as u64 * 16;
    // the peeled layers' payloads and masks: near, then far
    let layers = ctx.alloc32(4, 0)?;
    let mut acc = super::msaa::SampleAccumulators::new(ctx, 2)?;
    let mut captured = vec![0u32; ctx.pixels];
    let limit = ctx.plan.peel_limit.saturating_add(1);
    let mut passes = 0;
    while passes < limit {
        let last = passes + 1 == limit;
        let (r, shared) = (&range, &*ctx);
        let generated = shared.raster.for_each_masked_fragment(samples, |f, mask| {
            let px = f.pixel as usize;
            let k = peel_key(f, mask);
            let (lo, hi) = r[px];
            let slot = if k + 1 > lo && k < hi {
                if last {
                    // between the last layers the limit allows
                    shared.lose(px);
                } else {
                    near[px].fetch_min(k, Relaxed);
                    far[px].fetch_max(k, Relaxed);
                }
                return;
            } else if k + 1 == lo {
                0
            } else if k == hi {
                2
            } else {
                return;
            };
            layers[4 * px + slot].store(shared.payload(f), Relaxed);
            layers[4 * px + slot + 1].store(u32::from(mask), Relaxed);
        });
        ctx.ran_pass(generated);
        let shared = &*ctx;
        let peeled: u64 = range
            .par_iter_mut()
            .zip(acc.pixels_mut())
            .zip(captured.par_iter_mut())
            .enumerate()
            .map(|(px, ((range, a), n))| {
                if *range == DONE {
                    return 0;
                }
                // layers the last pass peeled: none before the first, one where near was far
                let at = match *range {
                    (0, u64::MAX) => 0,
                    (lo, hi) if hi.wrapping_add(1) == lo => 1,
                    _ => 2,
                };
                for (i, back) in [(0, false), (2, true)].into_iter().take(at) {
                    let (payload, mask) =
                        (layers[4 * px + i].load(Relaxed), layers[4 * px + i + 1].load(Relaxed));
                    accumulate(shared, a, 2, payload, mask as u8, back);
                    *n += 1;
                }
                let (kn, kf) = (take_u64(&near[px], EMPTY_MIN), take_u64(&far[px], 0));
                if kn == EMPTY_MIN {
                    *range = DONE;
                    return 0;
                }
                *range = (kn + 1, kf);
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
