// module bdp (raster): technique/bdp.wgsl
// bdp and bdp:P (Liu et al., HPG 2009, section 3.2), as oit-cpu's `technique/bdp.rs`.
// bounds: [zNear, zFar] bits per pixel (bounds.wgsl). pass_index 0 with param 0: colour mode;
// otherwise depth mode, pass `pass_index` of `bdp:P` (see bdp.rs).
@group(0) @binding(2) var<storage, read_write> bounds: array<u32>;
// Colour mode: 32 u32 buckets per pixel, integer MAX of bdp_pack_color; bucket k of pixel px is
// colors[k · pixels + px] (bucket-major), so that the resolve's neighbouring invocations read
// neighbouring words: pixel-major (px · 32 + k), each of its atomic loads touched as many memory
// sectors as invocations.
@group(0) @binding(3) var<storage, read_write> colors: array<atomic<u32>>;
// Depth mode: one array per pass, each 16 × (min, max) u64 keys per pixel, arrays back to back.
@group(0) @binding(4) var<storage, read_write> arrays: array<atomic<u64>>;

const MODE_COLOR: u32 = 0u;
const MODE_DEPTH: u32 = 1u;

fn bdp_z_near(px: u32) -> f32 {
    return bitcast<f32>(bounds[2u * px]);
}

fn bdp_z_far(px: u32) -> f32 {
    return bitcast<f32>(bounds[2u * px + 1u]);
}

// u64 words of one pass's array
fn bdp_stride() -> u32 {
    return fu.pixel_count * 2u * BDP_DEPTH_SUBINTERVALS;
}

// param: MODE_COLOR or MODE_DEPTH; pass_index: the pass of bdp:P (depth mode)
fn capture(f: Fragment) {
    let px = f.pixel;
    let zn = bdp_z_near(px);
    let zf = bdp_z_far(px);
    if (fu.param == MODE_COLOR) {
        let k = bucket_index(f.depth, zn, zf, BDP_COLOR_SUBINTERVALS);
        let word = bdp_pack_color(pack_rgba8(f.color));
        // a full bucket: one of the two fragments is gone; a zero word is never read back
        if (atomicMax(&colors[k * fu.pixel_count + px], word) != 0u || word == 0u) {
            lose(px);
        }
        return;
    }
    let k = bucket_index(f.depth, zn, zf, BDP_DEPTH_SUBINTERVALS);
    let slot = px * 2u * BDP_DEPTH_SUBINTERVALS + 2u * k;
    let p = fu.pass_index;
    let d = depth_bits(f.depth);
    if (p > 0u) {
        let prev = (p - 1u) * bdp_stride() + slot;
        let lo = atomicLoad(&arrays[prev]);
        let hi = atomicLoad(&arrays[prev + 1u]);
        // eq. 5: what the previous pass kept, or anything outside its range, is done
        if (!bdp_eq5_next(d, lo, hi)) {
            // at a depth the previous pass kept: kept then, or a tie eq. 5 skips
            if (lo != BDP_EMPTY_MIN && (d == u32(lo >> 32u) || d == u32(hi >> 32u))) {
                seen(px);
            }
            return;
        }
    }
    let key = (u64(d) << 32u) | u64(payload(f, fu.effect));
    let at = p * bdp_stride() + slot;
    atomicMin(&arrays[at], key);
    atomicMax(&arrays[at + 1u], key);
    if (last_pass()) {
        // the last pass: all but the kept min and max stay behind
        seen(px);
    }
}

// Empties the depth-mode arrays: min slots EMPTY, max slots 0. One invocation per (min, max) pair.
@compute @workgroup_size(64)
fn depth_init_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = kernel_pixel(gid, groups);
    if (2u * i + 1u >= arrayLength(&arrays)) {
        return;
    }
    atomicStore(&arrays[2u * i], BDP_EMPTY_MIN);
    atomicStore(&arrays[2u * i + 1u], 0lu);
}

// Colour mode's resolve: non-empty buckets in order, each at its subinterval's midpoint.
@compute @workgroup_size(64)
fn color_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = load_state(px);
    let zn = bdp_z_near(px);
    let zf = bdp_z_far(px);
    let n = BDP_COLOR_SUBINTERVALS;
    for (var k = 0u; k < n; k++) {
        let v = atomicLoad(&colors[k * fu.pixel_count + px]);
        if (v != 0u) {
            let d = bucket_midpoint(k, n, zn, zf);
            push_local(&s, d, bdp_unpack_color(v));
        }
    }
    store_state(px, s);
}

// Depth mode's resolve; param = arrays captured. Subinterval k reads min₁ … min_P, max_P … max₁
// (a max equal to its min is the same fragment; an empty min ends the subinterval).
@compute @workgroup_size(64)
fn depth_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = load_state(px);
    let arrays_used = fu.param;
    for (var k = 0u; k < BDP_DEPTH_SUBINTERVALS; k++) {
        let slot = px * 2u * BDP_DEPTH_SUBINTERVALS + 2u * k;
        var filled = 0u;
        for (var a = 0u; a < arrays_used; a++) {
            let lo = atomicLoad(&arrays[a * bdp_stride() + slot]);
            if (lo == BDP_EMPTY_MIN) {
                break;
            }
            push_local(&s, bitcast<f32>(u32(lo >> 32u)), u32(lo & 0xfffffffflu));
            filled += 1u;
        }
        for (var a = filled; a > 0u; a--) {
            let at = (a - 1u) * bdp_stride() + slot;
            let lo = atomicLoad(&arrays[at]);
            let hi = atomicLoad(&arrays[at + 1u]);
            if (hi != lo) {
                push_local(&s, bitcast<f32>(u32(hi >> 32u)), u32(hi & 0xfffffffflu));
            }
        }
    }
    store_state(px, s);
}

// Fragments array `p` kept for pixel `px`: a min, and a max unless it is the same key.
fn bdp_kept(p: u32, px: u32) -> u32 {
    var n = 0u;
    for (var k = 0u; k < BDP_DEPTH_SUBINTERVALS; k++) {
        let at = p * bdp_stride() + px * 2u * BDP_DEPTH_SUBINTERVALS + 2u * k;
        let lo = atomicLoad(&arrays[at]);
        let hi = atomicLoad(&arrays[at + 1u]);
        if (lo != BDP_EMPTY_MIN) {
            n += select(2u, 1u, hi == lo);
        }
    }
    return n;
}

// After depth pass `fu.pass_index`: ties at the previous pass's depths, and in the last pass what
// it left behind, become lost (oit-cpu's `bdp.rs`).
@compute @workgroup_size(64)
fn depth_settle_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let p = fu.pass_index;
    var taken = 0u;
    if (p > 0u) {
        taken = bdp_kept(p - 1u, px);
    }
    if (last_pass()) {
        taken += bdp_kept(p, px);
    }
    settle(px, taken);
}
