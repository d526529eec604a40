//! The compositing equations, as pure functions over straight-alpha colours.
//!
//! - front-to-back *under* (dp, and every technique that ends with sorted fragments):
//!   `C += T·α·c`, `T *= 1 − α`, result `C + T·background`;
//! - back-to-front *over* (the back half of ddp): `C = α·c + (1 − α)·C`, starting from the
//!   background;
//! - weighted average (Bavoil & Myers 2008): the α-weighted mean colour, with the mean alpha applied
//!   n times: `T = (1 − ᾱ)ⁿ`, result `c̄·(1 − T) + background·T`;
//! - weighted sum (Meshkin 2007): `Σ α·c + background·(1 − Σ α)` (clamped).
//!
//! The effects other than transparency, on sorted layers:
//! - translucency: layers pair up along the ray, 0 entering a medium and 1 leaving it, 2 entering
//!   and 3 leaving, ... (an unpaired last layer adds nothing); each pair absorbs per channel
//!   `(1 − c)·k` per unit of view-space distance over its thickness, `c` the entering layer's
//!   colour and `k` [`Scene::absorption_per_length`](crate::Scene::absorption_per_length); the
//!   result is the background times the Beer–Lambert transmittance `exp(−Σ (1 − c)·k·thickness)`;
//! - Fresnel: the background times every layer's Schlick transmittance `1 − (1 − |n·v|)⁵` (no
//!   index of refraction: F0 = 0, so a layer facing the camera passes everything);
//! - complexity: the layer count `n` of a pixel as [`heat`]`(n / max)`, `max` the deepest pixel's
//!   count; the background where there is no layer.
//!
//! The techniques' resolve runs these in f32 (oit-cpu's `resolve.rs`, oit-wgpu's `resolve.wgsl`);
//! the reference runs them in f64 ([`front_to_back_f64`], [`translucency_f64`], [`fresnel_f64`],
//! [`heat_f64`]), written apart from the f32 resolve so each checks the other.

use glam::{DVec3, Vec3, Vec4};

/// Front-to-back accumulator (under blending) in f32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontToBack {
    /// Accumulated premultiplied colour.
    pub color: Vec3,
    /// Remaining transmittance.
    pub transmittance: f32,
}

impl Default for FrontToBack {
    fn default() -> Self {
        FrontToBack { color: Vec3::ZERO, transmittance: 1.0 }
    }
}

impl FrontToBack {
    /// Adds the next fragment behind everything so far.
    #[inline]
    pub fn under(&mut self, c: Vec4) {
        self.color += self.transmittance * c.w * c.truncate();
        self.transmittance *= 1.0 - c.w;
    }

    /// The result over `background`.
    #[inline]
    pub fn finish(&self, background: Vec3) -> Vec3 {
        self.color + self.transmittance * background
    }

    /// Composites `self` (the front part) over a back-to-front result `back` (ddp's join).
    #[inline]
    pub fn over(&self, back: Vec3) -> Vec3 {
        self.color + self.transmittance * back
    }
}

/// Front-to-back compositing of fragments given nearest first, in f32.
pub fn front_to_back(fragments: impl IntoIterator<Item = Vec4>, background: Vec3) -> Vec3 {
    let mut acc = FrontToBack::default();
    for c in fragments {
        acc.under(c);
    }
    acc.finish(background)
}

/// Front-to-back compositing in f64 (the reference). Fragments nearest first, as `[r, g, b, a]`.
pub fn front_to_back_f64(fragments: impl IntoIterator<Item = [f64; 4]>, background: DVec3) -> DVec3 {
    let mut color = DVec3::ZERO;
    let mut t = 1.0f64;
    for [r, g, b, a] in fragments {
        color += t * a * DVec3::new(r, g, b);
        t *= 1.0 - a;
    }
    color + t * background
}

/// Back-to-front *over* of one fragment onto `dst`.
#[inline]
pub fn over(dst: Vec3, c: Vec4) -> Vec3 {
    c.w * c.truncate() + (1.0 - c.w) * dst
}

/// Back-to-front compositing of fragments given farthest first.
pub fn back_to_front(fragments: impl IntoIterator<Item = Vec4>, background: Vec3) -> Vec3 {
    fragments.into_iter().fold(background, over)
}

/// Sums a weighted technique accumulates per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WeightedSums {
    /// Σ α·c.
    pub premultiplied: Vec3,
    /// Σ α.
    pub alpha: f32,
    /// Number of fragments.
    pub count: u32,
}

impl WeightedSums {
    /// Adds one fragment.
    #[inline]
    pub fn add(&mut self, c: Vec4) {
        self.premultiplied += c.w * c.truncate();
        self.alpha += c.w;
        self.count += 1;
    }
}

/// Weighted average (Bavoil & Myers 2008).
pub fn weighted_average(s: &WeightedSums, background: Vec3) -> Vec3 {
    if s.count == 0 || s.alpha <= 0.0 {
        return background;
    }
    let mean_color = s.premultiplied / s.alpha;
    let mean_alpha = (s.alpha / s.count as f32).min(1.0);
    let t = (1.0 - mean_alpha).powi(s.count as i32);
    mean_color * (1.0 - t) + background * t
}

/// Weighted sum (Meshkin 2007).
pub fn weighted_sum(s: &WeightedSums, background: Vec3) -> Vec3 {
    (s.premultiplied + background * (1.0 - s.alpha)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// A pixel's sums for weighted blended OIT (McGuire & Bavoil 2013), as floats: Σ α·w·c (each
/// channel in [0, 255] units of the 8-bit colour), Σ α·w, the optical depth Σ −ln(1 − α) and the
/// count (see [`crate::rules::wboit_weight`] and [`crate::rules::WBOIT_OPTICAL_DEPTH`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WboitSums {
    /// Σ α·w·c, channel by channel.
    pub weighted: Vec3,
    /// Σ α·w.
    pub weight: f32,
    /// Σ −ln(1 − α).
    pub optical_depth: f32,
    /// Fragments.
    pub count: u32,
}

/// Weighted blended OIT's composite: the weighted mean colour under the exact coverage,
/// c̄·(1 − T) + bg·T with T = e^(−optical depth) = Π(1 − αᵢ).
pub fn wboit(s: &WboitSums, background: Vec3) -> Vec3 {
    if s.count == 0 || s.weight <= 0.0 {
        return background;
    }
    let mean = s.weighted / (s.weight * 255.0);
    let t = (-s.optical_depth).exp();
    mean * (1.0 - t) + background * t
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

/// Schlick's Fresnel transmittance for a surface seen at `cos_theta`: `1 − (1 − cos θ)⁵`.
#[inline]
pub fn schlick_transmittance(cos_theta: f32) -> f32 {
    1.0 - (1.0 - cos_theta.abs().min(1.0)).powi(5)
}

/// [`schlick_transmittance`] in f64 (the reference).
#[inline]
pub fn schlick_transmittance_f64(cos_theta: f64) -> f64 {
    1.0 - (1.0 - cos_theta.abs().min(1.0)).powi(5)
}

/// Fresnel in f64 (the reference): `background` seen through layers whose normals make the
/// cosines `cos_theta` with the viewing direction (any order: the product does not depend on it).
pub fn fresnel_f64(cos_theta: impl IntoIterator<Item = f64>, background: DVec3) -> DVec3 {
    background * cos_theta.into_iter().map(schlick_transmittance_f64).product::<f64>()
}

/// Beer–Lambert transmittance, per channel, through `thickness` of a medium absorbing `sigma`
/// per unit of length (a negative thickness, which sorted layers never give, absorbs nothing).
#[inline]
pub fn beer_lambert(sigma: DVec3, thickness: f64) -> DVec3 {
    let t = thickness.max(0.0);
    DVec3::new((-sigma.x * t).exp(), (-sigma.y * t).exp(), (-sigma.z * t).exp())
}

/// The media along a ray, from layers sorted nearest first as (view-space distance, payload):
/// layer 0 enters and layer 1 leaves, 2 enters and 3 leaves, ...; yields each entering layer's
/// payload and the medium's thickness (leaving distance − entering distance). An unpaired last
/// layer opens a medium that never closes and yields nothing.
pub fn paired_layers<T>(sorted: impl IntoIterator<Item = (f64, T)>) -> impl Iterator<Item = (T, f64)> {
    let mut it = sorted.into_iter();
    std::iter::from_fn(move || {
        let (entry, payload) = it.next()?;
        let (exit, _) = it.next()?;
        Some((payload, exit - entry))
    })
}

/// Translucency in f64 (the reference): layers sorted nearest first as (view-space distance,
/// straight-alpha colour), paired by [`paired_layers`]; each medium absorbs `(1 − c)·per_length`
/// per channel, `c` its entering layer's colour ([`beer_lambert`]).
pub fn translucency_f64(
    sorted: impl IntoIterator<Item = (f64, [f64; 4])>,
    per_length: f64,
    background: DVec3,
) -> DVec3 {
    paired_layers(sorted).fold(background, |color, ([r, g, b, _], thickness)| {
        color * beer_lambert((DVec3::ONE - DVec3::new(r, g, b)) * per_length, thickness)
    })
}

/// Linear [0, 1] to 8-bit sRGB: [`linear_to_srgb8_formula`]'s value, bit for bit, from a table
/// (every image of every technique ends in three of these a pixel; the formula's `powf` was a
/// tenth of a CPU frame).
///
/// How the table gives the formula's answer: the formula rises with `x` (for non-negative
/// floats, with `x`'s bit pattern), so the code of `x` is the number of codes `k ≥ 1` whose
/// threshold (the smallest float the formula takes to `k` or above, found once by bisection on
/// the bit patterns) is at or below `x`. The table holds, per group of 2¹⁶ consecutive floats
/// (the top 16 bits of `x`), the code of the group's first float; from there at most a step or two
/// of thresholds remain inside the group (a group spans under 1 % of `x`, an 8-bit sRGB code at
/// least 0.9 % near 1 and more below). `srgb8_table_matches_the_formula` checks it on every
/// 61st float of [0, 1] and on every float near each threshold.
#[inline]
pub fn linear_to_srgb8(x: f32) -> u8 {
    // NaN, negatives and −0 are 0 (as the formula makes them); above 1 is 1
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    let bits = x.min(1.0).to_bits();
    let table = srgb8_table();
    let mut code = table.start[(bits >> 16) as usize];
    while code < 255 && bits >= table.threshold[usize::from(code) + 1] {
        code += 1;
    }
    code
}

/// The sRGB transfer function to 8 bits, as written: `12.92·x` up to 0.0031308, then
/// `1.055·x^(1/2.4) − 0.055`, scaled to 255 and rounded half up; NaN is 0, `x` clamped to [0, 1].
/// [`linear_to_srgb8`] gives the same bits faster.
#[inline]
pub fn linear_to_srgb8_formula(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// [`linear_to_srgb8`]'s table, built once per process from [`linear_to_srgb8_formula`].
struct Srgb8Table {
    /// The code of the float with bits `i << 16`, for `i` up to 1.0's.
    start: Vec<u8>,
    /// `threshold[k]`: the bits of the smallest float in [0, 1] the formula takes to `k` or above
    /// (`threshold[0] = 0`).
    threshold: [u32; 256],
}

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::OnceLock<Srgb8Table> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        const ONE: u32 = 0x3F80_0000;
        let code = |bits: u32| linear_to_srgb8_formula(f32::from_bits(bits));
        let mut threshold = [0u32; 256];
        for (k, t) in threshold.iter_mut().enumerate().skip(1) {
            // the smallest bits in [0, ONE] whose code is at least k (ONE's is 255)
            let (mut lo, mut hi) = (0u32, ONE);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if usize::from(code(mid)) >= k { hi = mid } else { lo = mid + 1 }
            }
            *t = lo;
        }
        let start = (0..=ONE >> 16).map(|i| code(i << 16)).collect();
        Srgb8Table { start, threshold }
    })
}

/// Linear [0, 1] (f64) to 8-bit sRGB.
#[inline]
pub fn linear_to_srgb8_f64(x: f64) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// The stops of [`heat`]'s ramp, evenly spaced over [0, 1]: black, blue, magenta, orange, white.
pub const HEAT_STOPS: [[f32; 3]; 5] =
    [[0.0, 0.0, 0.0], [0.05, 0.1, 0.6], [0.6, 0.05, 0.5], [1.0, 0.5, 0.05], [1.0, 1.0, 1.0]];

/// A colour ramp for heat maps ([`HEAT_STOPS`], linear between them), `t` in [0, 1].
pub fn heat(t: f32) -> Vec3 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * (HEAT_STOPS.len() - 1) as f32;
    let i = (t.floor() as usize).min(HEAT_STOPS.len() - 2);
    Vec3::from(HEAT_STOPS[i]).lerp(Vec3::from(HEAT_STOPS[i + 1]), t - i as f32)
}

/// [`heat`] in f64 (the reference).
pub fn heat_f64(t: f64) -> DVec3 {
    let stop = |i: usize| Vec3::from(HEAT_STOPS[i]).as_dvec3();
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * (HEAT_STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(HEAT_STOPS.len() - 2);
    stop(i).lerp(stop(i + 1), t - i as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table against the formula: on every 61st float of [0, 1], on every float within 300
    /// of each threshold (where a wrong table would first go wrong), and on the values outside
    /// [0, 1]. Mutation caught: a step loop that stops one short (`>` for `>=`), a group index
    /// off by a bit.
    #[test]
    fn srgb8_table_matches_the_formula() {
        let check = |bits: u32| {
            let x = f32::from_bits(bits);
            assert_eq!(linear_to_srgb8(x), linear_to_srgb8_formula(x), "x = {x:e} (bits {bits:#x})");
        };
        const ONE: u32 = 0x3F80_0000;
        (0..=ONE).step_by(61).for_each(check);
        for &t in &srgb8_table().threshold {
            (t.saturating_sub(300)..=(t + 300).min(ONE)).for_each(check);
        }
        for x in
            [f32::NAN, -f32::NAN, -0.0, -1.0, f32::NEG_INFINITY, 1.0, 1.5, f32::INFINITY, f32::MIN_POSITIVE]
        {
            assert_eq!(linear_to_srgb8(x), linear_to_srgb8_formula(x), "{x}");
        }
        assert_eq!((linear_to_srgb8(0.0), linear_to_srgb8(1.0)), (0, 255));
    }

    /// Every float of [0, 1]: `cargo test --release -p oit-core -- --ignored every_float` (a few
    /// seconds in release).
    #[test]
    #[ignore = "a billion floats; the sampled test above runs in CI"]
    fn srgb8_table_matches_the_formula_on_every_float() {
        for bits in 0..=0x3F80_0000u32 {
            let x = f32::from_bits(bits);
            assert_eq!(linear_to_srgb8(x), linear_to_srgb8_formula(x), "bits {bits:#x}");
        }
    }

    #[test]
    fn under_and_over_agree() {
        let frags =
            [Vec4::new(1.0, 0.0, 0.0, 0.5), Vec4::new(0.0, 1.0, 0.0, 0.25), Vec4::new(0.0, 0.0, 1.0, 1.0)];
        let bg = Vec3::new(0.2, 0.3, 0.4);
        let a = front_to_back(frags, bg);
        let b = back_to_front(frags.iter().rev().copied(), bg);
        assert!((a - b).abs().max_element() < 1e-6, "{a} {b}");
        let c =
            front_to_back_f64(frags.map(|f| [f.x as f64, f.y as f64, f.z as f64, f.w as f64]), bg.as_dvec3());
        assert!((c.as_vec3() - a).abs().max_element() < 1e-6);
    }

    #[test]
    fn weighted_edges() {
        let bg = Vec3::ONE;
        assert_eq!(weighted_average(&WeightedSums::default(), bg), bg);
        let mut s = WeightedSums::default();
        s.add(Vec4::new(1.0, 0.0, 0.0, 0.0));
        assert_eq!(weighted_average(&s, bg), bg);
        let mut s = WeightedSums::default();
        s.add(Vec4::new(1.0, 0.0, 0.0, 1.0));
        assert_eq!(weighted_average(&s, bg), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(weighted_sum(&s, bg), Vec3::new(1.0, 0.0, 0.0));
    }

    /// Pairing: 0 enters and 1 leaves, 2 enters and 3 leaves; a last unpaired layer yields
    /// nothing. Fails if pairing started at layer 1 (yields ('b', 3) and misses 'c'), or if the
    /// unpaired layer were closed at infinity or at zero.
    #[test]
    fn layers_pair_up() {
        let pairs: Vec<_> = paired_layers([(1.0, 'a'), (2.0, 'b'), (5.0, 'c'), (7.5, 'd')]).collect();
        assert_eq!(pairs, [('a', 1.0), ('c', 2.5)]);
        let pairs: Vec<_> = paired_layers([(1.0, 'a'), (2.0, 'b'), (5.0, 'c')]).collect();
        assert_eq!(pairs, [('a', 1.0)]);
        assert_eq!(paired_layers::<char>([]).count(), 0);
    }

    /// Translucency of two media by hand: exp(−(1 − c)·k·thickness) per channel, per medium.
    /// Fails if the leaving layer's colour were used (its red is 0.5, not 0.25), or the sign of
    /// the exponent flipped.
    #[test]
    fn translucency_by_hand() {
        let bg = DVec3::new(1.0, 0.5, 0.25);
        let layers = [
            (2.0, [0.25, 1.0, 0.0, 0.3]),
            (3.5, [0.5, 0.5, 0.5, 0.3]),
            (4.0, [0.0, 0.5, 1.0, 0.3]),
            (4.5, [1.0, 1.0, 1.0, 0.3]),
        ];
        let k = 0.8;
        let got = translucency_f64(layers, k, bg);
        // medium 1: 1.5 long, entered at (0.25, 1, 0), absorbing (0.75, 0, 1)·k; medium 2: 0.5
        // long, entered at (0, 0.5, 1), absorbing (1, 0.5, 0)·k
        let want = DVec3::new(
            (-0.75 * k * 1.5f64).exp() * (-k * 0.5f64).exp(),
            0.5 * (-0.5 * k * 0.5f64).exp(),
            0.25 * (-k * 1.5f64).exp(),
        );
        assert!((got - want).abs().max_element() < 1e-15, "{got} {want}");
        assert_eq!(beer_lambert(DVec3::ONE, -1.0), DVec3::ONE, "no negative thickness");
    }

    /// Schlick with F0 = 0: 1 at normal incidence, 0 at grazing, 1 − (1/2)⁵ at 60°, and
    /// symmetric in the normal's side. Fails if the power were 4 (15/16 at 60°) or `abs` dropped.
    #[test]
    fn schlick_closed_forms() {
        assert_eq!(schlick_transmittance_f64(1.0), 1.0);
        assert_eq!(schlick_transmittance_f64(-1.0), 1.0);
        assert_eq!(schlick_transmittance_f64(0.0), 0.0);
        assert!((schlick_transmittance_f64(0.5) - 31.0 / 32.0).abs() < 1e-15);
        assert!((schlick_transmittance_f64(-0.5) - 31.0 / 32.0).abs() < 1e-15);
        let bg = DVec3::splat(0.5);
        assert!((fresnel_f64([0.5, -0.5], bg) - bg * (31.0f64 / 32.0).powi(2)).abs().max_element() < 1e-15);
        // the f32 resolve's Schlick agrees within f32 rounding
        for c in [-1.0f32, -0.3, 0.0, 0.1, 0.5, 0.99, 1.0] {
            let d = schlick_transmittance(c) as f64 - schlick_transmittance_f64(c as f64);
            assert!(d.abs() < 1e-6, "{c}: {d}");
        }
    }

    /// The heat ramp at its stops and midway between them, in f32 and f64. Fails if a stop
    /// were skipped (t·3 for t·4) or the ramp ran backwards.
    #[test]
    fn heat_at_stops() {
        for (i, stop) in HEAT_STOPS.iter().enumerate() {
            let t = i as f64 / 4.0;
            assert_eq!(heat_f64(t), Vec3::from(*stop).as_dvec3(), "stop {i}");
            assert_eq!(heat(t as f32), Vec3::from(*stop), "stop {i}");
        }
        let mid = heat_f64(0.125);
        // 1e-7: the stops are f32
        assert!((mid - DVec3::new(0.025, 0.05, 0.3)).abs().max_element() < 1e-7, "{mid}");
        assert_eq!(heat_f64(f64::NAN), DVec3::ZERO);
        assert_eq!(heat_f64(2.0), DVec3::ONE);
    }

    #[test]
    fn srgb_edges() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        assert_eq!(linear_to_srgb8_f64(0.5), linear_to_srgb8(0.5));
    }

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
