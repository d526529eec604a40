//! Triangle setup, the part of rasterization every backend shares: vertex transform, clipping,
//! perspective divide, viewport, fixed-point snapping, bounding boxes, and the formulas that turn
//! a covered pixel's edge functions into a [`Fragment`].
//!
//! Contract (Vulkan's rules, written so a GPU compute rasterizer can copy them line for line, as
//! oit-wgpu's `setup.wgsl` does, every float operation in the order written here and rounded as
//! here, into [`TriangleSetup::triangle_words`]' layout; the traversal that visits covered pixels
//! is each backend's own):
//! - clipping in homogeneous space against near (`z ≥ 0`), far (`z ≤ w`) and a guard band
//!   (`|x|, |y| ≤ GUARD_BAND·w`) that keeps the fixed-point coordinates in range; a clipped
//!   polygon is fan-triangulated and every piece keeps the original primitive id;
//! - viewport `x = (ndc.x·0.5 + 0.5)·width`, `y = (1 − (ndc.y·0.5 + 0.5))·height` (row 0 at the
//!   top, as in wgpu), snapped to [`SUBPIXEL_BITS`] fractional bits by `floor(v·256 + 0.5)`;
//! - a frame that is a window of a larger one (`Settings::region`, a screen tile) snaps in the
//!   full frame's viewport and subtracts the window's origin from the snapped coordinates (an
//!   exact integer shift: its fragments are the full frame's there, bit for bit); bounding boxes
//!   are clamped to the window;
//! - coverage at pixel centres by 64-bit integer edge functions ([`edge`]) with the top-left fill
//!   rule; zero-area triangles are dropped here, and so are a single-sided object's back faces,
//!   told by the sign of the same snapped area ([`back_face_sign`]); with several samples a
//!   pixel (`Settings::samples`, [`crate::msaa`]) the same functions and rule at each sample
//!   position ([`sample_mask`]), the boxes sized by the samples' reach;
//! - depth: NDC z interpolated linearly in screen space with barycentrics from the edge functions,
//!   clamped to [0, 1]; normal and vertex colour perspective-correct (barycentrics weighted by
//!   1/w); colour from [`Shading::shade`] ([`TriangleSetup::fragment`]);
//! - a textured object's triangles carry their texture coordinates (perspective-correct, as the
//!   vertex colours) and one level of detail each ([`crate::texture::level_for`]: the texels its
//!   uv triangle covers over the pixels it covers, after clipping and snapping); a fragment's
//!   base colour and vertex colour are multiplied by the texture's sample
//!   ([`crate::Texture::sample`]) before shading.
//!
//! Setup runs in parallel over chunks of triangles with the `rayon` feature, serially without;
//! the triangles come out in primitive order either way.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
#[cfg(feature = "rayon")]
use rayon::prelude::*;
use wide::{CmpGt, CmpLt, f32x8};

use crate::{Aabb, AlphaMode, Camera, MAX_SIZE, Scene, Settings, Shading, Texture};

/// Fractional bits of the snapped screen coordinates (Vulkan's minimum, and what GPUs use).
pub const SUBPIXEL_BITS: u32 = 8;
/// Guard band, in units of w: geometry beyond `|x|, |y| = GUARD_BAND·w` is clipped. At
/// [`MAX_SIZE`] pixels a side this keeps snapped coordinates within ±2^28, so edge functions (a
/// difference of products of coordinate differences) stay below 2^60 in an `i64`.
pub const GUARD_BAND: f32 = 64.0;
/// 32-bit words per triangle in [`TriangleSetup::triangle_words`].
pub const TRIANGLE_WORDS: usize = 44;

/// One pixel in sub-pixel units.
pub const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel in sub-pixel units: pixel k's centre is at `k·SUBPIXEL + HALF_PIXEL`.
pub const HALF_PIXEL: i64 = SUBPIXEL / 2;
/// Snapped coordinates beyond this are rejected (never reached within the guard band; a guard
/// against overflow should the float math go astray).
const COORD_LIMIT: f32 = (1u32 << 29) as f32;
/// Triangles per task of the setup.
const SETUP_CHUNK: usize = 1024;

/// Triangles a task of [`TriangleSetup::work_items`] bins: far fewer than a setup chunk, as a
/// large triangle has hundreds of tiles to test.
const ITEM_CHUNK: usize = 64;

/// [`Triangle::texture`] of a triangle without one.
pub const NO_TEXTURE: u32 = u32::MAX;

/// Fragments [`TriangleSetup::colors_at`] and [`headlight_colors`] shade at once.
pub const SHADE_LANES: usize = 8;

/// What the headlight shading of a fragment reads of its triangle, in one 64-byte line: a pass
/// that shades every fragment reads this instead of the triangle's three lines (a bunny pass is
/// bound by the memory it touches more than by its arithmetic).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
pub struct ShadeRecord {
    /// [`Triangle::inv_w`].
    pub inv_w: [f32; 3],
    /// [`Triangle::normal`], vertex by vertex.
    pub normal: [[f32; 3]; 3],
    /// [`Triangle::base`].
    pub base: Vec4,
}

impl ShadeRecord {
    /// The record of `t`.
    #[inline]
    pub fn new(t: &Triangle) -> ShadeRecord {
        ShadeRecord { inv_w: t.inv_w, normal: t.normal.map(|n| n.to_array()), base: t.base }
    }
}

/// [`TriangleSetup::color_at`] under [`Shading::Headlight`] for [`SHADE_LANES`] fragments at
/// once, bit for bit: lane `i` is the colour of the fragment of the triangle of `records[i]`
/// with barycentrics `b[i]`, lit from `forward`.
///
/// A fragment's shaded colour is a chain of dependent operations (two divisions and a square
/// root among them) too long for one fragment's worth of independent work to hide. Here each
/// step runs for every lane before the next (structure of arrays), each lane the very IEEE
/// operations of [`TriangleSetup::color_at`] in its order: a vector division, square root or
/// product rounds each lane as the scalar one does, and Rust contracts nothing into fused
/// multiply-adds, so the compiler may run the lanes in vector registers and the bits stay.
#[inline]
pub fn headlight_colors(
    records: [&ShadeRecord; SHADE_LANES],
    b: [[f32; 3]; SHADE_LANES],
    forward: Vec3,
) -> [Vec4; SHADE_LANES] {
    const N: usize = SHADE_LANES;
    #[inline(always)]
    fn gather(records: &[&ShadeRecord; SHADE_LANES], value: impl Fn(&ShadeRecord) -> f32) -> f32x8 {
        f32x8::new(std::array::from_fn(|i| value(records[i])))
    }
    let bs: [f32x8; 3] = std::array::from_fn(|k| f32x8::new(b.map(|b| b[k])));
    let iw: [f32x8; 3] = std::array::from_fn(|k| gather(&records, |r| r.inv_w[k]));
    // perspective(): q = b·(1/w), normalized by their sum ((q0 + q1) + q2)
    let q: [f32x8; 3] = std::array::from_fn(|k| bs[k] * iw[k]);
    let inv_q = f32x8::splat(1.0) / (q[0] + q[1] + q[2]);
    let p: [f32x8; 3] = q.map(|q| q * inv_q);
    // interpolated_normal(): n0·p0 + n1·p1 + n2·p2, per component
    let n: [f32x8; 3] = std::array::from_fn(|c| {
        gather(&records, |r| r.normal[0][c]) * p[0]
            + gather(&records, |r| r.normal[1][c]) * p[1]
            + gather(&records, |r| r.normal[2][c]) * p[2]
    });
    // Shading::shade(): normalize_or_zero (1 / sqrt of the dot product, used where it is finite
    // and positive, else the zero vector), then base · (0.3 + 0.7·|n·forward|), clamped to [0, 1]
    let zero = f32x8::splat(0.0);
    let rcp = f32x8::splat(1.0) / (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let unit = rcp.is_finite() & rcp.cmp_gt(zero);
    let u = n.map(|n| unit.blend(n * rcp, zero));
    let along =
        u[0] * f32x8::splat(forward.x) + u[1] * f32x8::splat(forward.y) + u[2] * f32x8::splat(forward.z);
    let light = f32x8::splat(0.3) + f32x8::splat(0.7) * along.abs();
    // glam's Vec3::clamp: the larger by `>` with 0, then the smaller by `<` with 1
    let clamp = |v: f32x8| {
        let v = v.cmp_gt(zero).blend(v, zero);
        v.cmp_lt(f32x8::splat(1.0)).blend(v, f32x8::splat(1.0))
    };
    let rgb: [[f32; N]; 3] =
        std::array::from_fn(|c| clamp(gather(&records, |r| r.base[c]) * light).to_array());
    std::array::from_fn(|i| Vec4::new(rgb[0][i], rgb[1][i], rgb[2][i], records[i].base.w.clamp(0.0, 1.0)))
}

/// One covered (pixel, triangle) pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// `y·width + x`, row `y = 0` at the top.
    pub pixel: u32,
    /// NDC z in [0, 1].
    pub depth: f32,
    /// Primitive id: `scene.primitive_bases().0[instance] + triangle index`.
    pub prim: u32,
    /// Shaded colour, straight-alpha linear RGBA.
    pub color: Vec4,
    /// Interpolated world-space normal, normalized (zero where the mesh has none).
    pub normal: Vec3,
}

/// A triangle after setup: snapped screen coordinates (positive orientation), what its fragments
/// interpolate, and the pixels it may cover.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Snapped x, in 1/256 pixel.
    pub x: [i32; 3],
    /// Snapped y, in 1/256 pixel.
    pub y: [i32; 3],
    /// NDC z of each vertex.
    pub z: [f32; 3],
    /// 1/w of each vertex.
    pub inv_w: [f32; 3],
    /// World normal of each vertex.
    pub normal: [Vec3; 3],
    /// Vertex colour of each vertex (meaningful when `has_color`).
    pub color: [Vec3; 3],
    /// 1 / (twice the area in 1/256² pixel units), for the barycentrics.
    pub inv_area: f32,
    /// Material colour (alpha override applied).
    pub base: Vec4,
    /// Whether the mesh has vertex colours.
    pub has_color: bool,
    /// Primitive id.
    pub prim: u32,
    /// Inclusive pixel box clamped to the viewport: x0, y0, x1, y1.
    pub bbox: [u32; 4],
    /// Texture coordinates of each vertex (meaningful where `texture` is one).
    pub uv: [Vec2; 3],
    /// Index into [`TriangleSetup::textures`], or [`NO_TEXTURE`].
    pub texture: u32,
    /// The mip level its fragments sample ([`crate::texture::level_for`]).
    pub lod: u32,
    /// The opaque pass discards a fragment whose alpha is below this: a textured masked
    /// object's cutoff; one half for an untextured masked object, which reaches the pass with
    /// alpha 1 or 0 already ([`crate::Object::effective_alpha`]); 0 (nothing) for any other.
    pub cutoff: f32,
}

/// The triangles of one frame after setup, in primitive order, ready for any number of geometry
/// passes on any backend.
#[derive(Clone, Debug)]
pub struct TriangleSetup {
    /// The set-up triangles.
    pub triangles: Vec<Triangle>,
    /// Viewport width in pixels.
    pub width: u32,
    /// Viewport height in pixels.
    pub height: u32,
    /// The shading the fragments get.
    pub shading: Shading,
    /// The camera's viewing direction (headlight shading).
    pub forward: Vec3,
    /// The textures the triangles sample ([`Triangle::texture`]): the scene's, where any object
    /// it draws is textured, else none (shading then needs no look at a triangle's texture, and
    /// runs in lanes: [`headlight_colors`]).
    pub textures: Vec<Texture>,
}

/// A vertex on its way through clipping: clip-space position and the attributes, which are linear
/// in clip space (that is what makes them perspective-correct after the divide).
#[derive(Clone, Copy, Debug, Default)]
struct ClipVertex {
    pos: Vec4,
    normal: Vec3,
    color: Vec3,
    uv: Vec2,
}

impl ClipVertex {
    fn toward(self, other: ClipVertex, t: f32) -> ClipVertex {
        ClipVertex {
            pos: self.pos + (other.pos - self.pos) * t,
            normal: self.normal + (other.normal - self.normal) * t,
            color: self.color + (other.color - self.color) * t,
            uv: self.uv + (other.uv - self.uv) * t,
        }
    }
}

const CLIP_PLANES: usize = 6;
/// Each plane adds at most one vertex to a convex polygon.
const MAX_POLYGON: usize = 3 + CLIP_PLANES;

/// Signed distance of `p` to clip plane `plane` (inside when ≥ 0): near, far, then the guard band.
fn plane_distance(p: Vec4, plane: usize) -> f32 {
    match plane {
        0 => p.z,
        1 => p.w - p.z,
        2 => GUARD_BAND * p.w - p.x,
        3 => GUARD_BAND * p.w + p.x,
        4 => GUARD_BAND * p.w - p.y,
        _ => GUARD_BAND * p.w + p.y,
    }
}

/// [`outcode`]'s bit for a position with a coordinate that is not finite.
const NOT_FINITE: u8 = 1 << 7;

/// Bit `plane` set for each clip plane `p` lies outside of ([`plane_distance`] below 0), or
/// [`NOT_FINITE`] alone.
#[inline]
fn outcode(p: Vec4) -> u8 {
    if !p.is_finite() {
        return NOT_FINITE;
    }
    (0..CLIP_PLANES).fold(0, |code, plane| code | u8::from(plane_distance(p, plane) < 0.0) << plane)
}

/// A convex polygon of at most [`MAX_POLYGON`] vertices.
#[derive(Clone, Copy)]
struct Polygon {
    v: [ClipVertex; MAX_POLYGON],
    n: usize,
}

impl Polygon {
    fn push(&mut self, v: ClipVertex) {
        if self.n < MAX_POLYGON {
            self.v[self.n] = v;
            self.n += 1;
        }
    }
}

/// Sutherland–Hodgman against the planes in `planes` (a bit mask).
fn clip(tri: [ClipVertex; 3], planes: u32) -> Polygon {
    let mut poly = Polygon { v: [ClipVertex::default(); MAX_POLYGON], n: 3 };
    poly.v[..3].copy_from_slice(&tri);
    for plane in 0..CLIP_PLANES {
        if planes & (1 << plane) == 0 {
            continue;
        }
        let mut out = Polygon { v: [ClipVertex::default(); MAX_POLYGON], n: 0 };
        for i in 0..poly.n {
            let a = poly.v[i];
            let b = poly.v[(i + 1) % poly.n];
            let (da, db) = (plane_distance(a.pos, plane), plane_distance(b.pos, plane));
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                // Cut from the inside end, so an edge shared by two triangles is cut at the same
                // point whichever way round each walks it (no crack at the near plane).
                let (inside, outside, di, dout) = if da >= 0.0 { (a, b, da, db) } else { (b, a, db, da) };
                out.push(inside.toward(outside, di / (di - dout)));
            }
        }
        poly = out;
        if poly.n < 3 {
            return poly;
        }
    }
    poly
}

/// What setup gives every triangle of an instance from its object.
#[derive(Clone, Copy, Debug)]
struct Material {
    /// [`Triangle::base`].
    base: Vec4,
    /// [`Triangle::has_color`].
    has_color: bool,
    /// [`Triangle::texture`].
    texture: u32,
    /// The texture's level 0 texel count (width × height), for the level of detail.
    texels: f64,
    /// The texture's mip levels.
    levels: u32,
    /// [`Triangle::cutoff`].
    cutoff: f32,
    /// The sign of the snapped area of the triangles dropped as back faces: 0 (none), 1 or −1
    /// ([`back_face_sign`]).
    cull: i64,
}

impl Material {
    /// Untextured, never discarded, drawn from both sides.
    fn plain(base: Vec4, has_color: bool) -> Material {
        Material { base, has_color, texture: NO_TEXTURE, texels: 0.0, levels: 1, cutoff: 0.0, cull: 0 }
    }
}

/// Which triangles of an instance of `object` placed by `transform` are back faces, dropped
/// before they make a fragment: 0 for a double-sided object (none); else the sign of the
/// snapped area (`Snap`'s `(x1 − x0)(y2 − y0) − (y1 − y0)(x2 − x0)`, in the rasterizer's
/// fixed-point pixel coordinates, rows down) that a back face has. glTF's front is
/// counter-clockwise in NDC (y up), which is clockwise, a negative area, in rows down: the back
/// has sign 1. A transform that mirrors (its 3×3 part's determinant negative) turns the winding
/// over, as glTF says, and the back has sign −1. The compute setup (`setup.wgsl`, flag bits 1 and
/// 2 of `I_FLAGS`) drops by the same sign; the hardware path hands it to its fragment stage
/// (`HwInstance`'s `normal1.w`, [`crate::pulled`]), which drops a fragment by the GPU's
/// `front_facing` (1: a fragment not front-facing; −1: one front-facing).
pub fn back_face_sign(object: &crate::Object, transform: &Mat4) -> i64 {
    if object.double_sided {
        0
    } else if Mat3::from_mat4(*transform).determinant() < 0.0 {
        -1
    } else {
        1
    }
}

/// A vertex in screen space.
#[derive(Clone, Copy, Default)]
struct Projected {
    x: i32,
    y: i32,
    z: f32,
    inv_w: f32,
}

/// What setup needs besides the geometry: the full frame's viewport, which every coordinate is
/// snapped in, and the window of it this frame covers (`Settings::region`; the whole frame when
/// none).
struct Snap {
    /// The full frame's width and height: the viewport transform's.
    width: u32,
    height: u32,
    /// The window's origin in the full frame, in 1/256 pixel: subtracted from the snapped
    /// coordinates, an exact integer shift (edge functions and barycentrics are differences of
    /// coordinates, so they are the full frame's bit for bit).
    origin: (i32, i32),
    /// The window's size: bounding boxes are clamped to it.
    region: (u32, u32),
    /// The smallest and largest offset of a pixel's samples from its top-left corner, in 1/256
    /// pixel ([`reach`]): (128, 128), the centre, with one sample. A triangle's box
    /// holds the pixels whose samples' square it reaches, and a triangle that reaches none is
    /// dropped.
    reach: (i64, i64),
}

impl Snap {
    /// Perspective divide, viewport, snap. `None` for a point that cannot be placed.
    fn project(&self, p: Vec4) -> Option<Projected> {
        if p.w.is_nan() || p.w <= 0.0 {
            return None;
        }
        let inv_w = 1.0 / p.w;
        let (nx, ny, nz) = (p.x * inv_w, p.y * inv_w, p.z * inv_w);
        let fx = (nx * 0.5 + 0.5) * self.width as f32;
        let fy = (1.0 - (ny * 0.5 + 0.5)) * self.height as f32;
        // Round half up, spelled out: `f32::round` rounds half away from zero and WGSL's `round`
        // half to even; this form is the same everywhere.
        let sx = (fx * SUBPIXEL as f32 + 0.5).floor();
        let sy = (fy * SUBPIXEL as f32 + 0.5).floor();
        let in_range = sx.abs() <= COORD_LIMIT && sy.abs() <= COORD_LIMIT;
        if !(in_range && nz.is_finite() && inv_w.is_finite()) {
            return None;
        }
        Some(Projected { x: sx as i32 - self.origin.0, y: sy as i32 - self.origin.1, z: nz, inv_w })
    }

    /// Clips one triangle and appends the pieces that touch the viewport. Its vertices come with
    /// their [`outcode`]s and [`Snap::project`]ions, made once per vertex ([`SetupVertex`]): a
    /// triangle inside every plane is snapped from those (the projection is a function of the
    /// clip-space position alone, so this is what projecting it here would give, bit for bit).
    #[inline]
    fn triangle(&self, out: &mut Vec<Triangle>, v: [&SetupVertex; 3], material: &Material, prim: u32) {
        let any = v[0].code | v[1].code | v[2].code;
        let all = v[0].code & v[1].code & v[2].code;
        // a vertex not finite, or all three outside one plane
        if any & NOT_FINITE != 0 || all != 0 {
            return;
        }
        if any == 0 {
            let [a, b, c] = v;
            if !(a.placed && b.placed && c.placed) {
                return;
            }
            self.snapped(out, [a.projected, b.projected, c.projected], material, prim, |[i, j, k]| {
                let v = [a, b, c];
                (
                    [v[i].normal, v[j].normal, v[k].normal],
                    [v[i].color, v[j].color, v[k].color],
                    [v[i].uv, v[j].uv, v[k].uv],
                )
            });
            return;
        }
        let poly = clip(v.map(SetupVertex::clip_vertex), u32::from(any));
        for i in 1..poly.n.saturating_sub(1) {
            self.piece(out, [poly.v[0], poly.v[i], poly.v[i + 1]], material, prim);
        }
    }

    /// Projects and snaps one (clipped) triangle; keeps it if it has area and touches the viewport.
    fn piece(&self, out: &mut Vec<Triangle>, v: [ClipVertex; 3], material: &Material, prim: u32) {
        let (Some(p0), Some(p1), Some(p2)) =
            (self.project(v[0].pos), self.project(v[1].pos), self.project(v[2].pos))
        else {
            return;
        };
        self.snapped(out, [p0, p1, p2], material, prim, |[i, j, k]| {
            (
                [v[i].normal, v[j].normal, v[k].normal],
                [v[i].color, v[j].color, v[k].color],
                [v[i].uv, v[j].uv, v[k].uv],
            )
        });
    }

    /// [`Snap::piece`] once its vertices are projected (`p`). `attributes(order)` gives the
    /// normals, colours and texture coordinates of the vertices in `order` (indices into `p`); it
    /// is called only for a
    /// triangle that is kept, so a triangle that setup drops (most of a dense mesh far away: no
    /// area, or no pixel centre in its box) never gathers them.
    #[inline]
    fn snapped(
        &self,
        out: &mut Vec<Triangle>,
        mut p: [Projected; 3],
        material: &Material,
        prim: u32,
        attributes: impl FnOnce([usize; 3]) -> ([Vec3; 3], [Vec3; 3], [Vec2; 3]),
    ) {
        let (x0, y0) = (i64::from(p[0].x), i64::from(p[0].y));
        let area = (i64::from(p[1].x) - x0) * (i64::from(p[2].y) - y0)
            - (i64::from(p[1].y) - y0) * (i64::from(p[2].x) - x0);
        // no area, or a single-sided object's back face (the sign of its snapped area)
        if area == 0 || area.signum() == material.cull {
            return;
        }
        // A clockwise triangle is turned round so every edge function is positive inside, which
        // is what the fill rule below assumes.
        let order = if area < 0 {
            p.swap(1, 2);
            [0, 2, 1]
        } else {
            [0, 1, 2]
        };
        let area = area.abs();
        let pixel_range = |lo: i32, hi: i32, size: u32| -> Option<(u32, u32)> {
            // Pixel k's centre is at 256k + 128: the first centre at or after `lo`, the last at or
            // before `hi`. With several samples a pixel (`reach`), the first pixel whose last
            // sample offset is at or after `lo`, the last whose first is at or before `hi`.
            let (near, far) = self.reach;
            let first = (i64::from(lo) - far + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
            let last = (i64::from(hi) - near).div_euclid(SUBPIXEL).min(i64::from(size) - 1);
            (first <= last).then_some((first as u32, last as u32))
        };
        let xs = [p[0].x, p[1].x, p[2].x];
        let ys = [p[0].y, p[1].y, p[2].y];
        let (Some((bx0, bx1)), Some((by0, by1))) = (
            pixel_range(xs[0].min(xs[1]).min(xs[2]), xs[0].max(xs[1]).max(xs[2]), self.region.0),
            pixel_range(ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]), self.region.1),
        ) else {
            return;
        };
        let (normal, color, uv) = attributes(order);
        let lod = if material.texture == NO_TEXTURE {
            0
        } else {
            // texels over pixels: |uv cross| / 2 × texels against area / 2 / 256², in f64 (the
            // product of a uv area and 2^28 texels must not round to anything a port computes
            // differently: it is made here once, for every path)
            let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
            let uv_cross = (f64::from(d1.x) * f64::from(d2.y) - f64::from(d1.y) * f64::from(d2.x)).abs();
            let pixel_area = area as f64 / (SUBPIXEL * SUBPIXEL) as f64;
            crate::texture::level_for(uv_cross * material.texels, pixel_area, material.levels)
        };
        out.push(Triangle {
            x: xs,
            y: ys,
            z: [p[0].z, p[1].z, p[2].z],
            inv_w: [p[0].inv_w, p[1].inv_w, p[2].inv_w],
            normal,
            color,
            inv_area: 1.0 / area as f32,
            base: material.base,
            has_color: material.has_color,
            prim,
            bbox: [bx0, by0, bx1, by1],
            uv,
            texture: material.texture,
            lod,
            cutoff: material.cutoff,
        });
    }

    /// The per-vertex half of setup for one instance: clip-space position, world normal and
    /// vertex colour (zero where the mesh has none), outcode and projection, once per vertex
    /// rather than once per triangle that uses it (about six on a closed mesh).
    fn vertices(&self, out: &mut Vec<SetupVertex>, mvp: &Mat4, normal_matrix: &Mat3, mesh: &crate::Mesh) {
        let colors = mesh.colors.as_deref();
        let uvs = mesh.uvs.as_deref();
        // every slot is written below; growing writes only the new tail first (a frame as large
        // as the last writes each slot once)
        out.resize(mesh.positions.len(), SetupVertex::default());
        // each vertex written into its slot by a loop, so the compiler builds it there: made by a
        // closure and collected, it came back through the stack and was copied again (about a
        // sixth of a frame of grid:4x4:bunny, in stalls reading the copy back)
        let fill = |first: usize, slots: &mut [SetupVertex], positions: &[Vec3]| {
            for (j, (slot, p)) in slots.iter_mut().zip(positions).enumerate() {
                let i = first + j;
                *slot = self.vertex(
                    transform_point(mvp, *p),
                    mesh.normals.get(i).map_or(Vec3::ZERO, |n| transform_normal(normal_matrix, *n)),
                    colors.and_then(|c| c.get(i).copied()).unwrap_or(Vec3::ZERO),
                    uvs.and_then(|c| c.get(i).copied()).unwrap_or(Vec2::ZERO),
                );
            }
        };
        #[cfg(feature = "rayon")]
        if mesh.positions.len() > SETUP_CHUNK {
            out.par_chunks_mut(SETUP_CHUNK)
                .zip(mesh.positions.par_chunks(SETUP_CHUNK))
                .enumerate()
                .for_each(|(c, (slots, positions))| fill(c * SETUP_CHUNK, slots, positions));
            return;
        }
        // one chunk: here, not handed to the pool (see `for_each_chunk`)
        fill(0, out, &mesh.positions);
    }

    /// One vertex's [`SetupVertex`]: its outcode and projection beside its attributes.
    #[inline]
    fn vertex(&self, clip: Vec4, normal: Vec3, color: Vec3, uv: Vec2) -> SetupVertex {
        let projected = self.project(clip);
        SetupVertex {
            clip,
            normal,
            color,
            uv,
            projected: projected.unwrap_or(Projected { x: 0, y: 0, z: 0.0, inv_w: 0.0 }),
            code: outcode(clip),
            placed: projected.is_some(),
        }
    }

    /// Sets up the triangles of one instance, in order, in parallel, from its vertices
    /// ([`Snap::vertices`]), and writes them to `out` from slot `start` on ([`copy_chunks`]);
    /// returns the slot after the last. `chunks` holds each task's triangles on the way (kept
    /// between frames, as `out` is, so a warm setup allocates nothing for them).
    #[allow(clippy::too_many_arguments, reason = "an instance's parts, and the two buffers it fills")]
    fn instance<T: Send, E: RecordSink<T>>(
        &self,
        (out, start, records, record): (
            &mut Vec<Triangle>,
            usize,
            &mut E,
            &(impl Fn(&Triangle) -> T + Sync + Send),
        ),
        chunks: &mut Vec<Vec<Triangle>>,
        vertices: &[SetupVertex],
        indices: &[[u32; 3]],
        material: &Material,
        prim_base: u32,
    ) -> usize {
        let n = indices.len().div_ceil(SETUP_CHUNK);
        if chunks.len() < n {
            chunks.resize_with(n, Vec::new);
        }
        let chunks = &mut chunks[..n];
        for_each_chunk(chunks, indices, SETUP_CHUNK, |c, out, chunk| {
            out.clear();
            let first = prim_base.saturating_add(u32::try_from(c * SETUP_CHUNK).unwrap_or(u32::MAX));
            self.triangles(out, vertices, chunk, material, first);
        });
        copy_chunks(out, start, chunks, records, record)
    }

    /// Sets up the triangles `indices` of one instance's `vertices` ([`Snap::vertices`]),
    /// appending them to `out`; the first has primitive id `first`, each next one more.
    fn triangles(
        &self,
        out: &mut Vec<Triangle>,
        vertices: &[SetupVertex],
        indices: &[[u32; 3]],
        material: &Material,
        first: u32,
    ) {
        for (j, tri) in indices.iter().enumerate() {
            let (Some(a), Some(b), Some(c)) =
                (vertices.get(tri[0] as usize), vertices.get(tri[1] as usize), vertices.get(tri[2] as usize))
            else {
                continue;
            };
            let prim = first.saturating_add(j as u32);
            self.triangle(out, [a, b, c], material, prim);
        }
    }
}

/// A vertex after the per-vertex half of setup ([`Snap::vertices`]).
#[derive(Clone, Copy, Default)]
struct SetupVertex {
    clip: Vec4,
    normal: Vec3,
    color: Vec3,
    uv: Vec2,
    /// [`Snap::project`]'s result, meaningful when `placed`.
    projected: Projected,
    code: u8,
    placed: bool,
}

impl SetupVertex {
    fn clip_vertex(&self) -> ClipVertex {
        ClipVertex { pos: self.clip, normal: self.normal, color: self.color, uv: self.uv }
    }
}

/// The normal matrix of `transform`: its inverse transpose (the matrix itself when singular), up
/// to a power-of-two factor, as only the directions it gives matter. The factor brings the largest
/// entry near 1 before inverting, so that a transform scaling by 10⁻²⁰ (determinant 10⁻⁶⁰, 0 in
/// f32) or 10²⁰ inverts as one scaling by 1 does; being a power of two, it changes no bit of a
/// normalized result.
pub fn normal_matrix(transform: &Mat4) -> Mat3 {
    let m = Mat3::from_mat4(*transform);
    let largest = m.to_cols_array().iter().fold(0.0f32, |a, &x| a.max(x.abs()));
    let m = if largest.is_normal() { m * 2f32.powi(-(largest.log2().round() as i32)) } else { m };
    let inv = m.inverse();
    if inv.is_finite() { inv.transpose() } else { m }
}

/// `m · (p, 1)`, spelled out in scalars in the order every port follows (oit-wgpu's setup.wgsl
/// does it in integer f32): per row, `((c0·x + c1·y) + c2·z) + c3·1`, each product rounded
/// before its add (Rust never fuses them). This is what glam's `Mat4 * Vec4` computes on x86_64;
/// written out so the order is this file's, not a library's.
#[inline]
pub fn transform_point(m: &Mat4, p: Vec3) -> Vec4 {
    let (c0, c1, c2, c3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    let row = |r: usize| ((c0[r] * p.x + c1[r] * p.y) + c2[r] * p.z) + c3[r] * 1.0;
    Vec4::new(row(0), row(1), row(2), row(3))
}

/// `m · n` for a normal: per row `(c0·x + c1·y) + c2·z`, as [`transform_point`] spells it.
#[inline]
pub fn transform_normal(m: &Mat3, n: Vec3) -> Vec3 {
    let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
    let row = |r: usize| (c0[r] * n.x + c1[r] * n.y) + c2[r] * n.z;
    Vec3::new(row(0), row(1), row(2))
}

/// The eight world-space corners of a mesh's bounding box under `transform` (`Aabb::corners`
/// order, the vertices `Aabb::TRIANGLES` indexes) and their normals, pointing out from the box's
/// centre: the geometry of [`TriangleSetup::bounding_boxes`].
pub fn box_vertices(mesh_bounds: &Aabb, transform: &Mat4) -> ([Vec3; 8], [Vec3; 8]) {
    let bounds = mesh_bounds.transformed(transform);
    let corners = bounds.corners();
    (corners, corners.map(|c| (c - bounds.center()).normalize_or_zero()))
}

/// The material an instance's triangles are set up with: its object's colour and mesh colours,
/// the sign of its back faces, its cutoff and its texture (`textures`: the setup's).
fn instance_material(
    object: &crate::Object,
    inst: &crate::Instance,
    mesh: &crate::Mesh,
    settings: &Settings,
    textures: &[crate::Texture],
) -> Material {
    let mut material = Material::plain(settings.material_color(object.color), mesh.colors.is_some());
    material.cull = back_face_sign(object, &inst.transform);
    // an untextured masked object comes with alpha 1 or 0 (Scene::layers), which one half
    // splits whatever the cutoff; a textured one with its factor's alpha, which the
    // texture's multiplies fragment by fragment
    if let AlphaMode::Mask { cutoff } = object.alpha_mode {
        material.cutoff = if object.texture.is_some() { cutoff } else { 0.5 };
    }
    if let Some((t, texture)) = object.texture.and_then(|t| Some(t).zip(textures.get(t))) {
        material.texture = u32::try_from(t).unwrap_or(NO_TEXTURE);
        material.texels = f64::from(texture.width()) * f64::from(texture.height());
        material.levels = texture.level_count();
    }
    material
}

/// Triangles a batch of small instances holds at most, but for one instance that passes it: a
/// task's worth of setup ([`SETUP_CHUNK`]'s quarter, so a few hundred small instances still
/// spread over the cores).
const SMALL_BATCH: usize = SETUP_CHUNK / 4;

/// `run` (small instances: index, primitive base, small) cut into consecutive batches of about
/// [`SMALL_BATCH`] triangles, as ranges of `run`, into `batches` (its storage kept).
fn small_batches<'b>(
    scene: &Scene,
    run: &[(usize, u32, bool)],
    batches: &'b mut Vec<std::ops::Range<usize>>,
) -> &'b [std::ops::Range<usize>] {
    batches.clear();
    let (mut first, mut count) = (0, 0);
    for (k, &(i, _, _)) in run.iter().enumerate() {
        let inst = &scene.instances[i];
        count += scene.meshes[scene.objects[inst.object].mesh].indices.len();
        if count >= SMALL_BATCH {
            batches.push(first..k + 1);
            (first, count) = (k + 1, 0);
        }
    }
    if first < run.len() {
        batches.push(first..run.len());
    }
    batches
}

/// `f(chunk index, out, chunk)` over the chunks of `items` of `size`, each with its own `out`
/// (`outs` has one per chunk): in parallel with the `rayon` feature.
fn for_each_chunk<T: Sync, R: Send>(
    outs: &mut [R],
    items: &[T],
    size: usize,
    f: impl Fn(usize, &mut R, &[T]) + Sync + Send,
) {
    #[cfg(feature = "rayon")]
    if items.len() > size {
        outs.par_iter_mut()
            .zip(items.par_chunks(size))
            .enumerate()
            .for_each(|(c, (out, chunk))| f(c, out, chunk));
        return;
    }
    // one chunk runs on the calling thread: a parallel iterator called from outside the pool
    // hands its work to a pool thread and sleeps until it is done, a round trip that costs more
    // than a small mesh's setup (a scene of hundreds of instances of a few triangles each, as
    // `foliage`, makes three such calls an instance)
    outs.iter_mut().zip(items.chunks(size)).enumerate().for_each(|(c, (out, chunk))| f(c, out, chunk));
}

/// Triangles a task of [`copy_chunks`] copies at most: pieces this size spread a small frame's
/// copy over many cores (a task a chunk left 16 cores waiting on two).
const COPY_PIECE: usize = 256;

/// Writes the chunks' triangles, in chunk order, to `out` from slot `start` on, and the `record`
/// of each to the same slots of `records`; returns the slot after the last. Where both already
/// hold the slots (a frame no larger than one before: a persistent renderer's steady state),
/// each task copies a piece of a chunk straight to its place (disjoint slices of the output), so
/// the copy is spread over every core and each slot written once. Where they must grow, they
/// are extended in parallel instead, item by item from the chunk that holds it (growing by
/// filler and then overwriting would write a fresh setup's storage twice).
fn copy_chunks<T: Send, E: RecordSink<T>>(
    out: &mut Vec<Triangle>,
    start: usize,
    chunks: &[Vec<Triangle>],
    records: &mut E,
    record: &(impl Fn(&Triangle) -> T + Sync + Send),
) -> usize {
    let total: usize = chunks.iter().map(Vec::len).sum();
    let end = start + total;
    if total <= COPY_PIECE {
        // one task's worth: here, not handed to the pool (see `for_each_chunk`)
        out.truncate(start);
        records.truncate(start);
        for c in chunks {
            out.extend_from_slice(c);
            for t in c {
                records.push(record(t));
            }
        }
        return end;
    }
    if out.len() < end || records.slots() < end {
        out.truncate(start);
        records.truncate(start);
        extend_from_chunks(out, chunks, records, record);
        return end;
    }
    let pieces: Vec<&[Triangle]> = chunks.iter().flat_map(|c| c.chunks(COPY_PIECE)).collect();
    let lens: Vec<usize> = pieces.iter().map(|p| p.len()).collect();
    let targets = split_parts(&mut out[start..end], &lens);
    let slots = records.parts(start, &lens);
    let copy = |((src, dst), mut slots): ((&[Triangle], &mut [Triangle]), E::Part<'_>)| {
        dst.copy_from_slice(src);
        for (i, t) in src.iter().enumerate() {
            E::put(&mut slots, i, record(t));
        }
    };
    #[cfg(feature = "rayon")]
    pieces.into_par_iter().zip(targets).zip(slots).for_each(copy);
    #[cfg(not(feature = "rayon"))]
    pieces.into_iter().zip(targets).zip(slots).for_each(copy);
    end
}

/// Appends the chunks' triangles to `out` in chunk order, and the `record` of each to
/// `records`: in parallel with the `rayon` feature, [`COPY_PIECE`] items a task at least.
fn extend_from_chunks<T: Send, E: RecordSink<T>>(
    out: &mut Vec<Triangle>,
    chunks: &[Vec<Triangle>],
    records: &mut E,
    record: &(impl Fn(&Triangle) -> T + Sync + Send),
) {
    #[cfg(feature = "rayon")]
    {
        let mut offsets = Vec::with_capacity(chunks.len() + 1);
        let mut total = 0;
        for c in chunks {
            offsets.push(total);
            total += c.len();
        }
        offsets.push(total);
        // both collections extended in one sweep (rayon extends a pair from pairs), keeping
        // their storage: taken out and put back
        let mut both = (std::mem::take(out), std::mem::take(records));
        both.par_extend((0..total).into_par_iter().with_min_len(COPY_PIECE).map(|i| {
            // the last chunk starting at or before i (empty chunks start where the next does)
            let c = offsets.partition_point(|&o| o <= i) - 1;
            let t = chunks[c][i - offsets[c]];
            let r = record(&t);
            (t, r)
        }));
        (*out, *records) = both;
    }
    #[cfg(not(feature = "rayon"))]
    for c in chunks {
        out.extend_from_slice(c);
        records.extend(c.iter().map(record));
    }
}

/// `slice` cut into consecutive parts of `lens` (which sum to at most its length).
fn split_parts<'a, T>(mut slice: &'a mut [T], lens: &[usize]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(lens.len());
    for &n in lens {
        let (part, rest) = std::mem::take(&mut slice).split_at_mut(n);
        parts.push(part);
        slice = rest;
    }
    parts
}

/// A collection a setup extends with records where its storage must grow: rayon's
/// `ParallelExtend` with the `rayon` feature, `Extend` without.
#[cfg(feature = "rayon")]
pub trait ExtendRecords<T: Send>: ParallelExtend<T> {}
#[cfg(feature = "rayon")]
impl<T: Send, E: ParallelExtend<T>> ExtendRecords<T> for E {}
/// A collection a setup extends with records where its storage must grow: rayon's
/// `ParallelExtend` with the `rayon` feature, `Extend` without.
#[cfg(not(feature = "rayon"))]
pub trait ExtendRecords<T: Send>: Extend<T> {}
#[cfg(not(feature = "rayon"))]
impl<T: Send, E: Extend<T>> ExtendRecords<T> for E {}

/// Where [`TriangleSetup::rebuild_with`] writes its records, one a triangle in the triangles'
/// order: a `Vec`, a pair of `Vec`s (for a pair of records), or `()` for none. Its storage is
/// kept from frame to frame; each task writes its own part of it.
pub trait RecordSink<T: Send>: ExtendRecords<T> + Default + Send {
    /// The consecutive slots one task writes.
    type Part<'a>: Send
    where
        Self: 'a;
    /// The number of slots.
    fn slots(&self) -> usize;
    /// Exactly `len` slots where there were more: the first `len` kept.
    fn truncate(&mut self, len: usize);
    /// Slots from `start` on, cut into consecutive parts of `lens` (which must be in range).
    fn parts(&mut self, start: usize, lens: &[usize]) -> Vec<Self::Part<'_>>;
    /// Writes `record` to slot `i` of `part`.
    fn put(part: &mut Self::Part<'_>, i: usize, record: T);
    /// Appends `record` after the last slot.
    fn push(&mut self, record: T);
}

impl<T: Send> RecordSink<T> for Vec<T> {
    type Part<'a>
        = &'a mut [T]
    where
        T: 'a;
    fn slots(&self) -> usize {
        self.len()
    }
    fn truncate(&mut self, len: usize) {
        Vec::truncate(self, len);
    }
    fn parts(&mut self, start: usize, lens: &[usize]) -> Vec<&mut [T]> {
        split_parts(&mut self[start..], lens)
    }
    fn put(part: &mut &mut [T], i: usize, record: T) {
        part[i] = record;
    }
    fn push(&mut self, record: T) {
        Vec::push(self, record);
    }
}

impl<A: Send, B: Send> RecordSink<(A, B)> for (Vec<A>, Vec<B>) {
    type Part<'a>
        = (&'a mut [A], &'a mut [B])
    where
        A: 'a,
        B: 'a;
    fn slots(&self) -> usize {
        self.0.len().min(self.1.len())
    }
    fn truncate(&mut self, len: usize) {
        self.0.truncate(len);
        self.1.truncate(len);
    }
    fn parts(&mut self, start: usize, lens: &[usize]) -> Vec<Self::Part<'_>> {
        self.0.parts(start, lens).into_iter().zip(self.1.parts(start, lens)).collect()
    }
    fn put(part: &mut Self::Part<'_>, i: usize, (a, b): (A, B)) {
        part.0[i] = a;
        part.1[i] = b;
    }
    fn push(&mut self, (a, b): (A, B)) {
        self.0.push(a);
        self.1.push(b);
    }
}

impl RecordSink<()> for () {
    type Part<'a> = ();
    fn slots(&self) -> usize {
        usize::MAX
    }
    fn truncate(&mut self, _: usize) {}
    fn parts(&mut self, _: usize, lens: &[usize]) -> Vec<()> {
        vec![(); lens.len()]
    }
    fn put(_: &mut (), _: usize, _: ()) {}
    fn push(&mut self, _: ()) {}
}

/// What setup keeps from one frame to the next: its per-vertex records and each task's triangle
/// list, so that a persistent renderer's setup ([`TriangleSetup::rebuild`]) allocates nothing
/// once warm (fresh memory is page faults, and the bunny's 11 MB of triangles made setup's
/// largest cost on a small host).
#[derive(Default)]
pub struct SetupScratch {
    vertices: Vec<SetupVertex>,
    chunks: Vec<Vec<Triangle>>,
    /// Each instance that references its data: index, primitive id base, whether small.
    instances: Vec<(usize, u32, bool)>,
    /// A run of small instances' batches, and each batch's vertices and triangles.
    batches: Vec<std::ops::Range<usize>>,
    batch_vertices: Vec<Vec<SetupVertex>>,
    batch_triangles: Vec<Vec<Triangle>>,
}

impl TriangleSetup {
    /// A setup of no triangles for `settings`' frame, to be filled by
    /// [`TriangleSetup::rebuild`] or [`TriangleSetup::rebuild_with`].
    pub fn empty(camera: &Camera, settings: &Settings) -> TriangleSetup {
        TriangleSetup {
            triangles: Vec::new(),
            // Settings::validate rejects larger sizes; clamping keeps the fixed point in range
            // for callers that skipped it.
            width: settings.width.min(MAX_SIZE),
            height: settings.height.min(MAX_SIZE),
            shading: settings.shading,
            forward: camera.forward,
            textures: Vec::new(),
        }
    }

    fn snap(settings: &Settings) -> Snap {
        let (width, height) = (settings.width.min(MAX_SIZE), settings.height.min(MAX_SIZE));
        let reach = reach(settings.samples);
        match settings.region {
            None => Snap { width, height, origin: (0, 0), region: (width, height), reach },
            // the origin lies within a frame of at most MAX_SIZE a side (Settings::validate), so
            // origin × 256 fits an i32 with room to spare
            Some(r) => Snap {
                width: r.full_width.min(MAX_SIZE),
                height: r.full_height.min(MAX_SIZE),
                origin: (
                    (r.x.min(MAX_SIZE) as i32) << SUBPIXEL_BITS,
                    (r.y.min(MAX_SIZE) as i32) << SUBPIXEL_BITS,
                ),
                region: (width, height),
                reach,
            },
        }
    }

    /// Sets up every instance's triangles: clip space (`view_proj · transform · p`), clipping,
    /// snapping. Triangle `t` of instance `i` gets primitive id `scene.primitive_bases().0[i] + t`,
    /// every piece of it after clipping the same. Instances or triangles that reference missing
    /// data are skipped (Scene::validate rejects them earlier).
    pub fn new(scene: &Scene, camera: &Camera, settings: &Settings) -> TriangleSetup {
        let mut r = TriangleSetup::empty(camera, settings);
        r.rebuild(scene, camera, settings, &mut SetupScratch::default());
        r
    }

    /// [`TriangleSetup::new`] into this setup's storage, with `scratch` kept from an earlier
    /// frame: the same triangles, bit for bit, and no allocation once the storage is as large
    /// as the scene needs.
    pub fn rebuild(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        scratch: &mut SetupScratch,
    ) {
        self.rebuild_with(scene, camera, settings, scratch, &mut (), |_| ());
    }

    /// [`TriangleSetup::rebuild`], writing `record(t)` for each set-up triangle `t`, in order, to
    /// `records` as each is copied into place: a renderer's own per-triangle data (oit-cpu's
    /// traversal and shading records) made while the triangle is in cache, in the same parallel
    /// step, rather than in another sweep over every triangle. `records` ends with one record a
    /// triangle, whatever it held before (its storage is reused); a pair of `Vec`s takes a pair
    /// of records.
    pub fn rebuild_with<T: Send, E: RecordSink<T>>(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: &Settings,
        scratch: &mut SetupScratch,
        records: &mut E,
        record: impl Fn(&Triangle) -> T + Sync + Send,
    ) {
        // the last frame's triangles stay until overwritten (and are cut to this frame's count
        // at the end), so a frame no larger than the last writes each slot once
        let triangles = std::mem::take(&mut self.triangles);
        *self = TriangleSetup { triangles, ..TriangleSetup::empty(camera, settings) };
        let mut filled = 0;
        let snap = TriangleSetup::snap(settings);
        let view_proj = camera.view_proj();
        if scene.objects.iter().any(|o| o.texture.is_some()) {
            self.textures.clone_from(&scene.textures);
        }
        // each instance's primitive id base (the triangles of the instances before it that
        // reference their data), and whether it is small (a chunk of triangles, of vertices)
        let mut prim_base = 0u32;
        scratch.instances.clear();
        for (i, inst) in scene.instances.iter().enumerate() {
            let Some(mesh) = scene.objects.get(inst.object).and_then(|o| scene.meshes.get(o.mesh)) else {
                continue;
            };
            let small = mesh.indices.len() <= SETUP_CHUNK && mesh.positions.len() <= SETUP_CHUNK;
            scratch.instances.push((i, prim_base, small));
            prim_base = prim_base.saturating_add(u32::try_from(mesh.indices.len()).unwrap_or(u32::MAX));
        }
        let textures = &self.textures;
        let instances = std::mem::take(&mut scratch.instances);
        let mut next = 0;
        while next < instances.len() {
            let (i, base_id, small) = instances[next];
            let run = instances[next..].iter().take_while(|x| x.2).count();
            if small && run > 1 {
                // a run of small instances (hundreds of leaves or particles of a few triangles
                // each): set up in batches of about a chunk's triangles, a batch a task, each
                // into its own list, copied into place in order
                let batches = small_batches(scene, &instances[next..next + run], &mut scratch.batches);
                let n = batches.len();
                scratch.batch_vertices.resize_with(n.max(scratch.batch_vertices.len()), Vec::new);
                scratch.batch_triangles.resize_with(n.max(scratch.batch_triangles.len()), Vec::new);
                let batch = |((vertices, out), range): (
                    (&mut Vec<SetupVertex>, &mut Vec<Triangle>),
                    &std::ops::Range<usize>,
                )| {
                    out.clear();
                    for &(i, base_id, _) in &instances[next..][range.clone()] {
                        let inst = &scene.instances[i];
                        let object = &scene.objects[inst.object];
                        let mesh = &scene.meshes[object.mesh];
                        let mvp = view_proj * inst.transform;
                        snap.vertices(vertices, &mvp, &normal_matrix(&inst.transform), mesh);
                        let material = instance_material(object, inst, mesh, settings, textures);
                        snap.triangles(out, vertices, &mesh.indices, &material, base_id);
                    }
                };
                let (vertices, lists) = (&mut scratch.batch_vertices[..n], &mut scratch.batch_triangles[..n]);
                #[cfg(feature = "rayon")]
                vertices.par_iter_mut().zip(lists.par_iter_mut()).zip(batches.par_iter()).for_each(batch);
                #[cfg(not(feature = "rayon"))]
                vertices.iter_mut().zip(lists.iter_mut()).zip(batches.iter()).for_each(batch);
                filled =
                    copy_chunks(&mut self.triangles, filled, &scratch.batch_triangles[..n], records, &record);
                next += run;
                continue;
            }
            let inst = &scene.instances[i];
            let object = &scene.objects[inst.object];
            let mesh = &scene.meshes[object.mesh];
            let mvp = view_proj * inst.transform;
            snap.vertices(&mut scratch.vertices, &mvp, &normal_matrix(&inst.transform), mesh);
            let material = instance_material(object, inst, mesh, settings, textures);
            filled = snap.instance(
                (&mut self.triangles, filled, records, &record),
                &mut scratch.chunks,
                &scratch.vertices,
                &mesh.indices,
                &material,
                base_id,
            );
            next += 1;
        }
        scratch.instances = instances;
        self.triangles.truncate(filled);
        records.truncate(filled);
    }

    /// The 12 triangles of each instance's world bounding box (`Aabb::TRIANGLES` over
    /// `Aabb::corners`), triangle `t` of instance `i` with primitive id `12·i + t`. For the bounds
    /// passes of the bucket techniques; colours and normals are not meaningful.
    pub fn bounding_boxes(scene: &Scene, camera: &Camera, settings: &Settings) -> TriangleSetup {
        let mut r = TriangleSetup::empty(camera, settings);
        let snap = TriangleSetup::snap(settings);
        let view_proj = camera.view_proj();
        let mesh_bounds = scene.mesh_bounds();
        let mut chunks = Vec::new();
        for (i, inst) in scene.instances.iter().enumerate() {
            let Some(object) = scene.objects.get(inst.object) else {
                continue;
            };
            let Some(bounds) = mesh_bounds.get(object.mesh) else {
                continue;
            };
            let (corners, normals) = box_vertices(bounds, &inst.transform);
            let vertices: Vec<SetupVertex> = (0..8)
                .map(|k| {
                    snap.vertex(transform_point(&view_proj, corners[k]), normals[k], Vec3::ZERO, Vec2::ZERO)
                })
                .collect();
            let base_id = u32::try_from(i).unwrap_or(u32::MAX).saturating_mul(12);
            let material = Material::plain(settings.material_color(object.color), false);
            let filled = r.triangles.len();
            snap.instance(
                (&mut r.triangles, filled, &mut (), &|_: &Triangle| ()),
                &mut chunks,
                &vertices,
                &Aabb::TRIANGLES,
                &material,
                base_id,
            );
        }
        r
    }

    /// Interpolates and shades the fragment of `t` at pixel (x, y), whose edge functions
    /// ([`edge`]) are `e`. The formula is fixed (no fused multiply-add), so a port gets the same
    /// bits. It is [`barycentrics`], [`depth_at`], then [`TriangleSetup::color_at`] and
    /// [`normal_at`]: a backend that needs only some of these for a fragment (a depth-only pass)
    /// may call just those, and gets the same bits for them.
    #[inline]
    pub fn fragment(&self, t: &Triangle, x: u32, y: u32, e: [i64; 3]) -> Fragment {
        let b = barycentrics(t, e);
        Fragment {
            pixel: y * self.width + x,
            depth: depth_at(t, b),
            prim: t.prim,
            color: self.color_at(t, b),
            normal: normal_at(t, b),
        }
    }

    /// The shaded colour of the fragment of `t` with barycentrics `b` ([`barycentrics`]):
    /// [`TriangleSetup::fragment`]'s `color`.
    ///
    /// A textured triangle's texture coordinates are interpolated as its vertex colours are,
    /// `(uv0·p0 + uv1·p1) + uv2·p2` per component, and the texture's sample there at the
    /// triangle's level ([`crate::Texture::sample`]) multiplies the base colour (RGB and alpha)
    /// and the vertex colour before shading: the material's factor times the texture.
    #[inline]
    pub fn color_at(&self, t: &Triangle, b: [f32; 3]) -> Vec4 {
        let p = perspective(t, b);
        let normal = interpolated_normal(t, p);
        let mut vertex_color = t.has_color.then(|| t.color[0] * p[0] + t.color[1] * p[1] + t.color[2] * p[2]);
        let mut base = t.base;
        if let Some(sample) = self.texture_sample(t, p) {
            base *= sample;
            vertex_color = vertex_color.map(|c| c * sample.truncate());
        }
        self.shading.shade(base, normal, vertex_color, self.forward)
    }

    /// [`TriangleSetup::color_at`]'s alpha, the same bits, without shading or the texture's
    /// colour channels: the base alpha times the texture's filtered alpha, clamped to [0, 1].
    /// What the opaque pass's alpha test reads.
    #[inline]
    pub fn alpha_at(&self, t: &Triangle, b: [f32; 3]) -> f32 {
        let mut alpha = t.base.w;
        if let Some(texture) = self.textures.get(t.texture as usize) {
            let p = perspective(t, b);
            let uv = t.uv[0] * p[0] + t.uv[1] * p[1] + t.uv[2] * p[2];
            // as `decode` divides it, and `Vec4 *=` multiplies lane by lane
            alpha *= f32::from(texture.sample_alpha8(t.lod, uv)) / 255.0;
        }
        alpha.clamp(0.0, 1.0)
    }

    /// `record` (of `t`) with its base multiplied by `t`'s texture's sample at barycentrics `b`,
    /// as [`TriangleSetup::color_at`] multiplies it before shading: the same product, so headlight
    /// lanes ([`headlight_colors`], which read no vertex colour) shading the returned record give
    /// `color_at`'s bits for a textured triangle too. `record` unchanged where `t` has no texture.
    #[inline]
    pub fn textured(&self, t: &Triangle, b: [f32; 3], mut record: ShadeRecord) -> ShadeRecord {
        if let Some(sample) = self.texture_sample(t, perspective(t, b)) {
            record.base *= sample;
        }
        record
    }

    /// The sample of `t`'s texture (none where it has none) at its texture coordinates
    /// interpolated as its vertex colours are, `(uv0·p0 + uv1·p1) + uv2·p2` per component, with the
    /// perspective-correct weights `p`, at the triangle's level.
    #[inline]
    fn texture_sample(&self, t: &Triangle, p: [f32; 3]) -> Option<Vec4> {
        let texture = self.textures.get(t.texture as usize)?;
        let uv = t.uv[0] * p[0] + t.uv[1] * p[1] + t.uv[2] * p[2];
        Some(texture.sample(t.lod, uv))
    }

    /// Whether any triangle may be textured: shading then looks at each triangle's texture
    /// ([`TriangleSetup::color_at`]) rather than running [`headlight_colors`]' lanes.
    #[inline]
    pub fn has_textures(&self) -> bool {
        !self.textures.is_empty()
    }
    /// [`TriangleSetup::color_at`] of [`SHADE_LANES`] fragments at once, bit for bit: lane `i` is
    /// the colour of the fragment of `tris[i]` with barycentrics `b[i]`. The headlight shading
    /// (the default) runs in lanes ([`headlight_colors`]), a textured triangle's base multiplied
    /// by its texture's sample first; the other shadings call [`TriangleSetup::color_at`] per lane.
    #[inline]
    pub fn colors_at(
        &self,
        tris: [&Triangle; SHADE_LANES],
        b: [[f32; 3]; SHADE_LANES],
    ) -> [Vec4; SHADE_LANES] {
        if self.shading == Shading::Headlight {
            let records: [ShadeRecord; SHADE_LANES] =
                std::array::from_fn(|i| self.textured(tris[i], b[i], ShadeRecord::new(tris[i])));
            headlight_colors(std::array::from_fn(|i| &records[i]), b, self.forward)
        } else {
            std::array::from_fn(|i| self.color_at(tris[i], b[i]))
        }
    }

    /// The set-up triangles as 32-bit words, [`TRIANGLE_WORDS`] per triangle, for a GPU rasterizer
    /// that walks and interpolates them with the same rules (oit-wgpu's compute path), so both
    /// produce the same fragments. Layout per triangle: `x[3]` (i32, 1/256 px), `y[3]` (i32),
    /// `z[3]` (f32), `inv_w[3]` (f32), `normal[3][3]` (f32), `color[3][3]` (f32), `inv_area`
    /// (f32), `base[4]` (f32), `has_color` (u32), `prim` (u32), `bbox[4]` (u32, inclusive x0 y0
    /// x1 y1), 3 words of padding.
    pub fn triangle_words(&self) -> Vec<u32> {
        let mut out = Vec::new();
        self.triangle_words_into(&mut out);
        out
    }

    /// [`TriangleSetup::triangle_words`] into `out` (cleared first; its storage kept).
    pub fn triangle_words_into(&self, out: &mut Vec<u32>) {
        out.clear();
        out.reserve(self.triangles.len() * TRIANGLE_WORDS);
        for t in &self.triangles {
            // a triangle's words made in place, then appended at once
            let mut w = [0u32; TRIANGLE_WORDS];
            let mut at = 0;
            let mut put = |words: &[u32]| {
                w[at..at + words.len()].copy_from_slice(words);
                at += words.len();
            };
            put(&t.x.map(|v| v as u32));
            put(&t.y.map(|v| v as u32));
            put(&t.z.map(f32::to_bits));
            put(&t.inv_w.map(f32::to_bits));
            for n in t.normal {
                put(&n.to_array().map(f32::to_bits));
            }
            for c in t.color {
                put(&c.to_array().map(f32::to_bits));
            }
            put(&[t.inv_area.to_bits()]);
            put(&t.base.to_array().map(f32::to_bits));
            put(&[u32::from(t.has_color), t.prim]);
            put(&t.bbox);
            // the last 3 words are padding (0)
            debug_assert_eq!(at, TRIANGLE_WORDS - 3);
            out.extend_from_slice(&w);
        }
    }

    /// The inclusive pixel boxes of the set-up triangles (x0, y0, x1, y1), in order.
    pub fn triangle_boxes(&self) -> impl Iterator<Item = [u32; 4]> + '_ {
        self.triangles.iter().map(|t| t.bbox)
    }

    /// [`TriangleSetup::work_items`] in its plainest form: every square of every triangle's box
    /// tested on its own by [`Triangle::may_cover`]. The list the row runs must give, and what
    /// they are timed against (`cargo bench -p oit-gpu --bench host_setup`).
    pub fn work_items_tile_by_tile(&self, tile: u32) -> Vec<[u32; 2]> {
        let mut items = Vec::new();
        for (i, t) in self.triangles.iter().enumerate() {
            let [x0, y0, x1, y1] = t.bbox;
            for ty in y0 / tile..=y1 / tile {
                let row = (x0 / tile..=x1 / tile).filter(|&tx| t.may_cover(tx, ty, tile));
                items.extend(row.map(|tx| [i as u32, ty << 16 | tx]));
            }
        }
        items
    }

    /// The compute path's work list: (triangle, `tile`-pixel square as row << 16 | column) for
    /// each square of each triangle's box that [`Triangle::may_cover`] keeps, triangle by
    /// triangle, row by row. What the GPU setup bins (setup.wgsl), in another order.
    pub fn work_items(&self, tile: u32) -> Vec<[u32; 2]> {
        let mut items = Vec::new();
        self.work_items_into(tile, &mut items, &mut Vec::new());
        items
    }

    /// [`TriangleSetup::work_items`] into `items` (cleared first), each task's list on the way in
    /// `chunks`: both keep their storage from one frame to the next.
    pub fn work_items_into(&self, tile: u32, items: &mut Vec<[u32; 2]>, chunks: &mut Vec<Vec<[u32; 2]>>) {
        // a triangle's items, row-major over its box's tiles
        let of = |i: usize, t: &Triangle, items: &mut Vec<[u32; 2]>| {
            let [x0, y0, x1, y1] = t.bbox;
            let edges = RowEdges::new(t);
            for ty in y0 / tile..=y1 / tile {
                items.extend(edges.run(ty, x0 / tile, x1 / tile, tile).map(|tx| [i as u32, ty << 16 | tx]));
            }
        };
        // a chunk of triangles' items: in parallel over chunks, the lists joined in order; a
        // textured frame (set up on the host) of large triangles has hundreds of thousands of
        // tiles
        let n = self.triangles.len().div_ceil(ITEM_CHUNK);
        if chunks.len() < n {
            chunks.resize_with(n, Vec::new);
        }
        let chunks = &mut chunks[..n];
        for_each_chunk(chunks, &self.triangles, ITEM_CHUNK, |c, out, tris| {
            out.clear();
            for (k, t) in tris.iter().enumerate() {
                of(c * ITEM_CHUNK + k, t, out);
            }
        });
        items.clear();
        items.reserve(chunks.iter().map(Vec::len).sum());
        for c in chunks.iter() {
            items.extend_from_slice(c);
        }
    }
}

impl Triangle {
    /// Whether the `tile`-pixel square (column `tx`, row `ty`) may hold a sample the triangle
    /// covers: false only where one edge leaves every point of the square's part of the box
    /// outside. An edge function is affine and exact in 64 bits, so its largest value over the
    /// rectangle of subpixel points from the first pixel's corner to the last's lies at a corner
    /// of it; every sample position of every sample count lies in that rectangle. So a square
    /// this drops has no covered sample; one it keeps may still have none (near a corner).
    pub fn may_cover(&self, tx: u32, ty: u32, tile: u32) -> bool {
        let [bx0, by0, bx1, by1] = self.bbox;
        let (x0, y0) = ((tx * tile).max(bx0), (ty * tile).max(by0));
        let (x1, y1) = ((tx * tile + tile - 1).min(bx1), (ty * tile + tile - 1).min(by1));
        if x0 > x1 || y0 > y1 {
            return false;
        }
        let xs = [i64::from(x0) * SUBPIXEL, i64::from(x1) * SUBPIXEL + SUBPIXEL - 1];
        let ys = [i64::from(y0) * SUBPIXEL, i64::from(y1) * SUBPIXEL + SUBPIXEL - 1];
        (0..3).all(|k| {
            let corners = xs.iter().flat_map(|&x| ys.iter().map(move |&y| (x, y)));
            corners.into_iter().any(|(x, y)| {
                let (value, _, _, above) = edge(self, k, x, y);
                value > above
            })
        })
    }
}

impl Triangle {
    /// The columns of row `ty`, from `tx0` to `tx1` (the triangle's box's), whose squares
    /// [`Triangle::may_cover`] keeps: a run ([`RowEdges::run`], which a caller asking for many
    /// rows makes once).
    pub fn row_run(&self, ty: u32, tx0: u32, tx1: u32, tile: u32) -> std::ops::Range<u32> {
        RowEdges::new(self).run(ty, tx0, tx1, tile)
    }
}

/// A triangle's three edges as its rows' runs read them ([`RowEdges::run`]): each edge's
/// function ([`edge`]) as `value(x, y) = dx·y − dy·x + value(0, 0)` and the bound it must
/// exceed, made once a triangle rather than once a row.
#[derive(Clone, Copy, Debug)]
pub struct RowEdges {
    bbox: [u32; 4],
    /// Per edge: dx, dy, value(0, 0), the bound (`edge`'s `inside_above`).
    edges: [[i64; 4]; 3],
}

impl RowEdges {
    /// The edges of `t`.
    pub fn new(t: &Triangle) -> RowEdges {
        let edges = std::array::from_fn(|k| {
            // edge's per-pixel steps are −dy and dx, times SUBPIXEL exactly
            let (origin, step_x, step_y, above) = edge(t, k, 0, 0);
            [step_y / SUBPIXEL, -step_x / SUBPIXEL, origin, above]
        });
        RowEdges { bbox: t.bbox, edges }
    }

    /// The columns of row `ty`, from `tx0` to `tx1` (the triangle's box's), whose squares
    /// [`Triangle::may_cover`] keeps. An edge keeps a square where its largest value over the
    /// square's part of the box exceeds its bound; an affine function's largest value over a
    /// rectangle lies at one corner (x̂, ŷ): the right side where it grows with x, the left
    /// where it falls, the bottom where it grows with y, the top where it falls. Along a row the
    /// square only moves right, so each edge keeps a prefix of the row or a suffix (or all, or
    /// none), known from its two ends; the squares all three keep are where those runs overlap.
    /// Where an edge's ends differ, the column where its verdict turns is solved for: for every
    /// column but the ends the corner lies on the tiles' grid, not on the box's clamped sides, so
    /// the verdict `value(x̂, ŷ) > bound` is a linear inequality in the column, solved exactly in
    /// 64 bits (`div_euclid` floors). The GPU's setup solves for it alike (`row_run` in
    /// `setup.wgsl`).
    pub fn run(&self, ty: u32, tx0: u32, tx1: u32, tile: u32) -> std::ops::Range<u32> {
        let [bx0, by0, bx1, by1] = self.bbox;
        let low = |v: u32, lo: u32| i64::from(v.max(lo)) * SUBPIXEL;
        let high = |v: u32, hi: u32| i64::from((v + tile - 1).min(hi)) * SUBPIXEL + SUBPIXEL - 1;
        let (top, bottom) = (low(ty * tile, by0), high(ty * tile, by1));
        let first = (low(tx0 * tile, bx0), high(tx0 * tile, bx1));
        let last = (low(tx1 * tile, bx0), high(tx1 * tile, bx1));
        let width = i64::from(tile) * SUBPIXEL;
        let (mut lo, mut end) = (tx0, tx1 + 1);
        for [dx, dy, origin, above] in self.edges {
            // value(x, ŷ) = c − dy·x
            let y = if dx > 0 { bottom } else { top };
            let c = dx * y + origin;
            let keeps = |(left, right): (i64, i64)| c - dy * if dy < 0 { right } else { left } > above;
            let (keeps_first, keeps_last) = (keeps(first), keeps(last));
            if !keeps_first && !keeps_last {
                return tx0..tx0;
            }
            if keeps_first == keeps_last {
                continue;
            }
            // dy ≠ 0 here: with dy = 0 the verdict is the same along the row
            let turn = if dy < 0 {
                // kept from the turn on: −dy·x̂ > above − c, x̂ = (column + 1)·width − 1
                let least = (above - c).div_euclid(-dy) + 1;
                (least + 1 + width - 1).div_euclid(width) - 1
            } else {
                // kept until the turn: dy·x̂ < c − above, x̂ = column·width
                let most = (c - above - 1).div_euclid(dy);
                most.div_euclid(width) + 1
            };
            let turn = turn.clamp(i64::from(tx0) + 1, i64::from(tx1)) as u32;
            if keeps_first {
                end = end.min(turn);
            } else {
                lo = lo.max(turn);
            }
        }
        lo..end.max(lo)
    }
}

/// The screen-space barycentrics of a fragment of `t` from its edge functions `e` ([`edge`]).
#[inline]
pub fn barycentrics(t: &Triangle, e: [i64; 3]) -> [f32; 3] {
    DepthPlane::new(t).barycentrics(e)
}

/// The depth of the fragment of `t` with barycentrics `b` ([`barycentrics`]):
/// [`TriangleSetup::fragment`]'s `depth`.
#[inline]
pub fn depth_at(t: &Triangle, b: [f32; 3]) -> f32 {
    DepthPlane::new(t).depth(b)
}

/// What a fragment's barycentrics and depth need of its triangle, a few words a traversal can
/// keep beside its edge functions (the rest of [`Triangle`] is read only for colour and normal).
/// The differences are the ones [`depth_at`] takes, the same f32 subtractions made once.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthPlane {
    /// NDC z of vertex 0.
    pub z0: f32,
    /// `z[1] − z[0]`.
    pub dz1: f32,
    /// `z[2] − z[0]`.
    pub dz2: f32,
    /// [`Triangle::inv_area`].
    pub inv_area: f32,
}

impl DepthPlane {
    /// The plane of `t`.
    #[inline]
    pub fn new(t: &Triangle) -> DepthPlane {
        DepthPlane { z0: t.z[0], dz1: t.z[1] - t.z[0], dz2: t.z[2] - t.z[0], inv_area: t.inv_area }
    }

    /// [`barycentrics`].
    #[inline]
    pub fn barycentrics(&self, e: [i64; 3]) -> [f32; 3] {
        e.map(|e| e as f32 * self.inv_area)
    }

    /// [`depth_at`].
    #[inline]
    pub fn depth(&self, b: [f32; 3]) -> f32 {
        // Anchored at vertex 0, so a triangle of constant depth (a quad facing the camera, a plane
        // at exactly d = 0 or 1) gives exactly that depth at every pixel: coplanar fragments of
        // different triangles then tie exactly, as the rules for ties assume.
        (self.z0 + b[1] * self.dz1 + b[2] * self.dz2).clamp(0.0, 1.0)
    }
}

/// The perspective-correct weights of the vertices (barycentrics weighted by 1/w, normalized).
#[inline]
fn perspective(t: &Triangle, b: [f32; 3]) -> [f32; 3] {
    let q = [b[0] * t.inv_w[0], b[1] * t.inv_w[1], b[2] * t.inv_w[2]];
    let inv_q = 1.0 / (q[0] + q[1] + q[2]);
    q.map(|q| q * inv_q)
}

/// The interpolated normal before normalization.
#[inline]
fn interpolated_normal(t: &Triangle, p: [f32; 3]) -> Vec3 {
    t.normal[0] * p[0] + t.normal[1] * p[1] + t.normal[2] * p[2]
}

/// The normalized world normal of the fragment of `t` with barycentrics `b` ([`barycentrics`]):
/// [`TriangleSetup::fragment`]'s `normal`.
#[inline]
pub fn normal_at(t: &Triangle, b: [f32; 3]) -> Vec3 {
    interpolated_normal(t, perspective(t, b)).normalize_or_zero()
}

/// Edge function `k` of `t` (the edge opposite vertex `k`) at the point (px, py) in sub-pixel
/// units: its value, its steps per pixel in x and in y, and the value a
/// covered pixel's edge function must exceed (−1 on a top or left edge, so 0 is covered; 0
/// elsewhere).
#[inline]
pub fn edge(t: &Triangle, k: usize, px: i64, py: i64) -> (i64, i64, i64, i64) {
    let (a, b) = ((k + 1) % 3, (k + 2) % 3);
    let (ax, ay) = (i64::from(t.x[a]), i64::from(t.y[a]));
    let dx = i64::from(t.x[b]) - ax;
    let dy = i64::from(t.y[b]) - ay;
    let value = dx * (py - ay) - dy * (px - ax);
    // y points down and the inside is on the positive side: a top edge runs +x, a left edge −y.
    let top_left = dy < 0 || (dy == 0 && dx > 0);
    let inside_above = if top_left { -1 } else { 0 };
    // Per-pixel steps in x and y.
    (value, -dy * SUBPIXEL, dx * SUBPIXEL, inside_above)
}

/// The rule in its plainest form: the edge functions of `t` at the centre of pixel (x, y) when
/// the pixel is covered. A backend's traversal must visit exactly these pixels.
#[inline]
pub fn covers(t: &Triangle, x: u32, y: u32) -> Option<[i64; 3]> {
    let (px, py) = (i64::from(x) * SUBPIXEL + HALF_PIXEL, i64::from(y) * SUBPIXEL + HALF_PIXEL);
    let e = [0, 1, 2].map(|k| edge(t, k, px, py));
    e.iter().all(|&(v, _, _, above)| v > above).then(|| e.map(|e| e.0))
}

/// The sample positions in the rasterizer's fixed point ([`SUBPIXEL`] units from
/// the pixel's top-left corner): each exact.
pub fn subpixel_offsets(samples: u32) -> impl Iterator<Item = (i64, i64)> {
    let scale = SUBPIXEL / i64::from(crate::msaa::POSITION_UNITS);
    crate::msaa::positions(samples).iter().map(move |&(x, y)| (i64::from(x) * scale, i64::from(y) * scale))
}

/// The smallest and largest sample offset, x and y together, in 1/256 pixel: the reach of a
/// pixel's samples that setup sizes a triangle's box by (the centre, 128, for one sample).
pub fn reach(samples: u32) -> (i64, i64) {
    let all = subpixel_offsets(samples).flat_map(|(x, y)| [x, y]);
    let (lo, hi) = all.fold((i64::MAX, i64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    (lo, hi)
}

/// The multisampled rule ([`crate::msaa`]): the coverage mask of `t` over the `samples` samples
/// of pixel (x, y), bit `i` set where sample `i` ([`crate::msaa::positions`]) is covered by the
/// same edge functions and top-left fill rule as [`covers`] tests the centre with (exact: the
/// sample positions lie on the 1/256-pixel grid), so two triangles sharing an edge cover each
/// sample exactly once. With one sample it is bit 0 set exactly where [`covers`] is `Some`.
#[inline]
pub fn sample_mask(t: &Triangle, x: u32, y: u32, samples: u32) -> u8 {
    let (x0, y0) = (i64::from(x) * SUBPIXEL, i64::from(y) * SUBPIXEL);
    let mut mask = 0u8;
    for (i, (dx, dy)) in subpixel_offsets(samples).enumerate() {
        let inside = (0..3).all(|k| {
            let (v, _, _, above) = edge(t, k, x0 + dx, y0 + dy);
            v > above
        });
        mask |= u8::from(inside) << i;
    }
    mask
}

/// The edge functions of `t` at the centre of pixel (x, y), covered or not: where a
/// multisampled fragment's centre lies outside its triangle, its barycentrics and depth are
/// extrapolated from these (docs/msaa.md).
#[inline]
pub fn centre_edges(t: &Triangle, x: u32, y: u32) -> [i64; 3] {
    let (px, py) = (i64::from(x) * SUBPIXEL + HALF_PIXEL, i64::from(y) * SUBPIXEL + HALF_PIXEL);
    [0, 1, 2].map(|k| edge(t, k, px, py).0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The samples' reach in fixed point: the centre for one sample, the standard patterns'
    /// extremes for four and eight.
    #[test]
    fn sample_reach() {
        assert_eq!(reach(1), (128, 128));
        assert_eq!(reach(4), (32, 224));
        assert_eq!(reach(8), (16, 240));
    }

    /// The work list comes triangle by triangle, each triangle's tiles row by row, as its doc
    /// says, across the chunks it is binned in (a chunk's list out of place fails it).
    ///
    /// Each row's run ([`Triangle::row_run`]) is the tiles [`Triangle::may_cover`] keeps, tested
    /// tile by tile at each of the rule's four corners: on small triangles (`spheres:3`), and on
    /// quads and billboards many tiles wide, seen turned, where the runs end inside rows.
    #[test]
    fn work_items_come_triangle_by_triangle_in_rows() {
        for (name, size, azimuth, tile) in
            [("spheres:3", 96, 0.0, 8), ("planes:4", 512, 37.0, 16), ("particles:64", 384, 20.0, 8)]
        {
            let scene = crate::load_scene(name).unwrap();
            let view = crate::View { azimuth, elevation: 25.0, ..Default::default() };
            let camera = Camera::orbit_scene(&scene, view, 1.0).unwrap();
            let settings = Settings { width: size, height: size, ..Default::default() };
            let setup = TriangleSetup::new(&scene, &camera, &settings);
            if name == "spheres:3" {
                // more triangles than one binning chunk, so the chunks' lists must join in order
                assert!(setup.triangles.len() > 4 * ITEM_CHUNK, "{} triangles", setup.triangles.len());
            }
            let expected = setup.work_items_tile_by_tile(tile);
            // rows whose kept tiles stop short of their box's ends (where a turn was solved for)
            let mut cut = 0;
            for row in expected.chunk_by(|a, b| a[0] == b[0] && a[1] >> 16 == b[1] >> 16) {
                let [x0, _, x1, _] = setup.triangles[row[0][0] as usize].bbox;
                let (first, last) = (row[0][1] & 0xffff, row[row.len() - 1][1] & 0xffff);
                cut += usize::from(first > x0 / tile) + usize::from(last < x1 / tile);
            }
            assert!(cut > 0, "{name}: no row's run ends inside its box");
            assert_eq!(setup.work_items(tile), expected, "{name}");
        }
    }

    /// A row's run is the tiles [`Triangle::may_cover`] keeps, on triangles whose vertices lie
    /// on or a unit beside the tiles' corners, where an edge's verdict turns exactly at a tile's
    /// side (the solved turn's floors and ceilings are off by one there if anywhere), and on
    /// triangles anywhere in a frame, in both windings. Turning either rounding by one fails it.
    #[test]
    fn row_runs_turn_where_the_tiles_say() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        let (mut turned, mut rows) = (0, 0);
        for n in 0..20_000 {
            let tile = if n % 2 == 0 { 8 } else { 16 };
            let width = i64::from(tile) * SUBPIXEL;
            let coordinate = |rng: &mut Rng| -> i32 {
                if n % 3 == 0 {
                    (rng.next_u64() % (256 * SUBPIXEL as u64)) as i32
                } else {
                    let corner = (rng.next_u64() % (256 / u64::from(tile))) as i64 * width;
                    (corner + [-1, 0, 0, 1][(rng.next_u64() % 4) as usize]) as i32
                }
            };
            let mut t = triangle(&mut rng);
            t.x = [0; 3].map(|_| coordinate(&mut rng));
            t.y = [0; 3].map(|_| coordinate(&mut rng));
            let pixel = |v: i32| (i64::from(v) - HALF_PIXEL).div_euclid(SUBPIXEL).clamp(0, 255) as u32;
            let (xs, ys) = (t.x.map(pixel), t.y.map(pixel));
            t.bbox = [
                xs[0].min(xs[1]).min(xs[2]),
                ys[0].min(ys[1]).min(ys[2]),
                xs[0].max(xs[1]).max(xs[2]),
                ys[0].max(ys[1]).max(ys[2]),
            ];
            let [x0, y0, x1, y1] = t.bbox;
            for ty in y0 / tile..=y1 / tile {
                let expected: Vec<u32> =
                    (x0 / tile..=x1 / tile).filter(|&tx| t.may_cover(tx, ty, tile)).collect();
                let run: Vec<u32> = t.row_run(ty, x0 / tile, x1 / tile, tile).collect();
                assert_eq!(
                    run, expected,
                    "triangle {n}: {:?} {:?}, box {:?}, row {ty}, tile {tile}",
                    t.x, t.y, t.bbox
                );
                rows += 1;
                turned +=
                    usize::from(!run.is_empty() && (run[0] > x0 / tile || run[run.len() - 1] < x1 / tile));
            }
        }
        assert!(turned > 1000, "{turned} of {rows} rows end inside their box");
    }

    /// A work list keeps every tile with a covered sample, at every sample count, and drops the
    /// tiles of a triangle's box that it misses: `planes` halves each quad's box along its
    /// diagonal, seen square on and turned.
    #[test]
    fn work_items_keep_every_covered_tile() {
        for name in ["planes:4", "spheres:3", "knot", "coplanar"] {
            let scene = crate::load_scene(name).unwrap();
            for azimuth in [0.0, 37.0] {
                let view = crate::View { azimuth, elevation: 20.0, ..Default::default() };
                let camera = Camera::orbit_scene(&scene, view, 1.0).unwrap();
                for samples in crate::msaa::SAMPLE_COUNTS {
                    let settings = Settings { width: 96, height: 96, samples, ..Default::default() };
                    let setup = TriangleSetup::new(&scene, &camera, &settings);
                    let items: std::collections::HashSet<[u32; 2]> =
                        setup.work_items(8).into_iter().collect();
                    let mut boxed = 0;
                    for (i, t) in setup.triangles.iter().enumerate() {
                        let [x0, y0, x1, y1] = t.bbox;
                        boxed += (x1 / 8 - x0 / 8 + 1) * (y1 / 8 - y0 / 8 + 1);
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                if sample_mask(t, x, y, samples) != 0 {
                                    let item = [i as u32, ((y / 8) << 16) | (x / 8)];
                                    assert!(
                                        items.contains(&item),
                                        "{name}, {samples} samples: pixel ({x}, {y}) of triangle {i} is covered, its tile dropped"
                                    );
                                }
                            }
                        }
                    }
                    if name == "planes:4" {
                        let kept = items.len() as f64 / f64::from(boxed);
                        assert!(kept < 0.8, "{name} at {azimuth}°: {kept:.2} of the boxes' tiles kept");
                    }
                }
            }
        }
    }

    use crate::rng::Rng;

    /// A float of any sign and of magnitudes from 2^-140 (subnormal squares) to 2^70 (squares
    /// past f32::MAX), or one of the values where the rules branch.
    fn wild(rng: &mut Rng) -> f32 {
        match rng.next_u64() % 8 {
            0 => [0.0, -0.0, 1.0, -1.0, f32::MIN_POSITIVE, 1e-30, 1e30][(rng.next_u64() % 7) as usize],
            _ => {
                let magnitude = 2f32.powi((rng.next_u64() % 211) as i32 - 140) * (1.0 + rng.next_f32());
                if rng.next_u64().is_multiple_of(2) { magnitude } else { -magnitude }
            }
        }
    }

    /// Three [`wild`] floats, or three in [-1, 1).
    fn vec3(rng: &mut Rng, wild_ones: bool) -> Vec3 {
        if wild_ones {
            Vec3::new(wild(rng), wild(rng), wild(rng))
        } else {
            Vec3::new(rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0 - 1.0)
        }
    }

    fn triangle(rng: &mut Rng) -> Triangle {
        let extreme = rng.next_u64().is_multiple_of(3);
        let normal = match rng.next_u64() % 6 {
            // a mesh without normals, and a normal cancelled by interpolation
            0 => [Vec3::ZERO; 3],
            1 => {
                let n = vec3(rng, false);
                [n, -n, n]
            }
            _ => [vec3(rng, extreme), vec3(rng, extreme), vec3(rng, extreme)],
        };
        Triangle {
            x: [0; 3],
            y: [0; 3],
            z: [0.0; 3],
            inv_w: [0; 3].map(|_| if extreme { wild(rng).abs() } else { 0.05 + rng.next_f32() * 10.0 }),
            normal,
            color: [vec3(rng, false), vec3(rng, false), vec3(rng, false)],
            inv_area: 1.0,
            // colours and alphas past [0, 1] too: the clamps decide
            base: Vec4::new(
                rng.next_f32() * 1.4 - 0.2,
                rng.next_f32() * 1.4 - 0.2,
                rng.next_f32(),
                rng.next_f32() * 1.4 - 0.2,
            ),
            has_color: rng.next_u64().is_multiple_of(2),
            prim: 0,
            bbox: [0; 4],
            uv: [Vec2::ZERO; 3],
            texture: NO_TEXTURE,
            lod: 0,
            cutoff: 0.0,
        }
    }

    fn barycentrics(rng: &mut Rng) -> [f32; 3] {
        let mut b = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        // on an edge, at a vertex
        match rng.next_u64() % 6 {
            0 => b[(rng.next_u64() % 3) as usize] = 0.0,
            1 => b = [0.0, 0.0, 1.0],
            _ => {}
        }
        let sum = b[0] + b[1] + b[2];
        if sum > 0.0 { b.map(|v| v / sum) } else { [1.0, 0.0, 0.0] }
    }

    /// The lanes give [`TriangleSetup::color_at`]'s bits in every lane, under every shading, for
    /// ordinary triangles and for the ones where the rules branch: zero and cancelling normals,
    /// normals whose squared length underflows or overflows, colours and alphas outside [0, 1],
    /// fragments on an edge or a vertex. A sum regrouped, or `is_finite` dropped from the
    /// normalization's test, fails it (both tried). [`TriangleSetup::alpha_at`] gives the
    /// colour's alpha bits on the same fragments.
    #[test]
    fn lanes_give_color_at_bits() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut checked = 0;
        for case in 0..4000 {
            let shading = [Shading::Headlight, Shading::Flat, Shading::Vertex, Shading::Normal][case % 4];
            let forward = vec3(&mut rng, false).normalize_or(Vec3::NEG_Z);
            // every other set of cases textured: a random texture, most lanes' triangles sampling
            // it at random coordinates (wrapping) and levels, the others untextured
            let textured = case % 8 >= 4;
            let textures = if textured {
                let (w, h) = (1 + (rng.next_u64() % 9) as u32, 1 + (rng.next_u64() % 9) as u32);
                let texels =
                    (0..w * h).map(|_| rng.next_u64().to_le_bytes()[..4].try_into().unwrap()).collect();
                let wrap = crate::texture::Wrap::Repeat;
                vec![crate::Texture::new("lanes", w, h, texels, [wrap, wrap]).unwrap()]
            } else {
                Vec::new()
            };
            let setup =
                TriangleSetup { triangles: Vec::new(), width: 1, height: 1, shading, forward, textures };
            let tris: [Triangle; SHADE_LANES] = std::array::from_fn(|_| {
                let mut t = triangle(&mut rng);
                if textured && !rng.next_u64().is_multiple_of(4) {
                    t.texture = 0;
                    t.uv = std::array::from_fn(|_| {
                        Vec2::new(rng.next_f32() * 5.0 - 2.0, rng.next_f32() * 5.0 - 2.0)
                    });
                    t.lod = (rng.next_u64() % 5) as u32;
                }
                t
            });
            let b: [[f32; 3]; SHADE_LANES] = std::array::from_fn(|_| barycentrics(&mut rng));
            let refs = std::array::from_fn(|i| &tris[i]);
            let got = setup.colors_at(refs, b);
            let records: [ShadeRecord; SHADE_LANES] =
                std::array::from_fn(|i| setup.textured(&tris[i], b[i], ShadeRecord::new(&tris[i])));
            let lanes = headlight_colors(std::array::from_fn(|i| &records[i]), b, forward);
            for i in 0..SHADE_LANES {
                let want = setup.color_at(&tris[i], b[i]).to_array().map(f32::to_bits);
                assert_eq!(got[i].to_array().map(f32::to_bits), want, "case {case} lane {i} ({shading:?})");
                assert_eq!(setup.alpha_at(&tris[i], b[i]).to_bits(), want[3], "case {case} lane {i} alpha");
                if shading == Shading::Headlight {
                    assert_eq!(lanes[i].to_array().map(f32::to_bits), want, "case {case} lane {i}");
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 1000 * SHADE_LANES);
    }

    /// A single-sided quad keeps its two triangles where it faces the camera (counter-clockwise
    /// seen from it, glTF's front), none where it faces away; mirrored in x, the same quads face
    /// the same ways (their screen winding turns over, and so does the rule); a double-sided
    /// one keeps both either way.
    #[test]
    fn back_faces_by_the_sign_of_the_snapped_area() {
        let positions = vec![
            Vec3::new(-0.5, -0.5, 0.0),
            Vec3::new(0.5, -0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(-0.5, 0.5, 0.0),
        ];
        let kept = |clockwise: bool, single: bool, transform: Mat4| {
            let indices = if clockwise { vec![[0, 2, 1], [0, 3, 2]] } else { vec![[0, 1, 2], [0, 2, 3]] };
            let mut scene = crate::Scene::from_meshes(
                "quad",
                vec![crate::Mesh::new("quad", positions.clone(), indices)],
                Vec4::ONE,
            );
            scene.objects[0].double_sided = !single;
            scene.instances[0].transform = transform;
            // looking down −z from +z
            let view = crate::View { azimuth: 0.0, elevation: 0.0, ..crate::View::default() };
            let camera = Camera::orbit_scene(&scene, view, 1.0).unwrap();
            let settings = Settings { width: 16, height: 16, ..Settings::default() };
            TriangleSetup::new(&scene, &camera, &settings).triangles.len()
        };
        let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        for (clockwise, transform, front) in [
            (false, Mat4::IDENTITY, true),
            (true, Mat4::IDENTITY, false),
            (false, mirror, true),
            (true, mirror, false),
        ] {
            let what = format!("clockwise {clockwise}, mirrored {}", transform != Mat4::IDENTITY);
            assert_eq!(kept(clockwise, false, transform), 2, "{what}: double-sided");
            assert_eq!(kept(clockwise, true, transform), if front { 2 } else { 0 }, "{what}: single-sided");
        }
    }
}
