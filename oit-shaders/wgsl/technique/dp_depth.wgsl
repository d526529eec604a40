// module dp_depth (stage): technique/dp_depth.wgsl
// dp through the graphics pipeline (Everitt 2001): each peel renders the scene with a depth test
// (LESS_EQUAL, cleared to 1) into a fresh Depth32Float attachment, while the fragment stage
// discards fragments at or in front of the previous peel's depth (read by pixel from the other
// of two ping-ponged depth textures); the nearest remaining fragment's payload lands in an
// Rg32Uint target (payload, 1 = peeled), and a compute step composites it under the layers
// before with `push`, its depth read from this peel's depth attachment.
//
// Strictly behind the previous layer, as dp.wgsl's `d + 1 > previous` on the same clamped
// depth; equal depths in one peel keep the last drawn (dp.wgsl keeps the smallest payload), and
// the other is lost in both.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE (group 0: fu, state), this, then the hardware raster's
// vertex stage (group 1 bindings 0..4; `HwOut`, `hw_vs`, `hw_color`) and `hw_dropped`
// (blend_stage.wgsl: a fragment at or behind the opaque depth is discarded before the depth
// test writes it, so no peel reaches it).

// The previous peel's depth (render pipeline, group 2; unused on the first peel).
@group(2) @binding(0) var dp_previous: texture_depth_2d;

// This peel's layer and depth (compute pipeline, group 1, after the vertex stage's bindings).
@group(1) @binding(3) var dp_layer: texture_2d<u32>;
@group(1) @binding(4) var dp_layer_depth: texture_depth_2d;

@fragment
fn dp_peel_fs(in: HwOut, @builtin(front_facing) front: bool) -> @location(0) vec2<u32> {
    if (hw_dropped(in, front)) {
        discard;
    }
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    let depth = clamp(in.position.z, 0.0, 1.0);
    if (fu.pass_index > 0u) {
        let previous = clamp(textureLoad(dp_previous, vec2<i32>(xy), 0), 0.0, 1.0);
        if (depth <= previous) {
            discard;
        }
    }
    var f: Fragment;
    f.pixel = xy.y * fu.width + xy.x;
    f.depth = depth;
    f.prim = in.prim;
    f.color = clamp(
        hw_color(in),
        vec4<f32>(0.0),
        vec4<f32>(1.0),
    );
    f.normal = normalize_or_zero(in.normal);
    return vec2<u32>(payload(f, fu.effect), 1u);
}

// Composites this peel's layer under the layers before (one invocation per pixel).
@compute @workgroup_size(64)
fn dp_composite_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = vec2<i32>(i32(px % fu.width), i32(px / fu.width));
    let layer = textureLoad(dp_layer, xy, 0).xy;
    if (layer.y == 0u) {
        return;
    }
    let depth = clamp(textureLoad(dp_layer_depth, xy, 0), 0.0, 1.0);
    push(px, depth, layer.x);
}
