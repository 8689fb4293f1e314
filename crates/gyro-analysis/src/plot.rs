//! Line plots as SVG and PNG from one layout.
//!
//! A [`Figure`] is laid out once into primitives (polylines, rectangles, text); the SVG writer
//! prints them, and a small rasteriser draws them into an RGBA image (anti-aliased lines by
//! distance to the segment, text from the public-domain 8×8 bitmap font of `font8x8`) that the
//! `png` crate encodes. No font file, system library or drawing crate is needed, so a fresh CI
//! machine renders the same picture.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{AnalysisError, Result};
use crate::file::write_whole;

/// Ten well-separated colours (matplotlib's tab10).
pub const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// One curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Shown in the legend (empty: not listed).
    pub name: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub color: [u8; 3],
    pub dashed: bool,
    pub width_px: f64,
}

/// A line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub width_px: u32,
    pub height_px: u32,
    /// Logarithmic x axis (decade ticks); non-positive x values are left out.
    pub log_x: bool,
    /// Logarithmic y axis (decade ticks); non-positive y values are left out.
    pub log_y: bool,
}

impl Figure {
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.to_owned(),
            x_label: x_label.to_owned(),
            y_label: y_label.to_owned(),
            series: Vec::new(),
            width_px: 1200,
            height_px: 700,
            log_x: false,
            log_y: false,
        }
    }

    /// Several figures in one SVG, `cols` per row (each at its own size; cells are the largest).
    pub fn grid_svg(figures: &[Figure], cols: usize) -> String {
        let (cw, ch, w, h) = grid_size(figures, cols);
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
        );
        let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        for (i, f) in figures.iter().enumerate() {
            let (x, y) = ((i % cols.max(1)) as u32 * cw, (i / cols.max(1)) as u32 * ch);
            let inner = f.to_svg();
            // The figure's own document, nested: an <svg> element places itself at x, y.
            let inner = inner.replacen("<svg ", &format!(r#"<svg x="{x}" y="{y}" "#), 1);
            s.push_str(&inner);
        }
        s.push_str("</svg>\n");
        s
    }

    /// Several figures in one PNG, `cols` per row.
    pub fn grid_png(figures: &[Figure], cols: usize) -> std::result::Result<Vec<u8>, String> {
        let (cw, ch, w, h) = grid_size(figures, cols);
        let mut canvas = Canvas::new(w, h);
        for (i, f) in figures.iter().enumerate() {
            let (dx, dy) = (
                f64::from((i % cols.max(1)) as u32 * cw),
                f64::from((i / cols.max(1)) as u32 * ch),
            );
            for p in &f.layout() {
                canvas.draw(&p.shifted(dx, dy));
            }
        }
        canvas.encode_png()
    }

    /// The SVG document.
    pub fn to_svg(&self) -> String {
        let prims = self.layout();
        let (w, h) = (self.width_px, self.height_px);
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
        );
        for p in &prims {
            match p {
                Prim::Rect {
                    x,
                    y,
                    w,
                    h,
                    fill,
                    stroke,
                } => {
                    let fill = fill.map_or("none".to_owned(), rgb);
                    let stroke = stroke.map_or("none".to_owned(), rgb);
                    let _ = writeln!(
                        s,
                        r#"<rect x="{x:.1}" y="{y:.1}" width="{w:.1}" height="{h:.1}" fill="{fill}" stroke="{stroke}"/>"#
                    );
                }
                Prim::Line {
                    points,
                    color,
                    width,
                    dashed,
                } => {
                    let mut d = String::with_capacity(points.len() * 14);
                    for (i, (x, y)) in points.iter().enumerate() {
                        let _ = write!(d, "{}{x:.1},{y:.1}", if i == 0 { "" } else { " " });
                    }
                    let dash = if *dashed {
                        r#" stroke-dasharray="7,5""#
                    } else {
                        ""
                    };
                    let _ = writeln!(
                        s,
                        r#"<polyline points="{d}" fill="none" stroke="{}" stroke-width="{width:.1}" stroke-linejoin="round"{dash}/>"#,
                        rgb(*color)
                    );
                }
                Prim::Text {
                    x,
                    y,
                    text,
                    size,
                    anchor,
                    vertical,
                } => {
                    let anchor = match anchor {
                        Anchor::Start => "start",
                        Anchor::Middle => "middle",
                        Anchor::End => "end",
                    };
                    let rotate = if *vertical {
                        format!(r#" transform="rotate(-90 {x:.1} {y:.1})""#)
                    } else {
                        String::new()
                    };
                    let _ = writeln!(
                        s,
                        r#"<text x="{x:.1}" y="{y:.1}" font-size="{}" text-anchor="{anchor}" dominant-baseline="middle"{rotate}>{}</text>"#,
                        size * 6.5,
                        xml_escape(text)
                    );
                }
            }
        }
        s.push_str("</svg>\n");
        s
    }

    /// The PNG image (8-bit RGB).
    pub fn to_png(&self) -> std::result::Result<Vec<u8>, String> {
        let mut canvas = Canvas::new(self.width_px, self.height_px);
        for p in &self.layout() {
            canvas.draw(p);
        }
        canvas.encode_png()
    }

    /// Writes `<stem>.svg` and `<stem>.png`.
    pub fn write(&self, stem: &Path) -> Result<(PathBuf, PathBuf)> {
        let svg = stem.with_extension("svg");
        let png = stem.with_extension("png");
        let text = self.to_svg();
        write_whole(&svg, |w| {
            w.write_all(text.as_bytes())
                .map_err(AnalysisError::io(&svg, "writing"))
        })?;
        let bytes = self.to_png().map_err(|e| AnalysisError::Io {
            path: png.clone(),
            action: "encoding PNG",
            source: std::io::Error::other(e),
        })?;
        write_whole(&png, |w| {
            w.write_all(&bytes)
                .map_err(AnalysisError::io(&png, "writing"))
        })?;
        Ok((svg, png))
    }

    fn layout(&self) -> Vec<Prim> {
        let (w, h) = (self.width_px as f64, self.height_px as f64);
        let (mut left, right, top, bottom) = (90.0, w - 250.0, 50.0, h - 60.0);
        let mut prims = vec![
            Prim::Rect {
                x: 0.0,
                y: 0.0,
                w,
                h,
                fill: Some([255, 255, 255]),
                stroke: None,
            },
            Prim::Text {
                x: w / 2.0,
                y: 22.0,
                text: self.title.clone(),
                size: 2.4,
                anchor: Anchor::Middle,
                vertical: false,
            },
        ];
        let (log_x, log_y) = (self.log_x, self.log_y);
        let axis = |v: f64, log: bool| if log { v.log10() } else { v };
        let finite = |s: &Series| -> Vec<(f64, f64)> {
            s.x.iter()
                .zip(&s.y)
                .map(|(a, b)| (axis(*a, log_x), axis(*b, log_y)))
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .collect()
        };
        let all: Vec<(f64, f64)> = self.series.iter().flat_map(finite).collect();
        let range = |f: fn(&(f64, f64)) -> f64| {
            let (lo, hi) = all
                .iter()
                .map(f)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(v), h.max(v))
                });
            if !(lo.is_finite() && hi.is_finite()) {
                (0.0, 1.0)
            } else if hi - lo <= f64::EPSILON * hi.abs().max(1.0) {
                (lo - 0.5 * lo.abs().max(1e-9), hi + 0.5 * hi.abs().max(1e-9))
            } else {
                (lo, hi)
            }
        };
        let ticks = |r: (f64, f64), log: bool| {
            if log { decade_ticks(r) } else { nice_ticks(r) }
        };
        let (x_ticks, (x0, x1)) = ticks(range(|p| p.0), log_x);
        let (y_ticks, (y0, y1)) = ticks(range(|p| p.1), log_y);
        let label = |t: f64, ticks: &[f64], log: bool| {
            if log {
                format!("1e{}", t.round() as i64)
            } else {
                tick_label(t, ticks)
            }
        };
        // Room for the longest y tick label (16 px per character in the PNG at size 1.6) and
        // the vertical axis label beside it.
        let widest = y_ticks
            .iter()
            .map(|&t| label(t, &y_ticks, log_y).chars().count())
            .max()
            .unwrap_or(0);
        left = f64::max(left, 44.0 + 16.0 * widest as f64);
        let px = |x: f64| left + (x - x0) / (x1 - x0) * (right - left);
        let py = |y: f64| bottom - (y - y0) / (y1 - y0) * (bottom - top);
        let grid = [225, 225, 225];
        let axis = [60, 60, 60];
        for &t in &x_ticks {
            prims.push(line(vec![(px(t), top), (px(t), bottom)], grid, 1.0));
            prims.push(text(
                px(t),
                bottom + 16.0,
                label(t, &x_ticks, log_x),
                1.6,
                Anchor::Middle,
            ));
        }
        for &t in &y_ticks {
            prims.push(line(vec![(left, py(t)), (right, py(t))], grid, 1.0));
            prims.push(text(
                left - 8.0,
                py(t),
                label(t, &y_ticks, log_y),
                1.6,
                Anchor::End,
            ));
        }
        prims.push(Prim::Rect {
            x: left,
            y: top,
            w: right - left,
            h: bottom - top,
            fill: None,
            stroke: Some(axis),
        });
        prims.push(text(
            (left + right) / 2.0,
            h - 20.0,
            self.x_label.clone(),
            2.0,
            Anchor::Middle,
        ));
        prims.push(Prim::Text {
            x: 16.0,
            y: (top + bottom) / 2.0,
            text: self.y_label.clone(),
            size: 2.0,
            anchor: Anchor::Middle,
            vertical: true,
        });
        for s in &self.series {
            let pts: Vec<(f64, f64)> = finite(s).iter().map(|(a, b)| (px(*a), py(*b))).collect();
            if pts.len() >= 2 {
                prims.push(Prim::Line {
                    points: pts,
                    color: s.color,
                    width: s.width_px,
                    dashed: s.dashed,
                });
            } else if let [(x, y)] = pts[..] {
                // A lone point (e.g. an exact method's one run): a cross.
                for (dx, dy) in [(6.0, 6.0), (6.0, -6.0)] {
                    prims.push(line(vec![(x - dx, y - dy), (x + dx, y + dy)], s.color, 2.0));
                }
            }
        }
        self.legend(&mut prims, right, top);
        prims
    }

    /// The legend to the right of the plot (from x = `right`), at most 24 entries.
    fn legend(&self, prims: &mut Vec<Prim>, right: f64, top: f64) {
        let w = self.width_px as f64;
        let named: Vec<&Series> = self.series.iter().filter(|s| !s.name.is_empty()).collect();
        let mut y = top + 10.0;
        for s in named.iter().take(24) {
            prims.push(Prim::Line {
                points: vec![(right + 14.0, y), (right + 44.0, y)],
                color: s.color,
                width: s.width_px.max(2.0),
                dashed: s.dashed,
            });
            // As many characters as fit between the legend's line and the image's edge.
            let room = ((w - right - 56.0) / 16.0).max(4.0) as usize;
            let name: String = s.name.chars().take(room.min(22)).collect();
            prims.push(text(right + 52.0, y, name, 1.6, Anchor::Start));
            y += 20.0;
        }
        if named.len() > 24 {
            prims.push(text(
                right + 52.0,
                y,
                format!("... and {} more", named.len() - 24),
                1.6,
                Anchor::Start,
            ));
        }
    }
}

fn line(points: Vec<(f64, f64)>, color: [u8; 3], width: f64) -> Prim {
    Prim::Line {
        points,
        color,
        width,
        dashed: false,
    }
}

fn text(x: f64, y: f64, text: String, size: f64, anchor: Anchor) -> Prim {
    Prim::Text {
        x,
        y,
        text,
        size,
        anchor,
        vertical: false,
    }
}

fn rgb(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Ticks at 1, 2 or 5 × 10^k covering (lo, hi); returns them and the widened range.
fn nice_ticks((lo, hi): (f64, f64)) -> (Vec<f64>, (f64, f64)) {
    let span = hi - lo;
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let a = (lo / step).floor() * step;
    let b = (hi / step).ceil() * step;
    let n = ((b - a) / step).round() as usize;
    let ticks = (0..=n.min(50)).map(|i| a + i as f64 * step).collect();
    (ticks, (a, b))
}

/// Whole decades covering (lo, hi) of log10 values (at most 8 labelled: every k-th decade).
fn decade_ticks((lo, hi): (f64, f64)) -> (Vec<f64>, (f64, f64)) {
    let (a, b) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
    let n = (b - a) as usize;
    let every = n.div_ceil(8).max(1);
    let ticks = (0..=n).step_by(every).map(|i| a + i as f64).collect();
    (ticks, (a, b))
}

fn grid_size(figures: &[Figure], cols: usize) -> (u32, u32, u32, u32) {
    let cols = cols.max(1);
    let cw = figures.iter().map(|f| f.width_px).max().unwrap_or(1);
    let ch = figures.iter().map(|f| f.height_px).max().unwrap_or(1);
    let rows = figures.len().div_ceil(cols).max(1) as u32;
    let used_cols = cols.min(figures.len().max(1)) as u32;
    (cw, ch, cw * used_cols, ch * rows)
}

fn tick_label(v: f64, ticks: &[f64]) -> String {
    let step = if ticks.len() >= 2 {
        (ticks[1] - ticks[0]).abs()
    } else {
        1.0
    };
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    let big = ticks.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    if big >= 1e5 || (big > 0.0 && big < 1e-3) {
        return format!("{v:.1e}");
    }
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Anchor {
    Start,
    Middle,
    End,
}

/// A drawing primitive in pixel coordinates (y down).
#[derive(Debug, Clone, PartialEq)]
enum Prim {
    Rect {
        x: f64,
        y: f64,
        w: f64,
        h: f64,
        fill: Option<[u8; 3]>,
        stroke: Option<[u8; 3]>,
    },
    Line {
        points: Vec<(f64, f64)>,
        color: [u8; 3],
        width: f64,
        dashed: bool,
    },
    /// `size`: glyph scale (the PNG draws 8×8 glyphs at round(size) pixels per font pixel,
    /// the SVG a font of 6.5 × size px).
    Text {
        x: f64,
        y: f64,
        text: String,
        size: f64,
        anchor: Anchor,
        vertical: bool,
    },
}

impl Prim {
    fn shifted(&self, dx: f64, dy: f64) -> Prim {
        let mut p = self.clone();
        match &mut p {
            Prim::Rect { x, y, .. } | Prim::Text { x, y, .. } => {
                *x += dx;
                *y += dy;
            }
            Prim::Line { points, .. } => {
                for (x, y) in points {
                    *x += dx;
                    *y += dy;
                }
            }
        }
        p
    }
}

struct Canvas {
    w: usize,
    h: usize,
    rgb: Vec<f32>,
}

impl Canvas {
    fn new(w: u32, h: u32) -> Self {
        let (w, h) = (w as usize, h as usize);
        Self {
            w,
            h,
            rgb: vec![1.0; w * h * 3],
        }
    }

    fn blend(&mut self, x: i64, y: i64, color: [u8; 3], alpha: f32) {
        if x < 0 || y < 0 || x as usize >= self.w || y as usize >= self.h || alpha <= 0.0 {
            return;
        }
        let i = (y as usize * self.w + x as usize) * 3;
        let a = alpha.min(1.0);
        for (px, c) in self.rgb[i..i + 3].iter_mut().zip(color) {
            *px = *px * (1.0 - a) + c as f32 / 255.0 * a;
        }
    }

    fn segment(&mut self, (ax, ay): (f64, f64), (bx, by): (f64, f64), color: [u8; 3], width: f64) {
        let half = width / 2.0;
        let pad = half + 1.0;
        let (x0, x1) = ((ax.min(bx) - pad).floor(), (ax.max(bx) + pad).ceil());
        let (y0, y1) = ((ay.min(by) - pad).floor(), (ay.max(by) + pad).ceil());
        let (dx, dy) = (bx - ax, by - ay);
        let len2 = dx * dx + dy * dy;
        for y in y0 as i64..=y1 as i64 {
            for x in x0 as i64..=x1 as i64 {
                let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                let t = if len2 > 0.0 {
                    (((cx - ax) * dx + (cy - ay) * dy) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = ((cx - ax - t * dx).powi(2) + (cy - ay - t * dy).powi(2)).sqrt();
                let coverage = (half + 0.5 - d).clamp(0.0, 1.0);
                if coverage > 0.0 {
                    self.blend(x, y, color, coverage as f32);
                }
            }
        }
    }

    fn polyline(&mut self, points: &[(f64, f64)], color: [u8; 3], width: f64, dashed: bool) {
        let (on, off) = (7.0, 5.0);
        let mut phase = 0.0f64;
        for w in points.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
            if !dashed {
                self.segment(a, b, color, width);
                continue;
            }
            // Walk the segment in dash pieces.
            let mut s = 0.0;
            while s < len {
                let in_period = phase % (on + off);
                let (drawing, left) = if in_period < on {
                    (true, on - in_period)
                } else {
                    (false, on + off - in_period)
                };
                let e = (s + left).min(len);
                if drawing && len > 0.0 {
                    let p = |f: f64| (a.0 + (b.0 - a.0) * f / len, a.1 + (b.1 - a.1) * f / len);
                    self.segment(p(s), p(e), color, width);
                }
                phase += e - s;
                s = e;
            }
        }
    }

    fn text(&mut self, x: f64, y: f64, text: &str, size: f64, anchor: Anchor, vertical: bool) {
        let scale = size.round().max(1.0) as i64;
        let glyphs: Vec<[u8; 8]> = text.chars().map(glyph).collect();
        let advance = 8 * scale;
        let width = advance * glyphs.len() as i64;
        let offset = match anchor {
            Anchor::Start => 0,
            Anchor::Middle => -width / 2,
            Anchor::End => -width,
        };
        let (x, y) = (x.round() as i64, y.round() as i64);
        for (k, g) in glyphs.iter().enumerate() {
            for (row, bits) in g.iter().enumerate() {
                for col in 0..8 {
                    if bits & (1 << col) == 0 {
                        continue;
                    }
                    for sy in 0..scale {
                        for sx in 0..scale {
                            // Along the text (u) and across it (v), glyph centred on y.
                            let u = offset + k as i64 * advance + col * scale + sx;
                            let v = row as i64 * scale + sy - 4 * scale;
                            let (px, py) = if vertical {
                                (x + v, y - u)
                            } else {
                                (x + u, y + v)
                            };
                            self.blend(px, py, [30, 30, 30], 1.0);
                        }
                    }
                }
            }
        }
    }

    fn draw(&mut self, p: &Prim) {
        match p {
            Prim::Rect {
                x,
                y,
                w,
                h,
                fill,
                stroke,
            } => {
                if let Some(c) = fill {
                    for yy in y.round() as i64..(y + h).round() as i64 {
                        for xx in x.round() as i64..(x + w).round() as i64 {
                            self.blend(xx, yy, *c, 1.0);
                        }
                    }
                }
                if let Some(c) = stroke {
                    let pts = [(*x, *y), (x + w, *y), (x + w, y + h), (*x, y + h), (*x, *y)];
                    self.polyline(&pts, *c, 1.0, false);
                }
            }
            Prim::Line {
                points,
                color,
                width,
                dashed,
            } => self.polyline(points, *color, *width, *dashed),
            Prim::Text {
                x,
                y,
                text,
                size,
                anchor,
                vertical,
            } => self.text(*x, *y, text, *size, *anchor, *vertical),
        }
    }

    fn encode_png(&self) -> std::result::Result<Vec<u8>, String> {
        let bytes: Vec<u8> = self
            .rgb
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect();
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.w as u32, self.h as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().map_err(|e| e.to_string())?;
            writer.write_image_data(&bytes).map_err(|e| e.to_string())?;
            writer.finish().map_err(|e| e.to_string())?;
        }
        Ok(out)
    }
}

/// The 8×8 glyph of a character (unknown characters: a hollow box).
fn glyph(c: char) -> [u8; 8] {
    let code = c as usize;
    if code < 128 {
        font8x8::legacy::BASIC_LEGACY[code]
    } else if (0xA0..0x100).contains(&code) {
        font8x8::legacy::LATIN_LEGACY[code - 0xA0]
    } else if c == 'Λ' {
        [0x08, 0x14, 0x14, 0x22, 0x22, 0x41, 0x41, 0x00]
    } else if c == 'ζ' {
        [0x3E, 0x10, 0x08, 0x04, 0x04, 0x38, 0x40, 0x30]
    } else {
        [0x7E, 0x42, 0x42, 0x42, 0x42, 0x42, 0x7E, 0x00]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_the_range() {
        let (t, (a, b)) = nice_ticks((-0.3, 2.7));
        assert!(a <= -0.3 && b >= 2.7);
        assert_eq!(t.first().copied(), Some(a));
        assert!(t.len() >= 4 && t.len() <= 12, "{t:?}");
    }

    #[test]
    fn png_and_svg_render() {
        let mut f = Figure::new("t", "x", "y");
        f.series.push(Series {
            name: "a".into(),
            x: vec![0.0, 1.0, 2.0],
            y: vec![0.0, 1.0, f64::NAN],
            color: PALETTE[0],
            dashed: true,
            width_px: 2.0,
        });
        assert!(f.to_svg().contains("<polyline"));
        let png = f.to_png().unwrap_or_default();
        assert_eq!(&png[1..4], b"PNG");
    }

    #[test]
    fn log_axes_put_decades_on_ticks_and_drop_non_positive_values() {
        let mut f = Figure::new("t", "wall [s]", "error");
        (f.log_x, f.log_y) = (true, true);
        f.series.push(Series {
            name: "a".into(),
            x: vec![1e-4, 1e-3, 1e-2, 0.0],
            y: vec![1e-2, 1e-6, 1e-10, 1e-12],
            color: PALETTE[0],
            dashed: false,
            width_px: 2.0,
        });
        let svg = f.to_svg();
        for label in ["1e-4", "1e-2", "1e-10", "1e-6"] {
            assert!(svg.contains(&format!(">{label}<")), "{label} missing");
        }
        // The point at x = 0 has no logarithm: three vertices remain.
        let line = svg
            .lines()
            .find(|l| l.contains("<polyline") && l.contains("#1f77b4"))
            .unwrap_or_default();
        let pts = line.split("points=\"").nth(1).unwrap_or_default();
        assert_eq!(
            pts.split('"').next().unwrap_or_default().split(' ').count(),
            3
        );
        let (t, (a, b)) = decade_ticks((-10.3, -1.2));
        assert_eq!((a, b), (-11.0, -1.0));
        assert!(t.len() <= 9 && t[0] == -11.0, "{t:?}");
    }

    #[test]
    fn a_grid_places_every_figure() {
        let figs = vec![
            Figure::new("one", "x", "y"),
            Figure::new("two", "x", "y"),
            Figure::new("three", "x", "y"),
        ];
        let svg = Figure::grid_svg(&figs, 2);
        assert!(svg.starts_with("<svg") && svg.contains(r#"width="2400" height="1400""#));
        assert!(svg.contains(r#"<svg x="0" y="700""#) && svg.contains(r#"<svg x="1200" y="0""#));
        let png = Figure::grid_png(&figs, 2).unwrap_or_default();
        assert_eq!(&png[1..4], b"PNG");
        // IHDR: width and height, big-endian, at bytes 16..24.
        assert_eq!(
            u32::from_be_bytes([png[16], png[17], png[18], png[19]]),
            2400
        );
        assert_eq!(
            u32::from_be_bytes([png[20], png[21], png[22], png[23]]),
            1400
        );
    }
}
