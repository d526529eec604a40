//! The rules every backend shares, defined once: how depth becomes an ordered integer, how a
//! fragment is routed to a bucket or a histogram bin, how the histogram is equalized, and how
//! colour, depth and normals are packed into the words the techniques store.
//!
//! The CPU backend calls these functions; the GPU backends carry the same functions in WGSL, and a
//! test runs both on the edge values (d = 0, d = 1, zNear = zFar, alpha 0 and 255).
//!
//! Conventions:
//! - depths are NDC z in [0, 1]; [`depth_bits`] clamps into that range, so a depth is always a
//!   non-negative float, and for non-negative floats the order of the bit patterns read as `u32`
//!   is the order of the values (which is why MAX on the bits is MAX on the floats);
//! - a fragment's colour is linear straight-alpha RGBA8, packed `r | g << 8 | b << 16 | a << 24`
//!   ([`pack_rgba8`]). Every technique, the reference included, composites these quantized
//!   colours, so exact techniques can match the reference bit for bit.

use glam::{DVec3, Vec2, Vec3, Vec4};

/// Number of subintervals in [`bucket_index`]'s depth mode (pairs of min/max buckets).
pub const BDP_DEPTH_SUBINTERVALS: u32 = 16;
/// Number of subintervals in bucket depth peeling's colour mode.
pub const BDP_COLOR_SUBINTERVALS: u32 = 32;
/// Buckets per pixel per capture pass (8 render targets × 4 channels).
pub const BUCKETS: usize = 32;
/// Bins of the adaptive scheme's depth histogram.
pub const HISTOGRAM_BINS: u32 = 1024;
/// `u32` words of the depth histogram.
pub const HISTOGRAM_WORDS: usize = (HISTOGRAM_BINS / 32) as usize;

/// A depth as an order-preserving `u32`: the bits of the depth clamped to [0, 1] (NaN → 1, −0 → 0).
#[inline]
pub fn depth_bits(d: f32) -> u32 {
    let d = if d.is_nan() { 1.0 } else { d.clamp(0.0, 1.0) };
    // `+ 0.0` turns −0.0 into +0.0, whose bits are 0.
    (d + 0.0).to_bits()
}

/// The depth a [`depth_bits`] word holds.
#[inline]
pub fn depth_from_bits(bits: u32) -> f32 {
    f32::from_bits(bits)
}

/// Quantizes a straight-alpha linear colour to RGBA8 (round to nearest) and packs it.
#[inline]
pub fn pack_rgba8(c: Vec4) -> u32 {
    let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
    q(c.x) | q(c.y) << 8 | q(c.z) << 16 | q(c.w) << 24
}

/// Unpacks [`pack_rgba8`] to floats in [0, 1].
#[inline]
pub fn unpack_rgba8(p: u32) -> Vec4 {
    let c = |s: u32| ((p >> s) & 0xff) as f32 / 255.0;
    Vec4::new(c(0), c(8), c(16), c(24))
}

/// Unpacks [`pack_rgba8`] to f64 channels in [0, 1] (for the reference).
#[inline]
pub fn unpack_rgba8_f64(p: u32) -> [f64; 4] {
    let c = |s: u32| ((p >> s) & 0xff) as f64 / 255.0;
    [c(0), c(8), c(16), c(24)]
}

/// The 64-bit sort key of a fragment: depth bits above the payload, so integer order is depth
/// order and, among equal depths, payload order (mdts64, dp, ddp, mlp, the depth-mode buckets).
#[inline]
pub fn depth_key64(d: f32, payload: u32) -> u64 {
    (depth_bits(d) as u64) << 32 | payload as u64
}

/// Splits a [`depth_key64`] into (depth, payload).
#[inline]
pub fn split_key64(key: u64) -> (f32, u32) {
    (depth_from_bits((key >> 32) as u32), key as u32)
}

/// Maps `d` into `n` uniform subintervals of [z_near, z_far]: `floor(n·(d − zNear)/(zFar − zNear))`
/// clamped to `0..n` (HPG 2009, eq. 2). An empty or inverted range (zNear ≥ zFar, a pixel with one
/// layer) puts everything in subinterval 0.
#[inline]
pub fn bucket_index(d: f32, z_near: f32, z_far: f32, n: u32) -> u32 {
    let range = z_far - z_near;
    if range.is_nan() || range <= 0.0 || !d.is_finite() {
        return 0;
    }
    let k = ((d - z_near) / range * n as f32).floor();
    if k <= 0.0 { 0 } else { (k as u32).min(n - 1) }
}

/// The depth bdp's colour mode gives the fragment kept in subinterval `k` of `n`: the
/// subinterval's midpoint (the bucket stores a colour, not a depth; the order of buckets is the
/// order of depths, which is all the composite needs).
#[inline]
pub fn bucket_midpoint(k: u32, n: u32, z_near: f32, z_far: f32) -> f32 {
    z_near + (k as f32 + 0.5) / n as f32 * (z_far - z_near)
}

/// The empty min slot of bdp's depth mode (a (min, max) pair of 64-bit depth-above-payload keys
/// per subinterval).
pub const BDP_EMPTY_MIN: u64 = u64::MAX;

/// HPG 2009's eq. 5 for `bdp:P`: may pass p capture a fragment of depth bits `d` in a subinterval
/// where pass p − 1 kept the keys `lo` (its min) and `hi` (its max)? Only strictly between them:
/// what the previous pass kept, or anything outside its range, is done; an empty subinterval
/// (`lo` = [`BDP_EMPTY_MIN`]) has nothing left.
#[inline]
pub fn bdp_eq5_next(d: u32, lo: u64, hi: u64) -> bool {
    lo != BDP_EMPTY_MIN && d > (lo >> 32) as u32 && d < (hi >> 32) as u32
}

/// The adaptive scheme's histogram bin: [`bucket_index`] with 1024 subintervals.
#[inline]
pub fn histogram_bin(d: f32, z_near: f32, z_far: f32) -> u32 {
    bucket_index(d, z_near, z_far, HISTOGRAM_BINS)
}

/// The upper bound `d_{k+1}` of histogram bin `k` (what the paper's equalization stores).
#[inline]
pub fn histogram_upper_bound(k: u32, z_near: f32, z_far: f32) -> f32 {
    z_near + (k + 1) as f32 / HISTOGRAM_BINS as f32 * (z_far - z_near)
}

/// Histogram equalization, as a rank: the number of set bins below `bin`. A fragment in `bin` goes
/// to bucket `rank % 32` of batch `rank / 32`.
///
/// The paper stores the upper bounds of the set bins in order and routes a fragment to the k-th
/// bucket when `EH[k−1] ≤ d < EH[k]`; since both passes compute the bin with the same formula,
/// that search and this rank give the same bucket, without comparing floats.
#[inline]
pub fn histogram_rank(hist: &[u32; HISTOGRAM_WORDS], bin: u32) -> u32 {
    let word = (bin / 32) as usize;
    let below: u32 = hist[..word].iter().map(|w| w.count_ones()).sum();
    let mask = (1u32 << (bin % 32)) - 1;
    below + (hist[word] & mask).count_ones()
}

/// Set bins of a histogram (its depth complexity as the adaptive scheme sees it).
#[inline]
pub fn histogram_count(hist: &[u32; HISTOGRAM_WORDS]) -> u32 {
    hist.iter().map(|w| w.count_ones()).sum()
}

/// The equalized histogram of batch `batch`: the upper bounds of its (at most 32) set bins, in
/// depth order, as the paper's fullscreen equalization pass writes them.
pub fn equalize(hist: &[u32; HISTOGRAM_WORDS], batch: u32, z_near: f32, z_far: f32) -> Vec<f32> {
    (0..HISTOGRAM_BINS)
        .filter(|&k| hist[(k / 32) as usize] >> (k % 32) & 1 == 1)
        .skip(batch as usize * BUCKETS)
        .take(BUCKETS)
        .map(|k| histogram_upper_bound(k, z_near, z_far))
        .collect()
}

/// Packs RGBA8 into a non-negative float's bits, as HPG 2009 section 3.2 does for transparency:
/// alpha scaled to 0..=127 in bits 24..=30 (bit 31, the sign, stays 0), RGB in bits 0..=23.
///
/// MAX on these values keeps the fragment with the largest alpha, then the largest red, green,
/// blue: a collision keeps one fragment, not a mix. With alpha 127 and red ≥ 128 the exponent bits
/// are all ones (the pattern of an infinity or NaN): comparing the bits as `u32` orders them
/// correctly, float MAX blending would not — backends update these buckets with integer MAX.
#[inline]
pub fn bdp_pack_color(rgba8: u32) -> u32 {
    let a = rgba8 >> 24;
    let a7 = (a * 127 + 127) / 255;
    a7 << 24 | (rgba8 & 0x00ff_ffff)
}

/// Inverse of [`bdp_pack_color`]; alpha comes back rounded from 7 bits.
#[inline]
pub fn bdp_unpack_color(packed: u32) -> u32 {
    let a7 = (packed >> 24) & 0x7f;
    let a = (a7 * 255 + 63) / 127;
    a << 24 | (packed & 0x00ff_ffff)
}

/// The most [`bdp_pack_color`] and [`bdp_unpack_color`] move a fragment's alpha: one 8-bit step
/// (`bdp_color_round_trip_every_alpha` checks all 256; 128 alphas come back exact, 0 and 255
/// among them, the other 128 one step off). RGB comes back exact.
pub const BDP_ALPHA_STEPS: u32 = 1;

/// How far bdp's colour mode can put a pixel from the reference, where none of its fragments was
/// lost: at most this much per channel of the linear [0, 1] composite, for `layers` fragments
/// composited. The bound is what the 7-bit alpha allows, not a measurement:
///
/// front to back, the composite is `C = P + T·(α·c + (1 − α)·R)` for the layer of alpha α and
/// colour c, with P and T what the layers in front of it give and R the composite of everything
/// behind it over the background. Moving α alone moves C by `T·(c − R)·Δα`, and `T ≤ 1`,
/// `|c − R| ≤ 1` (colours and background are in [0, 1]). Moving every layer's alpha in turn by at
/// most [`BDP_ALPHA_STEPS`] / 255 moves C at most that much per layer: `layers × 1/255`. With
/// nothing lost the buckets hold the pixel's fragments one each, in depth order, so the alpha is
/// the only difference from the reference. The 8-bit sRGB image turns this into a window of codes
/// around the reference's ([`crate::metrics::packing_window`]), widest where the pixel is dark.
pub fn bdp_color_error_bound(layers: u32) -> f64 {
    f64::from(layers) * f64::from(BDP_ALPHA_STEPS) / 255.0
}

/// Depth resolution of [`mdts_pack`]: depths closer than this may swap order (2⁻²⁰ ≈ 9.5e-7).
pub const MDTS_DEPTH_STEP: f32 = 1.0 / (1u32 << 20) as f32;

/// The 20 depth bits of the mdts packing (Huang et al. 2011, section 3.2): depth remapped into
/// [0.5, 1), where sign and exponent are the same for every value, and its top 20 mantissa bits
/// kept, shifted to bits 12..=31.
#[inline]
pub fn mdts_depth20(d: f32) -> u32 {
    let d = depth_from_bits(depth_bits(d));
    let remapped = (0.5 + 0.5 * d).min(f32::from_bits(0x3f7f_ffff));
    (remapped.to_bits() << 9) & 0xffff_f000
}

/// The two words of the mdts packing: the 20 depth bits above the high 12 bits of RGB, and the
/// same depth bits above the low 12 bits. Both are inserted with atomicMin, one after the other;
/// alpha is not stored (the paper assumes one alpha for the scene).
#[inline]
pub fn mdts_pack(d: f32, rgba8: u32) -> [u32; 2] {
    let depth = mdts_depth20(d);
    let rgb = rgba8 & 0x00ff_ffff;
    [depth | rgb >> 12, depth | (rgb & 0xfff)]
}

/// Recovers (depth, RGB as `r | g << 8 | b << 16`) from the two mdts words of one slot. The depth
/// is the lower end of its 2⁻²⁰ step.
#[inline]
pub fn mdts_unpack(words: [u32; 2]) -> (f32, u32) {
    let mantissa = words[0] >> 12; // the 20 kept bits
    let remapped = f32::from_bits(0x3f00_0000 | mantissa << 3);
    let d = (remapped - 0.5) * 2.0;
    let rgb = (words[0] & 0xfff) << 12 | (words[1] & 0xfff);
    (d, rgb)
}

/// Packs a unit normal into 32 bits (octahedral, 16 bits per axis), for effects that need it
/// beside depth (Fresnel).
#[inline]
pub fn pack_normal(n: Vec3) -> u32 {
    let n = n.normalize_or(Vec3::Z);
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let mut p = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        p = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * Vec2::new(p.x.signum(), p.y.signum());
    }
    let q = |x: f32| ((x.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0 + 0.5) as u32;
    q(p.x) | q(p.y) << 16
}

/// Inverse of [`pack_normal`].
#[inline]
pub fn unpack_normal(p: u32) -> Vec3 {
    let f = |v: u32| (v as f32 / 65535.0) * 2.0 - 1.0;
    let (x, y) = (f(p & 0xffff), f(p >> 16));
    let mut n = Vec3::new(x, y, 1.0 - x.abs() - y.abs());
    if n.z < 0.0 {
        let (ox, oy) = (n.x, n.y);
        n.x = (1.0 - oy.abs()) * ox.signum();
        n.y = (1.0 - ox.abs()) * oy.signum();
    }
    n.normalize_or(Vec3::Z)
}

/// [`unpack_normal`] in f64 (the reference's Fresnel).
#[inline]
pub fn unpack_normal_f64(p: u32) -> DVec3 {
    let f = |v: u32| (v as f64 / 65535.0) * 2.0 - 1.0;
    let (x, y) = (f(p & 0xffff), f(p >> 16));
    let mut n = DVec3::new(x, y, 1.0 - x.abs() - y.abs());
    if n.z < 0.0 {
        let (ox, oy) = (n.x, n.y);
        n.x = (1.0 - oy.abs()) * ox.signum();
        n.y = (1.0 - ox.abs()) * oy.signum();
    }
    n.normalize_or(DVec3::Z)
}

#[cfg(test)]
mod tests {

    #[test]
    fn eq5_keeps_only_what_lies_strictly_between() {
        let key = |d: f32| u64::from(depth_bits(d)) << 32 | 7;
        let (lo, hi) = (key(0.25), key(0.75));
        assert!(bdp_eq5_next(depth_bits(0.5), lo, hi));
        assert!(!bdp_eq5_next(depth_bits(0.25), lo, hi), "the previous min is done");
        assert!(!bdp_eq5_next(depth_bits(0.75), lo, hi), "the previous max is done");
        assert!(!bdp_eq5_next(depth_bits(0.1), lo, hi) && !bdp_eq5_next(depth_bits(0.9), lo, hi));
        assert!(!bdp_eq5_next(depth_bits(0.5), BDP_EMPTY_MIN, hi), "an empty subinterval is done");
    }

    #[test]
    fn midpoints_lie_inside_their_buckets() {
        for n in [16, 32] {
            for k in 0..n {
                let d = bucket_midpoint(k, n, 0.2, 0.6);
                assert_eq!(bucket_index(d, 0.2, 0.6, n), k, "k {k} of {n}");
            }
        }
        assert_eq!(bucket_midpoint(3, 32, 0.5, 0.5), 0.5, "a point range");
    }
    use super::*;

    #[test]
    fn depth_bits_order_and_edges() {
        assert_eq!(depth_bits(0.0), 0);
        assert_eq!(depth_bits(-0.0), 0);
        assert_eq!(depth_bits(-1.0), 0);
        assert_eq!(depth_bits(1.0), 1.0f32.to_bits());
        assert_eq!(depth_bits(2.0), 1.0f32.to_bits());
        assert_eq!(depth_bits(f32::NAN), 1.0f32.to_bits());
        let ds = [0.0f32, 1e-30, 1e-7, 0.1, 0.5, 0.9999999, 1.0];
        for w in ds.windows(2) {
            assert!(depth_bits(w[0]) < depth_bits(w[1]));
        }
    }

    #[test]
    fn bucket_index_edges() {
        assert_eq!(bucket_index(0.0, 0.0, 1.0, 16), 0);
        assert_eq!(bucket_index(1.0, 0.0, 1.0, 16), 15);
        assert_eq!(bucket_index(0.5, 0.5, 0.5, 16), 0);
        assert_eq!(bucket_index(0.4, 0.5, 0.6, 16), 0);
        assert_eq!(bucket_index(0.7, 0.5, 0.6, 16), 15);
        assert_eq!(bucket_index(0.55, 0.5, 0.6, 16), 8);
        assert_eq!(histogram_bin(1.0, 0.0, 1.0), 1023);
    }

    #[test]
    fn rank_matches_equalized_search() {
        let mut hist = [0u32; HISTOGRAM_WORDS];
        for bin in [2u32, 8, 9, 1022, 40, 700] {
            hist[(bin / 32) as usize] |= 1 << (bin % 32);
        }
        let (zn, zf) = (0.2, 0.7);
        let eh = equalize(&hist, 0, zn, zf);
        assert_eq!(eh.len(), 6);
        for bin in [2u32, 8, 9, 40, 700, 1022] {
            let d = zn + (bin as f32 + 0.5) / 1024.0 * (zf - zn);
            let b = histogram_bin(d, zn, zf);
            assert_eq!(b, bin);
            // the paper's search: the first upper bound above d
            let search = eh.iter().position(|&ub| d < ub).unwrap() as u32;
            assert_eq!(histogram_rank(&hist, b), search);
        }
    }

    const RGBS: [u32; 8] = [0x000000, 0xffffff, 0x123456, 0xff0000, 0x00ff00, 0x0000ff, 0x80807f, 0xfedcba];

    #[test]
    fn bdp_color_round_trip_every_alpha() {
        for a in 0..=255u32 {
            for rgb in RGBS {
                let c = rgb | a << 24;
                let packed = bdp_pack_color(c);
                assert_eq!(packed >> 31, 0, "sign bit clear: a non-negative float");
                let back = bdp_unpack_color(packed);
                assert_eq!(back & 0xffffff, rgb, "RGB exact");
                // 7-bit alpha: within one 8-bit step
                assert!((back >> 24).abs_diff(a) <= BDP_ALPHA_STEPS, "alpha {a} -> {}", back >> 24);
            }
        }
        // the alphas that come back exact: half of them, 0 and 255 among them (Stats::quantized's
        // doc and BDP_ALPHA_STEPS say so)
        let exact: Vec<u32> =
            (0..=255u32).filter(|&a| bdp_unpack_color(bdp_pack_color(a << 24)) >> 24 == a).collect();
        assert_eq!(exact.len(), 128);
        assert!(exact.contains(&0) && exact.contains(&255) && exact.contains(&64) && !exact.contains(&51));
        // MAX keeps the most opaque fragment first: packing is monotone in alpha
        for a in 1..=255u32 {
            assert!(
                bdp_pack_color(a << 24) >= bdp_pack_color((a - 1) << 24 | 0xffffff)
                    || (a * 127 + 127) / 255 == ((a - 1) * 127 + 127) / 255
            );
        }
    }

    #[test]
    fn mdts_round_trip_and_order() {
        for a in [0u32, 1, 127, 128, 255] {
            for rgb in RGBS {
                for d in [0.0f32, 0.25, 0.5, 0.999, 1.0] {
                    let words = mdts_pack(d, rgb | a << 24);
                    let (d2, rgb2) = mdts_unpack(words);
                    assert_eq!(rgb2, rgb, "RGB survives the 12 + 12 split");
                    assert!(d2 <= d && d - d2 <= MDTS_DEPTH_STEP * 1.0001, "{d} -> {d2}");
                    assert_eq!(
                        words[0] & 0xffff_f000,
                        words[1] & 0xffff_f000,
                        "both words share the depth bits"
                    );
                }
            }
        }
    }

    /// The smallest depth gap that always keeps order in the 20-bit mdts packing: found by search,
    /// and it is [`MDTS_DEPTH_STEP`] = 2⁻²⁰ (as the module docs state).
    #[test]
    fn mdts_smallest_ordered_gap() {
        let keeps_order = |gap: f32| {
            (0..20_000).all(|i| {
                let d = i as f32 / 20_000.0 * (1.0 - gap);
                mdts_depth20(d) < mdts_depth20(d + gap)
            })
        };
        let mut gap = 1e-3f32;
        while keeps_order(gap * 0.5) {
            gap *= 0.5;
        }
        // refine between gap/2 (fails) and gap (holds)
        let (mut lo, mut hi) = (gap * 0.5, gap);
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if keeps_order(mid) { hi = mid } else { lo = mid }
        }
        assert!((MDTS_DEPTH_STEP * 0.99..=MDTS_DEPTH_STEP * 1.01).contains(&hi), "smallest gap {hi}");
        assert!(!keeps_order(MDTS_DEPTH_STEP * 0.5));
    }

    #[test]
    fn normals_round_trip() {
        for n in [
            Vec3::X,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(1.0, -2.0, -0.5).normalize(),
            Vec3::new(-0.3, 0.2, 0.9).normalize(),
        ] {
            let back = unpack_normal(pack_normal(n));
            assert!((back - n).length() < 1e-3, "{n} -> {back}");
            let back64 = unpack_normal_f64(pack_normal(n));
            assert!((back64.as_vec3() - back).length() < 1e-6, "{n} -> {back64}");
        }
    }
}
