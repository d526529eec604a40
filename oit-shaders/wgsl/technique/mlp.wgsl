// module mlp (raster): technique/mlp.wgsl
// mlp:M: extended multi-layer peeling (Huang et al. 2011, section 3.3), as oit-cpu's
// `technique/mlp.rs`. Each geometry pass inserts, per pixel, the fragments strictly behind the
// deepest one the previous pass captured into M u64 words by repeated atomicMin (as mdts64), and
// raises `overflowed` when one falls off the end; the resolve composites the M words, empties them
// and records the deepest. param = M.
@group(0) @binding(2) var<storage, read_write> mlp_slots: array<atomic<u64>>;
// Depth bits + 1 of the deepest fragment captured so far; 0: none yet (below every depth).
@group(0) @binding(3) var<storage, read_write> mlp_deepest: array<u32>;
// [1 when some pixel had more than M fragments left in this pass]
@group(0) @binding(4) var<storage, read_write> mlp_overflowed: array<atomic<u32>>;

const MLP_EMPTY: u64 = 0xfffffffffffffffflu;

fn mlp_insert(base: u32, key: u64) -> bool {
    var carry = key;
    for (var i = 0u; i < fu.param; i++) {
        let old = atomicMin(&mlp_slots[base + i], carry);
        if (old == MLP_EMPTY) {
            return false;
        }
        carry = max(carry, old);
    }
    return true;
}

fn capture(f: Fragment) {
    let d = depth_bits(f.depth);
    let deepest = mlp_deepest[f.pixel];
    if (d + 1u > deepest) {
        if (mlp_insert(f.pixel * fu.param, (u64(d) << 32u) | u64(payload(f, fu.effect)))) {
            atomicStore(&mlp_overflowed[0], 1u);
            if (last_pass()) {
                // carried off the end in the last pass the plan allows
                lose(f.pixel);
            }
        }
    } else if (deepest != 0u && d + 1u == deepest) {
        // at the deepest depth the pass before captured: captured then, or a tie skipped
        seen(f.pixel);
    }
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = load_state(px);
    let base = px * fu.param;
    settle(px, atomicLoad(&acct[3u * px + 2u]));
    var at = 0u;
    var deep = mlp_deepest[px];
    for (var i = 0u; i < fu.param; i++) {
        let key = atomicExchange(&mlp_slots[base + i], MLP_EMPTY);
        if (key == MLP_EMPTY) {
            break;
        }
        let d = u32(key >> 32u);
        push_local(&s, bitcast<f32>(d), u32(key & 0xfffffffflu));
        at = select(1u, at + 1u, d + 1u == deep);
        deep = d + 1u;
    }
    if (at == 0u) {
        // nothing left behind the deepest: done (no depth matches all ones)
        deep = 0xffffffffu;
    }
    mlp_deepest[px] = deep;
    atomicStore(&acct[3u * px + 2u], at);
    store_state(px, s);
}
