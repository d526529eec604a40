//! The opaque pass: a frame's opaque and masked geometry ([`oit_core::Scene::layers`]) drawn
//! into a depth buffer and a colour image before the technique runs, as a renderer draws its
//! opaque geometry first.
//!
//! A standard z-buffer with oit's tie rule: each pixel keeps the fragment of the smallest
//! (depth, primitive id), the minimum of `depth bits << 32 | id` (a second geometry pass then
//! shades the one fragment whose key won), so the result does not depend on the order fragments
//! reach a pixel, and two coplanar opaque triangles resolve as they do on the GPU paths. Both
//! passes run in bands of rows ([`Rasterizer::for_each_fragment_by_band`]), each band's pixels
//! written by one thread, so the minimum is a plain compare and store where the GPUs take an
//! atomic MIN. A masked fragment whose alpha is under its object's cutoff is discarded and
//! counted ([`oit_core::Stats::masked`]): an untextured masked object reaches the pass with
//! alpha 1 or 0 ([`oit_core::Object::effective_alpha`]), a textured one with the factor's alpha
//! times the texture's, fragment by fragment ([`oit_core::setup::Triangle::cutoff`]).

use std::cell::Cell;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use glam::{Vec3, Vec4};
use oit_core::rules::depth_bits;
use oit_core::{AlphaMode, Camera, Scene, Settings};
use rayon::prelude::*;

use crate::raster::{Fragment, Rasterizer, Shade};

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
    /// Geometry passes it ran: 2 (depth, then the winners' colours), or 1 where the depth pass
    /// shaded every fragment ahead and kept each winner's colour as it went.
    pub passes: u32,
    /// What the next frame's pass reuses ([`draw_reusing`]): its rasterizer, set up again, and
    /// the z-buffer's keys and colours, overwritten.
    raster: Rasterizer,
    keys: Vec<AtomicU64>,
    rgb: Vec<[AtomicU32; 3]>,
}

/// The opaque fragments a pixel (on average over the frame) up to which the colour pass shades
/// every fragment in lanes rather than only the winners on demand.
const SHADE_ALL_LAYERS: u64 = 4;

/// Whether the pass over `scene` (a frame's opaque part) is one geometry pass, not two: where a
/// masked object is textured, its alpha is its texture's, so the depth test shades every fragment
/// ahead in lanes, the texture sampled eight fragments at once (a fragment's alpha is then its
/// colour's, the bits `alpha_at` gives), rather than sampling each fragment on its own. With every
/// colour in hand it keeps the winners' as it goes, and the colour pass, which would shade them
/// all again, is not run ([`draw_passes`]).
pub(crate) fn fuses(scene: &Scene) -> bool {
    scene.objects.iter().any(|o| matches!(o.alpha_mode, AlphaMode::Mask { .. }) && o.texture.is_some())
}

/// Draws `scene` (a frame's opaque part) seen by `camera` under `settings` (the layers'
/// settings: a tile's region included). Above one sample (docs/msaa.md) the z-buffer is kept a
/// sample: a fragment (one a pixel a triangle where it covers any sample, its depth the pixel
/// centre's as every multisampled fragment's) writes the samples its coverage mask holds, and
/// each sample keeps its own nearest key and that fragment's colour.
pub(crate) fn draw(scene: &Scene, camera: &Camera, settings: &Settings) -> OpaqueImage {
    draw_reusing(scene, camera, settings, None)
}

/// [`draw`] into the storage of an earlier frame's image (`kept`), where its sizes fit: a steady
/// frame allocates nothing, so the pass pays no page faults for fresh arrays (at 512², a wall
/// over the default scene, making the z-buffer and collecting into fresh arrays took 0.5–0.7 ms
/// of a 3.4 ms pass).
pub(crate) fn draw_reusing(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    kept: Option<OpaqueImage>,
) -> OpaqueImage {
    draw_passes(scene, camera, settings, kept, fuses(scene))
}

/// [`draw_reusing`] in one pass or two as `fused` says: one shades every fragment ahead and keeps
/// each winner's colour as it tests depth, two shade only the winners in a second pass.
fn draw_passes(
    scene: &Scene,
    camera: &Camera,
    settings: &Settings,
    kept: Option<OpaqueImage>,
    fused: bool,
) -> OpaqueImage {
    let samples = settings.samples.max(1);
    let per = samples as usize;
    let pixels = settings.pixel_count();
    let (raster, mut keys, mut rgb, mut depth, mut color) = match kept {
        Some(k) => {
            let mut raster = k.raster;
            raster.rebuild(scene, camera, settings);
            (raster, k.keys, k.rgb, k.depth, k.color)
        }
        None => (Rasterizer::new(scene, camera, settings), Vec::new(), Vec::new(), Arc::from([]), Vec::new()),
    };
    if keys.len() == pixels * per {
        keys.par_iter_mut().for_each(|k| *k.get_mut() = u64::MAX);
    } else {
        // another window's or sample count's arrays: freed before this frame's are made, so a
        // tiled frame never holds two windows' at once
        drop((std::mem::take(&mut keys), std::mem::take(&mut rgb), std::mem::take(&mut color)));
        depth = Arc::from([]);
        keys = (0..pixels * per).map(|_| AtomicU64::new(u64::MAX)).collect();
    }
    // a colour is read only where a key was set, and the pass that set it wrote the colour
    rgb.resize_with(pixels * per, Default::default);
    let masked = AtomicU64::new(0);
    // only a scene with a masked object needs a fragment's alpha before its depth test;
    // elsewhere it tests depth and id alone
    let masks = scene.objects.iter().any(|o| matches!(o.alpha_mode, AlphaMode::Mask { .. }));
    // alpha is never below a cutoff of 0 (an opaque object's): those skip the texture
    let masked_away = |f: &Fragment<'_>| masks && f.cutoff() > 0.0 && f.alpha() < f.cutoff();
    // fused: the depth pass shades in lanes (see `fuses`) and keeps the colour with each key it
    // wins; the colour a sample ends with is that of the last fragment to win it, the one holding
    // its least key, as the colour pass would find it
    let first_shade = if fused { Shade::Color } else { Shade::OnDemand };
    let key_of = |f: &Fragment<'_>| u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim);
    let store = |slot: &[AtomicU32; 3], c: Vec4| {
        for (word, v) in slot.iter().zip([c.x, c.y, c.z]) {
            word.store(v.to_bits(), Relaxed);
        }
    };
    let fragments: u64 = {
        // In bands of rows, each band's pixels written by its one task: the depth test is a plain
        // load and store, not a locked MIN (the wall of `wall:0:default` at 512²: 1.1 ms with the
        // MIN, 0.6 so); the colour pass likewise. Two passes, as the plan's schedule and the GPU
        // paths: a colour is made only for the fragment that holds a sample's key (unless the
        // depth pass shades them all anyway: `fused`).
        let (keys, rgb, masked) = (&keys, &rgb, &masked);
        let (masked_away, key_of, store) = (&masked_away, &key_of, &store);
        let first = |_| {
            let count = BandCount { masked: Cell::new(0), total: masked };
            move |f: &Fragment<'_>, mask: u8| {
                if masked_away(f) {
                    count.masked.set(count.masked.get() + 1);
                    return;
                }
                let (key, base) = (key_of(f), f.pixel as usize * per);
                let mut color = None;
                for i in (0..per).filter(|i| mask >> i & 1 == 1) {
                    if key < keys[base + i].load(Relaxed) {
                        keys[base + i].store(key, Relaxed);
                        if fused {
                            store(&rgb[base + i], *color.get_or_insert_with(|| f.color()));
                        }
                    }
                }
            }
        };
        // the winner's colour: one fragment a sample matches its key (ids are unique in a pixel)
        let second = |_| {
            move |f: &Fragment<'_>, mask: u8| {
                let (key, base) = (key_of(f), f.pixel as usize * per);
                let mut color = None;
                for i in (0..per).filter(|i| mask >> i & 1 == 1) {
                    if keys[base + i].load(Relaxed) == key {
                        store(&rgb[base + i], *color.get_or_insert_with(|| f.color()));
                    }
                }
            }
        };
        if samples > 1 {
            let fragments =
                raster.for_each_masked_fragment_by_band(samples, first_shade, None, first).iter().sum();
            if !fused {
                raster.for_each_masked_fragment_by_band(samples, Shade::OnDemand, None, second);
            }
            fragments
        } else {
            let fragments = raster
                .for_each_fragment_by_band(first_shade, |b| {
                    let first = first(b);
                    move |f: &Fragment<'_>| first(f, 1)
                })
                .iter()
                .sum();
            // shaded in lanes before the test ([`Shade::Color`]) where the opaque part is shallow: a
            // lane's shading costs a fraction of one fragment's on demand, so shading every fragment
            // costs less than shading the winners one by one while the fragments are few to a pixel
            // (a wall over the default scene at 512²: fabs's frame 10.3–11.9 ms on demand, 8.7–9.4 in
            // lanes, bench/results/cpu/opaque-lanes-512); a deep opaque part shades its winners alone
            let shallow = fragments <= SHADE_ALL_LAYERS * pixels as u64;
            if !fused {
                raster.for_each_fragment_by_band(if shallow { Shade::Color } else { Shade::OnDemand }, |b| {
                    let second = second(b);
                    move |f: &Fragment<'_>| second(f, 1)
                });
            }
            fragments
        }
    };
    let depth_of = |k: &AtomicU64| match k.load(Relaxed) {
        u64::MAX => f32::INFINITY,
        k => f32::from_bits((k >> 32) as u32),
    };
    match Arc::get_mut(&mut depth).filter(|d| d.len() == keys.len()) {
        Some(d) => d.par_iter_mut().zip(&keys[..]).for_each(|(d, k)| *d = depth_of(k)),
        None => depth = keys.par_iter().map(depth_of).collect::<Vec<f32>>().into(),
    }
    color.resize(keys.len(), None);
    color.par_iter_mut().zip(&keys[..]).zip(&rgb[..]).for_each(|((out, k), c)| {
        *out = (k.load(Relaxed) != u64::MAX)
            .then(|| Vec3::from_array(c.each_ref().map(|v| f32::from_bits(v.load(Relaxed)))));
    });
    let uniform = if samples > 1 {
        keys.par_chunks(per).map(|k| k.iter().all(|v| v.load(Relaxed) == k[0].load(Relaxed))).collect()
    } else {
        Vec::new()
    };
    OpaqueImage {
        depth,
        color,
        uniform,
        fragments,
        masked: masked.into_inner(),
        passes: if fused { 1 } else { 2 },
        raster,
        keys,
        rgb,
    }
}

/// A band's count of fragments its mask discarded, kept in the band's task and added to `total`
/// once, as the task drops its shader.
struct BandCount<'a> {
    masked: Cell<u64>,
    total: &'a AtomicU64,
}

impl Drop for BandCount<'_> {
    fn drop(&mut self) {
        self.total.fetch_add(self.masked.get(), Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use oit_core::{Camera, Settings, View, builtin_scene};

    use super::{draw_passes, fuses};

    /// The one-pass z-buffer (depth test shading ahead, each winner's colour kept as it wins) and
    /// the two-pass one (the winners shaded in a second pass) leave the same depth, colour and
    /// counts, bit for bit, at one sample and four, on scenes with textured masks (the fence's holes,
    /// the foliage's leaves) and without (a wall).
    #[test]
    fn one_pass_and_two_leave_the_same_image() {
        for name in ["fence", "foliage", "wall:0.5:planes:16"] {
            let scene = builtin_scene(name).unwrap().unwrap();
            let opaque = scene.layers(None).opaque.unwrap();
            assert_eq!(fuses(&opaque), name != "wall:0.5:planes:16", "{name}");
            for samples in [1, 4] {
                let settings = Settings { width: 96, height: 80, samples, ..Settings::default() };
                let camera = Camera::orbit_scene(&scene, View::default(), 96.0 / 80.0).unwrap();
                let [one, two] = [true, false].map(|f| draw_passes(&opaque, &camera, &settings, None, f));
                let what = format!("{name} at {samples} samples");
                assert_eq!((one.passes, two.passes), (1, 2), "{what}");
                assert!(one.fragments > 0 && one.color.iter().any(Option::is_some), "{what}: drew nothing");
                if name != "wall:0.5:planes:16" {
                    assert!(one.masked > 0, "{what}: no fragment masked away");
                }
                assert_eq!((one.fragments, one.masked), (two.fragments, two.masked), "{what}");
                let depth = |d: f32| d.to_bits();
                let rgb = |c: Option<glam::Vec3>| c.map(|v| v.to_array().map(f32::to_bits));
                let first_off = (0..one.depth.len()).find(|&i| {
                    depth(one.depth[i]) != depth(two.depth[i]) || rgb(one.color[i]) != rgb(two.color[i])
                });
                if let Some(i) = first_off {
                    panic!(
                        "{what}: sample {i}: depth {} colour {:?} in one pass, {} {:?} in two",
                        one.depth[i], one.color[i], two.depth[i], two.color[i]
                    );
                }
                assert_eq!(one.color.len(), two.color.len(), "{what}");
                assert_eq!(one.uniform, two.uniform, "{what}");
            }
        }
    }
}
