// `--overflow tail` for fabs:K, mdts:K and mdts64:K, appended to fabs.wgsl and mdts.wgsl: oit-cpu's
// `Ctx::tail_pass` and `Resolve::tail`. The tail of multi-layer alpha blending (Salvi &
// Vaidyanathan 2014), kept as order-independent sums: a geometry pass adds every fragment behind
// its pixel's K-th nearest into u64 integer sums of its RGBA8 colour (Σα·r, Σα·g, Σα·b in units of
// 1/255², Σα in units of 1/255, the count; 64-bit atomicAdd, so the sums do not depend on arrival
// order), and moves it from `lost` (where the capture counted it, finding no room) to merged. The
// resolve puts the sums' weighted average (Bavoil & Myers 2008) behind the K sorted fragments, as
// dual depth peeling's back half. The technique binds the sums at 6 and two words at 7.
@group(0) @binding(6) var<storage, read_write> tail_sums: array<atomic<u64>>;
// [a pixel overflowed (mdts raises it in its capture), fragments merged in all (the resolve)]
@group(0) @binding(7) var<storage, read_write> tail_words: array<atomic<u32>>;

fn tail_add(px: u32, c: u32) {
    let a = u64(c >> 24u);
    let base = px * 5u;
    atomicAdd(&tail_sums[base], a * u64(c & 0xffu));
    atomicAdd(&tail_sums[base + 1u], a * u64((c >> 8u) & 0xffu));
    atomicAdd(&tail_sums[base + 2u], a * u64((c >> 16u) & 0xffu));
    atomicAdd(&tail_sums[base + 3u], a);
    atomicAdd(&tail_sums[base + 4u], 1lu);
    atomicSub(&acct[3u * px], 1u);
}

// The pixel's tail as a layer (composite::weighted_average): xyz its colour, premultiplied
// (the mean colour times 1 − t), w its transmittance t, so that the tail over a colour `bg` is
// xyz + bg · w; (0, 0, 0, 1) where it has none. Counts its fragments merged (call it once a pixel).
fn tail_layer(px: u32) -> vec4<f32> {
    let base = px * 5u;
    let count = u32(atomicLoad(&tail_sums[base + 4u]));
    if (count == 0u) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let premultiplied = vec3<f32>(
        f32(atomicLoad(&tail_sums[base])),
        f32(atomicLoad(&tail_sums[base + 1u])),
        f32(atomicLoad(&tail_sums[base + 2u])),
    ) / (255.0 * 255.0);
    let alpha = f32(atomicLoad(&tail_sums[base + 3u])) / 255.0;
    var layer = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    if (alpha > 0.0) {
        let mean_color = premultiplied / alpha;
        let mean_alpha = min(alpha / f32(count), 1.0);
        let t = powi_rust(1.0 - mean_alpha, count);
        layer = vec4<f32>(mean_color * (1.0 - t), t);
    }
    atomicAdd(&tail_words[1], count);
    return layer;
}

// The pixel's tail over `bg` (composite::weighted_average), or `bg` where it has none; counts its
// fragments merged (call it once a pixel).
fn tail_back(px: u32, bg: vec3<f32>) -> vec3<f32> {
    let layer = tail_layer(px);
    return layer.xyz + bg * layer.w;
}

// The pixel's tail behind what was pushed into `s` (composite::weighted_average over the
// background, as the back colour the front composites over); counts its fragments merged.
fn tail_resolve(s: ptr<function, PixelState>, px: u32) {
    if (u32(atomicLoad(&tail_sums[px * 5u + 4u])) == 0u) {
        return;
    }
    let back = tail_back(px, background_at(px));
    (*s).br = back.x;
    (*s).bg = back.y;
    (*s).bb = back.z;
    (*s).has_back = 1u;
}
