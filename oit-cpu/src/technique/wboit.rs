//! `wboit`: weighted blended OIT (McGuire & Bavoil, JCGT 2013), one geometry pass, no ordering.
//! Each pixel accumulates Σ α·w·c, Σ α·w (w: the depth weight of the paper's eq. 10,
//! `oit_core::technique::wboit::wboit_weight`), the optical depth Σ −ln(1 − α) (the table
//! `WBOIT_OPTICAL_DEPTH`: the paper's revealage Π(1 − α) as a sum, so that atomics can keep it)
//! and the count, all as u64 integers of the 8-bit colour, so the sums do not depend on the
//! order threads add them in; `oit_core::technique::wboit::wboit` composites them.

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use oit_core::rules::pack_rgba8;
use oit_core::technique::wboit::{WBOIT_OPTICAL_DEPTH, WBOIT_OPTICAL_UNIT, WboitSums, wboit, wboit_weight};
use oit_core::{Frame, OitError};

use super::Ctx;
use crate::raster::prefetch;

/// u64 words a pixel: Σ α·w·r, Σ α·w·g, Σ α·w·b, Σ α·w, Σ −ln(1 − α), count.
const WORDS: usize = 6;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let sums = ctx.alloc64(WORDS, 0)?;
    let ahead = |px: u32| prefetch(&sums[WORDS * px as usize..WORDS * px as usize + WORDS]);
    ctx.pass_shaded_ahead(ahead, |f| {
        let c = pack_rgba8(f.color());
        let a = u64::from(c >> 24);
        let aw = a * wboit_weight(f.depth);
        let base = f.pixel as usize * WORDS;
        sums[base].fetch_add(aw * u64::from(c & 0xff), Relaxed);
        sums[base + 1].fetch_add(aw * u64::from(c >> 8 & 0xff), Relaxed);
        sums[base + 2].fetch_add(aw * u64::from(c >> 16 & 0xff), Relaxed);
        sums[base + 3].fetch_add(aw, Relaxed);
        sums[base + 4].fetch_add(u64::from(WBOIT_OPTICAL_DEPTH[(c >> 24) as usize]), Relaxed);
        sums[base + 5].fetch_add(1, Relaxed);
    });
    Ok(super::finish_sums(ctx, sums, WORDS, 5, |w, count, bg| {
        let sums = WboitSums {
            weighted: Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32),
            weight: w[3] as f32,
            optical_depth: w[4] as f32 / WBOIT_OPTICAL_UNIT,
            count,
        };
        wboit(&sums, bg)
    }))
}
