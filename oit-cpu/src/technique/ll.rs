//! `ll`: per-pixel linked lists (Yang, Hensley, Grün, Thibieroz, "Real-Time Concurrent Linked
//! List Construction on the GPU", EGSR 2010). A head per pixel, cleared to the end marker; one
//! pool of nodes; one node counter. The capture takes a node by atomic increment of the counter,
//! writes the fragment into it and links it in front of its pixel's list by atomic exchange of
//! the head. The resolve walks each list, sorts it by (depth, primitive id) and composites it.
//!
//! The paper sizes the pool by a guess; here a sizing pass (a geometry pass that stores nothing:
//! every pass counts the fragments it generates) gives the frame's fragments, and the pool has
//! exactly that many nodes. A fragment that finds the pool used up (a fill pass that met more
//! fragments than the sizing pass, which oit's repeatable rasterizers never do) is counted in
//! `lost` at its pixel, never dropped in silence.
//!
//! On oit-cpu both passes run by bands of rows
//! ([`Rasterizer::for_each_fragment_by_band`](crate::raster::Rasterizer::for_each_fragment_by_band)),
//! each band walked by one task. The sizing pass counts each band's fragments; in the capture each
//! band takes that many nodes from the counter by one atomic add (as GPU code aggregates a warp's
//! increments into one) and links them into its own pixels' lists with a plain load
//! and store of the head, which no other task writes. The lists, the sort and the image are the
//! same; what goes is a locked increment of one shared word per fragment, which on the 2-core VM
//! of issue 12 doubled the armadillo's frame in some processes and not in others.
//!
//! Storage: a 4-byte head a pixel, the counter, and 16 bytes a node: the 64-bit key (depth bits,
//! primitive id), the 32-bit payload and the 32-bit link. Carrying the id, `ll` orders ties as
//! the reference does and never counts `tied`.
//!
//! oit-wgpu's `technique/ll.rs` runs the same passes.

use oit_core::Compositor as _;
use std::cell::Cell;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use oit_core::plan::Counted;
use oit_core::rules::{depth_bits, depth_from_bits};
use oit_core::{Frame, OitError};

use super::Ctx;
use crate::raster::{Fragment, Shade};
use crate::storage::sort_keys;

/// The link of a list's last node, and the head of an empty list.
pub(crate) const END: u32 = u32::MAX;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // the sizing pass: the frame's fragments, counted by the pass itself, band by band
    let per_band = ctx.raster.for_each_fragment_by_band(Shade::OnDemand, |_| |_: &Fragment<'_>| {});
    ctx.ran_pass(per_band.iter().sum());
    let nodes = ctx.plan.check_fragments(ctx.fragments.unwrap_or(0))?;
    // ll's arrays follow the frame's fragments alone (no per-pixel count: deepest unknown, unused)
    ctx.check_counted(Counted { deepest: 0, fragments: u64::from(nodes) })?;
    capture_and_resolve(ctx, &per_band, nodes)
}

/// A band's block of a pool's nodes: as many as the sizing pass counted in the band, taken from
/// the pool's counter by one atomic add (saturating: a block past the counter's range lies past
/// the pool), then handed out one a fragment by the band's one task; `None` past the block or
/// past the pool's `nodes`, where the fragment is lost. Single-sample `ll` and `ll` at several
/// samples (`msaa.rs`) take their nodes so.
pub(crate) struct BandBlock {
    next: Cell<u32>,
    end: u32,
}

impl BandBlock {
    /// The block of `want` nodes from `counter`, in a pool of `nodes`.
    pub(crate) fn take(counter: &AtomicU32, want: u64, nodes: u32) -> BandBlock {
        let want = u32::try_from(want).unwrap_or(u32::MAX);
        let first =
            counter.fetch_update(Relaxed, Relaxed, |c| Some(c.saturating_add(want))).unwrap_or_else(|c| c);
        BandBlock { next: Cell::new(first), end: first.saturating_add(want).min(nodes) }
    }

    /// The block's next node, if any is left.
    pub(crate) fn next(&self) -> Option<u32> {
        let node = self.next.get();
        (node < self.end).then(|| {
            self.next.set(node + 1);
            node
        })
    }
}

/// The capture into a pool of `nodes` nodes, band by band (`per_band`: each band's fragments,
/// as the sizing pass counted them), and the resolve.
fn capture_and_resolve(ctx: &mut Ctx<'_>, per_band: &[u64], nodes: u32) -> Result<Frame, OitError> {
    let heads = ctx.alloc32(1, END)?;
    let counter = ctx.words32(1, 0)?;
    let keys = ctx.words64(u64::from(nodes), 0)?;
    let payloads = ctx.words32(u64::from(nodes), 0)?;
    let links = ctx.words32(u64::from(nodes), END)?;
    let shade = ctx.payload_shade();
    let raster = ctx.raster;
    let shared = &*ctx;
    let (heads, keys, payloads, links) = (&heads, &keys, &payloads, &links);
    // By bands of rows (the banded pass): each band takes its nodes from the counter in one
    // block, as many as the sizing pass counted in it, and links them into its own pixels'
    // lists, which no other task writes, by a plain load and store of the head. An atomic
    // increment a fragment had both threads fight over the counter's cache line: on the 2-core
    // VM of issue 12 the armadillo's frame ran 11–13 ms in one process and 23–24 ms in another,
    // the same binary. Past its block (or the pool) a fragment is counted lost.
    let generated = raster.for_each_fragment_by_band(shade, |b| {
        let block = BandBlock::take(&counter[0], per_band.get(b).copied().unwrap_or(0), nodes);
        move |f: &Fragment<'_>| {
            let px = f.pixel as usize;
            let Some(node) = block.next() else {
                // the band's block, or the pool, is used up: no node for this fragment
                shared.lose(px);
                return;
            };
            let n = node as usize;
            keys[n].store(u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim), Relaxed);
            payloads[n].store(shared.payload(f), Relaxed);
            // the band's own pixel: no other thread writes this head during the pass
            links[n].store(heads[px].load(Relaxed), Relaxed);
            heads[px].store(node, Relaxed);
        }
    });
    ctx.ran_pass(generated.iter().sum());
    let resolve = &ctx.resolve;
    Ok(super::finish_with(ctx, |px, list: &mut Vec<u128>, s| {
        list.clear();
        let mut node = heads[px].load(Relaxed);
        while node != END {
            let n = node as usize;
            // (depth bits, primitive id) above the payload: the payload never decides
            list.push(u128::from(keys[n].load(Relaxed)) << 32 | u128::from(payloads[n].load(Relaxed)));
            node = links[n].load(Relaxed);
        }
        sort_keys(list);
        for &key in list.iter() {
            resolve.push(s, depth_from_bits((key >> 64) as u32), key as u32);
        }
    }))
}

#[cfg(test)]
mod tests {
    use oit_core::plan::Plan;
    use oit_core::{Camera, Settings, Technique, View, load_scene};

    use super::*;
    use crate::pool::Pool;
    use crate::raster::Rasterizer;

    /// A pool smaller than the frame's fragments (a fill pass meeting more fragments than the
    /// sizing pass) loses exactly the fragments past it, each counted at its pixel.
    #[test]
    fn a_pool_too_small_counts_what_it_loses() {
        let scene = load_scene("planes:4").unwrap();
        let settings = Settings { width: 16, height: 16, technique: Technique::Ll, ..Settings::default() };
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        let raster = Rasterizer::new(&scene, &camera, &settings);
        let pool = Pool::default();
        let plan = Plan::new("cpu", &scene, &settings).unwrap();
        let mut ctx =
            Ctx::new(&scene, &camera, &settings, &raster, &pool, plan, scene.absorption_per_length(), None);
        let per_band =
            raster.for_each_fragment_by_band(crate::raster::Shade::OnDemand, |_| |_: &Fragment<'_>| {});
        assert!(per_band.len() > 1, "the case wants several bands, each taking its block");
        let frame = capture_and_resolve(&mut ctx, &per_band, 40).unwrap();
        let s = &frame.stats;
        assert!(s.fragments > 200, "the case needs far more fragments than nodes: {}", s.fragments);
        assert_eq!((s.captured, s.lost), (40, s.fragments - 40));
        let per_pixel: u64 = frame.lost_pixels.unwrap().iter().map(|&l| u64::from(l)).sum();
        assert_eq!(per_pixel, s.lost);
    }
}
