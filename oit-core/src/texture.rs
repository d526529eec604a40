//! Base-colour textures: the image, its mip chain and the one sampler every path uses.
//!
//! A fragment of a textured object takes the material's factor times a sample of its texture
//! ([`crate::setup::TriangleSetup::color_at`]). The sampler is written so that a GPU compute
//! port (WGSL) gets the same bits: the only float operations are one multiply by the level's
//! size in 1/256 texel and a `floor`, both exact or correctly rounded on every IEEE device; the
//! rest is integer arithmetic on 8-bit texels and one table look-up.
//!
//! - **Texel space.** `u·(width·256)` rounded to f32, floored: the coordinate in 1/256 texel with
//!   texel `i`'s centre at `256·i + 128`. Less the half texel, its top bits are the left texel
//!   `i0` and its low 8 bits the weight `f` of the right one (`i0 + 1`); the same in v.
//! - **Wrap** ([`Wrap`], glTF's names) maps each of `i0`, `i0 + 1` into the level.
//! - **Filter.** Per channel, on the 8-bit values as stored (RGB sRGB-encoded, A linear):
//!   `top = t00·(256 − fx) + t10·fx`, `bottom = t01·(256 − fx) + t11·fx`,
//!   `v = (top·(256 − fy) + bottom·fy + 2¹⁵) >> 16`, an 8-bit value again (round half up).
//! - **Decode.** RGB through [`srgb_to_linear`] (256 f32 entries), A as `v / 255`.
//!
//! Filtering the encoded values (what a GPU's `*_SRGB` format does not do, but what an 8-bit
//! integer filter a port can match bit for bit must do) differs from filtering in linear light
//! only between texels of different brightness, by less than the sRGB curve's bend over one
//! texel step.
//!
//! Level of detail: one per triangle, chosen at setup ([`level_for`]) from the ratio of the texels
//! its uv triangle covers at level 0 to the pixels its screen triangle covers: level `k` where
//! `4ᵏ ≤ ratio < 4ᵏ⁺¹` (so one texel of level k a pixel, about), clamped to the chain. A triangle
//! never changes level across its pixels, so its fragments need no derivatives, which a compute
//! rasterizer does not have.
//!
//! The mip chain is built once, when the texture is made ([`Texture::new`]), by an integer box
//! filter ([`downsample`]).

use std::sync::{Arc, OnceLock};

use glam::{Vec2, Vec4};

use crate::OitError;

/// How a coordinate outside [0, 1] maps into the image, per axis (glTF's sampler `wrapS` /
/// `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles the plane (glTF's `REPEAT`, the default).
    #[default]
    Repeat,
    /// The image tiles the plane, every other copy mirrored (`MIRRORED_REPEAT`).
    MirroredRepeat,
    /// The edge texels extend outward (`CLAMP_TO_EDGE`).
    ClampToEdge,
}

impl Wrap {
    /// Texel index `i` of a level `n` texels wide, wrapped into `0..n`.
    #[inline]
    pub fn apply(self, i: i32, n: u32) -> u32 {
        // inside the level every mode gives `i`: most taps, and no division
        if (i as u32) < n {
            return i as u32;
        }
        let n = n as i32;
        match self {
            Wrap::Repeat => i.rem_euclid(n) as u32,
            Wrap::ClampToEdge => i.clamp(0, n - 1) as u32,
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                (if m < n { m } else { 2 * n - 1 - m }) as u32
            }
        }
    }
}

/// One level of a mip chain: `width × height` texels, row by row from v = 0.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// RGB sRGB-encoded, A linear, row-major.
    pub texels: Vec<[u8; 4]>,
}

/// A base-colour texture: an RGBA8 image (RGB sRGB-encoded, A linear, as glTF's base-colour
/// texture is), how it wraps, and its mip chain. Made by [`Texture::new`], which checks the size
/// and builds the chain once; the levels are shared by every clone (a frame's setup clones the
/// scene's textures).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// A name, for messages.
    pub name: String,
    /// How u and v wrap.
    pub wrap: [Wrap; 2],
    /// Level 0 (the image) to the last (1×1).
    levels: Arc<[Level]>,
}

impl Texture {
    /// The largest side a texture may have: 16384 texels, what every GPU oit runs on samples
    /// (Vulkan guarantees 4096; desktop GPUs give 16384 or more), and 1 GiB of RGBA8 at most.
    pub const MAX_SIDE: u32 = 16384;

    /// A texture of `width × height` texels (row-major from v = 0), wrapping as `wrap` says, with
    /// its mip chain built. Refuses, by the texture's name, a side of zero or over
    /// [`Texture::MAX_SIDE`] and a texel count that is not `width × height`.
    pub fn new(
        name: impl Into<String>,
        width: u32,
        height: u32,
        texels: Vec<[u8; 4]>,
        wrap: [Wrap; 2],
    ) -> Result<Texture, OitError> {
        let name = name.into();
        if width == 0 || height == 0 || width > Texture::MAX_SIDE || height > Texture::MAX_SIDE {
            return Err(OitError::InvalidScene(format!(
                "texture '{name}' is {width}×{height}: each side must be 1 to {}",
                Texture::MAX_SIDE
            )));
        }
        if texels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(OitError::InvalidScene(format!(
                "texture '{name}' has {} texels for {width}×{height}",
                texels.len()
            )));
        }
        let mut levels = vec![Level { width, height, texels }];
        while let Some(last) = levels.last()
            && (last.width > 1 || last.height > 1)
        {
            let next = downsample(last);
            levels.push(next);
        }
        Ok(Texture { name, wrap, levels: levels.into() })
    }

    /// Level 0's width.
    pub fn width(&self) -> u32 {
        self.levels[0].width
    }

    /// Level 0's height.
    pub fn height(&self) -> u32 {
        self.levels[0].height
    }

    /// Level 0's texels.
    pub fn texels(&self) -> &[[u8; 4]] {
        &self.levels[0].texels
    }

    /// The mip chain, level 0 first, down to 1×1: `⌊log2(max side)⌋ + 1` levels.
    pub fn mips(&self) -> &[Level] {
        &self.levels
    }

    /// The number of levels.
    pub fn level_count(&self) -> u32 {
        self.levels.len() as u32
    }

    /// Level `level` of the chain, clamped to its last (the level a sample of `level` reads).
    #[inline]
    pub fn level(&self, level: u32) -> &Level {
        &self.levels[(level as usize).min(self.levels.len() - 1)]
    }

    /// The filtered 8-bit RGBA of level `level` (clamped to the chain) at `uv`, before decoding
    /// (the module's rule).
    #[inline]
    pub fn sample_rgba8(&self, level: u32, uv: Vec2) -> [u8; 4] {
        let taps = self.taps(level, uv);
        std::array::from_fn(|c| taps.channel(c))
    }

    /// [`Texture::sample_rgba8`]'s alpha alone, the same bits: what an alpha test needs.
    #[inline]
    pub fn sample_alpha8(&self, level: u32, uv: Vec2) -> u8 {
        self.taps(level, uv).channel(3)
    }

    /// The four texels the filter reads at `uv` on level `level` (clamped to the chain), and
    /// their weights.
    #[inline]
    fn taps(&self, level: u32, uv: Vec2) -> Taps {
        let l = self.level(level);
        let (x0, x1, fx) = axis(uv.x, l.width, self.wrap[0]);
        let (y0, y1, fy) = axis(uv.y, l.height, self.wrap[1]);
        let at = |x: u32, y: u32| l.texels[y as usize * l.width as usize + x as usize];
        Taps { texels: [at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1)], fx, fy }
    }

    /// The sample of level `level` at `uv`, linear RGBA: [`Texture::sample_rgba8`], RGB decoded
    /// by [`srgb_to_linear`], A divided by 255.
    #[inline]
    pub fn sample(&self, level: u32, uv: Vec2) -> Vec4 {
        decode(self.sample_rgba8(level, uv))
    }
}

/// The four texels of a bilinear sample (top left, top right, bottom left, bottom right) and the
/// right and bottom ones' weights in 1/256.
struct Taps {
    texels: [[u8; 4]; 4],
    fx: u32,
    fy: u32,
}

impl Taps {
    /// Channel `c` filtered: rows first, then columns, rounded half up once.
    #[inline]
    fn channel(&self, c: usize) -> u8 {
        let [t00, t10, t01, t11] = self.texels.map(|t| u32::from(t[c]));
        let (fx, fy) = (self.fx, self.fy);
        let top = t00 * (256 - fx) + t10 * fx;
        let bottom = t01 * (256 - fx) + t11 * fx;
        ((top * (256 - fy) + bottom * fy + (1 << 15)) >> 16) as u8
    }
}

/// Linear RGBA of an 8-bit texel: RGB through [`srgb_to_linear`], A / 255.
#[inline]
pub fn decode(c: [u8; 4]) -> Vec4 {
    let t = srgb_to_linear();
    Vec4::new(t[c[0] as usize], t[c[1] as usize], t[c[2] as usize], f32::from(c[3]) / 255.0)
}

/// Clamp of the coordinate in 1/256 texel, before it becomes an integer: ±2³⁰ keeps `i0 + 1`
/// and `2·n` in an i32. A repeating texture has lost its fraction long before (f32 holds 24
/// bits), so nothing of the image is lost that was not already.
const COORD_CLAMP: f32 = (1u32 << 30) as f32;

/// One axis of the sampler: the two texels (wrapped) and the right one's weight in 1/256.
#[inline]
fn axis(u: f32, n: u32, wrap: Wrap) -> (u32, u32, u32) {
    // one rounding (u times an integer below 2^23), then exact operations: clamped (NaN, which
    // validation keeps out, stays NaN and maps to 0 by `as`), then floored in integers, as
    // `f32::floor` is a library call where SSE4.1 is not assumed. The clamp's bounds are integers,
    // so clamping before the floor is clamping after it; below 2^24 the truncated value is exact
    // as an f32, above it `s` is an integer already
    let s = (u * (n * 256) as f32).clamp(-COORD_CLAMP, COORD_CLAMP);
    let t = s as i32;
    let s = t - i32::from(t as f32 > s) - 128;
    let (i0, f) = (s >> 8, (s & 255) as u32);
    (wrap.apply(i0, n), wrap.apply(i0 + 1, n), f)
}

/// sRGB-encoded 8-bit values to linear, the transfer function as written (`c/12.92` up to
/// 0.04045, `((c + 0.055)/1.055)^2.4` above), evaluated in f64 and rounded to f32: the table a
/// port uploads.
pub fn srgb_to_linear() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f64 / 255.0;
            let l = if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) };
            l as f32
        })
    })
}

/// Each sRGB code's linear value in 1/65535, rounded: the box filter's working space. Strictly
/// increasing (the smallest step, near 0, is about 20), so the nearest code to a linear value is
/// found by a search.
fn linear16() -> &'static [u16; 256] {
    static TABLE: OnceLock<[u16; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| (f64::from(srgb_to_linear()[i]) * 65535.0).round() as u16))
}

/// The sRGB code whose [`linear16`] value is nearest to `v` (the lower on a tie).
fn encode16(v: u32) -> u8 {
    let t = linear16();
    let hi = t.partition_point(|&x| u32::from(x) < v).min(255);
    if hi == 0 {
        return 0;
    }
    let (a, b) = (u32::from(t[hi - 1]), u32::from(t[hi]));
    if v - a <= b.saturating_sub(v) { (hi - 1) as u8 } else { hi as u8 }
}

/// The next level of the chain: `max(1, w/2) × max(1, h/2)` (halves rounded down), texel (x, y)
/// the box average of texels (2x, 2y), (2x+1, 2y), (2x, 2y+1), (2x+1, 2y+1) of `l`, each index
/// clamped to `l` (a side of 1 repeats its texel; an odd side's last row or column is left out,
/// as OpenGL's rounding down does). RGB is averaged in linear light, in integers: each code
/// through `linear16`, the sum of four rounded half up, the nearest code back; A (linear
/// already) as `(a + b + c + d + 2) / 4`. Integers throughout: the chain is the same on every
/// host.
pub fn downsample(l: &Level) -> Level {
    let (w, h) = ((l.width / 2).max(1), (l.height / 2).max(1));
    let lin = linear16();
    let mut texels = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        for x in 0..w {
            let at = |dx: u32, dy: u32| {
                let (sx, sy) = ((2 * x + dx).min(l.width - 1), (2 * y + dy).min(l.height - 1));
                l.texels[sy as usize * l.width as usize + sx as usize]
            };
            let four = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
            texels.push(std::array::from_fn(|c| {
                if c == 3 {
                    ((four.iter().map(|t| u32::from(t[3])).sum::<u32>() + 2) / 4) as u8
                } else {
                    encode16((four.iter().map(|t| u32::from(lin[t[c] as usize])).sum::<u32>() + 2) / 4)
                }
            }));
        }
    }
    Level { width: w, height: h, texels }
}

/// The level a triangle samples: `k` where `4ᵏ ≤ ratio < 4ᵏ⁺¹`, clamped to `0..levels`, for
/// `ratio` = the texels its uv triangle covers at level 0 (`texel_area`: the uv area times width
/// times height) over the pixels its screen triangle covers (`pixel_area`). Found by comparing
/// against powers of four, exact in f64 (no logarithm, whose last bit a library may round
/// differently); a ratio below 1, not finite, or of a triangle without area gives level 0.
pub fn level_for(texel_area: f64, pixel_area: f64, levels: u32) -> u32 {
    if pixel_area.is_nan() || pixel_area <= 0.0 || !texel_area.is_finite() {
        return 0;
    }
    let mut k = 0;
    let mut next = 4.0 * pixel_area;
    while k + 1 < levels && texel_area >= next {
        k += 1;
        next *= 4.0;
    }
    k
}

/// The most bytes an image's pixels may take per byte of its encoding: deflate (PNG) expands at
/// most 1,032 times, and a JPEG of one colour less; an image that claims more is refused before
/// its pixels are allocated.
const IMAGE_EXPANSION: u64 = 1100;

/// Decodes `bytes` as an image of `format`, with limits: a side of at most [`Texture::MAX_SIDE`]
/// and pixels of at most [`IMAGE_EXPANSION`] times its bytes, both checked before the pixels are
/// allocated. glTF's images and an OBJ's `map_Kd`/`map_d` textures are decoded here.
pub(crate) fn decode_limited(
    bytes: &[u8],
    format: image::ImageFormat,
    what: &str,
) -> Result<image::DynamicImage, String> {
    let undecoded = |e: image::ImageError| format!("{what} does not decode as {format:?}: {e}");
    let reader = || image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    // the header first: sides and the pixels' size against the bytes, before any is allocated
    let (width, height) = reader().into_dimensions().map_err(undecoded)?;
    let most = (bytes.len() as u64).saturating_mul(IMAGE_EXPANSION).max(1 << 16);
    if width > Texture::MAX_SIDE || height > Texture::MAX_SIDE {
        return Err(format!(
            "{what}: {width} × {height} pixels, over the largest side of a texture ({})",
            Texture::MAX_SIDE
        ));
    }
    if u64::from(width) * u64::from(height) * 4 > most {
        return Err(format!(
            "{what}: {width} × {height} pixels from {} bytes, more than its encoding can hold (refused \
             before its pixels are allocated)",
            bytes.len()
        ));
    }
    let mut reader = reader();
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(Texture::MAX_SIDE);
    limits.max_image_height = Some(Texture::MAX_SIDE);
    limits.max_alloc = Some(most);
    reader.limits(limits);
    reader.decode().map_err(undecoded)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gray(v: u8, a: u8) -> [u8; 4] {
        [v, v, v, a]
    }

    fn tex(w: u32, h: u32, texels: Vec<[u8; 4]>, wrap: Wrap) -> Texture {
        Texture::new("t", w, h, texels, [wrap; 2]).unwrap()
    }

    #[test]
    fn texel_centres_give_the_texel() {
        let texels: Vec<[u8; 4]> = (0..12u8).map(|i| [i * 20, 255 - i * 20, i, i * 7]).collect();
        let t = tex(4, 3, texels.clone(), Wrap::Repeat);
        for y in 0..3 {
            for x in 0..4 {
                let uv = Vec2::new((x as f32 + 0.5) / 4.0, (y as f32 + 0.5) / 3.0);
                assert_eq!(t.sample_rgba8(0, uv), texels[y * 4 + x], "{x},{y}");
                assert_eq!(t.sample(0, uv), decode(texels[y * 4 + x]));
            }
        }
    }

    #[test]
    fn bilinear_midpoints() {
        // 2×1: halfway between the centres is the rounded mean
        let t = tex(2, 1, vec![gray(10, 0), gray(21, 255)], Wrap::ClampToEdge);
        assert_eq!(t.sample_rgba8(0, Vec2::new(0.5, 0.5)), [16, 16, 16, 128]);
        // a quarter of the way: (10·192 + 21·64)/256 = 12.75 → 13
        assert_eq!(t.sample_rgba8(0, Vec2::new(0.375, 0.5)), [13, 13, 13, 64]);
        // 2×2 centre: the mean of four
        let t = tex(2, 2, vec![gray(0, 0), gray(100, 100), gray(200, 200), gray(255, 255)], Wrap::Repeat);
        assert_eq!(t.sample_rgba8(0, Vec2::new(0.5, 0.5)), gray(139, 139));
    }

    #[test]
    fn wrap_modes() {
        let texels = vec![gray(0, 0), gray(100, 100), gray(200, 200), gray(250, 250)];
        let at = |wrap, u: f32| tex(4, 1, texels.clone(), wrap).sample_rgba8(0, Vec2::new(u, 0.5))[0];
        let centre = |i: f32| (i + 0.5) / 4.0;
        // texel −1 and 4
        assert_eq!(at(Wrap::Repeat, centre(-1.0)), 250);
        assert_eq!(at(Wrap::Repeat, centre(4.0)), 0);
        assert_eq!(at(Wrap::Repeat, centre(9.0)), 100);
        assert_eq!(at(Wrap::MirroredRepeat, centre(-1.0)), 0);
        assert_eq!(at(Wrap::MirroredRepeat, centre(4.0)), 250);
        assert_eq!(at(Wrap::MirroredRepeat, centre(5.0)), 200);
        assert_eq!(at(Wrap::MirroredRepeat, centre(-3.0)), 200);
        assert_eq!(at(Wrap::ClampToEdge, centre(-7.0)), 0);
        assert_eq!(at(Wrap::ClampToEdge, centre(40.0)), 250);
        // at u = 0, halfway between texel −1 and 0
        assert_eq!(at(Wrap::Repeat, 0.0), 125);
        assert_eq!(at(Wrap::ClampToEdge, 0.0), 0);
        assert_eq!(at(Wrap::MirroredRepeat, 0.0), 0);
        for (i, w) in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge].into_iter().enumerate() {
            let applied: Vec<u32> = (-5..9).map(|i| w.apply(i, 4)).collect();
            let want: [&[u32]; 3] = [
                &[3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0],
                &[3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0],
                &[0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3],
            ];
            assert_eq!(applied, want[i], "{w:?}");
        }
    }

    #[test]
    fn integer_floor_is_the_float_floor() {
        // the sampler's axis as first written: `floor`, then the clamp, then `as` (the wrap's
        // shortcut inside the level is held by `wrap_modes`' table)
        let by_floor = |u: f32, n: u32, wrap: Wrap| {
            let s = (u * (n * 256) as f32).floor().clamp(-COORD_CLAMP, COORD_CLAMP) as i32 - 128;
            let (i0, f) = (s >> 8, (s & 255) as u32);
            (wrap.apply(i0, n), wrap.apply(i0 + 1, n), f)
        };
        let mut rng = crate::rng::Rng(38);
        let mut us: Vec<f32> = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -0.5,
            1e-30,
            -1e-30,
            3.9999998,
            -3.9999998,
            1e7,
            -1e7,
            1e30,
            -1e30,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        // integers and their neighbours around 2^23 and 2^24 texel units, and values spread over
        // every exponent
        for k in [1u32 << 22, 1 << 23, 1 << 24, 1 << 25] {
            for d in [-1.0f32, 0.0, 1.0] {
                let v = k as f32 + d;
                us.extend([v / 256.0, -v / 256.0, f32::from_bits(v.to_bits() + 1) / 256.0]);
            }
        }
        for _ in 0..200_000 {
            us.push(f32::from_bits((rng.next_u64() >> 32) as u32));
            us.push((rng.next_f32() - 0.5) * 64.0);
        }
        for n in [1, 2, 3, 7, 64, 255, 16384] {
            for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
                for &u in &us {
                    assert_eq!(
                        axis(u, n, wrap),
                        by_floor(u, n, wrap),
                        "u {u:e} ({:#x}), n {n}, {wrap:?}",
                        u.to_bits()
                    );
                }
            }
        }
    }

    #[test]
    fn mip_chain_sizes_and_values() {
        let t = tex(5, 3, vec![gray(200, 40); 15], Wrap::Repeat);
        let sizes: Vec<(u32, u32)> = t.mips().iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(5, 3), (2, 1), (1, 1)]);
        // a flat image stays flat
        assert!(t.mips().iter().all(|l| l.texels.iter().all(|&c| c == gray(200, 40))));
        let t = tex(1, 1, vec![gray(7, 7)], Wrap::Repeat);
        assert_eq!(t.level_count(), 1);
        assert_eq!(tex(16384, 1, vec![gray(0, 0); 16384], Wrap::Repeat).level_count(), 15);
        // black and white average to the linear middle (code 188), not the code middle; alpha
        // (linear) to the rounded mean
        let t = tex(2, 2, vec![gray(0, 0), gray(255, 255), gray(255, 255), gray(0, 1)], Wrap::Repeat);
        assert_eq!(t.mips()[1].texels, vec![[188, 188, 188, 128]]);
        assert!((srgb_to_linear()[188] - 0.5).abs() < 0.005);
        // every code survives a flat 2×2 average
        for v in 0..=255u8 {
            let t = tex(2, 2, vec![gray(v, v); 4], Wrap::Repeat);
            assert_eq!(t.mips()[1].texels[0], gray(v, v));
        }
    }

    #[test]
    fn level_selection() {
        // a quad of 64×64 texels on 64×64 pixels: level 0; on 32×32 (ratio 4): 1; just under
        // 4: 0; on 1 pixel: the last level
        assert_eq!(level_for(4096.0, 4096.0, 7), 0);
        assert_eq!(level_for(4096.0, 1024.0, 7), 1);
        assert_eq!(level_for(4095.0, 1024.0, 7), 0);
        assert_eq!(level_for(4096.0, 256.0, 7), 2);
        assert_eq!(level_for(4096.0, 1.0, 7), 6);
        assert_eq!(level_for(4096.0, 1e-9, 7), 6);
        // magnified, degenerate, not finite
        assert_eq!(level_for(1.0, 4096.0, 7), 0);
        assert_eq!(level_for(0.0, 0.0, 7), 0);
        assert_eq!(level_for(f64::NAN, 1.0, 7), 0);
        assert_eq!(level_for(f64::INFINITY, 1.0, 7), 0);
    }

    #[test]
    fn sizes_are_checked() {
        for (w, h, n) in [(0, 4, 0), (4, 0, 0), (16385, 1, 16385), (2, 2, 3)] {
            let e = Texture::new("bad", w, h, vec![[0; 4]; n], [Wrap::Repeat; 2]).unwrap_err();
            assert!(e.to_string().contains("'bad'"), "{e}");
        }
    }

    #[test]
    fn srgb_table_ends() {
        let t = srgb_to_linear();
        assert_eq!(t[0], 0.0);
        assert_eq!(t[255], 1.0);
        assert!(t.windows(2).all(|w| w[0] < w[1]));
        assert!(linear16().windows(2).all(|w| w[0] < w[1]));
        for v in 0..=255u8 {
            assert_eq!(encode16(u32::from(linear16()[v as usize])), v);
        }
    }
}
