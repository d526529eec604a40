// The per-sample accumulators of the peels that composite per sample (dp_samples.wgsl,
// ddp_samples.wgsl; oit-cpu's `SampleAccumulators` in technique/msaa.rs; docs/msaa.md): `halves`
// (1 for dp, 2 for ddp) vec4 a sample, sample i of pixel px at (px · samples + i) · halves, each
// (RGB, transmittance) from (0, 1): the front composited nearest first (premultiplied colour under
// what is in front), ddp's back farthest first, kept without what lies behind it, so sample i
// finishes to front.rgb + front.t · (back.rgb + back.t · behind(i)). Fresnel multiplies the
// transmittances only; the heat map counts layers a pixel (the state's `captured`).
@group(0) @binding(5) var<storage, read_write> acc: array<vec4<f32>>;

// A fragment's key in the per-sample peels (oit-core's `msaa::peel_key`): depth bits, primitive
// id, and the lowest sample of its coverage mask, which tells apart two pieces of one clipped
// triangle on one pixel (they share the id and the depth, never a sample).
fn peel_key(f: Fragment) -> u64 {
    return (u64(depth_bits(f.depth)) << 32u) | (u64(f.prim) << 3u) | u64(countTrailingZeros(f.mask) & 7u);
}

// Every sample's accumulators of pixel px set to (0, 0, 0, 1): before its first layer.
fn accumulators_init(px: u32, halves: u32) {
    let n = fu.msaa.x * halves;
    for (var i = 0u; i < n; i++) {
        acc[px * n + i] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
}

// Composites one layer (its payload, its coverage mask) into the covered samples' front (half 0,
// nearest first) or back (half 1, farthest first) of pixel px; counts it in the state.
fn accumulate(px: u32, halves: u32, payload: u32, mask: u32, half: u32) {
    var s = load_state(px);
    s.captured += 1u;
    store_state(px, s);
    accumulate_samples(px, halves, payload, mask, half);
}

// `accumulate` without the count: the samples of `mask` only (dp_depth_samples.wgsl composites
// each sample's own layer, a fragment counted once at the lowest sample it keeps).
fn accumulate_samples(px: u32, halves: u32, payload: u32, mask: u32, half: u32) {
    var c = vec4<f32>(0.0);
    var factor = 1.0;
    if (fu.effect == EFFECT_TRANSPARENCY) {
        c = unpack_rgba8(payload);
        factor = 1.0 - c.w;
    } else if (fu.effect == EFFECT_FRESNEL) {
        factor = schlick_transmittance(dot(unpack_normal(payload), fu.forward.xyz));
    } else {
        return;
    }
    let n = fu.msaa.x;
    for (var i = 0u; i < n; i++) {
        if (((mask >> i) & 1u) == 0u) {
            continue;
        }
        let at = (px * n + i) * halves + half;
        let a = acc[at];
        var rgb = a.xyz;
        if (fu.effect == EFFECT_TRANSPARENCY) {
            if (half == 1u) {
                rgb = c.w * c.xyz + (1.0 - c.w) * rgb;
            } else {
                rgb = rgb + a.w * c.w * c.xyz;
            }
        }
        acc[at] = vec4<f32>(rgb, a.w * factor);
    }
}

// After pixel px's last layer: its colour, each sample finished over what lies behind it (its
// opaque colour, or the background), summed in sample order, times 1/N, into the state as
// resolved; a pixel that captured nothing (or the heat map) is left to `finish_color`.
fn accumulated(px: u32, halves: u32) {
    var s = load_state(px);
    if (s.captured == 0u || fu.effect == EFFECT_COMPLEXITY) {
        return;
    }
    let n = fu.msaa.x;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        let at = (px * n + i) * halves;
        let behind = background_at_sample(px, i);
        var back = behind;
        if (halves == 2u) {
            let b = acc[at + 1u];
            back = b.xyz + b.w * behind;
        }
        let f = acc[at];
        sum += f.xyz + f.w * back;
    }
    state_resolved(&s, sum * (1.0 / f32(n)));
    store_state(px, s);
}
