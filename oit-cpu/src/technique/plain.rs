//! `plain`: unsorted alpha blending, the answer a renderer without OIT gives and the speed
//! baseline of every other technique. Each fragment is blended over what its pixel holds in
//! submission order, the highest primitive on top.
//!
//! Submission order, defined: a GPU's blender composites the fragments of one draw in primitive
//! order, which oit's hardware path gets for free (its one draw is the scene in primitive order).
//! A CPU's threads reach a pixel in no fixed order unless the pass is cut so that one thread owns
//! each pixel: here one geometry pass cut into bands of rows
//! ([`Rasterizer::for_each_fragment_in_order`](crate::raster::Rasterizer::for_each_fragment_in_order)),
//! each band walking its triangles highest primitive first, so each pixel's fragments arrive top
//! of the stack first and are composited front to back as they come (the same sum as blending
//! them back to front by ascending id), into a running colour and transmittance and a count per
//! pixel. No counting pass, no slots, no sort (a compute rasterizer, which has no such order,
//! keeps each pixel's fragments and sorts them by primitive id: the plan's `in_order`). The
//! composite is the shared resolve's, in the same order, so the image is the one that sorting
//! the pixel's fragments by descending id and pushing them through the resolve gives, bit for
//! bit (`in_order_equals_sorting` below).
//!
//! Depth is never looked at: where a pixel's fragments in primitive order are also farthest
//! first, this equals the reference; elsewhere it is wrong in the way plain blending is wrong.

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use oit_core::composite::FrontToBack;
use oit_core::rules::unpack_rgba8;
use oit_core::{Effect, Frame, OitError};

use super::Ctx;
use crate::raster::Fragment;
use crate::resolve::{PixelState, srgb};

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // translucency and Fresnel are refused by the plan (oit_core::plan::Plan::new); the heat map
    // needs the counts alone
    let colour = ctx.resolve.effect != Effect::Complexity;
    // the running (premultiplied colour, transmittance) of each pixel, read only where its
    // count says a fragment wrote it, and the count
    let fronts = ctx.scratch_words32(ctx.pixels as u64 * 4)?;
    let mut counts = ctx.alloc32(1, 0)?;
    let shade = ctx.payload_shade();
    let generated = ctx.raster.for_each_fragment_in_order(shade, |f: &Fragment<'_>| {
        let px = f.pixel as usize;
        // the band that holds the pixel is the one thread that writes it
        let n = counts[px].load(Relaxed);
        counts[px].store(n + 1, Relaxed);
        if !colour {
            return;
        }
        let words = &fronts[4 * px..4 * px + 4];
        let mut front = if n == 0 { FrontToBack::default() } else { load(words) };
        front.under(unpack_rgba8(ctx.payload(f)));
        store(words, front);
    });
    ctx.ran_pass(generated);
    if colour {
        let frame = finish_transparency(ctx, &counts, &fronts);
        counts.mark_clean(crate::pool::Clean::Word(0));
        return Ok(frame);
    }
    let frame = super::finish_with(ctx, |px, _: &mut (), s: &mut PixelState| {
        // each count read once, and left at zero for the next frame
        let n = counts[px].swap(0, Relaxed);
        if n > 0 {
            let front = if colour { load(&fronts[4 * px..4 * px + 4]) } else { FrontToBack::default() };
            *s = PixelState::composited(front, n);
        }
    });
    counts.mark_clean(crate::pool::Clean::Word(0));
    Ok(frame)
}

/// The transparency effect's ending: each pixel's running composite over what lies behind it
/// (the opaque colour or the background), as the
/// shared resolve finishes a state holding only it ([`PixelState::composited`]: the front over
/// the background, to sRGB), without making that state; the counts read once and left at zero.
fn finish_transparency(
    ctx: &Ctx<'_>,
    counts: &[std::sync::atomic::AtomicU32],
    fronts: &[std::sync::atomic::AtomicU32],
) -> Frame {
    let resolve = &ctx.resolve;
    let empty = srgb(FrontToBack::default().over(ctx.settings.background));
    super::finish_pixels(ctx, |px| {
        let n = counts[px].swap(0, Relaxed);
        let colour = match (n, resolve.opaque) {
            (0, None) => empty,
            (0, Some(_)) => srgb(resolve.background_at(px)),
            _ => srgb(load(&fronts[4 * px..4 * px + 4]).over(resolve.background_at(px))),
        };
        (colour, n)
    })
}

/// A pixel's running composite from its four words (colour, then transmittance, as f32 bits).
#[inline]
fn load(words: &[std::sync::atomic::AtomicU32]) -> FrontToBack {
    let w = |i: usize| f32::from_bits(words[i].load(Relaxed));
    FrontToBack { color: Vec3::new(w(0), w(1), w(2)), transmittance: w(3) }
}

/// Writes a pixel's running composite to its four words.
#[inline]
fn store(words: &[std::sync::atomic::AtomicU32], front: FrontToBack) {
    let [r, g, b] = front.color.to_array();
    for (word, v) in words.iter().zip([r, g, b, front.transmittance]) {
        word.store(v.to_bits(), Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};

    /// The banded pass's image against the slow definition: every fragment of a plain pass
    /// gathered, each pixel's sorted by primitive id, highest first, composited front to back in
    /// f32 over the background, to sRGB. Bit for bit, on scenes whose pixels hold many fragments
    /// from many primitives (and at 1 and 3 threads: bands of other heights), and the heat map
    /// of the complexity effect equals the reference's (the same counts). Mutations caught: a
    /// band's triangles in ascending order, a pixel's count not reset by the resolve (the second
    /// frame from the kept storage), the first fragment composited over a stale colour.
    #[test]
    fn in_order_equals_sorting() {
        use glam::Vec3;
        use oit_core::composite::{FrontToBack, linear_to_srgb8};
        use oit_core::rules::{pack_rgba8, unpack_rgba8};
        use std::sync::Mutex;

        for name in ["knot", "cluster:120", "planes:12"] {
            let scene = load_scene(name).unwrap();
            let settings =
                Settings { width: 96, height: 80, technique: Technique::Plain, ..Settings::default() };
            let camera = Camera::orbit_scene(&scene, View::default(), 96.0 / 80.0).unwrap();
            let raster = crate::raster::Rasterizer::new(&scene, &camera, &settings);
            let all = Mutex::new(Vec::new());
            raster.for_each_shaded_fragment(|f| {
                all.lock().unwrap().push((f.pixel, f.prim, pack_rgba8(f.color())))
            });
            let mut all = all.into_inner().unwrap();
            // by pixel, then highest primitive first
            all.sort_unstable_by_key(|&(px, prim, _)| (px, u32::MAX - prim));
            let mut expected = vec![[0u8, 0, 0, 255]; 96 * 80];
            let mut deep = 0;
            for (px, out) in expected.iter_mut().enumerate() {
                let mut front = FrontToBack::default();
                let here = all.iter().filter(|f| f.0 as usize == px);
                for (i, f) in here.enumerate() {
                    front.under(unpack_rgba8(f.2));
                    deep += usize::from(i > 0);
                }
                let c: Vec3 = front.finish(settings.background);
                *out = [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255];
            }
            assert!(deep > 1000, "{name}: only {deep} fragments behind another");
            for threads in [1, 3] {
                let backend = crate::CpuBackend::with_threads(Some(threads));
                let mut prepared = backend.prepare(&scene).unwrap();
                for frame in 0..2 {
                    let f = prepared.frame(&camera, &settings).unwrap();
                    assert_eq!(f.stats.fragments, all.len() as u64, "{name}");
                    assert_eq!(f.stats.captured, all.len() as u64, "{name}");
                    assert_eq!(f.stats.geometry_passes, 1, "{name}");
                    // a count left set by the last frame's resolve would come back as another
                    // array of the pool (the loss counters are lent first)
                    assert_eq!(f.stats.lost, 0, "{name}, {threads} threads, frame {frame}");
                    let differ = f.image.pixels.iter().zip(&expected).filter(|(a, b)| a != b).count();
                    assert_eq!(differ, 0, "{name}, {threads} threads, frame {frame}: pixels differ");
                }
                let mut heat = |technique| {
                    let s = Settings { technique, effect: oit_core::Effect::Complexity, ..settings.clone() };
                    prepared.frame(&camera, &s).unwrap().image.pixels
                };
                let plain = heat(Technique::Plain);
                assert!(plain == heat(Technique::Reference), "{name}: heat maps differ");
            }
        }
    }

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
            assert_eq!(plain.stats.geometry_passes, 1);
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
