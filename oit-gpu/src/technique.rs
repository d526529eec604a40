//! Every technique's GPU frame, written once over [`Frame`]: the same passes, storage and
//! resolve as oit-cpu's `technique/*.rs`, in the WGSL modules of oit-shaders. What a module's
//! bindings hold is said where its buffers are made; the bindings start at 2 of group 0 in the
//! order of each `buffers` array.
//!
//! The hardware path's own captures (blending, depth tests, logic ops) are each backend's; they
//! run instead of these where the settings ask for them (`--hardware-capture blend`).

use oit_core::rules::{BDP_COLOR_SUBINTERVALS, BDP_DEPTH_SUBINTERVALS, BUCKETS, HISTOGRAM_WORDS};
use oit_core::{BoundsMode, Effect, OitError, Technique};

use crate::{Frame, ImageFormat, Init, Rasters};

/// Runs the frame of the settings' technique through `rasters`: its passes, kernels and resolve
/// into the frame's state (the reference also leaves its per-pixel fragment counts for the
/// frame's `layers`).
pub fn render<R: ?Sized, F: Frame<R>>(ctx: &mut F, rasters: &impl Rasters<R>) -> Result<(), OitError> {
    match ctx.settings().technique {
        Technique::Reference => reference(ctx, rasters.scene()),
        Technique::Plain => plain(ctx, rasters.scene()),
        Technique::Fabs { .. } => fabs(ctx, rasters.scene()),
        Technique::Dp => dp(ctx, rasters.scene()),
        Technique::Ddp => ddp(ctx, rasters.scene()),
        Technique::WeightedAverage => weighted(ctx, rasters.scene(), true),
        Technique::WeightedSum => weighted(ctx, rasters.scene(), false),
        Technique::Wboit => wboit(ctx, rasters.scene()),
        Technique::Mboit { m } => mboit(ctx, rasters.scene(), m),
        Technique::Bdp { .. } => bdp(ctx, rasters),
        Technique::Adp => adp(ctx, rasters),
        Technique::Mdts { .. } => mdts(ctx, rasters.scene(), false),
        Technique::Mdts64 { .. } => mdts(ctx, rasters.scene(), true),
        Technique::Mlp { m } => mlp(ctx, rasters.scene(), m),
        Technique::Dfb => dfb(ctx, rasters.scene()),
        Technique::Ll => ll(ctx, rasters.scene()),
        Technique::Kbuf { .. } => kbuf(ctx, rasters.scene()),
    }
}

/// The buffers of `tail.wgsl` (`--overflow tail`), bound at 6 and 7: the tail sums (5 u64 a
/// pixel, `Plan::arrays`'s "tail sums") and two words of bookkeeping (overflowed, merged);
/// placeholders where the plan has no tail.
fn tail_buffers<R: ?Sized, F: Frame<R>>(ctx: &mut F) -> Result<(F::Buffer, F::Buffer), OitError> {
    if !ctx.plan().tail {
        return Ok((ctx.placeholder()?, ctx.placeholder()?));
    }
    let sums = ctx.array("tail sums", u64::from(ctx.pixels()) * 5 * 2, Init::Zero)?;
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
    let limit = ctx.plan().peel_limit;
    let speculated = ctx.take_speculated_peels(raster)?.filter(|&s| s >= 1).map(|s| s.min(limit));
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
    let offsets = ctx.array("reference offsets", entries, Init::Zero)?;
    ctx.copy(&counts, &offsets, entries * 4)?;
    let total = scan(ctx, &offsets, entries)?;
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    let total = u64::from(ctx.plan().check_fragments(u64::from(total))?);
    let cursor = ctx.array("reference cursor", u64::from(ctx.pixels()), Init::Zero)?;
    let keys = ctx.array("reference keys", total * 2, Init::Zero)?;
    let payloads = ctx.array("reference payloads", total, Init::Zero)?;
    let buffers = [&offsets, &cursor, &keys, &payloads];
    ctx.geometry_pass(raster, "reference", &buffers, 0, 0)?;
    ctx.pixel_kernel("reference", "resolve_main", &buffers, 0, 0)
}

/// `plain` where no rasterizer keeps submission order (the compute path): each pixel's fragments
/// kept (a counter and K slots of (primitive id, payload), K from a counting pass) and
/// composited in primitive order. Translucency and Fresnel are refused by the plan.
fn plain<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let deepest = count(ctx, raster)?.1;
    let k = ctx.plan().slots(deepest);
    let px = u64::from(ctx.pixels());
    let counters = ctx.array("plain counters", px, Init::Zero)?;
    let slots = ctx.array("plain slots", px * u64::from(k) * 2, Init::Zero)?;
    let buffers = [&counters, &slots];
    ctx.geometry_pass(raster, "plain", &buffers, 0, k)?;
    ctx.pixel_kernel("plain", "plain_resolve_main", &buffers, 0, k)
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
    let px = u64::from(ctx.pixels());
    let (module, counters) = if ctx.plan().image_atomics {
        ctx.storage_image("fabs counters", 8, 1, ImageFormat::R32Uint, 0)?;
        ("fabs_image", ctx.placeholder()?)
    } else {
        ("fabs", ctx.array("fabs counters", px, Init::Zero)?)
    };
    let slots = ctx.array("fabs slots", px * u64::from(k) * 2, Init::Zero)?;
    let payloads = ctx.array("fabs payloads", px * u64::from(k), Init::Zero)?;
    let overflowed = ctx.scratch("fabs overflowed", 1, Init::Zero)?;
    let (tail, tail_words) = tail_buffers(ctx)?;
    let buffers = [&counters, &slots, &payloads, &overflowed, &tail, &tail_words];
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
    ctx.pixel_kernel(module, "resolve_main", &buffers, resolve, k)
}

/// `wavg` (`average`) and `wsum`: one pass summing each pixel's premultiplied colour, alpha and
/// count in 64-bit integers (5 u64 a pixel), composited by the weighted formula. Translucency and
/// Fresnel are refused by the plan.
fn weighted<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R, average: bool) -> Result<(), OitError> {
    let sums = ctx.array("weighted sums", u64::from(ctx.pixels()) * 5 * 2, Init::Zero)?;
    ctx.geometry_pass(raster, "weighted", &[&sums], 0, 0)?;
    ctx.pixel_kernel("weighted", "composite_main", &[&sums], 0, u32::from(average))
}

/// Weighted blended OIT (McGuire & Bavoil 2013): one pass summing each pixel's Σ α·w·c, Σ α·w,
/// optical depth and count in 64-bit integers (6 u64 a pixel), composited as the weighted mean
/// colour under the exact coverage. Translucency and Fresnel are refused by the plan.
fn wboit<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let sums = ctx.array("wboit sums", u64::from(ctx.pixels()) * 6 * 2, Init::Zero)?;
    ctx.geometry_pass(raster, "wboit", &[&sums], 0, 0)?;
    ctx.pixel_kernel("wboit", "composite_main", &[&sums], 0, 0)
}

/// Moment-based OIT (Münstermann et al. 2018) with `m` = 4 power moments: a first pass sums each
/// pixel's optical depth and its moments, a second weighs each fragment by the transmittance the
/// moments bound in front of it and sums Σ T·α·c, Σ T·α and the count (m + 6 u64 a pixel, one
/// array); composited as the weighted colours under the exact total coverage. Translucency and
/// Fresnel are refused by the plan.
fn mboit<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R, m: u32) -> Result<(), OitError> {
    let sums = ctx.array("mboit sums", u64::from(ctx.pixels()) * (u64::from(m) + 6) * 2, Init::Zero)?;
    ctx.geometry_pass(raster, "mboit", &[&sums], 0, m)?;
    ctx.geometry_pass(raster, "mboit", &[&sums], 1, m)?;
    ctx.pixel_kernel("mboit", "composite_main", &[&sums], 0, m)
}

/// Depth peeling: one layer a pass, front to back, until a pass peels nothing ([`peel`]).
fn dp<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let px = u64::from(ctx.pixels());
    let nearest = ctx.array("dp nearest", px * 2, Init::Fill(u32::MAX))?;
    // the previous pass's depth buffer (oit-cpu counts 4 bytes a pixel too)
    let previous = ctx.array("dp previous depth", px, Init::Zero)?;
    let peeled = ctx.scratch("dp peeled count", 1, Init::Zero)?;
    let buffers = [&nearest, &previous, &peeled];
    peel(ctx, raster, "dp", &buffers, &peeled, 0, 0)
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

/// `ddp.wgsl`'s storage, allocated and initialised by its `ddp_init_main`: the near and far
/// (depth key, colour) words, the open depth range the previous pass left (oit-cpu counts 8 bytes
/// a pixel too), and the count of pixels that peeled a layer in the last pass (bookkeeping).
/// Shared with the backends' blend captures of ddp, which resolve through `ddp.wgsl` too.
pub fn ddp_state<R: ?Sized, F: Frame<R>>(ctx: &mut F) -> Result<[F::Buffer; 4], OitError> {
    let px = u64::from(ctx.pixels());
    let near = ctx.array("ddp near", px * 2, Init::Fill(u32::MAX))?;
    let far = ctx.array("ddp far", px * 2, Init::Zero)?;
    let range = ctx.array("ddp range", px * 2, Init::Zero)?;
    let peeled = ctx.scratch("ddp peeled count", 1, Init::Zero)?;
    ctx.pixel_kernel("ddp", "ddp_init_main", &[&near, &far, &range, &peeled], 0, 0)?;
    Ok([near, far, range, peeled])
}

/// Dual depth peeling: the nearest and farthest layer a pass ([`peel`]).
fn ddp<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
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
    let px = u64::from(ctx.pixels());
    let slots = ctx.array("mlp slots", px * u64::from(m) * 2, Init::Fill(u32::MAX))?;
    // the previous pass's deepest depth (oit-cpu counts 4 bytes a pixel too)
    let deepest = ctx.array("mlp deepest", px, Init::Zero)?;
    let overflowed = ctx.scratch("mlp overflowed", 1, Init::Zero)?;
    let buffers = [&slots, &deepest, &overflowed];
    peel(ctx, raster, "mlp", &buffers, &overflowed, m, 1)
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
) -> Result<F::Buffer, OitError> {
    let bounds = ctx.array("depth bounds", 2 * u64::from(ctx.pixels()), Init::Zero)?;
    ctx.pixel_kernel("bounds", "bounds_init_main", &[&bounds], 0, 0)?;
    match ctx.settings().bounds {
        BoundsMode::Exact => ctx.geometry_pass(rasters.scene(), "bounds", &[&bounds], 0, 0)?,
        BoundsMode::Boxes => {
            let fragments = ctx.fragments();
            rasters.with_boxes(&mut |boxes| ctx.geometry_pass(boxes, "bounds", &[&bounds], 0, 0))?;
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
    let bounds = depth_bounds(ctx, rasters)?;
    let raster = rasters.scene();
    if ctx.plan().bdp_color {
        let n = u64::from(BDP_COLOR_SUBINTERVALS);
        let colors = ctx.array("bdp colour buckets", u64::from(ctx.pixels()) * n, Init::Zero)?;
        let arrays = ctx.placeholder()?;
        let buffers = [&bounds, &colors, &arrays];
        ctx.geometry_pass(raster, "bdp", &buffers, 0, BDP_MODE_COLOR)?;
        return ctx.pixel_kernel("bdp", "color_resolve_main", &buffers, 0, 0);
    }
    // one array per capture pass run: P, or fewer under --max-peels (the plan's stop rule)
    let run = ctx.plan().bdp_capture_passes();
    // 16 × (min, max) u64 a pixel a pass
    let words = u64::from(ctx.pixels()) * 2 * u64::from(BDP_DEPTH_SUBINTERVALS) * 2;
    let arrays = ctx.array("bdp depth buckets", words * u64::from(run), Init::Zero)?;
    let pairs = words * u64::from(run) / 4;
    let colors = ctx.placeholder()?;
    let buffers = [&bounds, &colors, &arrays];
    ctx.kernel_over("bdp", "depth_init_main", &buffers, pairs, 0, 0, "depth_init_main")?;
    for p in 0..run {
        ctx.last_pass(p + 1 == run);
        ctx.geometry_pass(raster, "bdp", &buffers, p, BDP_MODE_DEPTH)?;
        ctx.pixel_kernel("bdp", "depth_settle_main", &buffers, p, BDP_MODE_DEPTH)?;
    }
    ctx.last_pass(false);
    ctx.pixel_kernel("bdp", "depth_resolve_main", &buffers, 0, run)
}

/// Adaptive bucket depth peeling: the depth bounds, a 1024-bit histogram pass (by the backend's
/// own capture where it has one, [`Frame::histogram_capture`]), the deepest pixel's set-bin
/// count, then one capture and resolve per batch of 32 bins, each bucket keeping its bin's
/// farthest and nearest fragment.
fn adp<R: ?Sized, F: Frame<R>>(ctx: &mut F, rasters: &impl Rasters<R>) -> Result<(), OitError> {
    let bounds = depth_bounds(ctx, rasters)?;
    let raster = rasters.scene();
    let px = u64::from(ctx.pixels());
    let hist = ctx.array("adp histogram", px * HISTOGRAM_WORDS as u64, Init::Zero)?;
    // sizing the batches is not per-pixel storage: oit-cpu does not count it either
    let max_bins = ctx.scratch("adp deepest pixel", 1, Init::Zero)?;
    // oit-cpu allocates the buckets after the histogram pass; the bytes are the same
    let buckets = ctx.array("adp buckets", px * BUCKETS as u64 * 2, Init::Zero)?;
    let nearest = ctx.array("adp nearest", px * BUCKETS as u64 * 2, Init::Fill(u32::MAX))?;
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
    Ok(())
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
    let words = u64::from(ctx.pixels()) * u64::from(k);
    // alpha is not stored in the 32-bit mode: the plan's (the override, else the objects' mean)
    let mode = if wide { MDTS_64 } else { MDTS_32 | ctx.plan().mdts_alpha8 << 8 };
    let (module, arrays) = match (ctx.plan().image_atomics, wide) {
        (true, true) => {
            ctx.storage_image("mdts64 keys", 8, k, ImageFormat::R64Uint, u32::MAX)?;
            ("mdts64_image", [ctx.placeholder()?, ctx.placeholder()?, ctx.placeholder()?])
        }
        (true, false) => {
            ctx.storage_image("mdts high words", 8, k, ImageFormat::R32Uint, u32::MAX)?;
            ctx.storage_image("mdts low words", 9, k, ImageFormat::R32Uint, u32::MAX)?;
            ("mdts_image", [ctx.placeholder()?, ctx.placeholder()?, ctx.placeholder()?])
        }
        (false, true) => {
            let slots = ctx.array("mdts64 slots", words * 2, Init::Fill(u32::MAX))?;
            ("mdts", [ctx.placeholder()?, ctx.placeholder()?, slots])
        }
        (false, false) => {
            let high = ctx.array("mdts high words", words, Init::Fill(u32::MAX))?;
            let low = ctx.array("mdts low words", words, Init::Fill(u32::MAX))?;
            ("mdts", [high, low, ctx.placeholder()?])
        }
    };
    let (tail, tail_words) = tail_buffers(ctx)?;
    let unused = ctx.placeholder()?;
    let buffers = [&arrays[0], &arrays[1], &arrays[2], &unused, &tail, &tail_words];
    let mode = if ctx.plan().tail { mode | MDTS_WITH_TAIL } else { mode };
    ctx.geometry_pass(raster, module, &buffers, mode, k)?;
    if ctx.plan().tail {
        // where the capture raised the overflow word
        ctx.geometry_pass_if(raster, module, &buffers, mode | MDTS_TAIL_PASS, k, &tail_words)?;
        ctx.note_merged(&tail_words);
    }
    ctx.pixel_kernel(module, "resolve_main", &buffers, mode, k)
}

/// The dynamic fragment buffer: a counting pass, the counts' prefix sum into per-pixel offsets,
/// a fill into exactly the frame's fragments, each pixel's range sorted by (depth, primitive id).
fn dfb<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let entries = u64::from(ctx.pixels()) + 1;
    // fragments per pixel; the last entry stays 0, so the offsets end in the total
    let counts = ctx.array("dfb counts", entries, Init::Zero)?;
    ctx.geometry_pass(raster, "dfb_count", &[&counts], 0, 0)?;
    let offsets = ctx.array("dfb offsets", entries, Init::Zero)?;
    ctx.copy(&counts, &offsets, entries * 4)?;
    let total = scan(ctx, &offsets, entries)?;
    // a u64 key and a u32 payload a fragment
    let total = ctx.fragment_capacity(&total, 12)?;
    let total = u64::from(ctx.plan().check_fragments(u64::from(total))?);
    let keys = ctx.array("dfb keys", total * 2, Init::Zero)?;
    let payloads = ctx.array("dfb payloads", total, Init::Zero)?;
    let buffers = [&counts, &offsets, &keys, &payloads];
    ctx.geometry_pass(raster, "dfb", &buffers, 0, 0)?;
    ctx.pixel_kernel("dfb", "resolve_main", &buffers, 0, 0)
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
    let heads = ctx.array("ll heads", u64::from(ctx.pixels()), Init::Fill(LL_END))?;
    let counter = ctx.array("ll node counter", 1, Init::Zero)?;
    let keys = ctx.array("ll keys", u64::from(nodes) * 2, Init::Zero)?;
    let payloads = ctx.array("ll payloads", u64::from(nodes), Init::Zero)?;
    let links = ctx.array("ll links", u64::from(nodes), Init::Fill(LL_END))?;
    let buffers = [&heads, &counter, &keys, &payloads, &links];
    ctx.geometry_pass(raster, "ll", &buffers, 0, nodes)?;
    ctx.pixel_kernel("ll", "resolve_main", &buffers, 0, nodes)
}

/// The ordered k-buffer: K sorted (depth, primitive id) slots and their payloads, kept by a
/// read-modify-write inside the fragment shader's ordered interlock (oit-vulkan's hardware path;
/// the plan refuses it elsewhere, `Plan::refuse_interlock`).
fn kbuf<R: ?Sized, F: Frame<R>>(ctx: &mut F, raster: &R) -> Result<(), OitError> {
    let deepest = if ctx.plan().needs_count() { count(ctx, raster)?.1 } else { 0 };
    let k = ctx.plan().slots(deepest);
    let px = u64::from(ctx.pixels());
    let slots = ctx.array("kbuf slots", px * u64::from(k) * 2, Init::Fill(u32::MAX))?;
    let payloads = ctx.array("kbuf payloads", px * u64::from(k), Init::Zero)?;
    let buffers = [&slots, &payloads];
    ctx.geometry_pass(raster, "kbuf", &buffers, 0, k)?;
    ctx.pixel_kernel("kbuf", "resolve_main", &buffers, 0, k)
}
