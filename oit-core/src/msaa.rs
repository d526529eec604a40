//! Multisampling (issue 40): the sample counts oit takes and the standard sample positions of
//! the graphics APIs, defined once here for every backend.
//!
//! With `Settings::samples` above 1 a triangle gives a pixel a fragment where it covers any of
//! the pixel's samples, and the fragment carries its coverage mask (bit `i` set where sample
//! `i` is covered). Shading and depth stay one evaluation at the pixel's centre (MSAA, not
//! supersampling). See docs/msaa.md.

use serde::Serialize;

use crate::{Camera, Effect, OitError, Settings, Stats, Technique};

/// The sample counts `--samples` takes.
pub const SAMPLE_COUNTS: [u32; 3] = [1, 4, 8];

/// Positions are given in 1/16 pixel from the pixel's top-left corner (x right, y down): the
/// grid the standard patterns lie on, exact in oit's 1/256-pixel fixed point.
pub const POSITION_UNITS: u32 = 16;

/// The single sample: the pixel's centre.
pub const POSITIONS_1: [(u8, u8); 1] = [(8, 8)];

/// Vulkan's and Direct3D's standard 4× pattern (the Vulkan spec's "standard sample locations"
/// table), in 1/16 pixel: (0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875).
pub const POSITIONS_4: [(u8, u8); 4] = [(6, 2), (14, 6), (2, 10), (10, 14)];

/// The standard 8× pattern, in 1/16 pixel: (0.5625, 0.3125), (0.4375, 0.6875), (0.8125, 0.5625),
/// (0.3125, 0.1875), (0.1875, 0.8125), (0.0625, 0.4375), (0.6875, 0.9375), (0.9375, 0.0625).
pub const POSITIONS_8: [(u8, u8); 8] = [(9, 5), (7, 11), (13, 9), (5, 3), (3, 13), (1, 7), (11, 15), (15, 1)];

/// Checks a sample count: 1, 4 or 8.
pub fn check_samples(samples: u32) -> Result<(), OitError> {
    if SAMPLE_COUNTS.contains(&samples) {
        Ok(())
    } else {
        Err(OitError::InvalidSettings(format!(
            "--samples {samples} is not a sample count oit takes: use 1, 4 or 8 (the standard patterns)"
        )))
    }
}

/// The sample positions of `samples` samples a pixel, in 1/16 pixel from its top-left corner
/// ([`POSITION_UNITS`]); the centre alone for 1 or any count [`check_samples`] refuses.
pub fn positions(samples: u32) -> &'static [(u8, u8)] {
    match samples {
        4 => &POSITIONS_4,
        8 => &POSITIONS_8,
        _ => &POSITIONS_1,
    }
}

/// The sample positions in pixels from the top-left corner, as floats (exact).
pub fn positions_f32(samples: u32) -> Vec<(f32, f32)> {
    positions(samples)
        .iter()
        .map(|&(x, y)| (f32::from(x) / POSITION_UNITS as f32, f32::from(y) / POSITION_UNITS as f32))
        .collect()
}

/// The mask of every sample of a pixel: `samples` low bits set.
pub fn full_mask(samples: u32) -> u8 {
    match samples {
        8.. => u8::MAX,
        n => ((1u16 << n) - 1) as u8,
    }
}

/// How a technique composites a fragment's coverage mask above one sample (docs/msaa.md), as a
/// frame's `Stats::coverage` reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Coverage {
    /// Per sample: the mask kept beside each entry's key, each sample compositing the entries
    /// that cover it, the pixel the mean of its samples (reference, dfb, ll, fabs); or each
    /// peeled layer's mask, composited into per-sample accumulators (dp, ddp, mlp:
    /// [`peels_masks`]).
    Sample,
    /// The fragment composited over the whole pixel, its alpha scaled by the fraction of the
    /// pixel's samples it covers (popcount(mask) / samples): the techniques without room for the
    /// mask (the fixed packings, the weighted sums, the bucket peels, the merges), and dp, ddp and mlp
    /// under `--coverage fraction`.
    Fraction,
    /// The fragment composited over the whole pixel at full alpha, whatever its mask: the
    /// per-pixel capture baseline (`--coverage pixel`), and what a technique does under an
    /// effect whose payload carries no alpha to scale (Fresnel, translucency).
    Pixel,
}

/// Whether `technique` keeps each fragment's mask beside its key and composites per sample.
pub fn keeps_masks(technique: Technique) -> bool {
    matches!(
        technique,
        Technique::Reference
            | Technique::Dfb
            | Technique::Ll
            | Technique::Fabs { .. }
            | Technique::Kbuf { .. }
    )
}

/// Whether `technique` peels per sample above one sample (dp, ddp, mlp: docs/msaa.md): each
/// peel finds a pixel's next layers by their (depth, primitive id) keys (mlp's M a pass), keeps
/// the peeled fragments' masks and composites them into per-sample accumulators. Where
/// [`coverage`] says [`Coverage::Sample`] for it ([`peels_per_sample`]).
pub fn peels_masks(technique: Technique) -> bool {
    matches!(technique, Technique::Dp | Technique::Ddp | Technique::Mlp { .. })
}

/// The most primitives a scene may have where the frame peels per sample ([`peels_per_sample`]):
/// a peel's key holds the primitive id (below this) in 29 bits, above 3 bits of [`peel_key`]'s
/// sample.
pub const PEEL_KEY_PRIMITIVES: u32 = 1 << 29;

/// A fragment's key in the per-sample peels (dp, ddp and mlp above one sample; oit-cpu's and the
/// compute and hardware paths' atomics captures alike): its depth bits, then its primitive id,
/// then the lowest sample its coverage `mask` holds. The sample tells apart the pieces of one
/// triangle: clipped at the near or the far plane, a triangle is fan-triangulated into pieces
/// that keep its primitive id ([`crate::setup`]), and above one sample two pieces may cover one
/// pixel at the same depth, though never one sample (the fill rule gives a sample on their shared
/// edge to one of them). A peel keeps one fragment a key, so with the primitive id alone it kept
/// one piece and lost the other without a count. Between primitive ids the order is the ids', as
/// the reference's; within one it is the pieces' samples', which no sample sees twice. The id must
/// be below [`PEEL_KEY_PRIMITIVES`] (the plan refuses scenes of more primitives).
#[inline]
pub fn peel_key(depth_bits: u32, prim: u32, mask: u8) -> u64 {
    u64::from(depth_bits) << 32 | u64::from(prim) << 3 | u64::from(mask.trailing_zeros() & 7)
}

/// Whether a frame under `settings` peels per sample ([`peels_masks`]: dp, ddp or mlp, several
/// samples, [`Coverage::Sample`]); `--coverage pixel`, `--coverage fraction` and translucency
/// (whose per-sample state the accumulators do not keep) leave them by coverage fraction or per
/// pixel as the techniques without a mask.
pub fn peels_per_sample(settings: &Settings) -> bool {
    peels_masks(settings.technique) && coverage(settings) == Some(Coverage::Sample)
}

/// What a frame under `settings` does with its fragments' coverage masks; `None` at one sample.
/// The reference is per sample always (the MSAA target); a technique that keeps masks is per
/// sample unless `--coverage pixel`, and so are dp, ddp and mlp unless `--coverage pixel` or
/// `--coverage fraction` or translucency; every other technique weighs a fragment's alpha by its
/// coverage fraction (measured to err less than per-pixel coverage against the per-sample
/// reference on each but bdp's colour mode, which takes it whole: docs/msaa.md), or takes it at
/// full alpha under `--coverage pixel` and under the effects whose payload has no alpha
/// (Fresnel's normal, translucency's absorbing colour); `--coverage fraction` weighs it in
/// every one.
pub fn coverage(settings: &Settings) -> Option<Coverage> {
    if settings.samples <= 1 {
        return None;
    }
    let technique = settings.technique;
    Some(if technique == Technique::Reference {
        Coverage::Sample
    } else if settings.pixel_coverage {
        Coverage::Pixel
    } else if keeps_masks(technique) {
        Coverage::Sample
    } else if peels_masks(technique) && !settings.fraction_coverage && settings.effect != Effect::Translucency
    {
        // the peels keep the peeled layer's mask and composite it per sample (transparency,
        // Fresnel's transmittance, the heat map's counts); `--coverage fraction` keeps the
        // coverage-fraction peel to measure it against
        Coverage::Sample
    } else if matches!(settings.effect, Effect::Fresnel | Effect::Translucency)
        || matches!(technique, Technique::Mdts { .. })
    {
        // no alpha to weight: Fresnel's payload is the normal, translucency's colour absorbs,
        // and `mdts`'s 32-bit word keeps RGB only (the plan's alpha for every fragment)
        Coverage::Pixel
    } else if settings.fraction_coverage {
        Coverage::Fraction
    } else if let Technique::Bdp { passes } = technique
        && settings.bdp_color_mode(passes).unwrap_or(false)
    {
        // one colour a bucket, the larger packed word kept: the two halves of a surface split
        // across an edge fall in one bucket and only one is kept, so at full alpha the pixel
        // gets the one layer the samples see, where weighted it gets a thinner one (measured:
        // `techniques_without_masks_weigh_alpha_by_coverage`)
        Coverage::Pixel
    } else {
        Coverage::Fraction
    })
}

/// A fragment's alpha under [`Coverage::Fraction`]: `alpha` times the fraction of the `samples`
/// samples its `mask` covers (k/4 and k/8 are exact in f32, so one rounding, the product's: the
/// compute path's `coverage_weighted` makes the same).
#[inline]
pub fn fraction_alpha(alpha: f32, mask: u8, samples: u32) -> f32 {
    alpha * (mask.count_ones() as f32 / samples as f32)
}

/// The supersampled reference (`Settings::supersample`, docs/msaa.md), made alike on every
/// backend: one single-sample reference frame a sample position ([`supersample_frames`]), each
/// rasterized and shaded at its pixels' centres under a projection moved so that the sample's
/// position falls on them, the frames' linear colours averaged. Whether a frame of `settings` is
/// one: the reference with `--supersample` at several samples (other techniques ignore it).
pub fn is_supersampled(settings: &Settings) -> bool {
    settings.supersample && settings.samples > 1 && settings.technique == Technique::Reference
}

/// The frames of the supersampled reference of `settings` seen by `camera`: the settings of each
/// (one sample, the reference, the rest as given: the same size and window), and per sample
/// position ([`positions_f32`]) the camera whose projection moves that position of every pixel
/// onto the pixel's centre: screen x by ½ − sx, which is NDC x by 2(½ − sx)/W of the full frame's
/// width (a window's frame moves as the full frame does); screen y grows down, NDC y up. The
/// positions lie on the 1/16-pixel grid, so the move is a whole number of the rasterizer's
/// 1/256-pixel fixed-point steps up to the projection's f32 rounding.
pub fn supersample_frames(camera: &Camera, settings: &Settings) -> (Settings, Vec<Camera>) {
    let single =
        Settings { samples: 1, supersample: false, technique: Technique::Reference, ..settings.clone() };
    let (full_w, full_h) = match settings.region {
        Some(r) => (r.full_width as f32, r.full_height as f32),
        None => (settings.width as f32, settings.height as f32),
    };
    let cameras = positions_f32(settings.samples)
        .into_iter()
        .map(|(sx, sy)| {
            let (dx, dy) = (2.0 * (0.5 - sx) / full_w, -2.0 * (0.5 - sy) / full_h);
            let mut moved = *camera;
            moved.proj = glam::Mat4::from_translation(glam::Vec3::new(dx, dy, 0.0)) * camera.proj;
            moved
        })
        .collect();
    (single, cameras)
}

/// What the frames of a supersampled reference add up to, alike on every backend: the geometry
/// passes, fragments, captured and lost fragments of every frame summed (each sample's frame is
/// a frame of its own fragments), and in a scene with opaque objects (each frame draws its own
/// opaque pass, at one sample) the occluded fragments and the opaque pass's fragments and masked
/// ones summed alike, so that a frame's accounting (`captured + merged + lost + occluded =
/// fragments`) holds of the sums; the largest frame's storage (the frames run one after the
/// other), and per pixel the most fragments one frame gave it (the frame's `layers`, whose
/// nonzero pixels are the covered ones) and the fragments lost in all.
#[derive(Clone, Debug, Default)]
pub struct SupersampleTotals {
    /// The summed stats.
    pub stats: Stats,
    /// Per pixel, the most fragments one frame gave it.
    pub layers: Option<Vec<u32>>,
    /// Per pixel, the fragments lost in all frames.
    pub lost_pixels: Option<Vec<u32>>,
}

impl SupersampleTotals {
    /// Adds one sample's frame: its `stats`, and its per-pixel `layers` and `lost_pixels` where
    /// it has them.
    pub fn add(&mut self, stats: &Stats, layers: Option<&[u32]>, lost_pixels: Option<&[u32]>) {
        let t = &mut self.stats;
        t.geometry_passes += stats.geometry_passes;
        t.fragments += stats.fragments;
        t.captured += stats.captured;
        t.lost += stats.lost;
        t.occluded += stats.occluded;
        t.opaque_fragments += stats.opaque_fragments;
        t.masked += stats.masked;
        t.storage_bytes = t.storage_bytes.max(stats.storage_bytes);
        t.max_layers = t.max_layers.max(stats.max_layers);
        t.wall_ms += stats.wall_ms;
        if let Some(ms) = stats.gpu_ms {
            t.gpu_ms = Some(t.gpu_ms.unwrap_or(0.0) + ms);
        }
        let fold = |into: &mut Option<Vec<u32>>, from: Option<&[u32]>, f: fn(u32, u32) -> u32| {
            if let Some(from) = from {
                match into {
                    Some(v) => v.iter_mut().zip(from).for_each(|(a, &b)| *a = f(*a, b)),
                    None => *into = Some(from.to_vec()),
                }
            }
        };
        fold(&mut self.layers, layers, u32::max);
        fold(&mut self.lost_pixels, lost_pixels, u32::saturating_add);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_are_the_standard_ones() {
        let p4 = positions_f32(4);
        assert_eq!(p4, vec![(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)]);
        let p8 = positions_f32(8);
        assert_eq!(p8[0], (0.5625, 0.3125));
        assert_eq!(p8[7], (0.9375, 0.0625));
        assert_eq!(positions_f32(1), vec![(0.5, 0.5)]);
        assert_eq!((full_mask(1), full_mask(4), full_mask(8)), (1, 0xF, 0xFF));
        assert!(check_samples(2).is_err() && check_samples(0).is_err() && check_samples(16).is_err());
    }
}
