// fabs:K (Huang et al. 2011, section 4): counter + K slots per pixel by atomic increment; the
// resolve sorts each pixel's n ≤ K slots (insertion sort, as oit-cpu does for short lists) and
// composites them. param = K. A slot is a key, depth bits << 32 | primitive id, and the payload
// beside it (in `payloads`, at the same index): sorted by key, equal depths come out in primitive
// order, as the reference's.
//
// Slot i of pixel px is slots[i · pixels + px] (slot-major), so the neighbouring pixels of one
// workgroup read and write neighbouring words in the resolve; lists of up to LOCAL_SLOTS are sorted
// in a private array, longer ones in place. Measured on the H100 (planes:64 at 1024², 64 layers a
// pixel): with pixel-major slots sorted in place the capture pass and its sizing pass took 2.8 ms
// and the resolve 4.4; with this layout 1.65 and 4.0; and with the pixel's resolve state kept in
// a local across the list (`push_local`, one load and one store instead of one per layer) the
// resolve takes 0.46 ms. Every resolve that walks a list does the same.
@group(0) @binding(2) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> slots: array<u64>;
@group(0) @binding(4) var<storage, read_write> payloads: array<u32>;

const LOCAL_SLOTS: u32 = 64u;

fn capture(f: Fragment) {
    let k = fu.param;
    let i = atomicAdd(&counters[f.pixel], 1u);
    if (i < k) {
        slots[i * fu.pixel_count + f.pixel] = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
        payloads[i * fu.pixel_count + f.pixel] = payload(f, fu.effect);
    } else {
        // the counter is past K: no slot for this fragment
        lose(f.pixel);
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = state[px];
    let n = min(atomicLoad(&counters[px]), fu.param);
    let stride = fu.pixel_count;
    if (n <= LOCAL_SLOTS) {
        var list: array<u64, LOCAL_SLOTS>;
        var list_payloads: array<u32, LOCAL_SLOTS>;
        for (var i = 0u; i < n; i++) {
            let v = slots[i * stride + px];
            let p = payloads[i * stride + px];
            var j = i;
            while (j > 0u && list[j - 1u] > v) {
                list[j] = list[j - 1u];
                list_payloads[j] = list_payloads[j - 1u];
                j -= 1u;
            }
            list[j] = v;
            list_payloads[j] = p;
        }
        for (var i = 0u; i < n; i++) {
            push_local(&s, bitcast<f32>(u32(list[i] >> 32u)), list_payloads[i]);
        }
        state[px] = s;
        return;
    }
    for (var i = 1u; i < n; i++) {
        let v = slots[i * stride + px];
        let p = payloads[i * stride + px];
        var j = i;
        while (j > 0u && slots[(j - 1u) * stride + px] > v) {
            slots[j * stride + px] = slots[(j - 1u) * stride + px];
            payloads[j * stride + px] = payloads[(j - 1u) * stride + px];
            j -= 1u;
        }
        slots[j * stride + px] = v;
        payloads[j * stride + px] = p;
    }
    for (var i = 0u; i < n; i++) {
        let key = slots[i * stride + px];
        push_local(&s, bitcast<f32>(u32(key >> 32u)), payloads[i * stride + px]);
    }
    state[px] = s;
}
