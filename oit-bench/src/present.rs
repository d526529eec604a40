//! Presentation, shared by the command line and the bench: what is drawn on top of the images and
//! numbers that backends return, for a person to read.
//!
//! - [`draw_text`] and [`text_width`]: one line of text, set in DejaVu Sans (embedded from
//!   `oit-bench/assets/`, licence beside it) and rasterized with anti-aliasing by `ab_glyph`.
//! - [`fill_rect`]: a rectangle, blended by the colour's alpha.
//! - [`draw_heat_legend`] and [`heat_legend_rect`]: the key to a depth-complexity [`heat`] map,
//!   drawn by the front end from [`oit_core::Stats::max_layers`]; [`annotate_frame`] draws it
//!   where a frame's effect needs it.
//! - [`contact_sheet`] and [`sheet_layout`]: techniques in a grid, each captioned above its image
//!   and its error image.
//!
//! Contract: every function here clips at the image's edges and never panics, whatever the
//! coordinates, the text size or the image's size (an empty image, or one whose `pixels` is
//! shorter than `width × height`, draws what fits and nothing else). A text size that is not a
//! positive number draws nothing; sizes above [`MAX_TEXT_PX`] are drawn at that size.

use std::sync::LazyLock;

use ab_glyph::{Font, FontRef, GlyphId, PxScale, ScaleFont, point};
use oit_core::composite::{heat, linear_to_srgb8};
use oit_core::{Effect, Image, Stats};

/// The embedded font: DejaVu Sans 2.37, unmodified (Bitstream Vera licence, in
/// `oit-bench/assets/DejaVuSans-LICENSE.txt`).
pub const FONT_TTF: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The largest text size drawn, in pixels; larger sizes are drawn at this one.
pub const MAX_TEXT_PX: f32 = 512.0;

/// [`FONT_TTF`], parsed once.
static FONT: LazyLock<FontRef<'static>> = LazyLock::new(|| {
    FontRef::try_from_slice(FONT_TTF).expect("the embedded DejaVu Sans is a valid TrueType font")
});

/// A rectangle of pixels: top-left corner and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// Left edge.
    pub x: u32,
    /// Top edge.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Rect {
    /// Whether the pixel (`x`, `y`) lies inside.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x..self.x.saturating_add(self.width)).contains(&x)
            && (self.y..self.y.saturating_add(self.height)).contains(&y)
    }
}

/// `px` made safe to draw with: `None` for zero, negative or NaN, at most [`MAX_TEXT_PX`].
fn text_px(px: f32) -> Option<f32> {
    (px > 0.0).then(|| px.min(MAX_TEXT_PX))
}

/// Height in pixels of one line of text at size `px`: the font's ascent to its descent, `px`
/// rounded up (the size of a text is the height of its line). 0 for a size that draws nothing.
pub fn line_height(px: f32) -> u32 {
    text_px(px).map_or(0, |px| px.ceil() as u32)
}

/// The glyphs of one line of `text` at size `px` (kerned, control characters skipped), positioned
/// with the line's top-left corner at the origin, and the caret after the last one.
fn layout(text: &str, px: f32) -> (Vec<ab_glyph::Glyph>, f32) {
    let font = &*FONT;
    let scaled = font.as_scaled(PxScale::from(px));
    let mut glyphs = Vec::new();
    let mut caret = 0.0f32;
    let mut previous: Option<GlyphId> = None;
    for c in text.chars().filter(|c| !c.is_control()) {
        let id = font.glyph_id(c);
        if let Some(p) = previous {
            caret += scaled.kern(p, id);
        }
        glyphs.push(id.with_scale_and_position(px, point(caret, scaled.ascent())));
        caret += scaled.h_advance(id);
        previous = Some(id);
    }
    (glyphs, caret)
}

/// Width in pixels of `text` drawn at size `px`: its advance, rounded up. Its height is
/// [`line_height`]`(px)`. 0 for empty text or a size that draws nothing.
pub fn text_width(text: &str, px: f32) -> u32 {
    let Some(px) = text_px(px) else {
        return 0;
    };
    layout(text, px).1.ceil() as u32
}

/// `text`, shortened with "…" until it is at most `max_width` pixels wide at size `px`.
pub fn fit_text(text: &str, px: f32, max_width: u32) -> String {
    if text_width(text, px) <= max_width {
        return text.to_string();
    }
    let mut chars: Vec<char> = text.chars().collect();
    while !chars.is_empty() {
        chars.pop();
        let shorter = format!("{}…", chars.iter().collect::<String>().trim_end());
        if text_width(&shorter, px) <= max_width {
            return shorter;
        }
    }
    String::new()
}

/// Blends `color` over the pixel (`x`, `y`) with opacity `color`'s alpha × `coverage`; the
/// pixel's own alpha is kept. Nothing happens outside the image.
fn blend_pixel(image: &mut Image, x: i64, y: i64, color: [u8; 4], coverage: f32) {
    if x < 0 || y < 0 || x >= i64::from(image.width) || y >= i64::from(image.height) {
        return;
    }
    let index = y as u64 * u64::from(image.width) + x as u64;
    let Some(pixel) = usize::try_from(index).ok().and_then(|i| image.pixels.get_mut(i)) else {
        return;
    };
    let a = f32::from(color[3]) / 255.0 * coverage.clamp(0.0, 1.0);
    for (p, &c) in pixel[..3].iter_mut().zip(&color[..3]) {
        *p = (f32::from(c) * a + f32::from(*p) * (1.0 - a)).round() as u8;
    }
}

/// Fills the `w` × `h` rectangle whose top-left corner is (`x`, `y`) with `color`, blended by
/// its alpha (255 replaces, 0 leaves the image as it was); the image's own alpha is kept. Clips
/// at the edges.
pub fn fill_rect(image: &mut Image, x: i64, y: i64, w: u64, h: u64, color: [u8; 4]) {
    let x0 = x.max(0);
    let y0 = y.max(0);
    let x1 = x.saturating_add(i64::try_from(w).unwrap_or(i64::MAX)).min(i64::from(image.width));
    let y1 = y.saturating_add(i64::try_from(h).unwrap_or(i64::MAX)).min(i64::from(image.height));
    for py in y0..y1 {
        for px in x0..x1 {
            blend_pixel(image, px, py, color, 1.0);
        }
    }
}

/// Draws one line of `text` at size `px` (its line height in pixels) with its top-left corner
/// at (`x`, `y`), in `color` blended by its alpha and the glyphs' anti-aliased coverage.
/// Touches only the box [`text_width`] × [`line_height`] from (`x`, `y`), clipped to the image.
/// Characters the font lacks draw its missing-glyph box; control characters draw nothing.
pub fn draw_text(image: &mut Image, x: i64, y: i64, text: &str, px: f32, color: [u8; 4]) {
    let Some(px) = text_px(px) else {
        return;
    };
    if image.width == 0 || image.height == 0 || y >= i64::from(image.height) || x >= i64::from(image.width) {
        return;
    }
    let (glyphs, caret) = layout(text, px);
    let (box_w, box_h) = (i64::from(caret.ceil() as u32), i64::from(line_height(px)));
    if x.saturating_add(box_w) <= 0 || y.saturating_add(box_h) <= 0 {
        return;
    }
    for glyph in glyphs {
        let Some(outline) = FONT.outline_glyph(glyph) else {
            continue; // a space
        };
        let bounds = outline.px_bounds();
        let (gx, gy) = (bounds.min.x as i64, bounds.min.y as i64);
        if x.saturating_add(gx) >= i64::from(image.width) {
            break;
        }
        outline.draw(|ox, oy, coverage| {
            let (bx, by) = (gx + i64::from(ox), gy + i64::from(oy));
            if (0..box_w).contains(&bx) && (0..box_h).contains(&by) && coverage > 0.0 {
                blend_pixel(image, x.saturating_add(bx), y.saturating_add(by), color, coverage);
            }
        });
    }
}

/// Caption of the heat legend.
pub const LEGEND_CAPTION: &str = "fragments / pixel";

/// Where the parts of a heat legend go, all in pixels of the image.
struct LegendLayout {
    /// The dark box holding everything.
    frame: Rect,
    /// Text size.
    px: f32,
    /// Multiplier of every spacing: 1 up to 1023 pixels on the short side, 2 from 1024 and so on.
    scale: u64,
    /// Inner padding of the box.
    pad: u64,
    /// Space between the caption, the bar and the labels.
    gap: u64,
    /// The colour bar's width and height.
    bar: (u64, u64),
    /// Length of the two tick marks under the bar.
    tick: u64,
    /// The label at the bar's right end.
    max_label: String,
}

/// The heat legend's layout on a `width` × `height` image, or `None` when the image is too small
/// to hold it and its margin.
fn legend_layout(width: u32, height: u32, max: u32) -> Option<LegendLayout> {
    let scale = u64::from((width.min(height) / 512).max(1));
    let px = 13.0 * scale as f32;
    let (pad, margin, gap, tick) = (5 * scale, 8 * scale, 3 * scale, 3 * scale);
    let line = u64::from(line_height(px));
    let max_label = max.to_string();
    let needed = u64::from(text_width(LEGEND_CAPTION, px))
        .max(u64::from(text_width("1", px)) + 4 * gap + u64::from(text_width(&max_label, px)));
    let bar_w = (u64::from(width) / 4).clamp(needed, needed.max(128 * scale));
    let bar_h = 10 * scale;
    let box_w = pad + bar_w + pad;
    let box_h = pad + line + gap + bar_h + tick + line + pad;
    if box_w + 2 * margin > u64::from(width) || box_h + 2 * margin > u64::from(height) {
        return None;
    }
    let frame = Rect {
        x: (u64::from(width) - margin - box_w) as u32,
        y: (u64::from(height) - margin - box_h) as u32,
        width: box_w as u32,
        height: box_h as u32,
    };
    Some(LegendLayout { frame, px, scale, pad, gap, bar: (bar_w, bar_h), tick, max_label })
}

/// The rectangle [`draw_heat_legend`] covers on a `width` × `height` image (it changes nothing
/// outside), or `None` when it draws nothing there.
pub fn heat_legend_rect(width: u32, height: u32, max: u32) -> Option<Rect> {
    legend_layout(width, height, max).map(|l| l.frame)
}

/// Draws the key to a heat map of fragments per pixel in the bottom-right corner of `image`: a
/// dark translucent box holding the caption "fragments / pixel", a bar of [`heat`]`(t)` for `t`
/// from 0 at the left to 1 at the right, and tick labels "1" under its left end and `max` under
/// its right end. `max` is the frame's [`oit_core::Stats::max_layers`] (the count the map's
/// white stands for).
///
/// The text is 13 pixels high up to 1023 pixels on the short side, 26 from 1024 and so on; the
/// bar is a quarter of the image's width, no narrower than its labels and no wider than 128
/// pixels × that scale. An image too small to hold the legend and its margin is left unchanged.
pub fn draw_heat_legend(image: &mut Image, max: u32) {
    let Some(l) = legend_layout(image.width, image.height, max) else {
        return;
    };
    let f = l.frame;
    fill_rect(image, f.x.into(), f.y.into(), f.width.into(), f.height.into(), [0, 0, 0, 176]);
    let text = [225, 225, 225, 255];
    let line = i64::from(line_height(l.px));
    let x = i64::from(f.x) + l.pad as i64;
    let mut y = i64::from(f.y) + l.pad as i64;
    draw_text(image, x, y, LEGEND_CAPTION, l.px, text);
    y += line + l.gap as i64;
    let (bar_w, bar_h) = l.bar;
    for i in 0..bar_w {
        let t = if bar_w > 1 { i as f32 / (bar_w - 1) as f32 } else { 0.0 };
        let c = heat(t);
        let color = [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255];
        fill_rect(image, x + i as i64, y, 1, bar_h, color);
    }
    y += bar_h as i64;
    let right = x + bar_w as i64;
    fill_rect(image, x, y, l.scale, l.tick, text);
    fill_rect(image, right - l.scale as i64, y, l.scale, l.tick, text);
    y += l.tick as i64;
    draw_text(image, x, y, "1", l.px, text);
    let label_x = right - i64::from(text_width(&l.max_label, l.px));
    draw_text(image, label_x, y, &l.max_label, l.px, text);
}

/// Draws on a frame's image what a person needs to read it: for [`Effect::Complexity`] the heat
/// legend, its top label `stats.max_layers` (at least 1); nothing for the other effects.
pub fn annotate_frame(image: &mut Image, effect: Effect, stats: &Stats) {
    if effect == Effect::Complexity {
        draw_heat_legend(image, stats.max_layers.max(1));
    }
}

/// One technique's cell of a [`contact_sheet`].
#[derive(Clone, Debug, PartialEq)]
pub struct SheetEntry {
    /// Name shown on the first line of the header, e.g. the technique.
    pub label: String,
    /// The rendered picture.
    pub image: Image,
    /// Its error against the reference, drawn to the right of `image` when present.
    pub error: Option<Image>,
    /// Numbers shown on the second line of the header, e.g. "EPR 0.12%  PSNR 41.3 dB".
    pub caption: String,
}

/// Space around and between everything on a [`contact_sheet`], in pixels.
pub const SHEET_GAP: u32 = 10;

/// Text size of a cell's label on a [`contact_sheet`] of images up to
/// [`SHEET_TEXT_BASE_HEIGHT`] pixels tall.
pub const SHEET_LABEL_PX: u32 = 18;

/// Text size of a cell's caption on a [`contact_sheet`] of images up to
/// [`SHEET_TEXT_BASE_HEIGHT`] pixels tall.
pub const SHEET_CAPTION_PX: u32 = 16;

/// The tallest image for which a [`contact_sheet`]'s text keeps its base sizes; for taller images
/// the text grows in proportion (up to [`SHEET_TEXT_MAX_SCALE`]×): a caption is about a twelfth of
/// its image's height (43 pixels over 512-pixel images), so that it stays readable when the
/// sheet is shown scaled down to a screen's or a page's width.
pub const SHEET_TEXT_BASE_HEIGHT: u32 = 192;

/// The most a [`contact_sheet`]'s text grows over its base sizes.
pub const SHEET_TEXT_MAX_SCALE: f32 = 6.0;

/// Height of a cell's header on a [`contact_sheet`]: label, 2 pixels, caption, 6 pixels.
fn header_height(label_px: u32, caption_px: u32) -> u32 {
    label_px + 2 + caption_px + 6
}

/// Height of a cell's header at the base text sizes.
pub const SHEET_HEADER_HEIGHT: u32 = SHEET_LABEL_PX + 2 + SHEET_CAPTION_PX + 6;

/// The widest a header's text makes a cell at the base text sizes (growing with the text);
/// longer labels and captions are cut short with "…" to the cell's width.
pub const SHEET_HEADER_MAX_WIDTH: u32 = 420;

/// Background of a [`contact_sheet`].
pub const SHEET_BACKGROUND: [u8; 4] = [40, 40, 40, 255];

/// The grid of a [`contact_sheet`], in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SheetLayout {
    /// Cells side by side.
    pub columns: u32,
    /// Rows of cells.
    pub rows: u32,
    /// Text size of the labels: [`SHEET_LABEL_PX`] × the text's scale (tallest image height /
    /// [`SHEET_TEXT_BASE_HEIGHT`], from 1 to [`SHEET_TEXT_MAX_SCALE`]), rounded.
    pub label_px: u32,
    /// Text size of the captions: [`SHEET_CAPTION_PX`] × the same scale, rounded.
    pub caption_px: u32,
    /// Height of a cell's header: label, 2 pixels, caption, 6 pixels.
    pub header_height: u32,
    /// Width of every cell: the widest image with its error image beside it (and a gap between),
    /// or the widest header text up to [`SHEET_HEADER_MAX_WIDTH`] × the text's scale, whichever
    /// is wider.
    pub cell_width: u32,
    /// Height of every cell: `header_height` and the tallest image or error image.
    pub cell_height: u32,
    /// The sheet's width: `gap + columns × (cell_width + gap)`.
    pub width: u32,
    /// The sheet's height: `gap + rows × (cell_height + gap)`.
    pub height: u32,
}

impl SheetLayout {
    /// Top-left corner of the `index`-th cell (filled row by row).
    pub fn cell(&self, index: usize) -> (u64, u64) {
        let columns = u64::from(self.columns.max(1));
        let (col, row) = (index as u64 % columns, index as u64 / columns);
        let gap = u64::from(SHEET_GAP);
        (gap + col * (u64::from(self.cell_width) + gap), gap + row * (u64::from(self.cell_height) + gap))
    }
}

/// The grid for `entries`: every cell the same size, and the fewest columns that make the sheet
/// at least as wide as it is tall (so it reads when scaled down), each row full but the last.
/// No entries give a 1 × 1 sheet with no cells.
pub fn sheet_layout(entries: &[SheetEntry]) -> SheetLayout {
    if entries.is_empty() {
        let (label_px, caption_px, header_height) = (SHEET_LABEL_PX, SHEET_CAPTION_PX, SHEET_HEADER_HEIGHT);
        return SheetLayout {
            columns: 0,
            rows: 0,
            label_px,
            caption_px,
            header_height,
            cell_width: 0,
            cell_height: 0,
            width: 1,
            height: 1,
        };
    }
    let gap = u64::from(SHEET_GAP);
    let pair = |e: &SheetEntry| {
        let (ew, eh) = e.error.as_ref().map_or((0, 0), |e| (gap + u64::from(e.width), u64::from(e.height)));
        (u64::from(e.image.width) + ew, u64::from(e.image.height).max(eh))
    };
    let tallest = entries.iter().map(|e| pair(e).1).max().unwrap_or(0);
    let scale = (tallest as f32 / SHEET_TEXT_BASE_HEIGHT as f32).clamp(1.0, SHEET_TEXT_MAX_SCALE);
    let sized = |base: u32| (base as f32 * scale).round() as u32;
    let (label_px, caption_px) = (sized(SHEET_LABEL_PX), sized(SHEET_CAPTION_PX));
    let header_max = u64::from(sized(SHEET_HEADER_MAX_WIDTH));
    let header = |e: &SheetEntry| {
        let label = text_width(&e.label, label_px as f32);
        let caption = text_width(&e.caption, caption_px as f32);
        u64::from(label.max(caption)).min(header_max)
    };
    let cell_w = entries.iter().map(|e| pair(e).0.max(header(e))).max().unwrap_or(0).max(1);
    let header_height = header_height(label_px, caption_px);
    let cell_h = u64::from(header_height) + tallest;
    let n = entries.len() as u64;
    let rows_for = |c: u64| n.div_ceil(c);
    let columns = (1..=n).find(|&c| c * (cell_w + gap) >= rows_for(c) * (cell_h + gap)).unwrap_or(n);
    let rows = rows_for(columns);
    let clamp = |v: u64| u32::try_from(v).unwrap_or(u32::MAX);
    SheetLayout {
        columns: clamp(columns),
        rows: clamp(rows),
        label_px,
        caption_px,
        header_height,
        cell_width: clamp(cell_w),
        cell_height: clamp(cell_h),
        width: clamp(gap + columns * (cell_w + gap)),
        height: clamp(gap + rows * (cell_h + gap)),
    }
}

/// Copies `src` into `dst` with its top-left corner at (`x`, `y`), clipped.
fn blit(dst: &mut Image, src: &Image, x: u64, y: u64) {
    for sy in 0..u64::from(src.height) {
        for sx in 0..u64::from(src.width) {
            let Some(&p) = src.pixels.get((sy * u64::from(src.width) + sx) as usize) else {
                return;
            };
            let (Ok(dx), Ok(dy)) = (i64::try_from(x + sx), i64::try_from(y + sy)) else {
                return;
            };
            blend_pixel(dst, dx, dy, [p[0], p[1], p[2], 255], 1.0);
        }
    }
}

/// Lays `entries` out in a grid on a dark grey sheet, row by row in their order, as
/// [`sheet_layout`] sizes it: each cell has a header with its label and, under it, its caption in
/// light text (sized with the images, cut short with "…" where wider than the cell), and under the header its image with
/// its error image (if any) to the right, [`SHEET_GAP`] pixels between them. Images may differ in
/// size; each sits at its cell's top-left.
pub fn contact_sheet(entries: &[SheetEntry]) -> Image {
    let layout = sheet_layout(entries);
    let mut sheet = Image::new(layout.width, layout.height, SHEET_BACKGROUND);
    let (label_color, caption_color) = ([240, 240, 240, 255], [195, 195, 195, 255]);
    let (label_px, caption_px) = (layout.label_px as f32, layout.caption_px as f32);
    for (i, entry) in entries.iter().enumerate() {
        let (x, y) = layout.cell(i);
        let (tx, ty) = (x as i64, y as i64);
        let label = fit_text(&entry.label, label_px, layout.cell_width);
        draw_text(&mut sheet, tx, ty, &label, label_px, label_color);
        let caption = fit_text(&entry.caption, caption_px, layout.cell_width);
        let caption_y = ty + i64::from(layout.label_px) + 2;
        draw_text(&mut sheet, tx, caption_y, &caption, caption_px, caption_color);
        let iy = y + u64::from(layout.header_height);
        blit(&mut sheet, &entry.image, x, iy);
        if let Some(error) = &entry.error {
            blit(&mut sheet, error, x + u64::from(entry.image.width) + u64::from(SHEET_GAP), iy);
        }
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    const BLACK: [u8; 4] = [0, 0, 0, 255];
    const WHITE: [u8; 4] = [255, 255, 255, 255];
    const GREY: [u8; 4] = [128, 128, 128, 255];

    /// Pixels of `after` that differ from `before`, as (x, y).
    fn changed(before: &Image, after: &Image) -> Vec<(u32, u32)> {
        assert_eq!((before.width, before.height), (after.width, after.height));
        let mut out = Vec::new();
        for y in 0..after.height {
            for x in 0..after.width {
                if before.get(x, y) != after.get(x, y) {
                    out.push((x, y));
                }
            }
        }
        out
    }

    #[test]
    fn font_parses_and_covers_the_labels_characters() {
        let font = &*FONT;
        for c in "0123456789 azAZ.,:;-+_=%()[]/<>#*'\"!?|·×²≤°…μ".chars() {
            assert_ne!(font.glyph_id(c), GlyphId(0), "{c:?} is missing from the font");
        }
        assert_eq!(font.glyph_id('\u{10FFFD}'), GlyphId(0));
    }

    #[test]
    fn text_width_of_known_strings() {
        assert_eq!(text_width("", 16.0), 0);
        assert_eq!(text_width("abc", 0.0), 0);
        assert_eq!(text_width("abc", -3.0), 0);
        assert_eq!(text_width("abc", f32::NAN), 0);
        // Proportional: narrow letters take less room than wide ones.
        assert!(text_width("iiii", 16.0) < text_width("WWWW", 16.0));
        // Grows with the text and with the size (about in proportion).
        let w16 = text_width("PSNR 41.3 dB", 16.0);
        assert!(w16 > text_width("PSNR 41.3", 16.0));
        let w32 = text_width("PSNR 41.3 dB", 32.0);
        assert!((2 * w16).abs_diff(w32) <= 2, "{w16} at 16 px, {w32} at 32 px");
        // DejaVu Sans at a 16 px line: digits advance 0.636 em, the em being 16 / 1.164 px.
        assert_eq!(text_width("0000000000", 16.0), (10.0f32 * 0.636 * 16.0 / 1.164).ceil() as u32);
        // Control characters take no room; the size is capped.
        assert_eq!(text_width("a\nb", 16.0), text_width("ab", 16.0));
        assert_eq!(text_width("a", 1e9), text_width("a", MAX_TEXT_PX));
        assert_eq!(line_height(16.0), 16);
        assert_eq!(line_height(13.5), 14);
        assert_eq!(line_height(f32::NAN), 0);
    }

    #[test]
    fn draw_text_changes_pixels_only_inside_its_box() {
        for px in [9.0, 13.0, 16.0, 24.5, 40.0] {
            let before = Image::new(900, 80, BLACK);
            let mut after = before.clone();
            let (x, y, text) = (7, 5, "Hello, jgqy 42% [ok]? É·×²");
            draw_text(&mut after, x, y, text, px, WHITE);
            let diff = changed(&before, &after);
            assert!(diff.len() > 20, "{px} px drew only {} pixels", diff.len());
            let (x1, y1) = (x as u32 + text_width(text, px), y as u32 + line_height(px));
            for &(qx, qy) in &diff {
                assert!(
                    (x as u32..x1).contains(&qx) && (y as u32..y1).contains(&qy),
                    "{px} px: ({qx}, {qy}) is outside the text's box"
                );
            }
            // The text fills its box: ink near both ends and in the top and bottom quarters.
            let xs = diff.iter().map(|p| p.0);
            assert!(xs.clone().min().unwrap() < x as u32 + 3 + px as u32 / 4);
            assert!(xs.max().unwrap() + 3 + px as u32 / 2 > x1);
            let ys = diff.iter().map(|p| p.1);
            assert!(ys.clone().min().unwrap() < y as u32 + line_height(px) / 4);
            assert!(ys.max().unwrap() >= y1 - line_height(px) / 4 - 1, "no descenders at {px} px");
        }
    }

    #[test]
    fn draw_text_blends_by_alpha_and_coverage() {
        let mut image = Image::new(60, 60, BLACK);
        draw_text(&mut image, 2, 2, "|#", 40.0, [255, 255, 255, 0]);
        assert_eq!(image, Image::new(60, 60, BLACK));
        draw_text(&mut image, 2, 2, "|", 40.0, [200, 100, 50, 255]);
        // Full coverage in the stroke's middle gives the colour, partial coverage less of it.
        let values: Vec<[u8; 4]> = image.pixels.iter().copied().filter(|p| *p != BLACK).collect();
        assert!(values.contains(&[200, 100, 50, 255]), "no fully covered pixel");
        assert!(values.iter().all(|p| p[0] <= 200 && p[1] <= 100 && p[2] <= 50 && p[3] == 255));
        let mut half = Image::new(60, 60, BLACK);
        draw_text(&mut half, 2, 2, "|", 40.0, [200, 100, 50, 128]);
        assert!(half.pixels.contains(&[100, 50, 25, 255]));
    }

    #[test]
    fn draw_text_clips_and_never_panics() {
        let text = "Clip me: 0123456789 |#%";
        for px in [0.0, -1.0, f32::NAN, f32::INFINITY, 1.0, 12.0, 300.0, 1e9] {
            for &(x, y) in &[
                (-3, 2),
                (2, -3),
                (-1000, -1000),
                (30, 2),
                (2, 14),
                (39, 19),
                (i64::MIN, i64::MIN),
                (i64::MAX, i64::MAX),
                (i64::MIN, 0),
                (0, i64::MAX),
            ] {
                let mut image = Image::new(40, 20, BLACK);
                draw_text(&mut image, x, y, text, px, WHITE);
                assert_eq!(image.pixels.len(), 40 * 20);
            }
        }
        // A glyph straddling the left and top edges still draws its visible part.
        let mut image = Image::new(10, 10, BLACK);
        draw_text(&mut image, -4, -6, "#", 16.0, WHITE);
        assert_ne!(image, Image::new(10, 10, BLACK));
        // Empty images, and one whose pixels are fewer than its size claims.
        for mut image in [Image::new(0, 0, BLACK), Image::new(0, 5, BLACK), Image::new(5, 0, BLACK)] {
            draw_text(&mut image, 0, 0, text, 16.0, WHITE);
            draw_heat_legend(&mut image, 9);
            assert!(image.pixels.is_empty());
        }
        let mut short = Image { width: 300, height: 300, pixels: vec![BLACK; 10] };
        draw_text(&mut short, 0, 0, text, 16.0, WHITE);
        draw_heat_legend(&mut short, 9);
        assert_eq!(short.pixels.len(), 10);
    }

    #[test]
    fn fit_text_cuts_to_the_width() {
        assert_eq!(fit_text("short", 16.0, 500), "short");
        let long = "failed: storage of 4096 MiB exceeds the device's limit of 2048 MiB";
        let cut = fit_text(long, 16.0, 150);
        assert!(cut.ends_with('…') && cut.len() < long.len(), "{cut}");
        assert!(text_width(&cut, 16.0) <= 150);
        assert!(long.starts_with(cut.trim_end_matches('…')));
        assert_eq!(fit_text(long, 16.0, 0), "");
    }

    #[test]
    fn legend_skips_tiny_images() {
        assert_eq!(heat_legend_rect(60, 60, 12), None);
        let before = Image::new(60, 60, BLACK);
        let mut after = before.clone();
        draw_heat_legend(&mut after, 12);
        assert_eq!(before, after);
    }

    /// A complexity image as the backends make it: the heat map of a radial count, background
    /// where there is none.
    fn complexity_image(size: u32, max: u32) -> Image {
        let mut image = Image::new(size, size, [60, 64, 72, 255]);
        let c = size as f32 / 2.0;
        for y in 0..size {
            for x in 0..size {
                let r = ((x as f32 - c).powi(2) + (y as f32 - c).powi(2)).sqrt() / c;
                let n = ((1.0 - r) * max as f32).ceil();
                if n >= 1.0 {
                    let h = heat(n / max as f32);
                    image.pixels[(y * size + x) as usize] =
                        [linear_to_srgb8(h.x), linear_to_srgb8(h.y), linear_to_srgb8(h.z), 255];
                }
            }
        }
        image
    }

    #[test]
    fn legend_changes_only_its_area_in_the_bottom_right() {
        for (size, max) in [(256, 7), (256, u32::MAX), (512, 12), (1024, 31)] {
            let before = complexity_image(size, max.min(64));
            let mut after = before.clone();
            draw_heat_legend(&mut after, max);
            let rect = heat_legend_rect(size, size, max).expect("room for the legend");
            assert!(rect.x >= size / 2 && rect.y >= size * 3 / 4, "{size}: {rect:?} not in the corner");
            assert!(rect.x + rect.width <= size - 8 && rect.y + rect.height <= size - 8, "{size}: {rect:?}");
            let diff = changed(&before, &after);
            assert!(diff.len() * 2 > (rect.width * rect.height) as usize, "{size}: legend too faint");
            for (x, y) in diff {
                assert!(rect.contains(x, y), "{size}: ({x}, {y}) changed outside {rect:?}");
            }
            // The ramp's two ends are there: black at the left and white at the right of one row.
            let ramp_row = (rect.y..rect.y + rect.height).any(|y| {
                let row: Vec<[u8; 4]> = (rect.x..rect.x + rect.width).map(|x| after.get(x, y)).collect();
                row.contains(&[0, 0, 0, 255]) && row.contains(&[255, 255, 255, 255])
            });
            assert!(ramp_row, "{size}: no row runs from black to white");
        }
        // The larger label widens the legend.
        let narrow = heat_legend_rect(256, 256, 7).unwrap();
        let wide = heat_legend_rect(256, 256, u32::MAX).unwrap();
        assert!(wide.width >= narrow.width && wide.x <= narrow.x);
    }

    /// Every backend compiled in fills `max_layers` with the most fragments at one pixel (what
    /// the CPU reference counts), for the complexity map and for plain transparency; the front end
    /// draws the legend from it, inside the legend's area only, and only on complexity frames.
    #[cfg(feature = "cpu")]
    #[test]
    fn frames_carry_the_legends_count() {
        use oit_core::{Backend, Camera, Settings, Technique, View, load_scene};
        let scene = load_scene("spheres:3").unwrap();
        let camera = Camera::orbit_scene(&scene, View::default(), 1.0).unwrap();
        let base = Settings { width: 256, height: 256, ..Settings::default() };
        let reference = oit_cpu::CpuBackend::default().render(&scene, &camera, &base).unwrap();
        let layers = reference.layers.as_ref().expect("the reference counts layers per pixel");
        let deepest = layers.iter().copied().max().unwrap();
        assert!(deepest >= 4, "spheres:3 overlap: {deepest}");
        for backend in crate::available_backends() {
            let techniques = [
                Technique::Reference,
                Technique::Dp,
                Technique::WeightedAverage,
                Technique::Fabs { k: None },
            ];
            for technique in techniques {
                for effect in [Effect::Transparency, Effect::Complexity] {
                    let settings = Settings { technique, effect, ..base.clone() };
                    let frame = backend.render(&scene, &camera, &settings).unwrap();
                    let what = format!("{technique} {effect:?} on {}", backend.name());
                    assert_eq!(frame.stats.max_layers, deepest, "{what}");
                    let mut image = frame.image.clone();
                    annotate_frame(&mut image, effect, &frame.stats);
                    let diff = changed(&frame.image, &image);
                    if effect == Effect::Complexity {
                        let rect = heat_legend_rect(256, 256, deepest).unwrap();
                        assert!(diff.len() > 1000, "{what}: no legend");
                        assert!(diff.iter().all(|&(x, y)| rect.contains(x, y)), "{what}: outside {rect:?}");
                    } else {
                        assert!(diff.is_empty(), "{what}: a transparency frame has no legend");
                    }
                }
            }
        }
    }

    fn entry(label: &str, caption: &str, fill: [u8; 4], error: bool) -> SheetEntry {
        SheetEntry {
            label: label.into(),
            image: Image::new(64, 48, fill),
            error: error.then(|| Image::new(64, 48, [255, 0, 0, 255])),
            caption: caption.into(),
        }
    }

    #[test]
    fn sheet_grid_follows_its_formula() {
        assert_eq!(contact_sheet(&[]), Image::new(1, 1, SHEET_BACKGROUND));
        let gap = SHEET_GAP;
        // Cells of 64 + gap + 64 by header + 48; captions short enough not to widen them.
        let (cw, ch) = (64 + gap + 64, SHEET_HEADER_HEIGHT + 48);
        let expected_columns =
            [(1, 1), (2, 2), (3, 2), (4, 2), (5, 3), (6, 3), (7, 3), (12, 3), (13, 4), (20, 4)];
        for (n, columns) in expected_columns {
            let entries: Vec<SheetEntry> =
                (0..n).map(|i| entry(&format!("t{i}"), "EPR 1%", GREY, true)).collect();
            let layout = sheet_layout(&entries);
            let rows = (n as u32).div_ceil(columns);
            assert_eq!((layout.columns, layout.rows), (columns, rows), "{n} entries");
            assert_eq!((layout.cell_width, layout.cell_height), (cw, ch));
            assert_eq!(layout.width, gap + columns * (cw + gap), "{n} entries");
            assert_eq!(layout.height, gap + rows * (ch + gap), "{n} entries");
            // Fewest columns with the sheet at least as wide as tall.
            assert!(layout.width >= layout.height || columns == n as u32);
            if columns > 1 {
                let fewer = columns - 1;
                assert!(gap + fewer * (cw + gap) < gap + (n as u32).div_ceil(fewer) * (ch + gap));
            }
            let sheet = contact_sheet(&entries);
            assert_eq!((sheet.width, sheet.height), (layout.width, layout.height));
            assert_eq!(sheet.pixels.len(), (sheet.width * sheet.height) as usize);
        }
    }

    #[test]
    fn sheet_puts_captions_above_images_in_grid_order() {
        let caption = "EPR 0.12%  PSNR 41.3 dB";
        let entries = [
            entry("reference", "", [0, 200, 0, 255], false),
            entry("wavg", caption, [0, 0, 200, 255], true),
            entry("bdp", caption, [200, 200, 0, 255], true),
        ];
        let sheet = contact_sheet(&entries);
        let layout = sheet_layout(&entries);
        assert_eq!(layout.columns, 2);
        let gap = u64::from(SHEET_GAP);
        for (i, e) in entries.iter().enumerate() {
            let (x, y) = layout.cell(i);
            let (col, row) = (i as u64 % 2, i as u64 / 2);
            assert_eq!(x, gap + col * u64::from(layout.cell_width + SHEET_GAP));
            assert_eq!(y, gap + row * u64::from(layout.cell_height + SHEET_GAP));
            let (x, y) = (x as u32, y as u32);
            let iy = y + SHEET_HEADER_HEIGHT;
            // The image and its error image land where the layout says.
            let fill = e.image.pixels[0];
            assert_eq!(sheet.get(x, iy), fill);
            assert_eq!(sheet.get(x + 63, iy + 47), fill);
            assert_eq!(sheet.get(x + 64, iy), SHEET_BACKGROUND);
            let error_at = sheet.get(x + 64 + SHEET_GAP, iy + 47);
            assert_eq!(error_at, if e.error.is_some() { [255, 0, 0, 255] } else { SHEET_BACKGROUND });
            // Above the image, the label's line and the caption's line hold text.
            let ink = |y0: u32, y1: u32, w: u32| {
                (y0..y1).any(|y| (x..x + w).any(|x| sheet.get(x, y) != SHEET_BACKGROUND))
            };
            let label_line = y + SHEET_LABEL_PX;
            assert!(ink(y, label_line, text_width(&e.label, SHEET_LABEL_PX as f32)), "no label {i}");
            let caption_drawn = ink(label_line + 2, label_line + 2 + SHEET_CAPTION_PX, layout.cell_width);
            assert_eq!(caption_drawn, !e.caption.is_empty(), "caption of {i}");
            // Nothing between the header and the image.
            assert!(!ink(iy - 3, iy, layout.cell_width), "ink under the header of {i}");
        }
    }

    #[test]
    fn sheet_text_grows_with_tall_images() {
        let small = sheet_layout(&[entry("dp", "EPR 1%", GREY, true)]);
        assert_eq!((small.label_px, small.caption_px), (SHEET_LABEL_PX, SHEET_CAPTION_PX));
        assert_eq!(small.header_height, SHEET_HEADER_HEIGHT);
        let mut tall = entry("dp", "EPR 1%", GREY, true);
        tall.image = Image::new(2 * SHEET_TEXT_BASE_HEIGHT, 2 * SHEET_TEXT_BASE_HEIGHT, GREY);
        let layout = sheet_layout(&[tall.clone()]);
        assert_eq!((layout.label_px, layout.caption_px), (2 * SHEET_LABEL_PX, 2 * SHEET_CAPTION_PX));
        assert_eq!(layout.header_height, 2 * SHEET_LABEL_PX + 2 + 2 * SHEET_CAPTION_PX + 6);
        assert_eq!(layout.cell_height, layout.header_height + 2 * SHEET_TEXT_BASE_HEIGHT);
        // The label's ink is about twice as tall as at the base size.
        let sheet = contact_sheet(&[tall]);
        let gap = SHEET_GAP;
        let inked = (gap..gap + layout.label_px)
            .filter(|&y| (gap..gap + 100).any(|x| sheet.get(x, y) != SHEET_BACKGROUND))
            .count() as u32;
        assert!(inked > SHEET_LABEL_PX, "label only {inked} rows high");
        // Huge images cap the scale.
        let mut huge = entry("dp", "", GREY, false);
        huge.image = Image::new(4, 5000, GREY);
        assert_eq!(sheet_layout(&[huge]).label_px, (SHEET_TEXT_MAX_SCALE * SHEET_LABEL_PX as f32) as u32);
        // 512-pixel renders, as `oit compare --sheet` makes by default: captions are at least a
        // thirteenth of the image's height, so a 3-column sheet shown 1000 pixels wide keeps
        // them over 12 pixels high
        let mut frame = entry("dp", "EPR 0.000%  PSNR 102.53 dB  lost 0  tied 0", GREY, true);
        frame.image = Image::new(512, 512, GREY);
        frame.error = Some(Image::new(512, 512, GREY));
        let layout = sheet_layout(&vec![frame.clone(); 13]);
        assert!(layout.caption_px * 13 >= 512, "{layout:?}");
        assert_eq!(layout.columns, 3, "{layout:?}");
        assert!(layout.caption_px as f32 * 1000.0 / layout.width as f32 > 12.0, "{layout:?}");
        // and the caption fits its cell uncut
        assert!(text_width(&frame.caption, layout.caption_px as f32) <= layout.cell_width);
    }

    #[test]
    fn sheet_cuts_long_captions_and_takes_mixed_sizes() {
        let mut entries = vec![entry("a", "b", WHITE, true), entry("c", "d", WHITE, false)];
        entries[1].image = Image::new(300, 10, WHITE);
        entries[0].error = Some(Image::new(5, 90, WHITE));
        let layout = sheet_layout(&entries);
        assert_eq!((layout.cell_width, layout.cell_height), (300, SHEET_HEADER_HEIGHT + 90));

        let long = "failed: ".to_string() + &"the device ran out of memory; ".repeat(20);
        entries[1].caption = long.clone();
        let layout = sheet_layout(&entries);
        assert_eq!(layout.cell_width, SHEET_HEADER_MAX_WIDTH, "a long caption widens the cell only so far");
        let sheet = contact_sheet(&entries);
        assert_eq!((sheet.width, sheet.height), (layout.width, layout.height));
        // The cut caption stays inside its cell: the column to the right of it is untouched.
        let (x, y) = layout.cell(1);
        let right = (x + u64::from(layout.cell_width)) as u32;
        let caption_top = y as u32 + SHEET_LABEL_PX + 2;
        for yy in caption_top..caption_top + SHEET_CAPTION_PX {
            for xx in right..(right + SHEET_GAP).min(sheet.width) {
                assert_eq!(sheet.get(xx, yy), SHEET_BACKGROUND, "({xx}, {yy})");
            }
        }
    }
}
