//! The opaque pass: a frame's opaque and masked geometry ([`oit_core::Scene::layers`]) drawn
//! into a depth buffer and a colour image before the technique runs, as a renderer draws its
//! opaque geometry first.
//!
//! A standard z-buffer with oit's tie rule: each pixel keeps the fragment of the smallest
//! (depth, primitive id), found by one 64-bit atomic MIN of `depth bits << 32 | id` (a second
//! geometry pass then shades the one fragment whose key won), so the result does not depend on
//! the order threads reach a pixel, and two coplanar opaque triangles resolve as they do on the
//! GPU paths. A masked fragment whose alpha is under its object's cutoff is discarded and
//! counted ([`oit_core::Stats::masked`]): an untextured masked object reaches the pass with
//! alpha 1 or 0 ([`oit_core::Object::effective_alpha`]), a textured one with the factor's alpha
//! times the texture's, fragment by fragment ([`oit_core::setup::Triangle::cutoff`]).

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use glam::Vec3;
use oit_core::rules::depth_bits;
use oit_core::{AlphaMode, Camera, Scene, Settings};

use crate::raster::{Rasterizer, Shade};

/// What the opaque pass leaves for the technique: the depth transparent fragments must be in
/// front of, and the colour they composite over, each kept a **sample** (`samples` a pixel, sample
/// `i` of pixel `px` at `px · samples + i`; one a pixel at one sample).
pub(crate) struct OpaqueImage {
    /// Per sample, the nearest opaque depth; `f32::INFINITY` where none fell.
    pub depth: Arc<[f32]>,
    /// Per sample, that fragment's linear RGB; `None` where none fell (the background shows).
    pub color: Vec<Option<Vec3>>,
    /// Per pixel (kept only above one sample), whether every sample holds the same key (the same
    /// opaque fragment, or none): the per-sample resolves composite such a pixel once.
    pub uniform: Vec<bool>,
    /// Fragments the pass drew (those masked away included).
    pub fragments: u64,
    /// Of those, fragments a mask's cutoff discarded.
    pub masked: u64,
    /// Geometry passes it ran.
    pub passes: u32,
}

/// The opaque fragments a pixel (on average over the frame) up to which the colour pass shades
/// every fragment in lanes rather than only the winners on demand.
const SHADE_ALL_LAYERS: u64 = 4;

/// Draws `scene` (a frame's opaque part) seen by `camera` under `settings` (the layers'
/// settings: a tile's region included). Above one sample (docs/msaa.md) the z-buffer is kept a
/// sample: a fragment (one a pixel a triangle where it covers any sample, its depth the pixel
/// centre's as every multisampled fragment's) writes the samples its coverage mask holds, and
/// each sample keeps its own nearest key and that fragment's colour.
pub(crate) fn draw(scene: &Scene, camera: &Camera, settings: &Settings) -> OpaqueImage {
    let raster = Rasterizer::new(scene, camera, settings);
    let samples = settings.samples.max(1);
    let per = samples as usize;
    let pixels = settings.pixel_count();
    let keys: Vec<AtomicU64> = (0..pixels * per).map(|_| AtomicU64::new(u64::MAX)).collect();
    let masked = AtomicU64::new(0);
    // only a scene with a masked object needs a fragment's alpha in the first pass; elsewhere
    // it tests depth and id alone, unshaded
    let masks = scene.objects.iter().any(|o| matches!(o.alpha_mode, AlphaMode::Mask { .. }));
    let key_of = |f: &crate::raster::Fragment<'_>| u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
    let first = |f: &crate::raster::Fragment<'_>, mask: u8| {
        // alpha is never below a cutoff of 0 (an opaque object's): those skip the texture
        if masks && f.cutoff() > 0.0 && f.alpha() < f.cutoff() {
            masked.fetch_add(1, Relaxed);
            return;
        }
        let key = key_of(f);
        let base = f.pixel as usize * per;
        for i in (0..per).filter(|i| mask >> i & 1 == 1) {
            keys[base + i].fetch_min(key, Relaxed);
        }
    };
    let fragments = if samples > 1 {
        raster.for_each_masked_fragment(samples, first)
    } else {
        raster.for_each_fragment(|f| first(f, 1))
    };
    // the winner's colour: one fragment a sample matches its key (ids are unique in a pixel)
    let rgb: Vec<[AtomicU32; 3]> = (0..pixels * per).map(|_| Default::default()).collect();
    let second = |f: &crate::raster::Fragment<'_>, mask: u8| {
        let key = key_of(f);
        let base = f.pixel as usize * per;
        let mut color = None;
        for i in (0..per).filter(|i| mask >> i & 1 == 1) {
            if keys[base + i].load(Relaxed) == key {
                let c = *color.get_or_insert_with(|| f.color());
                for (slot, v) in rgb[base + i].iter().zip([c.x, c.y, c.z]) {
                    slot.store(v.to_bits(), Relaxed);
                }
            }
        }
    };
    if samples > 1 {
        raster.for_each_masked_fragment(samples, second);
    } else {
        // shaded in lanes before the test ([`Shade::Color`]) where the opaque part is shallow: a
        // lane's shading costs a fraction of one fragment's on demand, so shading every fragment
        // costs less than shading the winners one by one while the fragments are few to a pixel
        // (a wall over the default scene at 512²: fabs's frame 10.3–11.9 ms on demand, 8.7–9.4 in
        // lanes, bench/results/cpu/opaque-lanes-512); a deep opaque part shades its winners alone
        let shallow = fragments <= SHADE_ALL_LAYERS * pixels as u64;
        raster.for_each_fragment_with(if shallow { Shade::Color } else { Shade::OnDemand }, |f| second(f, 1));
    }
    let depth: Arc<[f32]> = keys
        .iter()
        .map(|k| k.load(Relaxed))
        .map(|k| if k == u64::MAX { f32::INFINITY } else { f32::from_bits((k >> 32) as u32) })
        .collect();
    let color = keys
        .iter()
        .zip(&rgb)
        .map(|(k, c)| {
            (k.load(Relaxed) != u64::MAX)
                .then(|| Vec3::from_array(c.each_ref().map(|v| f32::from_bits(v.load(Relaxed)))))
        })
        .collect();
    let uniform = if samples > 1 {
        keys.chunks(per).map(|k| k.iter().all(|v| v.load(Relaxed) == k[0].load(Relaxed))).collect()
    } else {
        Vec::new()
    };
    OpaqueImage { depth, color, uniform, fragments, masked: masked.into_inner(), passes: 2 }
}
