//! `reference`: the exact A-buffer. A counting pass sizes each pixel's list, a second pass fills
//! it (atomic increment on a per-pixel cursor), then each list is sorted by (depth, primitive id)
//! and composited in f64. Two geometry passes; memory for every fragment.
//!
//! Every effect runs here in f64 on the sorted list ([`oit_core::composite`]'s `*_f64`
//! functions), not through the techniques' f32 [`Resolve`](crate::resolve::Resolve), so the
//! ground truth and the resolve it judges are two implementations of one definition.

use std::sync::atomic::Ordering::Relaxed;

use glam::DVec3;
use oit_core::composite::{fresnel_f64, front_to_back_f64, heat_f64, linear_to_srgb8_f64, translucency_f64};
use oit_core::plan::Counted;
use oit_core::rules::{depth_bits, unpack_normal_f64, unpack_rgba8_f64};
use oit_core::{Effect, Frame, Image, OitError};
use rayon::prelude::*;

use super::Ctx;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let (linear, counts, fragments) = linear(ctx)?;
    let pixels: Vec<[u8; 4]> = linear.into_par_iter().map(srgb8_f64).collect();
    let image = Image { width: ctx.settings.width, height: ctx.settings.height, pixels };
    let mut frame = super::frame(ctx, image, fragments);
    frame.stats.max_layers = counts.iter().copied().max().unwrap_or(0);
    frame.layers = Some(counts);
    Ok(frame)
}

/// The reference's passes and composite: each pixel's linear colour, each pixel's fragment
/// count, and the frame's fragments (the supersampled reference averages the linear colours of
/// several frames before it encodes them).
pub(crate) fn linear(ctx: &mut Ctx<'_>) -> Result<(Vec<DVec3>, Vec<u32>, u64), OitError> {
    let counts = ctx.alloc32(1, 0)?;
    ctx.pass(|f| {
        counts[f.pixel as usize].fetch_add(1, Relaxed);
    });
    let counts: Vec<u32> = counts.iter().map(|c| c.load(Relaxed)).collect();
    let mut offsets = Vec::with_capacity(counts.len() + 1);
    let mut total = 0usize;
    for &c in &counts {
        offsets.push(total);
        total += c as usize;
    }
    offsets.push(total);
    let deepest = counts.iter().copied().max().unwrap_or(0);
    ctx.check_counted(Counted { deepest, fragments: total as u64 })?;
    // the plan's arrays: the counts above serve as the fill cursors (a second array here, not
    // counted, as a GPU clears and reuses the counts); the offsets and the entries (counted as
    // they are lent), every slot of which the fill pass writes
    ctx.storage_bytes += offsets.len() as u64 * 4;
    let cursor = ctx.pool.u32s(counts.len(), 0);
    let keys = ctx.scratch_words64(total as u64)?;
    let payloads = ctx.scratch_words32(total as u64)?;
    let shade = ctx.payload_shade();
    let resolve_payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
    let raster = ctx.raster;
    raster.for_each_fragment_with(shade, |f| {
        let px = f.pixel as usize;
        let slot = offsets[px] + cursor[px].fetch_add(1, Relaxed) as usize;
        keys[slot].store((depth_bits(f.depth) as u64) << 32 | f.prim as u64, Relaxed);
        payloads[slot].store(resolve_payload(f), Relaxed);
    });
    ctx.passes += 1;
    drop(cursor);
    let (keys, payloads) = (&*keys, &*payloads);

    let resolve = &ctx.resolve;
    let (camera, effect) = (ctx.camera, ctx.settings.effect);
    let per_length = ctx.per_length;
    let deepest = counts.iter().copied().max().unwrap_or(0).max(1);
    let pixels: Vec<DVec3> = (0..counts.len())
        .into_par_iter()
        // one list a task, reused pixel after pixel: (key, payload) pairs sorted by key, which is
        // (depth, primitive id) and unique at a pixel (one fragment a primitive)
        .map_init(Vec::new, |list: &mut Vec<(u64, u32)>, px| {
            list.clear();
            list.extend(
                (offsets[px]..offsets[px + 1]).map(|i| (keys[i].load(Relaxed), payloads[i].load(Relaxed))),
            );
            list.sort_unstable_by_key(|&(key, _)| key);
            let layers = list.iter().copied();
            let bg = resolve.background_at(px).as_dvec3();
            let c: DVec3 = match effect {
                Effect::Complexity if counts[px] == 0 => bg,
                Effect::Complexity => heat_f64(f64::from(counts[px]) / f64::from(deepest)),
                _ => composite_f64(effect, camera, per_length, layers, bg),
            };
            c
        })
        .collect();
    Ok((pixels, counts, total as u64))
}

/// A linear colour as an sRGB8 pixel, in f64 (the reference's encoding).
pub(crate) fn srgb8_f64(c: DVec3) -> [u8; 4] {
    [linear_to_srgb8_f64(c.x), linear_to_srgb8_f64(c.y), linear_to_srgb8_f64(c.z), 255]
}

/// The reference's f64 composite of one pixel's (or one sample's) `layers`, (key, payload) pairs
/// nearest first, over `bg`, under every effect but the heat map (which needs the frame's
/// deepest pixel).
pub(crate) fn composite_f64(
    effect: Effect,
    camera: &oit_core::Camera,
    per_length: f64,
    layers: impl Iterator<Item = (u64, u32)>,
    bg: DVec3,
) -> DVec3 {
    let depth = |key: u64| f32::from_bits((key >> 32) as u32);
    match effect {
        Effect::Transparency | Effect::Complexity => {
            front_to_back_f64(layers.map(|(_, p)| unpack_rgba8_f64(p)), bg)
        }
        Effect::Translucency => translucency_f64(
            layers.map(|(key, p)| (camera.linear_depth_f64(depth(key)), unpack_rgba8_f64(p))),
            per_length,
            bg,
        ),
        Effect::Fresnel => {
            let forward = camera.forward.as_dvec3();
            fresnel_f64(layers.map(|(_, p)| unpack_normal_f64(p).dot(forward)), bg)
        }
    }
}
