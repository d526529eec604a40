// module ddp_blend (stage): technique/ddp_blend.wgsl
// ddp through the graphics pipeline (Bavoil & Myers 2008): each pass MAX-blends (−d, d) of the
// fragments strictly inside the previous pass's range into an Rg32Float target, so the target
// ends the pass holding (−nearest, farthest) of what is left; the fragments lying exactly on the
// previous range's ends are the layers that pass found, and they hand over their payloads here
// (u64 atomicMin / atomicMax of depth bits << 32 | payload into ddp.wgsl's `ddp_near` and
// `ddp_far`, the same keys as the atomics capture, so equal depths resolve the same way).
// ddp.wgsl's `resolve_main` then composites them. Fragments outside the open range are discarded
// after their hand-over, so the pass's occlusion query counts what is left to peel.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE (group 0: fu, state), this, then the hardware raster's
// vertex stage (group 1 bindings 0..4; `HwOut`, `hw_vs`, `hw_color`) and `hw_dropped`
// (blend_stage.wgsl: a fragment at or behind the opaque depth never enters a range).
@group(0) @binding(2) var<storage, read_write> ddp_near: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> ddp_far: array<atomic<u64>>;

// (−near, far) of the previous pass (unused by the first); nothing left: (−2, −2).
@group(2) @binding(0) var ddp_previous: texture_2d<f32>;

@fragment
fn ddp_peel_fs(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec2<f32> {
    if (hw_dropped(in, front)) {
        discard;
    }
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    // the clamped depth of the atomics capture, compared through its bits as ddp.wgsl does
    let d = depth_bits(clamp(in.position.z, 0.0, 1.0));
    var inside = true;
    if (fu.pass_index > 0u) {
        let previous = textureLoad(ddp_previous, vec2<i32>(xy), 0).xy;
        if (-previous.x > previous.y) {
            discard;
        }
        let near = depth_bits(-previous.x);
        let far = depth_bits(previous.y);
        if (d == near || d == far) {
            var f: Fragment;
            f.pixel = xy.y * fu.width + xy.x;
            f.depth = bitcast<f32>(d);
            f.prim = in.prim;
            f.color = clamp(
                hw_color(in),
                vec4<f32>(0.0),
                vec4<f32>(1.0),
            );
            f.normal = normalize_or_zero(in.normal);
            let key = (u64(d) << 32u) | u64(payload(f, fu.effect));
            if (d == near) {
                atomicMin(&ddp_near[f.pixel], key);
            }
            if (d == far) {
                atomicMax(&ddp_far[f.pixel], key);
            }
        }
        inside = d > near && d < far;
    }
    if (!inside) {
        discard;
    }
    let depth = bitcast<f32>(d);
    return vec2<f32>(-depth, depth);
}
