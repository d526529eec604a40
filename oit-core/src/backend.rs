//! The contract every backend keeps, and the capture abstractions the techniques are built from.
//!
//! A [`Backend`] turns a scene, a camera and settings into a [`Frame`]. Inside, each technique is
//! a *capture* — one or more geometry passes that update per-pixel storage — and a *resolve*
//! that turns each pixel's captured fragments into a colour. The storage comes in four shapes,
//! one trait each, so the CPU's atomics, the GPU's blend units and a GPU's storage buffers can
//! implement the same operation:
//!
//! - [`BucketArray`]: K one-fragment buckets per pixel, updated with MAX;
//! - [`DepthHistogram`]: a 1024-bit per-pixel presence histogram, updated with OR;
//! - [`AtomicFragmentList`]: a per-pixel fixed array, by atomic increment or atomic-min insertion;
//! - [`Compositor`]: a pixel's fragments, fed in depth order, to a colour.

use glam::Vec3;
use serde::Serialize;

use crate::rules::HISTOGRAM_WORDS;
use crate::{Camera, Frame, OitError, RasterPath, Scene, Settings, TechniqueKind};

/// What a backend can run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Capabilities {
    /// The device it runs on, in words.
    pub device: String,
    /// Techniques it runs.
    pub techniques: Vec<TechniqueKind>,
    /// Raster paths it has.
    pub raster_paths: Vec<RasterPath>,
    /// Device limits and features that matter to oit, as (name, value).
    pub limits: Vec<(String, String)>,
}

/// A scene made ready for many frames on one backend: geometry uploaded and per-scene data built
/// once; per-pixel storage kept between frames of the same size and reused; pipelines cached per
/// device. Made by [`Backend::prepare`].
///
/// ```
/// use oit_core::{Backend, Camera, Frame, OitError, Scene, Settings, View};
///
/// /// A turntable of `steps` frames: the scene is prepared once, each frame reuses its storage.
/// fn turntable(backend: &dyn Backend, scene: &Scene, settings: &Settings, steps: u32) -> Result<Vec<Frame>, OitError> {
///     let mut prepared = backend.prepare(scene)?;
///     let aspect = settings.width as f32 / settings.height as f32;
///     (0..steps)
///         .map(|i| {
///             let view = View { azimuth: 360.0 * i as f32 / steps as f32, ..View::default() };
///             prepared.frame(&Camera::orbit_scene(scene, view, aspect)?, settings)
///         })
///         .collect()
/// }
/// ```
pub trait Prepared {
    /// Renders one frame of the prepared scene. Bad input is an error, never a panic.
    fn frame(&mut self, camera: &Camera, settings: &Settings) -> Result<Frame, OitError>;
    /// Renders one frame as [`Prepared::frame`] does and waits for it, but reads back only its
    /// counters, not the image (nor per-pixel losses): what a frame loop that presents on the
    /// device pays. `oit bench` times it as the steady-state frame. The default renders a whole
    /// frame (a backend whose image is in host memory already has nothing to skip).
    fn frame_stats(&mut self, camera: &Camera, settings: &Settings) -> Result<crate::Stats, OitError> {
        self.frame(camera, settings).map(|f| f.stats)
    }
    /// A frame loop: one frame per camera, in order, each as [`Prepared::frame_stats`] renders it
    /// (its counters, not its image); `done(i, stats)` hears of frame `i` as it completes. A
    /// backend may keep [`Prepared::frames_in_flight`] frames submitted at once, recording frame
    /// `i + 1` while the device runs frame `i`, as a renderer's frame loop does; the wall time per
    /// frame of such a loop is what `oit bench` reports as the steady state. The default renders
    /// the frames one at a time.
    ///
    /// ```
    /// use oit_core::{Backend, Camera, OitError, Scene, Settings, View};
    ///
    /// /// Frames per second of a turntable of `steps` views.
    /// fn fps(backend: &dyn Backend, scene: &Scene, settings: &Settings, steps: u32) -> Result<f64, OitError> {
    ///     let cameras = (0..steps)
    ///         .map(|i| Camera::orbit_scene(scene, View { azimuth: 3.0 * i as f32, ..View::default() }, 1.0))
    ///         .collect::<Result<Vec<_>, _>>()?;
    ///     let mut prepared = backend.prepare(scene)?;
    ///     let start = std::time::Instant::now();
    ///     let mut fragments = 0;
    ///     prepared.frame_loop(&cameras, settings, &mut |_, stats| fragments += stats.fragments)?;
    ///     assert!(fragments > 0);
    ///     Ok(f64::from(steps) / start.elapsed().as_secs_f64())
    /// }
    /// ```
    fn frame_loop(
        &mut self,
        cameras: &[Camera],
        settings: &Settings,
        done: &mut dyn FnMut(usize, crate::Stats),
    ) -> Result<(), OitError> {
        frames_one_at_a_time(self, cameras, settings, done)
    }
    /// How many frames [`Prepared::frame_loop`] keeps submitted at once (1: one at a time).
    fn frames_in_flight(&self) -> usize {
        1
    }
    /// How many per-pixel storage allocations (buffers, arrays, resolve state) this prepared
    /// scene has made so far: the backend's own counter. A frame that reuses what an earlier
    /// frame of the same size made adds nothing.
    fn storage_allocations(&self) -> u64;
    /// How many pipelines (compute and render) the backend has created on this scene's device so
    /// far, where it makes any: a steady-state frame creates none. `None` for a backend without
    /// pipelines (oit-cpu).
    fn pipelines_created(&self) -> Option<u64> {
        None
    }
}

/// [`Prepared::frame_loop`] one frame at a time: the default, and what a backend that keeps frames
/// in flight falls back to where it cannot (frames in screen tiles).
pub fn frames_one_at_a_time<P: Prepared + ?Sized>(
    prepared: &mut P,
    cameras: &[Camera],
    settings: &Settings,
    done: &mut dyn FnMut(usize, crate::Stats),
) -> Result<(), OitError> {
    for (i, camera) in cameras.iter().enumerate() {
        done(i, prepared.frame_stats(camera, settings)?);
    }
    Ok(())
}

/// How [`frames_in_flight`] ended: the frames to render again one at a time (a frame whose end
/// found a speculation wrong: a sizing count, a peel count, a setup that outgrew its buffers), and
/// the first frame that must run in tiles (over the device's limits or the memory budget), if one
/// did.
#[derive(Debug, Default)]
#[must_use = "the frames it names have not been rendered yet: call `LoopEnd::finish`"]
pub struct LoopEnd {
    /// Frames to render again, in the order their ends found them wrong.
    pub again: Vec<usize>,
    /// The first frame that did not start: it and every frame after it render one at a time.
    pub from: Option<usize>,
}

impl LoopEnd {
    /// Renders the frames the loop left ([`Prepared::frame_stats`] each, in tiles where they
    /// need them); `done` hears of them after the others.
    pub fn finish<P: Prepared + ?Sized>(
        self,
        prepared: &mut P,
        cameras: &[Camera],
        settings: &Settings,
        done: &mut dyn FnMut(usize, crate::Stats),
    ) -> Result<(), OitError> {
        let rest = self.from.map_or(0..0, |from| from..cameras.len());
        for i in self.again.into_iter().chain(rest) {
            done(i, prepared.frame_stats(&cameras[i], settings)?);
        }
        Ok(())
    }
}

/// A frame loop with up to `depth` frames submitted at once: frame `i + 1` is started (recorded
/// and submitted) by `start` before frame `i`'s end is waited for by `end`, as a renderer's frame
/// loop does. `end` gives `None` for a frame to render again (its speculation was wrong; it is
/// named in [`LoopEnd::again`]). A start that fails with [`OitError::TooLarge`] ends the loop
/// there: the frames in flight are ended, and that frame and those after it are left to
/// [`LoopEnd::finish`], which renders them in tiles. Any other error ends the loop with it.
/// Windows of a frame (`--memory`, a region) are never in flight: with either set, every frame is
/// left to [`LoopEnd::finish`], one at a time.
pub fn frames_in_flight<'c, F>(
    cameras: &'c [Camera],
    settings: &Settings,
    depth: usize,
    mut start: impl FnMut(&'c Camera) -> Result<F, OitError>,
    mut end: impl FnMut(F) -> Result<Option<crate::Stats>, OitError>,
    done: &mut dyn FnMut(usize, crate::Stats),
) -> Result<LoopEnd, OitError> {
    if settings.memory.is_some() || settings.region.is_some() {
        return Ok(LoopEnd { again: Vec::new(), from: Some(0) });
    }
    let depth = depth.max(1);
    let mut flight = std::collections::VecDeque::with_capacity(depth);
    let mut out = LoopEnd::default();
    let mut finish = |(i, f): (usize, F), out: &mut LoopEnd| -> Result<(), OitError> {
        match end(f)? {
            Some(stats) => done(i, stats),
            None => out.again.push(i),
        }
        Ok(())
    };
    for (i, camera) in cameras.iter().enumerate() {
        if flight.len() >= depth
            && let Some(oldest) = flight.pop_front()
        {
            finish(oldest, &mut out)?;
        }
        match start(camera) {
            Ok(f) => flight.push_back((i, f)),
            Err(OitError::TooLarge { .. }) => {
                out.from = Some(i);
                break;
            }
            Err(e) => return Err(e),
        }
    }
    for f in flight.drain(..) {
        finish(f, &mut out)?;
    }
    Ok(out)
}

/// A renderer of every technique in its capabilities.
pub trait Backend {
    /// A short name (`cpu`, `wgpu`, `vulkan`).
    fn name(&self) -> &str;
    /// What it can run.
    fn capabilities(&self) -> Capabilities;
    /// Prepares `scene` for any number of frames ([`Prepared`]): checks it and builds what does
    /// not depend on the camera once.
    fn prepare<'s>(&'s self, scene: &'s Scene) -> Result<Box<dyn Prepared + 's>, OitError>;
    /// Renders one frame: the one-shot convenience over [`Backend::prepare`] and
    /// [`Prepared::frame`]. Bad input is an error, never a panic.
    fn render(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        self.prepare(scene)?.frame(camera, settings)
    }
    /// The raster path `render` takes with these settings (the one they name, else the
    /// backend's default for the technique).
    fn raster_path(&self, settings: &Settings) -> RasterPath {
        settings
            .raster
            .or_else(|| self.capabilities().raster_paths.first().copied())
            .unwrap_or(RasterPath::Cpu)
    }
    /// Bytes a pixel of a frame of `settings` holds beyond its plan's
    /// [`crate::plan::Plan::frame_bytes`], counted against the memory budget beside it: what
    /// the backend hands [`crate::tiling::run_with`] (oit-cpu's array of resolve states, larger
    /// than the plan's 23 words), and what [`crate::tiling::forecast`] sizes its windows by. 0 by
    /// default.
    fn frame_extra_bytes(&self, _settings: &Settings) -> u64 {
        0
    }
    /// Milliseconds of one plain geometry pass over `scene` (every fragment counted into a
    /// per-pixel atomic counter, nothing else) on the raster path `settings` select: the `Tv` of
    /// the depth-peeling speedup model `K = N·Tv / (Tv + Tf)`. Device time where the backend measures
    /// it, else wall time; per-frame setup (vertex transform, binning, pipeline creation) is not
    /// counted. The default says the backend cannot.
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        let _ = (scene, camera, settings);
        Err(OitError::Unsupported {
            backend: self.name().into(),
            what: "timing a plain geometry pass".into(),
        })
    }
}

/// A backend pinned to one raster path: `render` runs with `settings.raster` set to it. This is
/// how a front end lists one row per backend × path.
pub struct OnPath {
    /// The backend.
    pub backend: Box<dyn Backend>,
    /// Its path.
    pub path: RasterPath,
}

impl Backend for OnPath {
    fn name(&self) -> &str {
        self.backend.name()
    }
    fn capabilities(&self) -> Capabilities {
        self.backend.capabilities()
    }
    fn prepare<'s>(&'s self, scene: &'s Scene) -> Result<Box<dyn Prepared + 's>, OitError> {
        Ok(Box::new(PreparedOnPath { inner: self.backend.prepare(scene)?, path: self.path }))
    }
    fn render(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        self.backend.render(scene, camera, &Settings { raster: Some(self.path), ..settings.clone() })
    }
    fn raster_path(&self, _settings: &Settings) -> RasterPath {
        self.path
    }
    fn frame_extra_bytes(&self, settings: &Settings) -> u64 {
        self.backend.frame_extra_bytes(&Settings { raster: Some(self.path), ..settings.clone() })
    }
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        self.backend.plain_pass_ms(scene, camera, &Settings { raster: Some(self.path), ..settings.clone() })
    }
}

/// [`OnPath`]'s prepared scene: every frame on its path.
struct PreparedOnPath<'s> {
    inner: Box<dyn Prepared + 's>,
    path: RasterPath,
}

impl Prepared for PreparedOnPath<'_> {
    fn frame(&mut self, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        self.inner.frame(camera, &Settings { raster: Some(self.path), ..settings.clone() })
    }
    fn frame_stats(&mut self, camera: &Camera, settings: &Settings) -> Result<crate::Stats, OitError> {
        self.inner.frame_stats(camera, &Settings { raster: Some(self.path), ..settings.clone() })
    }
    fn frame_loop(
        &mut self,
        cameras: &[Camera],
        settings: &Settings,
        done: &mut dyn FnMut(usize, crate::Stats),
    ) -> Result<(), OitError> {
        self.inner.frame_loop(cameras, &Settings { raster: Some(self.path), ..settings.clone() }, done)
    }
    fn frames_in_flight(&self) -> usize {
        self.inner.frames_in_flight()
    }
    fn storage_allocations(&self) -> u64 {
        self.inner.storage_allocations()
    }
    fn pipelines_created(&self) -> Option<u64> {
        self.inner.pipelines_created()
    }
}

/// K one-fragment buckets per pixel, each updated concurrently with MAX: the bucket capture of
/// bdp (Liu et al., HPG 2009: MAX blending into 8 RGBA32F targets) and adp's batches.
///
/// The word is 32 bits (the bits of a non-negative float, which order as the float does, or a
/// packed colour) or 64 bits (depth bits above a payload). Zero is the empty bucket.
pub trait BucketArray: Sync {
    /// The bucket word.
    type Word: Copy + Eq + Default;
    /// Buckets per pixel.
    fn buckets(&self) -> usize;
    /// `bucket[pixel][k] = max(bucket[pixel][k], value)`; returns the bucket's previous word, so
    /// a capture can count the collision it just resolved (previous ≠ empty: one fragment of the
    /// two is gone).
    fn update_max(&self, pixel: usize, k: usize, value: Self::Word) -> Self::Word;
    /// Reads bucket `k` of `pixel` and empties it (adp reuses its buckets batch after batch).
    fn take(&self, pixel: usize, k: usize) -> Self::Word;
    /// The buckets of one pixel.
    fn read(&self, pixel: usize, out: &mut [Self::Word]);
}

/// A 1024-bit presence histogram per pixel, updated concurrently with OR: adp's first pass
/// (Liu et al., HPG 2009: logic-op OR into 8 RGBA32UI targets).
pub trait DepthHistogram: Sync {
    /// Sets bit `bin` of `pixel`'s histogram; true where the bit was clear before (from the OR's
    /// old value, as an atomic OR returns it), so a pixel's set bins can be counted as they are
    /// set.
    fn set(&self, pixel: usize, bin: u32) -> bool;
    /// The histogram of one pixel.
    fn read(&self, pixel: usize) -> [u32; HISTOGRAM_WORDS];
}

/// A fixed array of `capacity` fragment keys per pixel, filled concurrently: the capture of the
/// techniques that keep a pixel's fragments in K slots. Two disciplines implement it:
///
/// - **increment**: a per-pixel counter hands each fragment the next slot by atomic increment, in
///   arrival order, and the key is stored there; a fragment past K is the one dropped, and
///   `sorted` sorts the slots after capture (fabs; Liu et al. 2009). The GPU's accessor pairs for
///   the counter are `fabs_count_add` / `fabs_count`: `technique/fabs_counters.wgsl` over a
///   storage buffer and `fabs_counters_image.wgsl` over an R32_UINT storage image.
/// - **min**: each slot keeps the smaller of its key and the carried one and carries the larger
///   on, so the array stays sorted in any arrival order and the largest is the one dropped
///   (mdts, mdts64, mlp, fabs's overflow; Liu et al. 2009, Huang et al. 2011). On the GPU:
///   `mdts_min64` / `mdts_load64` (`mdts_keys.wgsl`, buffer; `mdts_keys_image.wgsl`, image) for
///   64-bit keys, and `mdts_min_high` / `mdts_min_low` / `mdts_load_*` (`mdts_words.wgsl`,
///   `mdts_words_image.wgsl`) for 32-bit mdts's two arrays, each one list of 32-bit keys.
///
/// The key is what the list orders by and what comes back: a 64-bit word (depth bits above a
/// payload, or above a primitive id), 32-bit mdts's packed word, or fabs's 96 bits (depth bits and
/// primitive id above the payload stored beside them, in a `u128`). Which fragment a full list
/// drops is the discipline's; the key that `insert` returns is it, so a capture counts its losses
/// where they happen.
pub trait AtomicFragmentList: Sync {
    /// A slot's key, in the order the list sorts by.
    type Key: Copy + Ord + Send + Sync;
    /// Slots per pixel.
    fn capacity(&self) -> usize;
    /// Offers a fragment key; returns the key that did not fit, if any (atomic-min insertion
    /// keeps the array sorted and drops the largest; atomic increment drops the newcomer).
    fn insert(&self, pixel: usize, key: Self::Key) -> Option<Self::Key>;
    /// The largest key the pixel keeps once its list is full; `None` while it has room. In a list
    /// that keeps the nearest (atomic min), every key it dropped is larger: `--overflow tail`
    /// merges the fragments whose keys are.
    fn last(&self, pixel: usize) -> Option<Self::Key>;
    /// The captured keys of one pixel, in key (depth) order.
    fn sorted(&self, pixel: usize, out: &mut Vec<Self::Key>);
    /// [`sorted`](Self::sorted), leaving the pixel's list empty: for a list reused pass after
    /// pass (mlp), read where no pass runs.
    fn take_sorted(&self, pixel: usize, out: &mut Vec<Self::Key>);
}

/// A pixel's captured fragments to a colour, fed one at a time in depth order: the resolve every
/// technique ends in, under the frame's effect (transparency, translucency, Fresnel, complexity).
///
/// Streaming, not a sorted slice: the peeling techniques produce a pixel's layers one pass at a
/// time and never hold them together, and dual depth peeling feeds two sequences (the front
/// nearest first, the back farthest first) that meet at the end. `push_back` is that second
/// sequence; a compositor that cannot take it composites it at `finish` from the nearest end.
/// The per-pixel state is the compositor's own type, kept in locals or a per-pixel array by the
/// backend. oit-cpu implements it over its f32 resolve (`oit-cpu/src/resolve.rs`); the GPU's
/// `resolve.wgsl` is the same state machine in WGSL, rule for rule.
pub trait Compositor {
    /// A pixel's state.
    type State: Default;
    /// The next fragment behind every fragment pushed so far (`payload`: the technique's packed
    /// colour, or the normal for Fresnel).
    fn push(&self, state: &mut Self::State, depth: f32, payload: u32);
    /// The next fragment in front of every fragment pushed from the back so far.
    fn push_back(&self, state: &mut Self::State, depth: f32, payload: u32);
    /// The pixel's linear colour once its fragments are in.
    fn finish(&self, state: &mut Self::State) -> Vec3;
}
