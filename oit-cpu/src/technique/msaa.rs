//! Multisampled frames (`Settings::samples` above 1, issue 40; docs/msaa.md): the techniques
//! that carry each fragment's coverage mask beside its key and composite per sample.
//!
//! Every pass here is [`Rasterizer::for_each_masked_fragment`](crate::raster::Rasterizer::for_each_masked_fragment):
//! a (pixel, triangle) pair is a fragment where the triangle covers any of the pixel's samples,
//! shaded once at the pixel's centre, with its coverage mask. A fragment is one entry whatever
//! its mask (the lists and the K slots size by fragments, as single-sample's), and the mask is
//! kept in a byte beside the entry's key and payload (8 samples at most).
//!
//! The resolve: each pixel's entries sorted by (depth, primitive id) as single-sample's; then
//! each sample composites, nearest first, only the entries whose mask holds it, over the
//! background, and the pixel is the mean of its samples in linear light, encoded to sRGB8 as
//! single-sample's. A pixel whose entries all cover every sample composites once (the mean of
//! equal samples). Fragments of one surface split across an edge therefore never stack: each
//! sample sees the one that covers it.
//!
//! - `reference`: the per-sample exact A-buffer, composited in f64 as the single-sample
//!   reference ([`super::reference::composite_f64`]).
//! - `reference` with `Settings::supersample`: the supersampled reference, every sample
//!   rasterized and shaded as a pixel of its own: one single-sample reference frame a sample
//!   position, the camera moved by the position's offset from the centre, averaged in linear
//!   light.
//! - `dfb` and `ll`: their single-sample passes (a counting pass and a fill), each entry with its
//!   mask, resolved per sample through the f32 resolve. `ll`'s run by bands of rows as
//!   single-sample's do
//!   ([`Rasterizer::for_each_masked_fragment_by_band`](crate::raster::Rasterizer::for_each_masked_fragment_by_band):
//!   the same fragments and masks), each band taking its block of nodes by one atomic add.
//! - `fabs`: K slots a pixel, each with its mask; the pixels that overflow keep their K nearest
//!   by (depth, primitive id), as single-sample's (two more passes). `--overflow tail` merges
//!   what lies behind the K into one tail a pixel, each fragment's alpha weighted by its coverage
//!   fraction, and each sample composites its covering slots over that tail.
//!
//! With `Settings::pixel_coverage` (`--coverage pixel`) every technique here but the reference
//! keeps each fragment's mask as the full mask: the per-pixel capture baseline.
//!
//! Every other technique keeps no mask: its own passes run over the multisampled fragments
//! ([`crate::raster::Rasterizer::cover`]), each over its whole pixel with its alpha weighted by
//! its coverage fraction, or at full alpha with `--coverage pixel` (`oit_core::msaa::coverage`).

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use glam::{DVec3, Vec3};
use oit_core::composite::heat_f64;
use oit_core::plan::Counted;
use oit_core::rules::{depth_bits, depth_from_bits};
use oit_core::{Compositor as _, Effect, Frame, Image, OitError, Settings, Technique};
use rayon::prelude::*;

use super::Ctx;
use super::reference::{composite_f64, srgb8_f64};
use crate::raster::{Fragment, Shade, prefetch};
use crate::resolve::PixelState;

/// One captured entry: the key (depth bits above the primitive id), the payload, the mask.
type Entry = (u64, u32, u8);

/// Runs `technique`'s multisampled frame over `ctx`.
pub(crate) fn render(ctx: &mut Ctx<'_>, technique: Technique) -> Result<Frame, OitError> {
    match technique {
        Technique::Reference if ctx.settings.supersample => supersampled(ctx),
        Technique::Reference => reference(ctx),
        Technique::Dfb => dfb(ctx),
        Technique::Ll => ll(ctx),
        Technique::Fabs { .. } => fabs(ctx),
        other => {
            Err(OitError::Unsupported { backend: "cpu".into(), what: format!("{other} at several samples") })
        }
    }
}

/// A fragment's key: depth bits above the primitive id.
#[inline]
pub(crate) fn key(f: &Fragment<'_>) -> u64 {
    u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim)
}

/// A fragment's key in the per-sample peels, its coverage `mask`'s lowest sample below its
/// primitive id ([`oit_core::msaa::peel_key`]: a clipped triangle's pieces apart).
#[inline]
pub(crate) fn peel_key(f: &Fragment<'_>, mask: u8) -> u64 {
    oit_core::msaa::peel_key(depth_bits(f.depth), f.prim, mask)
}

/// The mask a technique keeps of a fragment's `mask`: the mask itself, or every sample of the
/// pixel with `--coverage pixel` (the per-pixel capture baseline).
fn coverage(settings: &Settings) -> impl Fn(u8) -> u8 + Sync + Copy {
    let full = if settings.pixel_coverage { oit_core::msaa::full_mask(settings.samples) } else { 0 };
    move |mask| mask | full
}

/// One masked geometry pass, counted.
fn pass<F: Fn(&Fragment<'_>, u8) + Sync>(ctx: &mut Ctx<'_>, f: F) -> u64 {
    let n = ctx.raster.for_each_masked_fragment(ctx.settings.samples, f);
    ctx.ran_pass(n);
    n
}

/// Per-pixel fragment counts from one masked pass (not counted as storage: the counting pass's
/// array is the fill's cursors where a technique keeps it).
fn counts(ctx: &mut Ctx<'_>, counts: &[AtomicU32]) {
    pass(ctx, |f, _| {
        counts[f.pixel as usize].fetch_add(1, Relaxed);
    });
}

/// Counts a task of [`offsets_of`]'s and [`deepest_and_total`]'s sweeps takes.
const SCAN_CHUNK: usize = 1 << 14;

/// Exclusive prefix sum of `counts` into `offsets` (one longer), the total returned: each chunk's
/// sum in parallel, the chunks' starts in order, then each chunk's offsets from its start in
/// parallel (the same offsets as one serial sum: integers).
fn offsets_of(counts: &[AtomicU32]) -> (Vec<usize>, usize) {
    let sums: Vec<usize> =
        counts.par_chunks(SCAN_CHUNK).map(|c| c.iter().map(|v| v.load(Relaxed) as usize).sum()).collect();
    let mut total = 0usize;
    let starts: Vec<usize> = sums
        .iter()
        .map(|&s| {
            let start = total;
            total += s;
            start
        })
        .collect();
    let mut offsets = vec![0usize; counts.len() + 1];
    offsets[..counts.len()]
        .par_chunks_mut(SCAN_CHUNK)
        .zip(counts.par_chunks(SCAN_CHUNK))
        .zip(starts)
        .for_each(|((out, counts), start)| {
            let mut at = start;
            for (o, c) in out.iter_mut().zip(counts) {
                *o = at;
                at += c.load(Relaxed) as usize;
            }
        });
    offsets[counts.len()] = total;
    (offsets, total)
}

/// The largest of `counts` and their sum, in one parallel sweep.
fn deepest_and_total(counts: &[AtomicU32]) -> (u32, u64) {
    counts
        .par_chunks(SCAN_CHUNK)
        .map(|c| {
            c.iter().map(|v| v.load(Relaxed)).fold((0u32, 0u64), |(m, t), v| (m.max(v), t + u64::from(v)))
        })
        .reduce(|| (0, 0), |a, b| (a.0.max(b.0), a.1 + b.1))
}

/// The per-sample exact reference.
fn reference(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let counted = ctx.alloc32(1, 0)?;
    counts(ctx, &counted);
    let (offsets, total) = offsets_of(&counted);
    let deepest = counted.iter().map(|c| c.load(Relaxed)).max().unwrap_or(0);
    ctx.check_counted(Counted { deepest, fragments: total as u64 })?;
    ctx.storage_bytes += offsets.len() as u64 * 4;
    let cursor = ctx.pool.u32s(counted.len(), 0);
    let keys = ctx.scratch_words64(total as u64)?;
    let payloads = ctx.scratch_words32(total as u64)?;
    let masks = ctx.scratch_bytes(total as u64)?;
    let shared = &*ctx;
    let n = shared.raster.for_each_masked_fragment_with(
        shared.settings.samples,
        shared.payload_shade(),
        |f, mask| {
            let px = f.pixel as usize;
            let slot = offsets[px] + cursor[px].fetch_add(1, Relaxed) as usize;
            keys[slot].store(key(f), Relaxed);
            payloads[slot].store(shared.payload(f), Relaxed);
            masks[slot].store(mask, Relaxed);
        },
    );
    ctx.ran_pass(n);
    drop(cursor);
    let counts: Vec<u32> = counted.iter().map(|c| c.load(Relaxed)).collect();
    let (keys, payloads, masks) = (&*keys, &*payloads, &*masks);
    let (camera, effect, per_length) = (ctx.camera, ctx.settings.effect, ctx.per_length);
    let samples = ctx.settings.samples;
    let full = oit_core::msaa::full_mask(samples);
    let resolve = &ctx.resolve;
    let deepest = deepest.max(1);
    let pixels: Vec<[u8; 4]> = (0..counts.len())
        .into_par_iter()
        .map_init(Vec::new, |list: &mut Vec<Entry>, px| {
            list.clear();
            list.extend(
                (offsets[px]..offsets[px + 1])
                    .map(|i| (keys[i].load(Relaxed), payloads[i].load(Relaxed), masks[i].load(Relaxed))),
            );
            list.sort_unstable();
            let bg = |i: u32| resolve.background_at_sample(px, i as usize).as_dvec3();
            let c = match effect {
                Effect::Complexity if counts[px] == 0 => resolve.background_mean(px).as_dvec3(),
                Effect::Complexity => heat_f64(f64::from(counts[px]) / f64::from(deepest)),
                _ if resolve.opaque_uniform(px) && list.iter().all(|e| e.2 == full) => {
                    composite_f64(effect, camera, per_length, list.iter().map(|e| (e.0, e.1)), bg(0))
                }
                _ => {
                    // each sample over its own opaque colour (the background where none covers it)
                    let sum: DVec3 = (0..samples)
                        .map(|i| {
                            let covering = list.iter().filter(|e| e.2 >> i & 1 == 1).map(|e| (e.0, e.1));
                            composite_f64(effect, camera, per_length, covering, bg(i))
                        })
                        .sum();
                    sum / f64::from(samples)
                }
            };
            srgb8_f64(c)
        })
        .collect();
    let image = Image { width: ctx.settings.width, height: ctx.settings.height, pixels };
    let mut frame = super::frame(ctx, image, total as u64);
    frame.stats.max_layers = counts.iter().copied().max().unwrap_or(0);
    frame.layers = Some(counts);
    Ok(frame)
}

/// The supersampled reference: a single-sample reference frame a sample position, the
/// projection moved so that the position falls on the pixels' centres, the frames' linear
/// colours averaged (every sample rasterized and shaded as a pixel of its own); the frames and
/// their totals are oit-core's, alike on every backend ([`oit_core::msaa::supersample_frames`]).
/// In a scene with opaque objects ([`Ctx::opaque_part`]) each frame draws its own opaque pass at
/// one sample under its moved camera, as any single-sample frame: its depth cuts that frame's
/// transparent fragments, its colour is what they composite over.
fn supersampled(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let settings = ctx.settings;
    let (single, cameras) = oit_core::msaa::supersample_frames(ctx.camera, settings);
    let mut sum = vec![DVec3::ZERO; ctx.pixels];
    let mut totals = oit_core::msaa::SupersampleTotals::default();
    for camera in &cameras {
        let mut raster = crate::raster::Rasterizer::new(ctx.scene, camera, &single);
        let opaque = ctx.opaque_part.map(|o| crate::opaque::draw(o, camera, &single));
        raster.cut_at(opaque.as_ref().map(|o| o.depth.clone()));
        let plan = oit_core::plan::Plan::new("cpu", ctx.scene, &single)?.on_path(oit_core::RasterPath::Cpu);
        let mut inner =
            Ctx::new(ctx.scene, camera, &single, &raster, ctx.pool, plan, ctx.per_length, opaque.as_ref());
        let (linear, layer_counts, captured) = super::reference::linear(&mut inner)?;
        for (s, c) in sum.iter_mut().zip(linear) {
            *s += c;
        }
        let mut stats = oit_core::Stats {
            geometry_passes: inner.passes,
            fragments: inner.fragments.unwrap_or(0),
            captured,
            storage_bytes: inner.storage_bytes,
            max_layers: layer_counts.iter().copied().max().unwrap_or(0),
            ..Default::default()
        };
        drop(inner);
        if let Some(o) = &opaque {
            // (the reference's counting pass ran behind the cut, so it counted the occluded)
            stats.occluded = raster.occluded().unwrap_or(0);
            stats.opaque_fragments = o.fragments;
            stats.masked = o.masked;
            stats.geometry_passes += o.passes;
            stats.storage_bytes += ctx.pixels as u64 * oit_core::plan::OPAQUE_BYTES;
        }
        totals.add(&stats, Some(&layer_counts), Some(&vec![0; ctx.pixels]));
    }
    let n = f64::from(settings.samples);
    let pixels = sum.into_iter().map(|c| srgb8_f64(c / n)).collect();
    let image = Image { width: settings.width, height: settings.height, pixels };
    Ok(Frame { image, layers: totals.layers, lost_pixels: totals.lost_pixels, stats: totals.stats })
}

/// The f32 per-sample resolve of every pixel's entries, gathered by `gather(px, list)` (which
/// clears and fills `list`); sorted here. With `tail` (fabs's `--overflow tail` sums, 5 a pixel)
/// each sample composites its entries over the pixel's tail ([`crate::resolve::Resolve::tail_over`]:
/// one tail a pixel, its fragments' alpha weighted by their coverage fractions), put over that
/// sample's own opaque colour (the background where none covers it).
fn resolve_entries(
    ctx: &Ctx<'_>,
    tail: Option<&[AtomicU64]>,
    gather: impl Fn(usize, &mut Vec<Entry>) + Sync,
) -> Frame {
    let samples = ctx.settings.samples;
    let full = oit_core::msaa::full_mask(samples);
    let resolve = &ctx.resolve;
    let complexity = ctx.settings.effect == Effect::Complexity;
    let deepest = if complexity {
        (0..ctx.pixels)
            .into_par_iter()
            .map_init(Vec::new, |list, px| {
                gather(px, list);
                list.len() as u32
            })
            .max()
            .unwrap_or(0)
            .max(1)
    } else {
        1
    };
    let push_all = |s: &mut PixelState, entries: &mut dyn Iterator<Item = &Entry>| {
        for e in entries {
            resolve.push(s, depth_from_bits((e.0 >> 32) as u32), e.1);
        }
    };
    // sample i's state: nothing pushed, the pixel's tail behind (where it has one) over the
    // sample's own opaque colour
    let fresh = |px: usize, i: usize| {
        let mut s = PixelState::default();
        if let Some(t) = tail {
            resolve.tail_over(&mut s, &t[px * 5..px * 5 + 5], resolve.background_at_sample(px, i));
        }
        s
    };
    // each task's list of a pixel's entries, kept from pixel to pixel
    super::finish_pixels_with(ctx, Vec::new, |list: &mut Vec<Entry>, px| {
        gather(px, list);
        list.sort_unstable();
        let c: Vec3 = if complexity {
            if list.is_empty() {
                resolve.background_mean(px)
            } else {
                oit_core::composite::heat(list.len() as f32 / deepest as f32)
            }
        } else if resolve.opaque_uniform(px) && list.iter().all(|e| e.2 == full) {
            let mut s = fresh(px, 0);
            push_all(&mut s, &mut list.iter());
            resolve.finish_over(&mut s, resolve.background_at_sample(px, 0))
        } else {
            // each sample over its own opaque colour (the background where none covers it),
            // the samples' colours summed in sample order; a sample that composites the same
            // entries over the same colour as an earlier one takes its colour (the same
            // bits: the same pushes over the same state)
            let mut seen = [(0u64, [0u32; 3], Vec3::ZERO); 8];
            let mut distinct = 0;
            let mut sum = Vec3::ZERO;
            for i in 0..samples {
                let bg = resolve.background_at_sample(px, i as usize);
                let bits = bg.to_array().map(f32::to_bits);
                // the entries covering sample i, a bit each (none kept past 64 entries)
                let covering = (list.len() <= 64).then(|| {
                    list.iter().enumerate().fold(0u64, |m, (k, e)| m | u64::from(e.2 >> i & 1) << k)
                });
                let known =
                    covering.and_then(|set| seen[..distinct].iter().find(|s| s.0 == set && s.1 == bits));
                let c = match known {
                    Some(s) => s.2,
                    None => {
                        let mut s = fresh(px, i as usize);
                        push_all(&mut s, &mut list.iter().filter(|e| e.2 >> i & 1 == 1));
                        let c = resolve.finish_over(&mut s, bg);
                        if let Some(set) = covering {
                            seen[distinct] = (set, bits, c);
                            distinct += 1;
                        }
                        c
                    }
                };
                sum += c;
            }
            sum / samples as f32
        };
        (crate::resolve::srgb(c), list.len() as u32)
    })
}

/// `dfb` per sample: a counting pass, the offsets, a fill by atomic decrement of the counts, each
/// entry with its mask.
fn dfb(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let entries = ctx.pixels as u64 + 1;
    let counted = ctx.words32(entries, 0)?;
    counts(ctx, &counted);
    let (offsets, total) = offsets_of(&counted[..ctx.pixels]);
    ctx.storage_bytes += entries * 4;
    let total = ctx.plan.check_fragments(total as u64)?;
    let (deepest, _) = deepest_and_total(&counted);
    ctx.check_counted(Counted { deepest, fragments: u64::from(total) })?;
    let keys = ctx.words64(u64::from(total), 0)?;
    let payloads = ctx.words32(u64::from(total), 0)?;
    let masks = ctx.scratch_bytes(u64::from(total))?;
    let shared = &*ctx;
    let kept = coverage(shared.settings);
    // the pixel's count and the line its entries end in asked for ahead (filled from the end)
    let ahead = |p: u32| {
        let px = p as usize;
        prefetch(&counted[px]);
        let last = offsets[px + 1].saturating_sub(1).min(keys.len().saturating_sub(1));
        if let Some(key) = keys.get(last) {
            prefetch(key);
            prefetch(&payloads[last]);
            prefetch(&masks[last]);
        }
    };
    let n = shared.raster.for_each_masked_fragment_ahead(
        shared.settings.samples,
        shared.payload_shade(),
        &ahead,
        |f, mask| {
            let px = f.pixel as usize;
            let left = counted[px].fetch_sub(1, Relaxed);
            if left as i32 <= 0 {
                shared.lose(px);
                return;
            }
            let entry = offsets[px] + left as usize - 1;
            keys[entry].store(key(f), Relaxed);
            payloads[entry].store(shared.payload(f), Relaxed);
            masks[entry].store(kept(mask), Relaxed);
        },
    );
    ctx.ran_pass(n);
    let (keys, payloads, masks, counted) = (&*keys, &*payloads, &*masks, &*counted);
    Ok(resolve_entries(ctx, None, |px, list| {
        let unfilled = (counted[px].load(Relaxed) as i32).max(0) as usize;
        list.clear();
        list.extend(
            (offsets[px] + unfilled..offsets[px + 1])
                .map(|i| (keys[i].load(Relaxed), payloads[i].load(Relaxed), masks[i].load(Relaxed))),
        );
    }))
}

/// The end of a list and the head of an empty one.
const END: u32 = u32::MAX;

/// `ll` per sample: single-sample `ll`'s passes ([`super::ll`]) over the masked fragments, each
/// node with its mask. The sizing pass counts each band's fragments
/// ([`Rasterizer::for_each_masked_fragment_by_band`](crate::raster::Rasterizer::for_each_masked_fragment_by_band));
/// the pool has exactly the frame's fragments.
fn ll(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let samples = ctx.settings.samples;
    let per_band = ctx
        .raster
        .for_each_masked_fragment_by_band(samples, Shade::OnDemand, None, |_| |_: &Fragment<'_>, _: u8| {});
    let fragments = per_band.iter().sum();
    ctx.ran_pass(fragments);
    let nodes = ctx.plan.check_fragments(fragments)?;
    ctx.check_counted(Counted { deepest: 0, fragments: u64::from(nodes) })?;
    ll_capture_and_resolve(ctx, &per_band, nodes)
}

/// `ll`'s capture into a pool of `nodes` nodes by bands of rows (`per_band`: each band's
/// fragments, as the sizing pass counted them), and the resolve. Each band takes its block of
/// nodes from the counter by one atomic add and links them into its own pixels' lists, which no
/// other task writes, by a plain load and store of the head: a locked increment of one shared
/// counter a fragment (and an exchange of the head) had both threads of a 2-core VM fight over
/// the counter's line, the bunny's 4-sample frame at 1024² taking twice as long in some
/// processes as in others (issue 40), as single-sample's did before its bands (issue 12). A
/// fragment past its band's block or the pool (a fill pass meeting more fragments than the
/// sizing pass, which oit's repeatable rasterizers never do) is counted lost at its pixel.
fn ll_capture_and_resolve(ctx: &mut Ctx<'_>, per_band: &[u64], nodes: u32) -> Result<Frame, OitError> {
    let heads = ctx.alloc32(1, END)?;
    let counter = ctx.words32(1, 0)?;
    let keys = ctx.words64(u64::from(nodes), 0)?;
    let payloads = ctx.words32(u64::from(nodes), 0)?;
    let masks = ctx.scratch_bytes(u64::from(nodes))?;
    let links = ctx.words32(u64::from(nodes), END)?;
    let shared = &*ctx;
    let kept = coverage(shared.settings);
    let (heads, counter, keys, payloads, masks, links) = (&heads, &counter, &keys, &payloads, &masks, &links);
    // the pixel's head asked for ahead (a band's nodes come in order from its block)
    let ahead = |p: u32| prefetch(&heads[p as usize]);
    let generated = shared.raster.for_each_masked_fragment_by_band(
        shared.settings.samples,
        shared.payload_shade(),
        Some(&ahead),
        |b| {
            let block = super::ll::BandBlock::take(&counter[0], per_band.get(b).copied().unwrap_or(0), nodes);
            move |f: &Fragment<'_>, mask: u8| {
                let px = f.pixel as usize;
                let Some(node) = block.next() else {
                    // the band's block, or the pool, is used up: no node for this fragment
                    shared.lose(px);
                    return;
                };
                let i = node as usize;
                keys[i].store(key(f), Relaxed);
                payloads[i].store(shared.payload(f), Relaxed);
                masks[i].store(kept(mask), Relaxed);
                // the band's own pixel: no other thread writes this head during the pass
                links[i].store(heads[px].load(Relaxed), Relaxed);
                heads[px].store(node, Relaxed);
            }
        },
    );
    ctx.ran_pass(generated.iter().sum());
    Ok(resolve_entries(ctx, None, |px, list| {
        list.clear();
        let mut node = heads[px].load(Relaxed);
        while node != END {
            let i = node as usize;
            list.push((keys[i].load(Relaxed), payloads[i].load(Relaxed), masks[i].load(Relaxed)));
            node = links[i].load(Relaxed);
        }
    }))
}

/// `fabs:K` per sample: a counter a pixel hands each fragment one of the pixel's K slots (one a
/// fragment whatever its mask); a pixel past K keeps its K nearest keys, refilled by two more
/// passes as single-sample's, payload and mask following the key.
fn fabs(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    let deepest = if ctx.plan.needs_count() {
        let counted = ctx.alloc32(1, 0)?;
        counts(ctx, &counted);
        ctx.storage_bytes -= ctx.pixels as u64 * 4;
        let (deepest, fragments) = deepest_and_total(&counted);
        ctx.check_counted(Counted { deepest, fragments })?;
        deepest
    } else {
        0
    };
    let k = ctx.plan.slots(deepest) as usize;
    let counters = ctx.alloc32(1, 0)?;
    let slots = ctx.scratch64(k)?;
    let payloads = ctx.scratch32(k)?;
    let masks = ctx.scratch_bytes((ctx.pixels as u64).saturating_mul(k as u64))?;
    let tail = ctx.tail_sums()?;
    let shared = &*ctx;
    let kept = coverage(shared.settings);
    // the pixel's counter and the line of its first slot, payload and mask asked for ahead
    let ahead = |p: u32| {
        let px = p as usize;
        prefetch(&counters[px]);
        if k > 0 {
            prefetch(&slots[px * k]);
            prefetch(&payloads[px * k]);
            prefetch(&masks[px * k]);
        }
    };
    let n = shared.raster.for_each_masked_fragment_ahead(
        shared.settings.samples,
        shared.payload_shade(),
        &ahead,
        |f, mask| {
            let px = f.pixel as usize;
            let i = counters[px].fetch_add(1, Relaxed) as usize;
            if i < k {
                slots[px * k + i].store(key(f), Relaxed);
                payloads[px * k + i].store(shared.payload(f), Relaxed);
                masks[px * k + i].store(kept(mask), Relaxed);
            } else {
                shared.lose(px);
            }
        },
    );
    ctx.ran_pass(n);
    let list = crate::storage::CountedList::new(&counters, &slots, &payloads, k);
    if !ctx.plan.needs_count() && list.empty_overflowing() {
        // the K nearest keys of each overflowing pixel, whatever the arrival order (the lost
        // count stays what the capture counted: the fragments past K), then each kept key's
        // payload and mask written beside it
        let nearest = list.nearest();
        // the other pixels cost these passes their walk only, not their samples' tests
        let overflowed = |px: u32| list.overflowed(px as usize);
        ctx.raster.for_each_masked_fragment_where(ctx.settings.samples, &overflowed, |f, _| {
            oit_core::AtomicFragmentList::insert(&nearest, f.pixel as usize, key(f));
        });
        let shared = &*ctx;
        let kept = coverage(shared.settings);
        shared.raster.for_each_masked_fragment_where(shared.settings.samples, &overflowed, |f, mask| {
            let px = f.pixel as usize;
            let word = key(f);
            let at = (px * k..px * k + k).find(|&i| slots[i].load(Relaxed) == word);
            if let Some(i) = at {
                payloads[i].store(shared.payload(f), Relaxed);
                masks[i].store(kept(mask), Relaxed);
            }
        });
        ctx.passes += 2;
        if let Some(sums) = &tail {
            // `--overflow tail`: every fragment behind an overflowing pixel's K nearest (sorted
            // now: the last is the largest) merged into the pixel's one tail, its alpha weighted
            // by its coverage fraction, as the techniques without a mask weigh theirs
            let samples = ctx.settings.samples;
            let kept = coverage(ctx.settings);
            let nearest = &nearest;
            ctx.tail_pass_masked(sums, |f, mask| {
                let px = f.pixel as usize;
                let behind = list.overflowed(px)
                    && oit_core::AtomicFragmentList::last(nearest, px).is_some_and(|last| key(f) > last);
                behind.then(|| {
                    let mut color = f.color();
                    color.w = oit_core::msaa::fraction_alpha(color.w, kept(mask), samples);
                    oit_core::rules::pack_rgba8(color)
                })
            });
        }
    }
    let (counters, slots, payloads, masks) = (&*counters, &*slots, &*payloads, &*masks);
    Ok(resolve_entries(ctx, tail.as_deref().map(|t| &t[..]), |px, list| {
        list.clear();
        let n = (counters[px].load(Relaxed) as usize).min(k);
        list.extend(
            (px * k..px * k + n)
                .map(|i| (slots[i].load(Relaxed), payloads[i].load(Relaxed), masks[i].load(Relaxed))),
        );
    }))
}

/// The per-sample accumulators of the peels that composite per sample (`dp`, `ddp`;
/// docs/msaa.md): `halves` (1 for dp, 2 for ddp) `[f32; 4]` a sample, each (RGB, transmittance)
/// from (0, 1): the front composited nearest first (premultiplied colour under what is in front,
/// as `FrontToBack::under`), and ddp's back farthest first, kept without what lies behind it (its
/// colour and the transmittance to the background), so sample `i` finishes to
/// front.rgb + front.t · (back.rgb + back.t · behind(i)). Fresnel multiplies the transmittances
/// only; the heat map counts layers a pixel. The GPU's `technique/peel_samples.wgsl` keeps the same.
pub(crate) struct SampleAccumulators {
    words: Vec<[f32; 4]>,
    samples: usize,
    halves: usize,
}

impl SampleAccumulators {
    /// `halves` accumulators a sample of every pixel, counted in the frame's storage.
    pub fn new(ctx: &mut Ctx<'_>, halves: usize) -> Result<Self, OitError> {
        let samples = ctx.settings.samples as usize;
        let n = (ctx.pixels as u64).saturating_mul((samples * halves) as u64);
        let len = ctx.checked(n, 16)?;
        Ok(SampleAccumulators { words: vec![[0.0, 0.0, 0.0, 1.0]; len], samples, halves })
    }

    /// Each pixel's accumulators, in parallel with `other`.
    pub fn pixels_mut(&mut self) -> rayon::slice::ChunksMut<'_, [f32; 4]> {
        self.words.par_chunks_mut(self.samples * self.halves)
    }
}

/// Composites one layer (payload `payload`, coverage mask `mask`) into the accumulators `acc`
/// of a pixel (`halves` a sample): into each covered sample's front (`back` false), nearest
/// first, or its back (`back` true, ddp), farthest first.
pub(crate) fn accumulate(
    ctx: &Ctx<'_>,
    acc: &mut [[f32; 4]],
    halves: usize,
    payload: u32,
    mask: u8,
    back: bool,
) {
    let effect = ctx.settings.effect;
    let (colour, factor) = match effect {
        Effect::Transparency => {
            let c = oit_core::rules::unpack_rgba8(payload);
            (c, 1.0 - c.w)
        }
        Effect::Fresnel => {
            let n = oit_core::rules::unpack_normal(payload);
            (glam::Vec4::ZERO, oit_core::composite::schlick_transmittance(n.dot(ctx.camera.forward)))
        }
        _ => return,
    };
    let rgb = colour.truncate();
    for (i, sample) in acc.chunks_mut(halves).enumerate() {
        if mask >> i & 1 == 0 {
            continue;
        }
        let a = &mut sample[usize::from(back)];
        let (c, t) = (Vec3::new(a[0], a[1], a[2]), a[3]);
        let c = if effect != Effect::Transparency {
            c
        } else if back {
            colour.w * rgb + (1.0 - colour.w) * c
        } else {
            c + t * colour.w * rgb
        };
        *a = [c.x, c.y, c.z, t * factor];
    }
}

/// The linear colour of a pixel from its accumulators `acc` (`halves` a sample): each sample
/// finished over what lies behind it (its opaque colour, or the background), summed in sample
/// order, times 1/N.
pub(crate) fn accumulated(ctx: &Ctx<'_>, acc: &[[f32; 4]], halves: usize, px: usize) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for (i, sample) in acc.chunks(halves).enumerate() {
        let behind = ctx.resolve.background_at_sample(px, i);
        let back = match sample.get(1) {
            Some(b) => Vec3::new(b[0], b[1], b[2]) + b[3] * behind,
            None => behind,
        };
        let f = sample[0];
        sum += Vec3::new(f[0], f[1], f[2]) + f[3] * back;
    }
    sum * (1.0 / ctx.settings.samples as f32)
}

/// The frame of a peel composited per sample: each pixel's colour from its accumulators (or the
/// mean of its samples' backgrounds where it captured nothing, the heat map under complexity),
/// `captured[px]` layers a pixel.
pub(crate) fn finish_accumulated(ctx: &Ctx<'_>, acc: &SampleAccumulators, captured: &[u32]) -> Frame {
    let resolve = &ctx.resolve;
    let per = acc.samples * acc.halves;
    let deepest = captured.iter().copied().max().unwrap_or(0).max(1);
    let complexity = ctx.settings.effect == Effect::Complexity;
    super::finish_pixels(ctx, |px| {
        let n = captured[px];
        let c = if n == 0 {
            resolve.background_mean(px)
        } else if complexity {
            oit_core::composite::heat(n as f32 / deepest as f32)
        } else {
            accumulated(ctx, &acc.words[px * per..px * per + per], acc.halves, px)
        };
        (crate::resolve::srgb(c), n)
    })
}

#[cfg(test)]
mod tests {
    use oit_core::plan::Plan;
    use oit_core::{Camera, Technique, View, load_scene};

    use super::*;
    use crate::pool::Pool;
    use crate::raster::Rasterizer;

    /// `ll` at 4 samples with a pool smaller than the frame's fragments (a fill pass meeting more
    /// fragments than the sizing pass) loses exactly the fragments past it, each counted at its
    /// pixel; and a band whose block is short of its fragments loses its own excess, counted at
    /// its own pixels, never taking another band's nodes (the pool's spare nodes left unused).
    /// Mutations caught: the loss not counted (a fragment past its block dropped in silence),
    /// each band sized by the next band's count.
    #[test]
    fn ll_pool_or_block_too_small_counts_what_it_loses() {
        let scene = load_scene("planes:4").unwrap();
        let settings =
            Settings { width: 16, height: 16, technique: Technique::Ll, samples: 4, ..Settings::default() };
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        let raster = Rasterizer::new(&scene, &camera, &settings);
        let pool = Pool::default();
        let per_band = raster
            .for_each_masked_fragment_by_band(4, Shade::OnDemand, None, |_| |_: &Fragment<'_>, _: u8| {});
        assert!(per_band.len() > 1, "the case wants several bands, each taking its block");
        let total: u64 = per_band.iter().sum();
        let run = |per_band: &[u64], nodes: u32| {
            let plan = Plan::new("cpu", &scene, &settings).unwrap();
            let mut ctx = Ctx::new(
                &scene,
                &camera,
                &settings,
                &raster,
                &pool,
                plan,
                scene.absorption_per_length(),
                None,
            );
            ll_capture_and_resolve(&mut ctx, per_band, nodes).unwrap()
        };
        let frame = run(&per_band, 40);
        let s = &frame.stats;
        assert!(s.fragments > 200, "the case needs far more fragments than nodes: {}", s.fragments);
        assert_eq!(s.fragments, total);
        assert_eq!((s.captured, s.lost), (40, s.fragments - 40));
        let per_pixel: u64 = frame.lost_pixels.unwrap().iter().map(|&l| u64::from(l)).sum();
        assert_eq!(per_pixel, s.lost);
        // the exact pool loses nothing
        let exact = run(&per_band, u32::try_from(total).unwrap());
        assert_eq!((exact.stats.captured, exact.stats.lost), (total, 0));
        // the first band's block 5 short, the pool whole: its 5 are lost, in its rows
        let short = 5;
        assert!(per_band[0] > short, "the first band has {} fragments", per_band[0]);
        let mut less = per_band.clone();
        less[0] -= short;
        let frame = run(&less, u32::try_from(total).unwrap());
        assert_eq!((frame.stats.captured, frame.stats.lost), (total - short, short));
        let lost = frame.lost_pixels.unwrap();
        // (16 rows: bands of 8 rows, the fewest a band takes, whatever the threads)
        assert_eq!(per_band.len(), 2);
        let band_pixels = 8 * 16;
        assert_eq!(lost.iter().map(|&l| u64::from(l)).sum::<u64>(), short);
        assert!(
            lost.iter().enumerate().all(|(px, &l)| l == 0 || px < band_pixels),
            "a loss outside the first band's rows"
        );
    }
}
