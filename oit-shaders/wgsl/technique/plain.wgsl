// module plain (raster): technique/plain.wgsl
// plain (unsorted alpha blending in submission order) where no blender keeps that order: the
// compute rasterizer, and the embedded pass. As oit-cpu's `technique/plain.rs`: a counter and K
// slots a pixel (K = the deepest pixel's count from a counting pass), a slot one u64 word,
// (0xffffffff − primitive id) above the payload, so ascending words are descending primitive ids;
// the resolve sorts each pixel's words (insertion sort up to PLAIN_LOCAL, heapsort in place beyond)
// and pushes them front to back: the highest primitive on top, as a blender compositing the draw
// in primitive order leaves it. param = K. Slot i of pixel px is slots[i · pixels + px].
@group(0) @binding(2) var<storage, read_write> plain_counters: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> plain_slots: array<u64>;

const PLAIN_LOCAL: u32 = 64u;

fn capture(f: Fragment) {
    let i = atomicAdd(&plain_counters[f.pixel], 1u);
    if (i < fu.param) {
        plain_slots[i * fu.pixel_count + f.pixel] = (u64(0xffffffffu - f.prim) << 32u) | u64(payload(f, fu.effect));
    } else {
        // sized from the counting pass, a repeatable rasterizer never gets here
        lose(f.pixel);
    }
}

@compute @workgroup_size(64)
fn plain_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let n = min(atomicLoad(&plain_counters[px]), fu.param);
    if (n == 0u) {
        // nothing captured: the state stays as the frame cleared it
        return;
    }
    var s = load_state(px);
    let stride = fu.pixel_count;
    if (n <= PLAIN_LOCAL) {
        plain_push_short(&s, px, n);
        store_state(px, s);
        return;
    }
    for (var i = n / 2u; i > 0u; i--) {
        plain_sift_down(px, stride, i - 1u, n);
    }
    for (var end = n - 1u; end > 0u; end--) {
        plain_swap(px, stride, 0u, end);
        plain_sift_down(px, stride, 0u, end);
    }
    for (var i = 0u; i < n; i++) {
        push_local(&s, 0.0, u32(plain_slots[i * stride + px] & 0xfffffffflu));
    }
    store_state(px, s);
}

// Pushes pixel `px`'s n ≤ PLAIN_LOCAL words, sorted by insertion in a private array (declared
// here, not in the resolve, for the reason short_list.wgsl gives: its zero initializer is stored
// only for the pixels that have a list; no element is read before it is written, so oit-vulkan
// drops the initializer, as short_list.wgsl's).
fn plain_push_short(s: ptr<function, PixelState>, px: u32, n: u32) {
    let stride = fu.pixel_count;
    var list: array<u64, PLAIN_LOCAL>;
    for (var i = 0u; i < n; i++) {
        let v = plain_slots[i * stride + px];
        var j = i;
        while (j > 0u && list[j - 1u] > v) {
            list[j] = list[j - 1u];
            j -= 1u;
        }
        list[j] = v;
    }
    for (var i = 0u; i < n; i++) {
        push_local(s, 0.0, u32(list[i] & 0xfffffffflu));
    }
}

fn plain_swap(px: u32, stride: u32, a: u32, b: u32) {
    let w = plain_slots[a * stride + px];
    plain_slots[a * stride + px] = plain_slots[b * stride + px];
    plain_slots[b * stride + px] = w;
}

// Moves slot `root` of pixel `px`'s heap of `n` slots down to its place (a max-heap).
fn plain_sift_down(px: u32, stride: u32, root_in: u32, n: u32) {
    var root = root_in;
    loop {
        var child = 2u * root + 1u;
        if (child >= n) {
            break;
        }
        if (child + 1u < n && plain_slots[(child + 1u) * stride + px] > plain_slots[child * stride + px]) {
            child += 1u;
        }
        if (plain_slots[root * stride + px] >= plain_slots[child * stride + px]) {
            break;
        }
        plain_swap(px, stride, root, child);
        root = child;
    }
}
