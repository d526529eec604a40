// ddp's dual peel at several samples: a range a sample, each sample's layers into its own accumulators
// module ddp_blend_samples (stage): technique/peel_samples.wgsl technique/ddp_blend_samples.wgsl
// ddp through the blend unit at several samples a pixel (`--hardware-capture blend`, `--samples
// 4|8`; docs/msaa.md, "The blend captures at several samples"): ddp_blend.wgsl's dual peel with
// its range kept a sample. Each pass MAX-blends (−d, d) of a fragment into a multisampled Rg32Float
// target at the samples it keeps (`hw_kept`: those it covers in front of their opaque depths)
// that lie strictly inside the previous pass's range at that sample (read a sample from the other
// of two ping-ponged range targets), so each sample ends the pass with its own nearest and
// farthest of what is left. The fragments lying exactly on a sample's previous ends hand their
// payloads over for that sample (u64 atomicMin / atomicMax of depth bits << 32 | payload, the
// atomics capture's keys), and count themselves once, at the lowest sample they keep (where a
// fragment is handed over once). The resolve composites each sample's near layer into its front
// accumulator and its far one into its back (peel_samples.wgsl); after the last pass every pixel's
// samples are finished over their own opaque colours (`accumulated`).
//
// Equal depths on one sample's end cannot be ordered here: the range targets hold depths, not
// primitive ids, and a fragment can win a tie at one sample and lose it at another in different
// passes. Two or more on one end would hand over one payload (the smallest or largest key) and
// lose the rest while each counts itself handed over, and two on a collapsed range would be
// composited in key order with nothing counted `tied`. So the hand-over's atomics say whether
// another fragment reached the same end of the same sample in this pass (the hand-overs start
// every pass empty: the previous value holds this depth only where one did), and such a pass sets
// `ddps_ties`, which the frame's end refuses by name (`oit_gpu::technique::ddp_blend_sample_state`:
// use the atomics capture, whose keys order ties by primitive id). Exact: a previous near value
// is empty (all ones, no depth's bits) or a fragment's key; a previous far value is empty (0) or a
// key whose depth lies beyond the sample's near end, so above 0, or on a collapsed range, where
// the near end's test already sees the tie.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE (group 0: fu, state), peel_samples.wgsl (group 0 binding
// 5: the accumulators), this, then the hardware raster's vertex stage (group 1 bindings 0..4) and
// blend_stage.wgsl (`hw_kept`).

// The hand-overs, a sample (sample i of pixel px at px · samples + i), and the fragments handed
// over, a pixel.
@group(0) @binding(2) var<storage, read_write> ddps_near_key: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> ddps_far_key: array<atomic<u64>>;
@group(0) @binding(4) var<storage, read_write> ddps_handed: array<atomic<u32>>;
// Set where two fragments or more reached one end of one sample's range in a pass (word 0).
@group(0) @binding(6) var<storage, read_write> ddps_ties: array<atomic<u32>>;

// (−near, far) of the previous pass a sample (unused by the first); nothing left: (−2, −2).
@group(2) @binding(0) var ddps_previous: texture_multisampled_2d<f32>;

const DDPS_NONE: u64 = 0xfffffffffffffffflu;

struct DdpPeelMsOut {
    @location(0) range: vec2<f32>,
    @builtin(sample_mask) written: u32,
}

@fragment
fn ddp_peel_ms_fs(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) covered: u32) -> DdpPeelMsOut {
    let kept = hw_kept(in, front, covered);
    if (kept == 0u) {
        discard;
    }
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    let px = xy.y * fu.width + xy.x;
    // the clamped depth of the atomics capture, compared through its bits as ddp.wgsl does
    let d = depth_bits(clamp(in.position.z, 0.0, 1.0));
    var inside = kept;
    if (fu.pass_index > 0u) {
        inside = 0u;
        let n = fu.msaa.x;
        let lowest = kept & (0u - kept);
        var f: Fragment;
        f.pixel = px;
        f.depth = bitcast<f32>(d);
        f.prim = in.prim;
        f.color = clamp(hw_color(in), vec4<f32>(0.0), vec4<f32>(1.0));
        f.normal = normalize_or_zero(in.normal);
        let key = (u64(d) << 32u) | u64(payload(f, fu.effect));
        for (var i = 0u; i < n; i++) {
            if (((kept >> i) & 1u) == 0u) {
                continue;
            }
            let previous = textureLoad(ddps_previous, vec2<i32>(xy), i32(i)).xy;
            if (-previous.x > previous.y) {
                // nothing left at this sample
                continue;
            }
            let near = depth_bits(-previous.x);
            let far = depth_bits(previous.y);
            if (d == near || d == far) {
                // another fragment at this end of this sample in this pass: a tie
                var tie = false;
                if (d == near) {
                    let was = atomicMin(&ddps_near_key[px * n + i], key);
                    tie = tie || (was != DDPS_NONE && u32(was >> 32u) == d);
                }
                if (d == far) {
                    let was = atomicMax(&ddps_far_key[px * n + i], key);
                    tie = tie || (was != 0lu && u32(was >> 32u) == d);
                }
                if (tie) {
                    atomicStore(&ddps_ties[0], 1u);
                }
                if ((1u << i) == lowest) {
                    atomicAdd(&ddps_handed[px], 1u);
                }
            }
            if (d > near && d < far) {
                inside |= 1u << i;
            }
        }
    }
    if (inside == 0u) {
        discard;
    }
    let depth = bitcast<f32>(d);
    return DdpPeelMsOut(vec2<f32>(-depth, depth), inside);
}

// Before the first pass: every sample's accumulators set (the hand-overs start empty).
@compute @workgroup_size(64)
fn ddp_init_ms_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    accumulators_init(px, 2u);
}

// After a pass past the first: each sample's near layer into its front, its far one (where it
// is another) into its back; the fragments handed over counted.
@compute @workgroup_size(64)
fn ddp_resolve_ms_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let n = fu.msaa.x;
    for (var i = 0u; i < n; i++) {
        let near = atomicExchange(&ddps_near_key[px * n + i], DDPS_NONE);
        let far = atomicExchange(&ddps_far_key[px * n + i], 0lu);
        if (near == DDPS_NONE) {
            continue;
        }
        accumulate_samples(px, 2u, u32(near & 0xfffffffflu), 1u << i, 0u);
        if (far != near) {
            accumulate_samples(px, 2u, u32(far & 0xfffffffflu), 1u << i, 1u);
        }
    }
    let handed = atomicExchange(&ddps_handed[px], 0u);
    if (handed != 0u) {
        var s = load_state(px);
        s.captured += handed;
        store_state(px, s);
    }
}

// After the last pass: every pixel's samples finished over what lies behind them.
@compute @workgroup_size(64)
fn ddp_finish_ms_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    accumulated(px, 2u);
}
