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
    // as many steps as the widest group needs, each taken or not without a branch: a loop that
    // stopped at the first threshold above `x` mispredicted its exit where neighbouring values
    // take different steps (oit-cpu's `srgb` bench, values spread at random: 4.5 → 1.9 ns a
    // value; on a smooth ramp both 1.9)
    for _ in 0..table.steps {
        code += u8::from(bits >= table.threshold[usize::from(code) + 1]);
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
    /// (`threshold[0] = 0`); `threshold[256]` is `u32::MAX`, above every float's bits.
    threshold: [u32; 257],
    /// The most codes one group spans past its first float's: the steps that reach any float's
    /// code from its group's.
    steps: u8,
}

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::OnceLock<Srgb8Table> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        const ONE: u32 = 0x3F80_0000;
        let code = |bits: u32| linear_to_srgb8_formula(f32::from_bits(bits));
        let mut threshold = [0u32; 257];
        threshold[256] = u32::MAX;
        for (k, t) in threshold.iter_mut().enumerate().take(256).skip(1) {
            // the smallest bits in [0, ONE] whose code is at least k (ONE's is 255)
            let (mut lo, mut hi) = (0u32, ONE);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if usize::from(code(mid)) >= k { hi = mid } else { lo = mid + 1 }
            }
            *t = lo;
        }
        let start: Vec<u8> = (0..=ONE >> 16).map(|i| code(i << 16)).collect();
        // a group's last float is its largest code (the formula rises with the bits)
        let last = |i: u32| code((i << 16 | 0xffff).min(ONE));
        let steps = (0..=ONE >> 16).map(|i| last(i) - start[i as usize]).max().unwrap_or(0);
        Srgb8Table { start, threshold, steps }
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
}
