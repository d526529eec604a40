// module bdp_blend (stage): technique/bdp_blend.wgsl
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
// The same targets multisampled (`fu.msaa.x` samples a pixel): `bdp_blend_ms_fs` and its resolve.
@group(1) @binding(11) var bucket0_ms: texture_multisampled_2d<f32>;
@group(1) @binding(12) var bucket1_ms: texture_multisampled_2d<f32>;
@group(1) @binding(13) var bucket2_ms: texture_multisampled_2d<f32>;
@group(1) @binding(14) var bucket3_ms: texture_multisampled_2d<f32>;
@group(1) @binding(15) var bucket4_ms: texture_multisampled_2d<f32>;
@group(1) @binding(16) var bucket5_ms: texture_multisampled_2d<f32>;
@group(1) @binding(17) var bucket6_ms: texture_multisampled_2d<f32>;
@group(1) @binding(18) var bucket7_ms: texture_multisampled_2d<f32>;

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
    let packed = bdp_pack_color(pack_rgba8(clamp(hw_color(in), vec4<f32>(0.0), vec4<f32>(1.0))));
    return bdp_blend_lanes(in, xy, packed);
}

// The 8 targets' outputs of a fragment at `xy` whose packed colour is `packed`: its bucket's
// channel holds it, every other 0.
fn bdp_blend_lanes(in: HwOut, xy: vec2<u32>, packed: u32) -> BucketsOut {
    var out: BucketsOut;
    let px = xy.y * fu.width + xy.x;
    let depth = clamp(in.position.z, 0.0, 1.0);
    let zn = bitcast<f32>(bounds[2u * px]);
    let zf = bitcast<f32>(bounds[2u * px + 1u]);
    let k = bucket_index(depth, zn, zf, BDP_COLOR_SUBINTERVALS);
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

struct BucketsMsOut {
    @location(0) t0: vec4<f32>,
    @location(1) t1: vec4<f32>,
    @location(2) t2: vec4<f32>,
    @location(3) t3: vec4<f32>,
    @location(4) t4: vec4<f32>,
    @location(5) t5: vec4<f32>,
    @location(6) t6: vec4<f32>,
    @location(7) t7: vec4<f32>,
    @builtin(sample_mask) written: u32,
}

// At several samples a pixel (docs/msaa.md): the fragment's samples less those the opaque pass
// holds back (`hw_kept`), its colour weighted as the atomics capture's (`hw_blend_packed`: full
// alpha unless `--coverage fraction`), written at its first kept sample only; the resolve takes
// the MAX of each bucket over the samples, which is the one target's MAX over the fragments.
@fragment
fn bdp_blend_ms_fs(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) covered: u32) -> BucketsMsOut {
    let kept = hw_kept(in, front, covered);
    if (kept == 0u) {
        discard;
    }
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    let o = bdp_blend_lanes(in, xy, bdp_pack_color(hw_blend_packed(in, kept)));
    return BucketsMsOut(o.t0, o.t1, o.t2, o.t3, o.t4, o.t5, o.t6, o.t7, first_sample(kept));
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
    let xy = vec2<i32>(i32(px % fu.width), i32(px / fu.width));
    var s = load_state(px);
    for (var k = 0u; k < BDP_COLOR_SUBINTERVALS; k++) {
        bdp_blend_push(&s, px, k, bdp_blend_bucket(k, xy));
    }
    store_state(px, s);
}

// Bucket k of the pixel at xy in the multisampled targets: the largest over its samples (as u32,
// which orders the packed colours as float MAX does: bdp_blend.wgsl's header).
fn bdp_blend_bucket_ms(k: u32, xy: vec2<i32>) -> u32 {
    var m = 0u;
    for (var i = 0u; i < fu.msaa.x; i++) {
        var v: vec4<f32>;
        switch (k / 4u) {
            case 0u: { v = textureLoad(bucket0_ms, xy, i32(i)); }
            case 1u: { v = textureLoad(bucket1_ms, xy, i32(i)); }
            case 2u: { v = textureLoad(bucket2_ms, xy, i32(i)); }
            case 3u: { v = textureLoad(bucket3_ms, xy, i32(i)); }
            case 4u: { v = textureLoad(bucket4_ms, xy, i32(i)); }
            case 5u: { v = textureLoad(bucket5_ms, xy, i32(i)); }
            case 6u: { v = textureLoad(bucket6_ms, xy, i32(i)); }
            default: { v = textureLoad(bucket7_ms, xy, i32(i)); }
        }
        m = max(m, bitcast<u32>(v[k % 4u]));
    }
    return m;
}

// `bdp_blend_resolve_main` over the multisampled targets.
@compute @workgroup_size(64)
fn bdp_blend_ms_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = vec2<i32>(i32(px % fu.width), i32(px / fu.width));
    var s = load_state(px);
    for (var k = 0u; k < BDP_COLOR_SUBINTERVALS; k++) {
        bdp_blend_push(&s, px, k, bdp_blend_bucket_ms(k, xy));
    }
    store_state(px, s);
}

// Pushes bucket k of pixel px, whose word is `v`, at its subinterval's midpoint, unless it is
// empty. (The resolves read each bucket as they push it: gathered first into a private array,
// they cost every pixel that array's zero initializer; short_list.wgsl says why.)
fn bdp_blend_push(s: ptr<function, PixelState>, px: u32, k: u32, v: u32) {
    if (v != 0u) {
        let zn = bitcast<f32>(bounds[2u * px]);
        let zf = bitcast<f32>(bounds[2u * px + 1u]);
        let n = f32(BDP_COLOR_SUBINTERVALS);
        push_local(s, zn + (f32(k) + 0.5) / n * (zf - zn), bdp_unpack_color(v));
    }
}
