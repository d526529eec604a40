// What a capture function receives: one fragment, after raster and shading.
struct Fragment {
    pixel: u32,
    depth: f32,
    prim: u32,
    color: vec4<f32>,
    normal: vec3<f32>,
    // the opaque pass discards the fragment where its alpha is under this (oit-core's
    // `Triangle::cutoff`: a textured masked object's cutoff; one half for an untextured one,
    // whose alpha is 1 or 0; 0 elsewhere); no other capture reads it
    cutoff: f32,
    // the samples of the pixel the fragment covers (bit i: sample i of oit-core's standard
    // pattern; `fu.msaa.x` samples a pixel), set by the compute rasterizer; read only by the
    // multisampled captures (the hardware path runs one sample and leaves it 0)
    mask: u32,
}

// Every technique's group 0, binding 0: what the pass needs to know.
struct FrameUniform {
    width: u32,
    height: u32,
    pass_index: u32,
    param: u32,
    effect: u32,
    pixel_count: u32,
    // 1: the resolve counts ties (the plan's `count_ties`)
    ties: u32,
    // 1 in the last capture pass the plan allows
    last_pass: u32,
    forward: vec4<f32>,
    background: vec4<f32>,
    // near, far, sigma / unit, unused
    lens: vec4<f32>,
    // the opaque pass: x 1 where this pass cuts its fragments at the opaque depth, y 1 where it
    // counts those it holds back (the frame's first scene pass), z 1 where the frame has an
    // opaque image (what its pixels composite over), w unused
    opaque: vec4<u32>,
    // multisampling (oit-gpu's `FrameUniform::msaa`): x samples a pixel, y the mask ORed into
    // every kept coverage mask (`--coverage pixel`) in its low byte and MSAA_FRACTION, z and w the sample positions, a byte each
    // (x | y << 4 in 1/16 pixel), samples 0-3 in z, 4-7 in w
    msaa: vec4<u32>,
}

// oit-gpu's `MSAA_FRACTION`: each fragment's alpha weighted by its coverage fraction.
const MSAA_FRACTION: u32 = 256u;

// `f` as a technique that keeps no coverage mask captures it above one sample (oit-core's
// `msaa::Coverage::Fraction`, `fu.msaa.y` holding MSAA_FRACTION): its alpha times the fraction
// of its pixel's samples its mask covers (oit-core's `msaa::fraction_alpha`: k/4 and k/8 exact,
// one rounding, the product's, as oit-cpu's); else `f` as it is. `msaa` and `opaque` are the
// frame uniform's. The passes of a frame with an opaque image that do not cut at it (`opaque.z`
// without `opaque.x`: the opaque pass, oit-gpu's `opaque_pass`, and the instances' bounding
// boxes) take `f` as it is: the opaque pass tests a fragment's own alpha against its cutoff
// and writes every sample it covers, as oit-cpu's `opaque::draw` (weighted, an opaque wall's edge
// fragment covering one sample of four would fall under the cutoff of one half an untextured
// object gets and be discarded).
fn coverage_weighted(f: Fragment, msaa: vec4<u32>, opaque: vec4<u32>) -> Fragment {
    var g = f;
    let opaque_pass = opaque.z != 0u && opaque.x == 0u;
    if ((msaa.y & MSAA_FRACTION) != 0u && !opaque_pass) {
        g.color.a = f.color.a * (f32(countOneBits(f.mask)) / f32(msaa.x));
    }
    return g;
}

const EFFECT_TRANSPARENCY: u32 = 0u;
const EFFECT_TRANSLUCENCY: u32 = 1u;
const EFFECT_FRESNEL: u32 = 2u;
const EFFECT_COMPLEXITY: u32 = 3u;

// The payload word a fragment carries for the effect: RGBA8, or the packed normal for Fresnel.
fn payload(f: Fragment, effect: u32) -> u32 {
    if (effect == EFFECT_FRESNEL) {
        return pack_normal(f.normal);
    }
    return pack_rgba8(f.color);
}
