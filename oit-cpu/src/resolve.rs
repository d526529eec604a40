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
use oit_core::{Camera, Compositor, Effect, Image, Settings};

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

impl PixelState {
    /// Whether nothing was pushed, put behind or composited into the state: it is the default
    /// one (fields no fragment reached compared, not assumed).
    fn is_empty(&self) -> bool {
        self.captured == 0
            && self.back.is_none()
            && self.back_stack.is_empty()
            && self.front.color == Vec3::ZERO
            && self.front.transmittance == 1.0
            && self.optical == Vec3::ZERO
            && self.entry.is_none()
            && self.fresnel == 1.0
    }

    /// The state of a pixel whose fragments were composited front to back as they came
    /// (`plain`'s banded pass): `front` of the transparency effect after `captured` fragments,
    /// what [`Resolve::push`] of the same fragments in the same order leaves.
    pub fn composited(front: FrontToBack, captured: u32) -> PixelState {
        PixelState { front, captured, ..PixelState::default() }
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
    /// ([`oit_core::Scene::absorption_per_length`]).
    per_length: f32,
    /// Whether ties are counted (the plan's `count_ties`).
    pub count_ties: bool,
    /// The opaque pass's colours, where the frame has opaque parts: what each pixel's
    /// transparent fragments composite over instead of the background
    /// ([`Resolve::background_at`]).
    pub opaque: Option<&'a [Option<Vec3>]>,
    /// Samples a pixel: the opaque colours are kept a sample, sample `i` of pixel `px` at
    /// `px · samples + i` (docs/msaa.md).
    pub samples: usize,
    /// Above one sample, per pixel whether its opaque samples are all alike
    /// ([`crate::opaque::OpaqueImage::uniform`]).
    pub opaque_uniform: Option<&'a [bool]>,
}

impl<'a> Resolve<'a> {
    /// The resolve of a frame; `per_length` is the scene's [`oit_core::Scene::absorption_per_length`]
    /// (worked out once per prepared scene, not per frame).
    pub fn new(per_length: f64, camera: &'a Camera, settings: &Settings) -> Self {
        Resolve {
            effect: settings.effect,
            camera,
            background: settings.background,
            per_length: per_length as f32,
            count_ties: false,
            opaque: None,
            samples: 1,
            opaque_uniform: None,
        }
    }

    /// What sample `i` of pixel `px` composites over (a multisampled frame): that sample's opaque
    /// colour, or the background where no opaque fragment covers it.
    #[inline]
    pub fn background_at_sample(&self, px: usize, i: usize) -> Vec3 {
        match self.opaque {
            Some(o) => o[px * self.samples + i].unwrap_or(self.background),
            None => self.background,
        }
    }

    /// Whether every sample of pixel `px` composites over the same opaque fragment (or every one
    /// over the background): then a multisampled resolve may composite the pixel once, over
    /// [`Resolve::background_at_sample`]`(px, 0)`.
    #[inline]
    pub fn opaque_uniform(&self, px: usize) -> bool {
        self.opaque_uniform.is_none_or(|u| u[px])
    }

    /// What a multisampled pixel with nothing captured shows, and what a technique that keeps no
    /// mask composites a multisampled pixel over: the mean of its samples' backgrounds (summed in
    /// sample order, then times 1/N, as `background_at` in prelude.wgsl), the one background
    /// where they are alike.
    pub fn background_mean(&self, px: usize) -> Vec3 {
        if self.samples <= 1 || self.opaque_uniform(px) {
            return self.background_at_sample(px, 0);
        }
        let sum = (0..self.samples).fold(Vec3::ZERO, |sum, i| sum + self.background_at_sample(px, i));
        sum * (1.0 / self.samples as f32)
    }

    /// What pixel `px` composites over: its opaque colour, or the background where no opaque
    /// fragment fell (or the frame has no opaque parts). Above one sample, what a technique that
    /// keeps no mask composites the whole pixel over: the mean of its samples' colours
    /// ([`Resolve::background_mean`], prelude.wgsl's `background_at`; docs/msaa.md).
    #[inline]
    pub fn background_at(&self, px: usize) -> Vec3 {
        if self.samples > 1 {
            return self.background_mean(px);
        }
        match self.opaque {
            Some(o) => o[px].unwrap_or(self.background),
            None => self.background,
        }
    }

    /// Puts a pixel's tail (`--overflow tail`: the integer sums of the fragments behind its K
    /// nearest, Σα·r, Σα·g, Σα·b, Σα, count, as `Ctx::tail_pass` adds them) behind what was
    /// pushed: their weighted average (Bavoil & Myers 2008, `composite::weighted_average`) over
    /// the background becomes what the front composites over, as dual depth peeling's back half
    /// does. Transparency only (the plan refuses the tail with other effects).
    pub fn tail(&self, s: &mut PixelState, sums: &[std::sync::atomic::AtomicU64], px: usize) {
        self.tail_over(s, sums, self.background_at(px));
    }

    /// [`Resolve::tail`] over `behind` instead of the pixel's background: a multisampled pixel's
    /// one tail put behind each of its samples, over that sample's own opaque colour
    /// ([`Resolve::background_at_sample`]; docs/msaa.md).
    pub fn tail_over(&self, s: &mut PixelState, sums: &[std::sync::atomic::AtomicU64], behind: Vec3) {
        use std::sync::atomic::Ordering::Relaxed;
        let l = |i: usize| sums[i].load(Relaxed) as f32;
        let count = sums[4].load(Relaxed) as u32;
        if count == 0 {
            return;
        }
        let w = oit_core::composite::WeightedSums {
            premultiplied: Vec3::new(l(0), l(1), l(2)) / (255.0 * 255.0),
            alpha: l(3) / 255.0,
            count,
        };
        s.back = Some(oit_core::composite::weighted_average(&w, behind));
    }

    /// Finishes every pixel into an sRGB image; returns it, the fragments captured in all and
    /// those counted tied, and the most fragments one pixel captured. Each pixel is finished, converted to sRGB and counted in one parallel
    /// sweep (the heat map, which needs the deepest pixel first, takes a second).
    ///
    /// Every state is back to its default when this returns (each reset as it is finished, while
    /// it is in cache), so its array can be lent again without a sweep.
    pub fn image(&self, width: u32, height: u32, states: &mut [PixelState]) -> (Image, u64, u64, u32) {
        use rayon::prelude::*;
        let complexity = self.effect == Effect::Complexity;
        let mut image = Image::new(width, height, [0, 0, 0, 255]);
        let w = (width as usize).max(1);
        let (captured, tied, deepest) = image
            .pixels
            .par_chunks_mut(w)
            .zip(states.par_chunks_mut(w))
            .enumerate()
            .map(|(y, (pixels, states))| {
                let mut memo = SrgbMemo::default();
                let mut sums = (0, 0, 0);
                for (x, (px, s)) in pixels.iter_mut().zip(states).enumerate() {
                    *px = memo.srgb(self.finish_over(s, self.background_at(y * w + x)));
                    sums = add_counts(sums, (u64::from(s.captured), u64::from(s.tied()), s.captured));
                    if !complexity {
                        // reset while in cache: the states go back clean (see the doc)
                        *s = PixelState::default();
                    }
                }
                sums
            })
            .reduce(|| (0, 0, 0), add_counts);
        if complexity {
            let max = deepest.max(1);
            image.pixels.par_iter_mut().zip(states.par_iter_mut()).enumerate().for_each(|(i, (px, s))| {
                let c = if s.captured == 0 {
                    self.background_at(i)
                } else {
                    heat(s.captured as f32 / max as f32)
                };
                *px = srgb(c);
                *s = PixelState::default();
            });
        }
        (image, captured, tied, deepest)
    }
}

impl Resolve<'_> {
    /// [`Resolve::image`] for a technique whose fragments are all captured before the resolve
    /// (one sort and composite per pixel): each pixel's state lives only in the resolving thread's
    /// locals, made fresh, fed by `feed` (pixel index, a per-thread scratch value, the state) and
    /// finished at once, as a GPU resolve keeps it in registers: no per-pixel state array is
    /// written, reset or read back. Returns the image, the fragments captured and counted tied,
    /// and the most fragments one pixel captured.
    pub fn image_with<S, F>(&self, width: u32, height: u32, feed: F) -> (Image, u64, u64, u32)
    where
        S: Default + Send,
        F: Fn(usize, &mut S, &mut PixelState) + Sync + Send,
    {
        use rayon::prelude::*;
        let mut image = Image::new(width, height, [0, 0, 0, 255]);
        let complexity = self.effect == Effect::Complexity;
        // the heat map's scale is the deepest pixel: there a pixel keeps its count for a second
        // sweep (the pixel's bytes hold it, as `captured` fits no colour until the max is known)
        let mut counts = if complexity { vec![0u32; image.pixels.len()] } else { Vec::new() };
        // a pixel nothing reached finishes to the background under every effect (the heat map's
        // is drawn below): made once, not once per empty pixel
        let empty = srgb(self.finish(&mut PixelState::default()));
        // a row at a time, each row's colours converted through one memo
        let w = width as usize;
        let row = |scratch: &mut S, y: usize, pixels: &mut [[u8; 4]], mut counts: Option<&mut [u32]>| {
            let mut memo = SrgbMemo::default();
            let mut sums = (0, 0, 0);
            for (x, out) in pixels.iter_mut().enumerate() {
                let px = y * w + x;
                let mut state = PixelState::default();
                feed(px, scratch, &mut state);
                *out = match self.opaque {
                    None if state.is_empty() => empty,
                    _ => memo.srgb(self.finish_over(&mut state, self.background_at(px))),
                };
                if let Some(counts) = counts.as_deref_mut() {
                    counts[x] = state.captured;
                }
                sums = add_counts(sums, (u64::from(state.captured), u64::from(state.tied()), state.captured));
            }
            sums
        };
        let rows = image.pixels.par_chunks_mut(w.max(1)).enumerate();
        let (captured, tied, deepest) = if complexity {
            rows.zip(counts.par_chunks_mut(w.max(1)))
                .map_init(S::default, |scratch, ((y, pixels), counts)| row(scratch, y, pixels, Some(counts)))
                .reduce(|| (0, 0, 0), add_counts)
        } else {
            rows.map_init(S::default, |scratch, (y, pixels)| row(scratch, y, pixels, None))
                .reduce(|| (0, 0, 0), add_counts)
        };
        if complexity {
            let max = deepest.max(1);
            for (i, (px, &n)) in image.pixels.iter_mut().zip(&counts).enumerate() {
                let c = if n == 0 { self.background_at(i) } else { heat(n as f32 / max as f32) };
                *px = srgb(c);
            }
        }
        (image, captured, tied, deepest)
    }
}

/// The f32 resolve every technique of oit-cpu composites through (the reference has its own f64
/// code in `technique/reference.rs`).
impl Compositor for Resolve<'_> {
    type State = PixelState;

    /// The next fragment behind everything pushed so far.
    #[inline]
    fn push(&self, s: &mut PixelState, depth: f32, payload: u32) {
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
    fn push_back(&self, s: &mut PixelState, depth: f32, payload: u32) {
        self.push_back_over(s, depth, payload, self.background);
    }

    /// The final linear colour of a pixel (heat maps are finished by [`Resolve::image`]).
    fn finish(&self, s: &mut PixelState) -> Vec3 {
        self.finish_over(s, self.background)
    }
}

impl Resolve<'_> {
    /// [`Compositor::push_back`] of a pixel that composites over `background` (its
    /// [`Resolve::background_at`]).
    #[inline]
    pub fn push_back_over(&self, s: &mut PixelState, depth: f32, payload: u32, background: Vec3) {
        if self.effect == Effect::Transparency {
            s.captured += 1;
            if self.count_ties {
                s.tied += s.back_run.push(depth_bits(depth), payload);
            }
            let back = s.back.unwrap_or(background);
            s.back = Some(oit_core::composite::over(back, unpack_rgba8(payload)));
        } else {
            s.back_stack.push((depth, payload));
        }
    }

    /// [`Compositor::finish`] over `background` (the pixel's [`Resolve::background_at`]).
    #[inline]
    pub fn finish_over(&self, s: &mut PixelState, background: Vec3) -> Vec3 {
        while let Some((d, p)) = s.back_stack.pop() {
            self.push(s, d, p);
        }
        match self.effect {
            Effect::Transparency => s.front.over(s.back.unwrap_or(background)),
            Effect::Complexity => Vec3::ZERO,
            Effect::Fresnel => background * s.fresnel,
            Effect::Translucency => {
                let t = Vec3::new((-s.optical.x).exp(), (-s.optical.y).exp(), (-s.optical.z).exp());
                background * t
            }
        }
    }
}

/// Two parts' (captured, tied, deepest) of a resolve's sweep, joined.
fn add_counts(a: (u64, u64, u32), b: (u64, u64, u32)) -> (u64, u64, u32) {
    (a.0 + b.0, a.1 + b.1, a.2.max(b.2))
}

/// Linear RGB to an sRGB8 pixel.
#[inline]
pub(crate) fn srgb(c: Vec3) -> [u8; 4] {
    [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255]
}

/// [`srgb`] with the last colour's conversion kept: a run of pixels of one colour (the background
/// an empty pixel shows where the frame has an opaque part that misses it, row after row; a flat
/// unlit surface) converts it once. The same bits as [`srgb`]: a colour is reused only where it
/// is equal (a NaN never is; `-0.0 == 0.0`, both 0).
#[derive(Default)]
pub(crate) struct SrgbMemo {
    last: Option<(Vec3, [u8; 4])>,
}

impl SrgbMemo {
    #[inline]
    pub fn srgb(&mut self, c: Vec3) -> [u8; 4] {
        match self.last {
            Some((last, out)) if last == c => out,
            _ => {
                let out = srgb(c);
                self.last = Some((c, out));
                out
            }
        }
    }
}

#[cfg(test)]
mod tests {
    //! The resolve on small hand-built inputs. Each test names a mutation it catches (each was
    //! tried when the test was written).

    use glam::{DVec3, Vec3, Vec4};
    use oit_core::composite::{front_to_back, heat, translucency_f64};
    use oit_core::rules::{pack_normal, pack_rgba8};
    use oit_core::{Camera, Compositor as _, Effect, Scene, Settings, load_scene};

    use super::{PixelState, Resolve, Run, srgb};

    const BG: Vec3 = Vec3::new(0.9, 0.6, 0.3);

    /// A camera on +z looking at the origin, near 1, far 9 (so `linear_depth` spans 1..9).
    fn camera() -> Camera {
        Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 45.0, 1.0, 1.0, 9.0)
    }

    fn scene() -> Scene {
        load_scene("planes:2").unwrap()
    }

    fn resolve<'a>(scene: &Scene, camera: &'a Camera, effect: Effect, count_ties: bool) -> Resolve<'a> {
        let settings = Settings { effect, background: BG, ..Settings::default() };
        let mut r = Resolve::new(scene.absorption_per_length(), camera, &settings);
        r.count_ties = count_ties;
        r
    }

    /// The NDC depth [`Camera::linear_depth`] maps to view-space distance `dist`.
    fn ndc(camera: &Camera, dist: f32) -> f32 {
        let (n, f) = (camera.near, camera.far);
        (f - n * f / dist) / (f - n)
    }

    /// A run of equal depths counts nothing while it holds one payload, and every fragment of it
    /// once it holds two: the fragment that mixes it counts the whole run. Mutations caught:
    /// `tied = self.len` → `tied = 1` (the first push of `b` returns 1); a new run not clearing
    /// `mixed` (the push at depth 2 returns 1).
    #[test]
    fn runs_count_every_fragment_of_a_mixed_run() {
        let (a, b) = (7, 9);
        let mut run = Run::default();
        assert_eq!(run.counted(), 0);
        let got: Vec<u32> =
            [(1, a), (1, a), (1, b), (1, a), (2, a), (2, a), (3, b)].map(|(d, p)| run.push(d, p)).to_vec();
        assert_eq!(got, [0, 0, 3, 1, 0, 0, 0]);
        assert_eq!(run.counted(), 0, "the last run holds one fragment");
        // one payload over many depths is never tied
        let mut run = Run::default();
        assert_eq!([(1, a), (2, a), (2, a)].map(|(d, p)| run.push(d, p)), [0, 0, 0]);
        assert_eq!(run.counted(), 0);
        let mut run = Run::default();
        run.push(5, a);
        run.push(5, b);
        assert_eq!(run.counted(), 2);
    }

    /// Through [`Resolve::push`]: ties are counted only where the plan asks. Mutation caught:
    /// counting whatever `count_ties` says (the second total is 3, not 0).
    #[test]
    fn push_counts_ties_where_the_plan_asks() {
        let (scene, camera) = (scene(), camera());
        let (p, q) = (pack_rgba8(Vec4::new(1.0, 0.0, 0.0, 0.5)), pack_rgba8(Vec4::new(0.0, 1.0, 0.0, 0.5)));
        let layers = [(0.2, p), (0.2, p), (0.5, p), (0.5, q), (0.5, p)];
        for (count, want) in [(true, 3), (false, 0)] {
            let r = resolve(&scene, &camera, Effect::Transparency, count);
            let mut s = PixelState::default();
            for (d, payload) in layers {
                r.push(&mut s, d, payload);
            }
            assert_eq!((s.captured, s.tied()), (5, want), "count_ties {count}");
        }
    }

    /// Dual depth peeling: the front's last run and the back's last run join where they meet at
    /// one depth. Mutations caught: ignoring the back run's `mixed` in the join (case 5 gives 0);
    /// joining runs of different depths (case 4 gives 2); not subtracting the runs' own counts
    /// (case 3 gives 5).
    #[test]
    fn front_and_back_runs_join_where_they_meet() {
        let (scene, camera) = (scene(), camera());
        let r = resolve(&scene, &camera, Effect::Transparency, true);
        let (p, q) = (pack_rgba8(Vec4::new(1.0, 0.0, 0.0, 0.5)), pack_rgba8(Vec4::new(0.0, 1.0, 0.0, 0.5)));
        // (front pushes nearest first, back pushes farthest first, fragments counted tied)
        type Layers<'a> = &'a [(f32, u32)];
        let cases: [(Layers<'_>, Layers<'_>, u32); 6] = [
            (&[(0.3, p)], &[(0.3, q)], 2),
            (&[(0.3, p)], &[(0.3, p)], 0),
            (&[(0.3, p), (0.3, q)], &[(0.3, p)], 3),
            (&[(0.3, p)], &[(0.6, q)], 0),
            (&[(0.3, p)], &[(0.3, q), (0.3, p)], 3),
            (&[(0.1, q), (0.1, p), (0.3, p)], &[(0.9, q), (0.3, p)], 2),
        ];
        for (i, (front, back, want)) in cases.into_iter().enumerate() {
            let mut s = PixelState::default();
            for &(d, payload) in front {
                r.push(&mut s, d, payload);
            }
            for &(d, payload) in back {
                r.push_back(&mut s, d, payload);
            }
            assert_eq!(s.tied(), want, "case {}", i + 1);
            assert_eq!(s.captured as usize, front.len() + back.len(), "case {}", i + 1);
        }
    }

    /// Transparency from both ends equals front-to-back over all layers: the front under-blended,
    /// the back over-blended onto the background, joined. Mutation caught: the back half over
    /// `self.background` instead of the back accumulated so far (the middle layer drops out).
    #[test]
    fn front_and_back_halves_composite_as_one() {
        let (scene, camera) = (scene(), camera());
        let r = resolve(&scene, &camera, Effect::Transparency, false);
        let c = [
            Vec4::new(1.0, 0.0, 0.0, 0.4),
            Vec4::new(0.0, 1.0, 0.0, 0.6),
            Vec4::new(0.0, 0.0, 1.0, 0.2),
            Vec4::new(1.0, 1.0, 0.0, 0.8),
        ];
        let packed = c.map(pack_rgba8);
        let mut s = PixelState::default();
        r.push(&mut s, 0.1, packed[0]);
        r.push_back(&mut s, 0.9, packed[3]);
        r.push_back(&mut s, 0.6, packed[2]);
        r.push(&mut s, 0.3, packed[1]);
        let want = front_to_back(packed.map(oit_core::rules::unpack_rgba8), BG);
        let got = r.finish(&mut s);
        assert!((got - want).abs().max_element() < 1e-6, "{got} {want}");
    }

    /// Translucency pairs layers 0–1 and 2–3 and absorbs (1 − entry colour)·k per unit of
    /// view-space distance; the back half of dual depth peeling is replayed nearest first at the
    /// end. Closed form: background·exp(−k·((1 − c₀)·(d₁ − d₀) + (1 − c₂)·(d₃ − d₂))). Mutations
    /// caught: pairing the exit's colour (red channel: 0 absorbed for 1 − 0.25); replaying the
    /// back stack farthest first (the second medium gets a negative, clamped thickness).
    #[test]
    fn translucency_pairs_entries_with_exits() {
        let (scene, camera) = (scene(), camera());
        let r = resolve(&scene, &camera, Effect::Translucency, false);
        let k = scene.absorption_per_length();
        let dist = [2.0, 2.5, 3.25, 4.0];
        let c = [
            Vec4::new(0.2, 0.6, 1.0, 0.5),
            Vec4::new(1.0, 0.2, 0.6, 0.5),
            Vec4::new(0.6, 1.0, 0.2, 0.5),
            Vec4::new(0.2, 0.2, 0.2, 0.5),
        ];
        let (depth, payload) = (dist.map(|d| ndc(&camera, d)), c.map(pack_rgba8));
        let absorbed = |c: Vec4| (DVec3::ONE - c.truncate().as_dvec3()) * k;
        let tau = absorbed(c[0]) * 0.5 + absorbed(c[2]) * 0.75;
        let want = BG.as_dvec3() * DVec3::new((-tau.x).exp(), (-tau.y).exp(), (-tau.z).exp());
        // all from the front
        let mut s = PixelState::default();
        for i in 0..4 {
            r.push(&mut s, depth[i], payload[i]);
        }
        let front = r.finish(&mut s).as_dvec3();
        // dual depth peeling: two from the front, two from the back (farthest first)
        let mut s = PixelState::default();
        r.push(&mut s, depth[0], payload[0]);
        r.push(&mut s, depth[1], payload[1]);
        r.push_back(&mut s, depth[3], payload[3]);
        r.push_back(&mut s, depth[2], payload[2]);
        let dual = r.finish(&mut s).as_dvec3();
        assert_eq!(s.captured, 4);
        // the reference's f64 translucency on the same layers
        let reference = translucency_f64(
            (0..4).map(|i| {
                let q = oit_core::rules::unpack_rgba8_f64(payload[i]);
                (camera.linear_depth_f64(depth[i]), q)
            }),
            k,
            BG.as_dvec3(),
        );
        // 1e-5: f32 rounding of the depths, the distances and exp (the colours are exact in 8
        // bits: 0.2 = 51/255)
        for (what, got) in [("front", front), ("dual", dual), ("reference", reference)] {
            assert!((got - want).abs().max_element() < 1e-5, "{what}: {got} {want}");
        }
        // an unpaired last layer absorbs nothing
        let mut s = PixelState::default();
        for i in 0..3 {
            r.push(&mut s, depth[i], payload[i]);
        }
        let one = BG.as_dvec3()
            * DVec3::new(
                (-absorbed(c[0]).x * 0.5).exp(),
                (-absorbed(c[0]).y * 0.5).exp(),
                (-absorbed(c[0]).z * 0.5).exp(),
            );
        assert!((r.finish(&mut s).as_dvec3() - one).abs().max_element() < 1e-5);
    }

    /// Fresnel multiplies the background by 1 − (1 − |n·v|)⁵ per layer; complexity's heat map is
    /// heat(count / deepest), the background where nothing was captured. Mutations caught:
    /// dropping `abs` (the back-facing layer's 1 − 1.5⁵ < 0); the heat map scaled by a fixed 8
    /// instead of the deepest pixel (the 2-layer pixel shows heat(1/4), not heat(1/2)).
    #[test]
    fn fresnel_and_complexity() {
        let (scene, camera) = (scene(), camera());
        let r = resolve(&scene, &camera, Effect::Fresnel, false);
        let v = camera.forward;
        let tilted = |deg: f32| {
            let a = deg.to_radians();
            // a unit normal making angle `deg` with the viewing direction
            (v * a.cos() + Vec3::X * a.sin()).normalize()
        };
        let mut s = PixelState::default();
        r.push(&mut s, 0.2, pack_normal(tilted(0.0)));
        r.push(&mut s, 0.4, pack_normal(tilted(120.0)));
        r.push(&mut s, 0.6, pack_normal(tilted(60.0)));
        let want = BG * (31.0f32 / 32.0).powi(2);
        let got = r.finish(&mut s);
        assert!((got - want).abs().max_element() < 1e-4, "{got} {want}");

        let r = resolve(&scene, &camera, Effect::Complexity, false);
        let mut states = vec![PixelState::default(); 3];
        for (px, n) in [(1, 2), (2, 4)] {
            for i in 0..n {
                r.push(&mut states[px], 0.1 * (i + 1) as f32, 0);
            }
        }
        let (image, captured, tied, _) = r.image(3, 1, &mut states);
        assert_eq!((captured, tied), (6, 0));
        assert_eq!(image.pixels, [srgb(BG), srgb(heat(0.5)), srgb(heat(1.0))]);
        assert_eq!(heat(0.5), Vec3::new(0.6, 0.05, 0.5), "the ramp's middle stop");
    }
}
