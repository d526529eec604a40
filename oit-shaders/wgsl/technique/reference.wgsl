// module reference (raster): technique/reference.wgsl technique/sort_entries.wgsl technique/coverage.wgsl
// reference: every fragment in a per-pixel list (offsets from a counting pass and a prefix sum),
// sorted by (depth, primitive id), composited front to back (in f32 on the GPU; oit-cpu's
// reference composites in f64).
@group(0) @binding(2) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> keys: array<u64>;
@group(0) @binding(5) var<storage, read_write> payloads: array<u32>;
// multisampled: each entry's coverage mask, a byte (coverage.wgsl); a placeholder at one sample
@group(0) @binding(6) var<storage, read_write> masks: array<atomic<u32>>;

fn capture(f: Fragment) {
    let slot = offsets[f.pixel] + atomicAdd(&cursor[f.pixel], 1u);
    keys[slot] = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    payloads[slot] = payload(f, fu.effect);
    if (fu.msaa.x > 1u) {
        mask_new(slot, f.mask);
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = load_state(px);
    let lo = offsets[px];
    let hi = offsets[px + 1u];
    sort_entries(lo, hi - lo);
    if (fu.msaa.x > 1u) {
        // the per-sample reference: each sample composites the entries that cover it
        resolve_masked(px, lo, hi - lo);
        return;
    }
    for (var i = lo; i < hi; i++) {
        push_local(&s, bitcast<f32>(u32(keys[i] >> 32u)), payloads[i]);
    }
    store_state(px, s);
}
