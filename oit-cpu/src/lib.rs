//! oit-cpu: oit's CPU backend — a software rasterizer with the GPU's rules ([`raster`]) and every
//! technique of the catalogue on std atomics, parallel with rayon.
//!
//! Each technique is written the way a GPU runs it: geometry passes whose per-fragment "shader"
//! updates per-pixel storage with atomic MIN, MAX, OR and ADD (the blend units, logic ops and
//! atomics of the papers), then a per-pixel resolve. Exact techniques give the same image whatever
//! the number of threads, since every update they make is order-independent.
//!
//! ```
//! use oit_core::{load_scene, Backend, Camera, Settings, Technique, View};
//! let scene = load_scene("planes:4").unwrap();
//! let settings = Settings { width: 64, height: 64, technique: Technique::Dp, ..Settings::default() };
//! let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
//! let frame = oit_cpu::CpuBackend::default().render(&scene, &camera, &settings).unwrap();
//! assert_eq!(frame.stats.lost, 0);
//! assert_eq!(frame.stats.geometry_passes, 5); // 4 layers + the pass that finds none left
//! ```
//!
//! A scene prepared once renders many frames; the second orbit of the same views allocates no
//! per-pixel storage (the example of docs/embedding.md):
//!
//! ```
//! use oit_core::{load_scene, Backend, Camera, Settings, Technique, View};
//! let scene = load_scene("knot").unwrap();
//! let backend = oit_cpu::CpuBackend::default();
//! let mut prepared = backend.prepare(&scene).unwrap();
//! let settings = Settings { width: 64, height: 64, technique: Technique::Fabs { k: None }, ..Settings::default() };
//! let mut orbit = |prepared: &mut Box<dyn oit_core::Prepared + '_>| {
//!     for step in 0..4 {
//!         let view = View { azimuth: 90.0 * step as f32, ..View::default() };
//!         let frame = prepared.frame(&Camera::orbit_scene(&scene, view, 1.0).unwrap(), &settings).unwrap();
//!         assert_eq!(frame.stats.lost, 0);
//!     }
//! };
//! orbit(&mut prepared);
//! let made = prepared.storage_allocations();
//! orbit(&mut prepared);
//! assert_eq!(prepared.storage_allocations(), made);
//! ```

/// The crate's README (what crates.io shows), whose example runs as a doc test with these.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod opaque;
mod pool;
pub mod raster;
mod resolve;
mod storage;
mod technique;

use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use oit_core::{
    Backend, Camera, Capabilities, Frame, OitError, Prepared, RasterPath, Scene, Settings, Technique,
    TechniqueKind,
};

pub use storage::{INSERTION_SORT_MAX, sort_keys};

use crate::pool::Pool;
use crate::raster::{RasterMode, Rasterizer};
use crate::technique::Ctx;

/// The CPU backend.
///
/// A backend keeps what the last prepared scene dropped (its triangles' setup storage, its
/// per-pixel arrays, its thread pool) for the next [`Backend::prepare`], so one-shot
/// [`Backend::render`]s in a loop reuse their storage as a prepared scene's frames do, rather
/// than asking the allocator for fresh pages every frame (whether it hands back warm memory
/// depends on its trimming heuristics, and on a 16-core host a 64² `adp` frame took about 2 or
/// about 4 ms by that alone). [`CpuBackend::release_storage`] frees it; dropping the backend
/// does too.
///
/// ```
/// use oit_core::{load_scene, Backend, Camera, Settings, View};
/// let scene = load_scene("planes:4").unwrap();
/// let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
/// let backend = oit_cpu::CpuBackend::with_threads(Some(2));
/// let settings = Settings { width: 32, height: 32, ..Settings::default() };
/// let first = backend.render(&scene, &camera, &settings).unwrap();
/// // the second render reuses the first one's storage (and its two threads)
/// let second = backend.render(&scene, &camera, &settings).unwrap();
/// assert_eq!(first.image, second.image);
/// backend.release_storage();
/// ```
#[derive(Clone, Debug, Default)]
pub struct CpuBackend {
    /// Rayon threads; `None` uses rayon's global pool.
    pub threads: Option<usize>,
    /// Rasterizer work split; `None` uses [`raster::DEFAULT_MODE`].
    pub mode: Option<RasterMode>,
    /// What the last dropped prepared scene left for the next one.
    kept: Kept,
}

/// The storage a dropped [`CpuPrepared`] hands back to its backend. A clone of the backend starts
/// with none (storage is never shared between two prepared scenes).
#[derive(Default)]
struct Kept(std::sync::Mutex<Option<Spare>>);

/// What a prepared scene owns between frames, apart from its scene.
struct Spare {
    pool: Pool,
    raster: Option<Rasterizer>,
    threads: Option<rayon::ThreadPool>,
}

impl Clone for Kept {
    fn clone(&self) -> Self {
        Kept::default()
    }
}

impl std::fmt::Debug for Kept {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let holds = self.0.lock().is_ok_and(|k| k.is_some());
        f.debug_struct("Kept").field("holds_storage", &holds).finish()
    }
}

impl CpuBackend {
    /// A backend on `threads` rayon threads of its own (`None`: rayon's global pool). The
    /// fields stay public to read and change; a backend is made here or by `Default` (it also
    /// holds storage, see [`CpuBackend`]).
    pub fn with_threads(threads: Option<usize>) -> CpuBackend {
        CpuBackend { threads, ..CpuBackend::default() }
    }

    /// Geometry passes the opaque pass runs for `scene` in each frame (of each screen tile):
    /// none where the scene has no opaque or masked part; two (depth, then the winners'
    /// colours, as the plan's schedule and the GPU paths) in general; one where a masked object
    /// is textured, whose depth test shades every fragment ahead in lanes to read its alpha and
    /// so keeps the winners' colours as it goes (a second pass would shade them all again).
    pub fn opaque_passes(scene: &Scene) -> u32 {
        scene.layers(None).opaque.map_or(0, |o| if opaque::fuses(&o) { 1 } else { 2 })
    }

    /// Frees the storage kept from the last dropped prepared scene (see [`CpuBackend`]).
    pub fn release_storage(&self) {
        if let Ok(mut kept) = self.kept.0.lock() {
            kept.take();
        }
    }

    /// The rayon pool of `threads` (none: rayon's global pool): `kept` where it has as many
    /// threads, else a new one.
    fn thread_pool(&self, kept: Option<rayon::ThreadPool>) -> Result<Option<rayon::ThreadPool>, OitError> {
        self.threads
            .map(|n| {
                oit_core::check_threads(n)?;
                if let Some(pool) = kept.filter(|p| p.current_num_threads() == n) {
                    return Ok(pool);
                }
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| OitError::Device(format!("cannot start {n} rayon threads: {e}")))
            })
            .transpose()
    }
}

/// A scene prepared on the CPU backend: checked once, with its thread pool and the per-pixel
/// storage of earlier frames kept for the next ones.
pub struct CpuPrepared<'s> {
    backend: &'s CpuBackend,
    scene: &'s Scene,
    /// The scene split for its frames: its opaque part, drawn first, and the transparent part the
    /// technique captures ([`Scene::layers`]), made once per alpha override.
    layers: oit_core::LayersCache<'s>,
    threads: Option<rayon::ThreadPool>,
    pool: Pool,
    /// The scene's [`Scene::absorption_per_length`], from the bounds its validation found.
    per_length: f64,
    /// The last frame's rasterizer, set up again for the next ([`Rasterizer::rebuild`]) so
    /// steady frames reuse its storage.
    raster: std::sync::Mutex<Option<Rasterizer>>,
    /// The last frame's opaque image, whose storage the next frame's opaque pass draws into
    /// ([`opaque::draw_reusing`]).
    opaque: std::sync::Mutex<Option<opaque::OpaqueImage>>,
}

impl<'s> CpuPrepared<'s> {
    /// The scene's layers for `settings`' alpha override, made the first time it is asked for.
    fn layers(&self, settings: &Settings) -> std::sync::Arc<oit_core::Layers<'s>> {
        self.layers.get(self.scene, settings.alpha)
    }

    fn frame_inner(&self, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        settings.validate()?;
        if !(camera.view_proj().is_finite()) {
            return Err(OitError::InvalidSettings("camera matrices are not finite".into()));
        }
        let plan = oit_core::plan::Plan::new("cpu", self.scene, settings)?.on_path(RasterPath::Cpu);
        let plan_opaque_bytes = plan.opaque_bytes();
        plan.refuse_image_atomics("cpu")?;
        plan.refuse_interlock("cpu", "the CPU's rasterizer has no fragment stage to interlock")?;
        // the whole frame's storage and outputs against the host's memory, before anything is
        // allocated (sizes from a counting pass are checked again as they are allocated)
        let budget = cpu_budget(settings, &plan);
        if settings.region.is_some() {
            // a window of a tiled frame: the last window's outputs and temporaries, freed, go
            // back to the system before this one allocates (pool::trim)
            pool::trim();
        }
        // the pool keeps arrays of earlier frames and tiles only while all it holds fits the
        // frame's storage: within the budget, less the outputs, which are not the pool's
        self.pool.set_cap(budget.1.saturating_sub(plan.output_bytes(settings.pixel_count() as u64)));
        let pixels = settings.pixel_count() as u64;
        let needed = plan.frame_bytes(pixels, oit_core::plan::Counted::default());
        oit_core::plan::check_total(
            &format!("{} storage and outputs of a frame of {pixels} pixels", plan.technique),
            needed.saturating_add(pixels.saturating_mul(state_array_extra(settings))),
            (&budget.0, budget.1),
        )?;
        let start = Instant::now();
        // the lock is never contended (frames run one at a time); a poisoned one (a panic in an
        // earlier frame) only loses the storage
        let layers = self.layers(settings);
        let drawn = layers.settings(settings);
        let scene: &Scene = &layers.transparent;
        let kept = self.raster.lock().ok().and_then(|mut r| r.take());
        let mut raster = match kept {
            Some(mut r) => {
                r.rebuild(scene, camera, &drawn);
                r
            }
            None => Rasterizer::new(scene, camera, &drawn),
        };
        if let Some(mode) = self.backend.mode.filter(|&m| m != raster.mode()) {
            raster = raster.with_mode(mode);
        }
        // opaque first: its depth holds back the transparent fragments behind it (the
        // supersampled reference draws it in each of its frames, under each frame's camera)
        let supersampled = oit_core::msaa::is_supersampled(settings);
        let opaque = match &layers.opaque {
            Some(o) if !supersampled => {
                let kept = self.opaque.lock().ok().and_then(|mut k| k.take());
                Some(opaque::draw_reusing(o, camera, &drawn, kept))
            }
            _ => None,
        };
        raster.cut_at(opaque.as_ref().map(|o| o.depth.clone()));
        // above one sample, a technique that keeps no mask walks the multisampled fragments
        raster.cover(technique::covered(&drawn));
        let mut ctx =
            Ctx::new(scene, camera, &drawn, &raster, &self.pool, plan, self.per_length, opaque.as_ref());
        if supersampled {
            ctx.opaque_part = layers.opaque.as_ref();
        }
        let frame = technique::render(&mut ctx, settings.technique);
        drop(ctx);
        let occluded = raster.occluded().unwrap_or_else(|| {
            // no pass ran behind the cut (nothing to capture): one counts it
            if settings.samples > 1 {
                raster.for_each_masked_fragment(settings.samples, |_, _| {});
            } else {
                raster.for_each_fragment(|_| {});
            }
            raster.occluded().unwrap_or(0)
        });
        raster.cut_at(None);
        raster.cover(None);
        if let Ok(mut kept) = self.raster.lock() {
            *kept = Some(raster);
        }
        let mut frame = frame?;
        if let Some(o) = &opaque {
            let pixels = settings.pixel_count() as u64;
            frame.stats.occluded = occluded;
            frame.stats.opaque_fragments = o.fragments;
            frame.stats.masked = o.masked;
            frame.stats.geometry_passes += o.passes;
            frame.stats.storage_bytes += pixels * plan_opaque_bytes;
        }
        if let (Some(o), Ok(mut kept)) = (opaque, self.opaque.lock()) {
            *kept = Some(o);
        }
        frame.stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        // every fragment composited, merged, counted lost or held back, as on the GPUs: a
        // fragment a technique drops without a count is an error, never a frame
        frame.stats.check_accounting("cpu")?;
        Ok(frame)
    }
}

/// Bytes a pixel's resolve state takes on the CPU beyond the plan's
/// ([`oit_core::plan::RESOLVE_STATE_BYTES`], the GPU's 23 words), where the technique keeps an
/// array of states ([`Ctx::states`](crate::technique::Ctx::states)) and not only a state in each
/// resolving thread's locals: the CPU's state is a struct of floats and a stack
/// ([`resolve::PixelState`]), larger. Counted in the frame's budget beside
/// [`oit_core::plan::Plan::frame_bytes`], not in `Stats::storage_bytes`;
/// `the_state_array_is_counted_where_one_is_lent` holds the list to the techniques that lend one.
pub(crate) fn state_array_extra(settings: &Settings) -> u64 {
    let extra = (std::mem::size_of::<resolve::PixelState>() as u64)
        .saturating_sub(oit_core::plan::RESOLVE_STATE_BYTES);
    let weighted = settings.technique.sums().is_some();
    let lends = match settings.technique {
        Technique::Reference
        | Technique::Plain
        | Technique::Fabs { .. }
        | Technique::Kbuf { .. }
        | Technique::Dfb
        | Technique::Ll
        | Technique::Mdts { .. }
        | Technique::Mdts64 { .. } => false,
        // the colour mode's buckets are read into states; the depth mode's passes feed the
        // resolve pixel by pixel
        Technique::Bdp { passes } => settings.bdp_color_mode(passes).unwrap_or(true),
        // their sums resolve in place, but for the heat map, whose counts go into states
        _ if weighted => settings.effect == oit_core::Effect::Complexity,
        _ => true,
    };
    if lends { extra } else { 0 }
}

/// The budget of a CPU frame's storage and outputs ([`oit_core::plan::Plan::frame_bytes`]):
/// [`oit_core::tiling::host_budget`], the one [`oit_core::tiling::forecast`] foresees it by.
pub(crate) fn cpu_budget(settings: &Settings, plan: &oit_core::plan::Plan) -> (String, u64) {
    oit_core::tiling::host_budget(settings, plan)
}

impl Drop for CpuPrepared<'_> {
    /// Hands the storage back to the backend for its next prepared scene.
    fn drop(&mut self) {
        let spare = Spare {
            pool: std::mem::take(&mut self.pool),
            raster: self.raster.get_mut().ok().and_then(Option::take),
            threads: self.threads.take(),
        };
        if let Ok(mut kept) = self.backend.kept.0.lock() {
            *kept = Some(spare);
        }
    }
}

impl Prepared for CpuPrepared<'_> {
    /// One frame, in screen tiles where its storage does not fit the budget
    /// ([`oit_core::tiling`]).
    fn frame(&mut self, camera: &Camera, settings: &Settings) -> Result<Frame, OitError> {
        let this = &*self;
        let extra = state_array_extra(settings);
        let run = || {
            oit_core::tiling::run_with("cpu", this.scene, settings, extra, |s| this.frame_inner(camera, s))
        };
        match &self.threads {
            // The whole frame on one of the global pool's threads, as `install` runs it on a
            // pool of its own: called from outside a pool, each of a frame's parallel steps
            // (setup, passes, resolve) would otherwise be handed over to the pool and waited for
            // on a lock, a sleep and a wake-up of the calling thread apiece.
            None if rayon::current_thread_index().is_none() => rayon::scope(|_| run()),
            None => run(),
            Some(pool) => pool.install(run),
        }
    }

    fn storage_allocations(&self) -> u64 {
        self.pool.allocations()
    }
}

impl Backend for CpuBackend {
    fn name(&self) -> &str {
        "cpu"
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            device: format!("CPU, {} rayon threads", self.threads.unwrap_or_else(rayon::current_num_threads)),
            // no fragment stage: nothing that needs an interlock
            techniques: TechniqueKind::ALL.into_iter().filter(|t| !t.needs_interlock()).collect(),
            raster_paths: vec![RasterPath::Cpu],
            limits: vec![("max image side".into(), oit_core::MAX_SIZE.to_string())],
        }
    }

    fn frame_extra_bytes(&self, settings: &Settings) -> u64 {
        state_array_extra(settings)
    }

    fn prepare<'s>(&'s self, scene: &'s Scene) -> Result<Box<dyn Prepared + 's>, OitError> {
        let bounds = scene.validated_bounds()?;
        let spare = self.kept.0.lock().ok().and_then(|mut k| k.take());
        let (pool, raster, threads) = match spare {
            Some(Spare { pool, raster, threads }) => (pool, raster, threads),
            None => (Pool::default(), None, None),
        };
        Ok(Box::new(CpuPrepared {
            backend: self,
            scene,
            layers: oit_core::LayersCache::default(),
            threads: self.thread_pool(threads)?,
            pool,
            per_length: scene.absorption_per_length_in(&bounds),
            raster: std::sync::Mutex::new(raster),
            opaque: std::sync::Mutex::default(),
        }))
    }

    /// Wall time of one [`Rasterizer::for_each_fragment`] pass that adds 1 to an atomic per-pixel
    /// counter per fragment; each fragment's depth, primitive id and shaded colour are made (what
    /// a capture pass of the transparency effect reads; `black_box`, or the compiler would drop
    /// the interpolation and shading nothing reads). The setup, the tile binning included,
    /// is per frame and not counted; the pass runs twice and the second is timed.
    fn plain_pass_ms(&self, scene: &Scene, camera: &Camera, settings: &Settings) -> Result<f64, OitError> {
        settings.validate()?;
        scene.validate()?;
        let time = || {
            let mut raster = Rasterizer::new(scene, camera, settings);
            if let Some(mode) = self.mode {
                raster = raster.with_mode(mode);
            }
            let counts: Vec<AtomicU32> = (0..settings.pixel_count()).map(|_| AtomicU32::new(0)).collect();
            let pass = || {
                raster.for_each_shaded_fragment(|f| {
                    std::hint::black_box((f.depth, f.prim, f.color()));
                    counts[f.pixel as usize].fetch_add(1, Ordering::Relaxed);
                })
            };
            pass();
            let start = Instant::now();
            std::hint::black_box(pass());
            start.elapsed().as_secs_f64() * 1e3
        };
        match self.threads {
            None => Ok(time()),
            Some(_) => Ok(self.thread_pool(None)?.expect("threads are set").install(time)),
        }
    }
}

#[cfg(test)]
mod tests {
    use oit_core::{Backend, Camera, Effect, Settings, Technique, View, load_scene};

    /// The techniques [`crate::state_array_extra`] counts a resolve-state array for are those
    /// that lend one, under every effect: a technique that lends one uncounted would hold more
    /// than its budget says. Fails when a technique is moved in or out of its list (`dp` counted as
    /// a technique that resolves in its threads' locals, or `fabs` as one with an array).
    #[test]
    fn the_state_array_is_counted_where_one_is_lent() {
        let scene = load_scene("planes:4").unwrap();
        let mut checked = 0;
        for technique in [Technique::Reference].into_iter().chain(Technique::all()) {
            for effect in [Effect::Transparency, Effect::Translucency, Effect::Fresnel, Effect::Complexity] {
                let s = Settings { width: 16, height: 16, technique, effect, ..Settings::default() };
                let Ok(plan) = oit_core::plan::Plan::new("cpu", &scene, &s) else { continue };
                let plan = plan.on_path(oit_core::RasterPath::Cpu);
                let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
                let raster = crate::Rasterizer::new(&scene, &camera, &s);
                let pool = crate::Pool::default();
                let per_length = scene.absorption_per_length();
                let mut ctx = crate::Ctx::new(&scene, &camera, &s, &raster, &pool, plan, per_length, None);
                let Ok(frame) = crate::technique::render(&mut ctx, technique) else { continue };
                drop(ctx);
                assert!(frame.stats.fragments > 0, "{technique} {effect:?}");
                let lent = pool.states_lent() > 0;
                assert_eq!(
                    lent,
                    crate::state_array_extra(&s) > 0,
                    "{technique} {effect:?}: lends states: {lent}"
                );
                checked += 1;
            }
        }
        assert!(checked > 40, "{checked} cases");
        assert!(crate::state_array_extra(&Settings { technique: Technique::Dp, ..Settings::default() }) > 0);
    }

    /// A dropped prepared scene leaves its storage to the backend's next one: the next prepared
    /// scene starts with the arrays made so far and its frame makes none; a one-shot render in
    /// between (another scene) takes and returns it; `release_storage` frees it, so a prepared
    /// scene starts from nothing again. Mutations caught: storage not handed back on drop (the
    /// second scene starts at 0), not taken by `prepare`, not freed by `release_storage`.
    #[test]
    fn a_dropped_scene_leaves_its_storage_to_the_next() {
        let (knot, planes) = (load_scene("knot").unwrap(), load_scene("planes:4").unwrap());
        let camera = |scene| Camera::orbit_scene(scene, View::default(), 1.0).unwrap();
        let s = Settings { width: 40, height: 32, technique: Technique::Adp, ..Settings::default() };
        let backend = crate::CpuBackend::with_threads(Some(2));
        let mut first = backend.prepare(&knot).unwrap();
        assert_eq!(first.storage_allocations(), 0);
        let a = first.frame(&camera(&knot), &s).unwrap();
        let made = first.storage_allocations();
        assert!(made > 0);
        drop(first);
        let other = backend.render(&planes, &camera(&planes), &s).unwrap();
        assert!(other.stats.fragments > 0);
        let mut second = backend.prepare(&knot).unwrap();
        let kept = second.storage_allocations();
        assert!(kept >= made, "{kept} arrays kept, {made} made by the first scene");
        let mut b = second.frame(&camera(&knot), &s).unwrap();
        assert_eq!(second.storage_allocations(), kept, "the kept storage served the frame");
        b.stats.wall_ms = a.stats.wall_ms;
        assert_eq!(a, b);
        drop(second);
        backend.release_storage();
        assert_eq!(backend.prepare(&knot).unwrap().storage_allocations(), 0);
    }

    /// The storage a prepared scene keeps between frames (its rasterizer, the resolve states the
    /// resolve hands back reset, bdp:P's buckets its resolve empties, the scratch arrays) changes
    /// nothing: under every effect, frames of two views in turn equal one-shot renders bit for
    /// bit, stats included, for every technique and the reference. Each one-shot render comes
    /// from a backend of its own, so it shares no storage with the prepared scene nor with the
    /// other one-shot renders (`tests/tests/prepared.rs` renders both through one backend,
    /// whose one-shot renders reuse each other's storage: a frame that read stale storage would
    /// read the same there). Mutations caught: a state left as its last frame left it (the
    /// complexity sweep not resetting, a peel's back layers kept), a bdp bucket pair's max not
    /// emptied by the resolve, a rasterizer not set up again for the new view.
    #[test]
    fn kept_storage_changes_no_frame() {
        // the knot, and 40 planes for the storage only a deep pixel fills (adp's second batch,
        // whose count a histogram left set by the last view would change)
        for name in ["knot", "planes:40"] {
            kept_storage_changes_no_frame_of(name);
        }
    }

    fn kept_storage_changes_no_frame_of(name: &str) {
        let scene = load_scene(name).unwrap();
        let views: Vec<Camera> = [0.0, 70.0]
            .into_iter()
            .map(|azimuth| Camera::orbit_scene(&scene, View { azimuth, ..View::default() }, 1.0).unwrap())
            .collect();
        let backend = crate::CpuBackend::default();
        let techniques: Vec<Technique> = [Technique::Reference]
            .into_iter()
            .chain(Technique::all())
            .chain([Technique::Bdp { passes: 3 }])
            .collect();
        let mut compared = 0;
        for effect in [Effect::Transparency, Effect::Translucency, Effect::Fresnel, Effect::Complexity] {
            for &technique in &techniques {
                let s = Settings { width: 48, height: 40, technique, effect, ..Settings::default() };
                let mut prepared = backend.prepare(&scene).unwrap();
                for camera in views.iter().chain(&views) {
                    let one_shot = crate::CpuBackend::default().render(&scene, camera, &s);
                    let kept = prepared.frame(camera, &s);
                    match (one_shot, kept) {
                        (Ok(mut a), Ok(mut b)) => {
                            a.stats.wall_ms = 0.0;
                            b.stats.wall_ms = 0.0;
                            assert!(a.stats.fragments > 0);
                            assert_eq!(a, b, "{name}: {technique} {effect:?}");
                            compared += 1;
                        }
                        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                        (a, b) => {
                            panic!("{name}: {technique} {effect:?}: {:?} against {:?}", a.err(), b.err())
                        }
                    }
                }
            }
        }
        // 57 of the 64 technique × effect pairs run (the others are refused by both), 4 frames each
        assert!(compared >= 4 * 57, "{name}: {compared} frames compared");
    }
}
