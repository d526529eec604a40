//! What a backend returns: the image and the numbers of how it was made.

use std::path::Path;

use serde::Serialize;

use crate::OitError;

/// Counters every frame carries.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    /// Passes over the geometry (bounds, histogram, capture and peel passes all count).
    pub geometry_passes: u32,
    /// Fragments the rasterizer generated for the scene's transparent part (one geometry pass's
    /// worth), those behind the opaque depth included.
    pub fragments: u64,
    /// Of `fragments`, those at or behind the opaque depth ([`crate::Scene::layers`]): never
    /// captured, never composited, not lost. 0 in a scene without opaque parts.
    pub occluded: u64,
    /// Fragments the opaque pass drew (the opaque and masked objects'; one pass's worth), those
    /// masked away included. 0 in a scene without opaque parts.
    pub opaque_fragments: u64,
    /// Of `opaque_fragments`, those a mask's cutoff discarded ([`crate::AlphaMode::Mask`]).
    pub masked: u64,
    /// Fragments that reached the final composite.
    pub captured: u64,
    /// Fragments that did not: collisions, overflow, coplanar ties, peel limits.
    pub lost: u64,
    /// Fragments that did not reach the composite one by one but were merged into a pixel's tail
    /// behind its K nearest (`--overflow tail`): approximated, not lost. 0 elsewhere.
    pub merged: u64,
    /// Fragments that reached the composite but whose order against an equal-depth fragment of
    /// another colour (payload) the technique could not establish: the reference orders equal
    /// depths by primitive id, a technique that keys on (depth, payload) orders them by colour.
    /// Counted per fragment of every run of equal depths (equal at the precision the technique
    /// keeps: `mdts`'s 20 bits) holding two payloads or more. 0 where the technique orders ties
    /// as the reference does (`fabs` carries the primitive id), and where it cannot see them.
    pub tied: u64,
    /// Fragments that reached the composite through a lossy packing of their colour: bdp's colour
    /// mode keeps alpha in 7 bits ([`crate::rules::bdp_pack_color`]), so each fragment it
    /// composites may carry an alpha one 8-bit step off the reference's (half the 256 alphas do;
    /// 0 and 255 never). Where none of a pixel's fragments was lost its error is bounded by its
    /// layer count ([`crate::rules::bdp_color_error_bound`]); `docs/bdp-colour.md` says more. 0
    /// for every other technique, whose colours reach the composite as the reference's.
    pub quantized: u64,
    /// Bytes of per-pixel storage the technique allocated.
    pub storage_bytes: u64,
    /// Wall-clock time of the frame in milliseconds.
    pub wall_ms: f64,
    /// Device time from timestamp queries, where the backend has them.
    pub gpu_ms: Option<f64>,
    /// The most fragments captured at one pixel (0 when none was covered): the count the white
    /// end of the depth-complexity heat map stands for, which a front end needs to draw the
    /// map's key. Backends return the map without one; every backend fills this, for every effect.
    pub max_layers: u32,
    /// Screen tiles the frame ran in ([`crate::tiling`]): 1 for a frame run whole, more where
    /// its storage did not fit the memory budget (`--memory`) or the device. Every backend's
    /// `Prepared::frame` sets it; 0 only on a frame made outside that loop.
    pub tiles: u32,
    /// Device time per pass, where measured.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gpu_pass_ms: Vec<(String, f64)>,
    /// Above one sample a pixel: what the technique did with each fragment's coverage mask
    /// ([`crate::msaa::coverage`]: per sample, its alpha weighted by its coverage fraction, or
    /// per pixel at full alpha). Absent at one sample.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coverage: Option<crate::msaa::Coverage>,
}

impl Stats {
    /// Sets [`Stats::quantized`] (and [`Stats::coverage`]) for a frame made under `settings`: every fragment bdp's colour
    /// mode composites went through its packing; no other technique packs colour lossily. One
    /// rule for every backend, applied where their frames end ([`crate::tiling::run`],
    /// [`crate::tiling::frame_stats`]).
    pub fn count_packing(&mut self, settings: &crate::Settings) {
        let packs = match settings.technique {
            crate::Technique::Bdp { passes } => settings.bdp_color_mode(passes).unwrap_or(false),
            _ => false,
        };
        self.quantized = if packs { self.captured } else { 0 };
        // a frame of `plain` that says it composited each sample (a GPU's blender at several
        // samples: docs/msaa.md) keeps it; the settings say every other frame's
        let own = self.coverage.filter(|_| settings.technique == crate::Technique::Plain);
        self.coverage = own.or_else(|| crate::msaa::coverage(settings));
    }

    /// The frame's own check, where its losses were counted as they happened: every fragment the
    /// first geometry pass generated was either composited, merged into a tail or counted lost. A device that stops
    /// a kernel early (lavapipe ends a shader invocation's loops after 65,535 iterations in all)
    /// breaks it, and so would a technique that drops a fragment without counting it (the
    /// per-sample peels did, before `msaa::peel_key`); the frame is refused with an error rather
    /// than shown with fragments missing and `lost` silent.
    pub fn check_accounting(&self, backend: &str) -> Result<(), OitError> {
        if self.captured + self.merged + self.lost + self.occluded == self.fragments
            && self.masked <= self.opaque_fragments
        {
            return Ok(());
        }
        Err(OitError::Device(format!(
            "{backend}: {} fragments composited + {} merged + {} counted lost + {} occluded ≠ {} generated (or \
             {} masked of {} opaque): the device did not \
             run every step of the frame to the end (lavapipe, for one, ends a shader's loops after \
             65,535 iterations, which a pixel of thousands of layers can need), or the technique \
             dropped a fragment without counting it (a bug in oit: please report the scene and \
             settings); the frame is refused rather than shown wrong. Use fewer layers, another \
             raster path or the cpu backend",
            self.captured,
            self.merged,
            self.lost,
            self.occluded,
            self.fragments,
            self.masked,
            self.opaque_fragments
        )))
    }
}

/// An 8-bit sRGB image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 pixels (alpha 255).
    pub pixels: Vec<[u8; 4]>,
}

impl Image {
    /// A width × height image filled with `fill`.
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Image {
        Image { width, height, pixels: vec![fill; width as usize * height as usize] }
    }

    /// The pixel at (x, y).
    pub fn get(&self, x: u32, y: u32) -> [u8; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Writes a PNG. Encoded in memory and written with one checked write, so that a write that
    /// fails (a full disk) is an error however small the file: `image::save_buffer` drops its
    /// buffered writer unflushed, and a small file failed silently.
    pub fn save_png(&self, path: &Path) -> Result<(), OitError> {
        use image::ImageEncoder;
        let err = |message: String| OitError::Write { path: path.to_path_buf(), message };
        let bytes: Vec<u8> = self.pixels.iter().flatten().copied().collect();
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png)
            .write_image(&bytes, self.width, self.height, image::ExtendedColorType::Rgba8)
            .map_err(|e| err(e.to_string()))?;
        std::fs::write(path, png).map_err(|e| err(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 13.5: a write to a full disk is an error, even for a tiny image.
    #[cfg(target_os = "linux")]
    #[test]
    fn png_to_a_full_disk_is_an_error() {
        let image = Image::new(2, 2, [10, 20, 30, 255]);
        let e = image.save_png(Path::new("/dev/full")).expect_err("/dev/full must fail");
        assert!(matches!(e, OitError::Write { .. }), "{e}");
    }

    /// Issue 41.1: `quantized` is bdp's colour mode's captured fragments, 0 elsewhere (its depth
    /// mode, `bdp:2`, other effects, other techniques). Mutations caught: the count left at 0, set
    /// for every technique, or set from `fragments` (which counts the lost ones too).
    #[test]
    fn packing_is_counted_for_bdp_colour_mode_only() {
        use crate::{BdpMode, Effect, Settings};
        let counted = |technique: &str, f: fn(&mut Settings)| {
            let mut settings = Settings { technique: technique.parse().unwrap(), ..Settings::default() };
            f(&mut settings);
            let mut s = Stats { fragments: 12, captured: 10, lost: 2, quantized: 99, ..Stats::default() };
            s.count_packing(&settings);
            s.quantized
        };
        assert_eq!(counted("bdp", |_| {}), 10);
        assert_eq!(counted("bdp", |s| s.bdp_mode = BdpMode::Color), 10);
        assert_eq!(counted("bdp", |s| s.bdp_mode = BdpMode::Depth), 0);
        assert_eq!(counted("bdp", |s| s.effect = Effect::Fresnel), 0);
        assert_eq!(counted("bdp2", |_| {}), 0);
        assert_eq!(counted("ll", |_| {}), 0);
        assert_eq!(counted("mdts", |_| {}), 0);
    }

    fn totals(fragments: GpuFragments, counted_lost: Option<u64>) -> GpuTotals<'static> {
        const ACCT: [u32; 6] = [2, 9, 9, 1, 9, 9];
        GpuTotals {
            fragments,
            on_device: 40,
            captured: 37,
            counted_lost,
            occluded: 0,
            acct: Some(&ACCT),
            pixels: 2,
        }
    }

    /// Each source of the fragment count, counted and derived losses. Mutations caught: the
    /// on-device word ignored, losses derived where they are counted, the per-pixel words read
    /// from the wrong column.
    #[test]
    fn gpu_totals_take_each_count_from_where_it_is() {
        use GpuFragments::*;
        assert_eq!(totals(Known(50), Some(3)).counts(), (50, 3, Some(vec![2, 1])));
        assert_eq!(totals(OnDevice, Some(3)).counts(), (40, 3, Some(vec![2, 1])));
        // the blend captures: losses derived, no per-pixel losses
        assert_eq!(totals(OnDevice, None).counts(), (40, 3, None));
        assert_eq!(totals(Unset, None).counts(), (0, 0, None));
        // what the opaque cut held back is not lost: derived losses leave it out, counted ones
        // are as counted
        let occluded = |lost| GpuTotals { occluded: 2, ..totals(OnDevice, lost) };
        assert_eq!(occluded(None).counts(), (40, 1, None));
        assert_eq!(occluded(Some(3)).counts(), (40, 3, Some(vec![2, 1])));
    }
}

/// One rendered frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The picture.
    pub image: Image,
    /// Fragments generated per pixel, where the technique counted them (the reference does):
    /// pixels with none are not *covered* and accuracy metrics skip them.
    pub layers: Option<Vec<u32>>,
    /// Fragments lost per pixel, where the backend counts them per pixel (`oit-cpu`; oit-wgpu's
    /// compute path and its hardware path with atomics capture): each pixel's share of
    /// [`Stats::lost`]. `None` where losses are not counted per pixel.
    pub lost_pixels: Option<Vec<u32>>,
    /// How it was made.
    pub stats: Stats,
}

/// Where a GPU frame knows the fragments of its first geometry pass over the scene (a frame's
/// fragments are that pass's), the same on every GPU backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuFragments {
    /// No geometry pass of the scene has run.
    Unset,
    /// Left on the device, read with the frame's totals at its end.
    OnDevice,
    /// Read back.
    Known(u64),
}

/// What the end of a GPU frame read back, made into its fragment and loss counts by one rule for
/// every GPU backend ([`GpuTotals::counts`]).
#[derive(Clone, Copy, Debug)]
pub struct GpuTotals<'a> {
    /// Where the first pass's fragments are.
    pub fragments: GpuFragments,
    /// The first pass's count as read at the end (used for [`GpuFragments::OnDevice`]).
    pub on_device: u64,
    /// Fragments the resolve composited.
    pub captured: u64,
    /// The totals' counted losses where the capture counts them (`None`: the blend captures,
    /// whose blend unit returns no previous value to count by).
    pub counted_lost: Option<u64>,
    /// The fragments the opaque cut held back (`Stats::occluded`; 0 without opaque parts): of the
    /// fragments, neither captured nor lost.
    pub occluded: u64,
    /// The per-pixel loss accounting where read back: 3 words a pixel, fragments lost first
    /// (`acct` in the GPU prelude).
    pub acct: Option<&'a [u32]>,
    /// Pixels of the frame.
    pub pixels: usize,
}

impl GpuTotals<'_> {
    /// (fragments, lost, per-pixel losses). Without counted losses, `lost` is
    /// `fragments − captured − occluded` and there are no per-pixel losses.
    pub fn counts(&self) -> (u64, u64, Option<Vec<u32>>) {
        let fragments = match self.fragments {
            GpuFragments::Known(generated) => generated,
            GpuFragments::OnDevice => self.on_device,
            GpuFragments::Unset => 0,
        };
        match self.counted_lost {
            Some(lost) => {
                let px = self.acct.map(|acct| acct.chunks(3).take(self.pixels).map(|w| w[0]).collect());
                (fragments, lost, px)
            }
            None => (fragments, fragments.saturating_sub(self.captured + self.occluded), None),
        }
    }
}
