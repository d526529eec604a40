//! `wavg` and `wsum`: one geometry pass, no ordering (Bavoil & Myers 2008). Each pixel accumulates
//! Σα·c, Σα and the count; the sums are kept as integers of the 8-bit colours (α·c in units of
//! 1/255²), so the result does not depend on the order threads add them in.

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use oit_core::composite::{WeightedSums, weighted_average, weighted_sum};
use oit_core::rules::pack_rgba8;
use oit_core::{Frame, OitError};

use super::Ctx;
use crate::raster::prefetch;

pub(crate) fn render(ctx: &mut Ctx<'_>, average: bool) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    // r, g, b premultiplied sums, alpha sum, count
    let sums = ctx.alloc64(5, 0)?;
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
    let composite =
        |w: &WeightedSums, bg: Vec3| if average { weighted_average(w, bg) } else { weighted_sum(w, bg) };
    Ok(super::finish_sums(ctx, sums, 5, 4, |w, count, bg| {
        let sums = WeightedSums {
            premultiplied: Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32) / (255.0 * 255.0),
            alpha: w[3] as f32 / 255.0,
            count,
        };
        composite(&sums, bg)
    }))
}
