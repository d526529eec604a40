// module fabs (raster): technique/fabs_counters.wgsl technique/fabs.wgsl technique/tail.wgsl technique/coverage.wgsl technique/short_list.wgsl
// `--atomic-storage image`: the same technique over the storage-image accessor
// module fabs_image (raster): core/atomic_result.wgsl technique/fabs_counters_image.wgsl technique/fabs.wgsl technique/tail.wgsl technique/coverage.wgsl technique/short_list.wgsl
// fabs:K (Huang et al. 2011, section 4): counter + K slots per pixel by atomic increment; the
// resolve sorts each pixel's n ≤ K slots (short_list.wgsl up to SHORT_LIST, heapsort beyond) and
// composites them. param = K. A slot is a key, depth bits << 32 | primitive id, and the payload
// beside it (in `payloads`, at the same index): sorted by key, equal depths come out in primitive
// order, as the reference's.
//
// Slot i of pixel px is slots[i · pixels + px] (slot-major), so the neighbouring pixels of one
// workgroup read and write neighbouring words in the resolve; lists of up to SHORT_LIST are
// sorted in private arrays, longer ones in place (heapsort). Measured on the H100 (planes:64 at
// 1024², 64 layers a pixel): with pixel-major slots sorted in place the capture pass and its sizing pass took 2.8 ms
// and the resolve 4.4; with this layout 1.65 and 4.0; and with the pixel's resolve state kept in
// a local across the list (`push_local`, one load and one store instead of one per layer) the
// resolve takes 0.46 ms. Every resolve that walks a list does the same.
//
// Overflow (n > K at a pixel) keeps the K smallest keys, whatever the arrival order, as oit-cpu
// does: the first pass (FABS_CAPTURE) keeps the first K to arrive; `overflow_main` empties the
// slots of the pixels that overflowed and raises `overflowed[0]`; only then (the flag read back)
// FABS_KEYS inserts every key of those pixels by repeated atomicMin, carrying the larger value on
// (as mdts64), and FABS_PAYLOADS writes each surviving key's payload beside it. Pixels that did
// not overflow are untouched by the extra passes; a frame with none runs none of them.
//
// `--overflow tail` (tail.wgsl, appended): after those passes an overflowing pixel's slots hold
// its K smallest keys sorted, and FABS_TAIL adds every fragment whose key is larger than the last
// into the pixel's tail; the resolve (pass_index FABS_WITH_TAIL) puts the tail behind the K. Above
// one sample the tail is one a pixel, each fragment's alpha weighted by its coverage fraction, and
// each sample composites the slots that cover it over it.
//
// The counters are reached only through fabs_counters.wgsl's fabs_count_add and fabs_count
// (storage buffer); oit-vulkan's `--atomic-storage image` defines them over a storage image.
@group(0) @binding(3) var<storage, read_write> slots: array<atomic<u64>>;
@group(0) @binding(4) var<storage, read_write> payloads: array<u32>;
@group(0) @binding(5) var<storage, read_write> overflowed: array<atomic<u32>>;
// multisampled: each slot's coverage mask, a byte (coverage.wgsl), slot-major as the slots; a
// placeholder at one sample. A multisampled pixel's slots are sorted in place, masks following
// keys, then resolved per sample.
@group(0) @binding(8) var<storage, read_write> masks: array<atomic<u32>>;

const FABS_EMPTY: u64 = 0xfffffffffffffffflu;
const FABS_CAPTURE: u32 = 0u;
const FABS_KEYS: u32 = 1u;
const FABS_PAYLOADS: u32 = 2u;
const FABS_TAIL: u32 = 3u;
const FABS_WITH_TAIL: u32 = 1u;

fn capture(f: Fragment) {
    let k = fu.param;
    let stride = fu.pixel_count;
    let key = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    if (fu.pass_index == FABS_CAPTURE) {
        let i = fabs_count_add(f.pixel, 1u);
        if (i < k) {
            atomicStore(&slots[i * stride + f.pixel], key);
            payloads[i * stride + f.pixel] = payload(f, fu.effect);
            if (fu.msaa.x > 1u) {
                mask_new(i * stride + f.pixel, kept_mask(f));
            }
        } else {
            // the counter is past K: one fragment of this pixel finds no slot (which one is
            // settled by the overflow passes below: the K nearest stay); counted once here
            lose(f.pixel);
        }
        return;
    }
    if (fabs_count(f.pixel) <= k) {
        return;
    }
    if (fu.pass_index == FABS_TAIL) {
        if (key > atomicLoad(&slots[(k - 1u) * stride + f.pixel])) {
            var c = f.color;
            if (fu.msaa.x > 1u) {
                // one tail a pixel: the fragment's alpha weighted by its coverage fraction
                // (oit-core's msaa::fraction_alpha, as coverage_weighted)
                c.a = f.color.a * (f32(countOneBits(kept_mask(f))) / f32(fu.msaa.x));
            }
            tail_add(f.pixel, pack_rgba8(c));
        }
        return;
    }
    if (fu.pass_index == FABS_KEYS) {
        var carry = key;
        for (var i = 0u; i < k; i++) {
            let old = atomicMin(&slots[i * stride + f.pixel], carry);
            if (old == FABS_EMPTY) {
                return;
            }
            carry = max(carry, old);
        }
        return;
    }
    // FABS_PAYLOADS: keys are unique at a pixel (one fragment per primitive)
    for (var i = 0u; i < k; i++) {
        if (atomicLoad(&slots[i * stride + f.pixel]) == key) {
            payloads[i * stride + f.pixel] = payload(f, fu.effect);
            if (fu.msaa.x > 1u) {
                mask_put(i * stride + f.pixel, kept_mask(f));
            }
            return;
        }
    }
}

@compute @workgroup_size(64)
fn overflow_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count || fabs_count(px) <= fu.param) {
        return;
    }
    for (var i = 0u; i < fu.param; i++) {
        atomicStore(&slots[i * fu.pixel_count + px], FABS_EMPTY);
    }
    atomicMax(&overflowed[0], 1u);
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let n = min(fabs_count(px), fu.param);
    let stride = fu.pixel_count;
    if (fu.msaa.x > 1u) {
        if (n > 1u) {
            fabs_heapsort(px, stride, n);
        }
        var back = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        if (fu.pass_index == FABS_WITH_TAIL) {
            // each sample over the pixel's one tail put over the sample's own opaque colour
            // (oit-cpu's Resolve::tail_over: transparency's back colour, which the other effects
            // do not composite over); its merged counted alike
            let layer = tail_layer(px);
            if (fu.effect == EFFECT_TRANSPARENCY) {
                back = layer;
            }
        }
        resolve_masked_over(px, px, n, back);
        return;
    }
    if (n == 0u && fu.pass_index != FABS_WITH_TAIL) {
        // nothing captured: the state stays as the frame cleared it
        return;
    }
    var s = load_state(px);
    if (!push_short_list(&s, px, n, false)) {
        // longer: heapsort in place (O(n log n) loops; an in-place insertion sort composited
        // only part of 2,000-entry lists on lavapipe, see dfb.wgsl)
        fabs_heapsort(px, stride, n);
        for (var i = 0u; i < n; i++) {
            let key = atomicLoad(&slots[i * stride + px]);
            push_local(&s, bitcast<f32>(u32(key >> 32u)), payloads[i * stride + px]);
        }
    }
    if (fu.pass_index == FABS_WITH_TAIL) {
        tail_resolve(&s, px);
    }
    store_state(px, s);
}

// Pixel `px`'s n slots (n at least 2) sorted by key in place: heapsort.
fn fabs_heapsort(px: u32, stride: u32, n: u32) {
    for (var i = n / 2u; i > 0u; i--) {
        fabs_sift_down(px, stride, i - 1u, n);
    }
    for (var end = n - 1u; end > 0u; end--) {
        fabs_swap(px, stride, 0u, end);
        fabs_sift_down(px, stride, 0u, end);
    }
}

// Slot e (i · pixels + px) of a pixel's sorted slots, for coverage.wgsl: its key, its payload,
// the slot after it.
fn entry_key(e: u32) -> u64 {
    return atomicLoad(&slots[e]);
}

fn entry_payload(e: u32) -> u32 {
    return payloads[e];
}

fn entry_next(e: u32) -> u32 {
    return e + fu.pixel_count;
}

// Slots `a` and `b` of pixel `px` (and their payloads and masks) exchanged.
fn fabs_swap(px: u32, stride: u32, a: u32, b: u32) {
    mask_swap(a * stride + px, b * stride + px);
    let k = atomicLoad(&slots[a * stride + px]);
    let p = payloads[a * stride + px];
    atomicStore(&slots[a * stride + px], atomicLoad(&slots[b * stride + px]));
    payloads[a * stride + px] = payloads[b * stride + px];
    atomicStore(&slots[b * stride + px], k);
    payloads[b * stride + px] = p;
}

// Moves slot `root` of pixel `px`'s heap of `n` slots down to its place (a max-heap by key).
fn fabs_sift_down(px: u32, stride: u32, root_in: u32, n: u32) {
    var root = root_in;
    loop {
        var child = 2u * root + 1u;
        if (child >= n) {
            break;
        }
        if (child + 1u < n
            && atomicLoad(&slots[(child + 1u) * stride + px]) > atomicLoad(&slots[child * stride + px])) {
            child += 1u;
        }
        if (atomicLoad(&slots[root * stride + px]) >= atomicLoad(&slots[child * stride + px])) {
            break;
        }
        fabs_swap(px, stride, root, child);
        root = child;
    }
}
