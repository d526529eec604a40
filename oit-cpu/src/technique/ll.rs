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
//! Storage: a 4-byte head a pixel, the counter, and 16 bytes a node: the 64-bit key (depth bits,
//! primitive id), the 32-bit payload and the 32-bit link. Carrying the id, `ll` orders ties as
//! the reference does and never counts `tied`.
//!
//! oit-wgpu's `technique/ll.rs` runs the same passes.

use oit_core::Compositor as _;
use std::sync::atomic::Ordering::Relaxed;

use oit_core::rules::{depth_bits, depth_from_bits};
use oit_core::{Frame, OitError};
use rayon::prelude::*;

use super::Ctx;
use super::fabs::sort_keys;

/// The link of a list's last node, and the head of an empty list.
pub(crate) const END: u32 = u32::MAX;

pub(crate) fn render(ctx: &mut Ctx<'_>) -> Result<Frame, OitError> {
    // the sizing pass: the frame's fragments, counted by the pass itself
    ctx.pass(|_| {});
    let nodes = ctx.plan.check_fragments(ctx.fragments.unwrap_or(0))?;
    capture_and_resolve(ctx, nodes)
}

/// The capture into a pool of `nodes` nodes, and the resolve.
fn capture_and_resolve(ctx: &mut Ctx<'_>, nodes: u32) -> Result<Frame, OitError> {
    let heads = ctx.alloc32(1, END)?;
    let counter = ctx.words32(1, 0)?;
    let keys = ctx.words64(u64::from(nodes), 0)?;
    let payloads = ctx.words32(u64::from(nodes), 0)?;
    let links = ctx.words32(u64::from(nodes), END)?;
    ctx.pass_lossy(|f, ctx| {
        let px = f.pixel as usize;
        let node = counter[0].fetch_add(1, Relaxed);
        if node >= nodes {
            // the pool is used up: no node for this fragment
            ctx.lose(px);
            return;
        }
        let n = node as usize;
        keys[n].store(u64::from(depth_bits(f.depth)) << 32 | u64::from(f.prim), Relaxed);
        payloads[n].store(ctx.payload(f), Relaxed);
        links[n].store(heads[px].swap(node, Relaxed), Relaxed);
    });
    let mut states = ctx.states();
    let resolve = &ctx.resolve;
    states.par_iter_mut().zip(heads.par_iter()).for_each_init(Vec::new, |list, (s, head)| {
        list.clear();
        let mut node = head.load(Relaxed);
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
    });
    Ok(super::finish(ctx, states))
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
            Ctx::new(&scene, &camera, &settings, &raster, &pool, plan, scene.absorption_per_length());
        let frame = capture_and_resolve(&mut ctx, 40).unwrap();
        let s = &frame.stats;
        assert!(s.fragments > 200, "the case needs far more fragments than nodes: {}", s.fragments);
        assert_eq!((s.captured, s.lost), (40, s.fragments - 40));
        let per_pixel: u64 = frame.lost_pixels.unwrap().iter().map(|&l| u64::from(l)).sum();
        assert_eq!(per_pixel, s.lost);
    }
}
