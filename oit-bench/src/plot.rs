//! One chart description, drawn twice, the legend in a column right of the plot area (never over
//! the data): as SVG with plotters (text by the SVG viewer, no fonts needed) and as PNG with
//! plotters' bitmap backend for lines and points and [`crate::present::draw_text`] (the embedded
//! font) for every label, since plotters' bitmap text would need system font libraries; labels
//! are placed through the chart's own coordinate mapping.

use std::path::Path;

use oit_core::{Image, OitError};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::present::{draw_text, fill_rect, fit_text, line_height, text_width};

/// A set of points drawn in one colour.
#[derive(Clone, Debug)]
pub struct Series {
    /// Its name in the legend.
    pub name: String,
    /// The points, in data coordinates.
    pub points: Vec<(f64, f64)>,
    /// A label beside each point (empty: none).
    pub labels: Vec<String>,
    /// Join the points with a line.
    pub line: bool,
    /// Mark each point.
    pub markers: bool,
    /// Colour; `None` picks from plotters' palette by index.
    pub color: Option<(u8, u8, u8)>,
}

/// A chart: axes (each linear or log), series, title.
#[derive(Clone, Debug)]
pub struct Chart {
    /// Title.
    pub title: String,
    /// x axis description.
    pub x_desc: String,
    /// y axis description.
    pub y_desc: String,
    /// Log x axis.
    pub x_log: bool,
    /// Log y axis.
    pub y_log: bool,
    /// The series, drawn in order.
    pub series: Vec<Series>,
}

const WIDTH: u32 = 1200;
const HEIGHT: u32 = 720;
/// Room on the right of the SVG and the PNG for the legend, outside the plot area, so that it
/// never covers the data.
const LEGEND_WIDTH: u32 = 230;
/// Top of the legend's first row.
const LEGEND_TOP: i32 = 60;
/// Text sizes of the PNG (line heights in pixels): title, axis descriptions, tick labels, legend
/// entries, labels beside points.
const TITLE_PX: f32 = 24.0;
const DESC_PX: f32 = 17.0;
const TICK_PX: f32 = 16.0;
const LEGEND_PX: f32 = 16.0;
const POINT_PX: f32 = 13.0;
/// A label to draw once plotters is done with the buffer: x, y, text, size, centred on x.
type Label = (i32, i32, String, f32, bool);

fn write_err(path: &Path) -> impl Fn(&dyn std::fmt::Display) -> OitError + '_ {
    move |e| OitError::Write { path: path.to_path_buf(), message: e.to_string() }
}

/// The largest magnitude an axis reaches: values beyond are drawn at the edge, so that one absurd
/// number cannot stretch an axis over hundreds of decades (which plotters takes forever to draw).
const AXIS_LIMIT: f64 = 1e15;

/// The smallest value a log axis reaches.
const LOG_FLOOR: f64 = 1e-15;

/// Most ticks on one axis.
const MAX_TICKS: usize = 64;

/// `v` within the values an axis can show.
fn clamp_axis(v: f64, log: bool) -> f64 {
    if log { v.clamp(LOG_FLOOR, AXIS_LIMIT) } else { v.clamp(-AXIS_LIMIT, AXIS_LIMIT) }
}

/// The axis range holding `values`: whole decades on a log axis, 5 % padding on a linear one;
/// values are clamped to ±[`AXIS_LIMIT`] (and at least [`LOG_FLOOR`] on a log axis) first.
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)).map(|v| clamp_axis(v, log)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        let (a, b) = (lo.log10().floor(), hi.log10().ceil());
        let b = if b <= a { a + 1.0 } else { b };
        (10f64.powf(a), 10f64.powf(b))
    } else {
        let pad = ((hi - lo) * 0.05).max(hi.abs() * 0.05).max(1e-9);
        (lo - pad, hi + pad)
    }
}

/// Tick values: every decade (and 2, 5 between when there are few) on a log axis, about 6 round
/// numbers on a linear one.
fn ticks((lo, hi): (f64, f64), log: bool) -> Vec<f64> {
    let mut out = Vec::new();
    if log {
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let steps: &[f64] = if b - a <= 3 { &[1.0, 2.0, 5.0] } else { &[1.0] };
        for e in a..=b {
            for m in steps {
                let v = m * 10f64.powi(e);
                if v >= lo * 0.999 && v <= hi * 1.001 && out.len() < MAX_TICKS {
                    out.push(v);
                }
            }
        }
    } else {
        let raw = (hi - lo) / 6.0;
        let mag = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(raw);
        let mut v = (lo / step).ceil() * step;
        while v <= hi + step * 1e-6 && out.len() < MAX_TICKS {
            out.push(v);
            v += step;
        }
    }
    out
}

/// A tick label: plain for 0.01 to 99999, else `1e-3` style.
fn tick_label(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (0.01..100_000.0).contains(&v.abs()) {
        let s = format!("{v:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:e}")
    }
}

impl Series {
    fn rgb(&self, index: usize) -> RGBColor {
        match self.color {
            Some((r, g, b)) => RGBColor(r, g, b),
            None => {
                let c = Palette99::pick(index).to_rgba();
                RGBColor(c.0, c.1, c.2)
            }
        }
    }
}

impl Chart {
    /// The series the legend lists (those with a name), with their index for the palette.
    fn named(&self) -> impl Iterator<Item = (usize, &Series)> {
        self.series.iter().enumerate().filter(|(_, s)| !s.name.is_empty())
    }

    /// The legend's row pitch and text size: [`LEGEND_PX`] text 8 pixels apart, smaller when
    /// that many rows would run past the bottom of the picture.
    fn legend_rows(&self) -> (i32, f32) {
        let rows = self.named().count().max(1) as i32;
        let room = HEIGHT as i32 - LEGEND_TOP - 10;
        let step = (line_height(LEGEND_PX) as i32 + 8).min(room / rows).max(4);
        (step, (step as f32 - 4.0).clamp(3.0, LEGEND_PX))
    }

    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let pts = || self.series.iter().flat_map(|s| s.points.iter().copied());
        (range(pts().map(|p| p.0), self.x_log), range(pts().map(|p| p.1), self.y_log))
    }

    /// The chart with every point inside its axes' ranges (points that are not finite, or not
    /// positive on a log axis, dropped), so that drawing never meets an absurd coordinate.
    fn clamped(&self) -> Chart {
        let ((x0, x1), (y0, y1)) = self.ranges();
        let keep = |v: f64, log: bool| v.is_finite() && (!log || v > 0.0);
        let series = self
            .series
            .iter()
            .map(|s| {
                let (points, labels): (Vec<(f64, f64)>, Vec<String>) = s
                    .points
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| keep(p.0, self.x_log) && keep(p.1, self.y_log))
                    .map(|(k, p)| {
                        ((p.0.clamp(x0, x1), p.1.clamp(y0, y1)), s.labels.get(k).cloned().unwrap_or_default())
                    })
                    .unzip();
                let labels = if s.labels.is_empty() { Vec::new() } else { labels };
                Series { points, labels, ..s.clone() }
            })
            .collect();
        Chart { series, ..self.clone() }
    }

    /// Draws the chart into an SVG file.
    pub fn svg(&self, path: &Path) -> Result<(), OitError> {
        self.clamped().draw_svg(path)
    }

    /// Draws the chart into a PNG file: plotters' bitmap backend draws the grid, lines and
    /// points; [`crate::present`] the text, at pixels from the chart's coordinate mapping.
    pub fn png(&self, path: &Path) -> Result<(), OitError> {
        self.clamped().draw_png(path)
    }

    fn draw_svg(&self, path: &Path) -> Result<(), OitError> {
        let err = write_err(path);
        // drawn into memory and written with one checked write: plotters' file target drops its
        // writer unflushed, so a full disk would pass unnoticed (issue 13.5)
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, (WIDTH, HEIGHT)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| err(&e))?;
            let ((x0, x1), (y0, y1)) = self.ranges();
            // the plot on the left, the legend in its own column on the right: never over the data
            let (area, _) = root.split_horizontally(WIDTH - LEGEND_WIDTH);
            let mut builder = ChartBuilder::on(&area);
            builder
                .caption(&self.title, ("sans-serif", 22))
                .margin(14)
                .x_label_area_size(50)
                .y_label_area_size(90);
            // four axis kinds, one body
            macro_rules! body {
                ($xr:expr, $yr:expr) => {{
                    let mut chart = builder.build_cartesian_2d($xr, $yr).map_err(|e| err(&e))?;
                    chart
                        .configure_mesh()
                        .x_desc(&self.x_desc)
                        .y_desc(&self.y_desc)
                        .x_label_formatter(&|v| tick_label(*v))
                        .y_label_formatter(&|v| tick_label(*v))
                        .draw()
                        .map_err(|e| err(&e))?;
                    for (i, s) in self.series.iter().enumerate() {
                        let color = s.rgb(i);
                        let style = color.stroke_width(2);
                        if s.line {
                            chart
                                .draw_series(LineSeries::new(s.points.clone(), style))
                                .map_err(|e| err(&e))?;
                        }
                        if s.markers {
                            let labels = s.labels.clone();
                            chart
                                .draw_series(s.points.iter().enumerate().map(|(k, &p)| {
                                    EmptyElement::at(p)
                                        + Circle::new((0, 0), 5, color.filled())
                                        + Text::new(
                                            labels.get(k).cloned().unwrap_or_default(),
                                            (7, -14),
                                            ("sans-serif", 13),
                                        )
                                }))
                                .map_err(|e| err(&e))?;
                        }
                    }
                }};
            }
            match (self.x_log, self.y_log) {
                (true, true) => body!((x0..x1).log_scale(), (y0..y1).log_scale()),
                (true, false) => body!((x0..x1).log_scale(), y0..y1),
                (false, true) => body!(x0..x1, (y0..y1).log_scale()),
                (false, false) => body!(x0..x1, y0..y1),
            }
            let (step, px) = self.legend_rows();
            let lx = (WIDTH - LEGEND_WIDTH + 8) as i32;
            for (k, (i, s)) in self.named().enumerate() {
                let (r, g, b) = {
                    let c = s.rgb(i);
                    (c.0, c.1, c.2)
                };
                let y = LEGEND_TOP + k as i32 * step;
                let mid = y + line_height(px) as i32 / 2;
                root.draw(&Rectangle::new([(lx, mid - 5), (lx + 18, mid + 5)], RGBColor(r, g, b).filled()))
                    .map_err(|e| err(&e))?;
                let name = fit_text(&s.name, px, LEGEND_WIDTH - 36);
                let style = TextStyle::from(("sans-serif", px as f64).into_font())
                    .pos(Pos::new(HPos::Left, VPos::Center));
                root.draw(&Text::new(name, (lx + 24, mid), style)).map_err(|e| err(&e))?;
            }
            root.present().map_err(|e| err(&e))?;
        }
        std::fs::write(path, text).map_err(|e| err(&e))
    }

    fn draw_png(&self, path: &Path) -> Result<(), OitError> {
        self.png_image(path)?.save_png(path)
    }

    /// The PNG's pixels (`path` only names the file in errors).
    fn png_image(&self, path: &Path) -> Result<Image, OitError> {
        let err = write_err(path);
        let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
        let ((x0, x1), (y0, y1)) = self.ranges();
        let (xt, yt) = (ticks((x0, x1), self.x_log), ticks((y0, y1), self.y_log));
        let mut texts: Vec<Label> = Vec::new();
        {
            let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| err(&e))?;
            let (area, _) = root.split_horizontally(WIDTH - LEGEND_WIDTH);
            let mut builder = ChartBuilder::on(&area);
            builder.margin(14).margin_top(72).x_label_area_size(60).y_label_area_size(90);
            macro_rules! body {
                ($xr:expr, $yr:expr) => {{
                    let chart = builder.build_cartesian_2d($xr, $yr).map_err(|e| err(&e))?;
                    self.png_body(chart, &xt, &yt, (x0, x1), (y0, y1), &mut texts).map_err(|e| err(&e))?;
                }};
            }
            match (self.x_log, self.y_log) {
                (true, true) => body!((x0..x1).log_scale(), (y0..y1).log_scale()),
                (true, false) => body!((x0..x1).log_scale(), y0..y1),
                (false, true) => body!(x0..x1, (y0..y1).log_scale()),
                (false, false) => body!(x0..x1, y0..y1),
            }
            root.present().map_err(|e| err(&e))?;
        }
        let mut image = Image {
            width: WIDTH,
            height: HEIGHT,
            pixels: buf.chunks_exact(3).map(|p| [p[0], p[1], p[2], 255]).collect(),
        };
        texts.push(((WIDTH - LEGEND_WIDTH) as i32 / 2, 14, self.title.clone(), TITLE_PX, true));
        for (x, y, text, px, centred) in texts {
            let x = if centred { x - text_width(&text, px) as i32 / 2 } else { x };
            draw_text(&mut image, x.into(), y.into(), &text, px, [0, 0, 0, 255]);
        }
        // the legend, right of the chart
        let (step, px) = self.legend_rows();
        let lx = (WIDTH - LEGEND_WIDTH + 8) as i32;
        for (k, (i, s)) in self.named().enumerate() {
            let c = s.rgb(i);
            let y = LEGEND_TOP + k as i32 * step;
            let mid = y + line_height(px) as i32 / 2;
            fill_rect(&mut image, lx.into(), (mid - 5).into(), 18, 10, [c.0, c.1, c.2, 255]);
            let name = fit_text(&s.name, px, LEGEND_WIDTH - 36);
            draw_text(&mut image, (lx + 24).into(), y.into(), &name, px, [0, 0, 0, 255]);
        }
        Ok(image)
    }

    fn png_body<X, Y>(
        &self,
        mut chart: ChartContext<'_, BitMapBackend<'_>, Cartesian2d<X, Y>>,
        xt: &[f64],
        yt: &[f64],
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
        texts: &mut Vec<Label>,
    ) -> Result<(), String>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let e = |e: &dyn std::fmt::Display| e.to_string();
        let grid = RGBColor(225, 225, 225);
        for &x in xt {
            chart.draw_series(LineSeries::new([(x, y0), (x, y1)], grid)).map_err(|x| e(&x))?;
            let (px, py) = chart.backend_coord(&(x, y0));
            texts.push((px, py + 8, tick_label(x), TICK_PX, true));
        }
        for &y in yt {
            chart.draw_series(LineSeries::new([(x0, y), (x1, y)], grid)).map_err(|x| e(&x))?;
            let (px, py) = chart.backend_coord(&(x0, y));
            let label = tick_label(y);
            let (w, h) = (text_width(&label, TICK_PX) as i32, line_height(TICK_PX) as i32);
            texts.push((px - 8 - w, py - h / 2, label, TICK_PX, false));
        }
        chart
            .draw_series([PathElement::new(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)], BLACK)])
            .map_err(|x| e(&x))?;
        for (i, s) in self.series.iter().enumerate() {
            let color = s.rgb(i);
            if s.line {
                chart
                    .draw_series(LineSeries::new(s.points.clone(), color.stroke_width(2)))
                    .map_err(|x| e(&x))?;
            }
            if s.markers {
                chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 5, color.filled())))
                    .map_err(|x| e(&x))?;
                for (p, label) in s.points.iter().zip(&s.labels) {
                    let (px, py) = chart.backend_coord(p);
                    texts.push((px + 7, py - 15, label.clone(), POINT_PX, false));
                }
            }
        }
        let (bx, by) = chart.backend_coord(&(x0, y0));
        let (tx, ty) = chart.backend_coord(&(x1, y1));
        texts.push(((bx + tx) / 2, by + 34, self.x_desc.clone(), DESC_PX, true));
        texts.push((8, ty - 30, self.y_desc.clone(), DESC_PX, false));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_ticks() {
        assert_eq!(range([0.003, 0.2].into_iter(), true), (0.001, 1.0));
        assert_eq!(
            ticks((0.001, 1.0), true),
            vec![0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0]
        );
        let t = ticks((0.0, 10.0), false);
        assert_eq!(t.first(), Some(&0.0));
        assert_eq!(t.last(), Some(&10.0));
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(1e-5), "1e-5");
    }

    #[test]
    fn absurd_values_are_drawn_at_the_edge() {
        assert_eq!(range([1e-308, 1e308].into_iter(), true), (LOG_FLOOR, AXIS_LIMIT));
        let (lo, hi) = range([-1e308, 1e308].into_iter(), false);
        assert!(lo >= -AXIS_LIMIT * 1.1 && hi <= AXIS_LIMIT * 1.1);
        assert!(ticks((LOG_FLOOR, AXIS_LIMIT), true).len() <= MAX_TICKS);
        let chart = Chart {
            title: "extremes".into(),
            x_desc: "x".into(),
            y_desc: "y".into(),
            x_log: true,
            y_log: true,
            series: vec![Series {
                name: "s".into(),
                points: vec![(1e-308, 1e308), (1.0, f64::NAN), (2.0, 0.5), (f64::INFINITY, 1.0)],
                labels: vec!["a".into(), "b".into(), "c".into(), "d".into()],
                line: true,
                markers: true,
                color: None,
            }],
        };
        let clamped = chart.clamped();
        let s = &clamped.series[0];
        assert_eq!(s.points, [(LOG_FLOOR, AXIS_LIMIT), (2.0, 0.5)]);
        assert_eq!(s.labels, ["a", "c"]);
        let dir = std::env::temp_dir().join(format!("oit-plot-extremes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        chart.svg(&dir.join("x.svg")).unwrap();
        chart.png(&dir.join("x.png")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Issue 14: the legend sits in its own column right of the plot area, never over the data:
    /// naming the series (even many, with long names) changes no pixel left of that column, and
    /// the column holds the legend's swatches.
    #[test]
    fn the_legend_never_covers_the_plot() {
        let series = |named: bool| {
            (0..40)
                .map(|i| Series {
                    name: if named {
                        format!("technique {i} (backend/with-a-long-path-name)")
                    } else {
                        String::new()
                    },
                    points: (0..=36)
                        .map(|k| (f64::from(k) * 10.0, 1e-3 * f64::from(1 + (k * (i + 1)) % 97)))
                        .collect(),
                    labels: Vec::new(),
                    line: true,
                    markers: false,
                    color: None,
                })
                .collect()
        };
        let chart = |named| {
            Chart {
                title: "t".into(),
                x_desc: "x".into(),
                y_desc: "y".into(),
                x_log: false,
                y_log: true,
                series: series(named),
            }
            .clamped()
        };
        let path = Path::new("legend.png");
        let (with, without) = (chart(true).png_image(path).unwrap(), chart(false).png_image(path).unwrap());
        let column = WIDTH - LEGEND_WIDTH;
        let mut legend = 0;
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                let differs = with.get(x, y) != without.get(x, y);
                assert!(!differs || x >= column, "the legend drew at ({x}, {y}), inside the plot");
                legend += usize::from(differs);
            }
        }
        assert!(legend > 40 * 100, "the legend's 40 rows drew only {legend} pixels");
        // every row inside the picture
        let (step, px) = chart(true).legend_rows();
        assert!(LEGEND_TOP + 40 * step <= HEIGHT as i32 && px >= 3.0, "{step} {px}");
    }

    /// Issue 13.5: an SVG or PNG chart written to a full disk is an error.
    #[cfg(target_os = "linux")]
    #[test]
    fn charts_to_a_full_disk_are_errors() {
        let chart = Chart {
            title: "t".into(),
            x_desc: "x".into(),
            y_desc: "y".into(),
            x_log: false,
            y_log: false,
            series: vec![Series {
                name: "s".into(),
                points: vec![(1.0, 1.0), (2.0, 0.5)],
                labels: vec![],
                line: true,
                markers: false,
                color: None,
            }],
        };
        assert!(chart.svg(Path::new("/dev/full")).is_err());
        assert!(chart.png(Path::new("/dev/full")).is_err());
    }
}
