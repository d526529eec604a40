//! The compositing equations, as pure functions over straight-alpha colours.
//!
//! - front-to-back *under* (dp, and every technique that ends with sorted fragments):
//!   `C += T·α·c`, `T *= 1 − α`, result `C + T·background`;
//! - back-to-front *over* (the back half of ddp): `C = α·c + (1 − α)·C`, starting from the
//!   background;
//! - weighted average (Bavoil & Myers 2008): the α-weighted mean colour, with the mean alpha applied
//!   n times: `T = (1 − ᾱ)ⁿ`, result `c̄·(1 − T) + background·T`;
//! - weighted sum (Meshkin 2007): `Σ α·c + background·(1 − Σ α)` (clamped).

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

/// Beer–Lambert transmittance through `thickness` of a medium with absorption `sigma`.
#[inline]
pub fn beer_lambert(sigma: f32, thickness: f32) -> f32 {
    (-sigma * thickness.max(0.0)).exp()
}

/// Thickness of the medium along a ray from sorted view-space distances: the sum of the gaps
/// between successive entry/exit pairs (layer 0 to 1, 2 to 3, ...). An unpaired last layer adds
/// nothing.
pub fn paired_thickness(sorted_distances: impl IntoIterator<Item = f32>) -> f32 {
    let mut it = sorted_distances.into_iter();
    let mut total = 0.0;
    while let (Some(a), Some(b)) = (it.next(), it.next()) {
        total += b - a;
    }
    total
}

/// Linear [0, 1] to 8-bit sRGB.
#[inline]
pub fn linear_to_srgb8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Linear [0, 1] (f64) to 8-bit sRGB.
#[inline]
pub fn linear_to_srgb8_f64(x: f64) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// A colour ramp for heat maps (black → blue → magenta → orange → white), `t` in [0, 1].
pub fn heat(t: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.05, 0.1, 0.6),
        Vec3::new(0.6, 0.05, 0.5),
        Vec3::new(1.0, 0.5, 0.05),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * (STOPS.len() - 1) as f32;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    STOPS[i].lerp(STOPS[i + 1], t - i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn thickness_pairs() {
        assert_eq!(paired_thickness([1.0, 2.0, 5.0, 7.5]), 3.5);
        assert_eq!(paired_thickness([1.0, 2.0, 5.0]), 1.0);
        assert_eq!(paired_thickness([]), 0.0);
    }

    #[test]
    fn srgb_edges() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        assert_eq!(linear_to_srgb8_f64(0.5), linear_to_srgb8(0.5));
    }
}
