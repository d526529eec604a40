//! The resolve: each pixel's captured fragments, fed nearest first, become a colour under the
//! chosen effect. Every technique ends here, so the effects work on all of them alike.

use glam::{Vec3, Vec4};
use oit_core::composite::{FrontToBack, heat, linear_to_srgb8, schlick_transmittance};
use oit_core::rules::{unpack_normal, unpack_rgba8};
use oit_core::{Camera, Effect, Image, Scene, Settings};

/// Per-pixel state of the resolve, fed fragments in depth order.
#[derive(Clone, Debug)]
pub(crate) struct PixelState {
    front: FrontToBack,
    /// Back-to-front result of the back half (dual depth peeling), over the background.
    back: Option<Vec3>,
    /// Layers peeled from the back that an effect other than transparency replays at the end.
    back_stack: Vec<(f32, u32)>,
    /// Fragments that reached the composite.
    pub captured: u32,
    /// Translucency: per-channel optical depth so far, and the open entry (distance, colour).
    optical: Vec3,
    entry: Option<(f32, Vec4)>,
    /// Fresnel: transmittance so far.
    fresnel: f32,
}

impl Default for PixelState {
    fn default() -> Self {
        PixelState {
            front: FrontToBack::default(),
            back: None,
            back_stack: Vec::new(),
            captured: 0,
            optical: Vec3::ZERO,
            entry: None,
            fresnel: 1.0,
        }
    }
}

/// What the resolve needs to know about the frame.
pub(crate) struct Resolve<'a> {
    pub effect: Effect,
    pub camera: &'a Camera,
    pub background: Vec3,
    /// Translucency: absorption σ per unit of length, the unit being 1/8 of the scene radius (so
    /// an object of a scene of any scale absorbs alike).
    sigma: f32,
    radius: f32,
}

impl<'a> Resolve<'a> {
    pub fn new(scene: &Scene, camera: &'a Camera, settings: &Settings) -> Self {
        let sigma = if scene.objects.is_empty() {
            1.0
        } else {
            scene.objects.iter().map(|o| o.absorption).sum::<f32>() / scene.objects.len() as f32
        };
        Resolve {
            effect: settings.effect,
            camera,
            background: settings.background,
            sigma,
            radius: scene.bounds().radius().max(1e-6) / 8.0,
        }
    }

    /// The next fragment behind everything pushed so far.
    #[inline]
    pub fn push(&self, s: &mut PixelState, depth: f32, payload: u32) {
        s.captured += 1;
        match self.effect {
            Effect::Transparency => s.front.under(unpack_rgba8(payload)),
            Effect::Complexity => {}
            Effect::Fresnel => {
                let n = unpack_normal(payload);
                s.fresnel *= schlick_transmittance(n.dot(self.camera.forward));
            }
            Effect::Translucency => {
                let dist = self.camera.linear_depth(depth);
                match s.entry.take() {
                    None => s.entry = Some((dist, unpack_rgba8(payload))),
                    Some((d0, c)) => {
                        let absorb = (Vec3::ONE - c.truncate()) * self.sigma / self.radius;
                        s.optical += absorb * (dist - d0).max(0.0);
                    }
                }
            }
        }
    }

    /// The next fragment in front of everything pushed from the back so far (dual depth peeling).
    #[inline]
    pub fn push_back(&self, s: &mut PixelState, depth: f32, payload: u32) {
        if self.effect == Effect::Transparency {
            s.captured += 1;
            let back = s.back.unwrap_or(self.background);
            s.back = Some(oit_core::composite::over(back, unpack_rgba8(payload)));
        } else {
            s.back_stack.push((depth, payload));
        }
    }

    /// The final linear colour of a pixel (heat maps are finished by [`Resolve::image`]).
    pub fn finish(&self, s: &mut PixelState) -> Vec3 {
        while let Some((d, p)) = s.back_stack.pop() {
            self.push(s, d, p);
        }
        match self.effect {
            Effect::Transparency => s.front.over(s.back.unwrap_or(self.background)),
            Effect::Complexity => Vec3::ZERO,
            Effect::Fresnel => self.background * s.fresnel,
            Effect::Translucency => {
                let t = Vec3::new((-s.optical.x).exp(), (-s.optical.y).exp(), (-s.optical.z).exp());
                self.background * t
            }
        }
    }

    /// Finishes every pixel into an sRGB image; returns it and the fragments captured in all.
    pub fn image(&self, width: u32, height: u32, states: &mut [PixelState]) -> (Image, u64) {
        use rayon::prelude::*;
        let colors: Vec<Vec3> = states.par_iter_mut().map(|s| self.finish(s)).collect();
        let captured = states.iter().map(|s| u64::from(s.captured)).sum();
        let mut image = Image::new(width, height, [0, 0, 0, 255]);
        if self.effect == Effect::Complexity {
            let max = states.iter().map(|s| s.captured).max().unwrap_or(0).max(1);
            for (px, s) in image.pixels.iter_mut().zip(states.iter()) {
                let c = if s.captured == 0 { self.background } else { heat(s.captured as f32 / max as f32) };
                *px = srgb(c);
            }
        } else {
            for (px, c) in image.pixels.iter_mut().zip(colors) {
                *px = srgb(c);
            }
        }
        (image, captured)
    }
}

/// Linear RGB to an sRGB8 pixel.
#[inline]
pub(crate) fn srgb(c: Vec3) -> [u8; 4] {
    [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255]
}
