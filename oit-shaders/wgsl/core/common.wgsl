// The rules of oit-core (crates/oit-core/src/rules.rs, composite.rs, settings.rs), in WGSL.
// Function for function the same definitions; `tests/rules.rs` runs both on edge values.

const BDP_DEPTH_SUBINTERVALS: u32 = 16u;
const BDP_COLOR_SUBINTERVALS: u32 = 32u;
const BUCKETS: u32 = 32u;
const HISTOGRAM_BINS: u32 = 1024u;
const HISTOGRAM_WORDS: u32 = 32u;

// Depth as an order-preserving u32: the bits of the depth clamped to [0, 1] (NaN -> 1, -0 -> 0).
fn depth_bits(d: f32) -> u32 {
    let bits = bitcast<u32>(d);
    // NaN: exponent all ones and a mantissa
    if ((bits & 0x7f800000u) == 0x7f800000u && (bits & 0x007fffffu) != 0u) {
        return 0x3f800000u;
    }
    if ((bits & 0x80000000u) != 0u) {
        return 0u; // negative, -0 included
    }
    return min(bits, 0x3f800000u);
}

fn pack_rgba8(c: vec4<f32>) -> u32 {
    let q = vec4<u32>(clamp(c, vec4<f32>(0.0), vec4<f32>(1.0)) * 255.0 + 0.5);
    return q.x | (q.y << 8u) | (q.z << 16u) | (q.w << 24u);
}

fn unpack_rgba8(p: u32) -> vec4<f32> {
    return vec4<f32>(f32(p & 0xffu), f32((p >> 8u) & 0xffu), f32((p >> 16u) & 0xffu), f32(p >> 24u)) / 255.0;
}

// floor(n·(d − zNear)/(zFar − zNear)) clamped to 0..n; an empty range puts everything in 0.
fn bucket_index(d: f32, z_near: f32, z_far: f32, n: u32) -> u32 {
    let range = z_far - z_near;
    if (!(range > 0.0) || !(abs(d) <= 3.4e38)) {
        return 0u;
    }
    let k = floor((d - z_near) / range * f32(n));
    if (k <= 0.0) {
        return 0u;
    }
    return min(u32(k), n - 1u);
}

// oit_core::rules::bucket_midpoint: the depth bdp's colour mode gives bucket k of n.
fn bucket_midpoint(k: u32, n: u32, z_near: f32, z_far: f32) -> f32 {
    return z_near + (f32(k) + 0.5) / f32(n) * (z_far - z_near);
}

const BDP_EMPTY_MIN: u64 = 0xfffffffffffffffflu;

// oit_core::rules::bdp_eq5_next: HPG 2009's eq. 5, strictly between the previous pass's min and max.
fn bdp_eq5_next(d: u32, lo: u64, hi: u64) -> bool {
    return lo != BDP_EMPTY_MIN && d > u32(lo >> 32u) && d < u32(hi >> 32u);
}

fn histogram_bin(d: f32, z_near: f32, z_far: f32) -> u32 {
    return bucket_index(d, z_near, z_far, HISTOGRAM_BINS);
}

fn bdp_pack_color(rgba8: u32) -> u32 {
    let a = rgba8 >> 24u;
    let a7 = (a * 127u + 127u) / 255u;
    return (a7 << 24u) | (rgba8 & 0x00ffffffu);
}

fn bdp_unpack_color(packed: u32) -> u32 {
    let a7 = (packed >> 24u) & 0x7fu;
    let a = (a7 * 255u + 63u) / 127u;
    return (a << 24u) | (packed & 0x00ffffffu);
}

fn mdts_depth20(d: f32) -> u32 {
    let dd = bitcast<f32>(depth_bits(d));
    let remapped = min(0.5 + 0.5 * dd, bitcast<f32>(0x3f7fffffu));
    return (bitcast<u32>(remapped) << 9u) & 0xfffff000u;
}

fn mdts_pack(d: f32, rgba8: u32) -> vec2<u32> {
    let depth = mdts_depth20(d);
    let rgb = rgba8 & 0x00ffffffu;
    return vec2<u32>(depth | (rgb >> 12u), depth | (rgb & 0xfffu));
}

// (depth, rgb) from the two words of an mdts slot
fn mdts_unpack(words: vec2<u32>) -> vec2<u32> {
    let mantissa = words.x >> 12u;
    let remapped = bitcast<f32>(0x3f000000u | (mantissa << 3u));
    let d = (remapped - 0.5) * 2.0;
    let rgb = ((words.x & 0xfffu) << 12u) | (words.y & 0xfffu);
    return vec2<u32>(bitcast<u32>(d), rgb);
}

fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

fn pack_normal(n_in: vec3<f32>) -> u32 {
    var n = n_in;
    let len = length(n);
    if (!(len > 0.0)) {
        n = vec3<f32>(0.0, 0.0, 1.0);
    } else {
        n = n / len;
    }
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    var p = n.xy / l1;
    if (n.z < 0.0) {
        p = (vec2<f32>(1.0) - abs(p.yx)) * sign_not_zero(p);
    }
    let q = vec2<u32>((clamp(p, vec2<f32>(-1.0), vec2<f32>(1.0)) * 0.5 + 0.5) * 65535.0 + 0.5);
    return q.x | (q.y << 16u);
}

fn unpack_normal(p: u32) -> vec3<f32> {
    let f = vec2<f32>(f32(p & 0xffffu), f32(p >> 16u)) / 65535.0 * 2.0 - 1.0;
    var n = vec3<f32>(f.x, f.y, 1.0 - abs(f.x) - abs(f.y));
    if (n.z < 0.0) {
        let o = n.xy;
        n = vec3<f32>((vec2<f32>(1.0) - abs(o.yx)) * sign_not_zero(o), n.z);
    }
    return normalize(n);
}

// Shading modes, as oit_core::Shading.
const SHADING_HEADLIGHT: u32 = 0u;
const SHADING_FLAT: u32 = 1u;
const SHADING_VERTEX: u32 = 2u;
const SHADING_NORMAL: u32 = 3u;

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if (l > 0.0 && l <= 3.4e38) {
        return v * (1.0 / l);
    }
    return vec3<f32>(0.0);
}

fn shade(mode: u32, base: vec4<f32>, normal: vec3<f32>, vertex_color: vec3<f32>, has_color: bool, forward: vec3<f32>) -> vec4<f32> {
    let n = normalize_or_zero(normal);
    var rgb = base.xyz;
    if (mode == SHADING_HEADLIGHT) {
        rgb = base.xyz * (0.3 + 0.7 * abs(dot(n, forward)));
    } else if (mode == SHADING_VERTEX && has_color) {
        rgb = vertex_color;
    } else if (mode == SHADING_NORMAL) {
        rgb = n * 0.5 + vec3<f32>(0.5);
    }
    return vec4<f32>(clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0)), clamp(base.w, 0.0, 1.0));
}

fn linear_to_srgb8(x_in: f32) -> u32 {
    var x = x_in;
    if (!(x >= 0.0)) {
        x = 0.0;
    }
    x = min(x, 1.0);
    var s: f32;
    if (x <= 0.0031308) {
        s = 12.92 * x;
    } else {
        s = 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    }
    return u32(s * 255.0 + 0.5);
}

fn schlick_transmittance(cos_theta: f32) -> f32 {
    let c = min(abs(cos_theta), 1.0);
    let m = 1.0 - c;
    return 1.0 - m * m * m * m * m;
}

// f32::powi as Rust's compiler-builtins computes it (square and multiply), n ≥ 0: the weighted
// average's transmittance (1 − mean α)^n, in wavg's composite and the overflow tail's resolve.
fn powi_rust(x_in: f32, n_in: u32) -> f32 {
    var x = x_in;
    var n = n_in;
    var r = 1.0;
    loop {
        if ((n & 1u) != 0u) {
            r *= x;
        }
        n = n >> 1u;
        if (n == 0u) {
            break;
        }
        x *= x;
    }
    return r;
}
