// module scan (kernels): technique/scan.wgsl
// An exclusive prefix sum (scan) of `fu.param` 32-bit words, in place, in blocks of SCAN_BLOCK
// (64 invocations × 4 words). `scan_main` scans each block within its workgroup and writes the
// block's total to `block_sums`; the host scans `block_sums` the same way (one level per 256×
// fewer words, until one block holds them all) and `add_main` adds each block's scanned offset
// back into the block. dfb's offsets come from it (see `technique::scan`).
@group(0) @binding(2) var<storage, read_write> words: array<u32>;
@group(0) @binding(3) var<storage, read_write> block_sums: array<u32>;

const SCAN_PER_INVOCATION: u32 = 4u;
const SCAN_BLOCK: u32 = 256u;

var<workgroup> partial: array<u32, 64>;

@compute @workgroup_size(64)
fn scan_main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let block = wid.x + wid.y * groups.x;
    let base = block * SCAN_BLOCK + t * SCAN_PER_INVOCATION;
    var v: array<u32, 4>;
    var sum = 0u;
    for (var j = 0u; j < SCAN_PER_INVOCATION; j++) {
        let i = base + j;
        if (i < fu.param) {
            v[j] = words[i];
        }
        sum += v[j];
    }
    partial[t] = sum;
    workgroupBarrier();
    // the 64 invocations' totals, scanned inclusively (Hillis and Steele)
    for (var d = 1u; d < 64u; d *= 2u) {
        var below = 0u;
        if (t >= d) {
            below = partial[t - d];
        }
        workgroupBarrier();
        partial[t] += below;
        workgroupBarrier();
    }
    var run = partial[t] - sum;
    for (var j = 0u; j < SCAN_PER_INVOCATION; j++) {
        let i = base + j;
        if (i < fu.param) {
            words[i] = run;
        }
        run += v[j];
    }
    // a 2D dispatch may run workgroups past the last block: they write nothing
    if (t == 63u && block * SCAN_BLOCK < fu.param) {
        block_sums[block] = partial[63];
    }
}

@compute @workgroup_size(64)
fn add_main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let block = wid.x + wid.y * groups.x;
    if (block * SCAN_BLOCK >= fu.param) {
        return;
    }
    let add = block_sums[block];
    let base = block * SCAN_BLOCK + t * SCAN_PER_INVOCATION;
    for (var j = 0u; j < SCAN_PER_INVOCATION; j++) {
        let i = base + j;
        if (i < fu.param) {
            words[i] += add;
        }
    }
}
