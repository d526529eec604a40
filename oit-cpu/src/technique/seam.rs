//! The capture traits as the seam: each technique that keeps per-pixel fragment lists runs over
//! oit-cpu's atomic lists and, unchanged, over [`LockedList`], a second implementation of
//! [`AtomicFragmentList`] written here the slow and obvious way (a mutex and a vector a pixel).
//! The frames must be equal, and the second list must have seen every fragment offered and every
//! pixel read: a technique that kept its own words beside the list it is given fails both.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use oit_core::{
    AtomicFragmentList, Camera, Frame, OitError, Overflow, RasterPath, Scene, Settings, Technique, View,
};

use super::{Ctx, fabs, mdts, mlp};
use crate::pool::Pool;
use crate::raster::Rasterizer;

/// Which fragment a full [`LockedList`] drops.
#[derive(Clone, Copy)]
enum Keep {
    /// The K smallest keys (the min discipline): the largest is dropped.
    Nearest,
    /// The first K to arrive (the increment discipline): the newcomer is dropped.
    First,
}

/// K keys a pixel in a locked vector, kept sorted; counts what it is offered and read.
struct LockedList<K> {
    pixels: Vec<Mutex<Vec<K>>>,
    k: usize,
    keep: Keep,
    inserts: AtomicU64,
    reads: AtomicU64,
}

impl<K> LockedList<K> {
    fn new(pixels: usize, k: usize, keep: Keep) -> Self {
        LockedList {
            pixels: (0..pixels).map(|_| Mutex::new(Vec::new())).collect(),
            k,
            keep,
            inserts: AtomicU64::new(0),
            reads: AtomicU64::new(0),
        }
    }
}

impl<K: Copy + Ord + Send + Sync> AtomicFragmentList for LockedList<K> {
    type Key = K;
    fn capacity(&self) -> usize {
        self.k
    }
    fn insert(&self, pixel: usize, key: K) -> Option<K> {
        self.inserts.fetch_add(1, Relaxed);
        let mut list = self.pixels[pixel].lock().unwrap();
        match self.keep {
            Keep::First if list.len() == self.k => return Some(key),
            _ => {}
        }
        let at = list.partition_point(|&x| x <= key);
        list.insert(at, key);
        (list.len() > self.k).then(|| list.pop().unwrap())
    }
    fn last(&self, pixel: usize) -> Option<K> {
        let list = self.pixels[pixel].lock().unwrap();
        if list.len() == self.k { list.last().copied() } else { None }
    }
    fn sorted(&self, pixel: usize, out: &mut Vec<K>) {
        self.reads.fetch_add(1, Relaxed);
        out.clear();
        out.extend_from_slice(&self.pixels[pixel].lock().unwrap());
    }
    fn take_sorted(&self, pixel: usize, out: &mut Vec<K>) {
        self.sorted(pixel, out);
        self.pixels[pixel].lock().unwrap().clear();
    }
}

const W: u32 = 64;
const H: u32 = 48;

/// One frame of `settings` on `scene` through `render`, on a context as the backend makes it.
fn frame(
    scene: &Scene,
    settings: &Settings,
    render: impl FnOnce(&mut Ctx<'_>) -> Result<Frame, OitError>,
) -> Frame {
    let camera = Camera::orbit_scene(scene, View::default(), W as f32 / H as f32).unwrap();
    let raster = Rasterizer::new(scene, &camera, settings);
    let pool = Pool::default();
    let plan = oit_core::plan::Plan::new("cpu", scene, settings).unwrap().on_path(RasterPath::Cpu);
    let mut ctx =
        Ctx::new(scene, &camera, settings, &raster, &pool, plan, scene.absorption_per_length(), None);
    render(&mut ctx).unwrap()
}

/// The two frames agree in every pixel and every count but the storage (the locked list's is
/// not allocated through the context).
fn assert_same(name: &str, atomic: &Frame, locked: &Frame) {
    let (a, b) = (&atomic.stats, &locked.stats);
    assert!(a.fragments > 0 && a.captured > 0, "{name}: nothing drawn");
    let counts = |s: &oit_core::Stats| {
        (s.geometry_passes, s.fragments, s.captured, s.lost, s.merged, s.tied, s.max_layers)
    };
    assert_eq!(counts(a), counts(b), "{name}: (passes, fragments, captured, lost, merged, tied, deepest)");
    assert_eq!(atomic.lost_pixels, locked.lost_pixels, "{name}: losses per pixel");
    let differ = atomic.image.pixels.iter().zip(&locked.image.pixels).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{name}: pixels differ");
}

fn settings(technique: Technique, overflow: Overflow) -> Settings {
    Settings { width: W, height: H, technique, overflow, ..Settings::default() }
}

/// mdts64, 32-bit mdts and mlp (the min discipline) over the atomic min lists and the locked
/// list, with K below the scene's depth so that lists fill and drop, with and without the tail.
/// Mutations caught: a capture or resolve reading its own words instead of the list given (the
/// locked list sees no insert or no read, and the frame loses every fragment), a min list that
/// dropped the newcomer instead of the largest, a `last` that answered before the list was full.
#[test]
fn min_lists_capture_alike_over_two_implementations() {
    let scene = oit_core::load_scene("cluster:60").unwrap();
    let pixels = (W * H) as usize;
    for overflow in [Overflow::Drop, Overflow::Tail] {
        let s = settings(Technique::Mdts64 { k: Some(3) }, overflow);
        let atomic = frame(&scene, &s, mdts::render64);
        let locked = LockedList::<u64>::new(pixels, 3, Keep::Nearest);
        let other = frame(&scene, &s, |ctx| mdts::render64_over(ctx, &locked));
        assert!(atomic.stats.lost + atomic.stats.merged > 0, "mdts64:3 never filled a list");
        assert_same(&format!("mdts64:3 {overflow:?}"), &atomic, &other);
        assert_eq!(locked.inserts.load(Relaxed), other.stats.fragments, "mdts64: one insert a fragment");
        assert_eq!(locked.reads.load(Relaxed), pixels as u64, "mdts64: one read a pixel");

        let s = settings(Technique::Mdts { k: Some(3) }, overflow);
        let atomic = frame(&scene, &s, mdts::render32);
        let high = LockedList::<u32>::new(pixels, 3, Keep::Nearest);
        let low = LockedList::<u32>::new(pixels, 3, Keep::Nearest);
        let other = frame(&scene, &s, |ctx| mdts::render32_over(ctx, &high, &low));
        assert!(atomic.stats.lost + atomic.stats.merged > 0, "mdts:3 never filled a list");
        assert_same(&format!("mdts:3 {overflow:?}"), &atomic, &other);
        for list in [&high, &low] {
            assert_eq!(
                list.inserts.load(Relaxed),
                other.stats.fragments,
                "mdts: one insert a fragment a list"
            );
            assert_eq!(list.reads.load(Relaxed), pixels as u64, "mdts: one read a pixel a list");
        }
    }
    let s = settings(Technique::Mlp { m: 2 }, Overflow::Drop);
    let atomic = frame(&scene, &s, |ctx| mlp::render(ctx, 2));
    let locked = LockedList::<u64>::new(pixels, 2, Keep::Nearest);
    let other = frame(&scene, &s, |ctx| mlp::render_over(ctx, &locked));
    assert!(atomic.stats.geometry_passes > 2, "mlp:2 peeled once");
    assert_same("mlp:2", &atomic, &other);
    assert!(locked.inserts.load(Relaxed) >= other.stats.fragments, "mlp: every fragment offered");
}

/// fabs's capture and resolve (the increment discipline) over its counted list and over the
/// locked list keeping the first K, sized from the scene so that no pixel overflows (which
/// fragments a full increment list keeps depends on arrival order; fabs's overflow repair is its
/// own list's, tested with the backend): the same frame as the backend's whole fabs.
#[test]
fn fabs_captures_alike_over_two_implementations() {
    let scene = oit_core::load_scene("cluster:60").unwrap();
    let pixels = (W * H) as usize;
    let s = settings(Technique::Fabs { k: None }, Overflow::Drop);
    let atomic = frame(&scene, &s, fabs::render);
    let locked = LockedList::<u128>::new(pixels, 0, Keep::First);
    let other = frame(&scene, &s, |ctx| {
        let deepest = ctx.max_depth_complexity()?;
        let locked = LockedList { k: ctx.plan.slots(deepest) as usize, ..locked };
        fabs::capture(ctx, &locked);
        assert_eq!(locked.inserts.load(Relaxed), ctx.fragments.unwrap(), "fabs: one insert a fragment");
        let frame = fabs::resolve(ctx, &locked, None);
        assert_eq!(locked.reads.load(Relaxed), pixels as u64, "fabs: one read a pixel");
        Ok(frame)
    });
    assert!(atomic.stats.max_layers > 2, "cluster:60 is too shallow to sort anything");
    assert_same("fabs", &atomic, &other);
}
