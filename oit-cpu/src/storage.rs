//! oit-core's capture traits on std atomics: the CPU's bucket arrays, depth histograms and
//! per-pixel fragment lists. The techniques are written against the traits; the atomics here are
//! the CPU's stand-ins for the GPU's blend units (MAX), logic ops (OR) and atomics.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use oit_core::rules::{HISTOGRAM_WORDS, histogram_rank};
use oit_core::{AtomicFragmentList, BucketArray, DepthHistogram};

use crate::pool::Pooled;

/// `word.swap(empty, Relaxed)` for the sweep between passes, where one thread alone touches a
/// pixel's words and no pass runs: a plain load, and a store only where the word is not empty
/// already. An atomic swap is a locked read-modify-write, and a sweep does one or more per pixel,
/// most of them on pixels with nothing to take.
#[inline]
pub(crate) fn take_u32(word: &AtomicU32, empty: u32) -> u32 {
    let v = word.load(Relaxed);
    if v != empty {
        word.store(empty, Relaxed);
    }
    v
}

/// [`take_u32`] for 64-bit words.
#[inline]
pub(crate) fn take_u64(word: &AtomicU64, empty: u64) -> u64 {
    let v = word.load(Relaxed);
    if v != empty {
        word.store(empty, Relaxed);
    }
    v
}

/// K buckets of `W` per pixel, row after row.
pub(crate) struct Buckets<'p, A> {
    words: Pooled<'p, A>,
    k: usize,
}

impl<'p, A> Buckets<'p, A> {
    /// Buckets over `words` (pixels × `k`, all empty).
    pub fn new(words: Pooled<'p, A>, k: usize) -> Self {
        Buckets { words, k }
    }

    /// Says every bucket has been taken (all empty again): the words go back to the pool clean.
    pub fn mark_empty(&mut self) {
        self.words.mark_clean(crate::pool::Clean::Word(0));
    }

    /// The buckets of `pixel` (for a prefetch ahead of a pass's fragments).
    pub fn of_pixel(&self, pixel: usize) -> &[A] {
        &self.words[pixel * self.k..(pixel + 1) * self.k]
    }

    /// The buckets, pixel after pixel, to take between passes by plain reads and writes
    /// (`get_mut`: no pass runs, so the caller has them to itself), which the compiler may do
    /// several at a time, where [`BucketArray::take`] is a load a bucket.
    pub fn words_mut(&mut self) -> &mut [A] {
        &mut self.words
    }
}

macro_rules! buckets {
    ($atomic:ty, $word:ty, $take:ident) => {
        impl BucketArray for Buckets<'_, $atomic> {
            type Word = $word;
            fn buckets(&self) -> usize {
                self.k
            }
            #[inline]
            fn update_max(&self, pixel: usize, k: usize, value: $word) -> $word {
                self.words[pixel * self.k + k].fetch_max(value, Relaxed)
            }
            #[inline]
            fn take(&self, pixel: usize, k: usize) -> $word {
                // between passes (the trait's contract): no writer races the sweep
                $take(&self.words[pixel * self.k + k], 0)
            }
            fn read(&self, pixel: usize, out: &mut [$word]) {
                for (o, w) in out.iter_mut().zip(&self.words[pixel * self.k..(pixel + 1) * self.k]) {
                    *o = w.load(Relaxed);
                }
            }
        }
    };
}
buckets!(AtomicU32, u32, take_u32);
buckets!(AtomicU64, u64, take_u64);

/// 1024 bits per pixel.
pub(crate) struct Histogram<'p> {
    words: Pooled<'p, AtomicU32>,
}

impl<'p> Histogram<'p> {
    /// A histogram over `words` (pixels × [`HISTOGRAM_WORDS`], all zero).
    pub fn new(words: Pooled<'p, AtomicU32>) -> Self {
        Histogram { words }
    }

    /// [`DepthHistogram::read`], leaving the pixel's histogram empty.
    pub fn take(&self, pixel: usize) -> [u32; HISTOGRAM_WORDS] {
        std::array::from_fn(|i| take_u32(&self.words[pixel * HISTOGRAM_WORDS + i], 0))
    }

    /// Says every pixel has been taken (all empty again): the words go back to the pool clean.
    pub fn mark_empty(&mut self) {
        self.words.mark_clean(crate::pool::Clean::Word(0));
    }

    /// [`histogram_rank`] of the pixel's histogram, reading only the words at and below the
    /// bin's.
    #[inline]
    pub fn rank(&self, pixel: usize, bin: u32) -> u32 {
        let mut words = [0; HISTOGRAM_WORDS];
        let upto = (bin / 32) as usize;
        for (w, a) in words[..=upto].iter_mut().zip(&self.words[pixel * HISTOGRAM_WORDS..]) {
            *w = a.load(Relaxed);
        }
        histogram_rank(&words, bin)
    }
}

impl DepthHistogram for Histogram<'_> {
    #[inline]
    fn set(&self, pixel: usize, bin: u32) -> bool {
        let bit = 1 << (bin % 32);
        self.words[pixel * HISTOGRAM_WORDS + (bin / 32) as usize].fetch_or(bit, Relaxed) & bit == 0
    }
    fn read(&self, pixel: usize) -> [u32; HISTOGRAM_WORDS] {
        std::array::from_fn(|i| self.words[pixel * HISTOGRAM_WORDS + i].load(Relaxed))
    }
}

/// K keys per pixel kept sorted by repeated atomic min; `u64::MAX` is an empty slot.
pub(crate) struct MinList<'p> {
    slots: Pooled<'p, AtomicU64>,
    k: usize,
}

impl<'p> MinList<'p> {
    /// The empty slot.
    pub const EMPTY: u64 = u64::MAX;

    /// A list over `slots` (pixels × `k`, all [`MinList::EMPTY`]).
    pub fn new(slots: Pooled<'p, AtomicU64>, k: usize) -> Self {
        MinList { slots, k }
    }
}

impl MinList<'_> {
    /// The pixel's K-th slot: its largest key kept, [`MinList::EMPTY`] while the list is not full
    /// (`--overflow tail`: a fragment whose key is larger was carried off).
    pub fn last(&self, pixel: usize) -> u64 {
        self.slots[(pixel + 1) * self.k - 1].load(Relaxed)
    }

    /// [`AtomicFragmentList::sorted`], leaving the pixel's slots empty for the next pass (mlp).
    pub fn take_sorted(&self, pixel: usize, out: &mut Vec<u64>) {
        out.clear();
        for slot in &self.slots[pixel * self.k..(pixel + 1) * self.k] {
            let key = take_u64(slot, Self::EMPTY);
            if key == Self::EMPTY {
                break;
            }
            out.push(key);
        }
    }
}

impl AtomicFragmentList for MinList<'_> {
    fn capacity(&self) -> usize {
        self.k
    }

    /// Each slot keeps the smaller of its key and the carried one, and the larger is carried on
    /// to the next slot (Liu et al. 2009; Huang et al. 2011), so the array stays sorted whatever
    /// order fragments arrive in; what is carried off the end is returned.
    #[inline]
    fn insert(&self, pixel: usize, key: u64) -> Option<u64> {
        let mut carry = key;
        for slot in &self.slots[pixel * self.k..(pixel + 1) * self.k] {
            let old = slot.fetch_min(carry, Relaxed);
            if old == Self::EMPTY {
                return None;
            }
            carry = carry.max(old);
        }
        Some(carry)
    }

    fn sorted(&self, pixel: usize, out: &mut Vec<u64>) {
        out.clear();
        out.extend(
            self.slots[pixel * self.k..(pixel + 1) * self.k]
                .iter()
                .map(|s| s.load(Relaxed))
                .take_while(|&key| key != Self::EMPTY),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pool::Pool;

    #[test]
    fn min_list_keeps_the_k_smallest_sorted_and_returns_the_rest() {
        let pool = Pool::default();
        let list = MinList::new(pool.u64s(2 * 3, MinList::EMPTY), 3);
        let mut dropped = Vec::new();
        for key in [50, 10, 40, 30, 20] {
            dropped.extend(list.insert(1, key));
        }
        let mut out = Vec::new();
        list.sorted(1, &mut out);
        assert_eq!(out, [10, 20, 30]);
        dropped.sort_unstable();
        assert_eq!(dropped, [40, 50]);
        list.sorted(0, &mut out);
        assert!(out.is_empty(), "pixel 0 untouched");
    }

    #[test]
    fn buckets_report_collisions_and_empty_on_take() {
        let pool = Pool::default();
        let b = Buckets::new(pool.u32s(2 * 4, 0), 4);
        assert_eq!(b.update_max(1, 2, 7), 0, "first fragment: no collision");
        assert_eq!(b.update_max(1, 2, 5), 7, "second: the previous word comes back");
        let mut out = [0u32; 4];
        b.read(1, &mut out);
        assert_eq!(out, [0, 0, 7, 0]);
        assert_eq!(b.take(1, 2), 7);
        assert_eq!(b.take(1, 2), 0);
    }

    #[test]
    fn histogram_sets_bits() {
        let pool = Pool::default();
        let h = Histogram::new(pool.u32s(2 * HISTOGRAM_WORDS, 0));
        for bin in [0, 31, 32, 1023] {
            assert!(h.set(1, bin), "bin {bin} was clear");
        }
        assert!(!h.set(1, 31), "bin 31 was set already");
        // the rank reads only the words up to the bin's: the set bins below it, in any word
        for (bin, below) in [(0, 0), (31, 1), (32, 2), (33, 3), (1023, 3)] {
            assert_eq!(h.rank(1, bin), below, "set bins below {bin}");
        }
        let words = h.read(1);
        assert_eq!((words[0], words[1], words[31]), (1 | 1 << 31, 1, 1 << 31));
        assert_eq!(h.read(0), [0; HISTOGRAM_WORDS]);
    }
}
