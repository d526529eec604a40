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

pub(crate) fn render(ctx: &mut Ctx<'_>, average: bool) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let effect = ctx.resolve.effect;
    // r, g, b premultiplied sums, alpha sum, count
    let sums = ctx.alloc64(5, 0)?;
    ctx.pass(|f| {
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
    let mut states = ctx.states();
    let colors: Vec<Vec3> = sums
        .par_chunks(5)
        .zip(states.par_iter_mut())
        .map(|(s, state)| {
            let l = |i: usize| s[i].load(Relaxed) as f32;
            let w = WeightedSums {
                premultiplied: Vec3::new(l(0), l(1), l(2)) / (255.0 * 255.0),
                alpha: l(3) / 255.0,
                count: s[4].load(Relaxed) as u32,
            };
            state.captured = w.count;
            if average { weighted_average(&w, bg) } else { weighted_sum(&w, bg) }
        })
        .collect();
    if effect == Effect::Complexity {
        return Ok(super::finish(ctx, states));
    }
    let captured = states.iter().map(|s| u64::from(s.captured)).sum();
    let mut image = oit_core::Image::new(ctx.settings.width, ctx.settings.height, [0, 0, 0, 255]);
    // three powf a pixel: in parallel
    image.pixels.par_iter_mut().zip(colors.par_iter()).for_each(|(px, &c)| *px = crate::resolve::srgb(c));
    let mut frame = super::frame(ctx, image, captured);
    frame.stats.max_layers = states.iter().map(|s| s.captured).max().unwrap_or(0);
    Ok(frame)
}
