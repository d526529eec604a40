// Coverage masks of multisampled frames (`fu.msaa.x` samples a pixel above 1; docs/msaa.md), as
// oit-cpu's `technique/msaa.rs` keeps them: a byte an entry beside the entry's key and payload
// (an entry is one fragment whatever its mask), four to a word of `masks`, and the per-sample
// resolve. Appended to the modules that keep masks (reference, dfb, ll, fabs), which declare
// `masks: array<atomic<u32>>` and say how their entries are reached: `entry_key(e)`,
// `entry_payload(e)`, and `entry_next(e)`, the entry after `e` in a pixel's sorted list.
//
// A byte is written with atomics (its word holds other entries' bytes, which other invocations
// write at the same time): cleared, then set.

// Entry e's mask.
fn mask_at(e: u32) -> u32 {
    return (atomicLoad(&masks[e >> 2u]) >> (8u * (e & 3u))) & 0xffu;
}

// Sets the mask of entry e, whose byte is still 0 (each entry of a frame is written once, into
// zeroed words), to `m`.
fn mask_new(e: u32, m: u32) {
    atomicOr(&masks[e >> 2u], (m & 0xffu) << (8u * (e & 3u)));
}

// Sets entry e's mask to `m`.
fn mask_put(e: u32, m: u32) {
    let shift = 8u * (e & 3u);
    atomicAnd(&masks[e >> 2u], ~(0xffu << shift));
    atomicOr(&masks[e >> 2u], (m & 0xffu) << shift);
}

// The mask a capture keeps of `f`: its own, or every sample under `--coverage pixel` (the
// per-pixel capture baseline).
fn kept_mask(f: Fragment) -> u32 {
    return f.mask | (fu.msaa.y & 0xffu);
}

// Exchanges the masks of entries a and b (an in-place sort moving entries; nothing at one
// sample, where no mask is kept).
fn mask_swap(a: u32, b: u32) {
    if (fu.msaa.x > 1u) {
        let m = mask_at(a);
        mask_put(a, mask_at(b));
        mask_put(b, m);
    }
}

// The linear colour of the entries among pixel `px`'s n sorted entries from `first` whose masks
// share a bit with `bits`, composited over `bg` from a fresh state.
fn composite_covering(first: u32, n: u32, bits: u32, bg: vec3<f32>) -> vec3<f32> {
    var t: PixelState;
    var e = first;
    for (var i = 0u; i < n; i++) {
        if ((mask_at(e) & bits) != 0u) {
            push_local(&t, bitcast<f32>(u32(entry_key(e) >> 32u)), entry_payload(e));
        }
        e = entry_next(e);
    }
    return finish_over(t, bg);
}

// The per-sample resolve of pixel `px`'s n entries, sorted by key, from `first` (oit-cpu's
// `resolve_entries`): where every entry covers every sample and every sample holds the same
// opaque key (`opaque_uniform`) the pixel composites once; else each sample composites the entries
// that cover it over its own opaque colour or the background (`background_at_sample`), and the
// pixel is the mean of its samples. The colour goes into the state as resolved (`state_resolved`), with n
// captured and no ties counted (as oit-cpu's).
fn resolve_masked(px: u32, first: u32, n: u32) {
    resolve_masked_over(px, first, n, vec4<f32>(0.0, 0.0, 0.0, 1.0));
}

// What sample `j` of pixel `px` composites over: the layer `back` (xyz premultiplied colour, w
// transmittance: fabs's one tail a pixel, `tail_layer`; (0, 0, 0, 1) for none) over the sample's
// own opaque colour (the background where none covers it, or in a frame without an opaque part):
// oit-cpu's `Resolve::tail_over` of `background_at_sample`.
fn masked_background(px: u32, j: u32, back: vec4<f32>) -> vec3<f32> {
    return back.xyz + background_at_sample(px, j) * back.w;
}

// `resolve_masked` with every sample composited over the layer `back` (fabs's tail, where it has
// one) put over the sample's own colour (`masked_background`).
fn resolve_masked_over(px: u32, first: u32, n: u32, back: vec4<f32>) {
    let samples = fu.msaa.x;
    let full = (1u << samples) - 1u;
    var all = full;
    var e = first;
    for (var i = 0u; i < n; i++) {
        all &= mask_at(e);
        e = entry_next(e);
    }
    var s = load_state(px);
    s.captured = n;
    if (fu.effect != EFFECT_COMPLEXITY) {
        var c: vec3<f32>;
        if (all == full && opaque_uniform(px)) {
            c = composite_covering(first, n, full, masked_background(px, 0u, back));
        } else {
            // each sample over its own opaque colour (the background where none covers it)
            var sum = vec3<f32>(0.0);
            for (var j = 0u; j < samples; j++) {
                sum += composite_covering(first, n, 1u << j, masked_background(px, j, back));
            }
            // 4 or 8 samples: exact, as oit-cpu's division
            c = sum * (1.0 / f32(samples));
        }
        state_resolved(&s, c);
    }
    store_state(px, s);
}
