//! The resolve: each pixel's captured fragments, fed nearest first, become a colour under the
//! chosen effect. Every technique ends here, so the effects work on all of them alike.
//!
//! Ties: where the plan says the technique orders equal depths by payload rather than by primitive
//! id ([`Plan::count_ties`](oit_core::plan::Plan::count_ties)), the resolve watches the order it is
//! fed in: every fragment of a run of consecutive equal depths (equal bits) that holds two payloads
//! or more is counted in `tied`, since its order against the others is the technique's guess. Dual
//! depth peeling feeds two sequences, the front nearest first and the back farthest first; they
//! meet at the end, where the front's last run and the back's last run join when their depths are
//! equal (`PixelState::tied`). `oit-wgpu`'s `resolve.wgsl` keeps the same runs.

use glam::{Vec3, Vec4};
use oit_core::composite::{FrontToBack, heat, linear_to_srgb8, schlick_transmittance};
use oit_core::rules::{depth_bits, unpack_normal, unpack_rgba8};
use oit_core::{Camera, Effect, Image, Scene, Settings};

/// The run of equal depths a sequence of pushes ends in.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Run {
    /// Depth bits and payload of the last fragment pushed; `len` 0: none yet.
    depth: u32,
    payload: u32,
    /// Fragments in the run.
    len: u32,
    /// Whether the run holds two payloads or more (its fragments are counted tied).
    mixed: bool,
}

impl Run {
    /// Extends the run with a fragment; returns how many fragments that makes tied.
    #[inline]
    fn push(&mut self, depth: u32, payload: u32) -> u32 {
        let mut tied = 0;
        if self.len > 0 && self.depth == depth {
            self.len += 1;
            if self.mixed {
                tied = 1;
            } else if self.payload != payload {
                self.mixed = true;
                tied = self.len;
            }
        } else {
            *self = Run { depth, payload, len: 1, mixed: false };
        }
        self.depth = depth;
        self.payload = payload;
        tied
    }

    /// Fragments of the run counted tied.
    fn counted(&self) -> u32 {
        if self.mixed { self.len } else { 0 }
    }
}

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
    /// Ties: the runs the front and back sequences end in, and the fragments counted so far.
    front_run: Run,
    back_run: Run,
    tied: u32,
}

impl PixelState {
    /// Fragments counted tied, the join of the front and back sequences included.
    pub fn tied(&self) -> u32 {
        let (f, b) = (&self.front_run, &self.back_run);
        if f.len == 0 || b.len == 0 || f.depth != b.depth {
            return self.tied;
        }
        let joined = if f.mixed || b.mixed || f.payload != b.payload { f.len + b.len } else { 0 };
        self.tied - f.counted() - b.counted() + joined
    }
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
            front_run: Run::default(),
            back_run: Run::default(),
            tied: 0,
        }
    }
}

/// What the resolve needs to know about the frame.
pub(crate) struct Resolve<'a> {
    pub effect: Effect,
    pub camera: &'a Camera,
    pub background: Vec3,
    /// Translucency: absorption per unit of view-space distance
    /// ([`Scene::absorption_per_length`]).
    per_length: f32,
    /// Whether ties are counted (the plan's `count_ties`).
    pub count_ties: bool,
}

impl<'a> Resolve<'a> {
    pub fn new(scene: &Scene, camera: &'a Camera, settings: &Settings) -> Self {
        Resolve {
            effect: settings.effect,
            camera,
            background: settings.background,
            per_length: scene.absorption_per_length() as f32,
            count_ties: false,
        }
    }

    /// The next fragment behind everything pushed so far.
    #[inline]
    pub fn push(&self, s: &mut PixelState, depth: f32, payload: u32) {
        s.captured += 1;
        if self.count_ties {
            s.tied += s.front_run.push(depth_bits(depth), payload);
        }
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
                        let absorb = (Vec3::ONE - c.truncate()) * self.per_length;
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
            if self.count_ties {
                s.tied += s.back_run.push(depth_bits(depth), payload);
            }
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

    /// Finishes every pixel into an sRGB image; returns it, the fragments captured in all and
    /// those counted tied.
    pub fn image(&self, width: u32, height: u32, states: &mut [PixelState]) -> (Image, u64, u64) {
        use rayon::prelude::*;
        let colors: Vec<Vec3> = states.par_iter_mut().map(|s| self.finish(s)).collect();
        let captured = states.iter().map(|s| u64::from(s.captured)).sum();
        let tied = states.iter().map(|s| u64::from(s.tied())).sum();
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
        (image, captured, tied)
    }
}

/// Linear RGB to an sRGB8 pixel.
#[inline]
pub(crate) fn srgb(c: Vec3) -> [u8; 4] {
    [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255]
}
