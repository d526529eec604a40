//! Per-pixel storage kept between frames: a [`Pool`] of arrays by element type and length, lent
//! out as [`Pooled`] guards that give the array back when dropped. A frame of the same size as an
//! earlier one finds its arrays here and allocates nothing; [`Pool::allocations`] counts the
//! arrays that had to be made. A shelf keeps at most [`SHELF_ARRAYS`] arrays, and only while
//! every array the pool holds (shelved or lent out) and the array a lend must make fit the
//! frame's budget ([`Pool::set_cap`]; the host's, [`oit_core::plan::host_memory_budget`], until
//! a frame sets one), oldest out first: a tiled frame's windows, or frames of ever-new sizes, do
//! not pile up.

use std::ops::{Deref, DerefMut};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU8, AtomicU32, AtomicU64, Ordering::Relaxed};

use rayon::prelude::*;

use oit_core::rules::BDP_EMPTY_MIN;

use crate::resolve::PixelState;

/// The most arrays a shelf keeps: enough for the few lengths a prepared scene's frames take (a
/// turning camera changes the count-sized arrays' lengths), few enough that a run of frames of
/// ever-new shapes does not hoard them.
const SHELF_ARRAYS: usize = 8;

/// Elements a task of the reset sweep takes at least: an array of fewer is reset serially.
const RESET_GRAIN: usize = 1 << 14;

/// What every element of a shelved array is known to hold, where its last user said so
/// ([`Pooled::mark_clean`]): a lend that wants that finds it without a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Clean {
    /// Every word is this value (0, `u64::MAX`, ...).
    Word(u64),
    /// (min, max) pairs, each [`BDP_EMPTY_MIN`], 0: bucket depth peeling's empty buckets.
    EmptyMinMax,
    /// Every resolve state is its default.
    Default,
}

/// Free arrays of one element type, each with what it is known to hold.
pub(crate) struct Shelf<T> {
    free: Mutex<Vec<(Vec<T>, Option<Clean>)>>,
}

impl<T> Default for Shelf<T> {
    fn default() -> Self {
        Shelf { free: Mutex::new(Vec::new()) }
    }
}

/// The arrays one prepared scene owns between frames.
#[derive(Default)]
pub(crate) struct Pool {
    pub u8s: Shelf<AtomicU8>,
    pub u32s: Shelf<AtomicU32>,
    pub u64s: Shelf<AtomicU64>,
    pub states: Shelf<PixelState>,
    allocations: AtomicU64,
    /// Resolve-state arrays lent ([`Pool::states`]).
    states_lent: AtomicU64,
    /// Bytes of every array made and not yet let go: shelved or lent out.
    held: AtomicU64,
    /// The most bytes the pool holds where letting shelved arrays go can keep it there (0: the
    /// host's budget).
    cap: AtomicU64,
}

/// An array lent from a [`Pool`]; back on its shelf when dropped, marked clean where its user
/// said so.
pub(crate) struct Pooled<'p, T> {
    array: Vec<T>,
    shelf: &'p Shelf<T>,
    clean: Option<Clean>,
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
            free.push((array, self.clean));
        }
    }
}

impl<T> Pooled<'_, T> {
    /// Says every element holds `clean` again (whoever read the array reset each element it
    /// found written, while in cache), so the next lend of its length that wants `clean` takes it
    /// without a sweep. An element left written would reach the next frame:
    /// `kept_storage_changes_no_frame` (in lib.rs) holds every technique's prepared frames, two
    /// views in turn, to one-shot renders of backends of their own.
    pub fn mark_clean(&mut self, clean: Clean) {
        self.clean = Some(clean);
    }
}

impl Pool {
    /// Sets the most bytes the pool keeps, lent arrays included, where letting shelved ones go
    /// can keep it there: the frame's storage budget. A frame's arrays are held to its budget by
    /// its checks (`Ctx::checked`); this holds what earlier frames and tiles left on the shelves
    /// to it as well.
    pub fn set_cap(&self, bytes: u64) {
        self.cap.store(bytes.max(1), Relaxed);
    }

    /// Resolve-state arrays lent so far.
    #[cfg(test)]
    pub fn states_lent(&self) -> u64 {
        self.states_lent.load(Relaxed)
    }

    /// Arrays made so far (lends that found nothing of the right length on the shelf).
    pub fn allocations(&self) -> u64 {
        self.allocations.load(Relaxed)
    }

    /// An array of `len` elements: one shelved as `want` says it must be (no sweep), else one of
    /// that length each reset by `reset`, else one made by `make`. Returns it and whether it was
    /// the clean one `want` asked for.
    /// `reset` is generic, not `dyn`: called through a vtable per element, the sweep of a 512²
    /// frame's three 32-bit arrays took 5 % of the samples of `perf record` over
    /// `oit bench -t plain` (the armadillo at 512²); inlined, it is a fill.
    fn lend<'p, T: Send>(
        &'p self,
        shelf: &'p Shelf<T>,
        len: usize,
        want: Option<Clean>,
        make: impl Fn() -> T + Sync + Send,
        reset: Option<impl Fn(&mut T) + Sync + Send>,
    ) -> (Pooled<'p, T>, bool) {
        let found = shelf.free.lock().ok().and_then(|mut free| {
            let clean = want.and_then(|w| free.iter().position(|(a, c)| a.len() == len && *c == Some(w)));
            let Some(i) = clean.or_else(|| free.iter().position(|(a, _)| a.len() == len)) else {
                // a miss: the shelf keeps arrays of other lengths (other views' counts, other
                // tiles, sizes) for frames that may come back, but not past the frame's budget
                // with everything the pool holds (lent arrays too) and the array about to be
                // made; kept unbounded, the arrays of every tile of a tiled frame piled up (an
                // 8192² fabs frame in 5 tiles held 23.7 GB for 7.4 GB of storage a tile), and
                // kept to the host's budget, under --memory they piled up to several tiles'
                let bytes = |a: &Vec<T>| (a.len() * std::mem::size_of::<T>()) as u64;
                let cap = match self.cap.load(Relaxed) {
                    0 => oit_core::plan::host_memory_budget().1,
                    cap => cap,
                };
                let new = (len * std::mem::size_of::<T>()) as u64;
                let mut held = self.held.load(Relaxed);
                // oldest first out (arrays come back to the end of the list)
                let mut out = 0;
                while out < free.len() && (free.len() - out >= SHELF_ARRAYS || held.saturating_add(new) > cap)
                {
                    held = held.saturating_sub(bytes(&free[out].0));
                    out += 1;
                }
                let gone: u64 = free.drain(..out).map(|(a, _)| bytes(&a)).sum();
                let _ = self.held.fetch_update(Relaxed, Relaxed, |h| Some(h.saturating_sub(gone)));
                if gone > 0 {
                    trim();
                }
                return None;
            };
            // `remove`, not `swap_remove`: the list stays oldest first
            Some(free.remove(i))
        });
        let (array, hit) = match found {
            Some((array, clean)) if clean.is_some() && clean == want => (array, true),
            Some((mut array, _)) => {
                // a scratch array goes out as it came back; a small one is reset on this thread
                // (a parallel sweep wakes every thread: on many cores a small frame feels it)
                if let Some(reset) = reset {
                    array.par_iter_mut().with_min_len(RESET_GRAIN).for_each(reset);
                }
                (array, false)
            }
            None => {
                self.allocations.fetch_add(1, Relaxed);
                self.held.fetch_add((len * std::mem::size_of::<T>()) as u64, Relaxed);
                // made serially, as before the pool: a one-shot frame costs what it did
                ((0..len).map(|_| make()).collect(), false)
            }
        };
        (Pooled { array, shelf, clean: None }, hit)
    }

    /// `len` 32-bit atomics set to `init`.
    pub fn u32s(&self, len: usize, init: u32) -> Pooled<'_, AtomicU32> {
        let want = Some(Clean::Word(u64::from(init)));
        self.lend(
            &self.u32s,
            len,
            want,
            || AtomicU32::new(init),
            Some(move |a: &mut AtomicU32| *a.get_mut() = init),
        )
        .0
    }

    /// `len` 64-bit atomics set to `init`.
    pub fn u64s(&self, len: usize, init: u64) -> Pooled<'_, AtomicU64> {
        let want = Some(Clean::Word(init));
        self.lend(
            &self.u64s,
            len,
            want,
            || AtomicU64::new(init),
            Some(move |a: &mut AtomicU64| *a.get_mut() = init),
        )
        .0
    }

    /// `len` 64-bit atomics as (min, max) pairs, each [`BDP_EMPTY_MIN`], 0 (bucket depth peeling's
    /// empty buckets): one its last user handed back so ([`Clean::EmptyMinMax`]; no sweep), else
    /// one set by a single sweep.
    pub fn empty_min_max(&self, len: usize) -> Pooled<'_, AtomicU64> {
        let want = Some(Clean::EmptyMinMax);
        let (mut array, hit) =
            self.lend(&self.u64s, len, want, || AtomicU64::new(0), None::<fn(&mut AtomicU64)>);
        if !hit {
            array.par_chunks_mut(2).with_min_len(RESET_GRAIN / 2).for_each(|pair| {
                for (word, v) in pair.iter_mut().zip([BDP_EMPTY_MIN, 0]) {
                    *word.get_mut() = v;
                }
            });
        }
        array
    }

    /// `len` 32-bit atomics holding whatever their last user left (0 when newly made): for arrays
    /// every element of which is written before it is read.
    pub fn u32s_scratch(&self, len: usize) -> Pooled<'_, AtomicU32> {
        self.lend(&self.u32s, len, None, || AtomicU32::new(0), None::<fn(&mut AtomicU32)>).0
    }

    /// [`Pool::u32s_scratch`] in 8-bit atomics (the multisampled frames' coverage masks).
    pub fn u8s_scratch(&self, len: usize) -> Pooled<'_, AtomicU8> {
        self.lend(&self.u8s, len, None, || AtomicU8::new(0), None::<fn(&mut AtomicU8)>).0
    }

    /// [`Pool::u32s_scratch`] in 64-bit atomics.
    pub fn u64s_scratch(&self, len: usize) -> Pooled<'_, AtomicU64> {
        self.lend(&self.u64s, len, None, || AtomicU64::new(0), None::<fn(&mut AtomicU64)>).0
    }

    /// `len` fresh resolve states: an array the last resolve handed back reset
    /// ([`Clean::Default`]; no sweep), else one reset (or made).
    pub fn states(&self, len: usize) -> Pooled<'_, PixelState> {
        self.states_lent.fetch_add(1, Relaxed);
        let reset = Some(|s: &mut PixelState| *s = PixelState::default());
        self.lend(&self.states, len, Some(Clean::Default), PixelState::default, reset).0
    }
}

/// Hands the allocator's free pages back to the system. glibc's malloc serves blocks below its
/// dynamic mmap threshold (which rises to the largest block freed, up to 32 MiB) from its heaps
/// and keeps them there when freed: the arrays of a tiled frame's earlier tiles, of other lengths
/// than the next tile's, stayed resident beside it, and a 2048² `adp` frame under `--memory
/// 128M` peaked 69 MiB over its budget (2 MiB with this, called where the pool lets arrays go and
/// before each window of a tiled frame). Elsewhere a no-op.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub(crate) fn trim() {
    #[expect(unsafe_code, reason = "glibc's malloc_trim: takes no pointer and has no precondition")]
    unsafe extern "C" {
        safe fn malloc_trim(pad: usize) -> std::ffi::c_int;
    }
    malloc_trim(0);
}

/// See the glibc version: other allocators are left as they are.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub(crate) fn trim() {}
