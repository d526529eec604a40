// module ll (raster): technique/ll.wgsl technique/coverage.wgsl technique/short_list.wgsl
// ll, per-pixel linked lists (Yang et al. 2010), as oit-cpu's `technique/ll.rs`: a head per
// pixel (LL_END when empty), a pool of fu.param nodes sized by the sizing pass (ll_size.wgsl), a
// node counter. The capture takes a node by atomicAdd on the counter (past the pool: lost, where
// it happens), writes the key (depth bits << 32 | primitive id) and payload into it, and links it
// in front of its pixel's list by atomicExchange on the head. The resolve walks each list into
// private arrays of up to SHORT_LIST (short_list.wgsl), sorted as it goes (insertion, farthest
// first: a list holds its pixel's fragments newest first, so fragments that arrived front to back
// come out farthest first and each insertion is one comparison, as fabs's are for its slots in
// arrival order; sorted nearest first, that order was the insertion's worst case), and
// composites it from the nearest; a longer list is merge-sorted in place along its links.
@group(0) @binding(2) var<storage, read_write> heads: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> counter: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> keys: array<u64>;
@group(0) @binding(5) var<storage, read_write> payloads: array<u32>;
@group(0) @binding(6) var<storage, read_write> links: array<u32>;
// multisampled: each node's coverage mask, a byte (coverage.wgsl); a placeholder at one sample.
// A multisampled list is always merge-sorted along its links (the nodes, and so their masks,
// stay where they are), then resolved per sample.
@group(0) @binding(7) var<storage, read_write> masks: array<atomic<u32>>;

// the end of a list, where short_list.wgsl's walk stops
const LL_END: u32 = LIST_END;

fn capture(f: Fragment) {
    let node = atomicAdd(&counter[0], 1u);
    if (node >= fu.param) {
        // the pool is used up: no node for this fragment
        lose(f.pixel);
        return;
    }
    keys[node] = (u64(depth_bits(f.depth)) << 32u) | u64(f.prim);
    payloads[node] = payload(f, fu.effect);
    if (fu.msaa.x > 1u) {
        mask_new(node, kept_mask(f));
    }
    links[node] = atomicExchange(&heads[f.pixel], node);
}

// Node e of a sorted list, for coverage.wgsl: its key, its payload, the node after it.
fn entry_key(e: u32) -> u64 {
    return keys[e];
}

fn entry_payload(e: u32) -> u32 {
    return payloads[e];
}

fn entry_next(e: u32) -> u32 {
    return links[e];
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let head = atomicLoad(&heads[px]);
    if (head == LL_END) {
        // nothing captured: the state stays as the frame cleared it (and composites the
        // background where multisampled)
        return;
    }
    let masked = fu.msaa.x > 1u;
    var s = load_state(px);
    // as many entries as the walk finds before LL_END
    if (!masked && push_short_list(&s, head, 0xffffffffu, true)) {
        store_state(px, s);
        return;
    }
    // longer than the private array: merge sort along the links, in place (S. Tatham's
    // bottom-up merge sort of a linked list: runs of `width` nodes merged pairwise, `width`
    // doubled until one run is left), then walked
    var first = head;
    var width = 1u;
    loop {
        var p = first;
        first = LL_END;
        var tail = LL_END;
        var merges = 0u;
        while (p != LL_END) {
            merges += 1u;
            var q = p;
            var p_len = 0u;
            for (var i = 0u; i < width && q != LL_END; i++) {
                p_len += 1u;
                q = links[q];
            }
            var q_len = width;
            while (p_len > 0u || (q_len > 0u && q != LL_END)) {
                var e: u32;
                if (p_len == 0u || (q_len > 0u && q != LL_END && keys[q] < keys[p])) {
                    e = q;
                    q = links[q];
                    q_len -= 1u;
                } else {
                    e = p;
                    p = links[p];
                    p_len -= 1u;
                }
                if (tail == LL_END) {
                    first = e;
                } else {
                    links[tail] = e;
                }
                tail = e;
            }
            p = q;
        }
        links[tail] = LL_END;
        if (merges <= 1u) {
            break;
        }
        width *= 2u;
    }
    atomicStore(&heads[px], first);
    if (masked) {
        var count = 0u;
        for (var a = first; a != LL_END; a = links[a]) {
            count += 1u;
        }
        resolve_masked(px, first, count);
        return;
    }
    for (var a = first; a != LL_END; a = links[a]) {
        push_local(&s, bitcast<f32>(u32(keys[a] >> 32u)), payloads[a]);
    }
    store_state(px, s);
}
