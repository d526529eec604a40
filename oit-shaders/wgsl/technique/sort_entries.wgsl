// The in-place sort of one pixel's entries [lo, lo + n) of `keys` (u64, depth bits << 32 |
// primitive id) with `payloads` (and, multisampled, the masks of coverage.wgsl) beside them, by key: heapsort, O(n log n) loops and no private
// array. Appended to the modules whose resolve sorts entries in place (reference.wgsl, dfb.wgsl),
// which declare `keys` and `payloads`. (An in-place insertion sort composited only part of
// 1,000-entry lists on lavapipe, the counts and offsets read back correct; its O(n²) loop
// iterations are the suspect.)
fn sort_entries(lo: u32, n: u32) {
    for (var i = n / 2u; i > 0u; i--) {
        sift_down(lo, i - 1u, n);
    }
    for (var end = n - 1u; n > 1u && end > 0u; end--) {
        swap_entries(lo, lo + end);
        sift_down(lo, 0u, end);
    }
}

fn swap_entries(a: u32, b: u32) {
    mask_swap(a, b);
    let k = keys[a];
    let p = payloads[a];
    keys[a] = keys[b];
    payloads[a] = payloads[b];
    keys[b] = k;
    payloads[b] = p;
}

// Moves entry `root` of the heap over [lo, lo + n) down to its place (a max-heap by key).
fn sift_down(lo: u32, root_in: u32, n: u32) {
    var root = root_in;
    loop {
        var child = 2u * root + 1u;
        if (child >= n) {
            break;
        }
        if (child + 1u < n && keys[lo + child + 1u] > keys[lo + child]) {
            child += 1u;
        }
        if (keys[lo + root] >= keys[lo + child]) {
            break;
        }
        swap_entries(lo + root, lo + child);
        root = child;
    }
}

// Entry e of a pixel's range, for coverage.wgsl: its key, its payload, the entry after it.
fn entry_key(e: u32) -> u64 {
    return keys[e];
}

fn entry_payload(e: u32) -> u32 {
    return payloads[e];
}

fn entry_next(e: u32) -> u32 {
    return e + 1u;
}
