// module dfb (raster): technique/dfb.wgsl technique/sort_entries.wgsl technique/coverage.wgsl technique/short_list.wgsl
// dfb, the dynamic fragment buffer (Maule et al. 2012), as oit-cpu's `technique/dfb.rs`: after
// the counting pass (dfb_count.wgsl) and the prefix sum (scan.wgsl), `offsets[px]` is pixel px's
// first entry and `offsets[pixels]` the total; the fill (this capture) takes each fragment's
// entry by atomic decrement of its pixel's count, from the start of the range (so entries are in
// arrival order, as fabs's slots are: the private insertion sort below then does as little work as
// fabs's on the same scene; filled from the end, a scene that arrives front to back is its worst
// case: 5.5x fabs's resolve time on planes:64 on the H200), and a count already spent (below
// zero, read as signed) loses the fragment where it happens. The resolve sorts each
// range by key, (depth bits << 32 | primitive id), payload beside it, and composites: equal depths
// in primitive order, as the reference's.
//
// A range of up to SHORT_LIST is sorted in private arrays (short_list.wgsl, as fabs's lists), a longer
// one in place by heapsort, as reference.wgsl and fabs.wgsl do. (An in-place insertion sort composited only
// part of the list on lavapipe from about 1,000 entries a pixel: 250 of 1,000 on planes:1000 at
// 8², 1 of 2,000 on planes:2000, the counts and offsets read back correct; heapsort's
// O(n log n) loops composite all of them.)
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u64>;
@group(0) @binding(5) var<storage, read_write> payloads: array<u32>;
// multisampled: each entry's coverage mask, a byte (coverage.wgsl); a placeholder at one sample
@group(0) @binding(6) var<storage, read_write> masks: array<atomic<u32>>;

fn capture(f: Fragment) {
    let left = atomicSub(&counts[f.pixel], 1u);
    if (bitcast<i32>(left) <= 0) {
        // no entry left for this fragment
        lose(f.pixel);
        return;
    }
    let entry = offsets[f.pixel + 1u] - left;
    keys[entry] = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    payloads[entry] = payload(f, fu.effect);
    if (fu.msaa.x > 1u) {
        mask_new(entry, kept_mask(f));
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    // entries the fill did not reach (a count it did not spend, at the end) are left out
    let lo = offsets[px];
    let hi = offsets[px + 1u] - u32(max(bitcast<i32>(atomicLoad(&counts[px])), 0));
    if (fu.msaa.x > 1u) {
        // per sample: sorted in place with the masks, then each sample composited
        sort_entries(lo, hi - lo);
        resolve_masked(px, lo, hi - lo);
        return;
    }
    if (hi == lo) {
        // nothing captured: the state stays as the frame cleared it
        return;
    }
    var s = load_state(px);
    if (push_short_list(&s, lo, hi - lo, false)) {
        store_state(px, s);
        return;
    }
    // longer: in place (sort_entries.wgsl)
    sort_entries(lo, hi - lo);
    for (var i = lo; i < hi; i++) {
        push_local(&s, bitcast<f32>(u32(keys[i] >> 32u)), payloads[i]);
    }
    store_state(px, s);
}
