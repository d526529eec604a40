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
use std::sync::atomic::AtomicU64;

use oit_core::rules::{depth_bits, depth_from_bits};
use oit_core::{AtomicFragmentList, Frame, OitError};

use super::Ctx;
use crate::raster::Fragment;
use crate::storage::CountedList;

/// A fragment's slot word: depth bits above the primitive id. Under the test hook
/// `OIT_MUTATION=cpu-fabs-ties-reversed` ([`oit_core::mutation`]) the id is complemented, so
/// equal depths come out in descending primitive order, uncounted: `checks::exact` on a scene of
/// ties must fail (`tests/tests/mutations.rs`).
#[inline]
fn word(f: &Fragment<'_>) -> u64 {
    let prim = if oit_core::mutation::active("cpu-fabs-ties-reversed") { !f.prim } else { f.prim };
    u64::from(depth_bits(f.depth)) << 32 | u64::from(prim)
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
    let list = CountedList::new(&counters, &slots, &payloads, k);
    capture(ctx, &list);
    // Overflow keeps the K smallest keys whatever the arrival order (as `fabs.wgsl`): the pixels
    // that overflowed are emptied, every key of theirs is inserted into the same slots read as a
    // min list (as mdts64), then each surviving key's payload is written beside it. Sized from
    // the counting pass, no pixel can overflow; a frame where none did runs nothing.
    let any = !ctx.plan.needs_count() && list.empty_overflowing();
    let nearest = list.nearest();
    if any {
        ctx.raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            if list.overflowed(px) {
                // what the min list carries off is the fragment the capture counted lost
                nearest.insert(px, word(f));
            }
        });
        let payload = |f: &Fragment<'_>| ctx.payload(f);
        ctx.raster.for_each_fragment(|f| {
            let px = f.pixel as usize;
            if list.overflowed(px) {
                list.set_payload(px, word(f), payload(f));
            }
        });
        ctx.passes += 2;
    }
    if let (Some(sums), true) = (&tail, any) {
        // the overflow passes left an overflowing pixel's K words sorted: the last is the largest
        let color = |f: &Fragment<'_>| oit_core::rules::pack_rgba8(f.color());
        ctx.tail_pass(sums, |f| {
            let px = f.pixel as usize;
            (list.overflowed(px) && nearest.last(px).is_some_and(|last| word(f) > last)).then(|| color(f))
        });
    }
    Ok(resolve(ctx, &list, tail.as_deref().map(|t| &t[..])))
}

/// fabs's capture pass over any list of its keys (slot word above payload): each fragment offered
/// once, and the one the list drops counted lost (not counted under the test hook
/// `OIT_MUTATION=cpu-fabs-lose-uncounted`, [`oit_core::mutation`]: `checks::accounting` must
/// then fail, `tests/tests/mutations.rs`).
pub(crate) fn capture<L: AtomicFragmentList<Key = u128>>(ctx: &mut Ctx<'_>, list: &L) {
    let uncounted = oit_core::mutation::active("cpu-fabs-lose-uncounted");
    ctx.pass_lossy(|f, ctx| {
        let px = f.pixel as usize;
        if list.insert(px, CountedList::key(word(f), ctx.payload(f))).is_some() && !uncounted {
            // the counter is past K: no slot for this fragment
            ctx.lose(px);
        }
    });
}

/// fabs's resolve: each pixel's keys in order, (depth bits, primitive id) above the payload, so
/// equal depths come out in primitive order; `tail` the pixels' `--overflow tail` sums.
pub(crate) fn resolve<L: AtomicFragmentList<Key = u128>>(
    ctx: &Ctx<'_>,
    list: &L,
    tail: Option<&[AtomicU64]>,
) -> Frame {
    let resolve = &ctx.resolve;
    super::finish_with(ctx, |px, keys: &mut Vec<u128>, s| {
        list.sorted(px, keys);
        for &key in keys.iter() {
            resolve.push(s, depth_from_bits((key >> 64) as u32), key as u32);
        }
        if let Some(t) = tail {
            resolve.tail(s, &t[px * 5..px * 5 + 5], px);
        }
    })
}
