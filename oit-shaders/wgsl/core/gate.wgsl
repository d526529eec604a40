// module gate (kernels): core/gate.wgsl
// The gate of a geometry pass that has work only where word 0 of `gate_flag` is set (fabs's
// overflow passes, the tails' pass): the driver's arguments copied from `gate_from` to `gate_to`
// (param words; zeros when the flag is clear, so the dispatch or draw does nothing), and the pass
// counted in the frame's totals (word 5) when it runs. No readback: the flag stays on the device.
@group(0) @binding(2) var<storage, read_write> gate_flag: array<u32>;
@group(0) @binding(3) var<storage, read_write> gate_totals: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> gate_from: array<u32>;
@group(0) @binding(5) var<storage, read_write> gate_to: array<u32>;

@compute @workgroup_size(64)
fn gate_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let open = gate_flag[0] != 0u;
    if (gid.x == 0u && open) {
        atomicAdd(&gate_totals[5], 1u);
    }
    if (gid.x < fu.param) {
        gate_to[gid.x] = select(0u, gate_from[gid.x], open);
    }
}

// An occlusion query's 64-bit result (`gate_from`, as resolved) folded into word 0 of `gate_flag`:
// 1 where any sample passed (either word non-zero: zero or not is all a query promises), else 0,
// the flag a gated pass and a frame-end check read (the blend captures' peel loops).
@compute @workgroup_size(1)
fn occlusion_main() {
    gate_flag[0] = select(0u, 1u, (gate_from[0] | gate_from[1]) != 0u);
}
