//! Per-pixel storage kept between frames: a [`Pool`] of arrays by element type and length, lent
//! out as [`Pooled`] guards that give the array back when dropped. A frame of the same size as an
//! earlier one finds its arrays here and allocates nothing; [`Pool::allocations`] counts the
//! arrays that had to be made.

use std::ops::{Deref, DerefMut};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use rayon::prelude::*;

use crate::resolve::PixelState;

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
    fn lend<'p, T: Send>(
        &'p self,
        shelf: &'p Shelf<T>,
        len: usize,
        make: impl Fn() -> T + Sync + Send,
        reset: impl Fn(&mut T) + Sync + Send,
    ) -> Pooled<'p, T> {
        let found = shelf.free.lock().ok().and_then(|mut free| {
            let i = free.iter().position(|a| a.len() == len)?;
            Some(free.swap_remove(i))
        });
        let array = match found {
            Some(mut array) => {
                array.par_iter_mut().for_each(reset);
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
        self.lend(&self.u32s, len, || AtomicU32::new(init), |a| *a.get_mut() = init)
    }

    /// `len` 64-bit atomics set to `init`.
    pub fn u64s(&self, len: usize, init: u64) -> Pooled<'_, AtomicU64> {
        self.lend(&self.u64s, len, || AtomicU64::new(init), |a| *a.get_mut() = init)
    }

    /// `len` 32-bit atomics holding whatever their last user left (0 when newly made): for arrays
    /// every element of which is written before it is read.
    pub fn u32s_scratch(&self, len: usize) -> Pooled<'_, AtomicU32> {
        self.lend(&self.u32s, len, || AtomicU32::new(0), |_| {})
    }

    /// [`Pool::u32s_scratch`] in 64-bit atomics.
    pub fn u64s_scratch(&self, len: usize) -> Pooled<'_, AtomicU64> {
        self.lend(&self.u64s, len, || AtomicU64::new(0), |_| {})
    }

    /// `len` fresh resolve states.
    pub fn states(&self, len: usize) -> Pooled<'_, PixelState> {
        self.lend(&self.states, len, PixelState::default, |s| *s = PixelState::default())
    }
}
