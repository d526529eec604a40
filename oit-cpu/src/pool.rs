//! Per-pixel storage kept between frames: a [`Pool`] of arrays by element type and length, lent
//! out as [`Pooled`] guards that give the array back when dropped. A frame of the same size as an
//! earlier one finds its arrays here and allocates nothing; [`Pool::allocations`] counts the
//! arrays that had to be made. A shelf keeps at most [`SHELF_ARRAYS`] arrays, and only while they
//! and the array a lend must make fit the host's budget ([`oit_core::plan::host_memory_budget`]),
//! oldest out first: a tiled frame's windows, or frames of ever-new sizes, do not pile up.

use std::ops::{Deref, DerefMut};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use rayon::prelude::*;

use oit_core::rules::BDP_EMPTY_MIN;

use crate::resolve::PixelState;

/// The most arrays a shelf keeps: enough for the few lengths a prepared scene's frames take (a
/// turning camera changes the count-sized arrays' lengths), few enough that a run of frames of
/// ever-new shapes does not hoard them.
const SHELF_ARRAYS: usize = 8;

/// Elements a task of the reset sweep takes at least: an array of fewer is reset serially.
const RESET_GRAIN: usize = 1 << 14;

/// Free arrays of one element type.
pub(crate) struct Shelf<T> {
    free: Mutex<Vec<Vec<T>>>,
}

impl<T> Default for Shelf<T> {
    fn default() -> Self {
        Shelf { free: Mutex::new(Vec::new()) }
    }
}

/// The arrays one prepared scene owns between frames.
#[derive(Default)]
pub(crate) struct Pool {
    pub u32s: Shelf<AtomicU32>,
    pub u64s: Shelf<AtomicU64>,
    pub states: Shelf<PixelState>,
    /// (min, max) pairs already back to [`BDP_EMPTY_MIN`], 0 (the resolve that read them reset
    /// each: [`Pooled::mark_clean_pairs`]), lent by [`Pool::empty_min_max`] without a sweep.
    clean_pairs: Shelf<AtomicU64>,
    /// Resolve states already back to their default (the resolve resets each as it finishes
    /// it, while it is in cache: [`Pooled::mark_clean`]), lent without another sweep.
    clean_states: Shelf<PixelState>,
    allocations: AtomicU64,
}

/// An array lent from a [`Pool`]; back on its shelf when dropped.
pub(crate) struct Pooled<'p, T> {
    array: Vec<T>,
    shelf: &'p Shelf<T>,
}

impl<T> Deref for Pooled<'_, T> {
    type Target = Vec<T>;
    fn deref(&self) -> &Vec<T> {
        &self.array
    }
}

impl<T> DerefMut for Pooled<'_, T> {
    fn deref_mut(&mut self) -> &mut Vec<T> {
        &mut self.array
    }
}

impl<T> Drop for Pooled<'_, T> {
    fn drop(&mut self) {
        let array = std::mem::take(&mut self.array);
        if let Ok(mut free) = self.shelf.free.lock() {
            free.push(array);
        }
    }
}

impl Pool {
    /// Arrays made so far (lends that found nothing of the right length on the shelf).
    pub fn allocations(&self) -> u64 {
        self.allocations.load(Relaxed)
    }

    /// An array of `len` elements, each reset by `reset` (or made by `make` when the shelf has
    /// none of that length).
    /// `reset` is generic, not `dyn`: called through a vtable per element, the sweep of a 512²
    /// frame's three 32-bit arrays took about 5 % of a `plain` frame; inlined, it is a fill.
    fn lend<'p, T: Send>(
        &'p self,
        shelf: &'p Shelf<T>,
        len: usize,
        make: impl Fn() -> T + Sync + Send,
        reset: Option<impl Fn(&mut T) + Sync + Send>,
    ) -> Pooled<'p, T> {
        let found = shelf.free.lock().ok().and_then(|mut free| {
            let Some(i) = free.iter().position(|a| a.len() == len) else {
                // a miss: the shelf keeps arrays of other lengths (other views' counts, other
                // tiles, sizes) for frames that may come back, but not past the host's budget
                // with the array about to be made, largest first out; kept unbounded, the
                // arrays of every tile of a tiled frame piled up (an 8192² fabs frame in 5 tiles
                // held 23.7 GB for 7.4 GB of storage a tile)
                let bytes = |a: &Vec<T>| (a.len() * std::mem::size_of::<T>()) as u64;
                let cap = oit_core::plan::host_memory_budget().1;
                let new = (len * std::mem::size_of::<T>()) as u64;
                let mut kept: u64 = free.iter().map(bytes).sum();
                // oldest first out (arrays come back to the end of the list)
                let mut out = 0;
                while out < free.len() && (free.len() - out >= SHELF_ARRAYS || kept + new > cap) {
                    kept -= bytes(&free[out]);
                    out += 1;
                }
                free.drain(..out);
                return None;
            };
            Some(free.swap_remove(i))
        });
        let array = match found {
            Some(mut array) => {
                // a scratch array goes out as it came back; a small one is reset on this thread
                // (a parallel sweep wakes every thread: on many cores a small frame feels it)
                if let Some(reset) = reset {
                    array.par_iter_mut().with_min_len(RESET_GRAIN).for_each(reset);
                }
                array
            }
            None => {
                self.allocations.fetch_add(1, Relaxed);
                // made serially, as before the pool: a one-shot frame costs what it did
                (0..len).map(|_| make()).collect()
            }
        };
        Pooled { array, shelf }
    }

    /// `len` 32-bit atomics set to `init`.
    pub fn u32s(&self, len: usize, init: u32) -> Pooled<'_, AtomicU32> {
        self.lend(
            &self.u32s,
            len,
            || AtomicU32::new(init),
            Some(move |a: &mut AtomicU32| *a.get_mut() = init),
        )
    }

    /// `len` 64-bit atomics set to `init`.
    pub fn u64s(&self, len: usize, init: u64) -> Pooled<'_, AtomicU64> {
        self.lend(
            &self.u64s,
            len,
            || AtomicU64::new(init),
            Some(move |a: &mut AtomicU64| *a.get_mut() = init),
        )
    }

    /// `len` 64-bit atomics as (min, max) pairs, each [`BDP_EMPTY_MIN`], 0 (bucket depth peeling's
    /// empty buckets): a clean array where a resolve left one of that length
    /// ([`Pooled::mark_clean_pairs`]; no sweep), else one set by a single sweep.
    pub fn empty_min_max(&self, len: usize) -> Pooled<'_, AtomicU64> {
        if let Ok(mut clean) = self.clean_pairs.free.lock() {
            if let Some(i) = clean.iter().position(|a| a.len() == len) {
                return Pooled { array: clean.swap_remove(i), shelf: &self.u64s };
            }
            // none of that length: the others go back to be swept, under the shelf's limits
            if let Ok(mut free) = self.u64s.free.lock() {
                free.append(&mut clean);
            }
        }
        let mut array = self.lend(&self.u64s, len, || AtomicU64::new(0), None::<fn(&mut AtomicU64)>);
        array.par_chunks_mut(2).with_min_len(RESET_GRAIN / 2).for_each(|pair| {
            for (word, v) in pair.iter_mut().zip([BDP_EMPTY_MIN, 0]) {
                *word.get_mut() = v;
            }
        });
        array
    }

    /// `len` 32-bit atomics holding whatever their last user left (0 when newly made): for arrays
    /// every element of which is written before it is read.
    pub fn u32s_scratch(&self, len: usize) -> Pooled<'_, AtomicU32> {
        self.lend(&self.u32s, len, || AtomicU32::new(0), None::<fn(&mut AtomicU32)>)
    }

    /// [`Pool::u32s_scratch`] in 64-bit atomics.
    pub fn u64s_scratch(&self, len: usize) -> Pooled<'_, AtomicU64> {
        self.lend(&self.u64s, len, || AtomicU64::new(0), None::<fn(&mut AtomicU64)>)
    }

    /// `len` fresh resolve states: a clean array where the last resolve left one of that length
    /// (no sweep), else one reset (or made).
    pub fn states(&self, len: usize) -> Pooled<'_, PixelState> {
        if let Ok(mut clean) = self.clean_states.free.lock() {
            if let Some(i) = clean.iter().position(|a| a.len() == len) {
                return Pooled { array: clean.swap_remove(i), shelf: &self.states };
            }
            // none of that length: the others go back to be reset, under the shelf's limits
            if let Ok(mut free) = self.states.free.lock() {
                free.append(&mut clean);
            }
        }
        self.lend(
            &self.states,
            len,
            PixelState::default,
            Some(|s: &mut PixelState| *s = PixelState::default()),
        )
    }
}

impl<'p> Pooled<'p, AtomicU64> {
    /// Says every pair holds [`BDP_EMPTY_MIN`], 0 again (whoever read the array reset each pair
    /// it found written), so the array goes back to `pool`'s clean shelf and the next
    /// [`Pool::empty_min_max`] of its length lends it without a sweep. A pair left written would
    /// be read by the next frame as a fragment of its own: `kept_storage_changes_no_frame` (in
    /// lib.rs) renders each view into the other view's arrays and compares it with a one-shot
    /// render of a backend of its own.
    pub fn mark_clean_pairs(&mut self, pool: &'p Pool) {
        self.shelf = &pool.clean_pairs;
    }
}

impl<'p> Pooled<'p, PixelState> {
    /// Says every state holds its default again (the resolve reset each as it finished it), so
    /// the array goes back to `pool`'s clean shelf and the next frame's [`Pool::states`] lends it
    /// without a sweep.
    pub fn mark_clean(&mut self, pool: &'p Pool) {
        self.shelf = &pool.clean_states;
    }
}
