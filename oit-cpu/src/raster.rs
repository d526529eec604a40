//! The software rasterizer's traversal: the triangles oit-core's [`TriangleSetup`] made, turned
//! into fragments.
//!
//! Contract:
//! - [`Rasterizer::new`] does the per-frame setup once ([`TriangleSetup::new`]: vertex transform,
//!   clipping, snapping; the rules are oit-core's, shared with the GPU backends);
//!   [`Rasterizer::for_each_fragment`] is then one geometry pass, run as often as a technique
//!   needs, calling its closure exactly once per covered (pixel, triangle) pair, from several
//!   threads.
//! - Every [`Fragment`] depends only on its triangle and its pixel, so the set of fragments is the
//!   same whatever the [`RasterMode`] and the number of rayon threads; only the order of the calls
//!   varies.
//!
//! How: [`RasterMode::Scatter`] (the default, [`DEFAULT_MODE`]) runs the set-up triangles in
//! parallel chunks in primitive order. [`RasterMode::Tiled`] bins the triangles into
//! [`TILE_SIZE`]-pixel tiles once per frame, with the setup, and runs the tiles in parallel, each
//! on one thread (so a pixel's fragments all come from one thread, and a pass's per-pixel storage
//! is touched tile by tile, not all over the frame). In both, a triangle at most 64 pixels across
//! is walked eight pixels of a row at a time in 32-bit lanes (`walk_small`, its edge functions set
//! up once per frame), a larger one by the span walk, which visits row by row the exact span of covered pixels
//! ([`oit_core::setup::covers`]), found by integer division of the edge functions. Both walks are
//! tested against the per-pixel rule and against each other. Scatter's shaded pass runs in AVX2
//! where the host has it (`avx2`, picked at run time: the build targets SSE2), a small triangle's
//! box tested eight pixels at once in two, four or eight columns and its covered pixels packed by
//! one permutation; its fragments are the portable pass's, bit for bit, in the same order within
//! a task.
//!
//! [`Rasterizer::for_each_fragment_in_order`] is the pass that keeps order: the image cut into
//! bands of rows, one rayon task a band, each walking the triangles that reach into its band
//! highest primitive first (the same walks, in AVX2 where the host has it, cut to the band's
//! rows), so that each pixel's fragments come from one thread in reverse submission order:
//! `plain` composites them as they come, with no storage but a running colour and no sort.
//!
//! A pass reads one compact record per triangle (its edge functions, its [`DepthPlane`] and its
//! primitive id): depth and id are all a [`Fragment`] holds at once; colour and normal are
//! interpolated from the full [`Triangle`] only when a shader asks ([`Fragment::color`],
//! [`Fragment::normal`]), so a counting pass or a peel's depth test never shades.

use std::sync::OnceLock;

use glam::{Vec3, Vec4};
use oit_core::setup::{
    DepthPlane, HALF_PIXEL, SHADE_LANES, SUBPIXEL, SetupScratch, ShadeRecord, Triangle, TriangleSetup, edge,
    headlight_colors, normal_at,
};
use oit_core::{Camera, Scene, Settings, Shading};
use rayon::prelude::*;
use wide::i32x8;

pub use oit_core::setup::{GUARD_BAND, SUBPIXEL_BITS, TRIANGLE_WORDS};

/// One covered (pixel, triangle) pair as a technique's shader sees it: where it is, its depth and
/// primitive id at once, its colour and normal on demand ([`Fragment::color`],
/// [`Fragment::normal`]). Interpolation and shading are most of a geometry pass, and many passes
/// read neither (a counting pass, a peel that the fragment's depth alone rules out), so they are
/// computed only where a shader asks. Every value is [`TriangleSetup::fragment`]'s, bit for bit:
/// the same functions of oit-core compute it.
#[derive(Clone, Copy)]
pub struct Fragment<'a> {
    /// `y·width + x`, row `y = 0` at the top.
    pub pixel: u32,
    /// NDC z in [0, 1].
    pub depth: f32,
    /// Primitive id: `scene.primitive_bases().0[instance] + triangle index`.
    pub prim: u32,
    /// Screen-space barycentrics ([`oit_core::setup::barycentrics`]).
    b: [f32; 3],
    t: &'a Triangle,
    setup: &'a TriangleSetup,
    /// The colour, where the pass made it ahead ([`Shade::Color`]).
    color: Option<Vec4>,
}

/// When a pass makes its fragments' colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shade {
    /// Where the shader asks ([`Fragment::color`]): a pass that reads few colours (a peel that
    /// the depth alone rules out, a counting pass) shades few fragments.
    OnDemand,
    /// Every fragment's, before the shader sees it, several at once ([`RasterMode::Scatter`];
    /// [`RasterMode::Tiled`] shades on demand).
    Color,
}

/// Covered pixels a [`RasterMode::Scatter`] task gathers before it shades and hands them on.
const BATCH: usize = 64;

#[cfg(target_arch = "x86_64")]
mod avx2;

/// Which code runs [`RasterMode::Scatter`]'s shaded pass: the same fragments either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kernel {
    /// The build's own instructions (SSE2 on x86-64).
    Portable,
    /// AVX2 (with `popcnt`), where the host has it.
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Kernel {
    /// The fastest the host runs.
    fn detect() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("popcnt") {
            return Kernel::Avx2;
        }
        Kernel::Portable
    }
}

/// A task's triangles: the frame's triangles, their traversal and their shading records.
type Records<'a> = (&'a [Triangle], &'a [SmallEdges], &'a [ShadeRecord]);

/// `avx2::scatter_task` over the triangles of `order` in the rows `rows` (shading them where
/// `SHADE`), behind the early cut and the tile skip where given, where `kernel` is
/// [`Kernel::Avx2`]; `None` elsewhere.
#[cfg(target_arch = "x86_64")]
#[expect(clippy::too_many_arguments, reason = "the walk's inputs, passed through to the AVX2 task")]
fn avx2_task<const SHADE: bool, F: Fn(&Fragment<'_>)>(
    kernel: Kernel,
    setup: &TriangleSetup,
    records: Records<'_>,
    order: impl Iterator<Item = usize>,
    rows: [u32; 2],
    f: &F,
    ahead: Ahead<'_>,
    (cut, skip): (Option<EarlyCut<'_>>, Option<TileSkip<'_>>),
) -> Option<u64> {
    if kernel != Kernel::Avx2 {
        return None;
    }
    #[expect(unsafe_code, reason = "the one call into code compiled for AVX2")]
    // SAFETY: `Kernel::Avx2` is made only where the host has AVX2 and popcnt (`Kernel::detect`),
    // all that `scatter_task` is compiled to need
    let n = unsafe { avx2::scatter_task::<SHADE, F>(setup, records, order, rows, f, ahead, cut, skip) };
    Some(n)
}

/// A pass's request to fetch a pixel's storage from memory a few fragments before the
/// fragment reaches its capture ([`Rasterizer::for_each_shaded_fragment_ahead`]).
pub(crate) type Ahead<'a> = Option<&'a (dyn Fn(u32) + Sync)>;

/// Fragments between a pixel's [`Ahead`] request and its fragment's capture: enough for a
/// few memory accesses to be in flight together.
const AHEAD: usize = 8;

/// Triangles ahead of the walk whose traversal records the banded pass asks for from memory
/// ([`Rasterizer::for_each_fragment_in_order`]).
const PREFETCH: usize = 16;

/// Asks for the cache lines of `record` ahead of their use (nothing where the target has no
/// prefetch instruction).
#[inline(always)]
pub(crate) fn prefetch<T: ?Sized>(record: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p = std::ptr::from_ref(record).cast::<i8>();
        #[expect(unsafe_code, reason = "a prefetch hint")]
        // SAFETY: every x86-64 has SSE, all `_mm_prefetch` needs; a prefetch is a hint that
        // neither reads into the program nor faults, whatever the address (`wrapping_add`: the
        // record's last byte, in the same allocation)
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            // a record may end in the next line
            _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(size_of_val(record).saturating_sub(1)));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = record;
}

/// The part of the pixel box `bbox` in the rows `rows` (inclusive; empty where they miss it).
#[inline]
fn in_rows([x0, y0, x1, y1]: [u32; 4], rows: [u32; 2]) -> [u32; 4] {
    [x0, y0.max(rows[0]), x1, y1.min(rows[1])]
}

/// Each of `samples` samples' offset from the pixel's centre, in 1/256 pixel.
fn sample_offsets(samples: u32) -> Vec<(i64, i64)> {
    use oit_core::setup::{HALF_PIXEL, subpixel_offsets};
    subpixel_offsets(samples).map(|(x, y)| (x - HALF_PIXEL, y - HALF_PIXEL)).collect()
}

/// Every row: a Scatter task walks its triangles' whole boxes.
const ALL_ROWS: [u32; 2] = [0, u32::MAX];

/// A covered pixel waiting in a batch: the task's triangle, the pixel, the edge functions.
#[derive(Clone, Copy, Default)]
struct Candidate {
    tri: u32,
    pixel: u32,
    e: [i64; 3],
}

impl Fragment<'_> {
    /// Shaded colour, straight-alpha linear RGBA ([`TriangleSetup::color_at`]).
    #[inline]
    pub fn color(&self) -> Vec4 {
        self.color.unwrap_or_else(|| self.setup.color_at(self.t, self.b))
    }

    /// Shaded alpha, [`Fragment::color`]'s, the same bits; from the colour where the pass made
    /// it, else without shading ([`TriangleSetup::alpha_at`]).
    #[inline]
    pub fn alpha(&self) -> f32 {
        self.color.map_or_else(|| self.setup.alpha_at(self.t, self.b), |c| c.w)
    }

    /// The alpha below which the opaque pass discards it ([`Triangle::cutoff`]).
    #[inline]
    pub fn cutoff(&self) -> f32 {
        self.t.cutoff
    }

    /// Interpolated world-space normal, normalized, zero where the mesh has none ([`normal_at`]).
    #[inline]
    pub fn normal(&self) -> Vec3 {
        normal_at(self.t, self.b)
    }

    /// Every value at once, as [`TriangleSetup::fragment`] makes it.
    pub fn full(&self) -> oit_core::setup::Fragment {
        oit_core::setup::Fragment {
            pixel: self.pixel,
            depth: self.depth,
            prim: self.prim,
            color: self.color(),
            normal: self.normal(),
        }
    }
}

/// A triangle's traversal and headlight-shading records, made together (one read of it).
fn records_of(t: &Triangle) -> (SmallEdges, ShadeRecord) {
    (SmallEdges::new(t), ShadeRecord::new(t))
}

/// Side of a screen tile of [`RasterMode::Tiled`], in pixels.
pub const TILE_SIZE: u32 = 32;
/// Triangles per task of [`RasterMode::Scatter`], at most: a scene of fewer than
/// [`SCATTER_TASKS_PER_THREAD`] × 64 triangles a thread is cut finer ([`scatter_chunk`]).
const SCATTER_CHUNK: usize = 64;
/// Tasks a thread gets at least in [`RasterMode::Scatter`] where the triangles allow.
const SCATTER_TASKS_PER_THREAD: usize = 4;

/// Triangles per Scatter task for `triangles` triangles over `threads` threads: 64, or fewer when
/// that would leave threads idle. A scene of a few large triangles (`planes:8`: 16 triangles)
/// was one task of 64, so one thread walked every fragment of the frame; now each thread gets
/// about four tasks. The fragments are the same (each task walks whole triangles).
fn scatter_chunk(triangles: usize, threads: usize) -> usize {
    triangles.div_ceil(threads.max(1) * SCATTER_TASKS_PER_THREAD).clamp(1, SCATTER_CHUNK)
}

/// How a geometry pass spreads its work over threads. Both give the same fragments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RasterMode {
    /// Parallel over chunks of triangles; each walks its bounding box clamped to the viewport.
    Scatter,
    /// Triangles binned into screen tiles; parallel over tiles, each tile runs its triangles in
    /// a fixed order (by the tile their box starts in, then primitive order), so a pixel's
    /// fragments arrive from one thread, in the same order every pass.
    Tiled,
}

/// The mode [`Rasterizer::new`] starts in: [`RasterMode::Scatter`].
///
/// Measured side by side on a 2-core host shared with other jobs (`cargo bench -p oit-cpu
/// --bench raster`, 2 rayon threads, criterion's median, runs alternated; figures in
/// `bench/results/cpu/issue12/`): on the bunny at 512² the two modes' passes are within noise of
/// each other (colour 7.5–8.5 ms against 8.4–9.0 ms, depth only 2.9–4.0 ms against 2.5–3.7 ms),
/// on `planes:64` Tiled's colour pass is slower (269 ms against 155 ms: its large triangles are
/// walked tile by tile by the span walk), and Tiled adds the binning, serial, to each frame's
/// setup (the bench's bunny `setup` with the bins: 16.1–16.8 ms). At two threads Tiled does not
/// pay; re-measure on a many-core host, where one thread per pixel (no contended cache lines)
/// may.
pub const DEFAULT_MODE: RasterMode = RasterMode::Scatter;

/// The triangles in tile order, and the tiles' lists of them, compressed: tile `t` holds
/// sorted triangle `i` for `i` in `tris[start[t]..start[t + 1]]`.
struct Bins {
    tiles_x: u32,
    /// The set-up triangles' indices sorted by the tile of their box's top-left pixel
    /// (row-major), stably.
    order: Vec<u32>,
    /// [`SmallEdges`] of each of the sorted triangles: what a pass reads of every triangle it
    /// walks, so each tile's list reads them from a few runs of memory rather than from all over
    /// the frame's (a mesh's primitive order is seldom its order on screen). The triangles
    /// themselves are read (through `order`) only for a colour or a normal.
    edges: Vec<SmallEdges>,
    start: Vec<u32>,
    tris: Vec<u32>,
}

/// [`Rasterizer::for_each_fragment_in_order`]'s bands: rows of the image, `rows` apiece, and the
/// triangles whose boxes reach into each, in primitive order: band `b` holds triangle
/// `tris[i]` for `i` in `start[b]..start[b + 1]`. Kept from frame to frame (made again into the
/// same storage), so a steady frame allocates nothing for them.
#[derive(Default)]
struct Bands {
    rows: u32,
    /// In `usize`: a scene of many large triangles lists more (triangle, band) pairs than a
    /// `u32` counts (70M triangles across 64 bands), and a wrapped count would drop fragments in
    /// silence.
    start: Vec<usize>,
    tris: Vec<u32>,
    /// The per-run counts the parallel binning adds up (kept with the rest).
    counts: Vec<usize>,
}

/// Rows of a band: the image cut into about eight bands a thread (rayon balances them), each a
/// multiple of 8 rows (the AVX2 walk's tallest group of lanes) from 8 to 64.
fn band_rows(height: u32, threads: usize) -> u32 {
    let bands = u32::try_from(threads.max(1) * 8).unwrap_or(u32::MAX);
    height.div_ceil(bands).next_multiple_of(8).clamp(8, 64)
}

impl Bands {
    /// The bands of the triangles whose traversal records are `edges`, for an image `height`
    /// rows tall, made in place: each of `threads` runs of triangles counts its triangles per
    /// band, the counts become each run's first slot per band, and the runs write their
    /// triangles there, so every band lists its triangles in primitive order.
    fn make(&mut self, edges: &[SmallEdges], height: u32, threads: usize) {
        let rows = band_rows(height, threads);
        let bands = height.div_ceil(rows) as usize;
        let run = edges.len().div_ceil(threads.max(1)).max(1);
        let runs = edges.len().div_ceil(run);
        // (a box past the last row, which setup never makes, is cut to the last band)
        let last = bands.saturating_sub(1);
        let span = |s: &SmallEdges| {
            ((s.bbox[1] / rows) as usize).min(last)..=((s.bbox[3] / rows) as usize).min(last)
        };
        self.rows = rows;
        self.counts.clear();
        self.counts.resize(runs * bands, 0);
        self.counts.par_chunks_mut(bands).zip(edges.par_chunks(run)).for_each(|(counts, edges)| {
            for s in edges {
                for b in span(s) {
                    counts[b] += 1;
                }
            }
        });
        // band-major: band b's slots hold run 0's triangles of it, then run 1's, ...
        self.start.clear();
        self.start.resize(bands + 1, 0);
        let mut total = 0usize;
        for b in 0..bands {
            self.start[b] = total;
            for r in 0..runs {
                let n = self.counts[r * bands + b];
                self.counts[r * bands + b] = total;
                total += n;
            }
        }
        self.start[bands] = total;
        self.tris.clear();
        self.tris.resize(total, 0);
        // each run's slots, band by band: disjoint parts of `tris`, cut in slot order
        let mut parts: Vec<Vec<&mut [u32]>> = (0..runs).map(|_| Vec::with_capacity(bands)).collect();
        let mut rest = &mut self.tris[..];
        for b in 0..bands {
            for (r, part) in parts.iter_mut().enumerate() {
                let end = if r + 1 < runs { self.counts[(r + 1) * bands + b] } else { self.start[b + 1] };
                let (slots, tail) = std::mem::take(&mut rest).split_at_mut(end - self.counts[r * bands + b]);
                part.push(slots);
                rest = tail;
            }
        }
        parts.into_par_iter().zip(edges.par_chunks(run)).enumerate().for_each(|(r, (mut slots, edges))| {
            let mut filled = vec![0usize; bands];
            for (j, s) in edges.iter().enumerate() {
                for b in span(s) {
                    slots[b][filled[b]] = (r * run + j) as u32;
                    filled[b] += 1;
                }
            }
        });
    }

    /// Band `b`'s rows (inclusive) and its triangles' indices.
    fn band(&self, b: usize, height: u32) -> ([u32; 2], &[u32]) {
        let first = b as u32 * self.rows;
        let rows = [first, (first + self.rows - 1).min(height.saturating_sub(1))];
        (rows, &self.tris[self.start[b]..self.start[b + 1]])
    }
}

/// Runs `$pass` with `$g` bound to the pass's shader: `$f` itself, or, where the rasterizer has a
/// cut ([`Rasterizer::cut_at`]), `$f` behind the opaque depth test, counting what it holds back
/// where this is the first pass after the cut. Where the pass walks the multisampled fragments
/// ([`Rasterizer::cover`]) the cut is a sample's, made by the walk itself
/// ([`Rasterizer::task`]): `$f` is not wrapped, the pass only counts. A macro, not a function
/// taking the pass as a closure, so that each shader stays a concrete type the walks inline (a
/// `dyn` call a fragment costs every pass, cut or not).
macro_rules! behind_cut {
    ($self:ident, $f:ident, $g:ident => $pass:expr) => {{
        match &$self.cut {
            None => {
                let $g = &$f;
                $pass
            }
            Some(cut) => {
                let counting = cut.occluded.get().is_none();
                let pass = COUNTING_PASS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let id = if counting { pass } else { u64::MAX };
                cut.counting.store(id, std::sync::atomic::Ordering::Relaxed);
                let depth = &*cut.depth;
                // above one sample the covered walk cuts each sample (`Rasterizer::task`)
                let per_sample = $self.covered.is_some();
                let wrapped = |frag: &Fragment<'_>| {
                    if per_sample || frag.depth < depth[frag.pixel as usize] {
                        $f(frag)
                    } else if counting {
                        occlude(pass)
                    }
                };
                let $g = &wrapped;
                let n = $pass;
                cut.counting.store(u64::MAX, std::sync::atomic::Ordering::Relaxed);
                if counting {
                    let _ = cut.occluded.set(take_occluded(pass));
                }
                n
            }
        }
    }};
}

/// The triangles of one frame, ready for any number of geometry passes.
pub struct Rasterizer {
    setup: TriangleSetup,
    /// What the setup keeps between frames ([`Rasterizer::rebuild`]).
    scratch: SetupScratch,
    /// [`SmallEdges`] of each of `setup.triangles`, made with the setup ([`RasterMode::Scatter`]'s).
    edges: Vec<SmallEdges>,
    /// [`ShadeRecord`] of each of `setup.triangles`, read where the shading is the headlight
    /// (made under every shading, so that no frame can read another shading's records: 64 bytes
    /// a triangle the other shadings do not need).
    shades: Vec<ShadeRecord>,
    mode: RasterMode,
    bins: OnceLock<Bins>,
    /// [`Rasterizer::for_each_fragment_in_order`]'s bands, made by its first pass of a frame.
    bands: OnceLock<Bands>,
    /// The last frame's bands, their storage kept for the next.
    spare_bands: std::sync::Mutex<Bands>,
    fragments: OnceLock<u64>,
    /// The opaque pass's depth, where the frame has one ([`Rasterizer::cut_at`]).
    cut: Option<Cut>,
    /// Where every pass walks the multisampled fragments ([`Rasterizer::cover`]).
    covered: Option<Covered>,
    /// Whether the passes behind a cut skip the tiles it lies in front of
    /// ([`Rasterizer::skip_tiles`]).
    skip_tiles: bool,
}

/// The multisampled fragments of a technique that keeps no coverage mask (docs/msaa.md): every
/// pass of [`Rasterizer::cover`]'s frame walks a fragment where the triangle covers any of the
/// pixel's `samples` samples, shaded at the centre as [`Rasterizer::for_each_masked_fragment`]'s,
/// its alpha weighted by its coverage fraction where `fraction`
/// ([`oit_core::msaa::Coverage::Fraction`]), else left whole ([`oit_core::msaa::Coverage::Pixel`]).
/// Where the rasterizer has a cut ([`Rasterizer::cut_at`], one depth a sample) its mask is first
/// reduced to the samples it lies in front of, as [`Rasterizer::for_each_masked_fragment`]'s: the
/// fraction is of the samples it covers in front of each sample's opaque depth, and a fragment
/// left with none is held back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Covered {
    /// Samples a pixel (4 or 8).
    pub samples: u32,
    /// Whether each fragment's alpha is weighted by its coverage fraction.
    pub fraction: bool,
}

/// The opaque depth a frame's transparent fragments are tested against: a fragment reaches a
/// pass's shader only where its depth is strictly less than its pixel's (`f32::INFINITY` where no
/// opaque fragment fell). The fragments it holds back are counted by the first pass that runs.
struct Cut {
    depth: std::sync::Arc<[f32]>,
    occluded: OnceLock<u64>,
    /// The counting pass running now ([`COUNTING_PASS`]'s id), `u64::MAX` where the pass running
    /// does not count: the shaded walks test the cut before they shade ([`Rasterizer::early_cut`])
    /// and count what they drop themselves.
    counting: std::sync::atomic::AtomicU64,
    /// Each [`SKIP_TILE`]-pixel square tile's farthest opaque depth ([`farthest_by_tile`]),
    /// row-major, `tiles_x` a row: kept where the depth is one a pixel, empty above one sample.
    far: Vec<f32>,
    tiles_x: u32,
}

impl Cut {
    /// Runs a masked pass `walk` over `samples` samples a pixel of `pixels` pixels behind the
    /// cut: `walk` passes its fragments through the [`MaskedCut`] it is given, which hands a
    /// shader each fragment with the samples of its mask in front of the opaque depth there, and
    /// counts it occluded where none is (in the frame's first masked pass only, whose count is
    /// kept).
    fn masked<R>(&self, samples: u32, pixels: usize, walk: impl FnOnce(&MaskedCut<'_>) -> R) -> R {
        let counting = self.occluded.get().is_none();
        let pass = COUNTING_PASS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let per = samples as usize;
        debug_assert_eq!(self.depth.len(), pixels * per);
        let r = walk(&MaskedCut { depth: &self.depth, per, counting, pass });
        if counting {
            let _ = self.occluded.set(take_occluded(pass));
        }
        r
    }
}

/// A masked pass behind the cut ([`Cut::masked`]).
struct MaskedCut<'a> {
    depth: &'a [f32],
    per: usize,
    counting: bool,
    pass: u64,
}

impl MaskedCut<'_> {
    /// Hands `f` the fragment with its samples in front of the opaque depth, or counts it
    /// occluded where none is.
    #[inline]
    fn pass_on(&self, f: &impl Fn(&Fragment<'_>, u8), frag: &Fragment<'_>, mask: u8) {
        let kept = front_samples(&self.depth[frag.pixel as usize * self.per..][..self.per], frag.depth, mask);
        if kept != 0 {
            f(frag, kept);
        } else if self.counting {
            occlude(self.pass);
        }
    }
}

/// Side of the square tiles over which the cut keeps its farthest opaque depth, in pixels: a
/// triangle whose nearest depth lies behind a tile's farthest is walked there without its
/// fragments' depth tests ([`TileSkip`]).
const SKIP_TILE: u32 = 8;

/// The farthest of the opaque depths `depth` (one a pixel of a `width` × `height` image) in each
/// [`SKIP_TILE`]-pixel tile, row-major, with the tiles a row: `f32::INFINITY` in a tile where any
/// pixel has no opaque fragment.
fn farthest_by_tile(depth: &[f32], width: u32, height: u32) -> (Vec<f32>, u32) {
    let tiles_x = width.div_ceil(SKIP_TILE);
    let tiles_y = height.div_ceil(SKIP_TILE);
    let mut far = vec![f32::NEG_INFINITY; tiles_x as usize * tiles_y as usize];
    if tiles_x == 0 {
        return (far, tiles_x);
    }
    far.par_chunks_mut(tiles_x as usize).enumerate().for_each(|(ty, tiles)| {
        let y0 = ty as u32 * SKIP_TILE;
        for y in y0..(y0 + SKIP_TILE).min(height) {
            let line = &depth[(y * width) as usize..][..width as usize];
            for (far, pixels) in tiles.iter_mut().zip(line.chunks(SKIP_TILE as usize)) {
                // opaque depths are never NaN (a key's bits, or infinity where none fell)
                *far = pixels.iter().fold(*far, |a, &d| a.max(d));
            }
        }
    });
    (far, tiles_x)
}

/// A pass's view of the cut's tiles ([`Rasterizer::tile_skip`]): where a triangle's nearest
/// depth over its part of a tile ([`DepthBound`]) is not in front of the tile's farthest opaque
/// depth, every fragment of it there fails the depth test, so the walk counts them from coverage alone
/// (a row's span cut at the tile's columns, a small triangle's coverage lanes) and hands none of
/// them on: they are counted occluded where the pass counts (`counting`, as [`EarlyCut`]'s), and
/// in the fragments the pass returns. The same fragments reach the shader as without the skip.
#[derive(Clone, Copy)]
pub(crate) struct TileSkip<'a> {
    far: &'a [f32],
    tiles_x: u32,
    counting: u64,
}

/// Fragments the tile skip took off the walks (tests only: `tile_skip_changes_nothing` checks
/// that its scene exercises the skip).
#[cfg(test)]
static SKIPPED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A triangle's depth as the tile skip bounds it: [`DepthPlane::depth`] before its roundings, as
/// a function of the exact edge functions `e1`, `e2` (`z0 + e1·inv_area·dz1 + e2·inv_area·dz2`,
/// affine in the pixel, in f64), and the most those roundings take off it. Inside the triangle
/// the barycentrics lie in [0, 1], each made by three roundings (the integer to f32, `inv_area`,
/// the product), and the depth adds two rounded products to `z0`: the errors come to a few units
/// in the last place of `|z0| + |dz1| + |dz2|` (six at most), and `margin`, 2^-20 of it, is
/// sixteen (the clamp to [0, 1] only moves a depth towards an opaque one, itself in [0, 1]). NaN
/// where the plane is: then no tile is behind it.
#[derive(Clone, Copy)]
struct DepthBound {
    z0: f64,
    k1: f64,
    k2: f64,
    margin: f64,
}

impl DepthBound {
    #[inline]
    fn new(plane: &DepthPlane) -> DepthBound {
        let (z0, dz1, dz2) = (f64::from(plane.z0), f64::from(plane.dz1), f64::from(plane.dz2));
        let inv_area = f64::from(plane.inv_area);
        let margin = (z0.abs() + dz1.abs() + dz2.abs()) / f64::from(1u32 << 20);
        DepthBound { z0, k1: inv_area * dz1, k2: inv_area * dz2, margin }
    }

    /// The depth before rounding where the edge functions are `e` (outside the triangle too).
    #[inline]
    fn at(&self, e: [i64; 3]) -> f64 {
        self.z0 + e[1] as f64 * self.k1 + e[2] as f64 * self.k2
    }
}

impl TileSkip<'_> {
    /// Whether tile (`tx`, `ty`) lies wholly in front of depth `near`: its farthest opaque depth
    /// not behind it (false where `near` is NaN).
    #[inline]
    fn behind(&self, tx: u32, ty: u32, near: f64) -> bool {
        f64::from(self.far[(ty * self.tiles_x + tx) as usize]) <= near
    }

    /// Whether the covered pixels of the small triangle `s` in the pixel rectangle `rect` (not
    /// empty, inside its box) all lie behind the opaque depth: in each tile `rect` reaches into,
    /// the least of the plane's depth over the part of `rect` in it (an affine function's least
    /// over a rectangle is at a corner), less the rounding, not in front of the tile's farthest.
    #[inline]
    fn small_behind(&self, s: &SmallEdges, [x0, y0, x1, y1]: [u32; 4]) -> bool {
        let bound = DepthBound::new(&s.plane);
        let [bx, by] = [s.bbox[0], s.bbox[1]];
        // the depth at the box's first pixel and its steps a pixel
        let origin = bound.at(s.origin.map(i64::from));
        let step = |d: [i32; 3]| d[1] as f64 * bound.k1 + d[2] as f64 * bound.k2;
        let (gx, gy) = (step(s.step_x), step(s.step_y));
        let least =
            |a: u32, b: u32, first: u32, g: f64| (f64::from(a - first) * g).min(f64::from(b - first) * g);
        (y0 / SKIP_TILE..=y1 / SKIP_TILE).all(|ty| {
            let (ty0, ty1) = ((ty * SKIP_TILE).max(y0), (ty * SKIP_TILE + SKIP_TILE - 1).min(y1));
            let dy = least(ty0, ty1, by, gy);
            (x0 / SKIP_TILE..=x1 / SKIP_TILE).all(|tx| {
                let (tx0, tx1) = ((tx * SKIP_TILE).max(x0), (tx * SKIP_TILE + SKIP_TILE - 1).min(x1));
                let near = origin + least(tx0, tx1, bx, gx) + dy - bound.margin;
                self.behind(tx, ty, near)
            })
        })
    }

    /// Counts `n` fragments the walk skipped as occluded, where the pass counts.
    #[inline]
    fn count(&self, n: u64) {
        #[cfg(test)]
        SKIPPED.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        if n != 0 && self.counting != u64::MAX {
            occlude_n(self.counting, n);
        }
    }
}

/// A shaded walk's view of the cut: the opaque depth, and the counting pass to count the
/// fragments it drops in (`u64::MAX`: none).
#[derive(Clone, Copy)]
pub(crate) struct EarlyCut<'a> {
    depth: &'a [f32],
    counting: u64,
}

impl EarlyCut<'_> {
    /// Whether a fragment of `pixel` at `depth` is held back (counted where the pass counts).
    #[inline]
    fn holds_back(&self, pixel: u32, depth: f32) -> bool {
        // in front only where strictly less: a NaN depth (never made) would count as behind
        let in_front = depth < self.depth[pixel as usize];
        let behind = !in_front;
        if behind && self.counting != u64::MAX {
            occlude(self.counting);
        }
        behind
    }

    /// The samples of `mask` a multisampled fragment of `pixel` at `depth` keeps: those where it
    /// lies in front of the sample's opaque depth (the cut kept a sample, `samples` a pixel,
    /// [`front_samples`]); one that keeps none is counted where the pass counts.
    #[inline]
    fn kept(&self, pixel: u32, depth: f32, mask: u8, samples: usize) -> u8 {
        let kept = front_samples(&self.depth[pixel as usize * samples..][..samples], depth, mask);
        if kept == 0 && self.counting != u64::MAX {
            occlude(self.counting);
        }
        kept
    }
}

/// The samples of `mask` where a fragment at `depth` (its one depth, the pixel centre's) lies
/// strictly in front of the sample's opaque depth in `opaque` (one a sample of its pixel): the
/// cut of a multisampled fragment (docs/msaa.md). Strictly less: a NaN depth counts as behind.
#[inline]
fn front_samples(opaque: &[f32], depth: f32, mask: u8) -> u8 {
    let mut kept = 0u8;
    for (i, &d) in opaque.iter().enumerate() {
        kept |= u8::from(depth < d) << i;
    }
    kept & mask
}

thread_local! {
    /// The occluded fragments this thread held back, per counting pass (a plain add a fragment:
    /// an atomic one, even spread over cache lines, cost the 1.5 million occluded fragments of a
    /// 512² frame more than the capture they saved, the lines bouncing between threads that
    /// raster overlapping triangles). Keyed by pass, since one pool runs the passes of frames
    /// made at once on several threads, and a thread waiting in one may run another's work.
    /// Summed over the pool's threads after the pass ([`take_occluded`]).
    static OCCLUDED: std::cell::RefCell<Vec<(u64, u64)>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The id of the next counting pass.
static COUNTING_PASS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Counts one fragment occluded in counting pass `pass` on this thread ([`OCCLUDED`]).
#[inline]
fn occlude(pass: u64) {
    occlude_n(pass, 1);
}

/// Counts `count` fragments occluded in counting pass `pass` on this thread ([`OCCLUDED`]).
#[inline]
fn occlude_n(pass: u64, count: u64) {
    OCCLUDED.with(|c| {
        let mut c = c.borrow_mut();
        match c.iter_mut().rev().find(|(p, _)| *p == pass) {
            Some((_, n)) => *n += count,
            None => c.push((pass, count)),
        }
    });
}

/// The occluded fragments the threads of the current pool (this one included) counted in pass
/// `pass`, their counts of it dropped.
fn take_occluded(pass: u64) -> u64 {
    let take = || {
        OCCLUDED.with(|c| {
            let mut c = c.borrow_mut();
            let n = c.iter().filter(|(p, _)| *p == pass).map(|(_, n)| n).sum::<u64>();
            c.retain(|(p, _)| *p != pass);
            n
        })
    };
    // where this thread is one of the pool's, the broadcast reaches it too, after its own count
    let own = take();
    own + rayon::broadcast(|_| take()).into_iter().sum::<u64>()
}

impl Rasterizer {
    /// A rasterizer over triangles already set up (a persistent renderer keeps its setup).
    pub fn from_setup(setup: TriangleSetup) -> Rasterizer {
        let mut r = Rasterizer {
            setup,
            scratch: SetupScratch::default(),
            edges: Vec::new(),
            shades: Vec::new(),
            mode: DEFAULT_MODE,
            bins: OnceLock::new(),
            bands: OnceLock::new(),
            spare_bands: std::sync::Mutex::default(),
            fragments: OnceLock::new(),
            cut: None,
            covered: None,
            skip_tiles: true,
        };
        r.derive();
        r
    }

    /// Makes every pass that follows (but [`Rasterizer::for_each_masked_fragment`], which takes
    /// its samples itself) walk the multisampled fragments as `covered` says ([`Covered`]), on
    /// the portable per-pixel walk of [`Rasterizer::for_each_masked_fragment`], in
    /// [`RasterMode::Scatter`]'s tasks or the banded pass's bands (each pixel's fragments still
    /// from one thread, highest primitive first, there); `None` goes back to the single-sample
    /// walks.
    pub fn cover(&mut self, covered: Option<Covered>) {
        if self.covered != covered {
            self.fragments = OnceLock::new();
        }
        self.covered = covered;
    }

    /// Tests every fragment of the passes that follow against `depth` (one value a pixel, the
    /// opaque pass's; one a sample at several samples, for [`Rasterizer::for_each_masked_fragment`]'s
    /// passes and those of [`Rasterizer::cover`]'s walk, which reduce each fragment's mask to the
    /// samples it lies in front of): a fragment reaches the shader only where its depth is
    /// strictly less than its pixel's (a sample's), and [`Rasterizer::occluded`] counts those held
    /// back. `None` lifts the test.
    /// The passes still return (and [`Rasterizer::fragment_count`] still counts) every fragment
    /// drawn, those held back included.
    ///
    /// With a depth a pixel the cut keeps each small tile's farthest opaque depth, and the
    /// single-sample walks pass over a triangle's part of a tile that lies behind it without
    /// testing or handing on its fragments, counting them (the tile skip): the same fragments
    /// reach the shader, the same are counted.
    pub fn cut_at(&mut self, depth: Option<std::sync::Arc<[f32]>>) {
        let (width, height) = (self.setup.width, self.setup.height);
        self.cut = depth.map(|depth| {
            let (far, tiles_x) = if depth.len() == width as usize * height as usize {
                farthest_by_tile(&depth, width, height)
            } else {
                (Vec::new(), 0)
            };
            Cut {
                depth,
                occluded: OnceLock::new(),
                counting: std::sync::atomic::AtomicU64::new(u64::MAX),
                far,
                tiles_x,
            }
        });
    }

    /// The cut's tiles as a pass's walks skip them ([`TileSkip`]): where the rasterizer has a cut
    /// kept a pixel and walks the single-sample fragments (not [`Rasterizer::cover`]'s, whose
    /// depth is extrapolated at the pixel's centre, outside the triangle too), and the skip is on
    /// ([`Rasterizer::skip_tiles`]).
    fn tile_skip(&self) -> Option<TileSkip<'_>> {
        let cut = self.cut.as_ref()?;
        (self.skip_tiles && self.covered.is_none() && !cut.far.is_empty()).then(|| TileSkip {
            far: &cut.far,
            tiles_x: cut.tiles_x,
            counting: cut.counting.load(std::sync::atomic::Ordering::Relaxed),
        })
    }

    /// Turns the tile skip of the passes behind a cut on (as a rasterizer starts) or off
    /// ([`Rasterizer::cut_at`]): the same fragments and counts either way, so this is for
    /// checking that and for timing it.
    pub fn skip_tiles(&mut self, on: bool) {
        self.skip_tiles = on;
    }

    /// The cut as the shaded walks test it, before they shade: a fragment behind the opaque
    /// depth is dropped there, so its colour is never made (the shader's own test, behind it,
    /// then sees only fragments in front).
    fn early_cut(&self) -> Option<EarlyCut<'_>> {
        self.cut.as_ref().map(|c| EarlyCut {
            depth: &c.depth,
            counting: c.counting.load(std::sync::atomic::Ordering::Relaxed),
        })
    }

    /// Fragments the cut held back ([`Rasterizer::cut_at`]), counted by the first pass after it;
    /// 0 without a cut, `None` before a pass ran.
    pub fn occluded(&self) -> Option<u64> {
        match &self.cut {
            None => Some(0),
            Some(c) => c.occluded.get().copied(),
        }
    }

    /// What the traversal derives from the set-up triangles, made again: their [`SmallEdges`]
    /// (into the storage the last frame's used), the bins of [`RasterMode::Tiled`], the count.
    fn derive(&mut self) {
        // one parallel sweep for both (each sweep wakes every thread: on many cores a small
        // frame feels each one)
        self.setup.triangles.par_iter().map(records_of).unzip_into_vecs(&mut self.edges, &mut self.shades);
        self.records_changed();
    }

    /// The bins and the fragment count of the records before, dropped; Tiled's bins made again.
    fn records_changed(&mut self) {
        debug_assert_eq!(self.edges.len(), self.setup.triangles.len());
        self.bins = OnceLock::new();
        if let Some(bands) = self.bands.take() {
            *self.spare_bands.get_mut().unwrap_or_else(std::sync::PoisonError::into_inner) = bands;
        }
        self.fragments = OnceLock::new();
        self.warm_bins();
    }

    /// Sets up every instance's triangles ([`TriangleSetup::new`]), with the traversal's records
    /// ([`Rasterizer::rebuild`]).
    pub fn new(scene: &Scene, camera: &Camera, settings: &Settings) -> Rasterizer {
        let mut r = Rasterizer::from_setup(TriangleSetup::empty(camera, settings));
        r.rebuild(scene, camera, settings);
        r
    }

    /// Sets up another frame (another camera, size or scene) in this rasterizer's storage, as
    /// [`Rasterizer::new`] would, keeping the mode: a persistent renderer's frames then allocate
    /// nothing for their triangles once the storage has grown to the scene.
    pub fn rebuild(&mut self, scene: &Scene, camera: &Camera, settings: &Settings) {
        // the traversal's records made as setup copies each triangle into place
        // ([`TriangleSetup::rebuild_with`]): one parallel step fewer than setting up and then
        // deriving, and the triangles read while in cache; the last frame's records are
        // overwritten in place
        let mut records = (std::mem::take(&mut self.edges), std::mem::take(&mut self.shades));
        self.setup.rebuild_with(scene, camera, settings, &mut self.scratch, &mut records, records_of);
        (self.edges, self.shades) = records;
        self.records_changed();
    }

    /// The triangles of each instance's bounding box ([`TriangleSetup::bounding_boxes`]).
    pub fn bounding_boxes(scene: &Scene, camera: &Camera, settings: &Settings) -> Rasterizer {
        Rasterizer::from_setup(TriangleSetup::bounding_boxes(scene, camera, settings))
    }

    /// The set-up triangles.
    pub fn setup(&self) -> &TriangleSetup {
        &self.setup
    }
    /// The same triangles, passes run in `mode`.
    pub fn with_mode(mut self, mode: RasterMode) -> Self {
        self.mode = mode;
        self.warm_bins();
        self
    }

    /// The mode passes run in.
    pub fn mode(&self) -> RasterMode {
        self.mode
    }

    /// Binning is part of setup, not of each pass: the triangles do not change between passes.
    fn warm_bins(&self) {
        if self.mode == RasterMode::Tiled {
            self.bins();
        }
    }

    fn bins(&self) -> &Bins {
        self.bins.get_or_init(|| {
            let tiles_x = self.setup.width.div_ceil(TILE_SIZE);
            let tiles_y = self.setup.height.div_ceil(TILE_SIZE);
            let tiles = (tiles_x * tiles_y) as usize;
            let tile_range = |t: &SmallEdges| {
                let [x0, y0, x1, y1] = t.bbox;
                (x0 / TILE_SIZE..=x1 / TILE_SIZE, y0 / TILE_SIZE..=y1 / TILE_SIZE)
            };
            let first_tile =
                |t: &SmallEdges| ((t.bbox[1] / TILE_SIZE) * tiles_x + t.bbox[0] / TILE_SIZE) as usize;
            // Counting sort by first tile (stable: primitive order within a tile).
            let mut first = vec![0u32; tiles + 1];
            for t in &self.edges {
                first[first_tile(t) + 1] += 1;
            }
            for i in 1..first.len() {
                first[i] += first[i - 1];
            }
            let mut order = vec![0u32; self.edges.len()];
            for (i, t) in self.edges.iter().enumerate() {
                let slot = &mut first[first_tile(t)];
                order[*slot as usize] = i as u32;
                *slot += 1;
            }
            let edges: Vec<SmallEdges> = order.iter().map(|&i| self.edges[i as usize]).collect();
            let mut count = vec![0u32; tiles + 1];
            for t in &edges {
                let (xr, yr) = tile_range(t);
                for ty in yr {
                    for tx in xr.clone() {
                        count[(ty * tiles_x + tx) as usize + 1] += 1;
                    }
                }
            }
            for i in 1..count.len() {
                count[i] += count[i - 1];
            }
            let start = count;
            let mut fill = start.clone();
            let mut tris = vec![0u32; start[tiles] as usize];
            // Each tile's list is in the sorted triangles' order.
            for (i, t) in edges.iter().enumerate() {
                let (xr, yr) = tile_range(t);
                for ty in yr {
                    for tx in xr.clone() {
                        let slot = &mut fill[(ty * tiles_x + tx) as usize];
                        tris[*slot as usize] = i as u32;
                        *slot += 1;
                    }
                }
            }
            Bins { tiles_x, order, edges, start, tris }
        })
    }

    /// One geometry pass: calls `f` exactly once per covered (pixel, triangle), concurrently from
    /// rayon's threads, in no particular order (in [`RasterMode::Tiled`] a pixel's fragments come
    /// from one thread, in the same order every pass). Returns the number of fragments, i.e. of
    /// calls. Colour and normal are made where `f` asks ([`Shade::OnDemand`]); a pass that reads
    /// every fragment's colour is faster through [`Rasterizer::for_each_shaded_fragment`].
    pub fn for_each_fragment<F: Fn(&Fragment<'_>) + Sync>(&self, f: F) -> u64 {
        self.for_each_fragment_with(Shade::OnDemand, f)
    }

    /// [`Rasterizer::for_each_fragment`] with every fragment's colour made before `f` sees it
    /// ([`Shade::Color`]): the same colours, bit for bit, shaded several at once.
    pub fn for_each_shaded_fragment<F: Fn(&Fragment<'_>) + Sync>(&self, f: F) -> u64 {
        self.for_each_fragment_with(Shade::Color, f)
    }

    /// [`Rasterizer::for_each_shaded_fragment`] that calls `ahead(pixel)` a few fragments
    /// before each fragment of `pixel` reaches `f`, where the walk knows them that early (the
    /// AVX2 walk's batches): for a capture whose atomics go to memory all over a large array,
    /// `ahead` asks for the pixel's words (a prefetch), so that several of those fetches are in
    /// flight together instead of each locked instruction waiting on its own. The same
    /// fragments in the same order; `ahead` changes nothing that `f` sees.
    pub fn for_each_shaded_fragment_ahead<F: Fn(&Fragment<'_>) + Sync>(
        &self,
        ahead: &(dyn Fn(u32) + Sync),
        f: F,
    ) -> u64 {
        let n = behind_cut!(self, f, g => match self.pass_mode() {
            RasterMode::Scatter => self.scatter_shaded(Kernel::detect(), g, Some(ahead)),
            RasterMode::Tiled => self.covered_on_demand(g),
        });
        self.fragments.get_or_init(|| n);
        n
    }

    /// A geometry pass in which each pixel's fragments come from one thread, **highest primitive
    /// id first**: the image is cut into bands of rows, each band run by one rayon task over the
    /// triangles that reach into it, in descending primitive order, each walked in the band's
    /// rows only. A pixel's fragments (one per primitive: the pieces of a clipped triangle do not
    /// overlap) thus arrive in the reverse of submission order, which a shader composites front
    /// to back with no storage but the pixel's running colour and no sort: `plain` on oit-cpu
    /// (what a GPU's blender gets from one draw). The same fragments as every other pass, bit
    /// for bit; the AVX2 walk where the host has it. Shading as `shade` says. The bands are
    /// made by the first such pass of a frame (and kept for the next).
    pub fn for_each_fragment_in_order<F: Fn(&Fragment<'_>) + Sync>(&self, shade: Shade, f: F) -> u64 {
        behind_cut!(self, f, g => self.in_order(Kernel::detect(), shade, g))
    }

    /// [`Rasterizer::for_each_fragment_in_order`] on `kernel`.
    fn in_order<F: Fn(&Fragment<'_>) + Sync>(&self, kernel: Kernel, shade: Shade, f: &F) -> u64 {
        self.by_band(kernel, shade, |_| f).iter().sum()
    }

    /// The banded pass of [`Rasterizer::for_each_fragment_in_order`] with a shader per band:
    /// `make(b)` gives band `b`'s, which runs on the one task that walks the band. No other
    /// task writes a fragment to the band's pixels, so a shader may update its pixels' words by
    /// plain loads and stores instead of locked atomics, and may keep counts of its own (`ll`'s
    /// nodes, taken a band's block at a time). Returns each band's fragments, top band first;
    /// the bands, and so the split of the fragments between them, are the same for every pass
    /// of a frame.
    pub fn for_each_fragment_by_band<F: Fn(&Fragment<'_>)>(
        &self,
        shade: Shade,
        make: impl Fn(usize) -> F + Sync,
    ) -> Vec<u64> {
        let Some(cut) = &self.cut else {
            return self.by_band(Kernel::detect(), shade, make);
        };
        let counting = cut.occluded.get().is_none();
        let pass = COUNTING_PASS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        cut.counting.store(if counting { pass } else { u64::MAX }, std::sync::atomic::Ordering::Relaxed);
        let depth = &*cut.depth;
        let make = &make;
        // above one sample the covered walk cuts each sample (`Rasterizer::task`)
        let per_sample = self.covered.is_some();
        let per_band = self.by_band(Kernel::detect(), shade, move |b| {
            let f = make(b);
            move |frag: &Fragment<'_>| {
                if per_sample || frag.depth < depth[frag.pixel as usize] {
                    f(frag)
                } else if counting {
                    occlude(pass)
                }
            }
        });
        cut.counting.store(u64::MAX, std::sync::atomic::Ordering::Relaxed);
        if counting {
            let _ = cut.occluded.set(take_occluded(pass));
        }
        per_band
    }

    /// [`Rasterizer::for_each_fragment_by_band`] on `kernel`.
    fn by_band<F: Fn(&Fragment<'_>)>(
        &self,
        kernel: Kernel,
        shade: Shade,
        make: impl Fn(usize) -> F + Sync,
    ) -> Vec<u64> {
        let per_band = self.bands_run(|b, rows, tris| {
            self.task(kernel, shade, self.band_order(tris, shade), rows, &make(b), None)
        });
        self.fragments.get_or_init(|| per_band.iter().sum());
        per_band
    }

    /// The banded passes' tasks: `walk(b, rows, tris)` for each band `b`, one rayon task a band,
    /// `rows` the band's rows (inclusive) and `tris` its triangles ([`Bands`], made by the first
    /// banded pass of a frame); returns what each band's walk returns (its fragments), top band
    /// first.
    fn bands_run(&self, walk: impl Fn(usize, [u32; 2], &[u32]) -> u64 + Sync) -> Vec<u64> {
        let height = self.setup.height;
        let bands = self.bands.get_or_init(|| {
            let mut bands = std::mem::take(
                &mut *self.spare_bands.lock().unwrap_or_else(std::sync::PoisonError::into_inner),
            );
            bands.make(&self.edges, height, rayon::current_num_threads());
            bands
        });
        (0..bands.start.len() - 1)
            .into_par_iter()
            .map(|b| {
                let (rows, tris) = bands.band(b, height);
                walk(b, rows, tris)
            })
            .collect()
    }

    /// A band's triangles `tris` in the order its walk takes them: highest primitive first. A
    /// band's triangles lie all over the frame's records (every row of a grid of meshes is in
    /// every band's list), so each record (and its shading record, where the pass shades by the
    /// headlight, `shade`) is asked for from memory a few triangles ahead of its walk.
    fn band_order<'a>(&'a self, tris: &'a [u32], shade: Shade) -> impl Iterator<Item = usize> + 'a {
        let shaded = shade == Shade::Color && self.setup.shading == Shading::Headlight;
        (0..tris.len()).rev().map(move |k| {
            if let Some(&ahead) = k.checked_sub(PREFETCH).and_then(|a| tris.get(a)) {
                prefetch(&self.edges[ahead as usize]);
                if shaded {
                    prefetch(&self.shades[ahead as usize]);
                }
            }
            tris[k] as usize
        })
    }

    /// [`Rasterizer::for_each_fragment_with`]'s Scatter pass on `kernel`, behind the cut (tests:
    /// the portable kernel where the host has AVX2).
    #[cfg(test)]
    fn for_each_fragment_on<F: Fn(&Fragment<'_>) + Sync>(&self, kernel: Kernel, shade: Shade, f: F) -> u64 {
        behind_cut!(self, f, g => self.scatter_tasks(|run| self.task(kernel, shade, run, ALL_ROWS, g, None)))
    }

    /// [`Rasterizer::for_each_fragment`], shading as `shade` says.
    pub fn for_each_fragment_with<F: Fn(&Fragment<'_>) + Sync>(&self, shade: Shade, f: F) -> u64 {
        let n = behind_cut!(self, f, g => match (self.pass_mode(), shade) {
            (RasterMode::Scatter, Shade::Color) => self.scatter_shaded(Kernel::detect(), g, None),
            (RasterMode::Scatter, Shade::OnDemand) => self.scatter_on_demand(Kernel::detect(), g),
            (RasterMode::Tiled, _) => self.covered_on_demand(g),
        });
        self.fragments.get_or_init(|| n);
        n
    }

    /// The mode a pass runs in: [`RasterMode::Scatter`] where [`Rasterizer::cover`] asked for
    /// the multisampled fragments (whose walk is Scatter's tasks'), else the rasterizer's.
    fn pass_mode(&self) -> RasterMode {
        if self.covered.is_some() { RasterMode::Scatter } else { self.mode }
    }

    /// Every covered pixel handed to `f` with its colour and normal left to be made where `f`
    /// asks, by [`Rasterizer::for_each_covered`]'s traversal.
    fn covered_on_demand<F: Fn(&Fragment<'_>) + Sync>(&self, f: &F) -> u64 {
        // depth from the traversal's own record: the triangle is read only for colour or
        // normal, where `f` asks for it
        self.for_each_covered(|t, s, x, y, e| f(&self.on_demand_fragment(t, s, x, y, e)))
    }

    /// [`RasterMode::Scatter`]'s pass with [`Shade::OnDemand`]: the portable walk, or on an AVX2
    /// host the tasks of [`Rasterizer::scatter_shaded`], each `avx2::scatter_task` without its
    /// shading (a depth-only pass, a count or a peel, took as long on the portable walk as a
    /// shaded pass in AVX2: the bunny's 1.34–2.15 ms against 0.99 in AVX2, `cargo bench -p
    /// oit-cpu --bench raster`, `bench/results/cpu/issue12/`). The same fragments either way.
    fn scatter_on_demand<F: Fn(&Fragment<'_>) + Sync>(&self, kernel: Kernel, f: &F) -> u64 {
        self.scatter_tasks(|run| self.task(kernel, Shade::OnDemand, run, ALL_ROWS, f, None))
    }

    /// The frame's triangles with their traversal and shading records.
    fn records(&self) -> Records<'_> {
        (&self.setup.triangles, &self.edges, &self.shades)
    }

    /// [`RasterMode::Scatter`]'s tasks: the triangles cut into runs, several per thread
    /// ([`scatter_chunk`]), each run's indices given to `task`; returns the sum of what the tasks
    /// return (their fragments).
    fn scatter_tasks(&self, task: impl Fn(std::ops::Range<usize>) -> u64 + Sync) -> u64 {
        let n = self.setup.triangles.len();
        let chunk = scatter_chunk(n, rayon::current_num_threads());
        (0..n.div_ceil(chunk)).into_par_iter().map(|i| task(i * chunk..((i + 1) * chunk).min(n))).sum()
    }

    /// One task's walk: the triangles of `order` in the rows `rows`, shaded as `shade` says, in
    /// AVX2 where `kernel` is [`Kernel::Avx2`], else by the portable batch
    /// ([`Rasterizer::portable_shaded`]) or the portable walk with colour made where `f` asks.
    /// Scatter's tasks are runs of triangles over every row, the banded pass's a band's
    /// triangles, highest first, over its rows.
    fn task<F: Fn(&Fragment<'_>)>(
        &self,
        kernel: Kernel,
        shade: Shade,
        order: impl Iterator<Item = usize>,
        rows: [u32; 2],
        f: &F,
        ahead: Ahead<'_>,
    ) -> u64 {
        if let Some(covered) = self.covered {
            let offsets = sample_offsets(covered.samples);
            // the cut a sample (docs/msaa.md): each fragment's mask reduced to the samples it lies
            // in front of, as `for_each_masked_fragment`'s, before its coverage weighs its alpha;
            // one left with none held back (counted where the pass counts, `behind_cut!`)
            let cut = self.early_cut();
            let per = covered.samples as usize;
            return self.masked_task(
                kernel,
                shade,
                order,
                rows,
                &offsets,
                (&|_| true, None),
                &|frag, mask| {
                    let mask = match &cut {
                        Some(cut) => cut.kept(frag.pixel, frag.depth, mask, per),
                        None => mask,
                    };
                    if mask == 0 {
                        return;
                    }
                    if covered.fraction {
                        let mut color = frag.color();
                        color.w = oit_core::msaa::fraction_alpha(color.w, mask, covered.samples);
                        f(&Fragment { color: Some(color), ..*frag });
                    } else {
                        f(frag);
                    }
                },
            );
        }
        let skip = self.tile_skip();
        #[cfg(target_arch = "x86_64")]
        if kernel == Kernel::Avx2 {
            let (setup, records) = (&self.setup, self.records());
            // only a shaded walk has work to save by testing the cut first
            let n = match shade {
                Shade::Color => avx2_task::<true, F>(
                    kernel,
                    setup,
                    records,
                    order,
                    rows,
                    f,
                    ahead,
                    (self.early_cut(), skip),
                ),
                Shade::OnDemand => {
                    avx2_task::<false, F>(kernel, setup, records, order, rows, f, ahead, (None, skip))
                }
            };
            return n.unwrap_or(0);
        }
        // the portable walks hand each fragment over as it is found: nothing to ask for ahead
        let _ = (kernel, ahead);
        if shade == Shade::Color {
            return self.portable_shaded(order, rows, f);
        }
        let (mut n, mut skipped) = (0u64, 0u64);
        for i in order {
            let (t, s) = (&self.setup.triangles[i], &self.edges[i]);
            skipped += walk_tile_skipping(t, s, in_rows(s.bbox, rows), skip.as_ref(), |x, y, e| {
                f(&self.on_demand_fragment(t, s, x, y, e));
                n += 1;
            });
        }
        if let Some(skip) = &skip {
            skip.count(skipped);
        }
        n + skipped
    }

    /// The multisampled geometry pass ([`oit_core::msaa`], `Settings::samples` above 1): calls
    /// `f` once per (pixel, triangle) where the triangle covers **any** of the pixel's `samples`
    /// samples ([`oit_core::setup::sample_mask`]: the same edge functions and top-left rule as
    /// the centre's, at the standard positions), with the coverage mask (bit `i`: sample `i`).
    /// The fragment's depth, barycentrics, colour and normal are the pixel centre's, as
    /// single-sample's (one shading a pixel a fragment: MSAA, not supersampling); where the
    /// centre lies outside the triangle they are extrapolated from its plane (depth clamped to
    /// [0, 1] as always). Parallel over runs of triangles, in no particular order; colours made
    /// where `f` asks. The portable per-pixel walk of each triangle's box (setup sized the box
    /// by the samples' reach): the single-sample walks, batches and AVX2 kernels are not
    /// touched, so `samples == 1` runs exactly as before.
    ///
    /// Where the rasterizer has a cut ([`Rasterizer::cut_at`], here one depth a **sample**,
    /// `pixel · samples + i`), the mask `f` sees is reduced to the samples where the fragment's
    /// depth (the pixel centre's, its one depth) lies strictly in front of that sample's opaque
    /// depth; a fragment left with no sample does not reach `f` and is counted occluded by the
    /// first pass after the cut, as the single-sample walks count theirs. The pass still returns
    /// every fragment drawn.
    pub fn for_each_masked_fragment<F: Fn(&Fragment<'_>, u8) + Sync>(&self, samples: u32, f: F) -> u64 {
        self.masked_pass(samples, Shade::OnDemand, (&|_| true, None), f)
    }

    /// [`Rasterizer::for_each_masked_fragment`] shaded as `shade` says: with [`Shade::Color`]
    /// every fragment's colour is made before `f` sees it, the same colours bit for bit, shaded
    /// several at once where the walk batches them (AVX2), for a pass that reads every
    /// fragment's colour.
    pub fn for_each_masked_fragment_with<F: Fn(&Fragment<'_>, u8) + Sync>(
        &self,
        samples: u32,
        shade: Shade,
        f: F,
    ) -> u64 {
        self.masked_pass(samples, shade, (&|_| true, None), f)
    }

    /// [`Rasterizer::for_each_masked_fragment_with`] that calls `ahead(pixel)` a few fragments
    /// before each fragment of `pixel` reaches `f`, where the walk knows them that early (the
    /// AVX2 walk's batches), as [`Rasterizer::for_each_shaded_fragment_ahead`] does: for a capture
    /// whose stores go all over large arrays, `ahead` asks for the pixel's words. The same
    /// fragments and masks in the same order.
    pub fn for_each_masked_fragment_ahead<F: Fn(&Fragment<'_>, u8) + Sync>(
        &self,
        samples: u32,
        shade: Shade,
        ahead: &(dyn Fn(u32) + Sync),
        f: F,
    ) -> u64 {
        self.masked_pass(samples, shade, (&|_| true, Some(ahead)), f)
    }

    /// [`Rasterizer::for_each_masked_fragment`] over the pixels `keep` keeps only: a pixel it
    /// turns down costs its walk, not its samples' tests (fabs's passes over the pixels that
    /// overflowed). Returns the fragments of the pixels kept.
    pub fn for_each_masked_fragment_where<K, F>(&self, samples: u32, keep: &K, f: F) -> u64
    where
        K: Fn(u32) -> bool + Sync,
        F: Fn(&Fragment<'_>, u8) + Sync,
    {
        self.masked_pass(samples, Shade::OnDemand, (keep, None), f)
    }

    /// The banded pass ([`Rasterizer::for_each_fragment_by_band`]) over the multisampled
    /// fragments: each of [`Rasterizer::for_each_masked_fragment`]'s fragments with its mask
    /// (the same fragments and masks bit for bit, the cut a sample's as that pass's), walked by
    /// bands of rows, each band by one task with the shader `make(b)` gives it, its triangles
    /// highest primitive first. No other task writes a fragment to the band's pixels, so a
    /// shader may update its pixels' words by plain loads and stores and keep counts of its own
    /// (`ll`'s nodes at several samples, a band's block at a time). Where `ahead` is given each
    /// pixel is asked for a few fragments before its turn, as
    /// [`Rasterizer::for_each_masked_fragment_ahead`] does. Returns each band's fragments (every
    /// fragment drawn, those the cut holds back included), top band first; the bands are those
    /// of every banded pass of the frame.
    pub fn for_each_masked_fragment_by_band<F: Fn(&Fragment<'_>, u8)>(
        &self,
        samples: u32,
        shade: Shade,
        ahead: Option<&(dyn Fn(u32) + Sync)>,
        make: impl Fn(usize) -> F + Sync,
    ) -> Vec<u64> {
        let kernel = Kernel::detect();
        let Some(cut) = &self.cut else {
            return self.masked_by_band(kernel, samples, shade, ahead, make);
        };
        let pixels = self.setup.width as usize * self.setup.height as usize;
        cut.masked(samples, pixels, |at| {
            self.masked_by_band(kernel, samples, shade, ahead, |b| {
                let f = make(b);
                move |frag: &Fragment<'_>, mask: u8| at.pass_on(&f, frag, mask)
            })
        })
    }

    /// [`Rasterizer::for_each_masked_fragment_by_band`] on `kernel`, without the cut.
    fn masked_by_band<F: Fn(&Fragment<'_>, u8)>(
        &self,
        kernel: Kernel,
        samples: u32,
        shade: Shade,
        ahead: Ahead<'_>,
        make: impl Fn(usize) -> F + Sync,
    ) -> Vec<u64> {
        let offsets = sample_offsets(samples);
        let keep = |_: u32| true;
        self.bands_run(|b, rows, tris| {
            let order = self.band_order(tris, shade);
            self.masked_task(kernel, shade, order, rows, &offsets, (&keep, ahead), &make(b))
        })
    }

    /// The masked passes: [`Rasterizer::for_each_masked_fragment_where`] shaded as `shade` says,
    /// the pixels' words asked for ahead where `ahead` is given.
    fn masked_pass<K, F>(&self, samples: u32, shade: Shade, keep: (&K, Ahead<'_>), f: F) -> u64
    where
        K: Fn(u32) -> bool + Sync,
        F: Fn(&Fragment<'_>, u8) + Sync,
    {
        let Some(cut) = &self.cut else {
            return self.masked_walk(samples, shade, keep, &f);
        };
        let pixels = self.setup.width as usize * self.setup.height as usize;
        cut.masked(samples, pixels, |at| {
            self.masked_walk(samples, shade, keep, &|frag: &Fragment<'_>, mask: u8| {
                at.pass_on(&f, frag, mask)
            })
        })
    }

    /// [`Rasterizer::for_each_masked_fragment`]'s walk, without the cut, in Scatter's tasks.
    fn masked_walk<K, F>(&self, samples: u32, shade: Shade, keep: (&K, Ahead<'_>), f: &F) -> u64
    where
        K: Fn(u32) -> bool + Sync,
        F: Fn(&Fragment<'_>, u8) + Sync,
    {
        let offsets = sample_offsets(samples);
        let kernel = Kernel::detect();
        self.scatter_tasks(|run| self.masked_task(kernel, shade, run, ALL_ROWS, &offsets, keep, f))
    }

    /// One task of the multisampled walk: the triangles of `order` in the rows `rows`, the
    /// samples at `offsets` from the centre, the pixels `keep` keeps, each fragment handed to `f`
    /// with its mask in the order walked: in AVX2 where `kernel` is [`Kernel::Avx2`]
    /// (`avx2::masked_task`, shaded in batches where `shade` is [`Shade::Color`]), else the
    /// portable per-pixel walk with colours made where `f` asks ([`Rasterizer::walk_masked`]).
    /// The same fragments and masks either way, bit for bit (`masked_kernels_agree`); returns
    /// them.
    #[expect(clippy::too_many_arguments, reason = "the walk's inputs, passed through to the kernel")]
    fn masked_task<K, F>(
        &self,
        kernel: Kernel,
        shade: Shade,
        order: impl Iterator<Item = usize>,
        rows: [u32; 2],
        offsets: &[(i64, i64)],
        (keep, ahead): (&K, Ahead<'_>),
        f: &F,
    ) -> u64
    where
        K: Fn(u32) -> bool,
        F: Fn(&Fragment<'_>, u8),
    {
        #[cfg(target_arch = "x86_64")]
        if kernel == Kernel::Avx2 {
            let (setup, records) = (&self.setup, self.records());
            #[expect(unsafe_code, reason = "the one call into code compiled for AVX2")]
            // SAFETY: `Kernel::Avx2` is made only where the host has AVX2 and popcnt
            // (`Kernel::detect`), all that `masked_task` is compiled to need
            let n = unsafe {
                match shade {
                    Shade::Color => avx2::masked_task::<true, K, F>(
                        setup,
                        records,
                        order,
                        rows,
                        offsets,
                        (keep, ahead),
                        f,
                    ),
                    Shade::OnDemand => avx2::masked_task::<false, K, F>(
                        setup,
                        records,
                        order,
                        rows,
                        offsets,
                        (keep, ahead),
                        f,
                    ),
                }
            };
            return n;
        }
        // the portable walk hands each fragment over as it is found: nothing to ask for ahead
        let _ = (kernel, shade, ahead);
        order.map(|i| self.walk_masked(i, offsets, rows, keep, |frag, mask| f(frag, mask))).sum()
    }

    /// The multisampled walk of triangle `i` in the rows `rows` (inclusive), the samples at
    /// `offsets` from the pixel's centre ([`sample_offsets`]): `f` gets each fragment with its
    /// mask in the pixels `keep` keeps ([`Rasterizer::for_each_masked_fragment_where`]);
    /// returns those fragments.
    fn walk_masked(
        &self,
        i: usize,
        offsets: &[(i64, i64)],
        rows: [u32; 2],
        keep: &impl Fn(u32) -> bool,
        mut f: impl FnMut(&Fragment<'_>, u8),
    ) -> u64 {
        let (t, s) = (&self.setup.triangles[i], &self.edges[i]);
        let mut n = 0u64;
        masked_pixels(t, self.setup.width, offsets, rows, keep, |x, y, c, mask| {
            f(&self.on_demand_fragment(t, s, x, y, c), mask);
            n += 1;
        });
        n
    }

    /// The fragment of `t` (traversal record `s`) at pixel (`x`, `y`) with edge functions `e`,
    /// its depth from the record, colour and normal left to be made where a shader asks.
    #[inline]
    fn on_demand_fragment<'a>(
        &'a self,
        t: &'a Triangle,
        s: &SmallEdges,
        x: u32,
        y: u32,
        e: [i64; 3],
    ) -> Fragment<'a> {
        let b = s.plane.barycentrics(e);
        let depth = s.plane.depth(b);
        let setup = &self.setup;
        Fragment { pixel: y * setup.width + x, depth, prim: s.prim, b, t, setup, color: None }
    }

    /// [`RasterMode::Scatter`]'s pass with [`Shade::Color`]: each task walks its triangles into a
    /// batch of up to [`BATCH`] covered pixels, colours the batch [`SHADE_LANES`] at a time, then
    /// calls `f` for each in the order walked. Walking, shading and the technique's capture each
    /// run as a loop of their own, so a colour's long chain of dependent operations runs in
    /// vector lanes beside its neighbours' instead of stalling between the walk's branches and
    /// the capture's atomics. A pass that shades on demand walks without the portable batch:
    /// gathering measured slower for a depth-only pass (3.99–4.16 ms against 3.56–3.82 on the
    /// bunny); the AVX2 batch without its shading is faster ([`Rasterizer::scatter_on_demand`]).
    /// Measured side by side with the lanes and the row test in `wide`, the whole shaded bunny
    /// pass went from 7.20–7.35 ms to 4.76–5.16 (`cargo bench -p oit-cpu --bench raster`, 512²,
    /// 2 threads; `bench/results/cpu/issue12/`). With `kernel` [`Kernel::Avx2`] each task runs
    /// `avx2::scatter_task` instead (the same fragments; see that module for how).
    fn scatter_shaded<F: Fn(&Fragment<'_>) + Sync>(&self, kernel: Kernel, f: &F, ahead: Ahead<'_>) -> u64 {
        self.scatter_tasks(|run| self.task(kernel, Shade::Color, run, ALL_ROWS, f, ahead))
    }

    /// The portable shaded walk of one task: the triangles of `order` in the rows `rows`, walked
    /// into a batch of up to [`BATCH`] covered pixels, coloured [`SHADE_LANES`] at a time, then
    /// handed to `f` in the order walked ([`Rasterizer::scatter_shaded`] says why).
    fn portable_shaded<F: Fn(&Fragment<'_>)>(
        &self,
        order: impl Iterator<Item = usize>,
        rows: [u32; 2],
        f: &F,
    ) -> u64 {
        let setup = &self.setup;
        let (tris, edges, shades) = self.records();
        let flush = |batch: &[Candidate]| {
            let mut colors = [Vec4::ZERO; BATCH];
            for (start, out) in (0..batch.len()).step_by(SHADE_LANES).zip(colors.chunks_mut(SHADE_LANES)) {
                // a short last group repeats its last fragment in the spare lanes
                let lane = |i: usize| &batch[(start + i).min(batch.len() - 1)];
                let b = std::array::from_fn(|i| edges[lane(i).tri as usize].plane.barycentrics(lane(i).e));
                let shaded = if setup.shading != Shading::Headlight || setup.has_textures() {
                    setup.colors_at(std::array::from_fn(|i| &tris[lane(i).tri as usize]), b)
                } else {
                    headlight_colors(std::array::from_fn(|i| &shades[lane(i).tri as usize]), b, setup.forward)
                };
                out.copy_from_slice(&shaded);
            }
            for (c, &color) in batch.iter().zip(&colors) {
                let (t, s) = (&tris[c.tri as usize], &edges[c.tri as usize]);
                let b = s.plane.barycentrics(c.e);
                let color = Some(color);
                f(&Fragment { pixel: c.pixel, depth: s.plane.depth(b), prim: s.prim, b, t, setup, color });
            }
        };
        let mut batch = [Candidate::default(); BATCH];
        let (mut len, mut n) = (0usize, 0u64);
        let cut = self.early_cut();
        let skip = self.tile_skip();
        let mut skipped = 0u64;
        for i in order {
            let (t, s) = (&tris[i], &edges[i]);
            skipped += walk_tile_skipping(t, s, in_rows(s.bbox, rows), skip.as_ref(), |x, y, e| {
                n += 1;
                let pixel = y * setup.width + x;
                // behind the opaque depth: dropped before it is shaded
                if let Some(cut) = &cut
                    && cut.holds_back(pixel, s.plane.depth(s.plane.barycentrics(e)))
                {
                    return;
                }
                if len == BATCH {
                    flush(&batch);
                    len = 0;
                }
                batch[len] = Candidate { tri: i as u32, pixel, e };
                len += 1;
            });
        }
        flush(&batch[..len]);
        if let Some(skip) = &skip {
            skip.count(skipped);
        }
        n + skipped
    }

    /// The coverage pass under [`Rasterizer::for_each_fragment`], before any interpolation;
    /// returns the number of covered (pixel, triangle) pairs.
    fn for_each_covered<F: Fn(&Triangle, &SmallEdges, u32, u32, [i64; 3]) + Sync>(&self, f: F) -> u64 {
        match self.mode {
            RasterMode::Scatter => self.scatter_tasks(|run| {
                let mut n = 0u64;
                for i in run {
                    let (t, edges) = (&self.setup.triangles[i], &self.edges[i]);
                    walk_tile(t, edges, edges.bbox, |x, y, e| {
                        f(t, edges, x, y, e);
                        n += 1;
                    });
                }
                n
            }),
            RasterMode::Tiled => {
                let bins = self.bins();
                let tiles = bins.start.len() - 1;
                (0..tiles)
                    .into_par_iter()
                    .map(|tile| {
                        let tx = tile as u32 % bins.tiles_x;
                        let ty = tile as u32 / bins.tiles_x;
                        let (x0, y0) = (tx * TILE_SIZE, ty * TILE_SIZE);
                        let x1 = (x0 + TILE_SIZE - 1).min(self.setup.width - 1);
                        let y1 = (y0 + TILE_SIZE - 1).min(self.setup.height - 1);
                        let mut n = 0u64;
                        for &i in &bins.tris[bins.start[tile] as usize..bins.start[tile + 1] as usize] {
                            // The triangle itself is read only where it covers a pixel.
                            let edges = &bins.edges[i as usize];
                            let t = &self.setup.triangles[bins.order[i as usize] as usize];
                            let [bx0, by0, bx1, by1] = edges.bbox;
                            let rect = [bx0.max(x0), by0.max(y0), bx1.min(x1), by1.min(y1)];
                            walk_tile(t, edges, rect, |x, y, e| {
                                f(t, edges, x, y, e);
                                n += 1;
                            });
                        }
                        n
                    })
                    .sum()
            }
        }
    }

    /// A coverage-only pass: the traversal without interpolation or shading (what the
    /// rasterizer's bench times apart from the fragments); returns the covered pairs.
    pub fn coverage_pass(&self) -> u64 {
        self.for_each_covered(|_, _, _, _, e| {
            std::hint::black_box(e);
        })
    }

    /// Fragments one pass generates (counted by a coverage-only pass unless a pass ran already).
    pub fn fragment_count(&self) -> u64 {
        *self.fragments.get_or_init(|| match self.covered {
            Some(c) => self.for_each_masked_fragment(c.samples, |_, _| {}),
            None => self.for_each_covered(|_, _, _, _, _| {}),
        })
    }

    /// Triangles after setup: the pieces of clipped triangles counted apiece, triangles that cover
    /// no part of the viewport or have no area not counted.
    pub fn triangle_count(&self) -> usize {
        self.setup.triangles.len()
    }

    /// Viewport width in pixels.
    pub fn width(&self) -> u32 {
        self.setup.width
    }

    /// Viewport height in pixels.
    pub fn height(&self) -> u32 {
        self.setup.height
    }

    /// The shading the fragments get.
    pub fn shading(&self) -> Shading {
        self.setup.shading
    }

    /// The camera's viewing direction (headlight shading).
    pub fn forward(&self) -> Vec3 {
        self.setup.forward
    }

    /// The set-up triangles as 32-bit words ([`TriangleSetup::triangle_words`]).
    pub fn triangle_words(&self) -> Vec<u32> {
        self.setup.triangle_words()
    }

    /// The inclusive pixel boxes of the set-up triangles (x0, y0, x1, y1), in order.
    pub fn triangle_boxes(&self) -> impl Iterator<Item = [u32; 4]> + '_ {
        self.setup.triangle_boxes()
    }
}

/// Visits the covered pixels of `t` inside the inclusive pixel rectangle `rect`, row by row, with
/// the three edge functions ([`edge`]) at each pixel centre. Each row's covered span is found
/// exactly by integer division: edge k is covered at column offset n when
/// `e + step·n > inside_above`.
fn walk(t: &Triangle, rect: [u32; 4], visit: impl FnMut(u32, u32, [i64; 3])) {
    walk_spans(t, rect, None, visit);
}

/// [`walk`], skipping where `skip` holds the cut's tiles and the triangle's depth
/// ([`DepthBound`]): each row's span is cut at the tiles' columns, and a piece whose least depth
/// (at one of its ends, less the rounding) is [`TileSkip::behind`] its tile's farthest opaque
/// depth is counted, not visited. Returns the pixels skipped (the
/// covered pixels are those visited and those skipped, in the same order as [`walk`]'s).
fn walk_spans(
    t: &Triangle,
    rect: [u32; 4],
    skip: Option<(&TileSkip<'_>, DepthBound)>,
    mut visit: impl FnMut(u32, u32, [i64; 3]),
) -> u64 {
    let [x0, y0, x1, y1] = rect;
    let mut skipped = 0u64;
    if x0 > x1 || y0 > y1 {
        return skipped;
    }
    let (px, py) = (i64::from(x0) * SUBPIXEL + HALF_PIXEL, i64::from(y0) * SUBPIXEL + HALF_PIXEL);
    let edges = [0, 1, 2].map(|k| edge(t, k, px, py));
    let mut row = edges.map(|e| e.0);
    let last = i64::from(x1 - x0);
    for y in y0..=y1 {
        let (mut lo, mut hi) = (0i64, last);
        for (k, &(_, step, _, above)) in edges.iter().enumerate() {
            let c = row[k] - above; // covered where c + step·n > 0
            if step > 0 {
                lo = lo.max((-c).div_euclid(step) + 1);
            } else if step < 0 {
                hi = hi.min((c - 1).div_euclid(-step));
            } else if c <= 0 {
                hi = -1;
            }
        }
        if lo <= hi {
            let mut e = [0, 1, 2].map(|k| row[k] + edges[k].1 * lo);
            match skip {
                None => {
                    for n in lo..=hi {
                        visit(x0 + n as u32, y, e);
                        for k in 0..3 {
                            e[k] += edges[k].1;
                        }
                    }
                }
                Some((tiles, bound)) => {
                    // the span a tile at a time: columns `n..=end` lie in tile `x / SKIP_TILE`
                    let mut n = lo;
                    while n <= hi {
                        let x = x0 + n as u32;
                        let end = (i64::from((x / SKIP_TILE + 1) * SKIP_TILE) - 1 - i64::from(x0)).min(hi);
                        let run = end - n + 1;
                        let last = [0, 1, 2].map(|k| e[k] + edges[k].1 * (run - 1));
                        let near = bound.at(e).min(bound.at(last)) - bound.margin;
                        if tiles.behind(x / SKIP_TILE, y / SKIP_TILE, near) {
                            skipped += run as u64;
                            for k in 0..3 {
                                e[k] += edges[k].1 * run;
                            }
                        } else {
                            for m in n..=end {
                                visit(x0 + m as u32, y, e);
                                for k in 0..3 {
                                    e[k] += edges[k].1;
                                }
                            }
                        }
                        n = end + 1;
                    }
                }
            }
        }
        for k in 0..3 {
            row[k] += edges[k].2;
        }
    }
    skipped
}

/// The multisampled walk of `t` in the rows `rows` (inclusive), the samples at `offsets` from
/// the pixel's centre ([`sample_offsets`]): `visit(x, y, e, mask)` for each pixel `keep` keeps
/// (by index `y · width + x`) where the triangle covers any sample, with the centre's edge functions `e` and the
/// coverage mask (bit `j`: sample `j`), row by row.
fn masked_pixels(
    t: &Triangle,
    width: u32,
    offsets: &[(i64, i64)],
    rows: [u32; 2],
    keep: &impl Fn(u32) -> bool,
    mut visit: impl FnMut(u32, u32, [i64; 3], u8),
) {
    use oit_core::setup::{HALF_PIXEL, SUBPIXEL, edge};
    let [x0, y0, x1, y1] = t.bbox;
    // The edge functions stepped across the box from the first pixel's centre, and
    // each sample's as the centre's plus a constant: the plain rule
    // (`setup::sample_mask` and `setup::centre_edges` at every pixel) in integers,
    // so the same values (`masked_walk_is_the_plain_rule`).
    let (cx, cy) = (i64::from(x0) * SUBPIXEL + HALF_PIXEL, i64::from(y0) * SUBPIXEL + HALF_PIXEL);
    let e = [0, 1, 2].map(|k| edge(t, k, cx, cy));
    // sample j's three edge values less the centre's (no allocation a triangle)
    let mut deltas = [[0i64; 3]; 8];
    for (d, &(ox, oy)) in deltas.iter_mut().zip(offsets) {
        *d = e.map(|(_, step_x, step_y, _)| step_x / SUBPIXEL * ox + step_y / SUBPIXEL * oy);
    }
    let at_sample = &deltas[..offsets.len()];
    // each edge's least and greatest sample offset: a pixel every sample of which lies
    // outside one edge has no fragment, one every sample of which lies inside all three is
    // covered whole, both decided without testing the samples one by one (the same masks)
    let reach = |pick: fn(i64, i64) -> i64| {
        [0, 1, 2].map(|k| at_sample.iter().map(|d| d[k]).reduce(pick).unwrap_or(0))
    };
    let (least, most) = (reach(i64::min), reach(i64::max));
    let full = ((1u16 << offsets.len()) - 1) as u8;
    let mut row = e.map(|e| e.0);
    for y in y0..=y1 {
        if y >= rows[0] && y <= rows[1] {
            let mut c = row;
            for x in x0..=x1 {
                let mut mask = 0u8;
                if keep(y * width + x) && (0..3).all(|k| c[k] + most[k] > e[k].3) {
                    if (0..3).all(|k| c[k] + least[k] > e[k].3) {
                        mask = full;
                    } else {
                        for (j, d) in at_sample.iter().enumerate() {
                            let inside = (0..3).all(|k| c[k] + d[k] > e[k].3);
                            mask |= u8::from(inside) << j;
                        }
                    }
                }
                if mask != 0 {
                    visit(x, y, c, mask);
                }
                for k in 0..3 {
                    c[k] += e[k].1;
                }
            }
        }
        for k in 0..3 {
            row[k] += e[k].2;
        }
    }
}

/// Lanes of the vectorized coverage test: one row of [`LANES`] pixels at a time.
const LANES: usize = 8;
/// Largest extent (in sub-pixel units, each axis) of a triangle [`walk_small`] takes: every edge
/// function at a pixel centre inside the triangle's box is then below `2·SMALL_EXTENT² = 2^29`
/// in magnitude, so it fits an `i32` exactly.
const SMALL_EXTENT: i32 = 1 << 14;

/// The edge functions of a triangle at most [`SMALL_EXTENT`] across at the centre of its box's
/// top-left pixel, with their steps, in 32-bit form (exact: see [`SMALL_EXTENT`]); made once per
/// frame with the bins, so a pass does no 64-bit arithmetic for such a triangle.
#[derive(Clone, Copy, Debug, Default)]
struct SmallEdges {
    /// The triangle's box (a copy of [`Triangle::bbox`], so the traversal reads only this).
    bbox: [u32; 4],
    /// Whether the triangle is small; the rest is meaningful only then.
    small: bool,
    origin: [i32; 3],
    step_x: [i32; 3],
    step_y: [i32; 3],
    above: [i32; 3],
    /// What the fragments' depth needs ([`DepthPlane`]), and the primitive id: with these a
    /// depth-only pass reads nothing else of the triangle.
    plane: DepthPlane,
    prim: u32,
}

impl SmallEdges {
    fn new(t: &Triangle) -> SmallEdges {
        let extent = |v: [i32; 3]| v[0].max(v[1]).max(v[2]) - v[0].min(v[1]).min(v[2]);
        if extent(t.x) > SMALL_EXTENT || extent(t.y) > SMALL_EXTENT {
            return SmallEdges {
                bbox: t.bbox,
                plane: DepthPlane::new(t),
                prim: t.prim,
                ..SmallEdges::default()
            };
        }
        let [x0, y0, _, _] = t.bbox;
        let (px, py) = (i64::from(x0) * SUBPIXEL + HALF_PIXEL, i64::from(y0) * SUBPIXEL + HALF_PIXEL);
        let edges = [0, 1, 2].map(|k| edge(t, k, px, py));
        // The value within ±2^29 (the pixel is in the box), the steps within ±2^22.
        SmallEdges {
            bbox: t.bbox,
            small: true,
            origin: edges.map(|e| e.0 as i32),
            step_x: edges.map(|e| e.1 as i32),
            step_y: edges.map(|e| e.2 as i32),
            above: edges.map(|e| e.3 as i32),
            plane: DepthPlane::new(t),
            prim: t.prim,
        }
    }
}

/// Visits the covered pixels of `t` inside `rect` (within its box) as [`walk`] does (same pixels,
/// same order, same edge values): small triangles by [`walk_small`], the others by the span walk.
#[inline]
fn walk_tile(t: &Triangle, edges: &SmallEdges, rect: [u32; 4], visit: impl FnMut(u32, u32, [i64; 3])) {
    if edges.small {
        walk_small(edges, [edges.bbox[0], edges.bbox[1]], rect, visit);
    } else {
        walk(t, rect, visit);
    }
}

/// [`walk_tile`] behind the cut's tiles where `skip` has them: a small triangle whose rect lies
/// behind the opaque depth in every tile it reaches into ([`TileSkip::small_behind`]) is walked
/// for its count alone, a larger one skips the pieces of its spans that lie behind their tile's
/// ([`walk_spans`]). Returns the
/// covered pixels skipped (not visited), counted occluded ([`TileSkip::count`]) by the caller.
#[inline]
fn walk_tile_skipping(
    t: &Triangle,
    edges: &SmallEdges,
    rect: [u32; 4],
    skip: Option<&TileSkip<'_>>,
    visit: impl FnMut(u32, u32, [i64; 3]),
) -> u64 {
    let Some(tiles) = skip else {
        walk_tile(t, edges, rect, visit);
        return 0;
    };
    if !edges.small {
        return walk_spans(t, rect, Some((tiles, DepthBound::new(&edges.plane))), visit);
    }
    if rect[0] > rect[2] || rect[1] > rect[3] || !tiles.small_behind(edges, rect) {
        walk_small(edges, [edges.bbox[0], edges.bbox[1]], rect, visit);
        return 0;
    }
    let mut skipped = 0u64;
    walk_small(edges, [edges.bbox[0], edges.bbox[1]], rect, |_, _, _| skipped += 1);
    skipped
}

/// [`walk`] for a triangle at most [`SMALL_EXTENT`] across, whose box starts at pixel `origin`:
/// the edge functions of [`LANES`] pixels of a row are tested at once, in 32-bit lanes
/// ([`wide::i32x8`]: SSE2 has 32-bit adds and compares, not 64-bit ones). The rule is
/// [`edge`]'s, unchanged: wherever a pixel lies in the triangle's box its lane holds the 64-bit
/// edge function exactly (wrapping arithmetic is exact modulo 2^32, and the true value fits);
/// lanes past `rect` (which may wrap) are masked off before they are read.
///
/// The test `e > above` (`above` is −1 or 0) is `e − (above + 1) ≥ 0`, so the lanes hold the
/// edge functions less `above + 1` and a pixel is covered where the OR of its three lanes has
/// the sign bit clear: an add and an OR per edge, then the sign bits as a mask in one
/// instruction (`movmskps`).
#[inline]
fn walk_small(s: &SmallEdges, origin: [u32; 2], rect: [u32; 4], mut visit: impl FnMut(u32, u32, [i64; 3])) {
    let [x0, y0, x1, y1] = rect;
    if x0 > x1 || y0 > y1 {
        return;
    }
    let bias: [i32; 3] = std::array::from_fn(|k| s.above[k] + 1);
    let (dx, dy) = ((x0 - origin[0]) as i32, (y0 - origin[1]) as i32);
    let mut row: [i32; 3] = std::array::from_fn(|k| {
        s.origin[k]
            .wrapping_add(s.step_x[k].wrapping_mul(dx))
            .wrapping_add(s.step_y[k].wrapping_mul(dy))
            .wrapping_sub(bias[k])
    });
    // lane n of edge k steps n pixels right: by adds, as SSE2 has no 32-bit vector multiply
    let offsets: [i32x8; 3] = std::array::from_fn(|k| {
        let step = s.step_x[k];
        let mut lanes = [0i32; LANES];
        for n in 1..LANES {
            lanes[n] = lanes[n - 1].wrapping_add(step);
        }
        i32x8::new(lanes)
    });
    let stride: [i32; 3] = std::array::from_fn(|k| s.step_x[k].wrapping_mul(LANES as i32));
    let width = x1 - x0 + 1;
    for y in y0..=y1 {
        let mut base = row;
        let mut c = 0u32;
        while c < width {
            let sign = (i32x8::splat(base[0]) + offsets[0])
                | (i32x8::splat(base[1]) + offsets[1])
                | (i32x8::splat(base[2]) + offsets[2]);
            let outside = sign.move_mask() as u32;
            let left = width - c;
            let valid = if left >= LANES as u32 { (1u32 << LANES) - 1 } else { (1u32 << left) - 1 };
            let mut mask = !outside & valid;
            while mask != 0 {
                let n = mask.trailing_zeros();
                mask &= mask - 1;
                let e: [i64; 3] = std::array::from_fn(|k| {
                    i64::from(base[k].wrapping_add(s.step_x[k].wrapping_mul(n as i32)).wrapping_add(bias[k]))
                });
                visit(x0 + c + n, y, e);
            }
            c += LANES as u32;
            for k in 0..3 {
                base[k] = base[k].wrapping_add(stride[k]);
            }
        }
        for (r, step) in row.iter_mut().zip(s.step_y) {
            *r = r.wrapping_add(step);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicU32, Ordering};

    use glam::{Mat4, Vec2, Vec3, Vec4};
    use oit_core::{Camera, Instance, Mesh, Object, Scene, Settings, Shading, Texture, Wrap};

    use oit_core::setup::covers;

    use super::*;

    const W: u32 = 96;
    const H: u32 = 80;

    fn settings(width: u32, height: u32) -> Settings {
        Settings { width, height, ..Settings::default() }
    }

    fn camera(width: u32, height: u32) -> Camera {
        Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 60.0, width as f32 / height as f32, 0.5, 20.0)
    }

    /// The world point that lands at screen position (x, y) in pixels, NDC depth z.
    fn unproject(cam: &Camera, width: u32, height: u32, x: f32, y: f32, z: f32) -> Vec3 {
        let ndc = Vec3::new(x / width as f32 * 2.0 - 1.0, 1.0 - y / height as f32 * 2.0, z);
        cam.view_proj().inverse().project_point3(ndc)
    }

    fn screen_mesh(
        cam: &Camera,
        width: u32,
        height: u32,
        pts: &[(f32, f32)],
        indices: Vec<[u32; 3]>,
    ) -> Mesh {
        let positions = pts.iter().map(|&(x, y)| unproject(cam, width, height, x, y, 0.5)).collect();
        Mesh::new("screen", positions, indices)
    }

    fn scene_of(meshes: Vec<Mesh>) -> Scene {
        Scene::from_meshes("test", meshes, Vec4::new(0.8, 0.4, 0.2, 0.5))
    }

    /// Fragments per pixel of one pass.
    fn coverage(r: &Rasterizer) -> Vec<u32> {
        let counts: Vec<AtomicU32> = (0..r.width() * r.height()).map(|_| AtomicU32::new(0)).collect();
        r.for_each_fragment(|f| {
            counts[f.pixel as usize].fetch_add(1, Ordering::Relaxed);
        });
        counts.into_iter().map(AtomicU32::into_inner).collect()
    }

    type Key = (u32, u32, u32, [u32; 4], [u32; 3]);

    /// A fragment bit for bit: pixel, primitive id, depth, colour, normal.
    fn key(f: &oit_core::setup::Fragment) -> Key {
        (
            f.pixel,
            f.prim,
            f.depth.to_bits(),
            f.color.to_array().map(f32::to_bits),
            f.normal.to_array().map(f32::to_bits),
        )
    }

    /// The keys of a pass's fragments in the order it hands them out on `pool`, and the count it
    /// returns; each fragment must come with its colour made ahead exactly where `ahead`.
    fn keys_in_order(
        pool: &rayon::ThreadPool,
        ahead: bool,
        pass: impl FnOnce(&(dyn Fn(&Fragment<'_>) + Sync)) -> u64 + Send,
    ) -> (u64, Vec<Key>) {
        let all = Mutex::new(Vec::new());
        let sink = |f: &Fragment<'_>| {
            assert_eq!(f.color.is_some(), ahead);
            all.lock().unwrap().push(key(&f.full()));
        };
        let n = pool.install(|| pass(&sink));
        (n, all.into_inner().unwrap())
    }

    /// The masked walk steps the edge functions across each box; the plain rule evaluates
    /// `setup::sample_mask` and `setup::centre_edges` afresh at every pixel. Same fragments, masks
    /// and depths, bit for bit, at 4 and 8 samples, over triangles large, thin and smaller than a
    /// pixel, both windings. Mutation: a sample offset measured from the pixel's corner instead of
    /// its centre fails it.
    #[test]
    fn masked_walk_is_the_plain_rule() {
        let cam = camera(W, H);
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as f32 / (1u64 << 31) as f32
        };
        let mut pts = Vec::new();
        let mut indices = Vec::new();
        for i in 0..300u32 {
            let scale = [0.3, 3.0, 40.0][i as usize % 3];
            let (cx, cy) = (next() * W as f32, next() * H as f32);
            for _ in 0..3 {
                pts.push((cx + (next() - 0.5) * scale, cy + (next() - 0.5) * scale));
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let scene = scene_of(vec![screen_mesh(&cam, W, H, &pts, indices)]);
        for samples in [4, 8] {
            let s = Settings { samples, ..settings(W, H) };
            let r = Rasterizer::new(&scene, &cam, &s);
            let walked = Mutex::new(Vec::new());
            let n = r.for_each_masked_fragment(samples, |f, mask| {
                walked.lock().unwrap().push((f.pixel, f.prim, mask, f.depth.to_bits()));
            });
            let mut walked = walked.into_inner().unwrap();
            let mut plain = Vec::new();
            for (t, e) in r.setup.triangles.iter().zip(&r.edges) {
                let [x0, y0, x1, y1] = t.bbox;
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let mask = oit_core::setup::sample_mask(t, x, y, samples);
                        if mask != 0 {
                            let b = e.plane.barycentrics(oit_core::setup::centre_edges(t, x, y));
                            plain.push((y * W + x, e.prim, mask, e.plane.depth(b).to_bits()));
                        }
                    }
                }
            }
            walked.sort_unstable();
            plain.sort_unstable();
            assert_eq!(n as usize, walked.len());
            assert!(plain.len() > 1000 && plain.iter().any(|f| f.2 != oit_core::msaa::full_mask(samples)));
            assert_eq!(walked, plain, "{samples} samples");
        }
    }

    fn sorted_fragments(r: &Rasterizer) -> Vec<Key> {
        sorted_fragments_with(r, Shade::OnDemand)
    }

    fn sorted_fragments_with(r: &Rasterizer, shade: Shade) -> Vec<Key> {
        let all = Mutex::new(Vec::new());
        r.for_each_fragment_with(shade, |f| {
            // Scatter shades ahead where asked; Tiled always on demand
            let ahead = shade == Shade::Color && r.mode() == RasterMode::Scatter;
            assert_eq!(f.color.is_some(), ahead, "{shade:?} {:?}", r.mode());
            all.lock().unwrap().push(key(&f.full()));
        });
        let mut all = all.into_inner().unwrap();
        all.sort_unstable();
        all
    }

    /// Inside the convex polygon `pts` (either winding) by more than `margin` pixels.
    fn inside_convex(pts: &[(f32, f32)], x: f64, y: f64, margin: f64) -> bool {
        let n = pts.len();
        let mut sign = 0.0;
        for i in 0..n {
            let (ax, ay) = (f64::from(pts[i].0), f64::from(pts[i].1));
            let (bx, by) = (f64::from(pts[(i + 1) % n].0), f64::from(pts[(i + 1) % n].1));
            let len = ((bx - ax).powi(2) + (by - ay).powi(2)).sqrt();
            let d = ((bx - ax) * (y - ay) - (by - ay) * (x - ax)) / len;
            if sign == 0.0 {
                sign = d.signum();
            }
            if d * sign <= margin {
                return false;
            }
        }
        true
    }

    /// Every pixel strictly inside `outline` covered once, none twice, none outside.
    fn assert_watertight(mesh: Mesh, outline: &[(f32, f32)]) {
        let scene = scene_of(vec![mesh]);
        for mode in [RasterMode::Scatter, RasterMode::Tiled] {
            let r = Rasterizer::new(&scene, &camera(W, H), &settings(W, H)).with_mode(mode);
            let counts = coverage(&r);
            for y in 0..H {
                for x in 0..W {
                    let c = counts[(y * W + x) as usize];
                    let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                    assert!(c <= 1, "pixel ({x}, {y}) covered {c} times ({mode:?})");
                    // Snapping moves a vertex by at most 1/512 pixel; 0.01 keeps clear of it.
                    if inside_convex(outline, cx, cy, 0.01) {
                        assert_eq!(c, 1, "pixel ({x}, {y}) inside but not covered ({mode:?})");
                    }
                    if !inside_convex(outline, cx, cy, -0.01) {
                        assert_eq!(c, 0, "pixel ({x}, {y}) outside but covered ({mode:?})");
                    }
                }
            }
        }
    }

    /// The tile skip behind the opaque depth ([`TileSkip`]) hands the shader the same fragments,
    /// bit for bit, returns the same fragment count and counts the same fragments occluded as
    /// the per-fragment test alone: on walled scenes of large triangles (planes, the span walk)
    /// and of small ones (spheres, the lanes), images whose sizes are no multiple of the tiles',
    /// every pass over the cut (each the frame's counting pass) on this host's kernel and on the
    /// portable one; and the skip takes fragments off the walks there.
    #[test]
    fn tile_skip_changes_nothing() {
        // the planes' triangles larger than a small one at this size, the spheres' small
        for (name, w, h) in [("wall:0.4:planes:8", 403, 301), ("wall:0.5:spheres:3", 203, 150)] {
            let scene = oit_core::builtin_scene(name).unwrap().unwrap();
            let settings = settings(w, h);
            let camera = Camera::orbit_scene(&scene, oit_core::View::default(), w as f32 / h as f32).unwrap();
            let layers = scene.layers(None);
            let opaque = crate::opaque::draw(layers.opaque.as_ref().unwrap(), &camera, &settings);
            let run = |skip: bool, pass: usize| {
                let mut r = Rasterizer::new(&layers.transparent, &camera, &settings);
                r.cut_at(Some(opaque.depth.clone()));
                r.skip_tiles(skip);
                let seen = Mutex::new(Vec::new());
                let f = |frag: &Fragment<'_>| seen.lock().unwrap().push(key(&frag.full()));
                let n = match pass {
                    0 => r.for_each_fragment(f),
                    1 => r.for_each_shaded_fragment(f),
                    2 => r.for_each_fragment_in_order(Shade::Color, f),
                    3 => r.for_each_fragment_by_band(Shade::OnDemand, |_| &f).iter().sum(),
                    4 => r.for_each_fragment_on(Kernel::Portable, Shade::Color, f),
                    _ => r.for_each_fragment_on(Kernel::Portable, Shade::OnDemand, f),
                };
                let mut seen = seen.into_inner().unwrap();
                seen.sort_unstable();
                (seen, n, r.occluded())
            };
            for pass in 0..6 {
                let without = run(false, pass);
                // (other tests' cuts may add to the count as well: the check only needs it to grow)
                let before = SKIPPED.load(std::sync::atomic::Ordering::Relaxed);
                let with = run(true, pass);
                let skipped = SKIPPED.load(std::sync::atomic::Ordering::Relaxed) - before;
                assert!(!without.0.is_empty() && without.2.is_some_and(|o| o > 0), "{name}: nothing to test");
                assert!(skipped > 0, "{name}, pass {pass}: the skip took nothing off");
                assert_eq!(with.1, without.1, "{name}, pass {pass}: fragments");
                assert_eq!(with.2, without.2, "{name}, pass {pass}: occluded");
                assert!(with.0 == without.0, "{name}, pass {pass}: the fragments that reach the shader");
            }
        }
    }

    #[test]
    fn quad_diagonal_covers_each_pixel_once() {
        let cam = camera(W, H);
        // Off-grid corners; and a quad whose diagonal runs through pixel centres exactly.
        for pts in [
            [(10.3, 12.7), (60.9, 9.1), (57.2, 65.6), (8.8, 61.4)],
            [(10.5, 10.5), (40.3, 9.7), (60.5, 60.5), (9.2, 41.1)],
            [(20.5, 5.5), (70.5, 5.5), (70.5, 50.5), (20.5, 50.5)],
        ] {
            let mesh = screen_mesh(&cam, W, H, &pts, vec![[0, 1, 2], [0, 2, 3]]);
            assert_watertight(mesh, &pts);
            // The other diagonal, and the opposite winding.
            let mesh = screen_mesh(&cam, W, H, &pts, vec![[1, 2, 3], [3, 0, 1]]);
            assert_watertight(mesh, &pts);
            let mesh = screen_mesh(&cam, W, H, &pts, vec![[0, 2, 1], [0, 3, 2]]);
            assert_watertight(mesh, &pts);
        }
    }

    #[test]
    fn fan_covers_each_pixel_once() {
        let cam = camera(W, H);
        // Centres on a pixel centre, on a pixel corner, and off-grid; rims with horizontal and
        // vertical edges through pixel centres and with off-grid vertices.
        for centre in [(40.5, 40.5), (40.0, 40.0), (41.37, 38.91)] {
            for (radius, phase, n) in
                [(25.0f32, 0.0f32, 8), (30.3, 0.37, 7), (20.0, 0.0, 4), (33.3, 0.11, 13)]
            {
                let mut pts = vec![centre];
                for i in 0..n {
                    let a = phase + i as f32 / n as f32 * std::f32::consts::TAU;
                    // Vertices on a pixel-centre grid when phase is 0, so rim and spokes hit
                    // centres exactly.
                    let (x, y) = (centre.0 + radius * a.cos(), centre.1 + radius * a.sin());
                    pts.push(if phase == 0.0 { (x.floor() + 0.5, y.floor() + 0.5) } else { (x, y) });
                }
                let indices = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
                let mesh = screen_mesh(&cam, W, H, &pts, indices);
                assert_watertight(mesh, &pts[1..]);
            }
        }
    }

    #[test]
    fn jittered_grid_covers_each_pixel_once() {
        let cam = camera(W, H);
        let (nx, ny) = (9u32, 7u32);
        let (x0, y0, x1, y1) = (6.5f32, 4.25f32, 90.0f32, 75.5f32);
        let mut rng = Lcg(7);
        let mut pts = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                let mut x = x0 + (x1 - x0) * i as f32 / nx as f32;
                let mut y = y0 + (y1 - y0) * j as f32 / ny as f32;
                if i > 0 && i < nx && j > 0 && j < ny {
                    x += rng.next_f32() * 6.0 - 3.0;
                    y += rng.next_f32() * 6.0 - 3.0;
                    if rng.next_f32() < 0.3 {
                        (x, y) = (x.floor() + 0.5, y.floor() + 0.5);
                    }
                }
                pts.push((x, y));
            }
        }
        let mut indices = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let v = j * (nx + 1) + i;
                let (a, b, c, d) = (v, v + 1, v + nx + 2, v + nx + 1);
                if (i + j) % 2 == 0 {
                    indices.extend([[a, b, c], [a, c, d]]);
                } else {
                    indices.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        let mesh = screen_mesh(&cam, W, H, &pts, indices);
        assert_watertight(mesh, &[(x0, y0), (x1, y0), (x1, y1), (x0, y1)]);
    }

    #[test]
    fn near_plane_crossing_is_clipped_not_dropped() {
        let cam = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 60.0, 1.0, 0.1, 10.0);
        let meshes = vec![
            // One vertex behind the eye, two in front (the plane misses the eye, so it is not seen
            // edge-on).
            Mesh::new(
                "one behind",
                vec![Vec3::new(-1.0, -1.0, -2.0), Vec3::new(1.0, -1.0, -2.0), Vec3::new(0.0, 2.0, 1.0)],
                vec![[0, 1, 2]],
            ),
            // Two behind, one in front.
            Mesh::new(
                "two behind",
                vec![Vec3::new(-1.0, 0.5, 2.0), Vec3::new(1.0, 0.5, 2.0), Vec3::new(0.0, 0.2, -3.0)],
                vec![[0, 1, 2]],
            ),
        ];
        for mesh in meshes {
            let r = Rasterizer::new(&scene_of(vec![mesh]), &cam, &settings(64, 64));
            assert!(r.fragment_count() > 50, "{} fragments", r.fragment_count());
            let n = AtomicU32::new(0);
            r.for_each_fragment(|f| {
                assert!((0.0..=1.0).contains(&f.depth), "depth {}", f.depth);
                assert_eq!(f.prim, 0);
                n.fetch_add(1, Ordering::Relaxed);
            });
            assert_eq!(u64::from(n.into_inner()), r.fragment_count());
        }
    }

    #[test]
    fn degenerate_and_offscreen_triangles_produce_nothing() {
        let cam = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 60.0, 1.0, 0.1, 10.0);
        let p = Vec3::new(0.1, 0.2, -3.0);
        let cases = [
            ("zero area", vec![p, p, p]),
            ("collinear", vec![p, p + Vec3::new(0.3, 0.1, 0.0), p + Vec3::new(0.6, 0.2, 0.0)]),
            ("repeated vertex", vec![p, p + Vec3::X, p + Vec3::X]),
            (
                "left of the view",
                vec![Vec3::new(-50.0, 0.0, -3.0), Vec3::new(-40.0, 1.0, -3.0), Vec3::new(-45.0, -1.0, -3.0)],
            ),
            (
                "behind the camera",
                vec![Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 0.5)],
            ),
            (
                "beyond far",
                vec![Vec3::new(-1.0, -1.0, -11.0), Vec3::new(1.0, -1.0, -11.0), Vec3::new(0.0, 1.0, -12.0)],
            ),
            (
                "non-finite",
                vec![Vec3::new(f32::NAN, 0.0, -3.0), Vec3::new(1.0, -1.0, -3.0), Vec3::new(0.0, 1.0, -3.0)],
            ),
        ];
        for (name, positions) in cases {
            let mesh = Mesh {
                name: name.into(),
                normals: vec![Vec3::Z; 3],
                positions,
                colors: None,
                uvs: None,
                indices: vec![[0, 1, 2]],
            };
            let scene = scene_of(vec![mesh]);
            for r in [
                Rasterizer::new(&scene, &cam, &settings(64, 64)),
                Rasterizer::new(&scene, &cam, &settings(64, 64)).with_mode(RasterMode::Scatter),
            ] {
                assert_eq!(r.fragment_count(), 0, "{name}");
                r.for_each_fragment(|f| panic!("{name}: fragment at {}", f.pixel));
            }
        }
        // Bad references and sizes are skipped, not a panic.
        let mut scene = scene_of(vec![Mesh::new("bad", vec![p], vec![[0, 1, 2]])]);
        scene.instances.push(Instance { object: 9, transform: Mat4::IDENTITY });
        assert_eq!(Rasterizer::new(&scene, &cam, &settings(0, 0)).fragment_count(), 0);
        assert_eq!(Rasterizer::new(&scene, &cam, &settings(64, 64)).fragment_count(), 0);
        assert_eq!(Rasterizer::bounding_boxes(&scene, &cam, &settings(0, 7)).fragment_count(), 0);
    }

    /// A deterministic pseudo-random source for fixtures.
    struct Lcg(u64);

    impl Lcg {
        fn next_f32(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Triangles of all sizes around the origin, some crossing the near plane, vertex colours on one
    /// mesh, two instances of another.
    fn random_scene() -> Scene {
        let mut rng = Lcg(42);
        let mut meshes = Vec::new();
        for m in 0..3 {
            let mut positions = Vec::new();
            let mut indices = Vec::new();
            for t in 0..60u32 {
                let centre = Vec3::new(
                    rng.next_f32() * 4.0 - 2.0,
                    rng.next_f32() * 4.0 - 2.0,
                    rng.next_f32() * 5.0 - 2.0,
                );
                let size = if t % 10 == 0 { 4.0 } else { 0.4 };
                for _ in 0..3 {
                    positions.push(
                        centre
                            + Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5)
                                * size,
                    );
                }
                indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
            }
            let mut mesh = Mesh::new(format!("m{m}"), positions, indices);
            if m == 1 {
                mesh.colors = Some(
                    (0..mesh.positions.len())
                        .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()))
                        .collect(),
                );
            }
            meshes.push(mesh);
        }
        let mut scene = scene_of(meshes);
        scene.objects.push(Object::new("again", 0, Vec4::new(0.1, 0.9, 0.3, 0.7)));
        scene.instances.push(Instance {
            object: 3,
            transform: Mat4::from_rotation_y(0.7) * Mat4::from_scale(Vec3::new(1.0, 2.0, 0.5)),
        });
        scene
    }

    #[test]
    fn modes_and_thread_counts_agree() {
        let scene = random_scene();
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 70.0, 200.0 / 150.0, 0.3, 8.0);
        for shading in [Shading::Headlight, Shading::Vertex, Shading::Flat, Shading::Normal] {
            let s = Settings { shading, ..settings(200, 150) };
            let run = |threads: usize, mode: RasterMode| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| {
                    let r = Rasterizer::new(&scene, &cam, &s).with_mode(mode);
                    (sorted_fragments(&r), r.fragment_count())
                })
            };
            let (scatter, count) = run(4, RasterMode::Scatter);
            assert!(scatter.len() > 1000, "{} fragments", scatter.len());
            assert_eq!(scatter.len() as u64, count);
            assert_eq!(run(4, RasterMode::Tiled).0, scatter);
            assert_eq!(run(1, RasterMode::Scatter).0, scatter);
            assert_eq!(run(1, RasterMode::Tiled).0, scatter);
            // All four objects show up, each with its own ids.
            let bases = scene.primitive_bases().0;
            for base in bases {
                assert!(scatter.iter().any(|k| (base..base + 60).contains(&k.1)));
            }
        }
    }

    /// A rasterizer set up again ([`Rasterizer::rebuild`], the persistent renderer's path) for a
    /// sequence of cameras, sizes, windows, shadings and scenes gives what a new one gives: the
    /// same triangles, words and fragments (shaded on demand and ahead), in both modes. The
    /// sequence grows and shrinks the triangle count, and one scene's mesh spans several setup
    /// chunks and copy pieces. Mutation caught: storage not cleared between frames (the previous
    /// frame's triangles kept), bins or the fragment count kept. (A frame coloured under the
    /// wrong shading is caught by `fragments_are_the_setups`, which checks colours against
    /// oit-core's.)
    #[test]
    fn rebuild_is_new() {
        // the knot's 18,432 triangles: 18 setup chunks
        let mut meshes = random_scene().meshes;
        meshes.extend(oit_core::load_scene("knot").expect("built in").meshes);
        let with_knot = scene_of(meshes);
        let scenes = [random_scene(), scene_of(vec![random_scene().meshes[0].clone()]), with_knot];
        let views = [
            (Vec3::new(0.0, 0.0, 2.5), 120u32, 90u32, None, Shading::Headlight),
            (Vec3::new(1.5, 0.5, 1.0), 64, 64, None, Shading::Headlight),
            (Vec3::new(0.0, 0.3, 2.5), 100, 100, None, Shading::Headlight),
            (
                Vec3::new(0.0, 0.2, 2.5),
                50,
                40,
                Some(oit_core::Region { x: 30, y: 20, full_width: 120, full_height: 90 }),
                // after a larger scene's headlight frame
                Shading::Flat,
            ),
            (Vec3::new(0.2, 0.1, 0.9), 200, 150, None, Shading::Headlight),
            (Vec3::new(0.0, 0.0, 2.5), 90, 90, None, Shading::Headlight),
        ];
        for mode in [RasterMode::Scatter, RasterMode::Tiled] {
            let mut kept: Option<Rasterizer> = None;
            for (i, (eye, w, h, region, shading)) in views.iter().enumerate() {
                let scene = &scenes[i % scenes.len()];
                let cam = Camera::look_at(*eye, Vec3::ZERO, 70.0, *w as f32 / *h as f32, 0.1, 8.0);
                let s = Settings { region: *region, shading: *shading, ..settings(*w, *h) };
                let fresh = Rasterizer::new(scene, &cam, &s).with_mode(mode);
                let r = match kept.take() {
                    Some(mut r) => {
                        r.rebuild(scene, &cam, &s);
                        r
                    }
                    None => Rasterizer::new(scene, &cam, &s).with_mode(mode),
                };
                assert_eq!(r.mode(), mode);
                assert!(fresh.triangle_count() > 10, "view {i}: {} triangles", fresh.triangle_count());
                assert_eq!(r.triangle_words(), fresh.triangle_words(), "view {i} {mode:?}");
                assert_eq!(r.fragment_count(), fresh.fragment_count(), "view {i} {mode:?}");
                assert_eq!(sorted_fragments(&r), sorted_fragments(&fresh), "view {i} {mode:?}");
                assert_eq!(
                    sorted_fragments_with(&r, Shade::Color),
                    sorted_fragments_with(&fresh, Shade::Color),
                    "view {i} {mode:?}"
                );
                kept = Some(r);
            }
        }
    }

    /// What every traversal must give: [`TriangleSetup::fragment`] at each pixel of
    /// `pixels(triangle)` (an inclusive `[x0, y0, x1, y1]`) that the per-pixel rule covers, of
    /// every triangle of `r`, sorted.
    fn setup_fragments(r: &Rasterizer, pixels: impl Fn(&Triangle) -> [u32; 4]) -> Vec<Key> {
        let mut expected = Vec::new();
        for t in &r.setup().triangles {
            let [x0, y0, x1, y1] = pixels(t);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    if let Some(e) = covers(t, x, y) {
                        expected.push(key(&r.setup().fragment(t, x, y, e)));
                    }
                }
            }
        }
        expected.sort_unstable();
        expected
    }

    /// The fragments of a pass, in both modes, under every shading, shaded on demand and ahead,
    /// against [`TriangleSetup::fragment`] at every pixel the per-pixel rule covers: the same
    /// set, bit for bit (depth at once, colour on demand or in lanes, normal on demand).
    #[test]
    fn fragments_are_the_setups() {
        let scene = random_scene();
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 70.0, 1.0, 0.3, 8.0);
        for shading in [Shading::Headlight, Shading::Vertex, Shading::Flat, Shading::Normal] {
            let s = Settings { shading, ..settings(90, 90) };
            let r = Rasterizer::new(&scene, &cam, &s);
            // every pixel of the image, not only the boxes: no fragment may lie outside them
            let expected = setup_fragments(&r, |_| [0, 0, 89, 89]);
            assert!(expected.len() > 1000, "{} fragments", expected.len());
            for mode in [RasterMode::Scatter, RasterMode::Tiled] {
                let r = Rasterizer::new(&scene, &cam, &s).with_mode(mode);
                for shade in [Shade::OnDemand, Shade::Color] {
                    assert_eq!(sorted_fragments_with(&r, shade), expected, "{shading:?} {mode:?} {shade:?}");
                }
            }
        }
    }

    /// Triangles that probe the shaded Scatter kernels' corners, in pixels on a 128×96 screen: tiny
    /// ones of every box width and height to 12 (each layout of the AVX2 walk, and its column
    /// steps), random small ones, slivers, boxes at [`SMALL_EXTENT`] and one sub-pixel past it
    /// (vertices on the 1/256 grid, so they snap exactly there), triangles cut by each border of
    /// the image (clamped boxes), and some reaching into the guard band (the span walk).
    fn kernel_probe_meshes(cam: &Camera) -> Vec<Mesh> {
        let (w, h) = (128, 96);
        let mut rng = Lcg(12);
        let mut grid = |scale: f32| (rng.next_f32() * scale * 256.0).round() / 256.0;
        let mut pts = Vec::new();
        let quad = |pts: &mut Vec<(f32, f32)>, x: f32, y: f32, dx: f32, dy: f32| {
            pts.extend([(x, y), (x + dx, y), (x + dx, y + dy), (x, y), (x + dx, y + dy), (x, y + dy)]);
        };
        // every box size to 12×12, at pixel-centre and off-grid offsets
        for bw in 1..=12 {
            for bh in 1..=12 {
                let (x, y) = (1.0 + (bw * 10) as f32 % 120.0, (bh * 7) as f32 % 88.0);
                let off = if (bw + bh) % 2 == 0 { 0.5 } else { 0.2 };
                quad(&mut pts, x + off, y + off, bw as f32 - 0.3, bh as f32 - 0.3);
            }
        }
        // random small triangles, some on pixel centres
        for i in 0..400 {
            let (cx, cy) = (grid(132.0) - 2.0, grid(100.0) - 2.0);
            let size = [0.6, 1.5, 3.0, 7.0][i % 4];
            for _ in 0..3 {
                let (mut x, mut y) = (cx + (grid(1.0) - 0.5) * size, cy + (grid(1.0) - 0.5) * size);
                if i % 5 == 0 {
                    (x, y) = (x.floor() + 0.5, y.floor() + 0.5);
                }
                pts.push((x, y));
            }
        }
        // slivers
        for i in 0..20 {
            let (x, y) = (grid(100.0), grid(90.0));
            let thin = 0.05 + 0.05 * i as f32;
            pts.extend([(x, y), (x + 30.0, y + thin), (x + 15.0, y + thin / 3.0)]);
            pts.extend([(x, y), (x + thin, y + 20.0), (x + thin / 2.0, y + 9.0)]);
        }
        // 64 pixels across (SMALL_EXTENT), then one sub-pixel more, both axes, both windings
        for (i, extent) in [64.0, 64.0 + 1.0 / 256.0, 64.0 - 1.0 / 256.0].into_iter().enumerate() {
            let (x, y) = (3.0 + 20.0 * i as f32 + 0.25, 2.0 + 10.0 * i as f32);
            pts.extend([(x, y), (x + extent, y + 3.0), (x + 5.0, y + extent.min(90.0 - y))]);
            pts.extend([(x, y + 10.0), (x + 2.0, y + 11.0), (x + extent, y + 12.0)]);
            pts.extend([(x, y), (x + 5.0, y + 80.0), (x + extent, y + 3.0)]);
        }
        // cut by the borders: small ones straddling each edge and corner, and large ones
        for (x, y) in [(0.0, 40.0), (128.0, 30.0), (60.0, 0.0), (70.0, 96.0), (0.0, 0.0), (128.0, 96.0)] {
            for size in [2.5f32, 5.0, 11.0] {
                pts.extend([
                    (x - size, y - size * 0.7),
                    (x + size, y - size * 0.2),
                    (x + size * 0.3, y + size),
                ]);
            }
        }
        // into the guard band (clipped there), and across the whole screen
        pts.extend([(-500.0, -300.0), (900.0, 40.0), (50.0, 800.0)]);
        pts.extend([(-9000.0, 20.0), (60.0, -7000.0), (64.3, 50.7)]);
        let n = pts.len() as u32 / 3;
        // depths all over (0, 1), so that a regrouped sum in the depth changes bits
        let positions = pts
            .iter()
            .enumerate()
            .map(|(i, &(x, y))| unproject(cam, w, h, x, y, 0.05 + 0.9 * (i as f32 * 0.618_034).fract()))
            .collect();
        let mut flat =
            Mesh::new("probes", positions, (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect());
        flat.normals = (0..pts.len()).map(|i| Vec3::new(i as f32 % 7.0 - 3.0, 1.0, (i % 3) as f32)).collect();
        let mut colored = flat.clone();
        colored.colors = Some((0..pts.len()).map(|i| Vec3::new((i % 5) as f32 / 4.0, 0.3, 0.9)).collect());
        vec![flat, colored]
    }

    /// [`kernel_probe_meshes`] textured: the flat mesh by a 64×48 texture (repeating across,
    /// mirrored down), the coloured one by a 5×3 texture (clamped across, repeating down), then
    /// the flat mesh again without a texture, so a group of lanes may mix textures and none.
    /// Each triangle's texture coordinates span 0.01 to 10 textures from an origin in [-2, 2]
    /// (every level of both chains, and taps across every border and wrap).
    fn textured_probe(cam: &Camera) -> Scene {
        let mut rng = Lcg(38);
        let mut meshes = kernel_probe_meshes(cam);
        for mesh in &mut meshes {
            let mut uvs = Vec::with_capacity(mesh.positions.len());
            for i in 0..mesh.positions.len() / 3 {
                let span = [0.01, 0.1, 1.0, 10.0][i % 4];
                let origin = Vec2::new(rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0);
                for _ in 0..3 {
                    uvs.push(origin + Vec2::new(rng.next_f32(), rng.next_f32()) * span);
                }
            }
            mesh.uvs = Some(uvs);
        }
        let mut texels = |n: usize| -> Vec<[u8; 4]> {
            (0..n).map(|_| std::array::from_fn(|_| (rng.next_f32() * 256.0) as u8)).collect()
        };
        let textures = vec![
            Texture::new("a", 64, 48, texels(64 * 48), [Wrap::Repeat, Wrap::MirroredRepeat]).unwrap(),
            Texture::new("b", 5, 3, texels(15), [Wrap::ClampToEdge, Wrap::Repeat]).unwrap(),
        ];
        let color = Vec4::new(0.8, 0.4, 0.2, 0.5);
        let objects = vec![
            Object::new("a", 0, color).textured(0),
            Object::new("b", 1, color).textured(1),
            Object::new("plain", 0, color),
        ];
        let instances = (0..3).map(|object| Instance { object, transform: Mat4::IDENTITY }).collect();
        let scene =
            Scene { name: "textured probe".into(), meshes, objects, instances, textures, ..Scene::default() };
        scene.validate().unwrap();
        scene
    }

    /// The shaded Scatter pass of each kernel ([`Kernel`]) against the per-pixel rule and
    /// [`TriangleSetup::fragment`], bit for bit (pixel, primitive id, depth, colour, normal), under
    /// every shading, on [`kernel_probe_meshes`]; the two kernels' fragments in the same order
    /// on one thread; and each kernel's pass that shades on demand giving those fragments in that
    /// order; and the same on the probe textured ([`textured_probe`]). Where the host lacks AVX2
    /// only the portable kernel is checked.
    /// Mutations caught: the AVX2 walk's mask of valid columns one too wide (fragments past the
    /// box, at the image's right border), and its depth's sum regrouped; in the AVX2 texture
    /// lanes, the floor's correction left out, the border's lanes not wrapped, and a lane without
    /// a texture given its neighbour's.
    #[test]
    fn kernels_give_the_setups_fragments() {
        let (w, h) = (128u32, 96u32);
        let cam = camera(w, h);
        let scenes = [scene_of(kernel_probe_meshes(&cam)), textured_probe(&cam)];
        let kernels = if Kernel::detect() == Kernel::Portable {
            eprintln!("no AVX2 on this host: the portable kernel alone");
            vec![Kernel::Portable]
        } else {
            vec![Kernel::Portable, Kernel::detect()]
        };
        let shadings = [Shading::Headlight, Shading::Vertex, Shading::Flat, Shading::Normal];
        for (scene, shading) in scenes.iter().flat_map(|s| shadings.map(|shading| (s, shading))) {
            let s = Settings { shading, ..settings(w, h) };
            let r = Rasterizer::new(scene, &cam, &s);
            let extents: Vec<(i32, bool)> = r
                .setup()
                .triangles
                .iter()
                .map(|t| {
                    let extent = |v: [i32; 3]| v[0].max(v[1]).max(v[2]) - v[0].min(v[1]).min(v[2]);
                    (extent(t.x).max(extent(t.y)), SmallEdges::new(t).small)
                })
                .collect();
            assert!(extents.contains(&(SMALL_EXTENT, true)), "no triangle at the limit");
            assert!(extents.contains(&(SMALL_EXTENT + 1, false)), "none just past it");
            assert!(extents.iter().filter(|e| e.1).count() > 500);
            let expected = setup_fragments(&r, |t| t.bbox);
            assert!(expected.len() > 10_000, "{} fragments", expected.len());
            let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
            let mut orders = Vec::new();
            for &kernel in &kernels {
                let (n, all) =
                    keys_in_order(&one_thread, true, |sink| r.scatter_shaded(kernel, &|f| sink(f), None));
                let what = format!("{}: {shading:?} {kernel:?}", scene.name);
                assert_eq!(n, all.len() as u64, "{what}");
                let mut sorted = all.clone();
                sorted.sort_unstable();
                assert!(sorted == expected, "{what}: not the setup's fragments");
                orders.push(all);
            }
            assert!(
                orders.windows(2).all(|o| o[0] == o[1]),
                "{}, {shading:?}: the kernels' orders differ",
                scene.name
            );
            // the pass that shades on demand: no colour made ahead, the same fragments (made
            // from the barycentrics it hands out) in the same order
            for &kernel in &kernels {
                let (n, all) =
                    keys_in_order(&one_thread, false, |sink| r.scatter_on_demand(kernel, &|f| sink(f)));
                assert_eq!(n, all.len() as u64, "{shading:?} {kernel:?} on demand");
                assert!(
                    all == orders[0],
                    "{shading:?} {kernel:?} on demand: not the shaded pass's fragments"
                );
            }
        }
    }

    /// The multisampled walk of each kernel ([`Rasterizer::masked_task`]: the portable
    /// per-pixel walk and the AVX2 lanes), shaded ahead and on demand, at 4 and 8 samples, on
    /// the kernel probe (triangles at the small walk's limit and just past it, thin, tiny and
    /// both windings) under every shading: each gives the plain rule's fragments
    /// (`setup::sample_mask` and the centre's barycentrics afresh at every pixel), masks, depths,
    /// colours and normals bit for bit; and over half the pixels only (`keep`) the same
    /// fragments of those pixels, counted alike. Where the host lacks AVX2 only the portable
    /// kernel is checked.
    #[test]
    fn masked_kernels_agree() {
        let (w, h) = (128u32, 96u32);
        let cam = camera(w, h);
        let scenes = [scene_of(kernel_probe_meshes(&cam)), textured_probe(&cam)];
        let kernels = if Kernel::detect() == Kernel::Portable {
            eprintln!("no AVX2 on this host: the portable kernel alone");
            vec![Kernel::Portable]
        } else {
            vec![Kernel::Portable, Kernel::detect()]
        };
        let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        for (scene, samples) in scenes.iter().flat_map(|s| [4, 8].map(|samples| (s, samples))) {
            for shading in [Shading::Headlight, Shading::Vertex, Shading::Flat, Shading::Normal] {
                let s = Settings { shading, samples, ..settings(w, h) };
                let r = Rasterizer::new(scene, &cam, &s);
                let mut plain = Vec::new();
                for t in &r.setup.triangles {
                    let [x0, y0, x1, y1] = t.bbox;
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            let mask = oit_core::setup::sample_mask(t, x, y, samples);
                            if mask != 0 {
                                let f = r.setup.fragment(t, x, y, oit_core::setup::centre_edges(t, x, y));
                                plain.push((key(&f), mask));
                            }
                        }
                    }
                }
                plain.sort_unstable();
                let full = oit_core::msaa::full_mask(samples);
                assert!(
                    plain.len() > 10_000 && plain.iter().any(|f| f.1 != full),
                    "{} fragments",
                    plain.len()
                );
                let offsets = sample_offsets(samples);
                let n = r.setup.triangles.len();
                for &kernel in &kernels {
                    for shade in [Shade::OnDemand, Shade::Color] {
                        let what =
                            format!("{}: {samples} samples, {shading:?}, {kernel:?}, {shade:?}", scene.name);
                        for half in [false, true] {
                            let keep = |px: u32| !half || px % 2 == 1;
                            let all = Mutex::new(Vec::new());
                            let walked = one_thread.install(|| {
                                r.masked_task(
                                    kernel,
                                    shade,
                                    0..n,
                                    ALL_ROWS,
                                    &offsets,
                                    (&keep, None),
                                    &|f, mask| {
                                        assert_eq!(
                                            f.color.is_some(),
                                            shade == Shade::Color && kernel != Kernel::Portable
                                        );
                                        all.lock().unwrap().push((key(&f.full()), mask));
                                    },
                                )
                            });
                            let mut all = all.into_inner().unwrap();
                            all.sort_unstable();
                            let expected: Vec<_> = plain.iter().filter(|f| keep(f.0.0)).copied().collect();
                            assert_eq!(walked, all.len() as u64, "{what}, half {half}");
                            assert!(all == expected, "{what}, half {half}: not the plain rule's fragments");
                        }
                    }
                }
            }
        }
    }

    /// [`random_scene`] seen whole by a 128×96 camera: the case of the pass-order tests.
    fn random_view() -> (Scene, Camera, u32, u32) {
        let (w, h) = (128u32, 96u32);
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 70.0, w as f32 / h as f32, 0.3, 8.0);
        (random_scene(), cam, w, h)
    }

    /// The banded pass ([`Rasterizer::for_each_fragment_in_order`]) on each kernel, shaded
    /// ahead and on demand, on 1 and 3 threads (bands of 16 and 8 rows, which cut the large and
    /// the small triangles): the setup's fragments, bit for bit, and each pixel's from one
    /// thread, highest primitive first. Mutations caught: a band's triangles walked in primitive
    /// order (not reversed), the AVX2 walk starting a cut box at its own first row instead of the
    /// band's, and a box's last band left out of the binning.
    #[test]
    fn in_order_pass_gives_each_pixel_its_fragments_highest_first() {
        let (scene, cam, w, h) = random_view();
        let kernels = if Kernel::detect() == Kernel::Portable {
            eprintln!("no AVX2 on this host: the portable kernel alone");
            vec![Kernel::Portable]
        } else {
            vec![Kernel::Portable, Kernel::detect()]
        };
        for shading in [Shading::Headlight, Shading::Vertex] {
            let s = Settings { shading, ..settings(w, h) };
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                // set up and binned on the pool, so the bands are cut for its threads
                let r = pool.install(|| Rasterizer::new(&scene, &cam, &s));
                let expected = setup_fragments(&r, |t| t.bbox);
                assert!(expected.len() > 1000, "{} fragments", expected.len());
                for &kernel in &kernels {
                    for shade in [Shade::Color, Shade::OnDemand] {
                        let what = format!("{shading:?}, {threads} threads, {kernel:?}, {shade:?}");
                        let all = Mutex::new(Vec::new());
                        let n = pool.install(|| {
                            r.in_order(kernel, shade, &|f: &Fragment<'_>| {
                                assert_eq!(f.color.is_some(), shade == Shade::Color, "{what}");
                                let thread = rayon::current_thread_index();
                                all.lock().unwrap().push((key(&f.full()), thread));
                            })
                        });
                        let all = all.into_inner().unwrap();
                        assert_eq!(n, all.len() as u64, "{what}");
                        let mut sorted: Vec<Key> = all.iter().map(|a| a.0).collect();
                        sorted.sort_unstable();
                        assert!(sorted == expected, "{what}: not the setup's fragments");
                        // per pixel, in arrival order: one thread, descending primitive ids
                        let deep =
                            one_source_descending(&what, all.iter().map(|(k, t)| (k.0, k.1, *t)), true);
                        assert!(deep > 500, "{what}: only {deep} fragments behind another");
                    }
                }
            }
        }
    }

    /// Checks that each pixel's fragments, in arrival order (`arrivals`: pixel, primitive id,
    /// source: the thread or band that handed it over), come from one source in descending
    /// primitive order (`strict`: no id twice); returns how many arrived behind another.
    fn one_source_descending<S: PartialEq + Copy + std::fmt::Debug>(
        what: &str,
        arrivals: impl Iterator<Item = (u32, u32, S)>,
        strict: bool,
    ) -> usize {
        let mut last: std::collections::HashMap<u32, (u32, S)> = std::collections::HashMap::new();
        let mut deep = 0;
        for (px, id, source) in arrivals {
            if let Some(&(prim, from)) = last.get(&px) {
                assert!(
                    if strict { id < prim } else { id <= prim },
                    "{what}: pixel {px} got {id} after {prim}"
                );
                assert_eq!(source, from, "{what}: pixel {px} from two sources");
                deep += 1;
            }
            last.insert(px, (id, source));
        }
        deep
    }

    /// The masked banded pass ([`Rasterizer::for_each_masked_fragment_by_band`]) on each kernel,
    /// shaded ahead and on demand, at 4 and 8 samples, on 1 and 3 threads (bands of 16 and 8
    /// rows, which cut the large and the small triangles): the masked walk's fragments and masks
    /// over every row (`masked_kernels_agree`'s), bit for bit; each band's count the fragments
    /// its own shader got; each pixel's fragments from one band, highest primitive first.
    /// Mutations caught: the masked walk's rows left at every row (each band walking whole
    /// boxes: "not the masked walk's fragments and masks"), a band's triangles in primitive
    /// order.
    #[test]
    fn masked_band_pass_gives_the_masked_fragments_by_band() {
        let (scene, cam, w, h) = random_view();
        let kernels = if Kernel::detect() == Kernel::Portable {
            eprintln!("no AVX2 on this host: the portable kernel alone");
            vec![Kernel::Portable]
        } else {
            vec![Kernel::Portable, Kernel::detect()]
        };
        for samples in [4, 8] {
            let s = Settings { samples, ..settings(w, h) };
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                // set up and binned on the pool, so the bands are cut for its threads
                let r = pool.install(|| Rasterizer::new(&scene, &cam, &s));
                let offsets = sample_offsets(samples);
                let whole = Mutex::new(Vec::new());
                let n = r.setup.triangles.len();
                let keep = |_: u32| true;
                r.masked_task(
                    Kernel::Portable,
                    Shade::OnDemand,
                    0..n,
                    ALL_ROWS,
                    &offsets,
                    (&keep, None),
                    &|f, m| {
                        whole.lock().unwrap().push((key(&f.full()), m));
                    },
                );
                let mut expected = whole.into_inner().unwrap();
                expected.sort_unstable();
                let full = oit_core::msaa::full_mask(samples);
                assert!(expected.len() > 1000 && expected.iter().any(|f| f.1 != full), "{}", expected.len());
                for &kernel in &kernels {
                    for shade in [Shade::Color, Shade::OnDemand] {
                        let what = format!("{samples} samples, {threads} threads, {kernel:?}, {shade:?}");
                        let all = Mutex::new(Vec::new());
                        let per_band = pool.install(|| {
                            r.masked_by_band(kernel, samples, shade, None, |b| {
                                let (all, what) = (&all, &what);
                                move |f: &Fragment<'_>, mask: u8| {
                                    let made = shade == Shade::Color && kernel != Kernel::Portable;
                                    assert_eq!(f.color.is_some(), made, "{what}");
                                    all.lock().unwrap().push((key(&f.full()), mask, b));
                                }
                            })
                        });
                        let all = all.into_inner().unwrap();
                        assert!(per_band.len() > 1, "{what}: {} bands", per_band.len());
                        for (b, &count) in per_band.iter().enumerate() {
                            let got = all.iter().filter(|a| a.2 == b).count() as u64;
                            assert_eq!(count, got, "{what}: band {b}'s count");
                        }
                        let mut sorted: Vec<(Key, u8)> = all.iter().map(|a| (a.0, a.1)).collect();
                        sorted.sort_unstable();
                        assert!(sorted == expected, "{what}: not the masked walk's fragments and masks");
                        // per pixel, in arrival order: one band, descending primitive ids (a
                        // clipped triangle's pieces may each cover some samples of one pixel:
                        // one id twice)
                        let deep =
                            one_source_descending(&what, all.iter().map(|(k, _, b)| (k.0, k.1, *b)), false);
                        assert!(deep > 500, "{what}: only {deep} fragments behind another");
                    }
                }
            }
        }
    }

    /// Behind a cut a sample (an opaque wall drawn at 4 samples, seen from beside so that its
    /// edge crosses the two quads behind it), the masked banded pass hands its shaders the
    /// fragments and reduced masks of [`Rasterizer::for_each_masked_fragment`]'s cut, returns the
    /// same fragments drawn, counts the same held back, and with a request ahead asks for every
    /// pixel it hands over. Mutation caught: the band's shader given the uncut mask.
    #[test]
    fn masked_band_pass_cuts_as_the_masked_pass() {
        let (w, h) = (160u32, 120u32);
        let scene = oit_core::builtin_scene("wall:0:planes:2").unwrap().unwrap();
        let settings = Settings { samples: 4, ..settings(w, h) };
        let view = oit_core::View { azimuth: oit_core::View::default().azimuth - 65.0, ..Default::default() };
        let camera = Camera::orbit_scene(&scene, view, w as f32 / h as f32).unwrap();
        let layers = scene.layers(None);
        let opaque = crate::opaque::draw(layers.opaque.as_ref().unwrap(), &camera, &settings);
        let run = |banded: bool, cut: bool| {
            let mut r = Rasterizer::new(&layers.transparent, &camera, &settings);
            r.cut_at(cut.then(|| opaque.depth.clone()));
            let seen = Mutex::new(Vec::new());
            let asked = Mutex::new(std::collections::HashSet::new());
            let ahead = |p: u32| {
                asked.lock().unwrap().insert(p);
            };
            let f = |frag: &Fragment<'_>, mask: u8| seen.lock().unwrap().push((key(&frag.full()), mask));
            let n = if banded {
                r.for_each_masked_fragment_by_band(4, Shade::Color, Some(&ahead), |_| f).iter().sum()
            } else {
                r.for_each_masked_fragment(4, f)
            };
            let mut seen = seen.into_inner().unwrap();
            seen.sort_unstable();
            (seen, n, r.occluded(), asked.into_inner().unwrap())
        };
        // the cut reduces some masks short of nothing (the wall's edge, a sample at a time)
        let uncut: std::collections::HashMap<Key, u8> = run(false, false).0.into_iter().collect();
        let (plain, banded) = (run(false, true), run(true, true));
        assert!(plain.2.is_some_and(|o| o > 0), "nothing held back");
        let reduced = plain.0.iter().filter(|f| uncut[&f.0] != f.1).count();
        assert!(reduced > 10, "{reduced} masks reduced by the cut");
        assert_eq!((banded.1, banded.2), (plain.1, plain.2), "fragments drawn, occluded");
        assert!(banded.0 == plain.0, "the fragments and masks that reach the shader");
        if Kernel::detect() != Kernel::Portable {
            assert!(banded.0.iter().all(|f| banded.3.contains(&f.0.0)), "a pixel not asked for ahead");
        }
    }

    /// The pass with a request ahead gives the same fragments in the same order, and on the
    /// AVX2 walk asks for each fragment's pixel before the fragment comes, never more than a
    /// batch early.
    #[test]
    fn ahead_asks_for_each_pixel_before_its_fragment() {
        let (scene, cam, w, h) = random_view();
        let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let r = one_thread.install(|| Rasterizer::new(&scene, &cam, &settings(w, h)));
        #[derive(Clone, Copy, Debug, PartialEq)]
        enum Event {
            Ahead(u32),
            Fragment(u32, u32),
        }
        let plain = Mutex::new(Vec::new());
        one_thread.install(|| r.for_each_shaded_fragment(|f| plain.lock().unwrap().push((f.pixel, f.prim))));
        let events = Mutex::new(Vec::new());
        let ahead = |p: u32| events.lock().unwrap().push(Event::Ahead(p));
        one_thread.install(|| {
            r.for_each_shaded_fragment_ahead(&ahead, |f| {
                events.lock().unwrap().push(Event::Fragment(f.pixel, f.prim));
            })
        });
        let events = events.into_inner().unwrap();
        let fragments: Vec<(u32, u32)> = events
            .iter()
            .filter_map(|e| if let Event::Fragment(p, t) = *e { Some((p, t)) } else { None })
            .collect();
        let plain = plain.into_inner().unwrap();
        assert!(plain.len() > 1000, "{} fragments", plain.len());
        assert_eq!(fragments, plain, "the request ahead changed the fragments or their order");
        if Kernel::detect() != Kernel::Avx2 {
            eprintln!("no AVX2 on this host: the portable walk asks for nothing ahead");
            return;
        }
        // requests not yet met by their fragment, oldest first
        let mut pending = std::collections::VecDeque::new();
        for e in &events {
            match *e {
                Event::Ahead(p) => pending.push_back(p),
                Event::Fragment(p, _) => {
                    assert_eq!(
                        pending.pop_front(),
                        Some(p),
                        "a fragment whose pixel was not asked for first"
                    );
                    assert!(pending.len() <= AHEAD, "asked {} fragments ahead", pending.len());
                }
            }
        }
        assert!(pending.is_empty());
    }

    /// Each band's shader sees only the band's rows, the bands' counts add up to the pass's
    /// fragments, and every pass of a frame splits them alike (what `ll`'s blocks of nodes,
    /// sized by one pass and taken in the next, rest on).
    #[test]
    fn by_band_passes_split_the_fragments_alike() {
        let (scene, cam, w, h) = random_view();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let r = pool.install(|| Rasterizer::new(&scene, &cam, &settings(w, h)));
        let expected = setup_fragments(&r, |t| t.bbox).len() as u64;
        let mut splits = Vec::new();
        for shade in [Shade::OnDemand, Shade::Color, Shade::OnDemand] {
            let seen = Mutex::new(Vec::new());
            let per_band = pool.install(|| {
                r.for_each_fragment_by_band(shade, |b| {
                    let seen = &seen;
                    let mine = std::cell::Cell::new(0u64);
                    move |f: &Fragment<'_>| {
                        mine.set(mine.get() + 1);
                        seen.lock().unwrap().push((b, f.pixel / w, mine.get()));
                    }
                })
            });
            let bands = r.bands.get().expect("made by the pass");
            assert_eq!(per_band.len(), bands.start.len() - 1);
            assert!(per_band.len() > 2, "{} bands", per_band.len());
            assert_eq!(per_band.iter().sum::<u64>(), expected, "{shade:?}");
            let mut last = vec![0u64; per_band.len()];
            for (b, row, count) in seen.into_inner().unwrap() {
                let (rows, _) = bands.band(b, h);
                assert!((rows[0]..=rows[1]).contains(&row), "band {b} ({rows:?}) got row {row}");
                last[b] = last[b].max(count);
            }
            assert_eq!(last, per_band, "{shade:?}: each band's own count is its share");
            splits.push(per_band);
        }
        assert!(splits.windows(2).all(|p| p[0] == p[1]), "passes split the fragments apart: {splits:?}");
    }

    #[test]
    fn span_walk_matches_the_per_pixel_rule() {
        let scene = random_scene();
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 70.0, 1.0, 0.3, 8.0);
        let r = Rasterizer::new(&scene, &cam, &settings(70, 70));
        for t in &r.setup().triangles {
            let mut walked = Vec::new();
            walk(t, [0, 0, 69, 69], |x, y, e| walked.push((x, y, e)));
            let mut expected = Vec::new();
            for y in 0..70 {
                for x in 0..70 {
                    if let Some(e) = covers(t, x, y) {
                        expected.push((x, y, e));
                    }
                }
            }
            assert_eq!(walked, expected);
        }
    }

    /// The vectorized walk of small triangles against the span walk, on whole boxes and on
    /// tile-sized pieces of them, at a size where some triangles are small and some are not.
    #[test]
    fn tile_walk_matches_the_span_walk() {
        let scene = random_scene();
        let mut small = 0;
        for size in [70u32, 600] {
            let cam = Camera::look_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 70.0, 1.0, 0.3, 8.0);
            let r = Rasterizer::new(&scene, &cam, &settings(size, size));
            for t in &r.setup().triangles {
                let edges = SmallEdges::new(t);
                small += usize::from(edges.small);
                let [bx0, by0, bx1, by1] = t.bbox;
                let mut rects = vec![t.bbox];
                for tile in [7u32, 32] {
                    for ty in by0 / tile..=by1 / tile {
                        for tx in bx0 / tile..=bx1 / tile {
                            let (x0, y0) = (tx * tile, ty * tile);
                            rects.push([
                                bx0.max(x0),
                                by0.max(y0),
                                bx1.min(x0 + tile - 1),
                                by1.min(y0 + tile - 1),
                            ]);
                        }
                    }
                }
                for rect in rects {
                    let (mut spans, mut tiles) = (Vec::new(), Vec::new());
                    walk(t, rect, |x, y, e| spans.push((x, y, e)));
                    walk_tile(t, &edges, rect, |x, y, e| tiles.push((x, y, e)));
                    assert_eq!(tiles, spans, "triangle {} in {rect:?}", t.prim);
                }
            }
        }
        assert!(small > 100, "{small} small triangles");
    }

    #[test]
    fn depth_at_pixel_centres_matches_the_plane() {
        let (w, h) = (128u32, 96u32);
        let cam = camera(w, h);
        // Vertices on the sub-pixel grid, beyond the viewport, so the triangle covers it all and
        // snapping moves nothing.
        let pts = [(-20.0f32, -12.5f32, 0.2f32), (300.25, -10.5, 0.7), (-15.75, 290.0, 0.45)];
        let positions = pts.iter().map(|&(x, y, z)| unproject(&cam, w, h, x, y, z)).collect();
        let mesh = Mesh::new("plane", positions, vec![[0, 1, 2]]);
        let r = Rasterizer::new(&scene_of(vec![mesh]), &cam, &settings(w, h));
        assert_eq!(r.fragment_count(), u64::from(w * h));
        // The plane z = a + bx + cy through the three points, in f64.
        let [(x0, y0, z0), (x1, y1, z1), (x2, y2, z2)] =
            pts.map(|(x, y, z)| (f64::from(x), f64::from(y), f64::from(z)));
        let det = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        let b = ((z1 - z0) * (y2 - y0) - (z2 - z0) * (y1 - y0)) / det;
        let c = ((x1 - x0) * (z2 - z0) - (x2 - x0) * (z1 - z0)) / det;
        let worst = Mutex::new(0.0f64);
        r.for_each_fragment(|f| {
            let (x, y) = (f64::from(f.pixel % w) + 0.5, f64::from(f.pixel / w) + 0.5);
            let expected = z0 + b * (x - x0) + c * (y - y0);
            let err = (f64::from(f.depth) - expected).abs();
            let mut worst = worst.lock().unwrap();
            *worst = worst.max(err);
        });
        // 1e-6 is the brief's bound; f32 barycentrics of this size are good to a few 1e-8.
        let worst = worst.into_inner().unwrap();
        assert!(worst < 1e-6, "worst depth error {worst}");
    }

    #[test]
    fn bounding_boxes_have_twelve_ids_per_instance() {
        let scene = random_scene();
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 9.0), Vec3::ZERO, 60.0, 1.0, 1.0, 20.0);
        let r = Rasterizer::bounding_boxes(&scene, &cam, &settings(64, 64));
        let prims = Mutex::new(std::collections::BTreeSet::new());
        r.for_each_fragment(|f| {
            prims.lock().unwrap().insert(f.prim);
        });
        let prims = prims.into_inner().unwrap();
        assert!(prims.iter().all(|&p| p < 12 * scene.instances.len() as u32));
        for i in 0..scene.instances.len() as u32 {
            assert!(prims.range(12 * i..12 * i + 12).count() >= 2, "instance {i}");
        }
    }
}
