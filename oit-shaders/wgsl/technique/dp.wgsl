// module dp (raster): technique/dp.wgsl
// dp: classical depth peeling (Everitt 2001), as oit-cpu's `technique/dp.rs`. Each geometry pass
// keeps, per pixel, the nearest fragment strictly behind the previous peeled layer (u64 atomicMin
// of depth bits << 32 | payload); the resolve kernel composites it under the layers before and
// counts the pixels that peeled something (the occlusion query that ends the loop).
@group(0) @binding(2) var<storage, read_write> nearest: array<atomic<u64>>;
// Depth bits + 1 of the last peeled layer; 0: nothing peeled yet (below every depth).
@group(0) @binding(3) var<storage, read_write> previous: array<u32>;
// [pixels that peeled a layer this pass]
@group(0) @binding(4) var<storage, read_write> peeled: array<atomic<u32>>;

const DP_EMPTY: u64 = 0xfffffffffffffffflu;
const DP_DONE: u32 = 0xffffffffu;

fn capture(f: Fragment) {
    let d = depth_bits(f.depth);
    let prev = previous[f.pixel];
    if (d + 1u > prev) {
        let old = atomicMin(&nearest[f.pixel], (u64(d) << 32u) | u64(payload(f, fu.effect)));
        // the last peel allowed: of two fragments one is left behind for good
        if (last_pass() && old != DP_EMPTY) {
            lose(f.pixel);
        }
    } else if (prev != 0u && d + 1u == prev) {
        // at the depth just peeled: the peeled one, or a coplanar tie the `>` skips
        seen(f.pixel);
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    if (previous[px] != 0u && previous[px] != DP_DONE) {
        settle(px, 1u);
    }
    let key = atomicExchange(&nearest[px], DP_EMPTY);
    if (key == DP_EMPTY) {
        // nothing behind: done (no depth matches DP_DONE, so no tie is counted twice)
        previous[px] = DP_DONE;
        return;
    }
    let d = u32(key >> 32u);
    push(px, bitcast<f32>(d), u32(key & 0xfffffffflu));
    previous[px] = d + 1u;
    atomicAdd(&peeled[0], 1u);
}
