// module adp (raster): technique/adp.wgsl
// adp (Liu et al., HPG 2009, section 3.3), as oit-cpu's `technique/adp.rs`.
// pass_index 0: histogram pass; pass_index 1: bucket pass of batch `param`.
@group(0) @binding(2) var<storage, read_write> bounds: array<u32>;
// 32 u32 words (1024 presence bits) per pixel, set with atomicOr.
@group(0) @binding(3) var<storage, read_write> hist: array<atomic<u32>>;
// 32 u64 buckets per pixel: MAX of (depth key | 1 << 63); 0 is empty.
@group(0) @binding(4) var<storage, read_write> buckets: array<atomic<u64>>;
// The deepest pixel's set-bin count.
@group(0) @binding(5) var<storage, read_write> max_bins: array<atomic<u32>>;
// 32 u64 a pixel beside the buckets: MIN of each bin's depth keys (all ones is empty), so a bin of
// two fragments is captured whole (oit-cpu's `technique/adp.rs`).
@group(0) @binding(6) var<storage, read_write> nearest: array<atomic<u64>>;

const ADP_FILLED: u64 = 0x8000000000000000lu;

fn adp_bin(f: Fragment) -> u32 {
    let zn = bitcast<f32>(bounds[2u * f.pixel]);
    let zf = bitcast<f32>(bounds[2u * f.pixel + 1u]);
    return histogram_bin(f.depth, zn, zf);
}

// oit_core::rules::histogram_rank: the set bins of the pixel's histogram below `bin`.
fn adp_rank(px: u32, bin: u32) -> u32 {
    let word = bin / 32u;
    var below = 0u;
    for (var w = 0u; w < word; w++) {
        below += countOneBits(atomicLoad(&hist[px * HISTOGRAM_WORDS + w]));
    }
    let mask = (1u << (bin % 32u)) - 1u;
    return below + countOneBits(atomicLoad(&hist[px * HISTOGRAM_WORDS + word]) & mask);
}

fn capture(f: Fragment) {
    let px = f.pixel;
    let bin = adp_bin(f);
    if (fu.pass_index == 0u) {
        atomicOr(&hist[px * HISTOGRAM_WORDS + bin / 32u], 1u << (bin % 32u));
        return;
    }
    let rank = adp_rank(px, bin);
    if (rank / BUCKETS == fu.param) {
        let key = (u64(depth_bits(f.depth)) << 32u) | u64(payload(f, fu.effect));
        let bucket = px * BUCKETS + rank % BUCKETS;
        // the nearest of the bin (a depth key never has all bits set: depths are ≤ 1)
        atomicMin(&nearest[bucket], key);
        // two fragments in one bin: the MAX kept one (the resolve takes one back where the MIN
        // kept another)
        if (atomicMax(&buckets[bucket], key | ADP_FILLED) != 0lu) {
            lose(px);
        }
    } else if (rank / BUCKETS > fu.param && last_pass()) {
        // beyond the last batch the plan allows (--max-peels)
        lose(px);
    }
}

// The deepest pixel's set-bin count (sizes the number of batches).
@compute @workgroup_size(64)
fn count_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var n = 0u;
    for (var w = 0u; w < HISTOGRAM_WORDS; w++) {
        n += countOneBits(atomicLoad(&hist[px * HISTOGRAM_WORDS + w]));
    }
    atomicMax(&max_bins[0], n);
}

// One batch's resolve: the filled buckets in rank order, each bin's nearest then its farthest
// where they differ, emptied for the next.
@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = load_state(px);
    for (var b = 0u; b < BUCKETS; b++) {
        let key = atomicExchange(&buckets[px * BUCKETS + b], 0lu);
        let near = atomicExchange(&nearest[px * BUCKETS + b], 0xfffffffffffffffflu);
        if (key != 0lu) {
            let k = key & ~ADP_FILLED;
            if (near != k) {
                // a second fragment of the bin, in front of the farthest: captured after all
                push_local(&s, bitcast<f32>(u32(near >> 32u)), u32(near & 0xfffffffflu));
                atomicSub(&acct[3u * px], 1u);
            }
            push_local(&s, bitcast<f32>(u32(k >> 32u)), u32(k & 0xfffffffflu));
        }
    }
    store_state(px, s);
}
