//! `mboit:M`: moment-based OIT (Münstermann et al., HPG 2018) with M = 4 or 6 power moments, two
//! geometry passes, no ordering. The first pass sums each pixel's optical depth Σ a (a = −ln(1 − α),
//! the table `WBOIT_OPTICAL_DEPTH`) and its moments Σ a·zᵏ, k = 1..M, of the warped depth z
//! (`oit_core::technique::mboit::mboit_depth`); the second weighs each fragment by the transmittance in front
//! of it, e^(−Σa · share), where `oit_core::technique::mboit::mboit_share_in_front` (four moments) or
//! `mboit6_share_in_front` (six) bounds the share from the moments, and sums Σ T·α·c, Σ T·α and
//! the count. Every sum is an integer (the powers in
//! units of 2⁻²⁰, T in 16 bits), so none depends on the order threads add in;
//! `oit_core::technique::mboit::mboit` composites them.

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use oit_core::rules::pack_rgba8;
use oit_core::technique::mboit::{
    MBOIT_POWER_UNIT, MboitSums, mboit, mboit_depth, mboit_powers, mboit_share_in_front, mboit_weight16,
    mboit6_share_in_front,
};
use oit_core::technique::wboit::{WBOIT_OPTICAL_DEPTH, WBOIT_OPTICAL_UNIT};
use oit_core::{Frame, OitError, Technique};

use super::Ctx;
use crate::raster::prefetch;

/// u64 words a pixel besides the moments: Σ a, then (after Σ a·z, …, Σ a·zᴹ, two's complement)
/// Σ T·α·r, Σ T·α·g, Σ T·α·b, Σ T·α and the count: M + 6 in all (the plan's array).
const OTHER_WORDS: usize = 6;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let r = ctx.resolve.camera.near / ctx.resolve.camera.far;
    let m = match ctx.plan.technique {
        Technique::Mboit { m } => m as usize,
        t => unreachable!("mboit's render given {t}"),
    };
    let words = m + OTHER_WORDS;
    let (weighted, count) = (m + 1, m + 5);
    let sums = ctx.alloc64(words, 0)?;
    let ahead = |px: u32| prefetch(&sums[words * px as usize..words * px as usize + words]);
    // the moments
    ctx.pass_shaded_ahead(ahead, |f| {
        let a = WBOIT_OPTICAL_DEPTH[(pack_rgba8(f.color()) >> 24) as usize];
        let base = f.pixel as usize * words;
        sums[base].fetch_add(u64::from(a), Relaxed);
        for (k, p) in mboit_powers(mboit_depth(f.depth, r)).into_iter().take(m).enumerate() {
            sums[base + 1 + k].fetch_add((i64::from(a) * p) as u64, Relaxed);
        }
    });
    // each fragment weighed by the transmittance its pixel's moments bound in front of it
    ctx.pass_shaded_ahead(ahead, |f| {
        let c = pack_rgba8(f.color());
        let base = f.pixel as usize * words;
        let w = mboit_weight16(transmittance(&sums[base..base + 1 + m], mboit_depth(f.depth, r)));
        let wa = w * u64::from(c >> 24);
        let base = base + weighted;
        sums[base].fetch_add(wa * u64::from(c & 0xff), Relaxed);
        sums[base + 1].fetch_add(wa * u64::from(c >> 8 & 0xff), Relaxed);
        sums[base + 2].fetch_add(wa * u64::from(c >> 16 & 0xff), Relaxed);
        sums[base + 3].fetch_add(wa, Relaxed);
        sums[base + 4].fetch_add(1, Relaxed);
    });
    Ok(super::finish_sums(ctx, sums, words, count, |w, count, bg| {
        let s = &w[weighted..];
        let sums = MboitSums {
            weighted: Vec3::new(s[0] as f32, s[1] as f32, s[2] as f32),
            weight: s[3] as f32,
            optical_depth: w[0] as f32 / WBOIT_OPTICAL_UNIT,
            count,
        };
        mboit(&sums, bg)
    }))
}

/// The transmittance in front of warped depth `z` from a pixel's first-pass sums (Σ a, then the
/// four or six moment sums: `s` holds 5 or 7 words), as `mboit.wgsl`'s `capture`.
fn transmittance(s: &[std::sync::atomic::AtomicU64], z: f32) -> f32 {
    let total = s[0].load(Relaxed);
    if total == 0 {
        return 1.0;
    }
    let b0 = total as f32;
    let moment = |k: usize| s[1 + k].load(Relaxed) as i64 as f32 / b0 / MBOIT_POWER_UNIT;
    let share = if s.len() == 7 {
        mboit6_share_in_front(std::array::from_fn(moment), z)
    } else {
        mboit_share_in_front(std::array::from_fn(moment), z)
    };
    (-(b0 / WBOIT_OPTICAL_UNIT) * share).exp()
}
