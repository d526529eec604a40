//! Weighted blended OIT (McGuire & Bavoil, JCGT 2013), `wboit`: what every backend computes for
//! it, in one place. Each fragment adds its colour weighted by its depth ([`wboit_weight`], the
//! paper's eq. 10 in integer hundredths) and its optical depth ([`WBOIT_OPTICAL_DEPTH`]) to a
//! pixel's u64 sums; [`wboit`] composites them. oit-cpu's `technique/wboit.rs` and oit-shaders'
//! `technique/wboit.wgsl` (with `wboit_table.wgsl`) add the same integers.

use glam::Vec3;

/// Weighted blended OIT's depth weight (McGuire & Bavoil 2013, eq. 10: max(10⁻², 3·10³·(1 − d)³)),
/// in hundredths, from the depth quantized to 10 bits: q = 1023 − ⌊d·1024⌋ (an exact product, so
/// every backend finds the same q), w = max(1, 300000·q³ / 1023³) in integers. Nearer fragments
/// weigh more, from 0.01 at the far plane to 3000 at the near one.
#[inline]
pub fn wboit_weight(d: f32) -> u64 {
    let d = if d.is_nan() { 1.0 } else { d.clamp(0.0, 1.0) };
    let q = 1023 - ((d * 1024.0) as u64).min(1023);
    (300_000 * q * q * q / (1023 * 1023 * 1023)).max(1)
}

/// Units of one [`WBOIT_OPTICAL_DEPTH`] entry: 1/65536 of optical depth.
pub const WBOIT_OPTICAL_UNIT: f32 = 65536.0;

/// −ln(1 − a/255) in units of 1/65536 for each 8-bit alpha a (round to nearest), a = 255 capped
/// at 32 (e⁻³² ≈ 1.3·10⁻¹⁴: fully opaque to 8 bits). Weighted blended OIT sums these per pixel,
/// order-independently, and composites with e^(−Σ), the product of the fragments' 1 − α (the
/// paper's revealage, kept by multiplicative blending there). A table, not `ln`, so that every
/// backend adds the same integers: `wboit_table.wgsl` holds the same numbers (a test compares them, and
/// another checks the table against the formula).
#[rustfmt::skip]
pub const WBOIT_OPTICAL_DEPTH: [u32; 256] = [
    0, 258, 516, 776, 1036, 1298, 1560, 1824,
    2089, 2355, 2622, 2890, 3159, 3429, 3701, 3973,
    4247, 4522, 4797, 5075, 5353, 5632, 5913, 6195,
    6478, 6762, 7048, 7335, 7623, 7912, 8203, 8495,
    8788, 9082, 9378, 9675, 9974, 10274, 10575, 10878,
    11182, 11488, 11795, 12103, 12413, 12724, 13037, 13351,
    13667, 13985, 14303, 14624, 14946, 15270, 15595, 15922,
    16250, 16580, 16912, 17246, 17581, 17918, 18257, 18597,
    18939, 19283, 19629, 19977, 20326, 20678, 21031, 21386,
    21743, 22102, 22464, 22827, 23192, 23559, 23928, 24299,
    24673, 25048, 25426, 25806, 26188, 26573, 26959, 27348,
    27739, 28133, 28529, 28927, 29328, 29732, 30137, 30546,
    30957, 31370, 31786, 32205, 32626, 33051, 33477, 33907,
    34340, 34775, 35214, 35655, 36099, 36547, 36997, 37451,
    37907, 38367, 38830, 39297, 39767, 40240, 40716, 41196,
    41680, 42167, 42658, 43153, 43651, 44154, 44660, 45170,
    45684, 46202, 46724, 47250, 47781, 48316, 48855, 49399,
    49948, 50501, 51058, 51621, 52188, 52761, 53338, 53921,
    54508, 55102, 55700, 56304, 56914, 57529, 58150, 58777,
    59411, 60050, 60696, 61348, 62006, 62672, 63344, 64023,
    64709, 65403, 66104, 66812, 67529, 68253, 68985, 69726,
    70474, 71232, 71999, 72774, 73559, 74353, 75158, 75972,
    76796, 77631, 78477, 79333, 80201, 81081, 81973, 82877,
    83793, 84723, 85666, 86623, 87594, 88579, 89580, 90596,
    91628, 92676, 93742, 94825, 95927, 97047, 98187, 99347,
    100528, 101730, 102955, 104204, 105476, 106774, 108098, 109449,
    110829, 112238, 113679, 115152, 116658, 118200, 119780, 121398,
    123057, 124759, 126507, 128303, 130149, 132049, 134005, 136022,
    138102, 140251, 142473, 144773, 147156, 149630, 152200, 154875,
    157664, 160578, 163626, 166824, 170185, 173729, 177475, 181448,
    185677, 190199, 195056, 200301, 206004, 212250, 219155, 226874,
    235625, 245727, 257676, 272300, 291154, 317726, 363152, 2097152,
];

/// A pixel's sums for weighted blended OIT (McGuire & Bavoil 2013), as floats: Σ α·w·c (each
/// channel in [0, 255] units of the 8-bit colour), Σ α·w, the optical depth Σ −ln(1 − α) and the
/// count (see [`wboit_weight`] and [`WBOIT_OPTICAL_DEPTH`]).
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The table is the formula it says: −ln(1 − a/255)·65536 rounded, 255 capped at 32. Fails
    /// when an entry is edited by hand.
    #[test]
    fn wboit_optical_depth_is_the_formula() {
        for (a, &v) in WBOIT_OPTICAL_DEPTH.iter().enumerate() {
            let want =
                if a == 255 { 32.0 * 65536.0 } else { (-(1.0 - a as f64 / 255.0).ln() * 65536.0).round() };
            assert_eq!(f64::from(v), want, "alpha {a}");
        }
    }

    /// The weight falls with depth, from 3000 (300000 hundredths) at the near plane to the floor of
    /// 0.01 at the far one, as eq. 10. Fails when the cube or the floor is dropped.
    #[test]
    fn wboit_weight_is_eq10() {
        assert_eq!(wboit_weight(0.0), 300_000);
        assert_eq!(wboit_weight(1.0), 1);
        assert_eq!(wboit_weight(f32::NAN), 1);
        // (1 − d)³ at d = 0.5: q = 511, 300000·511³/1023³ = 37390
        assert_eq!(wboit_weight(0.5), 300_000 * 511 * 511 * 511 / (1023 * 1023 * 1023));
        let mut last = u64::MAX;
        for i in 0..=1000 {
            let w = wboit_weight(i as f32 / 1000.0);
            assert!(w <= last && w >= 1, "monotone at {i}");
            last = w;
        }
    }
}
