//! One file per technique. Each runs its geometry passes through [`Ctx::pass`], keeps its
//! per-pixel storage in std atomics, and feeds each pixel's captured fragments, nearest first, to
//! the shared [`Resolve`](crate::resolve::Resolve).

use std::sync::atomic::{AtomicU8, AtomicU32, AtomicU64, Ordering::Relaxed};

use oit_core::plan::{Counted, Plan};
use oit_core::rules::{depth_bits, pack_normal, pack_rgba8};
use oit_core::{Camera, Effect, OitError, Scene, Settings, Technique};

use crate::pool::{Pool, Pooled};
use crate::raster::{Fragment, Rasterizer, Shade};
use crate::resolve::{PixelState, Resolve};

pub(crate) mod adp;
pub(crate) mod bdp;
pub(crate) mod ddp;
pub(crate) mod dfb;
pub(crate) mod dp;
pub(crate) mod fabs;
pub(crate) mod ll;
pub(crate) mod mboit;
pub(crate) mod mdts;
pub(crate) mod mlp;
pub(crate) mod msaa;
pub(crate) mod plain;
pub(crate) mod reference;
#[cfg(test)]
mod seam;
pub(crate) mod wboit;
pub(crate) mod weighted;

/// Runs `technique`'s frame over `ctx`: the one line a technique adds on the CPU beside its module.
pub(crate) fn render(ctx: &mut Ctx<'_>, technique: Technique) -> Result<oit_core::Frame, OitError> {
    if ctx.settings.samples > 1 && oit_core::msaa::keeps_masks(technique) {
        return msaa::render(ctx, technique);
    }
    match technique {
        Technique::Reference => reference::render(ctx),
        Technique::Plain => plain::render(ctx),
        Technique::Dp => dp::render(ctx),
        Technique::Ddp => ddp::render(ctx),
        Technique::WeightedAverage => weighted::render(ctx, true),
        Technique::WeightedSum => weighted::render(ctx, false),
        Technique::Wboit => wboit::render(ctx),
        Technique::Mboit { .. } => mboit::render(ctx),
        Technique::Bdp { .. } => bdp::render(ctx),
        Technique::Adp => adp::render(ctx),
        Technique::Mdts { .. } => mdts::render32(ctx),
        Technique::Mdts64 { .. } => mdts::render64(ctx),
        Technique::Fabs { .. } => fabs::render(ctx),
        Technique::Mlp { m } => mlp::render(ctx, m),
        Technique::Dfb => dfb::render(ctx),
        Technique::Ll => ll::render(ctx),
        // refused before a frame starts with the plan's reason (Plan::refuse_interlock)
        Technique::Kbuf { .. } => Err(OitError::Unsupported {
            backend: "cpu".into(),
            what: "kbuf: no fragment-stage interlock".into(),
        }),
    }
}

/// What a frame's passes walk above one sample where its technique keeps no coverage mask
/// ([`oit_core::msaa::coverage`]: its alpha weighted by its coverage fraction, or at full alpha
/// per pixel); `None` where the frame walks single-sample fragments or the technique's own
/// masked passes ([`msaa`]).
pub(crate) fn covered(settings: &Settings) -> Option<crate::raster::Covered> {
    use oit_core::msaa::Coverage;
    match oit_core::msaa::coverage(settings)? {
        Coverage::Sample => None,
        _ if oit_core::msaa::keeps_masks(settings.technique) => None,
        c => Some(crate::raster::Covered { samples: settings.samples, fraction: c == Coverage::Fraction }),
    }
}

/// Everything a technique needs for one frame, and the counters it updates.
pub(crate) struct Ctx<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub settings: &'a Settings,
    pub raster: &'a Rasterizer,
    pub resolve: Resolve<'a>,
    pub pixels: usize,
    /// Geometry passes run so far.
    pub passes: u32,
    /// Fragments one pass over the scene generates (set by the first pass).
    pub fragments: Option<u64>,
    /// Bytes of per-pixel storage allocated.
    pub storage_bytes: u64,
    /// Where per-pixel storage comes from, and goes back to after the frame.
    pub pool: &'a Pool,
    /// The frame's plan: refusals, sizing and stop rules, oit-core's.
    pub plan: Plan,
    /// Translucency's absorption per unit of length ([`Scene::absorption_per_length`]).
    pub per_length: f64,
    /// The memory budget of the frame's storage and outputs, all allocations together (issue
    /// 13.9, 41.7).
    pub budget: (String, u64),
    /// Fragments lost per pixel, counted where each is lost (a bucket collision, a key carried
    /// off a full array, a counter past K, a tie a peel skips, a fragment left behind the last
    /// peel the plan allows): never derived from `fragments − captured`.
    pub lost: Pooled<'a, AtomicU32>,
    /// Fragments merged into pixels' tails (`--overflow tail`), set by the technique.
    pub merged: u64,
    /// The scene's opaque part where a technique draws the opaque pass itself: the supersampled
    /// reference, one opaque pass in each of its frames (docs/msaa.md); `None` elsewhere (the
    /// frame's opaque pass is drawn before the technique runs).
    pub opaque_part: Option<&'a Scene>,
}

impl<'a> Ctx<'a> {
    #[expect(clippy::too_many_arguments, reason = "a frame's context is that many things")]
    pub fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &'a Settings,
        raster: &'a Rasterizer,
        pool: &'a Pool,
        plan: Plan,
        per_length: f64,
        opaque: Option<&'a crate::opaque::OpaqueImage>,
    ) -> Self {
        let mut resolve = Resolve::new(per_length, camera, settings);
        resolve.count_ties = plan.count_ties;
        resolve.opaque = opaque.map(|o| &o.color[..]);
        resolve.opaque_uniform = opaque.map(|o| &o.uniform[..]);
        resolve.samples = settings.samples.max(1) as usize;
        let budget = crate::cpu_budget(settings, &plan);
        Ctx {
            scene,
            camera,
            settings,
            raster,
            resolve,
            pixels: settings.pixel_count(),
            passes: 0,
            fragments: None,
            storage_bytes: 0,
            pool,
            plan,
            per_length,
            budget,
            lost: pool.u32s(settings.pixel_count(), 0),
            merged: 0,
            opaque_part: None,
        }
    }

    /// Counts one fragment of `pixel` lost.
    #[inline]
    pub fn lose(&self, pixel: usize) {
        self.lost[pixel].fetch_add(1, Relaxed);
    }

    /// Settles a tie count after a peel pass: `seen` fragments of a pixel sat at the depths the
    /// previous pass peeled and were skipped by the strict comparison; `peeled` of them were the
    /// ones that pass captured, the rest are lost. A mismatch (`seen < peeled`) is left
    /// uncounted, so the frame's `captured + lost == fragments` check catches it.
    #[inline]
    pub fn settle_ties(&self, pixel: usize, seen: u32, peeled: u32) {
        let lost = seen.saturating_sub(peeled);
        if lost > 0 {
            self.lost[pixel].fetch_add(lost, Relaxed);
        }
    }

    /// A capture pass for shaders that count losses: `shader` gets the per-pixel lost counters,
    /// and every fragment's payload ([`Ctx::payload`]) is made ahead ([`Ctx::payload_shade`]).
    pub fn pass_lossy<F: Fn(&Fragment<'_>, &Ctx<'_>) + Sync>(&mut self, shader: F) {
        let generated = self.raster.for_each_fragment_with(self.payload_shade(), |f| shader(f, self));
        self.ran_pass(generated);
    }

    /// One geometry pass over the scene: `shader` runs for every fragment, concurrently; colour
    /// and normal are made where it asks.
    pub fn pass<F: Fn(&Fragment<'_>) + Sync>(&mut self, shader: F) {
        self.pass_with(Shade::OnDemand, shader);
    }

    /// A pass whose shader reads every fragment's colour (made ahead, several at once:
    /// [`Shade::Color`]), with `ahead(pixel)` called a few fragments before each fragment of the
    /// pixel comes ([`Rasterizer::for_each_shaded_fragment_ahead`]): for a shader whose atomics
    /// miss the cache, `ahead` prefetches the pixel's words.
    pub fn pass_shaded_ahead<F: Fn(&Fragment<'_>) + Sync>(&mut self, ahead: impl Fn(u32) + Sync, shader: F) {
        let generated = self.raster.for_each_shaded_fragment_ahead(&ahead, shader);
        self.ran_pass(generated);
    }

    fn pass_with<F: Fn(&Fragment<'_>) + Sync>(&mut self, shade: Shade, shader: F) {
        let generated = self.raster.for_each_fragment_with(shade, shader);
        self.ran_pass(generated);
    }

    /// Counts a geometry pass a technique ran on [`Ctx::raster`] itself, which generated
    /// `generated` fragments.
    pub fn ran_pass(&mut self, generated: u64) {
        self.passes += 1;
        self.fragments.get_or_insert(generated);
    }

    /// How a pass that reads every fragment's [`Ctx::payload`] shades: colours ahead
    /// ([`Shade::Color`]) unless the payload is the normal (Fresnel), made on demand.
    pub fn payload_shade(&self) -> Shade {
        match self.resolve.effect {
            Effect::Fresnel => Shade::OnDemand,
            _ => Shade::Color,
        }
    }

    /// The word a fragment carries for the chosen effect: its RGBA8 colour, or its packed normal.
    #[inline]
    pub fn payload(&self, f: &Fragment<'_>) -> u32 {
        match self.resolve.effect {
            Effect::Fresnel => pack_normal(f.normal()),
            _ => pack_rgba8(f.color()),
        }
    }

    /// Allocates `per_pixel` zeroed-or-`init` words of 32 bits per pixel, counting the bytes.
    pub fn alloc32(&mut self, per_pixel: usize, init: u32) -> Result<Pooled<'a, AtomicU32>, OitError> {
        self.words32((self.pixels as u64).saturating_mul(per_pixel as u64), init)
    }

    /// Allocates `per_pixel` words of 64 bits per pixel, counting the bytes.
    pub fn alloc64(&mut self, per_pixel: usize, init: u64) -> Result<Pooled<'a, AtomicU64>, OitError> {
        self.words64((self.pixels as u64).saturating_mul(per_pixel as u64), init)
    }

    /// Allocates `per_pixel` words of 64 bits per pixel as empty (min, max) pairs
    /// ([`Pool::empty_min_max`](crate::pool::Pool::empty_min_max)), counting the bytes.
    pub fn alloc_min_max(&mut self, per_pixel: usize) -> Result<Pooled<'a, AtomicU64>, OitError> {
        let n = self.checked((self.pixels as u64).saturating_mul(per_pixel as u64), 8)?;
        Ok(self.pool.empty_min_max(n))
    }

    /// Allocates `per_pixel` words of 64 bits per pixel whose contents are left as an earlier
    /// frame left them (zero when newly made), counting the bytes: for slots written before they
    /// are read (below a per-pixel counter), where resetting them would be a frame's largest
    /// memory traffic for nothing.
    pub fn scratch64(&mut self, per_pixel: usize) -> Result<Pooled<'a, AtomicU64>, OitError> {
        let n = self.checked((self.pixels as u64).saturating_mul(per_pixel as u64), 8)?;
        Ok(self.pool.u64s_scratch(n))
    }

    /// [`Ctx::scratch64`] in words of 32 bits.
    pub fn scratch32(&mut self, per_pixel: usize) -> Result<Pooled<'a, AtomicU32>, OitError> {
        let n = self.checked((self.pixels as u64).saturating_mul(per_pixel as u64), 4)?;
        Ok(self.pool.u32s_scratch(n))
    }

    /// Allocates `len` words of 32 bits (an array sized from a count, not a multiple of the
    /// pixels), counting the bytes.
    pub fn words32(&mut self, len: u64, init: u32) -> Result<Pooled<'a, AtomicU32>, OitError> {
        let n = self.checked(len, 4)?;
        Ok(self.pool.u32s(n, init))
    }

    /// Allocates `len` words of 64 bits, counting the bytes.
    pub fn words64(&mut self, len: u64, init: u64) -> Result<Pooled<'a, AtomicU64>, OitError> {
        let n = self.checked(len, 8)?;
        Ok(self.pool.u64s(n, init))
    }

    /// `len` words of 64 bits left as an earlier frame left them (zero when newly made), counting
    /// the bytes: for an array sized from a count whose every slot is written before it is read.
    pub fn scratch_words64(&mut self, len: u64) -> Result<Pooled<'a, AtomicU64>, OitError> {
        let n = self.checked(len, 8)?;
        Ok(self.pool.u64s_scratch(n))
    }

    /// [`Ctx::scratch_words64`] in bytes (the multisampled frames' coverage masks, one a fragment),
    /// counted in whole 32-bit words as every backend allocates them (`plan::Array::bytes`).
    pub fn scratch_bytes(&mut self, len: u64) -> Result<Pooled<'a, AtomicU8>, OitError> {
        self.checked(len.div_ceil(4), 4)?;
        let n = usize::try_from(len)
            .map_err(|_| OitError::Device(format!("{len} bytes do not fit this host's address space")))?;
        Ok(self.pool.u8s_scratch(n))
    }

    /// [`Ctx::scratch_words64`] in words of 32 bits.
    pub fn scratch_words32(&mut self, len: u64) -> Result<Pooled<'a, AtomicU32>, OitError> {
        let n = self.checked(len, 4)?;
        Ok(self.pool.u32s_scratch(n))
    }

    fn checked(&mut self, len: u64, word: u64) -> Result<usize, OitError> {
        // Keep one allocation under 16 GiB: past that a laptop swaps or dies, so say so instead.
        const LIMIT: u64 = 16 << 30;
        let bytes = len.saturating_mul(word);
        if bytes > LIMIT {
            return Err(OitError::TooLarge {
                what: format!("{} per-pixel storage", self.settings.technique),
                needed: bytes,
                limit_name: "oit-cpu allocation limit".into(),
                limit: LIMIT,
                hint: "use a smaller --size or a smaller K".into(),
            });
        }
        // the frame's total so far, the resolve state and the outputs included (as
        // `Plan::frame_bytes` counts them), against the budget: sizes known only after a counting
        // pass (the reference's lists, fabs/mdts without K) are checked here, before allocating
        let pixels = self.pixels as u64;
        let opaque = self.plan.opaque_bytes();
        let state = pixels.saturating_mul(oit_core::plan::RESOLVE_STATE_BYTES + opaque);
        oit_core::plan::check_total(
            &format!("{} storage and outputs of a frame of {} pixels", self.settings.technique, self.pixels),
            self.storage_bytes
                .saturating_add(state)
                .saturating_add(self.plan.output_bytes(pixels))
                .saturating_add(pixels.saturating_mul(crate::state_array_extra(self.settings)))
                .saturating_add(bytes),
            (&self.budget.0, self.budget.1),
        )?;
        self.storage_bytes += bytes;
        usize::try_from(len)
            .map_err(|_| OitError::Device(format!("{len} words do not fit this host's address space")))
    }

    /// The tail sums of `--overflow tail` where the plan has a tail (5 words a pixel: Σα·r,
    /// Σα·g, Σα·b in units of 1/255², Σα in units of 1/255, the count), allocated whether or not
    /// a pixel overflows, as `Plan::arrays` counts them.
    pub fn tail_sums(&mut self) -> Result<Option<Pooled<'a, AtomicU64>>, OitError> {
        if self.plan.tail { Ok(Some(self.alloc64(5, 0)?)) } else { Ok(None) }
    }

    /// The tail pass of `--overflow tail` (multi-layer alpha blending's tail, Salvi & Vaidyanathan
    /// 2014, kept as order-independent integer sums): one geometry pass in which `behind` gives the
    /// RGBA8 colour of each fragment that lies behind its pixel's K-th nearest (None for the
    /// others); those are added to the pixel's `sums` and, since the capture counted them lost
    /// when it found no room, moved from `lost` to `merged`. Integer adds, so the sums and the
    /// image do not depend on the order fragments arrive in.
    pub fn tail_pass<F: Fn(&Fragment<'_>) -> Option<u32> + Sync>(&mut self, sums: &[AtomicU64], behind: F) {
        let lost = &self.lost;
        self.raster.for_each_fragment(|f| {
            if let Some(c) = behind(f) {
                tail_add(sums, lost, f.pixel as usize, c);
            }
        });
        self.end_tail_pass(sums);
    }

    /// [`Ctx::tail_pass`] over the multisampled fragments (`Settings::samples` above 1, fabs's
    /// `--overflow tail`; docs/msaa.md): `behind` gives the RGBA8 colour of each fragment (with
    /// its coverage mask) behind its pixel's K-th nearest, its alpha already weighted by its
    /// coverage fraction; the same integer sums, the same move from `lost` to merged.
    pub fn tail_pass_masked<F: Fn(&Fragment<'_>, u8) -> Option<u32> + Sync>(
        &mut self,
        sums: &[AtomicU64],
        behind: F,
    ) {
        let lost = &self.lost;
        self.raster.for_each_masked_fragment(self.settings.samples, |f, mask| {
            if let Some(c) = behind(f, mask) {
                tail_add(sums, lost, f.pixel as usize, c);
            }
        });
        self.end_tail_pass(sums);
    }

    /// A tail pass counted, and the fragments merged in all read from the sums' counts.
    fn end_tail_pass(&mut self, sums: &[AtomicU64]) {
        self.passes += 1;
        self.merged = sums.iter().skip(4).step_by(5).map(|c| c.load(Relaxed)).sum();
    }

    /// Per-pixel resolve state.
    pub fn states(&self) -> Pooled<'a, PixelState> {
        self.pool.states(self.pixels)
    }

    /// The deepest pixel's fragment count, from one counting pass (for sizing arrays from the
    /// scene instead of a worst case).
    pub fn max_depth_complexity(&mut self) -> Result<u32, OitError> {
        let counts = self.alloc32(1, 0)?;
        self.pass(|f| {
            counts[f.pixel as usize].fetch_add(1, Relaxed);
        });
        self.storage_bytes -= self.pixels as u64 * 4;
        let deepest = counts.iter().map(|c| c.load(Relaxed)).max().unwrap_or(0);
        let fragments = counts.iter().map(|c| u64::from(c.load(Relaxed))).sum();
        drop(counts);
        self.check_counted(Counted { deepest, fragments })?;
        Ok(deepest)
    }

    /// Checks the whole frame, sized by what its counting pass found, against the budget before
    /// any array sized by it is allocated: the plan's [`Plan::frame_bytes`] and the state array's
    /// extra, as the tiling loop sized the window by before its count. A refusal then names the
    /// frame's whole need, not the part allocated when an array went over, so the window splits
    /// by the true ratio, and `auto` foresees it ([`oit_core::tiling::forecast`] refuses the
    /// same windows by the same numbers).
    pub fn check_counted(&self, counted: Counted) -> Result<(), OitError> {
        let pixels = self.pixels as u64;
        oit_core::plan::check_total(
            &format!("{} storage and outputs of a frame of {pixels} pixels", self.settings.technique),
            self.plan
                .frame_bytes(pixels, counted)
                .saturating_add(pixels.saturating_mul(crate::state_array_extra(self.settings))),
            (&self.budget.0, self.budget.1),
        )
    }

    /// Per-pixel depth range [zNear, zFar] for the bucket techniques, from the instances'
    /// bounding boxes (HPG 2009's default) or from the fragments themselves; one geometry pass.
    /// Pixels nothing reached get [0, 1].
    pub fn depth_bounds(&mut self) -> Result<Vec<(f32, f32)>, OitError> {
        let lo = self.alloc32(1, u32::MAX)?;
        let hi = self.alloc32(1, 0)?;
        let shader = |f: &Fragment<'_>| {
            let b = depth_bits(f.depth);
            lo[f.pixel as usize].fetch_min(b, Relaxed);
            hi[f.pixel as usize].fetch_max(b, Relaxed);
        };
        match self.plan.bounds {
            oit_core::BoundsMode::Exact => self.pass(shader),
            oit_core::BoundsMode::Boxes | oit_core::BoundsMode::Auto => {
                let mut boxes = Rasterizer::bounding_boxes(self.scene, self.camera, self.settings);
                // the boxes' multisampled fragments where the frame's are (the GPU's box raster
                // runs the same masked rule), so every pixel a fragment reaches has bounds
                boxes.cover(covered(self.settings));
                boxes.for_each_fragment(shader);
                self.passes += 1;
            }
        }
        Ok(lo
            .iter()
            .zip(hi.iter())
            .map(|(l, h)| {
                let (l, h) = (l.load(Relaxed), h.load(Relaxed));
                if l > h { (0.0, 1.0) } else { (f32::from_bits(l), f32::from_bits(h)) }
            })
            .collect())
    }
}

/// Wraps up a frame: stats from the context; `captured` fragments reached the composite. Under
/// the test hook `OIT_MUTATION=cpu-losses-at-pixel-zero` ([`oit_core::mutation`]) the per-pixel
/// losses are all reported at pixel 0: the sum holds, the pixels lie, and
/// `checks::errors_within_losses` must fail (`tests/tests/mutations.rs`).
pub(crate) fn frame(ctx: &Ctx<'_>, image: oit_core::Image, captured: u64) -> oit_core::Frame {
    let fragments = ctx.fragments.unwrap_or(0);
    let mut lost_pixels: Vec<u32> = ctx.lost.iter().map(|l| l.load(Relaxed)).collect();
    if oit_core::mutation::active("cpu-losses-at-pixel-zero") && !lost_pixels.is_empty() {
        let all = lost_pixels.iter().fold(0u32, |a, &l| a.wrapping_add(l));
        lost_pixels.fill(0);
        lost_pixels[0] = all;
    }
    let lost: u64 = lost_pixels.iter().map(|&l| u64::from(l)).sum();
    oit_core::Frame {
        image,
        layers: None,
        lost_pixels: Some(lost_pixels),
        stats: oit_core::Stats {
            geometry_passes: ctx.passes,
            fragments,
            captured,
            lost,
            merged: ctx.merged,
            storage_bytes: ctx.storage_bytes,
            ..Default::default()
        },
    }
}

/// The ending of a technique that finishes each pixel without a resolve state: `pixel(px)` gives
/// pixel `px`'s sRGB colour and the fragments it took, in parallel; the image, the fragments
/// captured and the deepest pixel go into the frame.
pub(crate) fn finish_pixels(
    ctx: &Ctx<'_>,
    pixel: impl Fn(usize) -> ([u8; 4], u32) + Sync,
) -> oit_core::Frame {
    finish_pixels_with(ctx, || (), |_, px| pixel(px))
}

/// [`finish_pixels`] with a scratch each task of the parallel sweep makes once by `init` and
/// hands to `pixel(scratch, px)` for each of its pixels (a list of a pixel's entries kept from
/// pixel to pixel: a thread-local's lookup a pixel cost as much as a pixel's sort).
pub(crate) fn finish_pixels_with<T>(
    ctx: &Ctx<'_>,
    init: impl Fn() -> T + Sync + Send,
    pixel: impl Fn(&mut T, usize) -> ([u8; 4], u32) + Sync,
) -> oit_core::Frame {
    use rayon::prelude::*;
    let mut image = oit_core::Image::new(ctx.settings.width, ctx.settings.height, [0, 0, 0, 255]);
    let (captured, deepest) = image
        .pixels
        .par_iter_mut()
        .enumerate()
        .map_init(init, |scratch, (px, out)| {
            let (colour, n) = pixel(scratch, px);
            *out = colour;
            (u64::from(n), n)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1.max(b.1)));
    let mut frame = frame(ctx, image, captured);
    frame.stats.max_layers = deepest;
    frame
}

/// The ending of the weighted techniques (`wavg`, `wsum`, `wboit`, `mboit`), which keep `words`
/// u64 sums a pixel with its fragment count at word `count_word`: each pixel's words are taken
/// (emptied as they are read, and only where a fragment came, so the next frame lends the array
/// without a sweep), and `colour(words, count, behind)` composites them to a linear colour over
/// `behind` (the pixel's opaque colour or the background); a pixel no fragment reached gets the
/// empty sums' composite. Under the complexity effect only the counts go into
/// the resolve states.
pub(crate) fn finish_sums<'a>(
    ctx: &Ctx<'a>,
    mut sums: Pooled<'a, AtomicU64>,
    words: usize,
    count_word: usize,
    colour: impl Fn(&[u64], u32, glam::Vec3) -> glam::Vec3 + Sync,
) -> oit_core::Frame {
    use rayon::prelude::*;
    const MAX_WORDS: usize = 16;
    assert!(words <= MAX_WORDS && count_word < words, "{words} sum words, count at {count_word}");
    let take = |s: &[AtomicU64]| {
        let count = crate::storage::take_u64(&s[count_word], 0) as u32;
        let mut w = [0u64; MAX_WORDS];
        if count > 0 {
            for (v, word) in w.iter_mut().zip(s) {
                *v = crate::storage::take_u64(word, 0);
            }
        }
        (w, count)
    };
    let frame = if ctx.resolve.effect == Effect::Complexity {
        let mut states = ctx.states();
        states.par_iter_mut().zip(sums.par_chunks(words)).for_each(|(state, s)| state.captured = take(s).1);
        finish(ctx, states)
    } else {
        // a pixel no fragment reached: the empty sums' composite over what lies behind it, made
        // once where that is the background everywhere
        let zeros = [0u64; MAX_WORDS];
        let empty = crate::resolve::srgb(colour(&zeros[..words], 0, ctx.settings.background));
        let resolve = &ctx.resolve;
        finish_pixels_with(ctx, crate::resolve::SrgbMemo::default, |memo, px| {
            let (w, count) = take(&sums[words * px..words * px + words]);
            let behind = resolve.background_at(px);
            match (count, resolve.opaque) {
                (0, None) => (empty, 0),
                (0, Some(_)) => (memo.srgb(colour(&zeros[..words], 0, behind)), 0),
                _ => (memo.srgb(colour(&w[..words], count, behind)), count),
            }
        })
    };
    sums.mark_clean(crate::pool::Clean::Word(0));
    frame
}

/// Resolves each pixel from a state in the resolving thread's locals, fed by `feed` (the ending
/// of a technique that captures every fragment before its one resolve;
/// [`Resolve::image_with`](crate::resolve::Resolve::image_with)).
pub(crate) fn finish_with<S, F>(ctx: &Ctx<'_>, feed: F) -> oit_core::Frame
where
    S: Default + Send,
    F: Fn(usize, &mut S, &mut PixelState) + Sync + Send,
{
    let (image, captured, tied, deepest) =
        ctx.resolve.image_with(ctx.settings.width, ctx.settings.height, feed);
    let mut frame = frame(ctx, image, captured);
    frame.stats.tied = tied;
    frame.stats.max_layers = deepest;
    frame
}

/// Resolves the states into the frame (the common ending).
pub(crate) fn finish<'a>(ctx: &Ctx<'a>, mut states: Pooled<'a, PixelState>) -> oit_core::Frame {
    let (image, captured, tied, deepest) =
        ctx.resolve.image(ctx.settings.width, ctx.settings.height, &mut states);
    // Resolve::image leaves every state at its default
    states.mark_clean(crate::pool::Clean::Default);
    let mut frame = frame(ctx, image, captured);
    frame.stats.tied = tied;
    frame.stats.max_layers = deepest;
    frame
}

/// Adds RGBA8 colour `c` to pixel `px`'s tail sums (Σα·r, Σα·g, Σα·b, Σα, count) and moves the
/// fragment from `lost` (where the capture counted it) to merged.
fn tail_add(sums: &[AtomicU64], lost: &[AtomicU32], px: usize, c: u32) {
    let a = u64::from(c >> 24);
    let base = px * 5;
    sums[base].fetch_add(a * u64::from(c & 0xff), Relaxed);
    sums[base + 1].fetch_add(a * u64::from(c >> 8 & 0xff), Relaxed);
    sums[base + 2].fetch_add(a * u64::from(c >> 16 & 0xff), Relaxed);
    sums[base + 3].fetch_add(a, Relaxed);
    sums[base + 4].fetch_add(1, Relaxed);
    lost[px].fetch_sub(1, Relaxed);
}
