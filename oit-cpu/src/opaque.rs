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
/// front of, and the colour they composite over.
pub(crate) struct OpaqueImage {
    /// Per pixel, the nearest opaque depth; `f32::INFINITY` where none fell.
    pub depth: Arc<[f32]>,
    /// Per pixel, that fragment's linear RGB; `None` where none fell (the background shows).
    pub color: Vec<Option<Vec3>>,
    /// Fragments the pass drew (those masked away included).
    pub fragments: u64,
    /// Of those, fragments a mask's cutoff discarded.
    pub masked: u64,
    /// Geometry passes it ran.
    pub passes: u32,
}

/// Draws `scene` (a frame's opaque part) seen by `camera` under `settings` (the layers'
/// settings: a tile's region included).
pub(crate) fn draw(scene: &Scene, camera: &Camera, settings: &Settings) -> OpaqueImage {
    let raster = Rasterizer::new(scene, camera, settings);
    let pixels = settings.pixel_count();
    let keys: Vec<AtomicU64> = (0..pixels).map(|_| AtomicU64::new(u64::MAX)).collect();
    let masked = AtomicU64::new(0);
    // only a scene with a masked object needs a fragment's alpha in the first pass; elsewhere
    // it tests depth and id alone, unshaded
    let masks = scene.objects.iter().any(|o| matches!(o.alpha_mode, AlphaMode::Mask { .. }));
    let fragments = raster.for_each_fragment(|f| {
        if masks && f.color().w < f.cutoff() {
            masked.fetch_add(1, Relaxed);
            return;
        }
        let key = u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
        keys[f.pixel as usize].fetch_min(key, Relaxed);
    });
    // the winner's colour: one fragment a pixel matches its key (ids are unique in a pixel)
    let rgb: Vec<[AtomicU32; 3]> = (0..pixels).map(|_| Default::default()).collect();
    raster.for_each_fragment_with(Shade::OnDemand, |f| {
        let px = f.pixel as usize;
        let key = u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
        if keys[px].load(Relaxed) == key {
            let c = f.color();
            for (slot, v) in rgb[px].iter().zip([c.x, c.y, c.z]) {
                slot.store(v.to_bits(), Relaxed);
            }
        }
    });
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
    OpaqueImage { depth, color, fragments, masked: masked.into_inner(), passes: 2 }
}
