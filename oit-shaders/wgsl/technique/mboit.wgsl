// mboit: moment-based OIT (Münstermann et al., HPG 2018) with four power moments, as oit-cpu's
// `technique/mboit.rs`. Pass 0 adds each pixel's optical depth Σa (a = −ln(1 − α), wboit.wgsl's
// table) and the moments Σa·zᵏ of the warped depth z (k = 1..4, the powers in units of 2⁻²⁰, two's
// complement in u64); pass 1 weighs each fragment by the transmittance in front of it that the
// moments bound, in 16 bits, and adds Σ T·α·c, Σ T·α and the count. All integers: the sums do not
// depend on arrival order. The composite kernel writes the final linear colour into the resolve
// state (front colour, zero transmittance, captured = count).
@group(0) @binding(2) var<storage, read_write> mb_sums: array<atomic<u64>>;

const MBOIT_WORDS: u32 = 10u;
const MBOIT_BIAS: f32 = 5e-6;
const MBOIT_OVERESTIMATION: f32 = 0.25;

// oit_core::rules::mboit_depth (fu.lens.x, fu.lens.y: near, far)
fn mboit_depth(depth: f32) -> f32 {
    let d = min(bitcast<f32>(depth_bits(depth)), 1.0);
    let r = fu.lens.x / fu.lens.y;
    if (!(r > 0.0 && r < 0.999999)) {
        return 2.0 * d - 1.0;
    }
    return clamp(2.0 * log(1.0 - d * (1.0 - r)) / log(r) - 1.0, -1.0, 1.0);
}

// oit_core::rules::mboit_powers: the power in units of 2⁻²⁰, half away from zero
fn mboit_power(p: f32) -> i64 {
    let v = p * 1048576.0;
    return i64(floor(abs(v) + 0.5) * sign(v));
}

// oit_core::composite's safe_div
fn mboit_div(a: f32, b: f32) -> f32 {
    var d = b;
    if (abs(b) < 1e-12) {
        d = select(1e-12, -1e-12, b < 0.0);
    }
    return a / d;
}

// oit_core::composite::mboit_share_in_front: the share of the optical depth in front of z that
// the four normalized moments m bound (see there)
fn mboit_share_in_front(m: vec4<f32>, z: f32) -> f32 {
    let b = m * (1.0 - MBOIT_BIAS) + vec4<f32>(0.0, 0.375, 0.0, 0.375) * MBOIT_BIAS;
    let d1 = b.y - b.x * b.x;
    let l = mboit_div(b.z - b.x * b.y, d1);
    let d2 = (b.w - b.y * b.y) - l * (b.z - b.x * b.y);
    let y1 = z - b.x;
    let y2 = z * z - b.y - l * y1;
    let c2 = mboit_div(y2, d2);
    let c1 = mboit_div(y1, d1) - l * c2;
    let c0 = 1.0 - b.x * c1 - b.y * c2;
    let half_p = mboit_div(c1, c2) * 0.5;
    let q = mboit_div(c0, c2);
    let root = sqrt(max(half_p * half_p - q, 0.0));
    let z1 = -half_p - root;
    let z2 = -half_p + root;
    let f0 = MBOIT_OVERESTIMATION;
    let f1 = select(0.0, 1.0, z1 < z);
    let f2 = select(0.0, 1.0, z2 < z);
    let f01 = mboit_div(f1 - f0, z1 - z);
    let f12 = mboit_div(f2 - f1, z2 - z1);
    let f012 = mboit_div(f12 - f01, z2 - z);
    let a2 = f012;
    let a1 = f01 - f012 * (z + z1);
    let a0 = f0 - f01 * z + f012 * z * z1;
    return clamp(a0 + a1 * b.x + a2 * b.y, 0.0, 1.0);
}

fn capture(f: Fragment) {
    let c = pack_rgba8(f.color);
    let alpha = c >> 24u;
    let a = WBOIT_OPTICAL_DEPTH[alpha];
    let base = f.pixel * MBOIT_WORDS;
    let z = mboit_depth(f.depth);
    if (fu.pass_index == 0u) {
        atomicAdd(&mb_sums[base], u64(a));
        let z2 = z * z;
        let z3 = z2 * z;
        let z4 = z2 * z2;
        atomicAdd(&mb_sums[base + 1u], bitcast<u64>(i64(a) * mboit_power(z)));
        atomicAdd(&mb_sums[base + 2u], bitcast<u64>(i64(a) * mboit_power(z2)));
        atomicAdd(&mb_sums[base + 3u], bitcast<u64>(i64(a) * mboit_power(z3)));
        atomicAdd(&mb_sums[base + 4u], bitcast<u64>(i64(a) * mboit_power(z4)));
        return;
    }
    // the transmittance in front of the fragment (oit-cpu's `transmittance`)
    let total = atomicLoad(&mb_sums[base]);
    var t = 1.0;
    if (total != 0lu) {
        let b0 = f32(total);
        let m = vec4<f32>(
            f32(bitcast<i64>(atomicLoad(&mb_sums[base + 1u]))) / b0 / 1048576.0,
            f32(bitcast<i64>(atomicLoad(&mb_sums[base + 2u]))) / b0 / 1048576.0,
            f32(bitcast<i64>(atomicLoad(&mb_sums[base + 3u]))) / b0 / 1048576.0,
            f32(bitcast<i64>(atomicLoad(&mb_sums[base + 4u]))) / b0 / 1048576.0,
        );
        t = exp(-(b0 / 65536.0) * mboit_share_in_front(m, z));
    }
    // oit_core::rules::mboit_weight16
    let w = u64(clamp(t, 0.0, 1.0) * 65536.0 + 0.5);
    let wa = w * u64(alpha);
    atomicAdd(&mb_sums[base + 5u], wa * u64(c & 0xffu));
    atomicAdd(&mb_sums[base + 6u], wa * u64((c >> 8u) & 0xffu));
    atomicAdd(&mb_sums[base + 7u], wa * u64((c >> 16u) & 0xffu));
    atomicAdd(&mb_sums[base + 8u], wa);
    atomicAdd(&mb_sums[base + 9u], 1lu);
}

// oit_core::composite::mboit
@compute @workgroup_size(64)
fn composite_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let base = px * MBOIT_WORDS;
    let count = u32(atomicLoad(&mb_sums[base + 9u]));
    let bg = background_at(px);
    var c = bg;
    if (count > 0u) {
        let t = exp(-(f32(atomicLoad(&mb_sums[base])) / 65536.0));
        let weight = f32(atomicLoad(&mb_sums[base + 8u]));
        var mean = vec3<f32>(0.0);
        if (weight > 0.0) {
            mean = vec3<f32>(
                f32(atomicLoad(&mb_sums[base + 5u])),
                f32(atomicLoad(&mb_sums[base + 6u])),
                f32(atomicLoad(&mb_sums[base + 7u])),
            ) / (weight * 255.0);
        }
        c = mean * (1.0 - t) + bg * t;
    }
    state_composited(px, c, count);
}
