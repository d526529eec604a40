//! Accuracy against the reference: error pixel rate, PSNR, max error.
//!
//! The pixels compared are those *covered* by either image: where the reference counted a fragment,
//! and where the image differs from the reference although the reference counted none (there the
//! reference shows the background, so a difference is something the image drew that should not be
//! there). A frame with no such pixel has nothing to measure: its EPR and PSNR are NaN and
//! `covered` is 0, never a perfect score.

use serde::Serialize;

use crate::composite::linear_to_srgb8_f64;
use crate::{Frame, Image, OitError};

/// How far an image is from the reference, over the pixels either covers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Accuracy {
    /// Error pixel rate (HPG 2009 section 5.2): the share of covered pixels whose 8-bit colour
    /// differs from the reference by more than 1 in any channel, a fraction in [0, 1] (the
    /// command line's tables print it in per cent). NaN when nothing is covered
    /// (`covered == 0`; serialized as null).
    pub epr: f64,
    /// Peak signal-to-noise ratio in dB over covered pixels (infinite when identical; NaN when
    /// nothing is covered).
    pub psnr: f64,
    /// The largest channel difference, in [0, 1] (8-bit difference / 255), over every pixel.
    pub max_error: f64,
    /// Pixels counted: covered by the reference, or drawn by the image where the reference is
    /// empty (all pixels when the reference recorded no coverage).
    pub covered: u64,
    /// Of those, pixels counted as errors.
    pub error_pixels: u64,
    /// Of `covered`, pixels the reference leaves empty but the image draws on.
    pub covered_by_image_only: u64,
}

impl Accuracy {
    /// Nothing compared (no reference, or nothing covered): EPR and PSNR NaN, counts zero.
    pub fn unmeasured() -> Accuracy {
        Accuracy {
            epr: f64::NAN,
            psnr: f64::NAN,
            max_error: f64::NAN,
            covered: 0,
            error_pixels: 0,
            covered_by_image_only: 0,
        }
    }

    /// Whether any pixel was compared; when not, [`Accuracy::epr`] and [`Accuracy::psnr`] are
    /// NaN, not a perfect score.
    pub fn is_measured(&self) -> bool {
        self.covered > 0
    }
}

/// Largest difference over the colour channels of two pixels.
fn worst(a: &[u8; 4], b: &[u8; 4]) -> u8 {
    (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0)
}

/// Whether pixel `i` is compared: the reference covers it (or recorded no coverage), or the image
/// differs from the reference there.
fn counted(reference: &Frame, i: usize, worst: u8) -> bool {
    reference.layers.as_ref().is_none_or(|l| l[i] > 0) || worst > 0
}

/// Compares `image` with the reference frame, over the pixels either covers (see the module
/// docs).
pub fn accuracy(reference: &Frame, image: &Image) -> Result<Accuracy, OitError> {
    let r = &reference.image;
    if r.width != image.width || r.height != image.height {
        return Err(OitError::InvalidSettings(format!(
            "cannot compare a {}x{} image with a {}x{} reference",
            image.width, image.height, r.width, r.height
        )));
    }
    if let Some(layers) = &reference.layers
        && layers.len() != r.pixels.len()
    {
        return Err(OitError::InvalidSettings(format!(
            "the reference's coverage has {} entries for {} pixels",
            layers.len(),
            r.pixels.len()
        )));
    }
    let mut acc = Accuracy {
        epr: f64::NAN,
        psnr: f64::NAN,
        max_error: 0.0,
        covered: 0,
        error_pixels: 0,
        covered_by_image_only: 0,
    };
    let mut squared = 0.0f64;
    let mut max = 0u8;
    for (i, (a, b)) in r.pixels.iter().zip(&image.pixels).enumerate() {
        let w = worst(a, b);
        max = max.max(w);
        if !counted(reference, i, w) {
            continue;
        }
        acc.covered += 1;
        if reference.layers.as_ref().is_some_and(|l| l[i] == 0) {
            acc.covered_by_image_only += 1;
        }
        squared += (0..3).map(|c| f64::from(a[c].abs_diff(b[c])).powi(2)).sum::<f64>();
        if w > 1 {
            acc.error_pixels += 1;
        }
    }
    if acc.covered > 0 {
        acc.epr = acc.error_pixels as f64 / acc.covered as f64;
        let mse = squared / (acc.covered as f64 * 3.0);
        acc.psnr = if mse == 0.0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / mse).log10() };
    }
    acc.max_error = f64::from(max) / 255.0;
    Ok(acc)
}

/// An image of the per-pixel error, amplified ×8, over the pixels [`accuracy`] compares (the rest
/// are dark grey; pixels within 1/255 are black).
pub fn error_image(reference: &Frame, image: &Image) -> Image {
    let r = &reference.image;
    let mut out = Image::new(r.width, r.height, [40, 40, 40, 255]);
    for (i, (a, b)) in r.pixels.iter().zip(&image.pixels).enumerate() {
        let w = worst(a, b);
        if !counted(reference, i, w) {
            continue;
        }
        let t = (f32::from(w) * 8.0 / 255.0).min(1.0);
        let h = crate::composite::heat(t);
        out.pixels[i] = [(h.x * 255.0) as u8, (h.y * 255.0) as u8, (h.z * 255.0) as u8, 255];
        if w <= 1 {
            out.pixels[i] = [0, 0, 0, 255];
        }
    }
    out
}

/// Pixels whose centre lies within `r` pixels of a projected triangle edge of `scene` under
/// `camera`, in a `width`×`height` image (row-major, top row first). Two rasterizers may disagree
/// on these pixels (each snaps vertices and breaks edge ties its own way); on every other pixel
/// they cover the same triangles. A triangle with a vertex behind the eye marks the whole image
/// (its projected edges are not segments): the scenes of the suite are fitted by the camera and
/// never have one.
pub fn edge_mask(scene: &crate::Scene, camera: &crate::Camera, width: u32, height: u32, r: f32) -> Vec<bool> {
    let vp = camera.view_proj();
    let mut mask = vec![false; (width * height) as usize];
    for inst in &scene.instances {
        let (_, mesh) = scene.instance_parts(inst);
        let clip: Vec<glam::Vec4> =
            mesh.positions.iter().map(|p| vp * inst.transform.transform_point3(*p).extend(1.0)).collect();
        for t in &mesh.indices {
            let Some(s) = screen(t.map(|i| clip[i as usize]), width, height) else {
                mask.fill(true);
                return mask;
            };
            for k in 0..3 {
                mark_segment(&mut mask, width, height, s[k], s[(k + 1) % 3], r);
            }
        }
    }
    mask
}

/// Pixels whose centre lies within `r` pixels of a line where a transparent triangle of `scene`
/// passes through an opaque one (a surface crossing a wall), under `camera`, in a
/// `width`×`height` image. On those pixels a transparent fragment's depth lies within rounding of
/// the opaque depth, so two rasterizers that interpolate depth each its own way may cut it apart
/// (one keeps it, the other holds it back); elsewhere the cut is the same on both. Empty (all
/// `false`) where the scene has no opaque part (a masked object counts as opaque: its texels
/// are not read, so the mask may mark more than is cut); a triangle with a vertex behind the eye marks the
/// whole image, as in [`edge_mask`]. Coplanar pairs mark nothing (their ties are broken by
/// primitive id alike on every path). The opaque triangles are binned into screen cells by their
/// projected bounds, so a transparent triangle is tested only against those it may overlap.
pub fn crossing_mask(
    scene: &crate::Scene,
    camera: &crate::Camera,
    width: u32,
    height: u32,
    r: f32,
) -> Vec<bool> {
    use glam::Vec3;
    let vp = camera.view_proj();
    let mut mask = vec![false; (width * height) as usize];
    // world-space triangles and their screen bounds, opaque and transparent
    let mut opaque: Vec<([Vec3; 3], [f32; 4])> = Vec::new();
    let mut transparent: Vec<([Vec3; 3], [f32; 4])> = Vec::new();
    for inst in &scene.instances {
        let (object, mesh) = scene.instance_parts(inst);
        let world: Vec<Vec3> = mesh.positions.iter().map(|p| inst.transform.transform_point3(*p)).collect();
        for t in &mesh.indices {
            let w = t.map(|i| world[i as usize]);
            let Some(s) = screen(w.map(|p| vp * p.extend(1.0)), width, height) else {
                mask.fill(true);
                return mask;
            };
            let bounds = [
                s.iter().map(|v| v.x).fold(f32::INFINITY, f32::min) - r,
                s.iter().map(|v| v.y).fold(f32::INFINITY, f32::min) - r,
                s.iter().map(|v| v.x).fold(f32::NEG_INFINITY, f32::max) + r,
                s.iter().map(|v| v.y).fold(f32::NEG_INFINITY, f32::max) + r,
            ];
            if object.is_opaque_pass() { opaque.push((w, bounds)) } else { transparent.push((w, bounds)) }
        }
    }
    if opaque.is_empty() || transparent.is_empty() {
        return mask;
    }
    // the opaque triangles binned into CELL-pixel cells by their bounds
    const CELL: f32 = 32.0;
    let (cols, rows) =
        ((width as f32 / CELL).ceil().max(1.0) as usize, (height as f32 / CELL).ceil().max(1.0) as usize);
    let cell_range = |b: &[f32; 4]| -> Option<(usize, usize, usize, usize)> {
        if b[2] < 0.0 || b[3] < 0.0 || b[0] >= width as f32 || b[1] >= height as f32 {
            return None;
        }
        let c = |v: f32, n: usize| ((v.max(0.0) / CELL) as usize).min(n - 1);
        Some((c(b[0], cols), c(b[1], rows), c(b[2], cols), c(b[3], rows)))
    };
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); cols * rows];
    for (i, (_, b)) in opaque.iter().enumerate() {
        if let Some((x0, y0, x1, y1)) = cell_range(b) {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    cells[y * cols + x].push(i as u32);
                }
            }
        }
    }
    let overlap = |a: &[f32; 4], b: &[f32; 4]| a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3];
    // the last transparent triangle each opaque one was tested against
    let mut seen = vec![u32::MAX; opaque.len()];
    for (ti, (t, tb)) in transparent.iter().enumerate() {
        let Some((x0, y0, x1, y1)) = cell_range(tb) else { continue };
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &oi in &cells[y * cols + x] {
                    let (o, ob) = &opaque[oi as usize];
                    if seen[oi as usize] == ti as u32 || !overlap(tb, ob) {
                        continue;
                    }
                    seen[oi as usize] = ti as u32;
                    let Some((p, q)) = triangles_cross(t, o) else { continue };
                    let ends = [p, q].map(|e| vp * e.extend(1.0));
                    if let Some([a, b, _]) = screen([ends[0], ends[1], ends[1]], width, height) {
                        mark_segment(&mut mask, width, height, a, b, r);
                    }
                }
            }
        }
    }
    mask
}

/// A triangle's clip-space vertices in pixels (x right, y down); `None` where one lies behind
/// the eye.
fn screen(clip: [glam::Vec4; 3], width: u32, height: u32) -> Option<[glam::Vec2; 3]> {
    if clip.iter().any(|v| v.w <= 0.0) {
        return None;
    }
    let (w, h) = (width as f32, height as f32);
    Some(clip.map(|v| {
        let n = v.truncate() / v.w;
        glam::Vec2::new((n.x * 0.5 + 0.5) * w, (0.5 - n.y * 0.5) * h)
    }))
}

/// Marks the pixels of `mask` whose centre lies within `r` of the segment `a`–`b` (pixels).
fn mark_segment(mask: &mut [bool], width: u32, height: u32, a: glam::Vec2, b: glam::Vec2, r: f32) {
    use glam::Vec2;
    let (w, h) = (width as f32, height as f32);
    // the pixels of the segment's bounding box grown by r
    let lo = a.min(b) - Vec2::splat(r + 0.5);
    let hi = a.max(b) + Vec2::splat(r + 0.5);
    if hi.x < 0.0 || hi.y < 0.0 || lo.x >= w || lo.y >= h {
        return;
    }
    let (x0, y0) = (lo.x.max(0.0) as u32, lo.y.max(0.0) as u32);
    let (x1, y1) = (hi.x.min(w - 1.0).max(0.0) as u32, hi.y.min(h - 1.0).max(0.0) as u32);
    let ab = b - a;
    for y in y0..=y1 {
        for x in x0..=x1 {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
            if (a + ab * t - p).length() < r {
                mask[(y * width + x) as usize] = true;
            }
        }
    }
}

/// The segment where triangles `a` and `b` pass through each other, if they do (not where they
/// only lie in one plane): the part of the line where their planes meet that lies in both.
fn triangles_cross(a: &[glam::Vec3; 3], b: &[glam::Vec3; 3]) -> Option<(glam::Vec3, glam::Vec3)> {
    let na = (a[1] - a[0]).cross(a[2] - a[0]);
    let nb = (b[1] - b[0]).cross(b[2] - b[0]);
    let dir = na.cross(nb);
    if dir.length_squared() <= f32::EPSILON * na.length_squared() * nb.length_squared() {
        return None; // parallel or coplanar
    }
    let (p0, p1) = plane_crossing(a, nb, b[0])?;
    let (q0, q1) = plane_crossing(b, na, a[0])?;
    // both segments lie on the line along `dir`: their overlap
    let along = |p: glam::Vec3| p.dot(dir);
    let (p0, p1) = if along(p0) <= along(p1) { (p0, p1) } else { (p1, p0) };
    let (q0, q1) = if along(q0) <= along(q1) { (q0, q1) } else { (q1, q0) };
    let start = if along(p0) >= along(q0) { p0 } else { q0 };
    let end = if along(p1) <= along(q1) { p1 } else { q1 };
    (along(start) <= along(end)).then_some((start, end))
}

/// Where triangle `t` crosses the plane through `origin` with normal `n`: the segment between
/// the two points its edges meet the plane at; `None` where it lies on one side.
fn plane_crossing(
    t: &[glam::Vec3; 3],
    n: glam::Vec3,
    origin: glam::Vec3,
) -> Option<(glam::Vec3, glam::Vec3)> {
    let d = t.map(|p| n.dot(p - origin));
    if d.iter().all(|&x| x > 0.0) || d.iter().all(|&x| x < 0.0) || d.iter().all(|&x| x == 0.0) {
        return None;
    }
    let mut points = Vec::with_capacity(3);
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        if d[i] == 0.0 {
            points.push(t[i]);
        } else if (d[i] < 0.0) != (d[j] < 0.0) && d[j] != 0.0 {
            points.push(t[i] + (t[j] - t[i]) * (d[i] / (d[i] - d[j])));
        }
    }
    match points.as_slice() {
        [p] => Some((*p, *p)),
        [p, q, ..] => Some((*p, *q)),
        [] => None,
    }
}

/// Over the pixels `mask` leaves out: the worst channel difference (RGB) between `a` and `b`, and
/// how many pixels differ by more than 1.
pub fn differ_off_mask(a: &Image, b: &Image, mask: &[bool]) -> (u8, usize) {
    let (mut worst, mut differ) = (0u8, 0usize);
    for ((p, q), &edge) in a.pixels.iter().zip(&b.pixels).zip(mask) {
        if edge {
            continue;
        }
        let d = (0..3).map(|i| p[i].abs_diff(q[i])).max().unwrap_or(0);
        worst = worst.max(d);
        differ += usize::from(d > 1);
    }
    (worst, differ)
}

/// Slack for the f32 resolve against the f64 reference, in linear [0, 1]: 2⁻¹⁶, some hundred
/// times the rounding of a 32-layer f32 composite.
const F32_SLACK: f64 = 1.0 / 65536.0;

/// The smallest linear value the reference's encoding ([`linear_to_srgb8_f64`]) takes to `code`
/// or above (0 for code 0, 1 above 255), by bisection: the encoding rises with its input.
fn first_linear_of(code: u16) -> f64 {
    if code == 0 {
        return 0.0;
    }
    if code > 255 {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..64 {
        let mid = 0.5 * (lo + hi);
        if u16::from(linear_to_srgb8_f64(mid)) >= code { hi = mid } else { lo = mid }
    }
    hi
}

/// The 8-bit sRGB codes (lowest, highest) a pixel may hold where the reference holds `code` and
/// the linear colour behind the pixel is within `delta` of the reference's: every value the
/// reference could have had for `code`, moved by `delta` (and a slack for the f32 resolve's
/// rounding, 2⁻¹⁶) either way, encoded. With `delta` from [`crate::rules::bdp_color_error_bound`] this is bdp's colour-mode bound
/// per pixel; the window is widest where the pixel is dark (sRGB is steepest there).
pub fn packing_window(code: u8, delta: f64) -> (u8, u8) {
    let slack = delta.max(0.0) + F32_SLACK;
    let lo = linear_to_srgb8_f64(first_linear_of(u16::from(code)) - slack);
    let hi = linear_to_srgb8_f64(first_linear_of(u16::from(code) + 1) + slack);
    (lo, hi)
}

/// bdp's colour mode held to its bound ([`packing_check`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PackingCheck {
    /// Pixels checked: covered by the reference, none of their fragments lost.
    pub checked: u64,
    /// Of those, pixels whose colour is not the reference's: the quantization seen.
    pub differing: u64,
    /// Of those, pixels outside [`packing_window`] for their layer count: a defect.
    pub outside: u64,
    /// The largest channel difference over the checked pixels, in 8-bit steps.
    pub max_error: u8,
    /// The widest window allowed at a pixel that differs, in 8-bit steps (highest − lowest).
    pub widest_window: u8,
}

/// Holds `frame`, a frame of bdp's colour mode, to [`crate::rules::bdp_color_error_bound`]
/// against `reference` (whose per-pixel `layers` give each pixel's count), on the covered pixels
/// that lost nothing (by `frame.lost_pixels`; a frame without per-pixel losses is checked only
/// when it lost nothing at all).
pub fn packing_check(reference: &Frame, frame: &Frame) -> Result<PackingCheck, OitError> {
    let layers = reference.layers.as_ref().ok_or_else(|| {
        OitError::InvalidSettings("the reference recorded no per-pixel layers to bound by".into())
    })?;
    let (r, f) = (&reference.image, &frame.image);
    if r.width != f.width || r.height != f.height || layers.len() != r.pixels.len() {
        return Err(OitError::InvalidSettings("frame and reference differ in size".into()));
    }
    let lost = |i: usize| match &frame.lost_pixels {
        Some(l) => Ok(l[i] > 0),
        None if frame.stats.lost == 0 => Ok(false),
        None => Err(OitError::InvalidSettings(format!(
            "{} fragments lost and no per-pixel losses: cannot tell which pixels to bound",
            frame.stats.lost
        ))),
    };
    let mut out = PackingCheck::default();
    for (i, (a, b)) in r.pixels.iter().zip(&f.pixels).enumerate() {
        if layers[i] == 0 || lost(i)? {
            continue;
        }
        out.checked += 1;
        let delta = crate::rules::bdp_color_error_bound(layers[i]);
        let w = worst(a, b);
        out.max_error = out.max_error.max(w);
        if w == 0 {
            continue;
        }
        out.differing += 1;
        let mut inside = true;
        for c in 0..3 {
            let (lo, hi) = packing_window(a[c], delta);
            out.widest_window = out.widest_window.max(hi - lo);
            inside &= (lo..=hi).contains(&b[c]);
        }
        out.outside += u64::from(!inside);
    }
    Ok(out)
}

/// A frame's depth complexity: how many pixels hold 0, 1, 2, … fragments, from per-pixel
/// fragment counts (`Frame::layers`: the reference counts every fragment a pixel generates).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DepthComplexity {
    /// `histogram[n]`: pixels with n fragments (index 0: pixels nothing covers); as long as the
    /// deepest pixel's count + 1.
    pub histogram: Vec<u64>,
    /// The deepest pixel's fragments (0 when nothing is covered).
    pub max_depth: u32,
}

impl DepthComplexity {
    /// The histogram of per-pixel counts `layers`.
    pub fn from_layers(layers: &[u32]) -> DepthComplexity {
        let max_depth = layers.iter().copied().max().unwrap_or(0);
        let mut histogram = vec![0u64; max_depth as usize + 1];
        for &n in layers {
            histogram[n as usize] += 1;
        }
        DepthComplexity { histogram, max_depth }
    }

    /// The smallest count that `share` (in [0, 1]) of the covered pixels hold at most (`None`
    /// when nothing is covered).
    pub fn percentile(&self, share: f64) -> Option<u32> {
        let covered: u64 = self.histogram.iter().skip(1).sum();
        if covered == 0 {
            return None;
        }
        let want = (share.clamp(0.0, 1.0) * covered as f64).ceil().max(1.0) as u64;
        let mut seen = 0;
        for (n, &count) in self.histogram.iter().enumerate().skip(1) {
            seen += count;
            if seen >= want {
                return Some(n as u32);
            }
        }
        Some(self.max_depth)
    }

    /// One line: the share of pixels covered, the median, 90th and 99th percentiles of the
    /// covered pixels' counts and the deepest, e.g. `62.1% of pixels covered; layers per covered
    /// pixel: median 2, p90 5, p99 9, max 14`.
    pub fn summary(&self) -> String {
        let pixels: u64 = self.histogram.iter().sum();
        let covered = pixels - self.histogram.first().copied().unwrap_or(0);
        match (self.percentile(0.5), self.percentile(0.9), self.percentile(0.99)) {
            (Some(p50), Some(p90), Some(p99)) => format!(
                "{:.1}% of pixels covered; layers per covered pixel: median {p50}, p90 {p90}, p99 {p99}, max {}",
                100.0 * covered as f64 / pixels as f64,
                self.max_depth
            ),
            _ => "no pixel covered".into(),
        }
    }
}

#[cfg(test)]
mod tests {
    /// The window is the reference code's linear interval moved by the bound either way: one code
    /// of slack at each end with no bound (the f32 resolve may round across a threshold), wider
    /// with it, widest where dark. Values: code 128 holds linear [0.2140, 0.2195); a bound of
    /// 16/255 reaches 0.151 and 0.277, codes 108 and 144; code 10 holds [0.0029, 0.0032), and
    /// the bound reaches 0 and 0.066, codes 0 and 73. Mutations caught: the bound not added (`slack` without `delta`),
    /// the window taken around the code's value instead of its interval's ends, the encoding
    /// read as linear.
    #[test]
    fn packing_window_values() {
        use super::packing_window;
        for code in 1..=254u8 {
            let (lo, hi) = packing_window(code, 0.0);
            assert!(lo == code - 1 && hi == code + 1, "{code}: {lo}..={hi}");
        }
        assert_eq!(packing_window(0, 0.0), (0, 1));
        assert_eq!(packing_window(255, 0.0), (254, 255));
        assert_eq!(packing_window(128, 16.0 / 255.0), (108, 144));
        assert_eq!(packing_window(10, 16.0 / 255.0), (0, 73));
        assert_eq!(packing_window(250, 1.0), (0, 255));
    }

    #[test]
    fn depth_complexity() {
        let d = DepthComplexity::from_layers(&[0, 0, 1, 3, 1, 2, 0, 1, 1, 1, 2, 1]);
        assert_eq!(d.histogram, [3, 6, 2, 1]);
        assert_eq!(d.max_depth, 3);
        // 9 covered pixels: six of 1, two of 2, one of 3; the 90th percentile is the 9th pixel's
        assert_eq!((d.percentile(0.5), d.percentile(0.8), d.percentile(0.9)), (Some(1), Some(2), Some(3)));
        assert_eq!(
            d.summary(),
            "75.0% of pixels covered; layers per covered pixel: median 1, p90 3, p99 3, max 3"
        );
        let empty = DepthComplexity::from_layers(&[0, 0]);
        assert_eq!(
            (empty.histogram.as_slice(), empty.max_depth, empty.percentile(0.5)),
            (&[2u64][..], 0, None)
        );
        assert_eq!(empty.summary(), "no pixel covered");
    }

    use super::*;
    use crate::Stats;

    const BG: [u8; 4] = [20, 30, 40, 255];

    /// A 4×4 reference: background everywhere, a 2×2 covered block of distinct colours in the
    /// top-left corner.
    fn reference() -> Frame {
        let mut image = Image::new(4, 4, BG);
        let mut layers = vec![0u32; 16];
        for (k, i) in [0usize, 1, 4, 5].into_iter().enumerate() {
            image.pixels[i] = [100 + k as u8 * 30, 50, 200 - k as u8 * 40, 255];
            layers[i] = 2;
        }
        Frame { image, layers: Some(layers), lost_pixels: None, stats: Stats::default() }
    }

    #[test]
    fn identical_is_exact() {
        let r = reference();
        let a = accuracy(&r, &r.image).unwrap();
        assert_eq!((a.epr, a.psnr, a.max_error, a.covered, a.error_pixels), (0.0, f64::INFINITY, 0.0, 4, 0));
        assert!(a.is_measured());
    }

    #[test]
    fn one_pixel_off_by_two_is_an_error_and_by_one_is_not() {
        let r = reference();
        let mut img = r.image.clone();
        img.pixels[5][1] += 2;
        let a = accuracy(&r, &img).unwrap();
        assert_eq!((a.covered, a.error_pixels), (4, 1));
        assert_eq!(a.epr, 0.25);
        assert_eq!(a.max_error, 2.0 / 255.0);
        // MSE = 2² / (4 pixels × 3 channels)
        assert!((a.psnr - 10.0 * (255.0f64 * 255.0 * 12.0 / 4.0).log10()).abs() < 1e-12, "{}", a.psnr);
        img.pixels[5][1] -= 1;
        let a = accuracy(&r, &img).unwrap();
        assert_eq!(a.epr, 0.0, "1/255 is within tolerance");
        assert!(a.psnr.is_finite(), "but PSNR sees it");
    }

    #[test]
    fn garbage_where_the_reference_is_empty_is_counted() {
        let r = reference();
        let mut img = r.image.clone();
        // drawn on 3 pixels the reference leaves to the background
        for i in [10, 11, 15] {
            img.pixels[i] = [255, 0, 255, 255];
        }
        let a = accuracy(&r, &img).unwrap();
        assert_eq!((a.covered, a.covered_by_image_only, a.error_pixels), (7, 3, 3));
        assert_eq!(a.epr, 3.0 / 7.0);
        assert!(a.psnr.is_finite());
        let e = error_image(&r, &img);
        assert_ne!(e.pixels[10], [40, 40, 40, 255], "shown in the error image");
        assert_eq!(e.pixels[12], [40, 40, 40, 255], "untouched background stays grey");
        assert_eq!(e.pixels[0], [0, 0, 0, 255], "a matching covered pixel is black");
    }

    #[test]
    fn nothing_covered_is_not_a_perfect_score() {
        let mut r = reference();
        r.image = Image::new(4, 4, BG);
        r.layers = Some(vec![0; 16]);
        let a = accuracy(&r, &r.image).unwrap();
        assert_eq!(a.covered, 0);
        assert!(!a.is_measured());
        assert!(a.epr.is_nan() && a.psnr.is_nan(), "{a:?}");
        assert_eq!(a.max_error, 0.0);
        // and drawing anything into that empty frame is all error
        let mut img = r.image.clone();
        img.pixels[3] = [0, 0, 0, 255];
        let a = accuracy(&r, &img).unwrap();
        assert_eq!((a.covered, a.epr), (1, 1.0));
    }

    #[test]
    fn no_recorded_coverage_compares_every_pixel() {
        let mut r = reference();
        r.layers = None;
        let a = accuracy(&r, &r.image).unwrap();
        assert_eq!((a.covered, a.epr), (16, 0.0));
    }

    #[test]
    fn mismatched_sizes_are_an_error() {
        let r = reference();
        assert!(accuracy(&r, &Image::new(4, 5, BG)).unwrap_err().to_string().contains("4x5"));
        let mut short = reference();
        short.layers = Some(vec![1; 3]);
        assert!(accuracy(&short, &short.image).is_err());
    }

    /// Two triangles passing through each other meet on the overlap of their two crossings of
    /// each other's planes; parallel ones and ones whose crossings do not overlap do not meet.
    /// Mutation caught: the overlap taken as the union (the ends ±1 instead of ±½).
    #[test]
    fn triangles_cross_on_the_overlap() {
        use glam::Vec3;
        let a = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let b = [Vec3::new(0.0, -0.5, -1.0), Vec3::new(0.0, -0.5, 1.0), Vec3::new(0.0, 0.5, 0.0)];
        let (p, q) = super::triangles_cross(&a, &b).expect("they cross");
        let (lo, hi) = if p.y < q.y { (p, q) } else { (q, p) };
        assert!((lo - Vec3::new(0.0, -0.5, 0.0)).length() < 1e-6, "{lo}");
        assert!((hi - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-6, "{hi}");
        let lifted = a.map(|v| v + Vec3::Z);
        assert_eq!(super::triangles_cross(&a, &lifted), None, "parallel");
        let above = b.map(|v| v + Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(super::triangles_cross(&a, &above), None, "their crossings do not overlap");
    }

    /// A wall through the planes marks the lines where the planes cross it, a thin share of the
    /// image, and so does the masked wall of `nowall:` (a masked object is drawn in the opaque
    /// pass; the mask reads geometry, not texels or alpha, so it marks alike); planes alone mark
    /// nothing.
    #[test]
    fn crossing_mask_marks_where_surfaces_cross_the_wall() {
        let marked = |name: &str| {
            let scene = crate::load_scene(name).unwrap();
            let camera = crate::Camera::orbit_scene(&scene, crate::View::default(), 1.0).unwrap();
            super::crossing_mask(&scene, &camera, 128, 128, 1.0).iter().filter(|&&m| m).count()
        };
        let wall = marked("wall:0.5:planes:4");
        assert!(wall > 64 && wall < 128 * 128 / 8, "{wall} pixels marked");
        assert_eq!(marked("nowall:0.5:planes:4"), wall);
        assert_eq!(marked("planes:4"), 0);
    }
}
