//! `wavg` and `wsum`: one geometry pass, no ordering (Bavoil & Myers 2008). Each pixel accumulates
//! Σα·c, Σα and the count; the sums are kept as integers of the 8-bit colours (α·c in units of
//! 1/255²), so the result does not depend on the order threads add them in.

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use oit_core::composite::{WeightedSums, weighted_average, weighted_sum};
use oit_core::rules::pack_rgba8;
use oit_core::{Effect, Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use crate::raster::prefetch;
use crate::storage::take_u64;

pub(crate) fn render(ctx: &mut Ctx<'_>, average: bool) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let effect = ctx.resolve.effect;
    // r, g, b premultiplied sums, alpha sum, count
    let mut sums = ctx.alloc64(5, 0)?;
    // each pixel's 40 bytes of sums asked for a few fragments before its turn: the five
    // locked adds of a fragment otherwise wait on memory one fragment at a time
    let ahead = |px: u32| prefetch(&sums[5 * px as usize..5 * px as usize + 5]);
    ctx.pass_shaded_ahead(ahead, |f| {
        let c = pack_rgba8(f.color());
        let a = u64::from(c >> 24);
        let base = f.pixel as usize * 5;
        sums[base].fetch_add(a * u64::from(c & 0xff), Relaxed);
        sums[base + 1].fetch_add(a * u64::from(c >> 8 & 0xff), Relaxed);
        sums[base + 2].fetch_add(a * u64::from(c >> 16 & 0xff), Relaxed);
        sums[base + 3].fetch_add(a, Relaxed);
        sums[base + 4].fetch_add(1, Relaxed);
    });
    let bg = ctx.settings.background;
    let composite = |w: &WeightedSums| if average { weighted_average(w, bg) } else { weighted_sum(w, bg) };
    // a pixel's sums and count, emptied as they are read (only where a fragment came: the
    // count), so the next frame lends the array without a sweep
    let take = |s: &[std::sync::atomic::AtomicU64]| {
        let count = take_u64(&s[4], 0) as u32;
        let mut l = [0.0f32; 4];
        if count > 0 {
            for (v, word) in l.iter_mut().zip(s) {
                *v = take_u64(word, 0) as f32;
            }
        }
        WeightedSums {
            premultiplied: Vec3::new(l[0], l[1], l[2]) / (255.0 * 255.0),
            alpha: l[3] / 255.0,
            count,
        }
    };
    let frame = if effect == Effect::Complexity {
        let mut states = ctx.states();
        states.par_iter_mut().zip(sums.par_chunks(5)).for_each(|(state, s)| state.captured = take(s).count);
        super::finish(ctx, states)
    } else {
        // each pixel's colour straight into the image, with the counts: no state array; a pixel
        // no fragment reached gets the empty sums' colour, made once (most of a frame's pixels,
        // each three sRGB conversions)
        let empty = crate::resolve::srgb(composite(&WeightedSums::default()));
        super::finish_pixels(ctx, |px| {
            let w = take(&sums[5 * px..5 * px + 5]);
            if w.count == 0 { (empty, 0) } else { (crate::resolve::srgb(composite(&w)), w.count) }
        })
    };
    sums.mark_clean(crate::pool::Clean::Word(0));
    Ok(frame)
}
