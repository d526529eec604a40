//! Labels drawn straight into an [`Image`], with no font file and no system library.
//!
//! Contract: every function here clips at the image's edges and never panics, whatever the
//! coordinates, the scale or the image's size (an empty image, or one whose `pixels` is shorter
//! than `width × height`, draws what fits and nothing else). Scale 0 draws nothing.
//!
//! - [`draw_text`] and [`text_width`]: one line of text in an embedded 5×7 bitmap font, set in a
//!   [`CHAR_WIDTH`] × [`LINE_HEIGHT`] cell (the eighth row holds the descenders of `g j p q y , ;
//!   _`). It covers ASCII digits, both cases of letters, space and `.,:;-+_=%()[]/<>#*'"!?|`;
//!   any other character, a newline included, draws a box.
//! - [`fill_rect`]: a rectangle, blended by the colour's alpha.
//! - [`draw_heat_legend`]: the key to a [`heat`] map.
//! - [`contact_sheet`]: techniques side by side, each with its error image and numbers.
//!
//! The font is a table of row strings turned into bit masks at compile time, so a malformed glyph
//! fails the build rather than a run.

use crate::Image;
use crate::composite::{heat, linear_to_srgb8};

/// Horizontal advance of one character at scale 1: a 5-pixel glyph and one column of spacing.
pub const CHAR_WIDTH: u32 = 6;

/// Height of one line of text at scale 1: 7 rows of glyph and one row for descenders.
pub const LINE_HEIGHT: u32 = 8;

/// Width of a glyph's drawn area; the rest of [`CHAR_WIDTH`] is spacing.
const GLYPH_COLUMNS: usize = 5;

/// Rows of a glyph: [`LINE_HEIGHT`].
const GLYPH_ROWS: usize = LINE_HEIGHT as usize;

/// One glyph: a bit mask per row, top row first; bit 4 is the leftmost column.
type Glyph = [u8; GLYPH_ROWS];

/// Turns rows of `.` and `#` into a [`Glyph`]; rows left out below are blank. Runs at compile
/// time, so a row of the wrong width or an unknown character stops the build.
const fn glyph(rows: &[&str]) -> Glyph {
    assert!(rows.len() <= GLYPH_ROWS, "a glyph has at most 8 rows");
    let mut out = [0u8; GLYPH_ROWS];
    let mut r = 0;
    while r < rows.len() {
        let bytes = rows[r].as_bytes();
        assert!(bytes.len() == GLYPH_COLUMNS, "a glyph row is 5 characters wide");
        let mut c = 0;
        while c < GLYPH_COLUMNS {
            match bytes[c] {
                b'#' => out[r] |= 1 << (GLYPH_COLUMNS - 1 - c),
                b'.' => {}
                _ => panic!("glyph rows hold only '.' and '#'"),
            }
            c += 1;
        }
        r += 1;
    }
    out
}

/// What a character outside the font draws.
const BOX: Glyph = glyph(&["#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"]);

/// The font. Capitals and digits fill rows 0–6; lower case has its x-height in rows 2–6,
/// ascenders from row 0 and descenders in row 7.
#[rustfmt::skip]
const FONT: &[(char, Glyph)] = &[
    (' ', glyph(&[])),
    ('0', glyph(&[".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."])),
    ('1', glyph(&["..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."])),
    ('2', glyph(&[".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"])),
    ('3', glyph(&["#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."])),
    ('4', glyph(&["...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."])),
    ('5', glyph(&["#####", "#....", "####.", "....#", "....#", "#...#", ".###."])),
    ('6', glyph(&["..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."])),
    ('7', glyph(&["#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."])),
    ('8', glyph(&[".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."])),
    ('9', glyph(&[".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."])),
    ('A', glyph(&[".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"])),
    ('B', glyph(&["####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."])),
    ('C', glyph(&[".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."])),
    ('D', glyph(&["###..", "#..#.", "#...#", "#...#", "#...#", "#..#.", "###.."])),
    ('E', glyph(&["#####", "#....", "#....", "####.", "#....", "#....", "#####"])),
    ('F', glyph(&["#####", "#....", "#....", "####.", "#....", "#....", "#...."])),
    ('G', glyph(&[".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"])),
    ('H', glyph(&["#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"])),
    ('I', glyph(&[".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."])),
    ('J', glyph(&["..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."])),
    ('K', glyph(&["#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"])),
    ('L', glyph(&["#....", "#....", "#....", "#....", "#....", "#....", "#####"])),
    ('M', glyph(&["#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"])),
    ('N', glyph(&["#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#"])),
    ('O', glyph(&[".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."])),
    ('P', glyph(&["####.", "#...#", "#...#", "####.", "#....", "#....", "#...."])),
    ('Q', glyph(&[".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"])),
    ('R', glyph(&["####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"])),
    ('S', glyph(&[".####", "#....", "#....", ".###.", "....#", "....#", "####."])),
    ('T', glyph(&["#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."])),
    ('U', glyph(&["#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."])),
    ('V', glyph(&["#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."])),
    ('W', glyph(&["#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#."])),
    ('X', glyph(&["#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"])),
    ('Y', glyph(&["#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."])),
    ('Z', glyph(&["#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"])),
    ('a', glyph(&[".....", ".....", ".###.", "....#", ".####", "#...#", ".####"])),
    ('b', glyph(&["#....", "#....", "####.", "#...#", "#...#", "#...#", "####."])),
    ('c', glyph(&[".....", ".....", ".###.", "#....", "#....", "#...#", ".###."])),
    ('d', glyph(&["....#", "....#", ".####", "#...#", "#...#", "#...#", ".####"])),
    ('e', glyph(&[".....", ".....", ".###.", "#...#", "#####", "#....", ".###."])),
    ('f', glyph(&["..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#..."])),
    ('g', glyph(&[".....", ".....", ".####", "#...#", "#...#", ".####", "....#", ".###."])),
    ('h', glyph(&["#....", "#....", "#.##.", "##..#", "#...#", "#...#", "#...#"])),
    ('i', glyph(&["..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###."])),
    ('j', glyph(&["...#.", ".....", "..##.", "...#.", "...#.", "...#.", "#..#.", ".##.."])),
    ('k', glyph(&["#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#."])),
    ('l', glyph(&[".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."])),
    ('m', glyph(&[".....", ".....", "##.#.", "#.#.#", "#.#.#", "#...#", "#...#"])),
    ('n', glyph(&[".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#"])),
    ('o', glyph(&[".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###."])),
    ('p', glyph(&[".....", ".....", "####.", "#...#", "#...#", "####.", "#....", "#...."])),
    ('q', glyph(&[".....", ".....", ".####", "#...#", "#...#", ".####", "....#", "....#"])),
    ('r', glyph(&[".....", ".....", "#.##.", "##..#", "#....", "#....", "#...."])),
    ('s', glyph(&[".....", ".....", ".####", "#....", ".###.", "....#", "####."])),
    ('t', glyph(&[".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##."])),
    ('u', glyph(&[".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#"])),
    ('v', glyph(&[".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#.."])),
    ('w', glyph(&[".....", ".....", "#...#", "#...#", "#.#.#", "#.#.#", ".#.#."])),
    ('x', glyph(&[".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"])),
    ('y', glyph(&[".....", ".....", "#...#", "#...#", "#...#", ".####", "....#", ".###."])),
    ('z', glyph(&[".....", ".....", "#####", "...#.", "..#..", ".#...", "#####"])),
    ('.', glyph(&[".....", ".....", ".....", ".....", ".....", ".##..", ".##.."])),
    (',', glyph(&[".....", ".....", ".....", ".....", ".....", ".##..", ".##..", ".#..."])),
    (':', glyph(&[".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."])),
    (';', glyph(&[".....", ".##..", ".##..", ".....", ".##..", ".##..", ".#..."])),
    ('-', glyph(&[".....", ".....", ".....", "#####", ".....", ".....", "....."])),
    ('+', glyph(&[".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."])),
    ('_', glyph(&[".....", ".....", ".....", ".....", ".....", ".....", ".....", "#####"])),
    ('=', glyph(&[".....", ".....", "#####", ".....", "#####", ".....", "....."])),
    ('%', glyph(&["##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"])),
    ('(', glyph(&["...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."])),
    (')', glyph(&[".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."])),
    ('[', glyph(&[".###.", ".#...", ".#...", ".#...", ".#...", ".#...", ".###."])),
    (']', glyph(&[".###.", "...#.", "...#.", "...#.", "...#.", "...#.", ".###."])),
    ('/', glyph(&[".....", "....#", "...#.", "..#..", ".#...", "#....", "....."])),
    ('<', glyph(&["...#.", "..#..", ".#...", "#....", ".#...", "..#..", "...#."])),
    ('>', glyph(&[".#...", "..#..", "...#.", "....#", "...#.", "..#..", ".#..."])),
    ('#', glyph(&[".#.#.", ".#.#.", "#####", ".#.#.", "#####", ".#.#.", ".#.#."])),
    ('*', glyph(&[".....", "..#..", "#.#.#", ".###.", "#.#.#", "..#..", "....."])),
    ('\'', glyph(&["..#..", "..#..", ".#...", ".....", ".....", ".....", "....."])),
    ('"', glyph(&[".#.#.", ".#.#.", ".#.#.", ".....", ".....", ".....", "....."])),
    ('!', glyph(&["..#..", "..#..", "..#..", "..#..", "..#..", ".....", "..#.."])),
    ('?', glyph(&[".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."])),
    ('|', glyph(&["..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."])),
];

/// The glyph of `c`, or [`BOX`] when the font lacks it.
fn glyph_of(c: char) -> &'static Glyph {
    FONT.iter().find(|(k, _)| *k == c).map_or(&BOX, |(_, g)| g)
}

/// Width in pixels of `text` drawn at `scale`: [`CHAR_WIDTH`] × `scale` per character (the last
/// one's spacing column included), saturating at `u32::MAX`. Its height is [`LINE_HEIGHT`] ×
/// `scale`.
pub fn text_width(text: &str, scale: u32) -> u32 {
    let w = text.chars().count() as u64 * u64::from(CHAR_WIDTH) * u64::from(scale);
    u32::try_from(w).unwrap_or(u32::MAX)
}

/// Blends `color` over one pixel by the colour's alpha (255 replaces it); the pixel's own alpha
/// is kept. Nothing happens outside the image.
fn blend_pixel(image: &mut Image, x: i64, y: i64, color: [u8; 4]) {
    if x < 0 || y < 0 || x >= i64::from(image.width) || y >= i64::from(image.height) {
        return;
    }
    let index = y as u64 * u64::from(image.width) + x as u64;
    let Some(px) = usize::try_from(index).ok().and_then(|i| image.pixels.get_mut(i)) else {
        return;
    };
    let a = u32::from(color[3]);
    for (p, &c) in px[..3].iter_mut().zip(&color[..3]) {
        *p = ((u32::from(c) * a + u32::from(*p) * (255 - a) + 127) / 255) as u8;
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
            blend_pixel(image, px, py, color);
        }
    }
}

/// Draws one line of `text` with its top-left corner at (`x`, `y`), each font pixel a `scale` ×
/// `scale` square of `color` (blended by its alpha). Touches only the box [`text_width`] ×
/// ([`LINE_HEIGHT`] × `scale`) from (`x`, `y`), clipped to the image; scale 0 draws nothing.
pub fn draw_text(image: &mut Image, x: i32, y: i32, text: &str, scale: u32, color: [u8; 4]) {
    draw_text_at(image, x.into(), y.into(), text, scale, color);
}

/// [`draw_text`] at 64-bit coordinates, so that callers laying out need not narrow theirs.
fn draw_text_at(image: &mut Image, x: i64, y: i64, text: &str, scale: u32, color: [u8; 4]) {
    if scale == 0 || image.width == 0 || image.height == 0 {
        return;
    }
    let s = i64::from(scale);
    let (w, h) = (i64::from(image.width), i64::from(image.height));
    if y >= h || y + GLYPH_ROWS as i64 * s <= 0 {
        return;
    }
    let advance = i64::from(CHAR_WIDTH) * s;
    for (i, c) in text.chars().enumerate() {
        let cx = x + i as i64 * advance;
        if cx >= w {
            break;
        }
        if cx + advance <= 0 {
            continue;
        }
        for (row, bits) in glyph_of(c).iter().enumerate() {
            for col in 0..GLYPH_COLUMNS {
                if bits & (1 << (GLYPH_COLUMNS - 1 - col)) != 0 {
                    let px = cx + col as i64 * s;
                    let py = y + row as i64 * s;
                    fill_rect(image, px, py, scale.into(), scale.into(), color);
                }
            }
        }
    }
}

/// Caption of the heat legend.
const LEGEND_CAPTION: &str = "fragments / pixel";

/// Draws the key to a heat map of fragments per pixel in the bottom-right corner of `image`: a
/// dark translucent box holding the caption "fragments / pixel", a bar of
/// [`heat`]`(t)` for `t` from 0 at the left to 1 at the right, and tick
/// labels "1" under its left end and `max` under its right end.
///
/// The text is drawn at scale 1 up to 1023 pixels on the short side, 2 from 1024 and so on; the
/// bar is a quarter of the image's width, no narrower than its labels and no wider than 128
/// pixels × scale. An image too small to hold the legend and its margin is left unchanged.
pub fn draw_heat_legend(image: &mut Image, max: u32) {
    let scale = (image.width.min(image.height) / 512).max(1);
    let s = u64::from(scale);
    let pad = 4 * s;
    let margin = 8 * s;
    let max_label = max.to_string();
    let line = u64::from(LINE_HEIGHT) * s;
    let gap = 2 * s;
    let tick = 2 * s;
    let needed = u64::from(text_width(LEGEND_CAPTION, scale)).max(
        u64::from(text_width("1", scale))
            + u64::from(CHAR_WIDTH) * s
            + u64::from(text_width(&max_label, scale)),
    );
    let bar_w = (u64::from(image.width) / 4).clamp(needed, needed.max(128 * s));
    let bar_h = line;
    let box_w = pad + bar_w + pad;
    let box_h = pad + line + gap + bar_h + tick + gap / 2 + line + pad;
    if box_w + 2 * margin > u64::from(image.width) || box_h + 2 * margin > u64::from(image.height) {
        return;
    }
    let left = (u64::from(image.width) - margin - box_w) as i64;
    let top = (u64::from(image.height) - margin - box_h) as i64;
    fill_rect(image, left, top, box_w, box_h, [0, 0, 0, 176]);

    let text = [225, 225, 225, 255];
    let x = left + pad as i64;
    let mut y = top + pad as i64;
    draw_text_at(image, x, y, LEGEND_CAPTION, scale, text);
    y += (line + gap) as i64;
    for i in 0..bar_w {
        let t = if bar_w > 1 { i as f32 / (bar_w - 1) as f32 } else { 0.0 };
        let c = heat(t);
        let color = [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255];
        fill_rect(image, x + i as i64, y, 1, bar_h, color);
    }
    y += bar_h as i64;
    let right = x + bar_w as i64;
    fill_rect(image, x, y, s, tick, text);
    fill_rect(image, right - s as i64, y, s, tick, text);
    y += (tick + gap / 2) as i64;
    draw_text_at(image, x, y, "1", scale, text);
    let label_x = right - i64::from(text_width(&max_label, scale)) + s as i64; // drop the spacing column
    draw_text_at(image, label_x, y, &max_label, scale, text);
}

/// One technique's row of a [`contact_sheet`].
#[derive(Clone, Debug, PartialEq)]
pub struct SheetRow {
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
pub const SHEET_GAP: u32 = 8;

/// Height of a row's header strip on a [`contact_sheet`]: label, caption and the space under them.
pub const SHEET_HEADER_HEIGHT: u32 = 2 * LINE_HEIGHT + 2 + 4;

/// Background of a [`contact_sheet`].
const SHEET_BACKGROUND: [u8; 4] = [40, 40, 40, 255];

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
            blend_pixel(dst, dx, dy, [p[0], p[1], p[2], 255]);
        }
    }
}

/// Lays techniques out one above the other on a dark grey sheet: for each row a header strip with
/// its label and, under it, its caption in light text, then its image with its error image (if
/// any) to the right. [`SHEET_GAP`] pixels surround and separate everything; images may differ
/// in size. The sheet is as wide as the widest row (image, gap, error image) or header text,
/// plus a gap on each side; each row is [`SHEET_HEADER_HEIGHT`] plus its taller image high, and
/// rows are separated and surrounded by a gap. No rows give a 1 × 1 sheet.
pub fn contact_sheet(rows: &[SheetRow]) -> Image {
    if rows.is_empty() {
        return Image::new(1, 1, SHEET_BACKGROUND);
    }
    let gap = u64::from(SHEET_GAP);
    let content = |r: &SheetRow| {
        let (ew, eh) = r.error.as_ref().map_or((0, 0), |e| (gap + u64::from(e.width), u64::from(e.height)));
        (u64::from(r.image.width) + ew, u64::from(r.image.height).max(eh))
    };
    let inner_w = rows
        .iter()
        .map(|r| {
            let header = text_width(&r.label, 1).max(text_width(&r.caption, 1));
            content(r).0.max(u64::from(header))
        })
        .max()
        .unwrap_or(0);
    let inner_h: u64 = rows.iter().map(|r| u64::from(SHEET_HEADER_HEIGHT) + content(r).1 + gap).sum();
    let width = u32::try_from(gap + inner_w + gap).unwrap_or(u32::MAX);
    let height = u32::try_from(gap + inner_h).unwrap_or(u32::MAX);
    let mut sheet = Image::new(width, height, SHEET_BACKGROUND);

    let (label_color, caption_color) = ([235, 235, 235, 255], [190, 190, 190, 255]);
    let mut y = gap;
    for row in rows {
        let (tx, ty) = (gap as i64, y as i64);
        draw_text_at(&mut sheet, tx, ty, &row.label, 1, label_color);
        draw_text_at(&mut sheet, tx, ty + i64::from(LINE_HEIGHT) + 2, &row.caption, 1, caption_color);
        let iy = y + u64::from(SHEET_HEADER_HEIGHT);
        blit(&mut sheet, &row.image, gap, iy);
        if let Some(error) = &row.error {
            blit(&mut sheet, error, gap + u64::from(row.image.width) + gap, iy);
        }
        y = iy + content(row).1 + gap;
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    const BLACK: [u8; 4] = [0, 0, 0, 255];
    const WHITE: [u8; 4] = [255, 255, 255, 255];

    /// Every character the font promises.
    const COVERED: &str =
        "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ .,:;-+_=%()[]/<>#*'\"!?|";

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
    fn text_width_of_known_strings() {
        assert_eq!(text_width("", 1), 0);
        assert_eq!(text_width("", 3), 0);
        assert_eq!(text_width("a", 1), 6);
        assert_eq!(text_width("abc", 1), 18);
        assert_eq!(text_width("PSNR 41.3 dB", 2), 144);
        assert_eq!(text_width(LEGEND_CAPTION, 1), 102);
        assert_eq!(text_width("x", 0), 0);
        // Counts characters, not bytes: the box of an unknown one is one cell wide.
        assert_eq!(text_width("é", 1), 6);
        assert_eq!(text_width("abc", u32::MAX), u32::MAX);
    }

    #[test]
    fn font_covers_its_characters_with_distinct_glyphs() {
        let glyphs: Vec<(char, &Glyph)> = COVERED.chars().map(|c| (c, glyph_of(c))).collect();
        for (i, (a, ga)) in glyphs.iter().enumerate() {
            assert!(FONT.iter().any(|(k, _)| k == a), "{a:?} is not in the font");
            assert!(*ga != &BOX, "{a:?} looks like the unknown box");
            assert_eq!(**ga == [0; GLYPH_ROWS], *a == ' ', "only space is blank, not {a:?}");
            for (b, gb) in &glyphs[i + 1..] {
                assert!(ga != gb, "{a:?} and {b:?} share a glyph");
            }
        }
        assert_eq!(glyph_of('\u{1F600}'), &BOX);
        assert_eq!(glyph_of('\n'), &BOX);
    }

    #[test]
    fn draw_text_changes_pixels_only_inside_its_box() {
        for scale in [1, 2, 3] {
            let before = Image::new(200, 60, BLACK);
            let mut after = before.clone();
            let (x, y, text) = (7, 5, "Hello 42% [ok]?");
            draw_text(&mut after, x, y, text, scale, WHITE);
            let diff = changed(&before, &after);
            assert!(!diff.is_empty(), "scale {scale} drew nothing");
            let (x1, y1) = (x as u32 + text_width(text, scale), y as u32 + LINE_HEIGHT * scale);
            for (px, py) in diff {
                assert!(
                    (x as u32..x1).contains(&px) && (y as u32..y1).contains(&py),
                    "scale {scale}: ({px}, {py}) is outside the text's box"
                );
            }
        }
    }

    #[test]
    fn draw_text_blends_by_alpha() {
        let mut image = Image::new(8, 8, BLACK);
        draw_text(&mut image, 0, 0, "|", 1, [255, 255, 255, 0]);
        assert_eq!(image, Image::new(8, 8, BLACK));
        draw_text(&mut image, 0, 0, "|", 1, [200, 100, 50, 128]);
        assert_eq!(image.get(2, 0), [100, 50, 25, 255]);
    }

    #[test]
    fn draw_text_clips_and_never_panics() {
        let text = "Clip me: 0123456789 |#%";
        for scale in [0, 1, 2, 7, 1000, u32::MAX] {
            for &(x, y) in &[
                (-3, 2),
                (2, -3),
                (-1000, -1000),
                (30, 2),
                (2, 14),
                (39, 19),
                (i32::MIN, i32::MIN),
                (i32::MAX, i32::MAX),
                (i32::MIN, 0),
                (0, i32::MAX),
            ] {
                let mut image = Image::new(40, 20, BLACK);
                draw_text(&mut image, x, y, text, scale, WHITE);
                assert_eq!(image.pixels.len(), 40 * 20);
            }
        }
        // A glyph straddling the left and top edges still draws its visible part.
        let mut image = Image::new(10, 10, BLACK);
        draw_text(&mut image, -2, -2, "#", 1, WHITE);
        assert_ne!(image, Image::new(10, 10, BLACK));
        // Empty images, and one whose pixels are fewer than its size claims.
        for mut image in [Image::new(0, 0, BLACK), Image::new(0, 5, BLACK), Image::new(5, 0, BLACK)] {
            draw_text(&mut image, 0, 0, text, 1, WHITE);
            draw_heat_legend(&mut image, 9);
        }
        let mut short = Image { width: 300, height: 300, pixels: vec![BLACK; 10] };
        draw_text(&mut short, 0, 0, text, 1, WHITE);
        draw_heat_legend(&mut short, 9);
        assert_eq!(short.pixels.len(), 10);
        // Scale 0 draws nothing.
        let mut image = Image::new(40, 20, BLACK);
        draw_text(&mut image, 0, 0, text, 0, WHITE);
        assert_eq!(image, Image::new(40, 20, BLACK));
    }

    #[test]
    fn legend_skips_tiny_images() {
        let before = Image::new(4, 4, BLACK);
        let mut after = before.clone();
        draw_heat_legend(&mut after, 12);
        assert_eq!(before, after);
    }

    #[test]
    fn legend_stays_in_the_bottom_right() {
        for (size, max) in [(256, 7), (256, u32::MAX), (1024, 31)] {
            // Mid grey, so that the dark box, the ramp and the text all show as changes.
            let before = Image::new(size, size, [128, 128, 128, 255]);
            let mut after = before.clone();
            draw_heat_legend(&mut after, max);
            let diff = changed(&before, &after);
            assert!(diff.len() > 1000, "{size}: only {} pixels changed", diff.len());
            for (x, y) in diff {
                assert!(x >= size / 2 && y >= size * 3 / 4, "{size}: ({x}, {y}) is outside the corner");
                assert!(x < size - 4 && y < size - 4, "{size}: ({x}, {y}) is in the margin");
            }
            // The ramp's two ends are there: black at the left and white at the right.
            // The bar's middle row: margin 8, box 37 high, bar 14 to 22 from the box's top; × scale.
            let s = (size / 512).max(1);
            let bar_row: Vec<[u8; 4]> = (0..size).map(|x| after.get(x, size - 27 * s)).collect();
            assert!(bar_row.contains(&[0, 0, 0, 255]));
            assert!(bar_row.contains(&[255, 255, 255, 255]));
        }
    }

    fn row(label: &str, caption: &str, fill: [u8; 4], error: bool) -> SheetRow {
        SheetRow {
            label: label.into(),
            image: Image::new(64, 48, fill),
            error: error.then(|| Image::new(64, 48, [255, 0, 0, 255])),
            caption: caption.into(),
        }
    }

    #[test]
    fn contact_sheet_size_follows_the_layout() {
        assert_eq!(contact_sheet(&[]), Image::new(1, 1, SHEET_BACKGROUND));

        let caption = "EPR 0.12%  PSNR 41.3 dB";
        let rows =
            [row("reference", "", [0, 200, 0, 255], false), row("wboit", caption, [0, 0, 200, 255], true)];
        let sheet = contact_sheet(&rows);
        let gap = SHEET_GAP;
        // Widest of: image + gap + error image (136), and the caption's text (138).
        let inner = (64 + gap + 64).max(text_width(caption, 1));
        assert_eq!(sheet.width, gap + inner + gap);
        assert_eq!(sheet.height, gap + 2 * (SHEET_HEADER_HEIGHT + 48 + gap));

        // Images land where the layout says.
        let y0 = gap + SHEET_HEADER_HEIGHT;
        assert_eq!(sheet.get(gap, y0), [0, 200, 0, 255]);
        assert_eq!(sheet.get(gap + 63, y0 + 47), [0, 200, 0, 255]);
        assert_eq!(sheet.get(gap + 64, y0), SHEET_BACKGROUND);
        let y1 = y0 + 48 + gap + SHEET_HEADER_HEIGHT;
        assert_eq!(sheet.get(gap, y1), [0, 0, 200, 255]);
        assert_eq!(sheet.get(gap + 64 + gap, y1 + 47), [255, 0, 0, 255]);
        assert_eq!(sheet.get(gap + 64 + gap - 1, y1), SHEET_BACKGROUND);
        // The header strip holds text.
        let header = (gap..gap + text_width("wboit", 1))
            .any(|x| sheet.get(x, y1 - SHEET_HEADER_HEIGHT + 3) != SHEET_BACKGROUND);
        assert!(header, "no label drawn");
    }

    #[test]
    fn contact_sheet_takes_mixed_sizes() {
        let mut rows = vec![row("a", "b", WHITE, true), row("c", "d", WHITE, false)];
        rows[1].image = Image::new(300, 10, WHITE);
        rows[0].error = Some(Image::new(5, 90, WHITE));
        let sheet = contact_sheet(&rows);
        let gap = SHEET_GAP;
        assert_eq!(sheet.width, gap + 300 + gap);
        assert_eq!(sheet.height, gap + (SHEET_HEADER_HEIGHT + 90 + gap) + (SHEET_HEADER_HEIGHT + 10 + gap));
        assert_eq!(sheet.pixels.len(), (sheet.width * sheet.height) as usize);
    }
}
