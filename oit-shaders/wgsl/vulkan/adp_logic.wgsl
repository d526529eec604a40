// module adp_logic (stage): technique/adp.wgsl vulkan/adp_logic.wgsl
// adp's histogram pass as the HPG 2009 paper builds it (Liu et al., section 3.3): the 1024 bins
// of a pixel's depth range are 1024 bits in 8 R32G32B32A32_UINT colour targets, and each fragment
// sets its bin's bit through the logic op OR (which replaces blending on every attachment: a
// pipeline of its own). A kernel then copies the targets into the storage histogram
// (adp.wgsl's `hist`, word w = target w / 4, channel w % 4), so the equalization, the bucket
// passes and the resolves are the storage capture's own.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE, adp.wgsl (group 0: bounds, hist...), this, then the
// hardware raster's vertex stage (group 1 bindings 0..4) and `hw_dropped` (blend_stage.wgsl: what
// the opaque pass holds back sets no bin, as in the storage capture). The copy kernel reads the
// targets as group 1 bindings 3..10, which only the compute pipeline's layout has.

@group(1) @binding(3) var adp_hist0: texture_2d<u32>;
@group(1) @binding(4) var adp_hist1: texture_2d<u32>;
@group(1) @binding(5) var adp_hist2: texture_2d<u32>;
@group(1) @binding(6) var adp_hist3: texture_2d<u32>;
@group(1) @binding(7) var adp_hist4: texture_2d<u32>;
@group(1) @binding(8) var adp_hist5: texture_2d<u32>;
@group(1) @binding(9) var adp_hist6: texture_2d<u32>;
@group(1) @binding(10) var adp_hist7: texture_2d<u32>;

struct AdpHistOut {
    @location(0) t0: vec4<u32>,
    @location(1) t1: vec4<u32>,
    @location(2) t2: vec4<u32>,
    @location(3) t3: vec4<u32>,
    @location(4) t4: vec4<u32>,
    @location(5) t5: vec4<u32>,
    @location(6) t6: vec4<u32>,
    @location(7) t7: vec4<u32>,
}

// The fragment's bin bit in its word's channel, 0 (a no-op under OR) everywhere else.
@fragment
fn adp_hist_fs(in: HwOut, @builtin(front_facing) front: bool) -> AdpHistOut {
    if (hw_dropped(in, front)) {
        discard;
    }
    var out: AdpHistOut;
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return out;
    }
    let px = xy.y * fu.width + xy.x;
    let zn = bitcast<f32>(bounds[2u * px]);
    let zf = bitcast<f32>(bounds[2u * px + 1u]);
    // the clamped depth the storage capture bins (capture_render.wgsl's `f.depth`)
    let bin = histogram_bin(clamp(in.position.z, 0.0, 1.0), zn, zf);
    var lanes = vec4<u32>(0u);
    lanes[(bin / 32u) % 4u] = 1u << (bin % 32u);
    switch (bin / 128u) {
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

// Target t's texel at xy.
fn adp_hist_texel(t: u32, xy: vec2<i32>) -> vec4<u32> {
    switch (t) {
        case 0u: { return textureLoad(adp_hist0, xy, 0); }
        case 1u: { return textureLoad(adp_hist1, xy, 0); }
        case 2u: { return textureLoad(adp_hist2, xy, 0); }
        case 3u: { return textureLoad(adp_hist3, xy, 0); }
        case 4u: { return textureLoad(adp_hist4, xy, 0); }
        case 5u: { return textureLoad(adp_hist5, xy, 0); }
        case 6u: { return textureLoad(adp_hist6, xy, 0); }
        default: { return textureLoad(adp_hist7, xy, 0); }
    }
}

// The targets into the storage histogram, one invocation per pixel.
@compute @workgroup_size(64)
fn adp_hist_copy_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = vec2<i32>(i32(px % fu.width), i32(px / fu.width));
    for (var t = 0u; t < 8u; t++) {
        let v = adp_hist_texel(t, xy);
        for (var c = 0u; c < 4u; c++) {
            atomicStore(&hist[px * HISTOGRAM_WORDS + 4u * t + c], v[c]);
        }
    }
}
