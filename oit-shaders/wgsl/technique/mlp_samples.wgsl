// mlp per sample: M (depth, primitive id) keys a pass into per-sample accumulators
// module mlp_samples (raster): technique/peel_samples.wgsl technique/mlp_samples.wgsl
// mlp:M per sample (several samples; oit-cpu's `mlp::render_samples`, docs/msaa.md): each geometry
// pass inserts, per pixel, the (depth bits, primitive id, lowest sample: `peel_key`) keys strictly behind the deepest key the
// pass before kept into M u64 slots by repeated atomicMin (as mlp.wgsl), so every fragment is one
// layer, ties in the reference's order. The fragments whose keys are among those the pass before
// kept write their payloads and coverage masks, which the resolve composites, nearest first, into
// the covered samples' accumulators (peel_samples.wgsl). The pass that keeps nothing fetches the
// last ones; in the last pass the plan allows (one past the peel limit) nothing is kept and what
// lies behind is lost. param = M.
@group(0) @binding(2) var<storage, read_write> mlps_slots: array<atomic<u64>>;
// the keys the pass before kept, sorted, all ones past them: M a pixel; a pixel whose keys are all
// ones after the first pass is done (nothing lies behind the deepest)
@group(0) @binding(3) var<storage, read_write> mlps_previous: array<u64>;
// the payload and mask of each of those keys, two words each
@group(0) @binding(4) var<storage, read_write> mlps_layers: array<u32>;
// [pixels that kept a layer this pass]
@group(0) @binding(6) var<storage, read_write> peeled: array<atomic<u32>>;

const MLPS_EMPTY: u64 = 0xfffffffffffffffflu;

fn mlps_insert(base: u32, key: u64) {
    var carry = key;
    for (var i = 0u; i < fu.param; i++) {
        let old = atomicMin(&mlps_slots[base + i], carry);
        if (old == MLPS_EMPTY) {
            return;
        }
        carry = max(carry, old);
    }
}

fn capture(f: Fragment) {
    let base = f.pixel * fu.param;
    let k = peel_key(f);
    if (fu.pass_index != 0u) {
        if (mlps_previous[base] == MLPS_EMPTY) {
            // done
            return;
        }
        // at or in front of the deepest key the pass before kept: one of them, or composited
        // earlier
        for (var i = 0u; i < fu.param; i++) {
            let p = mlps_previous[base + i];
            if (p == MLPS_EMPTY) {
                break;
            }
            if (p == k) {
                mlps_layers[2u * (base + i)] = payload(f, fu.effect);
                mlps_layers[2u * (base + i) + 1u] = f.mask;
                return;
            }
            if (p > k) {
                return;
            }
        }
    }
    if (last_pass()) {
        // behind the last layers the limit allows
        lose(f.pixel);
    } else {
        mlps_insert(base, k);
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let base = px * fu.param;
    if (fu.pass_index == 0u) {
        accumulators_init(px, 1u);
    } else {
        if (mlps_previous[base] == MLPS_EMPTY) {
            return;
        }
        for (var i = 0u; i < fu.param; i++) {
            if (mlps_previous[base + i] == MLPS_EMPTY) {
                break;
            }
            accumulate(px, 1u, mlps_layers[2u * (base + i)], mlps_layers[2u * (base + i) + 1u], 0u);
        }
    }
    var kept = false;
    for (var i = 0u; i < fu.param; i++) {
        let key = atomicExchange(&mlps_slots[base + i], MLPS_EMPTY);
        mlps_previous[base + i] = key;
        kept = kept || key != MLPS_EMPTY;
    }
    if (!kept) {
        accumulated(px, 1u);
        return;
    }
    atomicAdd(&peeled[0], 1u);
}
