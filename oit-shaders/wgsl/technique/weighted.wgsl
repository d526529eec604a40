// module weighted (raster): technique/weighted.wgsl
// wavg and wsum (Bavoil & Myers 2008; Meshkin 2007), as oit-cpu's `technique/weighted.rs`: one
// geometry pass adds, per pixel, Σα·r, Σα·g, Σα·b (in units of 1/255²), Σα (in units of 1/255) and
// the count, as u64 integers of the RGBA8 colour, so the sums do not depend on arrival order; the
// composite kernel writes the final linear colour into the resolve state (front colour, zero
// transmittance, captured = count) for the common finish. param bit 0: 1 = weighted average, 0 = sum (bit 1:
// blend.wgsl's RGBA16F units).
@group(0) @binding(2) var<storage, read_write> sums: array<atomic<u64>>;

fn capture(f: Fragment) {
    let c = pack_rgba8(f.color);
    let a = u64(c >> 24u);
    let base = f.pixel * 5u;
    atomicAdd(&sums[base], a * u64(c & 0xffu));
    atomicAdd(&sums[base + 1u], a * u64((c >> 8u) & 0xffu));
    atomicAdd(&sums[base + 2u], a * u64((c >> 16u) & 0xffu));
    atomicAdd(&sums[base + 3u], a);
    atomicAdd(&sums[base + 4u], 1lu);
}

@compute @workgroup_size(64)
fn composite_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let base = px * 5u;
    let premultiplied = vec3<f32>(
        f32(atomicLoad(&sums[base])),
        f32(atomicLoad(&sums[base + 1u])),
        f32(atomicLoad(&sums[base + 2u])),
    ) / (255.0 * 255.0);
    let alpha = f32(atomicLoad(&sums[base + 3u])) / 255.0;
    weighted_composite(px, premultiplied, alpha, u32(atomicLoad(&sums[base + 4u])));
}

// The composite of a pixel's sums (premultiplied colour, alpha), into its resolve state; shared
// with the blend capture (blend.wgsl).
fn weighted_composite(px: u32, premultiplied: vec3<f32>, alpha: f32, count: u32) {
    let bg = background_at(px);
    var c: vec3<f32>;
    if ((fu.param & 1u) == 1u) {
        // composite::weighted_average
        if (count == 0u || alpha <= 0.0) {
            c = bg;
        } else {
            let mean_color = premultiplied / alpha;
            let mean_alpha = min(alpha / f32(count), 1.0);
            let t = powi_rust(1.0 - mean_alpha, count);
            c = mean_color * (1.0 - t) + bg * t;
        }
    } else {
        // composite::weighted_sum
        c = clamp(premultiplied + bg * (1.0 - alpha), vec3<f32>(0.0), vec3<f32>(1.0));
    }
    state_composited(px, c, count);
}
