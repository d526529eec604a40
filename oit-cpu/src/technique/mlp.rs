//! `mlp:M`: extended multi-layer peeling (Huang et al. 2011, section 3.3). Each geometry pass
//! captures, per pixel, the M nearest fragments strictly behind the deepest one the previous pass
//! captured (atomic-min insertion into M 64-bit words, as `mdts64`), composites them, and repeats
//! while any pixel had more than M left: ⌈N/M⌉ passes for N layers. Fragments that tie in depth
//! with the deepest of a pass are never captured and are counted in `lost`.
//!
//! Ties within a pass: the insertion is atomic min on one 64-bit word, depth bits above the
//! payload, with no room for the primitive id the reference orders equal depths by, so equal
//! depths of a pass come out by colour; the resolve counts every fragment of such a run in `tied`.
//!
//! Above one sample (`Plan::sample_peel`) the keys are (depth, primitive id) instead, so nothing
//! ties or is lost, and each layer is composited into the samples its mask covers
//! (`render_samples`; docs/msaa.md).

use oit_core::Compositor as _;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};

use oit_core::rules::{depth_bits, depth_key64, split_key64};

use crate::raster::Shade;
use oit_core::{AtomicFragmentList, Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use crate::storage::MinList;

pub(crate) fn render(ctx: &mut Ctx<'_>, m: u32) -> Result<Frame, OitError> {
    if ctx.plan.sample_peel {
        return render_samples(ctx, m);
    }
    let m = m as usize;
    let slots = ctx.alloc64(m, MinList::<AtomicU64>::EMPTY)?;
    render_over(ctx, &MinList::new(&slots, m))
}

/// `mlp`'s passes over any list of its keys (depth bits above the payload) that keeps the
/// nearest, empty when lent and left empty (each pass's resolve takes what the pass kept).
pub(crate) fn render_over<L: AtomicFragmentList<Key = u64>>(
    ctx: &mut Ctx<'_>,
    list: &L,
) -> Result<Frame, OitError> {
    let mut deepest: Vec<i64> = vec![-1; ctx.pixels];
    ctx.storage_bytes += ctx.pixels as u64 * 4;
    // Per pixel: fragments of a pass at the deepest depth the pass before captured, and how many
    // that pass captured at that depth.
    let at_prev = ctx.pool.u32s(ctx.pixels, 0);
    let mut captured_at = vec![0u32; ctx.pixels];
    let mut states = ctx.states();
    let limit = ctx.plan.peel_limit;
    let mut peels = 0;
    while peels < limit {
        let more = AtomicBool::new(false);
        let prev = &deepest;
        let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
        let last = peels + 1 == limit;
        let (at_prev, lost) = (&at_prev, &*ctx);
        // the first pass takes every fragment's payload, later ones only the deeper fragments'
        let shade = if peels == 0 { ctx.payload_shade() } else { Shade::OnDemand };
        let generated = ctx.raster.for_each_fragment_with(shade, |f| {
            let px = f.pixel as usize;
            let d = i64::from(depth_bits(f.depth));
            if d > prev[px] {
                if list.insert(px, depth_key64(f.depth, payload(f))).is_some() {
                    more.store(true, Relaxed);
                    if last {
                        // carried off the end in the last pass the plan allows
                        lost.lose(px);
                    }
                }
            } else if d == prev[px] {
                // at the deepest depth the pass before captured: captured then, or a tie skipped
                at_prev[px].fetch_add(1, Relaxed);
            }
        });
        ctx.ran_pass(generated);
        peels += 1;
        let resolve = &ctx.resolve;
        let ctx_ref = &*ctx;
        states
            .par_iter_mut()
            .zip(deepest.par_iter_mut())
            .zip(captured_at.par_iter_mut())
            .enumerate()
            .for_each_init(Vec::new, |keys, (px, ((s, deep), at))| {
                if *deep == i64::MAX {
                    // done: no depth is above it or equal to it, so the pass touched nothing here
                    return;
                }
                ctx_ref.settle_ties(px, crate::storage::take_u32(&at_prev[px], 0), *at);
                list.take_sorted(px, keys);
                if keys.is_empty() {
                    // nothing left behind the deepest: done (no depth matches i64::MAX)
                    *at = 0;
                    *deep = i64::MAX;
                }
                for &key in keys.iter() {
                    let (d, p) = split_key64(key);
                    resolve.push(s, d, p);
                    let bits = i64::from(depth_bits(d));
                    *at = if bits == *deep { *at + 1 } else { 1 };
                    *deep = bits;
                }
            });
        if !more.load(Relaxed) {
            break;
        }
    }
    Ok(super::finish(ctx, states))
}

/// `mlp:M` per sample (several samples, docs/msaa.md): each pass walks the multisampled
/// fragments and inserts, per pixel, the (depth bits, primitive id, lowest sample) keys strictly behind the
/// deepest key the pass before kept into M slots by atomic min, so every fragment is one layer
/// and ties come in the reference's order (none lost). The next pass fetches the payloads and
/// coverage masks of the keys the pass before kept (the fragments whose keys are among them),
/// and its resolve composites them, nearest first, into the covered samples' accumulators
/// ([`super::msaa::SampleAccumulators`]); the pass that keeps nothing fetches the last ones, so
/// the passes are ⌈layers / M⌉ and one. Where the peel limit stops it first, one more pass
/// fetches the last pass's layers and counts what lies behind them lost.
fn render_samples(ctx: &mut Ctx<'_>, m: u32) -> Result<Frame, OitError> {
    use super::msaa::{accumulate, finish_accumulated, peel_key};
    const EMPTY: u64 = MinList::<AtomicU64>::EMPTY;
    let samples = ctx.settings.samples;
    let m = m.max(1) as usize;
    let slots = ctx.alloc64(m, EMPTY)?;
    let list = MinList::new(&slots, m);
    // the keys the pass before kept, sorted, all ones past them; a pixel whose keys are all
    // ones after the first pass is done (nothing lies behind the deepest)
    let previous = ctx.alloc64(m, EMPTY)?;
    // the payload and mask of each of those keys, fetched by this pass
    let layers = ctx.alloc32(2 * m, 0)?;
    let mut acc = super::msaa::SampleAccumulators::new(ctx, 1)?;
    let mut captured = vec![0u32; ctx.pixels];
    let (list, previous, layers) = (&list, &*previous, &*layers);
    let limit = ctx.plan.peel_limit.saturating_add(1);
    let mut passes = 0;
    while passes < limit {
        let (first, last) = (passes == 0, passes + 1 == limit);
        let shared = &*ctx;
        let generated = shared.raster.for_each_masked_fragment(samples, |f, mask| {
            let px = f.pixel as usize;
            let k = peel_key(f, mask);
            let prev = &previous[px * m..px * m + m];
            if !first {
                let nearest = prev[0].load(Relaxed);
                if nearest == EMPTY {
                    // done
                    return;
                }
                let deepest = prev.iter().map(|p| p.load(Relaxed)).take_while(|&p| p != EMPTY).last();
                if deepest.is_some_and(|d| k <= d) {
                    if let Some(i) = prev.iter().position(|p| p.load(Relaxed) == k) {
                        layers[2 * (px * m + i)].store(shared.payload(f), Relaxed);
                        layers[2 * (px * m + i) + 1].store(u32::from(mask), Relaxed);
                    }
                    return;
                }
            }
            if last {
                // behind the last layers the limit allows
                shared.lose(px);
            } else {
                list.insert(px, k);
            }
        });
        ctx.ran_pass(generated);
        let shared = &*ctx;
        let peeled: u64 = acc
            .pixels_mut()
            .zip(captured.par_iter_mut())
            .enumerate()
            .map_init(Vec::new, |keys, (px, (a, n))| {
                let prev = &previous[px * m..px * m + m];
                if !first && prev[0].load(Relaxed) == EMPTY {
                    return 0;
                }
                for (i, p) in prev.iter().enumerate() {
                    if p.load(Relaxed) == EMPTY {
                        break;
                    }
                    let (payload, mask) =
                        (layers[2 * (px * m + i)].load(Relaxed), layers[2 * (px * m + i) + 1].load(Relaxed));
                    accumulate(shared, a, 1, payload, mask as u8, false);
                    *n += 1;
                }
                list.take_sorted(px, keys);
                for (i, p) in prev.iter().enumerate() {
                    p.store(keys.get(i).copied().unwrap_or(EMPTY), Relaxed);
                }
                u64::from(!keys.is_empty())
            })
            .sum();
        passes += 1;
        if peeled == 0 {
            break;
        }
    }
    Ok(finish_accumulated(ctx, &acc, &captured))
}
