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

/// Up to this many fragments a pixel's list is insertion-sorted; beyond, `sort_unstable`
/// (pattern-defeating quicksort). Measured with `cargo bench -p oit-cpu --bench sort` on this
/// project's 2-core machine, time to sort 256 lists of n random 64-bit keys:
///
/// | n | insertion | bitonic network | merge (`sort`) | pdq (`sort_unstable`) |
/// |---|---|---|---|---|
/// | 4 | 1.8 µs | 16 µs | 2.5 µs | 2.0 µs |
/// | 8 | 5.0 µs | 54 µs | 6.4 µs | 5.4 µs |
/// | 16 | 29 µs | 152 µs | 16 µs | 25 µs |
/// | 32 | 129 µs | 344 µs | 77 µs | 39 µs |
/// | 128 | 1.0 ms | 2.4 ms | 601 µs | 351 µs |
///
/// Insertion sort wins on the short lists most pixels have; pdqsort from 32 on; the sorting
/// network, which suits a GPU's lockstep threads, loses everywhere on a CPU. Merge sort's lead at
/// 16 is within the noise of these runs, so the rule stays two-way.
pub const INSERTION_SORT_MAX: usize = 8;

/// Sorts a pixel's keys in place, choosing the sort by length (see [`INSERTION_SORT_MAX`]).
pub fn sort_keys<K: Ord + Copy>(keys: &mut [K]) {
    if keys.len() <= INSERTION_SORT_MAX {
        for i in 1..keys.len() {
            let v = keys[i];
            let mut j = i;
            while j > 0 && keys[j - 1] > v {
                keys[j] = keys[j - 1];
                j -= 1;
            }
            keys[j] = v;
        }
    } else {
        keys.sort_unstable();
    }
}

/// The min discipline of [`AtomicFragmentList`]: K keys per pixel kept sorted by repeated atomic
/// min over `slots` (pixels × K words, row after row), all ones the empty slot. Over 64-bit words
/// (mdts64, mlp, fabs's overflow) and 32-bit words (each of mdts's two arrays); the list borrows
/// its words, so one array can be read as a min list by one pass and otherwise by another
/// (fabs's slots, filled by increment and, where a pixel overflows, refilled by min).
pub(crate) struct MinList<'s, A> {
    slots: &'s [A],
    k: usize,
}

impl<'s, A> MinList<'s, A> {
    /// A list over `slots` (pixels × `k`; a pixel's are all empty before its first insert).
    pub fn new(slots: &'s [A], k: usize) -> Self {
        MinList { slots, k }
    }
}

impl MinList<'_, AtomicU64> {
    /// The empty slot of a 64-bit list.
    pub const EMPTY: u64 = u64::MAX;
}

impl MinList<'_, AtomicU32> {
    /// The empty slot of a 32-bit list.
    pub const EMPTY: u32 = u32::MAX;
}

macro_rules! min_list {
    ($atomic:ty, $word:ty, $take:ident) => {
        impl AtomicFragmentList for MinList<'_, $atomic> {
            type Key = $word;

            fn capacity(&self) -> usize {
                self.k
            }

            /// Each slot keeps the smaller of its key and the carried one, and the larger is
            /// carried on to the next slot (Liu et al. 2009; Huang et al. 2011), so the array
            /// stays sorted whatever order fragments arrive in; what is carried off the end is
            /// returned.
            #[inline]
            fn insert(&self, pixel: usize, key: $word) -> Option<$word> {
                let mut carry = key;
                for slot in &self.slots[pixel * self.k..(pixel + 1) * self.k] {
                    let old = slot.fetch_min(carry, Relaxed);
                    if old == <$word>::MAX {
                        return None;
                    }
                    carry = carry.max(old);
                }
                Some(carry)
            }

            /// The K-th slot: the largest key kept, empty while the list is not full.
            #[inline]
            fn last(&self, pixel: usize) -> Option<$word> {
                let key = self.slots[(pixel + 1) * self.k - 1].load(Relaxed);
                (key != <$word>::MAX).then_some(key)
            }

            fn sorted(&self, pixel: usize, out: &mut Vec<$word>) {
                out.clear();
                out.extend(
                    self.slots[pixel * self.k..(pixel + 1) * self.k]
                        .iter()
                        .map(|s| s.load(Relaxed))
                        .take_while(|&key| key != <$word>::MAX),
                );
            }

            fn take_sorted(&self, pixel: usize, out: &mut Vec<$word>) {
                out.clear();
                for slot in &self.slots[pixel * self.k..(pixel + 1) * self.k] {
                    let key = $take(slot, <$word>::MAX);
                    if key == <$word>::MAX {
                        break;
                    }
                    out.push(key);
                }
            }
        }
    };
}
min_list!(AtomicU64, u64, take_u64);
min_list!(AtomicU32, u32, take_u32);

/// The increment discipline of [`AtomicFragmentList`] (fabs): a counter per pixel hands each
/// fragment a slot by atomic increment; a slot is a 64-bit word (depth bits above the primitive
/// id) and a 32-bit payload beside it, and the key is the two together, the word above the
/// payload (a `u128` holding 96 bits). Sorted after capture, by the whole key: one primitive has
/// one fragment a pixel, so the payload never decides.
pub(crate) struct CountedList<'s> {
    counters: &'s [AtomicU32],
    slots: &'s [AtomicU64],
    payloads: &'s [AtomicU32],
    k: usize,
}

impl<'s> CountedList<'s> {
    /// A list of `k` slots a pixel over zeroed `counters` (one a pixel) and `slots` and
    /// `payloads` (pixels × `k`, in any state: below a pixel's counter each slot is written
    /// before it is read).
    pub fn new(
        counters: &'s [AtomicU32],
        slots: &'s [AtomicU64],
        payloads: &'s [AtomicU32],
        k: usize,
    ) -> Self {
        CountedList { counters, slots, payloads, k }
    }

    /// The key of a slot word and its payload.
    #[inline]
    pub fn key(word: u64, payload: u32) -> u128 {
        u128::from(word) << 32 | u128::from(payload)
    }

    /// Whether more fragments came to `pixel` than it has slots (its counter is past K).
    #[inline]
    pub fn overflowed(&self, pixel: usize) -> bool {
        self.counters[pixel].load(Relaxed) as usize > self.k
    }

    /// The slot words read as a [`MinList`], for refilling an overflowing pixel with its K
    /// nearest words whatever their arrival order (fabs's overflow; the payloads follow by
    /// [`CountedList::set_payload`]). Only the pixels [`CountedList::empty_overflowing`] emptied
    /// are a min list's.
    pub fn nearest(&self) -> MinList<'s, AtomicU64> {
        MinList::new(self.slots, self.k)
    }

    /// Empties the slots of every pixel that overflowed, for [`CountedList::nearest`] to refill;
    /// true where any did.
    pub fn empty_overflowing(&self) -> bool {
        use rayon::prelude::*;
        self.slots
            .par_chunks(self.k)
            .enumerate()
            .map(|(px, s)| {
                if self.overflowed(px) {
                    s.iter().for_each(|w| w.store(MinList::<AtomicU64>::EMPTY, Relaxed));
                    true
                } else {
                    false
                }
            })
            .reduce(|| false, |a, b| a || b)
    }

    /// Writes `payload` beside the slot that holds `word` at `pixel`, if one does (words are
    /// unique at a pixel: one fragment per primitive).
    #[inline]
    pub fn set_payload(&self, pixel: usize, word: u64, payload: u32) {
        let k = self.k;
        if let Some(i) = self.slots[pixel * k..pixel * k + k].iter().position(|w| w.load(Relaxed) == word) {
            self.payloads[pixel * k + i].store(payload, Relaxed);
        }
    }
}

impl AtomicFragmentList for CountedList<'_> {
    type Key = u128;

    fn capacity(&self) -> usize {
        self.k
    }

    /// The counter's old value is the slot; past K the newcomer is dropped (the counter keeps
    /// counting, so [`CountedList::overflowed`] knows).
    #[inline]
    fn insert(&self, pixel: usize, key: u128) -> Option<u128> {
        let i = self.counters[pixel].fetch_add(1, Relaxed) as usize;
        if i < self.k {
            self.slots[pixel * self.k + i].store((key >> 32) as u64, Relaxed);
            self.payloads[pixel * self.k + i].store(key as u32, Relaxed);
            None
        } else {
            Some(key)
        }
    }

    /// The largest key kept, once the pixel's K slots are taken: a scan, since the slots are in
    /// arrival order.
    fn last(&self, pixel: usize) -> Option<u128> {
        let n = self.counters[pixel].load(Relaxed) as usize;
        let k = self.k;
        (n >= k).then(|| {
            (pixel * k..pixel * k + k)
                .map(|i| Self::key(self.slots[i].load(Relaxed), self.payloads[i].load(Relaxed)))
                .max()
                .unwrap_or(0)
        })
    }

    fn sorted(&self, pixel: usize, out: &mut Vec<u128>) {
        let k = self.k;
        let n = (self.counters[pixel].load(Relaxed) as usize).min(k);
        let (slots, payloads) =
            (&self.slots[pixel * k..pixel * k + n], &self.payloads[pixel * k..pixel * k + n]);
        out.clear();
        out.extend(slots.iter().zip(payloads).map(|(x, p)| Self::key(x.load(Relaxed), p.load(Relaxed))));
        sort_keys(out);
    }

    fn take_sorted(&self, pixel: usize, out: &mut Vec<u128>) {
        self.sorted(pixel, out);
        // the slots below the counter are written before they are read: the counter alone
        take_u32(&self.counters[pixel], 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pool::Pool;

    #[test]
    fn min_list_keeps_the_k_smallest_sorted_and_returns_the_rest() {
        let pool = Pool::default();
        let slots = pool.u64s(2 * 3, MinList::<AtomicU64>::EMPTY);
        let list = MinList::new(&slots, 3);
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
