// The image of a recorded frame (one sRGB8 RGBA word a pixel, red in the low byte) drawn into the
// caller's target: a triangle over the viewport, each fragment its pixel's word. A `…Srgb` target
// encodes what it is given, so `blit_srgb_fs` gives it the decoded value, and the target stores
// the same bytes as a `…Unorm` one.
@group(0) @binding(0) var<uniform> blit_size: vec4<u32>;
@group(0) @binding(1) var<storage, read> blit_image: array<u32>;

@vertex
fn blit_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn blit_texel(p: vec4<f32>) -> vec4<f32> {
    let x = min(u32(p.x), blit_size.x - 1u);
    let y = min(u32(p.y), blit_size.y - 1u);
    return unpack4x8unorm(blit_image[y * blit_size.x + x]);
}

@fragment
fn blit_fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return blit_texel(p);
}

fn blit_decode(c: f32) -> f32 {
    if (c <= 0.04045) {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

@fragment
fn blit_srgb_fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = blit_texel(p);
    return vec4<f32>(blit_decode(c.r), blit_decode(c.g), blit_decode(c.b), c.a);
}
