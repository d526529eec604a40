// fabs:K (Huang et al. 2011, section 4): counter + K slots per pixel by atomic increment; the
// resolve sorts each pixel's n ≤ K slots (insertion sort, as oit-cpu does for short lists) and
// composites them. param = K.
@group(0) @binding(2) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> slots: array<u64>;

fn capture(f: Fragment) {
    let k = fu.param;
    let i = atomicAdd(&counters[f.pixel], 1u);
    if (i < k) {
        slots[f.pixel * k + i] = (u64(depth_bits(f.depth)) << 32u) | u64(payload(f, fu.effect));
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let k = fu.param;
    let n = min(atomicLoad(&counters[px]), k);
    let base = px * k;
    for (var i = 1u; i < n; i++) {
        let v = slots[base + i];
        var j = i;
        while (j > 0u && slots[base + j - 1u] > v) {
            slots[base + j] = slots[base + j - 1u];
            j -= 1u;
        }
        slots[base + j] = v;
    }
    for (var i = 0u; i < n; i++) {
        let key = slots[base + i];
        push(px, bitcast<f32>(u32(key >> 32u)), u32(key & 0xfffffffflu));
    }
}
