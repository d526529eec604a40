//! `mboit`: moment-based OIT (Münstermann et al., HPG 2018) with four power moments, two geometry
//! passes, no ordering. The first pass sums each pixel's optical depth Σ a (a = −ln(1 − α), the
//! table `WBOIT_OPTICAL_DEPTH`) and its moments Σ a·zᵏ, k = 1..4, of the warped depth z
//! (`oit_core::rules::mboit_depth`); the second weighs each fragment by the transmittance in front
//! of it, e^(−Σa · share), where `oit_core::composite::mboit_share_in_front` bounds the share from
//! the moments, and sums Σ T·α·c, Σ T·α and the count. Every sum is an integer (the powers in
//! units of 2⁻²⁰, T in 16 bits), so none depends on the order threads add in;
//! `oit_core::composite::mboit` composites them.

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use oit_core::composite::{MboitSums, mboit, mboit_share_in_front};
use oit_core::rules::{
    MBOIT_POWER_UNIT, WBOIT_OPTICAL_DEPTH, WBOIT_OPTICAL_UNIT, mboit_depth, mboit_powers, mboit_weight16,
    pack_rgba8,
};
use oit_core::{Frame, OitError};

use super::Ctx;
use crate::raster::prefetch;

/// u64 words a pixel: Σ a, Σ a·z, Σ a·z², Σ a·z³, Σ a·z⁴ (two's complement), then Σ T·α·r,
/// Σ T·α·g, Σ T·α·b, Σ T·α and the count.
const WORDS: usize = 10;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let r = ctx.resolve.camera.near / ctx.resolve.camera.far;
    let sums = ctx.alloc64(WORDS, 0)?;
    let ahead = |px: u32| prefetch(&sums[WORDS * px as usize..WORDS * px as usize + WORDS]);
    // the moments
    ctx.pass_shaded_ahead(ahead, |f| {
        let a = WBOIT_OPTICAL_DEPTH[(pack_rgba8(f.color()) >> 24) as usize];
        let base = f.pixel as usize * WORDS;
        sums[base].fetch_add(u64::from(a), Relaxed);
        for (k, p) in mboit_powers(mboit_depth(f.depth, r)).into_iter().enumerate() {
            sums[base + 1 + k].fetch_add((i64::from(a) * p) as u64, Relaxed);
        }
    });
    // each fragment weighed by the transmittance its pixel's moments bound in front of it
    ctx.pass_shaded_ahead(ahead, |f| {
        let c = pack_rgba8(f.color());
        let base = f.pixel as usize * WORDS;
        let w = mboit_weight16(transmittance(&sums[base..base + 5], mboit_depth(f.depth, r)));
        let wa = w * u64::from(c >> 24);
        sums[base + 5].fetch_add(wa * u64::from(c & 0xff), Relaxed);
        sums[base + 6].fetch_add(wa * u64::from(c >> 8 & 0xff), Relaxed);
        sums[base + 7].fetch_add(wa * u64::from(c >> 16 & 0xff), Relaxed);
        sums[base + 8].fetch_add(wa, Relaxed);
        sums[base + 9].fetch_add(1, Relaxed);
    });
    Ok(super::finish_sums(ctx, sums, WORDS, 9, |w, count, bg| {
        let sums = MboitSums {
            weighted: Vec3::new(w[5] as f32, w[6] as f32, w[7] as f32),
            weight: w[8] as f32,
            optical_depth: w[0] as f32 / WBOIT_OPTICAL_UNIT,
            count,
        };
        mboit(&sums, bg)
    }))
}

/// The transmittance in front of warped depth `z` from a pixel's first-pass sums (Σ a, then the
/// four moment sums), as `mboit.wgsl`'s `mboit_transmittance`.
fn transmittance(s: &[std::sync::atomic::AtomicU64], z: f32) -> f32 {
    let total = s[0].load(Relaxed);
    if total == 0 {
        return 1.0;
    }
    let b0 = total as f32;
    let m: [f32; 4] = std::array::from_fn(|k| s[1 + k].load(Relaxed) as i64 as f32 / b0 / MBOIT_POWER_UNIT);
    (-(b0 / WBOIT_OPTICAL_UNIT) * mboit_share_in_front(m, z)).exp()
}
