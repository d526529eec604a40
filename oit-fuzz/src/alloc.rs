//! The worker's global allocator: the system allocator, counting live bytes, keeping the peak,
//! and refusing (a null pointer) any request that would take the live total over the limit.
//!
//! A refused request ends the worker (`memory allocation of N bytes failed`, then abort), and
//! the supervisor, which saw which input was running, reports it as unbounded allocation: no
//! input may make the code under test allocate past the limit, one huge request or many small
//! ones. Code that asks fallibly (`try_reserve`) gets its error instead, as it would from a full
//! machine.
#![expect(unsafe_code, reason = "a GlobalAlloc is an unsafe trait; this is the harness's one unsafe")]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Bytes live now.
static LIVE: AtomicUsize = AtomicUsize::new(0);
/// The most bytes live since [`reset_peak`].
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// Requests that would take [`LIVE`] past this are refused.
static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);

/// The counting allocator (see the module docs).
pub struct Counting;

/// Sets the limit on live bytes.
pub fn set_limit(bytes: usize) {
    LIMIT.store(bytes, Ordering::Relaxed);
}

/// Starts a new peak from the bytes live now.
pub fn reset_peak() {
    PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// The most bytes live since [`reset_peak`].
pub fn peak() -> usize {
    PEAK.load(Ordering::Relaxed)
}

/// Bytes live now.
pub fn live() -> usize {
    LIVE.load(Ordering::Relaxed)
}

/// Counts `size` more bytes, or refuses them (counting nothing) when over the limit.
fn reserve(size: usize) -> bool {
    let before = LIVE.fetch_add(size, Ordering::Relaxed);
    let now = before.saturating_add(size);
    if now > LIMIT.load(Ordering::Relaxed) || before.checked_add(size).is_none() {
        LIVE.fetch_sub(size, Ordering::Relaxed);
        return false;
    }
    PEAK.fetch_max(now, Ordering::Relaxed);
    true
}

fn release(size: usize) {
    LIVE.fetch_sub(size, Ordering::Relaxed);
}

// SAFETY: every method forwards to `System` with the caller's layout and pointer unchanged, so it
// keeps `System`'s guarantees; the counting around it allocates nothing and cannot unwind.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !reserve(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract for `alloc` (a non-zero-size layout) is passed on as is.
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            release(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !reserve(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            release(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by this allocator (so by `System`) with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        release(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && !reserve(new_size - old) {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract for `realloc` (a live `ptr` of `layout`, a valid
        // `new_size`) is passed on as is.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                release(new_size - old);
            }
        } else if new_size < old {
            release(old - new_size);
        }
        p
    }
}
