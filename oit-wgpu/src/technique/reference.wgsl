// reference: every fragment in a per-pixel list (offsets from a counting pass and a prefix sum),
// sorted by (depth, primitive id), composited front to back (in f32 on the GPU; oit-cpu's
// reference composites in f64).
@group(0) @binding(2) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> keys: array<u64>;
@group(0) @binding(5) var<storage, read_write> payloads: array<u32>;

fn capture(f: Fragment) {
    let slot = offsets[f.pixel] + atomicAdd(&cursor[f.pixel], 1u);
    keys[slot] = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    payloads[slot] = payload(f, fu.effect);
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = state[px];
    let lo = offsets[px];
    let hi = offsets[px + 1u];
    // heapsort in place: O(n log n) loops. (An in-place insertion sort composited only part of a
    // 1,000-entry list on lavapipe, about one frame in five, the counts and offsets correct; see
    // dfb.wgsl. Its O(n²) loop iterations are the suspect.)
    let n = hi - lo;
    for (var i = n / 2u; i > 0u; i--) {
        sift_down(lo, i - 1u, n);
    }
    for (var end = n - 1u; n > 1u && end > 0u; end--) {
        swap_entries(lo, lo + end);
        sift_down(lo, 0u, end);
    }
    for (var i = lo; i < hi; i++) {
        push_local(&s, bitcast<f32>(u32(keys[i] >> 32u)), payloads[i]);
    }
    state[px] = s;
}

fn swap_entries(a: u32, b: u32) {
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
