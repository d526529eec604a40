//! Every technique's GPU frame, written once over [`Frame`]: the same passes, storage and
//! resolve as oit-cpu's `technique/*.rs`, in the WGSL modules of oit-shaders. What a module's
//! bindings hold is said where its buffers are made; the bindings start at 2 of group 0 in the
//! order of each `buffers` array.
//!
//! The hardware path's own captures (blending, depth tests, logic ops) are each backend's; they
//! run instead of these where the settings ask for them (`--hardware-capture blend`).

use oit_core::plan::{Array, Counted};
use oit_core::rules::BDP_DEPTH_SUBINTERVALS;
use oit_core::{BoundsMode, Effect, OitError, Technique};

use crate::{Frame, ImageFormat, Init, Rasters};

/// Runs the frame of the settings' technique through `rasters`: its passes, kernels and resolve
/// into the frame's state (the reference also leaves its per-pixel fragment counts for the
/// frame's `layers`).
pub fn render<R: ?Sized, F: Frame<R>>(ctx: &mut F, rasters: &impl Rasters<R>) -> Result<(), OitError> {
    opaque_first(ctx, rasters)?;
    match ctx.settings().technique {
        Technique::Reference => reference(ctx, rasters.scene()),
        Technique::Plain => plain(ctx, rasters.scene()),
        Technique::Fabs { .. } => fabs(ctx, rasters.scene()),
        Technique::Dp => dp(ctx, rasters.scene()),
        Technique::Ddp => ddp(ctx, rasters.scene()),
        Technique::Bdp { .. } => bdp(ctx, rasters),
        Technique::Adp => adp(ctx, rasters),
        Technique::Mdts { .. } => mdts(ctx, rasters.scene(), false),
        Technique::Mdts64 { .. } => mdts(ctx, rasters.scene(), true),
        Technique::Mlp { m } => mlp(ctx, rasters.scene(), m),
        Technique::Dfb => dfb(ctx, rasters.scene()),
        Technique::Ll => ll(ctx, rasters.scene()),
        Technique::Kbuf { .. } => kbuf(ctx, rasters.scene()),
        // the order-free sums, one frame for all ([`Technique::sums`])
        t => sums(ctx, rasters.scene(), t),
    }
}

/// What every GPU frame runs before its technique, [`render`]'s and each backend's own hardware
/// captures' (`--hardware-capture blend`, plain's blender) alike: the [`opaque_pass`] where the
/// frame has an opaque part. The passes that follow cut their fragments at its depth (the blend
/// captures in their fragment stages: `hw_dropped`, `core/blend_stage.wgsl`), the frame's first
/// scene pass (or count-only draw) counts what the cut holds back, and every resolve composites
/// over its colour (`background_at`).
pub fn opaque_first<R: ?Sized, F: Frame<R>>(ctx: &mut F, rasters: &impl Rasters<R>) -> Result<(), OitError> {
    if let Some(opaque) = rasters.opaque() {
        opaque_pass(ctx, opaque)?;
    }
    Ok(())
}

/// The opaque pass (oit-cpu's `opaque::draw`): two geometry passes of `opaque.wgsl` over the
/// frame's opaque part, the first a 64-bit MIN of each pixel's `depth bits << 32 | id` (masked
/// fragments discarded and counted), the second writing the winner's colour into the frame's
/// opaque image (group 0, [`crate::OPAQUE_KEYS_BINDING`] and [`crate::OPAQUE_RGB_BINDING`]). The
/// technique's passes that follow cut their fragments at its depth ([`Frame::cut`]). Neither pass
/// is the scene's first: the frame's fragments stay the transparent part's.
pub fn opaque_pass<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let fragments = ctx.fragments();
    ctx.cut(false);
    let count = ctx.geometry_pass_counted(raster, crate::OPAQUE_MODULE, &[], 0, 0)?;
    ctx.geometry_pass(raster, crate::OPAQUE_MODULE, &[], 1, 0)?;
    // each compute-raster tile's farthest opaque depth, for the passes that follow to skip the
    // work items wholly behind it
    let tiles = oit_gpu_tiles(ctx.settings());
    ctx.kernel_over(crate::OPAQUE_MODULE, "opaque_tiles_main", &[], tiles, 0, 0, "opaque tiles")?;
    ctx.set_fragments(fragments);
    ctx.note_opaque(&count);
    ctx.cut(true);
    Ok(())
}

/// The compute rasterizer's tiles of the frame of `settings` ([`crate::opaque_tiles`]).
fn oit_gpu_tiles(settings: &oit_core::Settings) -> u64 {
    crate::opaque_tiles(settings.width, settings.height)
}

/// A frame's storage as its plan names it ([`Plan::arrays`](oit_core::plan::Plan::arrays)): a
/// technique takes each of its arrays from here by the plan's name, and the sizes are the plan's,
/// so a GPU frame allocates exactly what the plan counts and checks against the memory budget,
/// with nothing corrected by hand. [`Storage::finish`] refuses a frame that left one of the
/// plan's arrays out.
///
/// An array's element may be kept as several parallel buffers, one per field (structure of
/// arrays, as the WGSL reads them: `dfb`'s 12-byte entries as 8-byte keys and 4-byte payloads),
/// or as storage images (`--atomic-storage image`): the same array of the plan over another
/// storage kind, with the same bytes.
pub struct Storage {
    technique: Technique,
    pixels: u64,
    arrays: Vec<(Array, bool)>,
    /// The fragments per-fragment arrays hold, once the frame knows them ([`Storage::hold`]).
    fragments: Option<u64>,
}

impl Storage {
    /// The plan's arrays of `ctx`'s frame, its per-pixel slots sized from a counting pass whose
    /// deepest pixel held `deepest` fragments (0 where the frame counts none).
    pub fn new<R: ?Sized, F: Frame<R>>(ctx: &F, deepest: u32) -> Storage {
        let arrays = ctx.plan().arrays(Counted { deepest, fragments: 0 });
        Storage {
            technique: ctx.settings().technique,
            pixels: u64::from(ctx.pixels()),
            arrays: arrays.into_iter().map(|a| (a, false)).collect(),
            fragments: None,
        }
    }

    /// Sizes the per-fragment arrays (exact allocations) for `fragments` fragments.
    pub fn hold(&mut self, fragments: u64) {
        self.fragments = Some(fragments);
    }

    /// The plan's array whose name is `name` (up to its parenthesised gloss) and its element
    /// count, marked taken.
    fn take(&mut self, name: &str) -> Result<(Array, u64), OitError> {
        let technique = self.technique;
        let internal = |what: String| OitError::Device(format!("internal: {technique}'s GPU frame {what}"));
        let (array, taken) = self
            .arrays
            .iter_mut()
            .find(|(a, _)| a.name.split(" (").next() == Some(name))
            .ok_or_else(|| internal(format!("asked for '{name}', which its plan does not allocate")))?;
        if std::mem::replace(taken, true) {
            return Err(internal(format!("allocated its plan's '{name}' twice")));
        }
        let fragments = match (array.per_fragment, self.fragments) {
            (0, _) => 0,
            (_, Some(n)) => n,
            (_, None) => return Err(internal(format!("allocated '{name}' before it knew its fragments"))),
        };
        let elements = self
            .pixels
            .saturating_mul(array.per_pixel)
            .saturating_add(fragments.saturating_mul(array.per_fragment))
            .saturating_add(array.fixed);
        Ok((*array, elements))
    }

    /// The plan's array `name` as one storage buffer a field of its element: `fields` gives each
    /// field's bytes (a multiple of 4; together the element's) and initial words.
    pub fn buffers<const N: usize, R: ?Sized, F: Frame<R>>(
        &mut self,
        ctx: &mut F,
        name: &str,
        fields: [(u64, Init); N],
    ) -> Result<[F::Buffer; N], OitError> {
        let (array, elements) = self.take(name)?;
        let bytes: u64 = fields.iter().map(|f| f.0).sum();
        if bytes != array.element_bytes || fields.iter().any(|f| f.0 % 4 != 0) {
            return Err(OitError::Device(format!(
                "internal: {}'s '{name}' kept as fields of {:?} bytes, its plan's elements are {} bytes",
                self.technique,
                fields.map(|f| f.0),
                array.element_bytes
            )));
        }
        let label = format!("{} {name}", self.technique);
        let mut out = Vec::with_capacity(N);
        for (field_bytes, init) in fields {
            out.push(ctx.array(&label, elements.saturating_mul(field_bytes / 4), init)?);
        }
        Ok(out.try_into().unwrap_or_else(|_| unreachable!("N fields, N buffers")))
    }

    /// [`Storage::buffers`] of one field: the element whole.
    pub fn buffer<R: ?Sized, F: Frame<R>>(
        &mut self,
        ctx: &mut F,
        name: &str,
        init: Init,
    ) -> Result<F::Buffer, OitError> {
        let bytes = self
            .arrays
            .iter()
            .find(|(a, _)| a.name.split(" (").next() == Some(name))
            .map_or(4, |a| a.0.element_bytes);
        Ok(self.buffers(ctx, name, [(bytes, init)])?.into_iter().next().unwrap_or_else(|| unreachable!()))
    }

    /// The plan's array `name` of one-byte elements as one storage buffer, four elements a word
    /// (the coverage masks of multisampled frames: `technique/coverage.wgsl`), zeroed.
    pub fn bytes<R: ?Sized, F: Frame<R>>(&mut self, ctx: &mut F, name: &str) -> Result<F::Buffer, OitError> {
        let (array, elements) = self.take(name)?;
        if array.element_bytes != 1 {
            return Err(OitError::Device(format!(
                "internal: {}'s '{name}' kept as bytes, its plan's elements are {} bytes",
                self.technique, array.element_bytes
            )));
        }
        ctx.array(&format!("{} {name}", self.technique), elements.div_ceil(4), Init::Zero)
    }

    /// The coverage masks of a multisampled frame (the plan's "coverage masks", a byte an entry;
    /// docs/msaa.md), or a placeholder at one sample, where the plan has none and the WGSL reads
    /// none.
    pub fn masks<R: ?Sized, F: Frame<R>>(&mut self, ctx: &mut F) -> Result<F::Buffer, OitError> {
        if ctx.plan().samples > 1 { self.bytes(ctx, "coverage masks") } else { ctx.placeholder() }
    }

    /// The plan's per-pixel array `name` as storage images of the frame's size, one a field of its
    /// element (`formats`, bound from `binding` on), a layer per element of a pixel, every 32-bit
    /// half of every texel set to `fill` (`--atomic-storage image`).
    pub fn images<R: ?Sized, F: Frame<R>>(
        &mut self,
        ctx: &mut F,
        name: &str,
        binding: u32,
        formats: &[ImageFormat],
        fill: u32,
    ) -> Result<(), OitError> {
        let (array, _) = self.take(name)?;
        let bytes: u64 = formats.iter().map(|f| f.bytes()).sum();
        let layers =
            u32::try_from(array.per_pixel).ok().filter(|_| array.per_fragment == 0 && array.fixed == 0);
        let (Some(layers), true) = (layers, bytes == array.element_bytes) else {
            return Err(OitError::Device(format!(
                "internal: {}'s '{name}' as images of {formats:?}: its plan's array is {array:?}",
                self.technique
            )));
        };
        let label = format!("{} {name}", self.technique);
        for (i, &format) in formats.iter().enumerate() {
            ctx.storage_image(&label, binding + i as u32, layers, format, fill)?;
        }
        Ok(())
    }

    /// The plan's per-pixel array `name` as render targets the backend makes and counts itself
    /// (the hardware path's blend captures), `bytes` a pixel in all: checked against the plan's.
    pub fn attachments(&mut self, name: &str, bytes: u64) -> Result<(), OitError> {
        let (array, _) = self.take(name)?;
        if array.per_fragment != 0 || array.fixed != 0 || array.per_pixel * array.element_bytes != bytes {
            return Err(OitError::Device(format!(
                "internal: {}'s '{name}' as render targets of {bytes} bytes a pixel: its plan's array is {array:?}",
                self.technique
            )));
        }
        Ok(())
    }

    /// Checks that the frame allocated every array of its plan.
    pub fn finish(self) -> Result<(), OitError> {
        match self.arrays.iter().find(|(_, taken)| !taken) {
            None => Ok(()),
            Some((a, _)) => Err(OitError::Device(format!(
                "internal: {}'s GPU frame left its plan's '{}' unallocated",
                self.technique, a.name
            ))),
        }
    }
}

/// The buffers of `tail.wgsl` (`--overflow tail`), bound at 6 and 7: the tail sums (5 u64 a
/// pixel, `Plan::arrays`'s "tail sums") and two words of bookkeeping (overflowed, merged);
/// placeholders where the plan has no tail.
fn tail_buffers<R: ?Sized, F: Frame<R>>(
    ctx: &mut F,
    storage: &mut Storage,
) -> Result<(F::Buffer, F::Buffer), OitError> {
    if !ctx.plan().tail {
        return Ok((ctx.placeholder()?, ctx.placeholder()?));
    }
    let sums = storage.buffer(ctx, "tail sums", Init::Zero)?;
    let words = ctx.scratch("tail words", 2, Init::Zero)?;
    Ok((sums, words))
}

/// Fragments per pixel from one counting pass (`count`), and the deepest pixel's count (an
/// earlier frame's where the frame speculates, checked at its end). The counts size the
/// technique's arrays: they are not its storage (oit-cpu counts none either).
pub fn count<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(F::Buffer, u32), OitError> {
    let counts = ctx.scratch("fragment counts", u64::from(ctx.pixels()), Init::Zero)?;
    let max = ctx.scratch("max count", 1, Init::Zero)?;
    ctx.geometry_pass(raster, "count", &[&counts, &max], 0, 0)?;
    ctx.pixel_kernel("count", "max_main", &[&counts, &max], 0, 0)?;
    let deepest = ctx.deepest(&max)?;
    Ok((counts, deepest))
}

/// Words one workgroup of `scan.wgsl` scans (64 invocations × 4 words).
const SCAN_BLOCK: u64 = 256;

/// The exclusive prefix sum of the first `n` words of `words`, in place, on the GPU (`scan`):
/// each block of 256 words scanned by one workgroup, the blocks' totals scanned the same way one
/// level up, and added back. Returns the buffer whose word 0 holds the total, on the device
/// ([`Frame::fragment_capacity`] sizes from it). The block totals are bookkeeping.
fn scan<R: ?Sized, F: Frame<R>>(ctx: &mut F, words: &F::Buffer, n: u64) -> Result<F::Buffer, OitError> {
    let blocks = n.div_ceil(SCAN_BLOCK).max(1);
    let param = u32::try_from(n).map_err(|_| OitError::Device(format!("a prefix sum over {n} words")))?;
    let sums = ctx.scratch("scan block sums", blocks, Init::Zero)?;
    ctx.kernel_over("scan", "scan_main", &[words, &sums], blocks * 64, 0, param, "scan")?;
    if blocks == 1 {
        return Ok(sums);
    }
    let total = scan(ctx, &sums, blocks)?;
    ctx.kernel_over("scan", "add_main", &[words, &sums], blocks * 64, 0, param, "scan")?;
    Ok(total)
}

/// The peel loop of dp, ddp and mlp: until a pass leaves word 0 of `flag` at zero (nothing
/// peeled, or for mlp nothing overflowed) or the plan's limit, each pass `flag` cleared, the
/// geometry pass (pass index p, `param`), then the resolve kernel (pass index `p +
/// resolve_step`).
///
/// Where the frame has a speculated pass count ([`Frame::take_speculated_peels`]) it records
/// that many passes with no round trip: each after the first gated on the flag its predecessor
/// left (a pass that would not have run does nothing and is not counted), and the last one's
/// flag checked at the frame's end, where a frame that needed more passes runs again. Without
/// one, the flag is read after each pass and the count kept for the next frame.
fn peel<R: ?Sized, F: Frame<R>>(
    ctx: &mut F,
    raster: &R,
    module: &'static str,
    buffers: &[&F::Buffer],
    flag: &F::Buffer,
    param: u32,
    resolve_step: u32,
) -> Result<(), OitError> {
    // per sample, one pass past the peels fetches the last layer peeled (`Plan::schedule`)
    let limit = match ctx.plan() {
        p if p.sample_peel => p.peel_limit.saturating_add(1),
        p => p.peel_limit,
    };
    let speculated = ctx.take_speculated_peels()?.filter(|&s| s >= 1).map(|s| s.min(limit));
    let previous = match speculated {
        Some(_) => Some(ctx.scratch("peel gate", 1, Init::Zero)?),
        None => None,
    };
    let mut p = 0;
    while p < limit {
        ctx.last_pass(p + 1 == limit);
        match &previous {
            Some(prev) if p > 0 => {
                ctx.copy(flag, prev, 4)?;
                ctx.fill(flag, 0)?;
                ctx.geometry_pass_if(raster, module, buffers, p, param, prev)?;
            }
            _ => {
                ctx.fill(flag, 0)?;
                ctx.geometry_pass(raster, module, buffers, p, param)?;
            }
        }
        ctx.pixel_kernel(module, "resolve_main", buffers, p + resolve_step, param)?;
        p += 1;
        match speculated {
            Some(s) if p == s => {
                if p < limit {
                    // the last speculated pass must have found nothing more
                    ctx.check_at_end(flag);
                }
                break;
            }
            Some(_) => {}
            None => {
                if ctx.read_u32(flag)?[0] == 0 {
                    break;
                }
            }
        }
    }
    if speculated.is_none() {
        ctx.note_peels(p);
    }
    ctx.last_pass(false);
    Ok(())
}

/// The exact reference: a counting pass (dfb's), the counts' prefix sum into offsets, every
/// fragment filled into its pixel's range, each range sorted by (depth, primitive id) and
/// composited. The counts are the frame's `layers`, not the technique's storage.
fn reference<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels()) + 1;
    // fragments per pixel; the last entry stays 0, so the offsets end in the total
    let counts = ctx.scratch("reference counts", entries, Init::Zero)?;
    ctx.geometry_pass(raster, "dfb_count", &[&counts], 0, 0)?;
    ctx.note_layers(&counts);
    let mut storage = Storage::new(ctx, 0);
    let offsets = storage.buffer(ctx, "offsets", Init::Zero)?;
    ctx.copy(&counts, &offsets, entries * 4)?;
    let total = scan(ctx, &offsets, entries)?;
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    storage.hold(u64::from(ctx.plan().check_fragments(u64::from(total))?));
    let cursor = storage.buffer(ctx, "fill cursors", Init::Zero)?;
    // each pixel's range is filled whole before the resolve reads it
    let [keys, payloads] = storage.buffers(ctx, "entries", [(8, Init::Unwritten), (4, Init::Unwritten)])?;
    let masks = storage.masks(ctx)?;
    let buffers = [&offsets, &cursor, &keys, &payloads, &masks];
    ctx.geometry_pass(raster, "reference", &buffers, 0, 0)?;
    ctx.pixel_kernel("reference", "resolve_main", &buffers, 0, 0)?;
    storage.finish()
}

/// `plain` where no rasterizer keeps submission order (the compute path): each pixel's fragments
/// kept (a counter and K slots of (primitive id, payload), K from a counting pass) and
/// composited in primitive order. Translucency and Fresnel are refused by the plan.
fn plain<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let deepest = count(ctx, raster)?.1;
    let k = ctx.plan().slots(deepest);
    let mut storage = Storage::new(ctx, deepest);
    let counters = storage.buffer(ctx, "counter", Init::Zero)?;
    let slots = storage.buffer(ctx, "slots", Init::Zero)?;
    let buffers = [&counters, &slots];
    ctx.geometry_pass(raster, "plain", &buffers, 0, k)?;
    ctx.pixel_kernel("plain", "plain_resolve_main", &buffers, 0, k)?;
    storage.finish()
}

/// The passes of `fabs.wgsl` (pass_index).
const FABS_CAPTURE: u32 = 0;
const FABS_KEYS: u32 = 1;
const FABS_PAYLOADS: u32 = 2;
const FABS_TAIL: u32 = 3;
/// The resolve's pass_index when the plan has a tail.
const FABS_WITH_TAIL: u32 = 1;

/// `fabs:K`: a per-pixel counter and K slots of a 64-bit (depth bits, primitive id) key and a
/// 32-bit payload, sorted by key at the resolve, so ties come out in primitive order as the
/// reference's do. A pixel that overflows keeps its K smallest keys (two passes gated on the
/// overflow flag), so the same input gives the same image; `--overflow tail` adds one pass
/// merging what lies behind the K into a tail (`tail.wgsl`). With `--atomic-storage image` the
/// counters are a storage image (module `fabs_image`: the same technique over the image
/// accessor); the slots stay in buffers.
fn fabs<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    // slots per pixel by the plan: K, or the deepest pixel's count from a counting pass
    let deepest = if ctx.plan().needs_count() { count(ctx, raster)?.1 } else { 0 };
    let k = ctx.plan().slots(deepest);
    let mut storage = Storage::new(ctx, deepest);
    let (module, counters) = if ctx.plan().image_atomics {
        storage.images(ctx, "counter", 9, &[ImageFormat::R32Uint], 0)?;
        ("fabs_image", ctx.placeholder()?)
    } else {
        ("fabs", storage.buffer(ctx, "counter", Init::Zero)?)
    };
    // slot i of a pixel is written (FABS_CAPTURE, or emptied by overflow_main) before any pass
    // reads it, and the resolve reads the first min(count, K)
    let slots = storage.buffer(ctx, "slots", Init::Unwritten)?;
    let payloads = storage.buffer(ctx, "payloads", Init::Unwritten)?;
    let overflowed = ctx.scratch("fabs overflowed", 1, Init::Zero)?;
    let (tail, tail_words) = tail_buffers(ctx, &mut storage)?;
    let masks = storage.masks(ctx)?;
    let buffers = [&counters, &slots, &payloads, &overflowed, &tail, &tail_words, &masks];
    ctx.geometry_pass(raster, module, &buffers, FABS_CAPTURE, k)?;
    // sized from the counting pass, no pixel can overflow: no check
    if !ctx.plan().needs_count() {
        ctx.pixel_kernel(module, "overflow_main", &buffers, FABS_CAPTURE, k)?;
        // where a pixel overflowed: the K smallest (depth, primitive) keys of each overflowing
        // pixel, then their payloads, then the tail
        ctx.geometry_pass_if(raster, module, &buffers, FABS_KEYS, k, &overflowed)?;
        ctx.geometry_pass_if(raster, module, &buffers, FABS_PAYLOADS, k, &overflowed)?;
        if ctx.plan().tail {
            ctx.geometry_pass_if(raster, module, &buffers, FABS_TAIL, k, &overflowed)?;
            ctx.note_merged(&tail_words);
        }
    }
    let resolve = if ctx.plan().tail { FABS_WITH_TAIL } else { 0 };
    ctx.pixel_kernel(module, "resolve_main", &buffers, resolve, k)?;
    storage.finish()
}

/// An order-free sum technique's frame, as its entry says ([`Technique::sums`]: `wavg`, `wsum`,
/// `wboit`, `mboit`): the plan's one array of u64 sums, zeroed; the entry's geometry passes of its
/// module (pass index 0, 1, ...: mboit's moments, then its transmittance-weighted colours); its
/// `composite_main` over every pixel. The sums are integers added by atomics, so the frame is the
/// same whatever order fragments arrive in. Translucency and Fresnel are refused by the plan.
fn sums<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R, technique: Technique) -> Result<(), OitError> {
    let Some(entry) = technique.sums() else {
        return Err(OitError::Unsupported {
            backend: "the GPU layer".into(),
            what: format!("{technique}: it has no GPU frame"),
        });
    };
    let mut storage = Storage::new(ctx, 0);
    let sums = storage.buffer(ctx, entry.array, Init::Zero)?;
    for pass in 0..entry.passes {
        ctx.geometry_pass(raster, entry.module, &[&sums], pass, entry.param)?;
    }
    ctx.pixel_kernel(entry.module, "composite_main", &[&sums], 0, entry.param)?;
    storage.finish()
}

/// Depth peeling: one layer a pass, front to back, until a pass peels nothing ([`peel`]).
fn dp<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    if ctx.plan().sample_peel {
        return dp_samples(ctx, raster);
    }
    let mut storage = Storage::new(ctx, 0);
    let nearest = storage.buffer(ctx, "nearest", Init::Fill(u32::MAX))?;
    // the previous pass's depth buffer (oit-cpu counts 4 bytes a pixel too)
    let previous = storage.buffer(ctx, "previous peel's depth", Init::Zero)?;
    let peeled = ctx.scratch("dp peeled count", 1, Init::Zero)?;
    let buffers = [&nearest, &previous, &peeled];
    peel(ctx, raster, "dp", &buffers, &peeled, 0, 0)?;
    storage.finish()
}

/// Depth peeling per sample (several samples, `dp_samples.wgsl`; docs/msaa.md): (depth,
/// primitive id) peels, each peeled layer's payload and mask fetched by the next pass and
/// composited into the covered samples' accumulators ([`peel`], one pass past the peels).
fn dp_samples<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let mut storage = Storage::new(ctx, 0);
    let nearest = storage.buffer(ctx, "nearest", Init::Fill(u32::MAX))?;
    let previous = storage.buffer(ctx, "previous peel's key", Init::Zero)?;
    let layer = storage.buffer(ctx, "peeled layer", Init::Zero)?;
    // set by the first pass's resolve
    let acc = storage.buffer(ctx, "sample accumulators", Init::Zero)?;
    let peeled = ctx.scratch("dp peeled count", 1, Init::Zero)?;
    let buffers = [&nearest, &previous, &layer, &acc, &peeled];
    peel(ctx, raster, "dp_samples", &buffers, &peeled, 0, 0)?;
    storage.finish()
}

/// Dual depth peeling per sample (several samples, `ddp_samples.wgsl`; docs/msaa.md): as
/// [`dp_samples`], the near layer into each covered sample's front, the far one into its back.
fn ddp_samples<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let mut storage = Storage::new(ctx, 0);
    let near = storage.buffer(ctx, "near", Init::Fill(u32::MAX))?;
    let far = storage.buffer(ctx, "far", Init::Zero)?;
    // (lo, !hi): zeroed is the first pass's open range
    let range = storage.buffer(ctx, "open key range", Init::Zero)?;
    let acc = storage.buffer(ctx, "sample accumulators", Init::Zero)?;
    let layers = storage.buffer(ctx, "peeled layers", Init::Zero)?;
    let peeled = ctx.scratch("ddp peeled count", 1, Init::Zero)?;
    let buffers = [&near, &far, &range, &acc, &layers, &peeled];
    peel(ctx, raster, "ddp_samples", &buffers, &peeled, 0, 0)?;
    storage.finish()
}

/// Refuses the effects ddp's GPU resolve cannot do (for both captures, atomics and blend).
pub fn check_ddp_effect(backend: &str, effect: Effect) -> Result<(), OitError> {
    if matches!(effect, Effect::Transparency | Effect::Complexity) {
        return Ok(());
    }
    Err(OitError::Unsupported {
        backend: backend.into(),
        what: format!(
            "the {effect:?} effect with ddp: the far layers it peels would have to be replayed nearest first from a per-pixel stack, which the GPU resolve does not keep; use dp, fabs, mlp or adp (or the cpu backend)"
        ),
    })
}

/// ddp's state on a GPU's blender per sample (`--hardware-capture blend` at several samples; each
/// backend's own capture): the plan's arrays, its two multisampled range targets (which the
/// backend makes as render targets) checked against them, then each sample's near and far
/// hand-overs, the fragments handed over a pixel and each sample's accumulators; and a flag word
/// (bookkeeping) that `ddp_blend_samples.wgsl` sets where two fragments or more arrive at one end
/// of a sample's range in one pass, which the frame's end refuses ([`Frame::refuse_at_end`]): the
/// range targets hold depths, not primitive ids, so the capture keeps one of such a tie and counts
/// both handed over, or composites two on a collapsed range in key order, wrong where nothing
/// says so.
pub fn ddp_blend_sample_state<R: ?Sized, F: Frame<R>>(ctx: &mut F) -> Result<[F::Buffer; 5], OitError> {
    let samples = u64::from(ctx.settings().samples);
    let mut storage = Storage::new(ctx, 0);
    storage.attachments("range targets", 16 * samples)?;
    let near = storage.buffer(ctx, "near hand-overs", Init::Fill(u32::MAX))?;
    let far = storage.buffer(ctx, "far hand-overs", Init::Zero)?;
    let handed = storage.buffer(ctx, "fragments handed over", Init::Zero)?;
    let acc = storage.buffer(ctx, "sample accumulators", Init::Zero)?;
    storage.finish()?;
    let ties = ctx.scratch("ddp ties at a sample", 1, Init::Zero)?;
    let samples = ctx.settings().samples;
    ctx.refuse_at_end(
        &ties,
        format!(
            "ddp with --hardware-capture blend at --samples {samples} on coplanar fragments: two or more \
             met at equal depths at one end of a sample's depth range, which its range targets (depths, \
             no primitive ids) cannot order, so it would keep one and count both, in silence; use \
             --hardware-capture atomics, which orders ties by primitive id (docs/msaa.md)"
        ),
    );
    Ok([near, far, handed, acc, ties])
}

/// `ddp.wgsl`'s storage, allocated and initialised by its `ddp_init_main`: the near and far
/// (depth key, colour) words, the open depth range the previous pass left (oit-cpu counts 8 bytes
/// a pixel too), and the count of pixels that peeled a layer in the last pass (bookkeeping).
/// Shared with the backends' blend captures of ddp, which resolve through `ddp.wgsl` too.
pub fn ddp_state<R: ?Sized, F: Frame<R>>(ctx: &mut F) -> Result<[F::Buffer; 4], OitError> {
    let mut storage = Storage::new(ctx, 0);
    let near = storage.buffer(ctx, "near", Init::Fill(u32::MAX))?;
    let far = storage.buffer(ctx, "far", Init::Zero)?;
    let range = storage.buffer(ctx, "open depth range", Init::Zero)?;
    storage.finish()?;
    let peeled = ctx.scratch("ddp peeled count", 1, Init::Zero)?;
    ctx.pixel_kernel("ddp", "ddp_init_main", &[&near, &far, &range, &peeled], 0, 0)?;
    Ok([near, far, range, peeled])
}

/// Dual depth peeling: the nearest and farthest layer a pass ([`peel`]).
fn ddp<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    if ctx.plan().sample_peel {
        return ddp_samples(ctx, raster);
    }
    check_ddp_effect(ctx.backend(), ctx.settings().effect)?;
    let [near, far, range, peeled] = ddp_state(ctx)?;
    peel(ctx, raster, "ddp", &[&near, &far, &range, &peeled], &peeled, 0, 0)
}

/// Multi-layer peeling: the M nearest remaining layers a pass ([`peel`]), until no pixel
/// overflows its M slots.
fn mlp<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R, m: u32) -> Result<(), OitError> {
    if m == 0 {
        // every fragment would overflow an empty array, every pass
        return Err(OitError::InvalidSettings("mlp:0 holds no layer: use mlp:M with M ≥ 1".into()));
    }
    if ctx.plan().sample_peel {
        return mlp_samples(ctx, raster, m);
    }
    let mut storage = Storage::new(ctx, 0);
    let slots = storage.buffer(ctx, "sorted slots", Init::Fill(u32::MAX))?;
    // the previous pass's deepest depth (oit-cpu counts 4 bytes a pixel too)
    let deepest = storage.buffer(ctx, "fragments at the previous pass's deepest depth", Init::Zero)?;
    let overflowed = ctx.scratch("mlp overflowed", 1, Init::Zero)?;
    let buffers = [&slots, &deepest, &overflowed];
    peel(ctx, raster, "mlp", &buffers, &overflowed, m, 1)?;
    storage.finish()
}

/// Multi-layer peeling per sample (several samples, `mlp_samples.wgsl`; docs/msaa.md): the M
/// nearest (depth, primitive id) keys behind the pass before's a pass, their payloads and masks
/// fetched by the next pass and composited into the covered samples' accumulators ([`peel`],
/// one pass past the peels).
fn mlp_samples<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R, m: u32) -> Result<(), OitError> {
    let mut storage = Storage::new(ctx, 0);
    let slots = storage.buffer(ctx, "sorted slots", Init::Fill(u32::MAX))?;
    // written by each pass's resolve (the first pass reads none)
    let previous = storage.buffer(ctx, "previous pass's keys", Init::Fill(u32::MAX))?;
    let layers = storage.buffer(ctx, "peeled layers", Init::Zero)?;
    // set by the first pass's resolve
    let acc = storage.buffer(ctx, "sample accumulators", Init::Zero)?;
    let peeled = ctx.scratch("mlp peeled count", 1, Init::Zero)?;
    let buffers = [&slots, &previous, &layers, &acc, &peeled];
    peel(ctx, raster, "mlp_samples", &buffers, &peeled, m, 0)?;
    storage.finish()
}

/// `capture`'s param in `bdp.wgsl`.
const BDP_MODE_COLOR: u32 = 0;
const BDP_MODE_DEPTH: u32 = 1;

/// Per-pixel [zNear, zFar] (two words of depth bits a pixel, the plan's `depth bounds`) from one
/// geometry pass over the scene or the instances' bounding boxes (`--bounds`), as oit-cpu's
/// `Ctx::depth_bounds`; pixels nothing reached get [0, 1].
pub fn depth_bounds<R: ?Sized, F: Frame<R>>(
    ctx: &mut F,
    rasters: &impl Rasters<R>,
    storage: &mut Storage,
) -> Result<F::Buffer, OitError> {
    let bounds = storage.buffer(ctx, "depth bounds", Init::Zero)?;
    ctx.pixel_kernel("bounds", "bounds_init_main", &[&bounds], 0, 0)?;
    match ctx.plan().bounds {
        BoundsMode::Exact => ctx.geometry_pass(rasters.scene(), "bounds", &[&bounds], 0, 0)?,
        BoundsMode::Boxes | BoundsMode::Auto => {
            let fragments = ctx.fragments();
            // the boxes are not cut at the opaque depth (nor are they on the CPU)
            ctx.cut(false);
            rasters.with_boxes(&mut |boxes| ctx.geometry_pass(boxes, "bounds", &[&bounds], 0, 0))?;
            ctx.cut(true);
            // the frame's fragments are the scene's, not the boxes'
            ctx.set_fragments(fragments);
        }
    }
    ctx.pixel_kernel("bounds", "bounds_finish_main", &[&bounds], 0, 0)?;
    Ok(bounds)
}

/// Bucket depth peeling: 32 buckets over each pixel's depth range. The colour mode (one capture,
/// the plan's `bdp_color`) MAX-updates 32 packed colour words; the depth mode runs the plan's
/// capture passes, each keeping the (min, max) of 16 subintervals, settled after each pass.
fn bdp<R: ?Sized, F: Frame<R>>(ctx: &mut F, rasters: &impl Rasters<R>) -> Result<(), OitError> {
    let mut storage = Storage::new(ctx, 0);
    let bounds = depth_bounds(ctx, rasters, &mut storage)?;
    let raster = rasters.scene();
    if ctx.plan().bdp_color {
        let colors = storage.buffer(ctx, "colour buckets", Init::Zero)?;
        let arrays = ctx.placeholder()?;
        let buffers = [&bounds, &colors, &arrays];
        ctx.geometry_pass(raster, "bdp", &buffers, 0, BDP_MODE_COLOR)?;
        ctx.pixel_kernel("bdp", "color_resolve_main", &buffers, 0, 0)?;
        return storage.finish();
    }
    // one array per capture pass run: P, or fewer under --max-peels (the plan's stop rule), of
    // 16 × (min, max) u64 a pixel
    let run = ctx.plan().bdp_capture_passes();
    let arrays = storage.buffer(ctx, "min and max buckets, per capture pass", Init::Zero)?;
    let pairs = u64::from(ctx.pixels()) * u64::from(BDP_DEPTH_SUBINTERVALS) * u64::from(run);
    let colors = ctx.placeholder()?;
    let buffers = [&bounds, &colors, &arrays];
    ctx.kernel_over("bdp", "depth_init_main", &buffers, pairs, 0, 0, "depth_init_main")?;
    for p in 0..run {
        ctx.last_pass(p + 1 == run);
        ctx.geometry_pass(raster, "bdp", &buffers, p, BDP_MODE_DEPTH)?;
        ctx.pixel_kernel("bdp", "depth_settle_main", &buffers, p, BDP_MODE_DEPTH)?;
    }
    ctx.last_pass(false);
    ctx.pixel_kernel("bdp", "depth_resolve_main", &buffers, 0, run)?;
    storage.finish()
}

/// Adaptive bucket depth peeling: the depth bounds, a 1024-bit histogram pass (by the backend's
/// own capture where it has one, [`Frame::histogram_capture`]), the deepest pixel's set-bin
/// count, then one capture and resolve per batch of 32 bins, each bucket keeping its bin's
/// farthest and nearest fragment.
fn adp<R: ?Sized, F: Frame<R>>(ctx: &mut F, rasters: &impl Rasters<R>) -> Result<(), OitError> {
    let mut storage = Storage::new(ctx, 0);
    let bounds = depth_bounds(ctx, rasters, &mut storage)?;
    let raster = rasters.scene();
    let hist = storage.buffer(ctx, "depth histogram", Init::Zero)?;
    // sizing the batches is not per-pixel storage: oit-cpu does not count it either
    let max_bins = ctx.scratch("adp deepest pixel", 1, Init::Zero)?;
    // oit-cpu allocates the buckets after the histogram pass; the bytes are the same
    let buckets = storage.buffer(ctx, "buckets", Init::Zero)?;
    let nearest = storage.buffer(ctx, "nearest of each bin", Init::Fill(u32::MAX))?;
    let buffers = [&bounds, &hist, &buckets, &max_bins, &nearest];
    if !ctx.histogram_capture(raster, &buffers)? {
        ctx.geometry_pass(raster, "adp", &buffers, 0, 0)?;
    }
    ctx.pixel_kernel("adp", "count_main", &buffers, 0, 0)?;
    // an earlier frame's count where it makes as many batches (checked at the end), else read back
    let plan = ctx.plan().clone();
    let bins =
        ctx.deepest_alike(&max_bins, Box::new(move |a, b| plan.adp_batches(a) == plan.adp_batches(b)))?;
    let batches = ctx.plan().adp_batches(bins);
    for batch in 0..batches {
        ctx.last_pass(batch + 1 == batches);
        ctx.geometry_pass(raster, "adp", &buffers, 1, batch)?;
        ctx.pixel_kernel("adp", "resolve_main", &buffers, 1, batch)?;
    }
    ctx.last_pass(false);
    storage.finish()
}

/// The modes of `mdts.wgsl` (low byte of pass_index).
const MDTS_32: u32 = 0;
const MDTS_64: u32 = 1;
/// Flags of pass_index: the plan has a tail; this pass is the tail pass.
const MDTS_WITH_TAIL: u32 = 0x10000;
const MDTS_TAIL_PASS: u32 = 0x20000;

/// `mdts:K` (`wide`: `mdts64:K`): K words a pixel kept sorted by atomic min, the 32-bit mode's
/// depth and colour in a 20+12-bit packing over two words (alpha is the plan's), the 64-bit mode's
/// depth above RGBA8. With `--atomic-storage image` the words are storage images (modules
/// `mdts_image`, `mdts64_image`: the same technique over the image accessors).
fn mdts<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R, wide: bool) -> Result<(), OitError> {
    // the plan refuses Fresnel with the 32-bit words (no room for a normal)
    let deepest = if ctx.plan().needs_count() { count(ctx, raster)?.1 } else { 0 };
    let k = ctx.plan().slots(deepest);
    let mut storage = Storage::new(ctx, deepest);
    // alpha is not stored in the 32-bit mode: the plan's (the override, else the objects' mean)
    let mode = if wide { MDTS_64 } else { MDTS_32 | ctx.plan().mdts_alpha8 << 8 };
    let (module, arrays) = match (ctx.plan().image_atomics, wide) {
        (true, true) => {
            storage.images(ctx, "sorted slots", 8, &[ImageFormat::R64Uint], u32::MAX)?;
            ("mdts64_image", [ctx.placeholder()?, ctx.placeholder()?, ctx.placeholder()?])
        }
        (true, false) => {
            let formats = [ImageFormat::R32Uint, ImageFormat::R32Uint];
            storage.images(ctx, "sorted slots", 8, &formats, u32::MAX)?;
            ("mdts_image", [ctx.placeholder()?, ctx.placeholder()?, ctx.placeholder()?])
        }
        (false, true) => {
            let slots = storage.buffer(ctx, "sorted slots", Init::Fill(u32::MAX))?;
            ("mdts", [ctx.placeholder()?, ctx.placeholder()?, slots])
        }
        (false, false) => {
            // the high and low words apart
            let fields = [(4, Init::Fill(u32::MAX)), (4, Init::Fill(u32::MAX))];
            let [high, low] = storage.buffers(ctx, "sorted slots", fields)?;
            ("mdts", [high, low, ctx.placeholder()?])
        }
    };
    let (tail, tail_words) = tail_buffers(ctx, &mut storage)?;
    let unused = ctx.placeholder()?;
    let buffers = [&arrays[0], &arrays[1], &arrays[2], &unused, &tail, &tail_words];
    let mode = if ctx.plan().tail { mode | MDTS_WITH_TAIL } else { mode };
    ctx.geometry_pass(raster, module, &buffers, mode, k)?;
    if ctx.plan().tail {
        // where the capture raised the overflow word
        ctx.geometry_pass_if(raster, module, &buffers, mode | MDTS_TAIL_PASS, k, &tail_words)?;
        ctx.note_merged(&tail_words);
    }
    ctx.pixel_kernel(module, "resolve_main", &buffers, mode, k)?;
    storage.finish()
}

/// The dynamic fragment buffer: a counting pass, the counts' prefix sum into per-pixel offsets,
/// a fill into exactly the frame's fragments, each pixel's range sorted by (depth, primitive id).
fn dfb<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels()) + 1;
    // fragments per pixel; the last entry stays 0, so the offsets end in the total
    let mut storage = Storage::new(ctx, 0);
    let counts = storage.buffer(ctx, "counts", Init::Zero)?;
    ctx.geometry_pass(raster, "dfb_count", &[&counts], 0, 0)?;
    let offsets = storage.buffer(ctx, "offsets", Init::Zero)?;
    ctx.copy(&counts, &offsets, entries * 4)?;
    let total = scan(ctx, &offsets, entries)?;
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    storage.hold(u64::from(ctx.plan().check_fragments(u64::from(total))?));
    // each pixel's range is filled whole before the resolve reads it
    let [keys, payloads] = storage.buffers(ctx, "entries", [(8, Init::Unwritten), (4, Init::Unwritten)])?;
    let masks = storage.masks(ctx)?;
    let buffers = [&counts, &offsets, &keys, &payloads, &masks];
    ctx.geometry_pass(raster, "dfb", &buffers, 0, 0)?;
    ctx.pixel_kernel("dfb", "resolve_main", &buffers, 0, 0)?;
    storage.finish()
}

/// `LL_END` of `ll.wgsl`: an empty list's head, a last node's link.
const LL_END: u32 = u32::MAX;

/// Per-pixel linked lists: a pass that only counts the frame's fragments sizes the node pool;
/// nodes taken by an atomic counter and linked by atomic exchange; each list sorted by (depth,
/// primitive id) at the resolve.
fn ll<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let generated = ctx.geometry_pass_counted(raster, "ll_size", &[], 0, 0)?;
    // a u64 key, a u32 payload and a u32 link a node
    let nodes = ctx.fragment_capacity(&generated, 16)?;
    let nodes = ctx.plan().check_fragments(u64::from(nodes))?;
    let mut storage = Storage::new(ctx, 0);
    storage.hold(u64::from(nodes));
    let heads = storage.buffer(ctx, "heads", Init::Fill(LL_END))?;
    let counter = storage.buffer(ctx, "node counter", Init::Zero)?;
    // a node is written whole (key, payload, link) when the counter hands it out, before any
    // list reaches it
    let fields = [(8, Init::Unwritten), (4, Init::Unwritten), (4, Init::Unwritten)];
    let [keys, payloads, links] = storage.buffers(ctx, "nodes", fields)?;
    let masks = storage.masks(ctx)?;
    let buffers = [&heads, &counter, &keys, &payloads, &links, &masks];
    ctx.geometry_pass(raster, "ll", &buffers, 0, nodes)?;
    ctx.pixel_kernel("ll", "resolve_main", &buffers, 0, nodes)?;
    storage.finish()
}

/// The ordered k-buffer: K sorted (depth, primitive id) slots and their payloads (and, at several
/// samples, their coverage masks), kept by a
/// read-modify-write inside the fragment shader's ordered interlock (oit-vulkan's hardware path;
/// the plan refuses it elsewhere, `Plan::refuse_interlock`).
fn kbuf<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let deepest = if ctx.plan().needs_count() { count(ctx, raster)?.1 } else { 0 };
    let k = ctx.plan().slots(deepest);
    let mut storage = Storage::new(ctx, deepest);
    let slots = storage.buffer(ctx, "sorted slots", Init::Fill(u32::MAX))?;
    let payloads = storage.buffer(ctx, "payloads", Init::Zero)?;
    let masks = storage.masks(ctx)?;
    let buffers = [&slots, &payloads, &masks];
    ctx.geometry_pass(raster, "kbuf", &buffers, 0, k)?;
    ctx.pixel_kernel("kbuf", "resolve_main", &buffers, 0, k)?;
    storage.finish()
}

#[cfg(test)]
mod tests {
    //! [`Storage`] against a frame that only records what it is asked to allocate.

    use oit_core::plan::{Counted, Plan};
    use oit_core::{GpuFragments, OitError, Settings, Technique, load_scene};

    use super::Storage;
    use crate::{Frame, ImageFormat, Init};

    /// A frame that allocates nothing but notes each array's words (and each image's bytes).
    struct Fake {
        plan: Plan,
        settings: Settings,
        arrays: Vec<u64>,
    }

    impl Frame<()> for Fake {
        type Buffer = ();
        fn plan(&self) -> &Plan {
            &self.plan
        }
        fn settings(&self) -> &Settings {
            &self.settings
        }
        fn pixels(&self) -> u32 {
            self.settings.width * self.settings.height
        }
        fn backend(&self) -> &'static str {
            "fake"
        }
        fn array(&mut self, _: &str, words: u64, _: Init) -> Result<(), OitError> {
            self.arrays.push(words);
            Ok(())
        }
        fn storage_image(
            &mut self,
            _: &str,
            _: u32,
            layers: u32,
            f: ImageFormat,
            _: u32,
        ) -> Result<(), OitError> {
            self.arrays.push(u64::from(self.pixels()) * u64::from(layers) * f.bytes() / 4);
            Ok(())
        }
        fn scratch(&mut self, _: &str, _: u64, _: Init) -> Result<(), OitError> {
            Ok(())
        }
        fn placeholder(&mut self) -> Result<(), OitError> {
            Ok(())
        }
        fn fill(&mut self, _: &(), _: u32) -> Result<(), OitError> {
            unreachable!("not a pass")
        }
        fn copy(&mut self, _: &(), _: &(), _: u64) -> Result<(), OitError> {
            unreachable!("not a pass")
        }
        fn read_u32(&mut self, _: &()) -> Result<Vec<u32>, OitError> {
            unreachable!("not a pass")
        }
        fn last_pass(&mut self, _: bool) {}
        fn cut(&mut self, _: bool) {}
        fn note_opaque(&mut self, _: &()) {}
        fn geometry_pass(
            &mut self,
            _: &(),
            _: &'static str,
            _: &[&()],
            _: u32,
            _: u32,
        ) -> Result<(), OitError> {
            unreachable!("not a pass")
        }
        fn geometry_pass_counted(
            &mut self,
            _: &(),
            _: &'static str,
            _: &[&()],
            _: u32,
            _: u32,
        ) -> Result<(), OitError> {
            unreachable!("not a pass")
        }
        fn geometry_pass_if(
            &mut self,
            _: &(),
            _: &'static str,
            _: &[&()],
            _: u32,
            _: u32,
            _: &(),
        ) -> Result<(), OitError> {
            unreachable!("not a pass")
        }
        fn fragments(&self) -> GpuFragments {
            unreachable!("not a pass")
        }
        fn set_fragments(&mut self, _: GpuFragments) {}
        fn kernel_over(
            &mut self,
            _: &'static str,
            _: &'static str,
            _: &[&()],
            _: u64,
            _: u32,
            _: u32,
            _: &'static str,
        ) -> Result<(), OitError> {
            unreachable!("not a pass")
        }
        fn deepest_alike(&mut self, _: &(), _: Box<dyn Fn(u32, u32) -> bool>) -> Result<u32, OitError> {
            unreachable!("not a pass")
        }
        fn fragment_capacity(&mut self, _: &(), _: u64) -> Result<u32, OitError> {
            unreachable!("not a pass")
        }
        fn take_speculated_peels(&mut self) -> Result<Option<u32>, OitError> {
            Ok(None)
        }
        fn note_peels(&mut self, _: u32) {}
        fn check_at_end(&mut self, _: &()) {}
        fn refuse_at_end(&mut self, _: &(), _: String) {}
        fn note_merged(&mut self, _: &()) {}
        fn note_layers(&mut self, _: &()) {}
    }

    fn fake(technique: &str) -> Fake {
        let settings = Settings {
            technique: technique.parse::<Technique>().expect("a technique"),
            width: 8,
            height: 4,
            ..Settings::default()
        };
        let scene = load_scene("planes:3").expect("a procedural scene");
        let plan = Plan::new("fake", &scene, &settings).expect("a plan");
        Fake { plan, settings, arrays: Vec::new() }
    }

    /// What a frame takes is the plan's bytes, field by field and as images alike; a technique
    /// that asks for what its plan does not name, takes an array twice, splits it into fields of
    /// other bytes, or leaves one out is refused. Mutations caught: `take` matching any array
    /// (the unnamed request passes), `finish` returning Ok unconditionally (the left-out payloads
    /// pass), the field check dropped (the 12-byte split of 8-byte slots passes).
    #[test]
    fn storage_is_the_plans_arrays_and_refuses_the_rest() {
        let mut ctx = fake("fabs:3");
        let mut storage = Storage::new(&ctx, 0);
        storage.buffer(&mut ctx, "counter", Init::Zero).unwrap();
        let [(), ()] = storage.buffers(&mut ctx, "slots", [(4, Init::Zero), (4, Init::Zero)]).unwrap();
        storage.buffer(&mut ctx, "payloads", Init::Zero).unwrap();
        storage.finish().unwrap();
        let words: u64 = ctx.arrays.iter().sum();
        let plan_bytes =
            ctx.plan.storage_bytes(32, Counted::default()) - 32 * oit_core::plan::RESOLVE_STATE_BYTES;
        assert_eq!(words * 4, plan_bytes, "{:?}", ctx.arrays);

        let mut storage = Storage::new(&ctx, 0);
        assert!(storage.buffer(&mut ctx, "nodes", Init::Zero).is_err(), "an array fabs's plan lacks");
        storage.buffer(&mut ctx, "slots", Init::Zero).unwrap();
        assert!(storage.buffer(&mut ctx, "slots", Init::Zero).is_err(), "taken twice");
        assert!(
            storage.buffers(&mut ctx, "payloads", [(8, Init::Zero), (4, Init::Zero)]).is_err(),
            "12 ≠ 4 bytes"
        );
        assert!(storage.finish().is_err(), "the counter and payloads left out");

        // the image kind of the same array: the same bytes
        let mut ctx = fake("fabs:3");
        let mut storage = Storage::new(&ctx, 0);
        storage.images(&mut ctx, "counter", 9, &[ImageFormat::R32Uint], 0).unwrap();
        assert_eq!(ctx.arrays, [32]);
        assert!(storage.images(&mut ctx, "slots", 9, &[ImageFormat::R32Uint], 0).is_err(), "8-byte slots");

        // an exact allocation needs its fragments first
        let mut ctx = fake("ll");
        let mut storage = Storage::new(&ctx, 0);
        let fields = [(8, Init::Zero), (4, Init::Zero), (4, Init::Zero)];
        assert!(storage.buffers(&mut ctx, "nodes", fields).is_err(), "before hold");
        let mut storage = Storage::new(&ctx, 0);
        storage.hold(100);
        storage.buffers(&mut ctx, "nodes", fields).unwrap();
        assert_eq!(ctx.arrays, [200, 100, 100]);
    }
}
