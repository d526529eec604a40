// module ddp (raster): technique/ddp.wgsl
// ddp: dual depth peeling (Bavoil & Myers 2008), as oit-cpu's `technique/ddp.rs`. Each geometry
// pass takes, per pixel, the nearest and the farthest fragment strictly inside the open range the
// previous pass left (u64 atomicMin / atomicMax of depth bits << 32 | payload); the resolve pushes
// the near one to the front and the far one to the back (transparency), or counts both
// (complexity), and narrows the range.
@group(0) @binding(2) var<storage, read_write> ddp_near: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> ddp_far: array<atomic<u64>>;
// Per pixel (low + 1, high) of the open range in depth bits: d + 1 > low + 1 and d < high.
// The first pass: (0, 0xffffffff), everything; a pixel with nothing left: (1, 0), nothing.
@group(0) @binding(4) var<storage, read_write> ddp_range: array<u32>;
// [pixels that peeled a layer this pass]
@group(0) @binding(5) var<storage, read_write> peeled: array<atomic<u32>>;

const DDP_EMPTY_MIN: u64 = 0xfffffffffffffffflu;

fn capture(f: Fragment) {
    let d = depth_bits(f.depth);
    let px = f.pixel;
    let lo = ddp_range[2u * px];
    let hi = ddp_range[2u * px + 1u];
    if (d + 1u > lo && d < hi) {
        let key = (u64(d) << 32u) | u64(payload(f, fu.effect));
        atomicMin(&ddp_near[px], key);
        atomicMax(&ddp_far[px], key);
        if (last_pass()) {
            // the last peel allowed: all but the one or two it peels stay behind
            seen(px);
        }
    } else if (atomicLoad(&acct[3u * px + 2u]) > 0u && (d + 1u == lo || d == hi)) {
        // at a depth just peeled: a peeled one, or a tie the strict range skips
        seen(px);
    }
}

// Before the first pass: every ddp_range open.
@compute @workgroup_size(64)
fn ddp_init_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    ddp_range[2u * px] = 0u;
    ddp_range[2u * px + 1u] = 0xffffffffu;
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let n = atomicExchange(&ddp_near[px], DDP_EMPTY_MIN);
    let f = atomicExchange(&ddp_far[px], 0lu);
    var count = 0u;
    if (n != DDP_EMPTY_MIN) {
        count = select(1u, 2u, f != n);
    }
    // ties at the previous pass's depths, or (last pass) what it left behind
    let before = atomicExchange(&acct[3u * px + 2u], count);
    settle(px, select(before, before + count, last_pass()));
    if (n == DDP_EMPTY_MIN) {
        ddp_range[2u * px] = 1u;
        ddp_range[2u * px + 1u] = 0u;
        return;
    }
    let dn = u32(n >> 32u);
    let df = u32(f >> 32u);
    push(px, bitcast<f32>(dn), u32(n & 0xfffffffflu));
    if (f != n) {
        if (fu.effect == EFFECT_TRANSPARENCY) {
            push_back(px, bitcast<f32>(df), u32(f & 0xfffffffflu));
        } else {
            // complexity: only the count matters, and push counts it
            push(px, bitcast<f32>(df), u32(f & 0xfffffffflu));
        }
    }
    ddp_range[2u * px] = dn + 1u;
    ddp_range[2u * px + 1u] = df;
    atomicAdd(&peeled[0], 1u);
}
