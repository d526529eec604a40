//! `fabs:K`: the fixed A-buffer (Liu et al., SIGGRAPH 2009 talk; Huang et al. 2011, section 4).
//! A per-pixel counter hands each fragment a slot by atomic increment, in rasterization order; a
//! resolve sorts each pixel's n ≤ K slots by depth and composites them. Fragments past K are
//! counted in `lost`; a pixel that overflowed keeps its K nearest fragments by (depth, primitive
//! id), found by two more passes over the overflowing pixels only, so the same input always gives
//! the same image (issue 13.7). With `--overflow tail` one more pass merges the fragments behind
//! those K into the pixel's tail (see `Ctx::tail_pass`): each is one whose key is larger than the
//! K-th kept, so every fragment past K is merged and none is lost.
//!
//! Ties: a slot is the 64-bit key (depth bits, primitive id) and the payload beside it (12 bytes),
//! and the sort is by key, so equal depths come out in primitive order, as the reference orders
//! them: `fabs` never counts `tied`. It can, where the one-word techniques cannot, because its
//! sort runs after capture, over words no atomic has to compare (`mdts64`, `mlp`, `ddp` and `dp`
//! order by an atomic min/max of one 64-bit word, with no room for an id beside depth and payload,
//! and count their ties instead).

use oit_core::Compositor as _;
use std::sync::atomic::Ordering::Relaxed;

use oit_core::rules::{depth_bits, depth_from_bits};
use oit_core::{Frame, OitError};
use rayon::prelude::*;

use super::Ctx;

/// Up to this many fragments a pixel's list is insertion-sorted; beyond, `sort_unstable`
/// (pattern-defeating quicksort). Measured with `cargo bench -p oit-cpu --bench sort` on this
/// project's 2-core machine, time to sort 256 lists of n random 64-bit keys:
///
/// | n | insertion | bitonic network | merge (`sort`) | pdq (`sort_unstable`) |
/// |---|---|---|---|---|
/// | 4 | 1.8 µs | 16 µs | 2.5 µs | 2.0 µs |
/// | 8 | 5.0 µs | 54 µs | 6.4 µs | 5.4 µs |
/// | 16 | 29 µs | 152 µs | 16 µs | 25 µs |
/// | 32 | 129 µs | 344 µs | 77 µs | 39 µs |
/// | 128 | 1.0 ms | 2.4 ms | 601 µs | 351 µs |
///
/// Insertion sort wins on the short lists most pixels have; pdqsort from 32 on; the sorting
/// network, which suits a GPU's lockstep threads, loses everywhere on a CPU. Merge sort's lead at
/// 16 is within the noise of these runs, so the rule stays two-way.
pub const INSERTION_SORT_MAX: usize = 8;

/// Sorts a pixel's keys in place, choosing the sort by length (see [`INSERTION_SORT_MAX`]).
pub fn sort_keys<K: Ord + Copy>(keys: &mut [K]) {
    if keys.len() <= INSERTION_SORT_MAX {
        for i in 1..keys.len() {
            let v = keys[i];
            let mut j = i;
            while j > 0 && keys[j - 1] > v {
                keys[j] = keys[j - 1];
                j -= 1;
            }
            keys[j] = v;
        }
    } else {
        keys.sort_unstable();
    }
}

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let deepest = if ctx.plan.needs_count() { ctx.max_depth_complexity()? } else { 0 };
    let k = ctx.plan.slots(deepest) as usize;
    let counters = ctx.alloc32(1, 0)?;
    // below each pixel's counter every slot is written before the resolve reads it (an
    // overflowing pixel's are all set before its keys are inserted)
    let slots = ctx.scratch64(k)?;
    let payloads = ctx.scratch32(k)?;
    let tail = ctx.tail_sums()?;
    let shade = ctx.payload_shade();
    let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
    let lost = &*ctx;
    let generated = ctx.raster.for_each_fragment_with(shade, |f| {
        let px = f.pixel as usize;
        let i = counters[px].fetch_add(1, Relaxed) as usize;
        if i < k {
            slots[px * k + i].store(u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim), Relaxed);
            payloads[px * k + i].store(payload(f), Relaxed);
        } else {
            // the counter is past K: no slot for this fragment
            lost.lose(px);
        }
    });
    let mut passes = 1;
    // Overflow keeps the K smallest keys whatever the arrival order (as `fabs.wgsl`): the pixels
    // that overflowed are emptied, every key of theirs is inserted by repeated atomic min carrying
    // the larger value on (as mdts64), then each surviving key's payload is written beside it.
    // Sized from the counting pass, no pixel can overflow; a frame where none did runs nothing.
    let overflowing = |px: usize| counters[px].load(Relaxed) as usize > k;
    let any = !ctx.plan.needs_count()
        && slots
            .par_chunks(k)
            .enumerate()
            .map(|(px, s)| {
                if overflowing(px) {
                    s.iter().for_each(|w| w.store(u64::MAX, Relaxed));
                    true
                } else {
                    false
                }
            })
            .reduce(|| false, |a, b| a || b);
    if any {
        ctx.raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            if overflowing(px) {
                let mut carry = u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
                for slot in &slots[px * k..px * k + k] {
                    let old = slot.fetch_min(carry, Relaxed);
                    if old == u64::MAX {
                        break;
                    }
                    carry = carry.max(old);
                }
            }
        });
        ctx.raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            if overflowing(px) {
                // keys are unique at a pixel: one fragment per primitive
                let key = u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
                if let Some(i) = slots[px * k..px * k + k].iter().position(|w| w.load(Relaxed) == key) {
                    payloads[px * k + i].store(payload(f), Relaxed);
                }
            }
        });
        passes += 2;
    }
    ctx.passes += passes;
    if let (Some(sums), true) = (&tail, any) {
        // the overflow passes left an overflowing pixel's K keys sorted: the last is the largest
        let color = |f: &crate::raster::Fragment<'_>| oit_core::rules::pack_rgba8(f.color());
        ctx.tail_pass(sums, |f| {
            let px = f.pixel as usize;
            let key = u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
            (overflowing(px) && key > slots[px * k + k - 1].load(Relaxed)).then(|| color(f))
        });
    }
    ctx.fragments.get_or_insert(generated);
    let resolve = &ctx.resolve;
    let tail = tail.as_deref();
    Ok(super::finish_with(ctx, |px, keys: &mut Vec<u128>, s| {
        let n = (counters[px].load(Relaxed) as usize).min(k);
        let (slots, payloads) = (&slots[px * k..px * k + n], &payloads[px * k..px * k + n]);
        keys.clear();
        // (depth bits, primitive id) above the payload: one primitive has one fragment a pixel,
        // so the payload never decides
        keys.extend(
            slots
                .iter()
                .zip(payloads)
                .map(|(x, p)| u128::from(x.load(Relaxed)) << 32 | u128::from(p.load(Relaxed))),
        );
        sort_keys(keys);
        for &key in keys.iter() {
            resolve.push(s, depth_from_bits((key >> 64) as u32), key as u32);
        }
        if let Some(t) = tail {
            resolve.tail(s, &t[px * 5..px * 5 + 5]);
        }
    }))
}
