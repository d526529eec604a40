// the same optical depths as wboit's
// module mboit (raster): technique/wboit_table.wgsl technique/mboit.wgsl
// mboit:M: moment-based OIT (Münstermann et al., HPG 2018) with M = fu.param = 4 or 6 power
// moments, as oit-cpu's `technique/mboit.rs`. Pass 0 adds each pixel's optical depth Σa
// (a = −ln(1 − α), wboit.wgsl's table) and the moments Σa·zᵏ of the warped depth z (k = 1..M, the
// powers in units of 2⁻²⁰, two's complement in u64); pass 1 weighs each fragment by the transmittance in front of it that the
// moments bound, in 16 bits, and adds Σ T·α·c, Σ T·α and the count. All integers: the sums do not
// depend on arrival order. The composite kernel writes the final linear colour into the resolve
// state (front colour, zero transmittance, captured = count).
@group(0) @binding(2) var<storage, read_write> mb_sums: array<atomic<u64>>;

// a pixel's words besides its M moments: Σa, then Σ T·α·r, g, b, Σ T·α and the count
const MBOIT_OTHER_WORDS: u32 = 6u;
const MBOIT_BIAS: f32 = 5e-6;
const MBOIT6_BIAS: f32 = 5e-5;
const MBOIT_OVERESTIMATION: f32 = 0.25;

// oit_core::technique::mboit::mboit_depth (fu.lens.x, fu.lens.y: near, far)
fn mboit_depth(depth: f32) -> f32 {
    let d = min(bitcast<f32>(depth_bits(depth)), 1.0);
    let r = fu.lens.x / fu.lens.y;
    if (!(r > 0.0 && r < 0.999999)) {
        return 2.0 * d - 1.0;
    }
    return clamp(2.0 * log(1.0 - d * (1.0 - r)) / log(r) - 1.0, -1.0, 1.0);
}

// oit_core::technique::mboit::mboit_powers: the power in units of 2⁻²⁰, half away from zero
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

// oit_core::technique::mboit::mboit_share_in_front: the share of the optical depth in front of z that
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

// oit_core::composite's cubic_roots: the roots of c.x + c.y·x + c.z·x² + c.w·x³, the one of
// largest magnitude last (Viète's trigonometric form for it, scaled against overflow; then the
// quadratic left once it is divided out, in the cancellation-free form)
fn mboit_cubic_roots(c: vec4<f32>) -> vec3<f32> {
    let a0 = mboit_div(c.z, c.w);
    let b0 = mboit_div(c.y, c.w);
    let e0 = mboit_div(c.x, c.w);
    let s = max(max(abs(a0), sqrt(abs(b0))), pow(max(abs(e0), 1e-30), 1.0 / 3.0));
    let a = a0 / s;
    let b = b0 / s / s;
    let e = e0 / s / s / s;
    let p = min(b - a * a / 3.0, 0.0);
    let q = a * (2.0 * a * a - 9.0 * b) / 27.0 + e;
    let rho = sqrt(-p / 3.0);
    var cos_phi = 0.0;
    if (rho > 0.0) {
        cos_phi = clamp(-q / (2.0 * rho * rho * rho), -1.0, 1.0);
    }
    let third = acos(cos_phi) / 3.0;
    let hi = 2.0 * rho * cos(third) - a / 3.0;
    // 2π/3: the smallest of the three t (the largest is at angle `third`)
    let lo = 2.0 * rho * cos(third + 2.0943951) - a / 3.0;
    // one Newton step: this device's acos and cos may be off by 2⁻¹¹
    var u = select(lo, hi, abs(hi) >= abs(lo));
    let slope = (3.0 * u + 2.0 * a) * u + b;
    let step = ((u + a) * u + b) * u + e;
    if (abs(slope) > 1e-3) {
        u = u - step / slope;
    }
    let r = s * u;
    var k2 = c.w;
    var k1 = c.z + r * c.w;
    var k0 = c.y + r * k1;
    if (abs(r) > 1.0) {
        k1 = c.y + c.x / r;
        k2 = c.z + k1 / r;
        k0 = c.x;
    }
    let disc = max(k1 * k1 - 4.0 * k2 * k0, 0.0);
    let h = -0.5 * (k1 + select(sqrt(disc), -sqrt(disc), k1 < 0.0));
    return vec3<f32>(mboit_div(k0, h), mboit_div(h, k2), r);
}

// oit_core::technique::mboit::mboit6_share_in_front: the share of the optical depth in front of z that
// six normalized moments (m0 = z¹..z⁴, m1 = z⁵, z⁶) bound (see there)
fn mboit6_share_in_front(m0: vec4<f32>, m1: vec2<f32>, z: f32) -> f32 {
    // the bias towards (0, 7/16, 0, 19/64, 0, 67/256)
    let b0 = m0 * (1.0 - MBOIT6_BIAS) + vec4<f32>(0.0, 0.4375, 0.0, 0.296875) * MBOIT6_BIAS;
    let b1 = m1 * (1.0 - MBOIT6_BIAS) + vec2<f32>(0.0, 0.26171875) * MBOIT6_BIAS;
    // the 4×4 Hankel matrix as L·D·Lᵀ
    let d1 = b0.y - b0.x * b0.x;
    let l21 = mboit_div(b0.z - b0.y * b0.x, d1);
    let l31 = mboit_div(b0.w - b0.z * b0.x, d1);
    let d2 = b0.w - b0.y * b0.y - l21 * l21 * d1;
    let l32 = mboit_div(b1.x - b0.z * b0.y - l31 * l21 * d1, d2);
    let d3 = b1.y - b0.z * b0.z - l31 * l31 * d1 - l32 * l32 * d2;
    // H·c = (1, z, z², z³)
    let y1 = z - b0.x;
    let y2 = z * z - b0.y - l21 * y1;
    let y3 = z * z * z - b0.z - l31 * y1 - l32 * y2;
    let c3 = mboit_div(y3, d3);
    let c2 = mboit_div(y2, d2) - l32 * c3;
    let c1 = mboit_div(y1, d1) - l21 * c2 - l31 * c3;
    let c0 = 1.0 - b0.x * c1 - b0.y * c2 - b0.z * c3;
    let x = mboit_cubic_roots(vec4<f32>(c0, c1, c2, c3));
    // the cubic through (z, η) and the roots' indicators, by divided differences
    let f0 = MBOIT_OVERESTIMATION;
    let f1 = select(0.0, 1.0, x.x < z);
    let f2 = select(0.0, 1.0, x.y < z);
    let f3 = select(0.0, 1.0, x.z < z);
    let f01 = mboit_div(f1 - f0, x.x - z);
    let f12 = mboit_div(f2 - f1, x.y - x.x);
    let f23 = mboit_div(f3 - f2, x.z - x.y);
    let f012 = mboit_div(f12 - f01, x.y - z);
    let f123 = mboit_div(f23 - f12, x.z - x.x);
    let f0123 = mboit_div(f123 - f012, x.z - z);
    // its expectation under the moments
    let e1 = b0.x - z;
    let e2 = b0.y - (z + x.x) * b0.x + z * x.x;
    let e3 = b0.z - (z + x.x + x.y) * b0.y + (z * x.x + z * x.y + x.x * x.y) * b0.x - z * x.x * x.y;
    return clamp(f0 + f01 * e1 + f012 * e2 + f0123 * e3, 0.0, 1.0);
}

fn capture(f: Fragment) {
    let c = pack_rgba8(f.color);
    let alpha = c >> 24u;
    let a = WBOIT_OPTICAL_DEPTH[alpha];
    let moments = fu.param;
    let base = f.pixel * (moments + MBOIT_OTHER_WORDS);
    let z = mboit_depth(f.depth);
    if (fu.pass_index == 0u) {
        atomicAdd(&mb_sums[base], u64(a));
        // oit_core::technique::mboit::mboit_powers: each power from the same two factors
        let z2 = z * z;
        let z3 = z2 * z;
        let z4 = z2 * z2;
        atomicAdd(&mb_sums[base + 1u], bitcast<u64>(i64(a) * mboit_power(z)));
        atomicAdd(&mb_sums[base + 2u], bitcast<u64>(i64(a) * mboit_power(z2)));
        atomicAdd(&mb_sums[base + 3u], bitcast<u64>(i64(a) * mboit_power(z3)));
        atomicAdd(&mb_sums[base + 4u], bitcast<u64>(i64(a) * mboit_power(z4)));
        if (moments == 6u) {
            atomicAdd(&mb_sums[base + 5u], bitcast<u64>(i64(a) * mboit_power(z4 * z)));
            atomicAdd(&mb_sums[base + 6u], bitcast<u64>(i64(a) * mboit_power(z3 * z3)));
        }
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
        var share = 0.0;
        if (moments == 6u) {
            let m56 = vec2<f32>(
                f32(bitcast<i64>(atomicLoad(&mb_sums[base + 5u]))) / b0 / 1048576.0,
                f32(bitcast<i64>(atomicLoad(&mb_sums[base + 6u]))) / b0 / 1048576.0,
            );
            share = mboit6_share_in_front(m, m56, z);
        } else {
            share = mboit_share_in_front(m, z);
        }
        t = exp(-(b0 / 65536.0) * share);
    }
    // oit_core::technique::mboit::mboit_weight16
    let w = u64(clamp(t, 0.0, 1.0) * 65536.0 + 0.5);
    let wa = w * u64(alpha);
    let sums = base + moments + 1u;
    atomicAdd(&mb_sums[sums], wa * u64(c & 0xffu));
    atomicAdd(&mb_sums[sums + 1u], wa * u64((c >> 8u) & 0xffu));
    atomicAdd(&mb_sums[sums + 2u], wa * u64((c >> 16u) & 0xffu));
    atomicAdd(&mb_sums[sums + 3u], wa);
    atomicAdd(&mb_sums[sums + 4u], 1lu);
}

// oit_core::technique::mboit::mboit
@compute @workgroup_size(64)
fn composite_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let base = px * (fu.param + MBOIT_OTHER_WORDS);
    let sums = base + fu.param + 1u;
    let count = u32(atomicLoad(&mb_sums[sums + 4u]));
    let bg = background_at(px);
    var c = bg;
    if (count > 0u) {
        let t = exp(-(f32(atomicLoad(&mb_sums[base])) / 65536.0));
        let weight = f32(atomicLoad(&mb_sums[sums + 3u]));
        var mean = vec3<f32>(0.0);
        if (weight > 0.0) {
            mean = vec3<f32>(
                f32(atomicLoad(&mb_sums[sums])),
                f32(atomicLoad(&mb_sums[sums + 1u])),
                f32(atomicLoad(&mb_sums[sums + 2u])),
            ) / (weight * 255.0);
        }
        c = mean * (1.0 - t) + bg * t;
    }
    state_composited(px, c, count);
}
