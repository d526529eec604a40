// the blend captures: fragment stages of their own after the hardware raster's vertex stage (each drops first what `hw_dropped`, core/blend_stage.wgsl, drops)
// module blend (stage): technique/weighted.wgsl technique/blend.wgsl
// plain, wavg and wsum through the blend unit (hardware path): one draw of oit's scene vertex
// stage into two float targets, then a compute resolve reading them into the resolve state, as
// the storage captures leave it (front colour, transmittance, captured), for the common finish.
//
// Target 0 (`blend_color`) and target 1 (`blend_count`, additive: the fragments of each pixel).
// Colours go through pack_rgba8 first, as every capture's payload does, so the blender gets the
// same 8-bit colours as oit-cpu's resolve.
// - plain: target 0 holds (premultiplied colour, transmittance), cleared to (0, 0, 0, 1); colour
//   blended One, OneMinusSrcAlpha (the over operator) and alpha Zero, OneMinusSrcAlpha (the product
//   of 1 − α), in the blender's primitive order: the highest primitive on top.
// - wavg / wsum: target 0 holds (Σα·r, Σα·g, Σα·b, Σα) in units of 1/255² and 1/255 (integers),
//   additive, as the atomics capture's u64 sums (weighted.wgsl); integer-valued floats add exactly
//   while a sum stays below 2^24, i.e. up to 258 layers of full-alpha white at one pixel, so the
//   blend equals the atomics capture there, in any summation order (see technique/blend.rs).
//   With `--blend-target f16` (param bit 1) the target is RGBA16F and holds (Σα·r, Σα·g, Σα·b, Σα)
//   in [0, 1] units instead, each addition rounded to f16, as weighted blended OIT accumulates.
//
// Module: COMMON_WGSL, TECHNIQUE_PRELUDE (group 0: fu, state), this, then the hardware raster's
// vertex stage (group 1 bindings 0..4; `HwOut`, `hw_vs`, `hw_color`) and `hw_dropped`
// (blend_stage.wgsl: back faces and what the opaque pass holds back are dropped unwritten, so
// neither target sees them). The resolve's targets are group 1 bindings 8 and 9 of the compute
// pipeline, clear of the vertex stage's.

@group(1) @binding(8) var blend_color: texture_2d<f32>;
@group(1) @binding(9) var blend_count: texture_2d<f32>;
// The same targets multisampled (`fu.msaa.x` samples a pixel): the `_ms` entry points below.
@group(1) @binding(10) var blend_color_ms: texture_multisampled_2d<f32>;
@group(1) @binding(11) var blend_count_ms: texture_multisampled_2d<f32>;

struct BlendOut {
    @location(0) color: vec4<f32>,
    @location(1) count: vec4<f32>,
}

// The fragment's 8-bit colour (pack_rgba8, unpacked), or none outside the image.
fn blend_fragment(in: HwOut, out: ptr<function, BlendOut>) -> vec4<f32> {
    let xy = vec2<u32>(max(floor(in.position.xy), vec2<f32>(0.0)));
    if (xy.x >= fu.width || xy.y >= fu.height) {
        return vec4<f32>(0.0);
    }
    (*out).count = vec4<f32>(1.0, 0.0, 0.0, 0.0);
    let color = hw_color(in);
    return unpack_rgba8(pack_rgba8(clamp(color, vec4<f32>(0.0), vec4<f32>(1.0))));
}

@fragment
fn plain_blend_fs(in: HwOut, @builtin(front_facing) front: bool) -> BlendOut {
    if (hw_dropped(in, front)) {
        discard;
    }
    var out: BlendOut;
    let c = blend_fragment(in, &out);
    out.color = vec4<f32>(c.xyz * c.w, c.w);
    return out;
}

@fragment
fn weighted_blend_fs(in: HwOut, @builtin(front_facing) front: bool) -> BlendOut {
    if (hw_dropped(in, front)) {
        discard;
    }
    var out: BlendOut;
    let c = blend_fragment(in, &out);
    if ((fu.param & 2u) != 0u) {
        // RGBA16F (--blend-target f16): α·r and α in [0, 1], as weighted blended OIT adds them
        out.color = vec4<f32>(c.xyz * c.w, c.w);
    } else {
        // the 8-bit integers themselves: a·r in units of 1/255², a in units of 1/255
        let q = round(c * 255.0);
        out.color = vec4<f32>(q.xyz * q.w, q.w);
    }
    return out;
}

fn blend_texel(px: u32) -> vec2<i32> {
    return vec2<i32>(i32(px % fu.width), i32(px / fu.width));
}

@compute @workgroup_size(64)
fn plain_blend_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = blend_texel(px);
    let c = textureLoad(blend_color, xy, 0);
    var s = load_state(px);
    s.fr = c.x;
    s.fg = c.y;
    s.fb = c.z;
    s.transmittance_x = one_xor(c.w);
    s.captured = u32(textureLoad(blend_count, xy, 0).x + 0.5);
    store_state(px, s);
}

@compute @workgroup_size(64)
fn weighted_blend_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = blend_texel(px);
    let sums = textureLoad(blend_color, xy, 0);
    let count = u32(textureLoad(blend_count, xy, 0).x + 0.5);
    if ((fu.param & 2u) != 0u) {
        weighted_composite(px, sums.xyz, sums.w, count);
    } else {
        weighted_composite(px, sums.xyz / (255.0 * 255.0), sums.w / 255.0, count);
    }
}

// At several samples a pixel (docs/msaa.md, "The blend captures at several samples"): one draw
// into multisampled targets, each fragment given the samples it covers less those the opaque pass
// holds back (`hw_kept`).

struct BlendMsOut {
    @location(0) color: vec4<f32>,
    @location(1) count: vec4<f32>,
    @builtin(sample_mask) written: u32,
}

// A fragment's count at each sample it writes where it writes `k` of them: 1/k of a fragment, in
// units of 1/840 (840 is divisible by every k from 1 to 8, so each addend is an integer and the
// sums are exact in f32 up to 2^24 / 840, about 19,900 fragments a pixel).
const PLAIN_COUNT_UNIT: f32 = 840.0;

// plain per sample: the blender composites each sample's fragments in primitive order, each at
// its full alpha (not weighted by its coverage: the samples it misses are its coverage) at every
// sample it keeps (the MSAA colour buffer); the resolve takes the mean of the samples. A
// fragment's count is split over the samples it writes (PLAIN_COUNT_UNIT).
@fragment
fn plain_blend_ms_fs(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) covered: u32) -> BlendMsOut {
    let kept = hw_kept(in, front, covered);
    if (kept == 0u) {
        discard;
    }
    var out: BlendMsOut;
    out.written = kept;
    let c = unpack_rgba8(pack_rgba8(clamp(hw_color(in), vec4<f32>(0.0), vec4<f32>(1.0))));
    out.color = vec4<f32>(c.xyz * c.w, c.w);
    out.count = vec4<f32>(PLAIN_COUNT_UNIT / f32(countOneBits(kept)), 0.0, 0.0, 0.0);
    return out;
}

// wavg and wsum at several samples: the fragment's sums (its alpha weighted by the coverage of
// the samples it keeps, as the atomics captures take it) and its count written at its first kept
// sample only, so that the samples' sums, added by the resolve, are the single target's: the
// same integers in another order (exact below 2^24, as one target's), or the same f16 addends.
@fragment
fn weighted_blend_ms_fs(in: HwOut, @builtin(front_facing) front: bool, @builtin(sample_mask) covered: u32) -> BlendMsOut {
    let kept = hw_kept(in, front, covered);
    if (kept == 0u) {
        discard;
    }
    var out: BlendMsOut;
    out.written = first_sample(kept);
    let c = hw_blend_color(in, kept);
    out.count = vec4<f32>(1.0, 0.0, 0.0, 0.0);
    if ((fu.param & 2u) != 0u) {
        out.color = vec4<f32>(c.xyz * c.w, c.w);
    } else {
        let q = round(c * 255.0);
        out.color = vec4<f32>(q.xyz * q.w, q.w);
    }
    return out;
}

// The mean of the pixel's samples' (premultiplied colour, transmittance): summed in sample order,
// then times 1/N (exact for 4 and 8), the mean of the samples' composites over one background.
// Over opaque objects (`fu.opaque.z`) each sample's composite is put over that sample's own opaque
// colour first (`background_at_sample`: C + T·B a sample, as the per-sample reference composites
// each sample over its own), and the pixel is the mean of those, composited (`state_resolved`);
// the composite is affine in what lies behind it, so where every sample holds one opaque colour
// this is the composite over the mean.
@compute @workgroup_size(64)
fn plain_blend_ms_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = blend_texel(px);
    var c = vec4<f32>(0.0);
    var over = vec3<f32>(0.0);
    var count = 0.0;
    for (var i = 0u; i < fu.msaa.x; i++) {
        let sample = textureLoad(blend_color_ms, xy, i32(i));
        c += sample;
        over += sample.xyz + sample.w * background_at_sample(px, i);
        count += textureLoad(blend_count_ms, xy, i32(i)).x;
    }
    let mean = 1.0 / f32(fu.msaa.x);
    c *= mean;
    var s = load_state(px);
    s.fr = c.x;
    s.fg = c.y;
    s.fb = c.z;
    s.transmittance_x = one_xor(c.w);
    s.captured = u32(count / PLAIN_COUNT_UNIT + 0.5);
    if (fu.opaque.z != 0u && s.captured != 0u && fu.effect == EFFECT_TRANSPARENCY) {
        state_resolved(&s, over * mean);
    }
    store_state(px, s);
}

// The weighted sums of the pixel's samples added up: each fragment wrote one sample.
@compute @workgroup_size(64)
fn weighted_blend_ms_resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let xy = blend_texel(px);
    var sums = vec4<f32>(0.0);
    var n = 0.0;
    for (var i = 0u; i < fu.msaa.x; i++) {
        sums += textureLoad(blend_color_ms, xy, i32(i));
        n += textureLoad(blend_count_ms, xy, i32(i)).x;
    }
    let count = u32(n + 0.5);
    if ((fu.param & 2u) != 0u) {
        weighted_composite(px, sums.xyz, sums.w, count);
    } else {
        weighted_composite(px, sums.xyz / (255.0 * 255.0), sums.w / 255.0, count);
    }
}
