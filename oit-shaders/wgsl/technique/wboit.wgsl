// module wboit (raster): technique/wboit_table.wgsl technique/wboit.wgsl
// wboit: weighted blended OIT (McGuire & Bavoil, JCGT 2013), as oit-cpu's `technique/wboit.rs`:
// one geometry pass adds, per pixel, Σα·w·r, Σα·w·g, Σα·w·b, Σα·w (w: the depth weight of the
// paper's eq. 10 in hundredths, `wboit_weight`), the optical depth Σ−ln(1 − α) (in 1/65536, from
// the table below: the paper's revealage Π(1 − α) as a sum) and the count, as u64 integers of the
// RGBA8 colour, so the sums do not depend on arrival order; the composite kernel writes the final
// linear colour into the resolve state (front colour, zero transmittance, captured = count).
@group(0) @binding(2) var<storage, read_write> wb_sums: array<atomic<u64>>;


// oit_core::technique::wboit::wboit_weight: max(1, 300000·q³/1023³) with q = 1023 − ⌊d·1024⌋
fn wboit_weight(depth: f32) -> u64 {
    let d = min(bitcast<f32>(depth_bits(depth)), 1.0);
    let q = u64(1023u - min(u32(d * 1024.0), 1023u));
    return max(300000lu * q * q * q / 1070599167lu, 1lu);
}

fn capture(f: Fragment) {
    let c = pack_rgba8(f.color);
    let a = c >> 24u;
    let aw = u64(a) * wboit_weight(f.depth);
    let base = f.pixel * 6u;
    atomicAdd(&wb_sums[base], aw * u64(c & 0xffu));
    atomicAdd(&wb_sums[base + 1u], aw * u64((c >> 8u) & 0xffu));
    atomicAdd(&wb_sums[base + 2u], aw * u64((c >> 16u) & 0xffu));
    atomicAdd(&wb_sums[base + 3u], aw);
    atomicAdd(&wb_sums[base + 4u], u64(WBOIT_OPTICAL_DEPTH[a]));
    atomicAdd(&wb_sums[base + 5u], 1lu);
}

// oit_core::technique::wboit::wboit: the weighted mean colour under the exact coverage
@compute @workgroup_size(64)
fn composite_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let base = px * 6u;
    let count = u32(atomicLoad(&wb_sums[base + 5u]));
    let weight = f32(atomicLoad(&wb_sums[base + 3u]));
    let bg = background_at(px);
    var c = bg;
    if (count > 0u && weight > 0.0) {
        let weighted = vec3<f32>(
            f32(atomicLoad(&wb_sums[base])),
            f32(atomicLoad(&wb_sums[base + 1u])),
            f32(atomicLoad(&wb_sums[base + 2u])),
        );
        let mean = weighted / (weight * 255.0);
        let t = exp(-(f32(atomicLoad(&wb_sums[base + 4u])) / 65536.0));
        c = mean * (1.0 - t) + bg * t;
    }
    state_composited(px, c, count);
}
