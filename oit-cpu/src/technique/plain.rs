//! `plain`: unsorted alpha blending, the answer a renderer without OIT gives and the speed
//! baseline of every other technique. Each fragment is blended over what its pixel holds in
//! submission order, the highest primitive on top.
//!
//! Submission order, defined: a GPU's blender composites the fragments of one draw in primitive
//! order, which oit's hardware path gets for free (its one draw is the scene in primitive order).
//! A CPU's threads (and a compute rasterizer's) reach a pixel in no fixed order, so here each
//! pixel's fragments are kept — a counter and as many slots as the deepest pixel holds, sized by a
//! counting pass — and sorted by primitive id, descending, then composited front to back through
//! the shared resolve: the same sum as blending them back to front by ascending id. A slot is one
//! 64-bit word, (u32::MAX − primitive id) above the payload: one primitive has one fragment a
//! pixel, so the payload never decides and ascending words are descending ids.
//!
//! Depth is never looked at: where a pixel's fragments in primitive order are also farthest
//! first, this equals the reference; elsewhere it is wrong in the way plain blending is wrong.

use oit_core::Compositor as _;
use std::sync::atomic::Ordering::Relaxed;

use oit_core::{Frame, OitError};

use super::Ctx;
use super::fabs::sort_keys;

/// The slot word of a fragment: ascending words are descending primitive ids.
#[inline]
pub(crate) fn slot_word(prim: u32, payload: u32) -> u64 {
    u64::from(u32::MAX - prim) << 32 | u64::from(payload)
}

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new)
    let deepest = ctx.max_depth_complexity()?;
    let k = ctx.plan.slots(deepest) as usize;
    let counters = ctx.alloc32(1, 0)?;
    // below each pixel's counter every slot is written before the resolve reads it
    let slots = ctx.scratch64(k)?;
    let shade = ctx.payload_shade();
    let payload = |f: &crate::raster::Fragment<'_>| ctx.payload(f);
    let lost = &*ctx;
    let generated = ctx.raster.for_each_fragment_with(shade, |f| {
        let px = f.pixel as usize;
        let i = counters[px].fetch_add(1, Relaxed) as usize;
        if i < k {
            slots[px * k + i].store(slot_word(f.prim, payload(f)), Relaxed);
        } else {
            // sized from the counting pass, a repeatable rasterizer never gets here
            lost.lose(px);
        }
    });
    ctx.passes += 1;
    ctx.fragments.get_or_insert(generated);
    let resolve = &ctx.resolve;
    Ok(super::finish_with(ctx, |px, words: &mut Vec<u64>, s| {
        let n = (counters[px].load(Relaxed) as usize).min(k);
        words.clear();
        words.extend(slots[px * k..px * k + n].iter().map(|w| w.load(Relaxed)));
        sort_keys(words);
        for &w in words.iter() {
            resolve.push(s, 0.0, w as u32);
        }
    }))
}

#[cfg(test)]
mod tests {
    use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};

    /// Overlapping quads seen from the front and from behind: in one view primitive order is
    /// farthest first and plain blending equals the reference pixel for pixel; in the other it
    /// is nearest first and plain blending puts the far quads on top, so every pixel two quads
    /// cover differs.
    #[test]
    fn exact_only_where_primitive_order_is_back_to_front() {
        let scene = load_scene("planes:3").unwrap();
        let settings = Settings { width: 32, height: 32, technique: Technique::Plain, ..Settings::default() };
        let backend = crate::CpuBackend::default();
        let mut equal_views = 0;
        for azimuth in [0.0, 180.0] {
            let camera = Camera::orbit_scene(&scene, View { azimuth, ..View::default() }, 1.0).unwrap();
            let plain = backend.render(&scene, &camera, &settings).unwrap();
            let reference = backend
                .render(&scene, &camera, &Settings { technique: Technique::Reference, ..settings.clone() })
                .unwrap();
            assert_eq!(plain.stats.lost, 0);
            assert_eq!(plain.stats.captured, plain.stats.fragments);
            assert_eq!(plain.stats.geometry_passes, 2);
            assert!(plain.stats.fragments > 0);
            let layers = reference.layers.as_ref().unwrap();
            let deep = layers.iter().filter(|&&n| n >= 2).count();
            assert!(deep > 0, "no pixel holds two quads at azimuth {azimuth}");
            let differs =
                plain.image.pixels.iter().zip(&reference.image.pixels).filter(|(a, b)| a != b).count();
            if differs == 0 {
                equal_views += 1;
            } else {
                // wrong exactly where order matters: pixels of two or more layers
                assert_eq!(differs, deep, "azimuth {azimuth}");
            }
        }
        assert_eq!(equal_views, 1, "plain must equal the reference from exactly one side");
    }
}
