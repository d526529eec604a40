//! Moment-based OIT (Münstermann et al., HPG 2018), `mboit`: what every backend computes for it,
//! in one place. A first pass sums each pixel's optical depth and power moments of its log-warped
//! depths ([`mboit_depth`], [`mboit_powers`]; the optical depths are wboit's,
//! [`super::wboit::WBOIT_OPTICAL_DEPTH`]); a second weighs each fragment by the transmittance
//! that the moments bound in front of it ([`mboit_share_in_front`], [`mboit6_share_in_front`],
//! quantized by [`mboit_weight16`]); [`mboit`] composites the sums. oit-cpu's
//! `technique/mboit.rs` and oit-shaders' `technique/mboit.wgsl` compute the same.

use glam::Vec3;

/// The most triangles a scene `mboit` renders may have ([`crate::Sums::max_triangles`]): its i64
/// moment sums hold 2²² fragments a pixel, with four moments or six (every power of the warped
/// depth is at most 2²⁰ units, so z⁶'s sum needs no more headroom than z's). Why: |a·zᵏ| < 2⁴¹
/// a fragment (a < 2²¹, |zᵏ| ≤ 2²⁰ units), and 2²² of them stay under 2⁶³.
pub const MBOIT_MAX_TRIANGLES: u64 = 1 << 22;

/// Moment-based OIT's depth: the fragment's view distance on a log scale from the near plane
/// (−1) to the far one (+1), as the paper warps it so that moments resolve near and far alike:
/// 2·ln(z/near)/ln(far/near) − 1 with z = near/(1 − d(1 − near/far)) (oit_core's
/// `Camera::linear_depth`), which is 2·ln(1 − d(1 − r))/ln r − 1 for r = near/far. A camera
/// whose near and far planes meet (r ≥ 1 − 10⁻⁶) gets 2d − 1.
#[inline]
pub fn mboit_depth(d: f32, near_over_far: f32) -> f32 {
    let d = if d.is_nan() { 1.0 } else { d.clamp(0.0, 1.0) };
    let r = near_over_far;
    if !(r > 0.0 && r < 0.999_999) {
        return 2.0 * d - 1.0;
    }
    (2.0 * (1.0 - d * (1.0 - r)).ln() / r.ln() - 1.0).clamp(-1.0, 1.0)
}

/// Units of a power of [`mboit_depth`] in the moment sums: 2²⁰ (z^k ∈ [−1, 1] to ±2²⁰).
pub const MBOIT_POWER_UNIT: f32 = 1_048_576.0;

/// The warped depth's powers z, z², …, z⁶ in units of 2⁻²⁰ (rounded to nearest, half away from
/// zero): what a fragment adds to the moment sums, times its optical depth
/// ([`super::wboit::WBOIT_OPTICAL_DEPTH`]), in integers, so the sums do not depend on the order they are added
/// in (`mboit:4` adds the first four, `mboit:6` all six). The powers are products of f32s, never
/// fused, each from the same two factors on every backend (z⁵ = z⁴·z, z⁶ = z³·z³), so every
/// backend finds the same integers. As |z| ≤ 1, every power is at most 2²⁰ units whatever M is:
/// the sums' headroom ([`MBOIT_MAX_TRIANGLES`]) is the same for six moments as
/// for four.
#[inline]
pub fn mboit_powers(z: f32) -> [i64; 6] {
    let z2 = z * z;
    let z3 = z2 * z;
    let z4 = z2 * z2;
    let z5 = z4 * z;
    let z6 = z3 * z3;
    // v is exact (a power-of-two scale) and so are |v| + 0.5 and its floor for |v| ≤ 2²⁰: the
    // same integers wherever it runs (WGSL's `round` rounds half to even; this does not)
    [z, z2, z3, z4, z5, z6].map(|p| {
        let v = p * MBOIT_POWER_UNIT;
        ((v.abs() + 0.5).floor() * v.signum()) as i64
    })
}

/// Quantizes a fragment's transmittance T ∈ [0, 1] to 16 bits (units of 1/65536, round to
/// nearest): its weight in moment-based OIT's second pass.
#[inline]
pub fn mboit_weight16(t: f32) -> u64 {
    (t.clamp(0.0, 1.0) * 65536.0 + 0.5) as u64
}

/// The moment bias of `mboit` (the paper's β for four power moments, raised from its 5·10⁻⁷ for
/// 32-bit floats to cover our sums' 2⁻²⁰ steps): the normalized moments are moved this far
/// towards those of a canonical distribution, so that the Hankel matrix stays positive definite.
pub const MBOIT_BIAS: f32 = 5e-6;
/// The moments the bias moves towards: (0, 0.375, 0, 0.375), as in the paper.
pub const MBOIT_BIAS_TARGET: [f32; 4] = [0.0, 0.375, 0.0, 0.375];
/// The share of the optical depth at a fragment's own depth counted in front of it (the paper's
/// overestimation, 0.25: a bound between the lower (0) and upper (1) one, tilted towards
/// overestimating absorbance, which darkens less than underestimating it brightens).
pub const MBOIT_OVERESTIMATION: f32 = 0.25;

/// Divides by `b`, or by ±10⁻¹² where `b` is smaller: the bound's divided differences meet
/// coincident nodes when a root falls on the fragment's own depth.
#[inline]
fn safe_div(a: f32, b: f32) -> f32 {
    let b = if b.abs() < 1e-12 { if b < 0.0 { -1e-12 } else { 1e-12 } } else { b };
    a / b
}

/// The share, in [0, 1], of a pixel's optical depth that lies in front of warped depth `z`, bounded
/// from the pixel's four normalized power moments `m` (Σ a·zᵏ / Σ a), as moment-based OIT
/// estimates it (Münstermann et al. 2018, after Peters & Klein's moment shadow maps). Of all
/// distributions with these moments, the canonical one that has an atom at `z` has two more atoms,
/// at the roots of the quadratic that the Hankel matrix of the moments makes with (1, z, z²); the
/// estimate weighs the atoms in front of `z` fully and the one at `z` by
/// [`MBOIT_OVERESTIMATION`], and reads those weights off as the expectation, under the moments, of
/// the quadratic that interpolates the three indicator values.
pub fn mboit_share_in_front(m: [f32; 4], z: f32) -> f32 {
    // the bias: the moments of a slightly blurred distribution
    let b: [f32; 4] = std::array::from_fn(|i| m[i] * (1.0 - MBOIT_BIAS) + MBOIT_BIAS_TARGET[i] * MBOIT_BIAS);
    // B = [[1, b0, b1], [b0, b1, b2], [b1, b2, b3]] = L·D·Lᵀ with L = [[1, 0, 0], [b0, 1, 0],
    // [b1, l, 1]], D = diag(1, d1, d2)
    let d1 = b[1] - b[0] * b[0];
    let l = safe_div(b[2] - b[0] * b[1], d1);
    let d2 = (b[3] - b[1] * b[1]) - l * (b[2] - b[0] * b[1]);
    // B·c = (1, z, z²): forward (L), scale (D), back (Lᵀ)
    let y1 = z - b[0];
    let y2 = z * z - b[1] - l * y1;
    let c2 = safe_div(y2, d2);
    let c1 = safe_div(y1, d1) - l * c2;
    let c0 = 1.0 - b[0] * c1 - b[1] * c2;
    // the two other atoms: the roots of c0 + c1·x + c2·x²
    let half_p = safe_div(c1, c2) * 0.5;
    let q = safe_div(c0, c2);
    let root = (half_p * half_p - q).max(0.0).sqrt();
    let (z1, z2) = (-half_p - root, -half_p + root);
    // the quadratic through (z, η), (z1, [z1 < z]), (z2, [z2 < z]) by divided differences
    let f0 = MBOIT_OVERESTIMATION;
    let f1 = if z1 < z { 1.0 } else { 0.0 };
    let f2 = if z2 < z { 1.0 } else { 0.0 };
    let f01 = safe_div(f1 - f0, z1 - z);
    let f12 = safe_div(f2 - f1, z2 - z1);
    let f012 = safe_div(f12 - f01, z2 - z);
    // f0 + f01·(x − z) + f012·(x − z)(x − z1) = a0 + a1·x + a2·x²
    let a2 = f012;
    let a1 = f01 - f012 * (z + z1);
    let a0 = f0 - f01 * z + f012 * z * z1;
    (a0 + a1 * b[0] + a2 * b[1]).clamp(0.0, 1.0)
}

/// The moment bias of `mboit:6`, larger than [`MBOIT_BIAS`]: the 4×4 Hankel matrix of six moments
/// is far worse conditioned than the 3×3 one of four, and its last pivot must stay clear of the
/// f32 rounding of moments up to z⁶ (chosen by measurement: see `mboit6_bias_is_measured`).
pub const MBOIT6_BIAS: f32 = 5e-5;
/// The moments the six-moment bias moves towards: those of the symmetric distribution with 3/8 at
/// ±1/2 and 1/8 at ±1, (0, 7/16, 0, 19/64, 0, 67/256), exact in binary. Among symmetric
/// distributions on [−1, 1] this one (found by a search over two atom pairs) nearly maximizes
/// the smallest eigenvalue of its 4×4 Hankel matrix (0.04; the four-moment target's 3×3 has
/// 0.2), so a given bias lifts the biased matrix's smallest eigenvalue the most.
pub const MBOIT6_BIAS_TARGET: [f32; 6] = [0.0, 0.4375, 0.0, 0.296_875, 0.0, 0.261_718_75];

/// The three roots of c0 + c1·x + c2·x² + c3·x³, which has three real ones (see
/// [`mboit6_share_in_front`]), the one of largest magnitude last. Viète's trigonometric form
/// finds that one: the cubic made monic and scaled so that its coefficients are at most 1 (no
/// overflow when c3 nears zero and one root runs off to infinity), shifted to t³ + p·t + q, its
/// roots 2ρ·cos(φ/3 − 2πk/3) with ρ = √(−p/3), cos φ = −q/(2ρ³); of the largest and the smallest
/// t, the one farther from zero once shifted back (no cancellation: its relative error is a few
/// ulps), then polished by one Newton step (the trigonometric functions of a GPU are far less
/// exact than its arithmetic). Rounding that makes a near-double root look complex (p > 0 or
/// |cos φ| > 1) is clamped to the coincident root, the continuous limit. That root r is then divided out, from the
/// constant term up when |r| > 1 (as the factor 1 − x/r, so the quotient stays finite however
/// far r runs: dividing from the leading term, or solving the monic cubic for the other roots,
/// would lose them to cancellation against r), and the quadratic quotient k2·x² + k1·x + k0
/// solved in the cancellation-free form h = −(k1 + sign(k1)·√disc)/2, roots k0/h and h/k2.
macro_rules! cubic_roots {
    ($t:ident, $c0:expr, $c1:expr, $c2:expr, $c3:expr, $div:expr) => {{
        let (c0, c1, c2, c3): ($t, $t, $t, $t) = ($c0, $c1, $c2, $c3);
        let div = $div;
        let (a, b, c) = (div(c2, c3), div(c1, c3), div(c0, c3));
        let s = a.abs().max(b.abs().sqrt()).max(c.abs().max(1e-30).cbrt());
        let (a, b, c) = (a / s, b / s / s, c / s / s / s);
        let p = (b - a * a / 3.0).min(0.0);
        let q = a * (2.0 * a * a - 9.0 * b) / 27.0 + c;
        let rho = (-p / 3.0).sqrt();
        let cos_phi = if rho > 0.0 { (-q / (2.0 * rho * rho * rho)).clamp(-1.0, 1.0) } else { 0.0 };
        let third = cos_phi.acos() / 3.0;
        let hi = 2.0 * rho * third.cos() - a / 3.0;
        let lo = 2.0 * rho * (third + 2.0 * std::f64::consts::FRAC_PI_3 as $t).cos() - a / 3.0;
        // one Newton step on the scaled monic cubic: a GPU's acos and cos may be off by 2⁻¹¹
        // (Vulkan's bound), which the step takes to f32 rounding; a near-double root (a slope
        // near zero) keeps the trigonometric one
        let u = if hi.abs() >= lo.abs() { hi } else { lo };
        let slope = (3.0 * u + 2.0 * a) * u + b;
        let step = ((u + a) * u + b) * u + c;
        let u = if slope.abs() > 1e-3 { u - step / slope } else { u };
        let r = s * u;
        // c = (x − r)·(k2·x² + k1·x + k0) for |r| ≤ 1, c = (1 − x/r)·(k2·x² + k1·x + k0) beyond:
        // the second keeps the quotient finite as r runs off (it tends to c2·x² + c1·x + c0)
        let (k2, k1, k0) = if r.abs() > 1.0 {
            let k1 = c1 + c0 / r;
            (c2 + k1 / r, k1, c0)
        } else {
            let k1 = c2 + r * c3;
            (c3, k1, c1 + r * k1)
        };
        let disc = (k1 * k1 - 4.0 * k2 * k0).max(0.0);
        let h = -0.5 * (k1 + if k1 < 0.0 { -disc.sqrt() } else { disc.sqrt() });
        [div(k0, h), div(h, k2), r]
    }};
}

/// The six-moment bound, in f32 ([`mboit6_share_in_front`]) and, for the tests, in f64.
macro_rules! mboit6_share {
    ($(#[$attr:meta])* $vis:vis fn $name:ident($t:ident)) => {
        $(#[$attr])*
        $vis fn $name(m: [$t; 6], z: $t) -> $t {
            let div = |a: $t, b: $t| -> $t {
                let b = if b.abs() < 1e-12 { if b < 0.0 { -1e-12 } else { 1e-12 } } else { b };
                a / b
            };
            let beta = MBOIT6_BIAS as $t;
            let b: [$t; 6] =
                std::array::from_fn(|i| m[i] * (1.0 - beta) + MBOIT6_BIAS_TARGET[i] as $t * beta);
            // the Hankel matrix H[i][j] = b(i + j), b(0) = 1, i, j = 0..3, as L·D·Lᵀ: L unit lower
            // triangular, its first column (1, b1, b2, b3), D = diag(1, d1, d2, d3)
            let d1 = b[1] - b[0] * b[0];
            let l21 = div(b[2] - b[1] * b[0], d1);
            let l31 = div(b[3] - b[2] * b[0], d1);
            let d2 = b[3] - b[1] * b[1] - l21 * l21 * d1;
            let l32 = div(b[4] - b[2] * b[1] - l31 * l21 * d1, d2);
            let d3 = b[5] - b[2] * b[2] - l31 * l31 * d1 - l32 * l32 * d2;
            // H·c = (1, z, z², z³): forward through L, scale by D⁻¹, back through Lᵀ
            let y1 = z - b[0];
            let y2 = z * z - b[1] - l21 * y1;
            let y3 = z * z * z - b[2] - l31 * y1 - l32 * y2;
            let c3 = div(y3, d3);
            let c2 = div(y2, d2) - l32 * c3;
            let c1 = div(y1, d1) - l21 * c2 - l31 * c3;
            let c0 = 1.0 - b[0] * c1 - b[1] * c2 - b[2] * c3;
            // the three other atoms: the roots of c0 + c1·x + c2·x² + c3·x³
            let [x1, x2, x3] = cubic_roots!($t, c0, c1, c2, c3, div);
            // the cubic through (z, η) and (xᵢ, [xᵢ < z]) in Newton's form, by divided differences
            let f0 = MBOIT_OVERESTIMATION as $t;
            let step = |x: $t| -> $t { if x < z { 1.0 } else { 0.0 } };
            let (f1, f2, f3) = (step(x1), step(x2), step(x3));
            let f01 = div(f1 - f0, x1 - z);
            let f12 = div(f2 - f1, x2 - x1);
            let f23 = div(f3 - f2, x3 - x2);
            let f012 = div(f12 - f01, x2 - z);
            let f123 = div(f23 - f12, x3 - x1);
            let f0123 = div(f123 - f012, x3 - z);
            // its expectation under the moments, basis polynomial by basis polynomial:
            // E[x − z], E[(x − z)(x − x1)], E[(x − z)(x − x1)(x − x2)]
            let e1 = b[0] - z;
            let e2 = b[1] - (z + x1) * b[0] + z * x1;
            let e3 = b[2] - (z + x1 + x2) * b[1] + (z * x1 + z * x2 + x1 * x2) * b[0] - z * x1 * x2;
            (f0 + f01 * e1 + f012 * e2 + f0123 * e3).clamp(0.0, 1.0)
        }
    };
}

mboit6_share! {
    /// The share, in [0, 1], of a pixel's optical depth that lies in front of warped depth `z`,
    /// bounded from its six normalized power moments `m` (Σ a·zᵏ / Σ a, k = 1..6): moment-based
    /// OIT with six moments (Münstermann et al. 2018, the six-moment case of its Hamburger bound).
    /// As [`mboit_share_in_front`], one size up: the moments, moved by [`MBOIT6_BIAS`] towards
    /// [`MBOIT6_BIAS_TARGET`], make a positive definite 4×4 Hankel matrix H; the solution c of
    /// H·c = (1, z, z², z³) is the kernel polynomial whose three roots, with z, carry the one
    /// distribution with these moments that has an atom at z (they are real and distinct from z
    /// when H is positive definite). The estimate weighs the atoms in front of z fully and the one
    /// at z by [`MBOIT_OVERESTIMATION`]: the expectation, under the moments, of the cubic that
    /// interpolates those four values, which weighs each atom by its mass.
    pub fn mboit6_share_in_front(f32)
}

#[cfg(test)]
mboit6_share! {
    /// [`mboit6_share_in_front`] in f64, for the tests.
    fn mboit6_share_in_front_f64(f64)
}

/// A pixel's sums for moment-based OIT, as floats: Σ T·α·c (each channel in 8-bit units times the
/// 16-bit transmittance), Σ T·α, the optical depth Σ −ln(1 − α) and the count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MboitSums {
    /// Σ T·α·c, channel by channel.
    pub weighted: Vec3,
    /// Σ T·α.
    pub weight: f32,
    /// Σ −ln(1 − α).
    pub optical_depth: f32,
    /// Fragments.
    pub count: u32,
}

/// Moment-based OIT's composite: the transmittance-weighted colours normalized to the exact total
/// coverage, c̄·(1 − T) + bg·T with T = e^(−optical depth) (the paper's resolve).
pub fn mboit(s: &MboitSums, background: Vec3) -> Vec3 {
    if s.count == 0 {
        return background;
    }
    let t = (-s.optical_depth).exp();
    let mean = if s.weight > 0.0 { s.weighted / (s.weight * 255.0) } else { Vec3::ZERO };
    mean * (1.0 - t) + background * t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The moment bound finds the atoms it is given: one fragment's absorbance lies wholly behind
    /// a depth in front of it and wholly in front of a depth behind it; two equal fragments put half
    /// in front of a depth between them. Fails when the forward or back substitution, the roots or
    /// the divided differences are off.
    #[test]
    fn mboit_bound_finds_its_atoms() {
        let one = |z0: f32| [z0, z0 * z0, z0 * z0 * z0, z0 * z0 * z0 * z0];
        for z0 in [-0.7f32, -0.2, 0.0, 0.3, 0.8] {
            let m = one(z0);
            assert!(mboit_share_in_front(m, z0 + 0.15) > 0.97, "{z0}: behind it");
            assert!(mboit_share_in_front(m, z0 - 0.15) < 0.03, "{z0}: in front of it");
        }
        let two: [f32; 4] =
            std::array::from_fn(|k| 0.5 * ((-0.5f32).powi(k as i32 + 1) + 0.5f32.powi(k as i32 + 1)));
        let mid = mboit_share_in_front(two, 0.0);
        assert!((mid - 0.5).abs() < 0.05, "half in front of the middle: {mid}");
        assert!(mboit_share_in_front(two, 0.9) > 0.95 && mboit_share_in_front(two, -0.9) < 0.05);
        // monotone in depth, and bounded
        let mut last = 0.0;
        for i in 0..=100 {
            let s = mboit_share_in_front(two, -1.0 + i as f32 / 50.0);
            assert!((0.0..=1.0).contains(&s) && s >= last - 1e-4, "at {i}: {s} after {last}");
            last = s;
        }
    }

    /// A pixel's fragments as (optical depth, warped depth): their normalized moments z¹..z⁶ and
    /// the share of the optical depth in front of `z`, the one at `z` counted by the
    /// overestimation (what the bound estimates).
    fn moments6(set: &[(f64, f64)]) -> [f64; 6] {
        let total: f64 = set.iter().map(|f| f.0).sum();
        std::array::from_fn(|k| set.iter().map(|f| f.0 * f.1.powi(k as i32 + 1)).sum::<f64>() / total)
    }

    fn true_share(set: &[(f64, f64)], z: f64) -> f64 {
        let total: f64 = set.iter().map(|f| f.0).sum();
        let w = |f: &(f64, f64)| {
            if f.1 < z {
                f.0
            } else if f.1 == z {
                f.0 * f64::from(MBOIT_OVERESTIMATION)
            } else {
                0.0
            }
        };
        set.iter().map(w).sum::<f64>() / total
    }

    /// Random fragment sets, 1 to 12 fragments a set, each (optical depth, warped depth).
    fn random_sets(n: usize) -> Vec<Vec<(f64, f64)>> {
        let mut s = 0x9e37_79b9u32;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            f64::from(s) / f64::from(u32::MAX)
        };
        (0..n).map(|i| (0..1 + i % 12).map(|_| (0.05 + next(), next() * 2.0 - 1.0)).collect()).collect()
    }

    /// The six-moment bound finds the atoms it is given, as the four-moment one does, and three
    /// atoms besides, which four moments cannot resolve: between (−0.6, 0, 0.6) it puts the first
    /// third in front within 0.02 (four moments miss by more than 0.05). Fails when the
    /// factorization, the substitutions, a root of the cubic or the divided differences are off.
    #[test]
    fn mboit6_bound_finds_its_atoms() {
        let f32s = |m: [f64; 6]| m.map(|v| v as f32);
        for z0 in [-0.7f64, -0.2, 0.0, 0.3, 0.8] {
            let m = f32s(moments6(&[(1.0, z0)]));
            let z0 = z0 as f32;
            assert!(mboit6_share_in_front(m, z0 + 0.15) > 0.97, "{z0}: behind it");
            assert!(mboit6_share_in_front(m, z0 - 0.15) < 0.03, "{z0}: in front of it");
        }
        let two = f32s(moments6(&[(1.0, -0.5), (1.0, 0.5)]));
        let mid = mboit6_share_in_front(two, 0.0);
        assert!((mid - 0.5).abs() < 0.02, "half in front of the middle: {mid}");
        let three = moments6(&[(1.0, -0.6), (1.0, 0.0), (1.0, 0.6)]);
        for (z, want) in [(-0.3f32, 1.0 / 3.0), (0.3, 2.0 / 3.0), (0.9, 1.0), (-0.9, 0.0)] {
            let six = mboit6_share_in_front(f32s(three), z);
            let four = mboit_share_in_front(std::array::from_fn(|k| three[k] as f32), z);
            assert!((six - want).abs() < 0.02, "three atoms at {z}: {six}, not {want}");
            if z.abs() < 0.5 {
                assert!((four - want).abs() > 0.05, "four moments resolve three atoms at {z}: {four}");
            }
        }
        // monotone in depth, and bounded
        for set in random_sets(24) {
            let m = f32s(moments6(&set));
            let mut last = 0.0;
            for i in 0..=200 {
                let s = mboit6_share_in_front(m, -1.0 + i as f32 / 100.0);
                assert!((0.0..=1.0).contains(&s) && s >= last - 2e-3, "{set:?} at {i}: {s} after {last}");
                last = s;
            }
        }
    }

    /// The cubic's roots: three real roots, spread, clustered, double, and one running off to
    /// infinity (the leading coefficient near zero), each found to a few ulps of its size, the
    /// finite ones not lost to the large one. Fails when the trigonometric form's angle, the
    /// scaling, the deflation or the quadratic's stable form is off.
    #[test]
    fn mboit6_cubic_roots() {
        let div = |a: f32, b: f32| a / if b.abs() < 1e-12 { 1e-12f32.copysign(b) } else { b };
        for (roots, lead) in [
            ([-0.5f32, 0.1, 0.7], 1.0f32),
            ([-0.5, 0.1, 0.7], -3e4),
            ([0.2, 0.2, -0.9], 2.0),
            ([0.3, 0.30001, 0.31], 1.0),
            ([-0.4, 0.6, 1e6], 1e-6),
            ([-0.4, 0.6, -3e8], 1.0),
            ([0.0, 0.5, -0.5], 1.0),
        ] {
            let [r1, r2, r3] = roots.map(f64::from);
            let l = f64::from(lead);
            let c = [-l * r1 * r2 * r3, l * (r1 * r2 + r1 * r3 + r2 * r3), -l * (r1 + r2 + r3), l];
            let c = c.map(|v| v as f32);
            let mut got = cubic_roots!(f32, c[0], c[1], c[2], c[3], div);
            got.sort_by(f32::total_cmp);
            let mut want = roots;
            want.sort_by(f32::total_cmp);
            for (g, w) in got.iter().zip(want) {
                // a double root is ill-conditioned: √ε of its size
                let close = (roots[0] - roots[1]).abs() < 1e-3;
                let tol = if close { 1e-3 } else { 1e-4 * w.abs().max(1.0) };
                assert!((g - w).abs() <= tol, "{roots:?}: got {got:?}");
            }
        }
    }

    /// The f32 bound against itself in f64, and both against the share they estimate, on random
    /// fragment sets at depths across [−1, 1]: the f32 bound stays within 2·10⁻³ of the f64 one
    /// (the bias keeps the Hankel matrix's last pivot above f32's rounding of moments to z⁶), and
    /// its mean error against the true share is printed beside four moments'. Fails when the
    /// bias is too small for f32 (5·10⁻⁶ here: the pivots drown in rounding) or the roots lose
    /// precision.
    #[test]
    fn mboit6_f32_follows_f64() {
        let (mut worst, mut err6, mut err4, mut n) = (0.0f64, 0.0, 0.0, 0);
        for set in random_sets(600) {
            let m = moments6(&set);
            let m32 = m.map(|v| v as f32);
            for i in 0..=40 {
                let z = -1.0 + f64::from(i) / 20.0;
                let s32 = f64::from(mboit6_share_in_front(m32, z as f32));
                let s64 = mboit6_share_in_front_f64(m, z);
                worst = worst.max((s32 - s64).abs());
                let truth = true_share(&set, z);
                err6 += (s64 - truth).abs();
                err4 += (f64::from(mboit_share_in_front(std::array::from_fn(|k| m32[k]), z as f32)) - truth)
                    .abs();
                n += 1;
            }
        }
        let n = f64::from(n);
        eprintln!(
            "f32 against f64 at most {worst:.2e}; mean error six {:.4}, four {:.4}",
            err6 / n,
            err4 / n
        );
        assert!(worst <= 2e-3, "f32 off f64 by {worst}");
        assert!(err6 < err4, "six moments no closer than four: {} against {}", err6 / n, err4 / n);
    }
}
