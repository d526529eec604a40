//! `mdts:K` and `mdts64:K`: the multi-depth test (Liu et al., SIGGRAPH 2009 talk; Huang et al.
//! 2011, section 3). K words per pixel start at all ones; each fragment is inserted by repeated
//! atomic min, carrying the larger value on to the next word, so the array stays sorted while
//! fragments arrive in any order, and the K nearest survive.
//!
//! - `mdts` keeps the paper's 32-bit words: the 20 depth bits of [`mdts_pack`] above 12 bits of
//!   RGB, in two arrays (high and low colour halves) updated one after the other. Depths closer
//!   than 2⁻²⁰ may swap or mismatch halves, and alpha is not stored: the scene's alpha is used
//!   (the `--alpha` override, else the mean of the objects' alphas).
//! - `mdts64` stores depth bits above the packed RGBA8 in one 64-bit word: exact for the first K.
//!
//! Ties: neither word has room for the primitive id the reference orders equal depths by, so
//! equal depths come out by colour, and `mdts` makes depths equal that were only within one 2⁻²⁰
//! step (where the reference orders them by their f32 depths).
//!
//! `--overflow tail`: a second pass merges into the pixel's tail every fragment whose word is
//! larger than the K-th kept (see `Ctx::tail_pass`); one equal to it (same depth bits and colour)
//! that was carried off stays counted in `lost`. `mdts`'s tail takes the fragment's 8-bit RGB and
//! the plan's alpha, as its kept words do. The resolve counts in `tied` every
//! fragment of a run of equal stored depths (f32 bits for `mdts64`, the 20 bits for `mdts`) that
//! holds two colours or more; a run of one colour composites alike in any order. What `mdts`
//! loses besides, and does not count: depth below 2⁻²⁰ (the resolve sees the lower end of the
//! step, which moves translucency's distances) and per-fragment alpha.

use oit_core::Compositor as _;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use oit_core::rules::{depth_key64, mdts_pack, mdts_unpack, pack_rgba8, split_key64};
use oit_core::{AtomicFragmentList, Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use crate::storage::MinList;

/// Whether the capture found a pixel full (a fragment counted lost): the tail pass runs only then.
fn overflowed(ctx: &Ctx<'_>) -> bool {
    ctx.lost.par_iter().any(|l| l.load(Relaxed) > 0)
}

/// Slots per pixel, by the plan (a counting pass first where it sizes from the scene).
pub(crate) fn capacity(ctx: &mut Ctx<'_>) -> Result<usize, OitError> {
    let deepest = if ctx.plan.needs_count() { ctx.max_depth_complexity()? } else { 0 };
    Ok(ctx.plan.slots(deepest) as usize)
}

pub(crate) fn render64(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let k = capacity(ctx)?;
    let slots = ctx.alloc64(k, MinList::<AtomicU64>::EMPTY)?;
    render64_over(ctx, &MinList::new(&slots, k))
}

/// `mdts64`'s frame over any list of its keys (depth bits above the payload) that keeps the
/// nearest: capture, the tail pass, the resolve.
pub(crate) fn render64_over<L: AtomicFragmentList<Key = u64>>(
    ctx: &mut Ctx<'_>,
    list: &L,
) -> Result<Frame, OitError> {
    let tail = ctx.tail_sums()?;
    ctx.pass_lossy(|f, ctx| {
        if list.insert(f.pixel as usize, depth_key64(f.depth, ctx.payload(f))).is_some() {
            // a key carried off the end of the full array
            ctx.lose(f.pixel as usize);
        }
    });
    if let Some(sums) = &tail
        && overflowed(ctx)
    {
        ctx.tail_pass(sums, |f| {
            let p = pack_rgba8(f.color());
            list.last(f.pixel as usize).is_some_and(|last| depth_key64(f.depth, p) > last).then_some(p)
        });
    }
    let resolve = &ctx.resolve;
    let tail = tail.as_deref();
    Ok(super::finish_with(ctx, |px, keys: &mut Vec<u64>, s| {
        list.sorted(px, keys);
        for &key in keys.iter() {
            let (d, p) = split_key64(key);
            resolve.push(s, d, p);
        }
        if let Some(t) = tail {
            resolve.tail(s, &t[px * 5..px * 5 + 5], px);
        }
    }))
}

/// The 32-bit words; the plan refuses Fresnel (no room for a normal) and gives the alpha.
pub(crate) fn render32(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let k = capacity(ctx)?;
    let high = ctx.alloc32(k, MinList::<AtomicU32>::EMPTY)?;
    let low = ctx.alloc32(k, MinList::<AtomicU32>::EMPTY)?;
    render32_over(ctx, &MinList::new(&high, k), &MinList::new(&low, k))
}

/// `mdts`'s frame over any two lists of 32-bit words that keep the nearest, `high` and `low`
/// ([`mdts_pack`]'s two words, each inserted into its own list one after the other, as the
/// paper's two arrays): capture, the tail pass, the resolve.
pub(crate) fn render32_over<L: AtomicFragmentList<Key = u32>>(
    ctx: &mut Ctx<'_>,
    high: &L,
    low: &L,
) -> Result<Frame, OitError> {
    let alpha8 = ctx.plan.mdts_alpha8;
    let tail = ctx.tail_sums()?;
    // All ones is the empty word: a fragment at d ≈ 1 with that colour gives up its last bit.
    let words = |f: &crate::raster::Fragment<'_>| {
        mdts_pack(f.depth, pack_rgba8(f.color())).map(|w| w.min(u32::MAX - 1))
    };
    ctx.pass_lossy(|f, ctx| {
        let px = f.pixel as usize;
        let [a, b] = words(f);
        // both arrays hold the same number of words: one carried off the high array is one lost
        if high.insert(px, a).is_some() {
            ctx.lose(px);
        }
        low.insert(px, b);
    });
    if let Some(sums) = &tail
        && overflowed(ctx)
    {
        ctx.tail_pass(sums, |f| {
            let [a, _] = words(f);
            high.last(f.pixel as usize)
                .is_some_and(|last| a > last)
                .then(|| pack_rgba8(f.color()) & 0xff_ffff | alpha8 << 24)
        });
    }
    let resolve = &ctx.resolve;
    let tail = tail.as_deref();
    Ok(super::finish_with(ctx, |px, (hi, lo): &mut (Vec<u32>, Vec<u32>), s| {
        high.sorted(px, hi);
        low.sorted(px, lo);
        // a pixel's two lists hold as many words; the shorter ends the pixel where a word of
        // the other was all ones
        for (&h, &l) in hi.iter().zip(lo.iter()) {
            let (d, rgb) = mdts_unpack([h, l]);
            resolve.push(s, d, rgb | alpha8 << 24);
        }
        if let Some(t) = tail {
            resolve.tail(s, &t[px * 5..px * 5 + 5], px);
        }
    }))
}
