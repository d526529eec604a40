// Base-colour textures on the GPU: oit-core's sampler (oit-core/src/texture.rs) in WGSL, the same
// integers and the same two float operations, so a fragment's sample is the CPU's bit for bit
// given the same texture coordinates and level. A rasterizer that includes this file defines
// `tex_word(i)`, the `i`-th word of the buffer its textures are packed in (oit-gpu's
// `TextureRegion`): the compute rasterizer's triangle buffer, the hardware raster's `hw_tex`.
//
// The packing (oit-gpu's `TextureRegion::words`), from the region's first word `tables`:
// `tables + 0..256` sRGB code -> linear (f32 bits, `oit_core::texture::srgb_to_linear`),
// `tables + 256..512` code / 255 (f32 bits, the alpha decode: a table rather than a division,
// which a GPU need not round correctly); then per texture and level a descriptor of 4 words
// [first texel word, width, height, wrap_u | wrap_v << 8] (wrap: 0 repeat, 1 mirrored repeat,
// 2 clamp to edge); then the texels, one word each, r | g << 8 | b << 16 | a << 24. A fragment
// names its level's descriptor by its word offset (0: untextured).

const WRAP_REPEAT: u32 = 0u;
const WRAP_MIRRORED: u32 = 1u;
// oit_core::texture::COORD_CLAMP
const TEX_COORD_CLAMP: f32 = 1073741824.0;

// Wrap::apply: texel index `i` of a level `n` texels wide, wrapped into 0..n.
fn tex_wrap(i: i32, n: i32, mode: u32) -> u32 {
    if (mode == WRAP_REPEAT) {
        return u32(((i % n) + n) % n);
    }
    if (mode == WRAP_MIRRORED) {
        let m = ((i % (2 * n)) + 2 * n) % (2 * n);
        return u32(select(2 * n - 1 - m, m, m < n));
    }
    return u32(clamp(i, 0, n - 1));
}

// texture.rs's `axis`: the two texels (wrapped) and the right one's weight in 1/256.
fn tex_axis(u: f32, n: u32, mode: u32) -> vec3<u32> {
    var s = floor(u * f32(n * 256u));
    // NaN (which validation keeps out) maps to 0, as Rust's `as` does
    if (s != s) {
        s = 0.0;
    }
    let si = i32(clamp(s, -TEX_COORD_CLAMP, TEX_COORD_CLAMP)) - 128;
    let i0 = si >> 8u;
    return vec3<u32>(tex_wrap(i0, i32(n), mode), tex_wrap(i0 + 1, i32(n), mode), u32(si & 255));
}

fn tex_texel(first: u32, width: u32, x: u32, y: u32) -> vec4<u32> {
    let w = tex_word(first + y * width + x);
    return vec4<u32>(w & 0xffu, (w >> 8u) & 0xffu, (w >> 16u) & 0xffu, w >> 24u);
}

// Texture::sample: the level whose descriptor is at `desc`, at `uv`, decoded through the tables at
// `tables` (linear RGB, alpha).
fn tex_sample(tables: u32, desc: u32, uv: vec2<f32>) -> vec4<f32> {
    let first = tex_word(desc);
    let width = tex_word(desc + 1u);
    let height = tex_word(desc + 2u);
    let wrap = tex_word(desc + 3u);
    let ax = tex_axis(uv.x, width, wrap & 0xffu);
    let ay = tex_axis(uv.y, height, wrap >> 8u);
    let t00 = tex_texel(first, width, ax.x, ay.x);
    let t10 = tex_texel(first, width, ax.y, ay.x);
    let t01 = tex_texel(first, width, ax.x, ay.y);
    let t11 = tex_texel(first, width, ax.y, ay.y);
    let fx = ax.z;
    let fy = ay.z;
    let top = t00 * (256u - fx) + t10 * fx;
    let bottom = t01 * (256u - fx) + t11 * fx;
    let v = (top * (256u - fy) + bottom * fy + vec4<u32>(32768u)) >> vec4<u32>(16u);
    return vec4<f32>(
        bitcast<f32>(tex_word(tables + v.x)),
        bitcast<f32>(tex_word(tables + v.y)),
        bitcast<f32>(tex_word(tables + v.z)),
        bitcast<f32>(tex_word(tables + 256u + v.w)),
    );
}
