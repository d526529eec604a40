// bdp's colour mode through the graphics pipeline (Liu et al., HPG 2009, section 3.2): one
// geometry pass, each fragment's packed colour (bdp_pack_color) written as float bits to the
// channel of its subinterval, MAX-blended into 8 Rgba32Float targets (32 buckets = 8 × 4), then a
// compute resolve reads the targets back as u32 and pushes the non-empty buckets in order, as
// bdp.wgsl's `color_resolve_main` does with the storage buckets.
//
// Float MAX equals the integer MAX of the storage path for packed values that are positive,
// finite, normal floats (or zero): the sign bit is clear by construction, and positive floats
// order as their bits. The exponent bits are 30..23 = alpha7 (7 bits) and the top bit of blue, so
// - alpha7 = 127 (alpha ≥ 254) with blue ≥ 128: exponent all ones, an Inf (blue = 128, red =
//   green = 0) or a NaN: MAX blending of NaNs is undefined (a NaN may win or lose, or be
//   canonicalized), so such a bucket may differ from the storage path's;
// - alpha7 = 0 (alpha ≤ 1) with blue < 128: a denormal, which a blend unit may flush to zero (the
//   bucket then looks empty, its fragment lost).
// Other values compare exactly as their bits.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE (group 0: fu, state), this, then the hardware raster's
// vertex stage (group 1 bindings 0..4: hw_vertices, hw_indices, hw, hw_instances, hw_tex;
// `HwOut`, `hw_vs`, `hw_color`) and `hw_dropped` (blend_stage.wgsl: what the opaque pass holds
// back reaches no bucket).

// [zNear, zFar] bits per pixel (bounds.wgsl), read by the fragment stage.
@group(0) @binding(2) var<storage, read_write> bounds: array<u32>;

// The 8 targets, read by the resolve (group 1 of the compute pipeline; bindings after the vertex
// stage's, which the compute pipeline does not use).
@group(1) @binding(3) var bucket0: texture_2d<f32>;
@group(1) @binding(4) var bucket1: texture_2d<f32>;
@group(1) @binding(5) var bucket2: texture_2d<f32>;
@group(1) @binding(6) var bucket3: texture_2d<f32>;
@group(1) @binding(7) var bucket4: texture_2d<f32>;
@group(1) @binding(8) var bucket5: texture_2d<f32>;
@group(1) @binding(9) var bucket6: texture_2d<f32>;
@group(1) @binding(10) var bucket7: texture_2d<f32>;

struct BucketsOut {
    @location(0) t0: vec4<f32>,
    @location(1) t1: vec4<f32>,
    @location(2) t2: vec4<f32>,
    @location(3) t3: vec4<f32>,
    @location(4) t4: vec4<f32>,
    @location(5) t5: vec4<f32>,
    @location(6) t6: vec4<f32>,
    @location(7) t7: vec4<f32>,
}

// Shades like raster_hardware.wgsl's `hw_fs`, then writes the packed colour to its bucket's
// channel and 0 (a no-op under MAX: every stored value is ≥ +0) everywhere else.
@fragment
fn bdp_blend_fs(in: HwOut, @builtin(front_facing) front: bool) -> BucketsOut {
    if (hw_dropped(in, front)) {
        discard;
    }
    var out: BucketsOut;
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return out;
    }
    let px = xy.y * fu.width + xy.x;
    let color = hw_color(in);
    let depth = clamp(in.position.z, 0.0, 1.0);
    let zn = bitcast<f32>(bounds[2u * px]);
    let zf = bitcast<f32>(bounds[2u * px + 1u]);
    let k = bucket_index(depth, zn, zf, BDP_COLOR_SUBINTERVALS);
    let packed = bdp_pack_color(pack_rgba8(clamp(color, vec4<f32>(0.0), vec4<f32>(1.0))));
    var lanes = vec4<f32>(0.0);
    lanes[k % 4u] = bitcast<f32>(packed);
    switch (k / 4u) {
        case 0u: { out.t0 = lanes; }
        case 1u: { out.t1 = lanes; }
        case 2u: { out.t2 = lanes; }
        case 3u: { out.t3 = lanes; }
        case 4u: { out.t4 = lanes; }
        case 5u: { out.t5 = lanes; }
        case 6u: { out.t6 = lanes; }
        default: { out.t7 = lanes; }
    }
    return out;
}

// Bucket k of the pixel at xy, as the u32 the storage path would hold.
fn bdp_blend_bucket(k: u32, xy: vec2<i32>) -> u32 {
    var v: vec4<f32>;
    switch (k / 4u) {
        case 0u: { v = textureLoad(bucket0, xy, 0); }
        case 1u: { v = textureLoad(bucket1, xy, 0); }
        case 2u: { v = textureLoad(bucket2, xy, 0); }
        case 3u: { v = textureLoad(bucket3, xy, 0); }
        case 4u: { v = textureLoad(bucket4, xy, 0); }
        case 5u: { v = textureLoad(bucket5, xy, 0); }
        case 6u: { v = textureLoad(bucket6, xy, 0); }
        default: { v = textureLoad(bucket7, xy, 0); }
    }
    return bitcast<u32>(v[k % 4u]);
}

// The resolve: non-empty buckets in order, each at its subinterval's midpoint (as bdp.wgsl).
@compute @workgroup_size(64)
fn bdp_blend_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    var s = state[px];
    let xy = vec2<i32>(i32(px % fu.width), i32(px / fu.width));
    let zn = bitcast<f32>(bounds[2u * px]);
    let zf = bitcast<f32>(bounds[2u * px + 1u]);
    let n = BDP_COLOR_SUBINTERVALS;
    for (var k = 0u; k < n; k++) {
        let v = bdp_blend_bucket(k, xy);
        if (v != 0u) {
            let d = zn + (f32(k) + 0.5) / f32(n) * (zf - zn);
            push_local(&s, d, bdp_unpack_color(v));
        }
    }
    state[px] = s;
}
