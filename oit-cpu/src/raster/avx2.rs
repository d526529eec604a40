//! [`RasterMode::Scatter`](super::RasterMode::Scatter)'s shaded pass in AVX2, for hosts that have
//! it (the build targets SSE2; [`super::Kernel`] picks at run time). The same fragments as the
//! portable pass, bit for bit, in the same order within a task:
//! - a small triangle's box is tested eight pixels at a time as two, four or eight columns of as
//!   many rows (the narrowest that holds its width), so a box of 2×4 or 4×2 pixels, most of the
//!   bunny's, is one test; the edge functions are [`super::walk_small`]'s, in 32-bit lanes;
//! - each test's covered pixels are packed to the front of the lanes by one permutation
//!   (`vpermd`, its indices from a table by the coverage mask) and stored at the end of the
//!   batch whatever the mask, so the walk has no branch on coverage;
//! - barycentrics and depth are made in the test's lanes, by the very operations of
//!   [`DepthPlane`](oit_core::setup::DepthPlane) (an exact integer converted with
//!   round-to-nearest, then IEEE products and sums in the same order, no fused multiply-add);
//! - the batch is kept by component, shaded eight at a time
//!   (the headlight shading by [`headlight`], the operations of
//!   [`oit_core::setup::headlight_colors`] in AVX2, a textured triangle's base times its texture's
//!   sample by [`texture_lanes`], the sampler of `oit_core::texture` in AVX2), then handed to the
//!   shader fragment by fragment.

use std::arch::x86_64::*;

use glam::Vec4;
use oit_core::Shading;
use oit_core::setup::{SHADE_LANES, ShadeRecord, Triangle, TriangleSetup};
use oit_core::texture::Wrap;

use super::{AHEAD, Ahead, DepthBound, EarlyCut, Fragment, SmallEdges, TileSkip, in_rows, walk_spans};

/// Fragments a batch holds (a multiple of [`SHADE_LANES`]).
const CAP: usize = 128;

/// A task's covered pixels waiting to be shaded, by component.
struct Batch {
    /// The task's triangle of each.
    tri: [u32; CAP],
    pixel: [u32; CAP],
    depth: [f32; CAP],
    b: [[f32; CAP]; 3],
    /// RGBA after one another.
    color: [f32; 4 * CAP],
    /// The coverage mask of each, in the multisampled walk ([`masked_task`]).
    mask: [u32; CAP],
}

impl Batch {
    fn new() -> Batch {
        Batch {
            tri: [0; CAP],
            pixel: [0; CAP],
            depth: [0.0; CAP],
            b: [[0.0; CAP]; 3],
            color: [0.0; 4 * CAP],
            mask: [0; CAP],
        }
    }
}

/// For each 8-bit coverage mask, the lanes that are set, in order, a byte each (the first
/// `popcount` bytes meaningful): the indices of the permutation that packs them to the front.
const PACK: [u64; 256] = {
    let mut table = [0u64; 256];
    let mut mask = 0;
    while mask < 256 {
        let (mut lane, mut packed) = (0, 0);
        while lane < 8 {
            if mask >> lane & 1 != 0 {
                table[mask] |= (lane as u64) << (8 * packed);
                packed += 1;
            }
            lane += 1;
        }
        mask += 1;
    }
    table
};

/// Lanes per row of each layout ([`layout`]): 2, 4 or 8 columns.
const COLUMNS: [u32; 3] = [2, 4, 8];
/// The lanes of one row of each layout, as a mask bit pattern repeated for every row.
const ROW_PATTERN: [u32; 3] = [0x55, 0x11, 0x01];

/// The narrowest layout whose rows hold a box `width` pixels wide (the widest steps along).
#[inline]
fn layout(width: u32) -> usize {
    usize::from(width > 2) + usize::from(width > 4)
}

#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn store_u32(dst: &mut [u32; CAP], at: usize, v: __m256i) {
    let lanes: [u32; 8] = bytemuck::cast(v);
    dst[at..at + 8].copy_from_slice(&lanes);
}

#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn store_f32(dst: &mut [f32; CAP], at: usize, v: __m256) {
    let lanes: [f32; 8] = bytemuck::cast(v);
    dst[at..at + 8].copy_from_slice(&lanes);
}

/// One task: the triangles of `order` (indices into `tris` and their records `edges` and
/// `shades`), in that order, walked in the rows `window` (inclusive; the whole box where it holds
/// it), shaded where `SHADE` (else each fragment's colour is left to be made where `f` asks, as
/// [`Shade::OnDemand`](super::Shade::OnDemand) passes do) and handed to `f`; returns the
/// fragments. A Scatter task is a run of triangles over every row; a band of
/// [`Rasterizer::for_each_fragment_in_order`](super::Rasterizer::for_each_fragment_in_order) is
/// the band's triangles, highest primitive first, over the band's rows.
/// Where `skip` holds the cut's tiles, a triangle's fragments where it lies behind a tile's
/// farthest opaque depth are counted, not batched ([`TileSkip`]; a small triangle's where its
/// whole box does, by its coverage lanes alone), and counted occluded where the pass counts.
#[target_feature(enable = "avx2,popcnt")]
#[expect(clippy::too_many_arguments, reason = "the walk's inputs, the cut's two tests among them")]
pub(super) fn scatter_task<const SHADE: bool, F: Fn(&Fragment<'_>)>(
    setup: &TriangleSetup,
    (tris, edges, shades): (&[Triangle], &[SmallEdges], &[ShadeRecord]),
    order: impl Iterator<Item = usize>,
    window: [u32; 2],
    f: &F,
    ahead: Ahead<'_>,
    cut: Option<EarlyCut<'_>>,
    skip: Option<TileSkip<'_>>,
) -> u64 {
    let width = setup.width;
    let mut batch = Batch::new();
    let (mut len, mut n, mut behind) = (0usize, 0u64, 0u64);
    // lane i of each layout: its column and row in the box
    let columns = [
        _mm256_setr_epi32(0, 1, 0, 1, 0, 1, 0, 1),
        _mm256_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
    ];
    let rows = [
        _mm256_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3),
        _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1),
        _mm256_setzero_si256(),
    ];
    let pixel_offsets = std::array::from_fn::<_, 3, _>(|l| {
        _mm256_add_epi32(columns[l], _mm256_mullo_epi32(rows[l], _mm256_set1_epi32(width as i32)))
    });
    let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
    for i in order {
        let (t, s) = (&tris[i], &edges[i]);
        let box_y0 = s.bbox[1];
        // the box's rows inside the task's
        let [x0, y0, x1, y1] = in_rows(s.bbox, window);
        if !s.small {
            let bound = skip.as_ref().map(|tiles| (tiles, DepthBound::new(&s.plane)));
            behind += walk_spans(t, [x0, y0, x1, y1], bound, |x, y, e| {
                if len == CAP {
                    flush::<SHADE, F>(setup, (tris, edges, shades), &mut batch, len, f, ahead, cut);
                    len = 0;
                }
                let b = s.plane.barycentrics(e);
                batch.tri[len] = i as u32;
                batch.pixel[len] = y * width + x;
                batch.depth[len] = s.plane.depth(b);
                for (lanes, b) in batch.b.iter_mut().zip(b) {
                    lanes[len] = b;
                }
                len += 1;
                n += 1;
            });
            continue;
        }
        if x0 > x1 || y0 > y1 {
            continue;
        }
        // the whole box behind the opaque depth: its coverage counted, nothing batched
        let hidden = skip.as_ref().is_some_and(|tiles| tiles.small_behind(s, [x0, y0, x1, y1]));
        let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
        let l = layout(w);
        let (lanes_x, lanes_y) = (COLUMNS[l], 8 / COLUMNS[l]);
        // as in walk_small: the lanes hold e − (above + 1), covered where the sign bit is clear
        let bias: [i32; 3] = std::array::from_fn(|k| s.above[k] + 1);
        let offsets: [__m256i; 3] = std::array::from_fn(|k| {
            _mm256_add_epi32(
                _mm256_mullo_epi32(columns[l], _mm256_set1_epi32(s.step_x[k])),
                _mm256_mullo_epi32(rows[l], _mm256_set1_epi32(s.step_y[k])),
            )
        });
        let bias_lanes = bias.map(|v| _mm256_set1_epi32(v));
        let column_step: [i32; 3] = std::array::from_fn(|k| s.step_x[k].wrapping_mul(lanes_x as i32));
        let row_step: [i32; 3] = std::array::from_fn(|k| s.step_y[k].wrapping_mul(lanes_y as i32));
        let inv_area = _mm256_set1_ps(s.plane.inv_area);
        let (z0, dz1, dz2) =
            (_mm256_set1_ps(s.plane.z0), _mm256_set1_ps(s.plane.dz1), _mm256_set1_ps(s.plane.dz2));
        let tri = _mm256_set1_epi32(i as i32);
        // the edge functions at the first row walked, `y0 − box_y0` rows below the box's top
        // (exact modulo 2^32, as every lane is: see walk_small)
        let skipped = (y0 - box_y0) as i32;
        let mut row: [i32; 3] = std::array::from_fn(|k| {
            s.origin[k].wrapping_add(s.step_y[k].wrapping_mul(skipped)).wrapping_sub(bias[k])
        });
        let mut row_pixel = y0 * width + x0;
        let mut by = 0;
        while by < h {
            let rows_valid = (1u32 << (lanes_x * (h - by).min(lanes_y))) - 1;
            let mut base = row;
            let mut bx = 0;
            while bx < w {
                let valid = (((1u32 << (w - bx).min(lanes_x)) - 1) * ROW_PATTERN[l]) & rows_valid;
                if len > CAP - 8 {
                    flush::<SHADE, F>(setup, (tris, edges, shades), &mut batch, len, f, ahead, cut);
                    len = 0;
                }
                let e: [__m256i; 3] =
                    std::array::from_fn(|k| _mm256_add_epi32(_mm256_set1_epi32(base[k]), offsets[k]));
                let sign = _mm256_or_si256(_mm256_or_si256(e[0], e[1]), e[2]);
                let covered = !(_mm256_movemask_ps(_mm256_castsi256_ps(sign)) as u32) & valid;
                if hidden {
                    behind += u64::from(covered.count_ones());
                    bx += lanes_x;
                    for k in 0..3 {
                        base[k] = base[k].wrapping_add(column_step[k]);
                    }
                    continue;
                }
                let pack = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(PACK[covered as usize] as i64));
                let pixel = _mm256_add_epi32(_mm256_set1_epi32((row_pixel + bx) as i32), pixel_offsets[l]);
                store_u32(&mut batch.pixel, len, _mm256_permutevar8x32_epi32(pixel, pack));
                store_u32(&mut batch.tri, len, tri);
                // DepthPlane::barycentrics: the edge function (exact in the covered lanes) as f32,
                // times 1 / area
                let b: [__m256; 3] = std::array::from_fn(|k| {
                    _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(e[k], bias_lanes[k])), inv_area)
                });
                for (lanes, b) in batch.b.iter_mut().zip(b) {
                    store_f32(lanes, len, _mm256_permutevar8x32_ps(b, pack));
                }
                // DepthPlane::depth: (z0 + b1·dz1) + b2·dz2, then f32::clamp(0, 1): below 0 is 0,
                // then above 1 is 1 (NaN kept)
                let d = _mm256_add_ps(_mm256_add_ps(z0, _mm256_mul_ps(b[1], dz1)), _mm256_mul_ps(b[2], dz2));
                let d = _mm256_blendv_ps(d, zero, _mm256_cmp_ps::<_CMP_LT_OQ>(d, zero));
                let d = _mm256_blendv_ps(d, one, _mm256_cmp_ps::<_CMP_GT_OQ>(d, one));
                store_f32(&mut batch.depth, len, _mm256_permutevar8x32_ps(d, pack));
                len += covered.count_ones() as usize;
                n += u64::from(covered.count_ones());
                bx += lanes_x;
                for k in 0..3 {
                    base[k] = base[k].wrapping_add(column_step[k]);
                }
            }
            by += lanes_y;
            row_pixel += lanes_y * width;
            for k in 0..3 {
                row[k] = row[k].wrapping_add(row_step[k]);
            }
        }
    }
    flush::<SHADE, F>(setup, (tris, edges, shades), &mut batch, len, f, ahead, cut);
    if let Some(tiles) = &skip {
        tiles.count(behind);
    }
    n + behind
}

/// The multisampled walk ([`Rasterizer::for_each_masked_fragment`](super::Rasterizer::for_each_masked_fragment))
/// of one task: the triangles of `order` in the rows `window` (inclusive), each pixel where the
/// triangle covers any of the samples at `offsets` from the centre (in 1/256 pixel,
/// [`super::sample_offsets`]) handed to `f` with its coverage mask, shaded where `SHADE` (else
/// colours made where `f` asks); returns the fragments. The same fragments, masks, depths and
/// barycentrics as the portable walk ([`super::Rasterizer::walk_masked`]'s `masked_pixels`),
/// bit for bit: a small triangle's box is tested eight pixels at a time in the layouts of
/// [`scatter_task`], each sample's three edge functions as the centre's lanes plus a constant (the
/// sample's offset along the edge's steps, exact in 32 bits: a small triangle's edge functions
/// within a pixel of its box stay below 2^30), a sample inside where the OR of its three lanes
/// has the sign bit clear; the mask is made in the lanes (bit j of lane i: sample j of pixel i),
/// the pixels with a mask packed to the front as the single-sample walk packs its covered ones.
/// Larger triangles take the portable per-pixel test into the same batch. The centre's
/// barycentrics and depth are made in the lanes whether or not the centre is covered
/// (extrapolated, as the portable walk's). Where `ahead` is given, each pixel is asked for a
/// few fragments before its turn, as [`scatter_task`]'s batches do.
#[target_feature(enable = "avx2,popcnt")]
pub(super) fn masked_task<const SHADE: bool, K: Fn(u32) -> bool, F: Fn(&Fragment<'_>, u8)>(
    setup: &TriangleSetup,
    (tris, edges, shades): (&[Triangle], &[SmallEdges], &[ShadeRecord]),
    order: impl Iterator<Item = usize>,
    window: [u32; 2],
    offsets: &[(i64, i64)],
    (keep, ahead): (&K, Ahead<'_>),
    f: &F,
) -> u64 {
    let width = setup.width;
    let mut batch = Batch::new();
    let (mut len, mut n) = (0usize, 0u64);
    // the batch handed over in the order walked, the pixels `keep` turns down left out (and
    // not counted), each pixel asked for `AHEAD` fragments before its turn where `ahead` is
    // given (as `flush`); returns the fragments handed over
    let flush = |batch: &mut Batch, len: usize| {
        if SHADE {
            shade(setup, (tris, edges, shades), batch, len);
        }
        if let Some(ahead) = ahead {
            batch.pixel[..len].iter().take(AHEAD).for_each(|&p| ahead(p));
        }
        let mut kept = 0u64;
        for i in 0..len {
            if let Some(ahead) = ahead
                && i + AHEAD < len
            {
                ahead(batch.pixel[i + AHEAD]);
            }
            if keep(batch.pixel[i]) {
                f(&batch.fragment::<SHADE>(setup, (tris, edges), i), batch.mask[i] as u8);
                kept += 1;
            }
        }
        kept
    };
    let columns = [
        _mm256_setr_epi32(0, 1, 0, 1, 0, 1, 0, 1),
        _mm256_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
    ];
    let rows = [
        _mm256_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3),
        _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1),
        _mm256_setzero_si256(),
    ];
    let pixel_offsets = std::array::from_fn::<_, 3, _>(|l| {
        _mm256_add_epi32(columns[l], _mm256_mullo_epi32(rows[l], _mm256_set1_epi32(width as i32)))
    });
    let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
    let samples = offsets.len().min(8);
    let bits: [__m256i; 8] = std::array::from_fn(|j| _mm256_set1_epi32(1 << j));
    for i in order {
        let (t, s) = (&tris[i], &edges[i]);
        let box_y0 = s.bbox[1];
        let [x0, y0, x1, y1] = in_rows(s.bbox, window);
        if !s.small {
            super::masked_pixels(t, width, offsets, window, keep, |x, y, e, mask| {
                if len == CAP {
                    n += flush(&mut batch, len);
                    len = 0;
                }
                let b = s.plane.barycentrics(e);
                batch.tri[len] = i as u32;
                batch.pixel[len] = y * width + x;
                batch.depth[len] = s.plane.depth(b);
                for (lanes, b) in batch.b.iter_mut().zip(b) {
                    lanes[len] = b;
                }
                batch.mask[len] = u32::from(mask);
                len += 1;
            });
            continue;
        }
        if x0 > x1 || y0 > y1 {
            continue;
        }
        let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
        let l = layout(w);
        let (lanes_x, lanes_y) = (COLUMNS[l], 8 / COLUMNS[l]);
        // as in walk_small: the lanes hold e − (above + 1), inside where the sign bit is clear
        let bias: [i32; 3] = std::array::from_fn(|k| s.above[k] + 1);
        let lane_offsets: [__m256i; 3] = std::array::from_fn(|k| {
            _mm256_add_epi32(
                _mm256_mullo_epi32(columns[l], _mm256_set1_epi32(s.step_x[k])),
                _mm256_mullo_epi32(rows[l], _mm256_set1_epi32(s.step_y[k])),
            )
        });
        // sample j's three edge values less the centre's (walk_masked's deltas, in 32 bits)
        let deltas: [[__m256i; 3]; 8] = std::array::from_fn(|j| {
            let (ox, oy) = offsets.get(j).copied().unwrap_or_default();
            std::array::from_fn(|k| {
                let d = i64::from(s.step_x[k]) / oit_core::setup::SUBPIXEL * ox
                    + i64::from(s.step_y[k]) / oit_core::setup::SUBPIXEL * oy;
                _mm256_set1_epi32(d as i32)
            })
        });
        let bias_lanes = bias.map(|v| _mm256_set1_epi32(v));
        let column_step: [i32; 3] = std::array::from_fn(|k| s.step_x[k].wrapping_mul(lanes_x as i32));
        let row_step: [i32; 3] = std::array::from_fn(|k| s.step_y[k].wrapping_mul(lanes_y as i32));
        let inv_area = _mm256_set1_ps(s.plane.inv_area);
        let (z0, dz1, dz2) =
            (_mm256_set1_ps(s.plane.z0), _mm256_set1_ps(s.plane.dz1), _mm256_set1_ps(s.plane.dz2));
        let tri = _mm256_set1_epi32(i as i32);
        let skipped = (y0 - box_y0) as i32;
        let mut row: [i32; 3] = std::array::from_fn(|k| {
            s.origin[k].wrapping_add(s.step_y[k].wrapping_mul(skipped)).wrapping_sub(bias[k])
        });
        let mut row_pixel = y0 * width + x0;
        let mut by = 0;
        while by < h {
            let rows_valid = (1u32 << (lanes_x * (h - by).min(lanes_y))) - 1;
            let mut base = row;
            let mut bx = 0;
            while bx < w {
                let valid = (((1u32 << (w - bx).min(lanes_x)) - 1) * ROW_PATTERN[l]) & rows_valid;
                if len > CAP - 8 {
                    n += flush(&mut batch, len);
                    len = 0;
                }
                let e: [__m256i; 3] =
                    std::array::from_fn(|k| _mm256_add_epi32(_mm256_set1_epi32(base[k]), lane_offsets[k]));
                // each sample's bit where its three edge functions are all inside
                let mut mask = _mm256_setzero_si256();
                for (d, bit) in deltas.iter().zip(&bits).take(samples) {
                    let sign = _mm256_or_si256(
                        _mm256_or_si256(_mm256_add_epi32(e[0], d[0]), _mm256_add_epi32(e[1], d[1])),
                        _mm256_add_epi32(e[2], d[2]),
                    );
                    mask = _mm256_or_si256(mask, _mm256_andnot_si256(_mm256_srai_epi32::<31>(sign), *bit));
                }
                let empty =
                    _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(mask, _mm256_setzero_si256())));
                let covered = !(empty as u32) & valid;
                if covered != 0 {
                    let pack = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(PACK[covered as usize] as i64));
                    let pixel =
                        _mm256_add_epi32(_mm256_set1_epi32((row_pixel + bx) as i32), pixel_offsets[l]);
                    store_u32(&mut batch.pixel, len, _mm256_permutevar8x32_epi32(pixel, pack));
                    store_u32(&mut batch.tri, len, tri);
                    store_u32(&mut batch.mask, len, _mm256_permutevar8x32_epi32(mask, pack));
                    // DepthPlane::barycentrics of the centre's edge functions (exact in the
                    // lanes, outside the triangle too), then DepthPlane::depth
                    let b: [__m256; 3] = std::array::from_fn(|k| {
                        _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(e[k], bias_lanes[k])), inv_area)
                    });
                    for (lanes, b) in batch.b.iter_mut().zip(b) {
                        store_f32(lanes, len, _mm256_permutevar8x32_ps(b, pack));
                    }
                    let d =
                        _mm256_add_ps(_mm256_add_ps(z0, _mm256_mul_ps(b[1], dz1)), _mm256_mul_ps(b[2], dz2));
                    let d = _mm256_blendv_ps(d, zero, _mm256_cmp_ps::<_CMP_LT_OQ>(d, zero));
                    let d = _mm256_blendv_ps(d, one, _mm256_cmp_ps::<_CMP_GT_OQ>(d, one));
                    store_f32(&mut batch.depth, len, _mm256_permutevar8x32_ps(d, pack));
                    len += covered.count_ones() as usize;
                }
                bx += lanes_x;
                for k in 0..3 {
                    base[k] = base[k].wrapping_add(column_step[k]);
                }
            }
            by += lanes_y;
            row_pixel += lanes_y * width;
            for k in 0..3 {
                row[k] = row[k].wrapping_add(row_step[k]);
            }
        }
    }
    n + flush(&mut batch, len)
}

/// Shades the first `len` fragments of `batch` [`SHADE_LANES`] at a time (where `SHADE`), then
/// hands each to `f` in the order walked.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn flush<const SHADE: bool, F: Fn(&Fragment<'_>)>(
    setup: &TriangleSetup,
    (tris, edges, shades): (&[Triangle], &[SmallEdges], &[ShadeRecord]),
    batch: &mut Batch,
    len: usize,
    f: &F,
    ahead: Ahead<'_>,
    cut: Option<EarlyCut<'_>>,
) {
    // behind the opaque depth: dropped before the batch is shaded, the rest packed to the front
    let len = match cut {
        None => len,
        Some(cut) => {
            let mut kept = 0;
            for i in 0..len {
                if !cut.holds_back(batch.pixel[i], batch.depth[i]) {
                    batch.tri[kept] = batch.tri[i];
                    batch.pixel[kept] = batch.pixel[i];
                    batch.depth[kept] = batch.depth[i];
                    for k in 0..3 {
                        batch.b[k][kept] = batch.b[k][i];
                    }
                    kept += 1;
                }
            }
            kept
        }
    };
    if SHADE {
        shade(setup, (tris, edges, shades), batch, len);
    }
    let emit = |i: usize| f(&batch.fragment::<SHADE>(setup, (tris, edges), i));
    let pixels = &batch.pixel[..len];
    match ahead {
        Some(ahead) => {
            // the first few asked for together, then each AHEAD fragments before its turn
            pixels.iter().take(AHEAD).for_each(|&p| ahead(p));
            for i in 0..len {
                if let Some(&p) = pixels.get(i + AHEAD) {
                    ahead(p);
                }
                emit(i);
            }
        }
        None => (0..len).for_each(emit),
    }
}

impl Batch {
    /// Fragment `i` of the batch (its colour where `SHADE`, else made where the shader asks).
    #[inline]
    fn fragment<'a, const SHADE: bool>(
        &self,
        setup: &'a TriangleSetup,
        (tris, edges): (&'a [Triangle], &[SmallEdges]),
        i: usize,
    ) -> Fragment<'a> {
        let tri = self.tri[i] as usize;
        Fragment {
            pixel: self.pixel[i],
            depth: self.depth[i],
            prim: edges[tri].prim,
            b: [self.b[0][i], self.b[1][i], self.b[2][i]],
            t: &tris[tri],
            setup,
            color: SHADE.then(|| Vec4::from_slice(&self.color[4 * i..4 * i + 4])),
        }
    }
}

/// Colours the first `len` fragments of `batch`, [`SHADE_LANES`] at a time.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn shade(
    setup: &TriangleSetup,
    (tris, _, shades): (&[Triangle], &[SmallEdges], &[ShadeRecord]),
    batch: &mut Batch,
    len: usize,
) {
    // a short last group shades what the lanes past `len` hold from before (a triangle of the
    // task, its colour not read)
    for at in (0..len).step_by(SHADE_LANES) {
        let lane = |k: usize| -> [f32; SHADE_LANES] { std::array::from_fn(|i| batch.b[k][at + i]) };
        let b = [lane(0), lane(1), lane(2)];
        let tri: [usize; SHADE_LANES] = std::array::from_fn(|i| batch.tri[at + i] as usize);
        let colors: [f32; 4 * SHADE_LANES] = if setup.shading == Shading::Headlight {
            // textured: each lane's base times its texture's sample, in lanes too
            let textured = setup.has_textures().then(|| (setup, tri.map(|t| &tris[t])));
            headlight(tri.map(|t| &shades[t]), b.map(bytemuck::cast), setup.forward, textured)
        } else {
            let colors =
                setup.colors_at(tri.map(|t| &tris[t]), std::array::from_fn(|i| [b[0][i], b[1][i], b[2][i]]));
            bytemuck::cast(colors.map(|c| c.to_array()))
        };
        batch.color[4 * at..4 * (at + SHADE_LANES)].copy_from_slice(&colors);
    }
}

/// Columns of the 8×8 matrix whose rows are `rows`.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn transpose(rows: [__m256; 8]) -> [__m256; 8] {
    let t: [__m256; 8] = std::array::from_fn(|i| {
        let (a, b) = (rows[i & !1], rows[i | 1]);
        if i % 2 == 0 { _mm256_unpacklo_ps(a, b) } else { _mm256_unpackhi_ps(a, b) }
    });
    // s[4h + j]: column j (low half) and j + 4 (high half) of rows 4h..4h + 4
    let s: [__m256; 8] = std::array::from_fn(|i| {
        let (h, j) = (i / 4, i % 4);
        let (a, b) = (t[4 * h + j / 2], t[4 * h + 2 + j / 2]);
        if j % 2 == 0 { _mm256_shuffle_ps::<0x44>(a, b) } else { _mm256_shuffle_ps::<0xEE>(a, b) }
    });
    std::array::from_fn(|j| {
        if j < 4 {
            _mm256_permute2f128_ps::<0x20>(s[j], s[4 + j])
        } else {
            _mm256_permute2f128_ps::<0x31>(s[j - 4], s[j])
        }
    })
}

/// [`oit_core::setup::headlight_colors`] in AVX2, the same operations in the same order (so the same
/// bits): lane `i` shaded from `records[i]` at barycentrics `b[k]`'s lane `i`; the colours
/// RGBA after one another.
///
/// Where `textured` gives the setup and each lane's triangle, a lane's base is multiplied by its
/// texture's sample first ([`texture_lanes`]), as [`TriangleSetup::textured`] multiplies it.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn headlight(
    records: [&ShadeRecord; SHADE_LANES],
    b: [__m256; 3],
    forward: glam::Vec3,
    textured: Option<(&TriangleSetup, [&Triangle; SHADE_LANES])>,
) -> [f32; 4 * SHADE_LANES] {
    // each record's 16 words as two rows, turned into one vector of lanes per word
    let low = transpose(records.map(|r| {
        let [n0, n1, _] = r.normal;
        bytemuck::cast::<[f32; 8], __m256>([
            r.inv_w[0], r.inv_w[1], r.inv_w[2], n0[0], n0[1], n0[2], n1[0], n1[1],
        ])
    }));
    let high = transpose(records.map(|r| {
        let [_, n1, n2] = r.normal;
        bytemuck::cast::<[f32; 8], __m256>([
            n1[2], n2[0], n2[1], n2[2], r.base.x, r.base.y, r.base.z, r.base.w,
        ])
    }));
    let iw = [low[0], low[1], low[2]];
    let normal = [[low[3], low[4], low[5]], [low[6], low[7], high[0]], [high[1], high[2], high[3]]];
    let mut base = [high[4], high[5], high[6], high[7]];
    let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
    let (add, mul) = (|a, b| _mm256_add_ps(a, b), |a, b| _mm256_mul_ps(a, b));
    // perspective(): q = b·(1/w), normalized by their sum ((q0 + q1) + q2)
    let q: [__m256; 3] = std::array::from_fn(|k| mul(b[k], iw[k]));
    let inv_q = _mm256_div_ps(one, add(add(q[0], q[1]), q[2]));
    let p = q.map(|q| mul(q, inv_q));
    if let Some((setup, tris)) = textured {
        let sample = texture_lanes(setup, tris, p);
        base = std::array::from_fn(|c| mul(base[c], sample[c]));
    }
    // interpolated_normal(): (n0·p0 + n1·p1) + n2·p2, per component
    let n: [__m256; 3] = std::array::from_fn(|c| {
        add(add(mul(normal[0][c], p[0]), mul(normal[1][c], p[1])), mul(normal[2][c], p[2]))
    });
    // normalize_or_zero: 1 / sqrt of the dot product where it is finite and positive
    let rcp = _mm256_div_ps(one, _mm256_sqrt_ps(add(add(mul(n[0], n[0]), mul(n[1], n[1])), mul(n[2], n[2]))));
    let unit = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GT_OQ>(rcp, zero),
        _mm256_cmp_ps::<_CMP_LT_OQ>(rcp, _mm256_set1_ps(f32::INFINITY)),
    );
    let u = n.map(|n| _mm256_and_ps(mul(n, rcp), unit));
    let along = add(
        add(mul(u[0], _mm256_set1_ps(forward.x)), mul(u[1], _mm256_set1_ps(forward.y))),
        mul(u[2], _mm256_set1_ps(forward.z)),
    );
    let magnitude = _mm256_andnot_ps(_mm256_set1_ps(-0.0), along);
    let light = add(_mm256_set1_ps(0.3), mul(_mm256_set1_ps(0.7), magnitude));
    // glam's Vec3::clamp: the larger by `>` with 0, then the smaller by `<` with 1
    let rgb = [0, 1, 2].map(|c| {
        let v = mul(base[c], light);
        let v = _mm256_and_ps(v, _mm256_cmp_ps::<_CMP_GT_OQ>(v, zero));
        _mm256_blendv_ps(one, v, _mm256_cmp_ps::<_CMP_LT_OQ>(v, one))
    });
    // f32::clamp(0, 1) of the alpha: below 0 is 0, then above 1 is 1 (NaN kept)
    let a = base[3];
    let a = _mm256_blendv_ps(a, zero, _mm256_cmp_ps::<_CMP_LT_OQ>(a, zero));
    let a = _mm256_blendv_ps(a, one, _mm256_cmp_ps::<_CMP_GT_OQ>(a, one));
    // RGBA of lanes (0, 4), (1, 5), (2, 6), (3, 7), then in lane order
    let (rg_low, rg_high) = (_mm256_unpacklo_ps(rgb[0], rgb[1]), _mm256_unpackhi_ps(rgb[0], rgb[1]));
    let (ba_low, ba_high) = (_mm256_unpacklo_ps(rgb[2], a), _mm256_unpackhi_ps(rgb[2], a));
    let c = [
        _mm256_shuffle_ps::<0x44>(rg_low, ba_low),
        _mm256_shuffle_ps::<0xEE>(rg_low, ba_low),
        _mm256_shuffle_ps::<0x44>(rg_high, ba_high),
        _mm256_shuffle_ps::<0xEE>(rg_high, ba_high),
    ];
    bytemuck::cast([
        _mm256_permute2f128_ps::<0x20>(c[0], c[1]),
        _mm256_permute2f128_ps::<0x20>(c[2], c[3]),
        _mm256_permute2f128_ps::<0x31>(c[0], c[1]),
        _mm256_permute2f128_ps::<0x31>(c[2], c[3]),
    ])
}

/// What a lane samples: its triangle's texture level, the level's size, how it wraps, and the
/// triangle's texture coordinates.
#[derive(Clone, Copy)]
struct TexLane<'a> {
    texels: &'a [[u8; 4]],
    size: [u32; 2],
    wrap: [Wrap; 2],
    uv: [[f32; 2]; 3],
}

impl<'a> TexLane<'a> {
    /// `t`'s lane, `None` where it has no texture.
    #[inline]
    fn of(setup: &'a TriangleSetup, t: &Triangle) -> Option<TexLane<'a>> {
        let texture = setup.textures.get(t.texture as usize)?;
        let level = texture.level(t.lod);
        Some(TexLane {
            texels: &level.texels,
            size: [level.width, level.height],
            wrap: texture.wrap,
            uv: t.uv.map(|uv| uv.to_array()),
        })
    }
}

/// The texture samples of eight lanes: lane `i` is the linear RGBA that
/// [`TriangleSetup::textured`] multiplies `tris[i]`'s base by at perspective weights `p`'s lane
/// `i` (1 in every channel where the triangle has no texture), bit for bit. The sampler of
/// `oit_core::texture` step by step ([`sample_lanes`]); lanes of one triangle, the most common
/// group, read it once.
///
/// The vector steps are written as functions compiled for AVX2, not as closures handed to
/// `array::map`: such a closure is not inlined into the generic `map` (compiled without AVX2),
/// and each lane's call passed its vectors through memory (the first version of this sampler,
/// 2.8 times the untextured pass).
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn texture_lanes(setup: &TriangleSetup, tris: [&Triangle; SHADE_LANES], p: [__m256; 3]) -> [__m256; 4] {
    const N: usize = SHADE_LANES;
    let first = tris[0];
    if tris.iter().all(|&t| std::ptr::eq(t, first)) {
        let Some(lane) = TexLane::of(setup, first) else { return [_mm256_set1_ps(1.0); 4] };
        let mut uv = [[_mm256_setzero_ps(); 3]; 2];
        for (k, c) in lane.uv.iter().enumerate() {
            uv[0][k] = _mm256_set1_ps(c[0]);
            uv[1][k] = _mm256_set1_ps(c[1]);
        }
        let size = [_mm256_set1_epi32(lane.size[0] as i32), _mm256_set1_epi32(lane.size[1] as i32)];
        return sample_lanes(
            p,
            (uv, size, _mm256_set1_epi32(-1)),
            |_, a, i| lane.wrap[a].apply(i, lane.size[a]),
            |_, at| lane.texels[at as usize],
        );
    }
    let lanes: [Option<TexLane<'_>>; N] = tris.map(|t| TexLane::of(setup, t));
    let (mut uv, mut size, mut live) = ([[[0f32; N]; 3]; 2], [[1u32; N]; 2], [0u32; N]);
    for (i, lane) in lanes.iter().enumerate() {
        // a lane without a texture: a 1×1 level at texel 0 (its indices are masked to 0)
        if let Some(lane) = lane {
            for (k, c) in lane.uv.iter().enumerate() {
                (uv[0][k][i], uv[1][k][i]) = (c[0], c[1]);
            }
            (size[0][i], size[1][i], live[i]) = (lane.size[0], lane.size[1], u32::MAX);
        }
    }
    let uv = uv.map(|axis| axis.map(bytemuck::cast::<[f32; N], __m256>));
    let size = size.map(bytemuck::cast::<[u32; N], __m256i>);
    sample_lanes(
        p,
        (uv, size, bytemuck::cast(live)),
        |i, a, at| lanes[i].map_or(0, |l| l.wrap[a].apply(at, l.size[a])),
        |i, at| lanes[i].map_or([255; 4], |l| l.texels[at as usize]),
    )
}

/// [`texture_lanes`]' sampler over lanes given as vectors: each lane's texture coordinates
/// (`uv[axis][vertex]`), its level's size (`size[axis]`) and whether it has a texture (`live`,
/// all ones), with `wrap(lane, axis, i)` wrapping texel index `i` into that lane's level and
/// `texel(lane, index)` reading its texel (a lane without a texture reads white, which decodes
/// to 1 in every channel). The texture coordinates `(uv0·p0 + uv1·p1) + uv2·p2`, each axis times
/// its level's size in 1/256 texel (one rounding), clamped and floored in integers, the two
/// texels wrapped (in lanes where both are inside the level, which is every tap but those at a
/// border; the others lane by lane by `wrap`), the four texels loaded lane by lane, then the
/// integer filter and the decoding table in lanes.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn sample_lanes(
    p: [__m256; 3],
    (uv, size, live): ([[__m256; 3]; 2], [__m256i; 2], __m256i),
    wrap: impl Fn(usize, usize, i32) -> u32,
    texel: impl Fn(usize, u32) -> [u8; 4],
) -> [__m256; 4] {
    const N: usize = SHADE_LANES;
    let mut at = [[[0u32; N]; 2]; 2];
    let mut weight = [_mm256_setzero_si256(); 2];
    for a in 0..2 {
        let u = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(uv[a][0], p[0]), _mm256_mul_ps(uv[a][1], p[1])),
            _mm256_mul_ps(uv[a][2], p[2]),
        );
        let (i0, f, outside) = texel_axis(u, size[a]);
        weight[a] = f;
        at[a] = [bytemuck::cast(i0), bytemuck::cast(_mm256_add_epi32(i0, _mm256_set1_epi32(1)))];
        // lanes with a texture whose two texels are not both inside the level: wrapped one by one
        let cross = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_and_si256(outside, live)));
        if cross != 0 {
            for i in (0..N).filter(|&i| cross & (1 << i) != 0) {
                for texel in &mut at[a] {
                    texel[i] = wrap(i, a, texel[i] as i32);
                }
            }
        }
    }
    // the four taps' texels, row by row (index 0 in a lane without a texture)
    let mut texels = [_mm256_setzero_si256(); 4];
    for (tap, texels) in texels.iter_mut().enumerate() {
        let (x, y): (__m256i, __m256i) = (bytemuck::cast(at[0][tap & 1]), bytemuck::cast(at[1][tap >> 1]));
        let index: [u32; N] =
            bytemuck::cast(_mm256_and_si256(_mm256_add_epi32(_mm256_mullo_epi32(y, size[0]), x), live));
        let mut words = [0u32; N];
        for i in 0..N {
            words[i] = u32::from_le_bytes(texel(i, index[i]));
        }
        *texels = bytemuck::cast(words);
    }
    let [fx, fy] = weight;
    let rgb = [
        filter_channel::<0>(texels, fx, fy),
        filter_channel::<8>(texels, fx, fy),
        filter_channel::<16>(texels, fx, fy),
    ];
    // decode: RGB through the sRGB table (looked up lane by lane: a gather is `unsafe`), A / 255
    let table = oit_core::texture::srgb_to_linear();
    let mut out = [_mm256_setzero_ps(); 4];
    for c in 0..3 {
        let codes: [u32; N] = bytemuck::cast(rgb[c]);
        let mut linear = [0f32; N];
        for i in 0..N {
            linear[i] = table[codes[i] as usize & 255];
        }
        out[c] = bytemuck::cast(linear);
    }
    out[3] = _mm256_div_ps(_mm256_cvtepi32_ps(filter_channel::<24>(texels, fx, fy)), _mm256_set1_ps(255.0));
    out
}

/// One axis of the sampler in lanes (`oit_core::texture`'s `axis` before wrapping): `u` times the
/// level's size `n` in 1/256 texel, clamped to ±2³⁰ and floored, less half a texel: the left
/// texel `i0`, the right one's weight in 1/256, and all ones where `i0` or `i0 + 1` is outside
/// `0..n`.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn texel_axis(u: __m256, n: __m256i) -> (__m256i, __m256i, __m256i) {
    let s = _mm256_mul_ps(u, _mm256_cvtepi32_ps(_mm256_slli_epi32::<8>(n)));
    // f32::clamp, NaN kept: max and min return their second operand where one is NaN
    let bound = (1u32 << 30) as f32;
    let s = _mm256_min_ps(_mm256_set1_ps(bound), _mm256_max_ps(_mm256_set1_ps(-bound), s));
    // `as i32` (NaN to 0), floored: one less where the truncation rounded up
    let ordered = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_ORD_Q>(s, s));
    let t = _mm256_and_si256(_mm256_cvttps_epi32(s), ordered);
    let above = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_cvtepi32_ps(t), s));
    let s = _mm256_sub_epi32(_mm256_add_epi32(t, above), _mm256_set1_epi32(128));
    let i0 = _mm256_srai_epi32::<8>(s);
    let f = _mm256_and_si256(s, _mm256_set1_epi32(255));
    // inside: 0 ≤ i0 ≤ n − 2 (n ≥ 1)
    let last = _mm256_sub_epi32(n, _mm256_set1_epi32(2));
    let outside =
        _mm256_or_si256(_mm256_cmpgt_epi32(_mm256_setzero_si256(), i0), _mm256_cmpgt_epi32(i0, last));
    (i0, f, outside)
}

/// The channel at bit `SHIFT` of the four taps' texels (top left, top right, bottom left, bottom
/// right) filtered as `oit_core::texture`'s `Taps::channel`: rows first, then columns, rounded
/// half up once, with the right and bottom weights `fx`, `fy` in 1/256.
#[inline]
#[target_feature(enable = "avx2,popcnt")]
fn filter_channel<const SHIFT: i32>(texels: [__m256i; 4], fx: __m256i, fy: __m256i) -> __m256i {
    let byte = _mm256_set1_epi32(255);
    let t00 = _mm256_and_si256(_mm256_srli_epi32::<SHIFT>(texels[0]), byte);
    let t10 = _mm256_and_si256(_mm256_srli_epi32::<SHIFT>(texels[1]), byte);
    let t01 = _mm256_and_si256(_mm256_srli_epi32::<SHIFT>(texels[2]), byte);
    let t11 = _mm256_and_si256(_mm256_srli_epi32::<SHIFT>(texels[3]), byte);
    let full = _mm256_set1_epi32(256);
    let (gx, gy) = (_mm256_sub_epi32(full, fx), _mm256_sub_epi32(full, fy));
    let top = _mm256_add_epi32(_mm256_mullo_epi32(t00, gx), _mm256_mullo_epi32(t10, fx));
    let bottom = _mm256_add_epi32(_mm256_mullo_epi32(t01, gx), _mm256_mullo_epi32(t11, fx));
    let sum = _mm256_add_epi32(_mm256_mullo_epi32(top, gy), _mm256_mullo_epi32(bottom, fy));
    _mm256_srli_epi32::<16>(_mm256_add_epi32(sum, _mm256_set1_epi32(1 << 15)))
}
