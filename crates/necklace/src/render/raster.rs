//! The canvas one view is drawn on, at `supersample` times the final resolution: a
//! shaded surface layer with its depth, an overlay layer (lines and dots) with its own
//! depth, compositing (overlay hidden behind the surface shows through at `1 − opacity`),
//! outlines at depth jumps, text, and the box-filtered reduction to final pixels.
//!
//! Pixel coordinates: x to the right, y down, pixel centres at half-integers; depth grows
//! away from the viewer (world units).

use super::font;

/// A colour with components in 0..=1.
pub type Rgb = [f32; 3];

pub struct Canvas {
    pub width: usize,
    pub height: usize,
    color: Vec<[u8; 3]>,
    depth: Vec<f32>,
    overlay: Vec<[u8; 3]>,
    overlay_depth: Vec<f32>,
}

fn to_u8(c: Rgb) -> [u8; 3] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
}

fn to_f32(c: [u8; 3]) -> Rgb {
    c.map(|v| f32::from(v) / 255.0)
}

/// The parameter of the point of segment `a`–`b` closest to the centre of pixel
/// (`x`, `y`), and the distance to it.
fn closest_on_segment(x: usize, y: usize, a: [f64; 2], b: [f64; 2]) -> (f64, f64) {
    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
    let d = [b[0] - a[0], b[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        (((px - a[0]) * d[0] + (py - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a[0] + t * d[0] - px, a[1] + t * d[1] - py);
    (t, (qx * qx + qy * qy).sqrt())
}

fn mix(a: Rgb, b: Rgb, t: f32) -> Rgb {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

impl Canvas {
    pub fn new(width: usize, height: usize, background: Rgb) -> Canvas {
        let n = width * height;
        Canvas {
            width,
            height,
            color: vec![to_u8(background); n],
            depth: vec![f32::INFINITY; n],
            overlay: vec![[0; 3]; n],
            overlay_depth: vec![f32::INFINITY; n],
        }
    }

    /// Pixel index range of `[lo, hi]` clipped to `0..len`.
    fn span(lo: f64, hi: f64, len: usize) -> std::ops::Range<usize> {
        let a = lo.floor().max(0.0) as usize;
        let b = (hi.ceil().max(0.0) as usize).min(len);
        a.min(b)..b
    }

    /// Fill a triangle (screen x, y and depth per corner) into the surface layer with the
    /// colour `shade` gives for the interpolated corner `normals`.
    pub fn triangle(
        &mut self,
        p: [[f64; 3]; 3],
        normals: [[f64; 3]; 3],
        shade: impl Fn([f64; 3]) -> Rgb,
    ) {
        let area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        if area.abs() < 1e-12 {
            return;
        }
        let xs = Self::span(
            p.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min) - 0.5,
            p.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max) + 0.5,
            self.width,
        );
        let ys = Self::span(
            p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min) - 0.5,
            p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max) + 0.5,
            self.height,
        );
        let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| {
            (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
        };
        for y in ys {
            let py = y as f64 + 0.5;
            for x in xs.clone() {
                let px = x as f64 + 0.5;
                let w0 = edge(p[1], p[2], px, py) / area;
                let w1 = edge(p[2], p[0], px, py) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9 {
                    continue;
                }
                let z = (w0 * p[0][2] + w1 * p[1][2] + w2 * p[2][2]) as f32;
                let i = y * self.width + x;
                if z >= self.depth[i] {
                    continue;
                }
                self.depth[i] = z;
                let n =
                    [0, 1, 2].map(|k| w0 * normals[0][k] + w1 * normals[1][k] + w2 * normals[2][k]);
                self.color[i] = to_u8(shade(n));
            }
        }
    }

    fn overlay_fragment(&mut self, x: usize, y: usize, z: f32, color: Rgb) {
        let i = y * self.width + x;
        if z < self.overlay_depth[i] {
            self.overlay_depth[i] = z;
            self.overlay[i] = to_u8(color);
        }
    }

    /// A segment `a`–`b` (screen x, y, depth) as a shaded tube of half width `w` pixels.
    pub fn segment(&mut self, a: [f64; 3], b: [f64; 3], w: f64, color: Rgb) {
        let xs = Self::span(a[0].min(b[0]) - w, a[0].max(b[0]) + w, self.width);
        let ys = Self::span(a[1].min(b[1]) - w, a[1].max(b[1]) + w, self.height);
        for y in ys {
            for x in xs.clone() {
                let (t, distance) = closest_on_segment(x, y, [a[0], a[1]], [b[0], b[1]]);
                let s = distance / w;
                if s > 1.0 {
                    continue;
                }
                // A cylinder lit from the viewer: bright along its axis, darker at its rim.
                let light = (0.45 + 0.55 * (1.0 - s * s).sqrt()) as f32;
                let z = a[2] + t * (b[2] - a[2]);
                self.overlay_fragment(x, y, z as f32, color.map(|c| c * light));
            }
        }
    }

    /// A dot at `c` (screen x, y, depth) of radius `r` pixels, shaded as a ball with a
    /// dark rim.
    pub fn dot(&mut self, c: [f64; 3], r: f64, color: Rgb) {
        let xs = Self::span(c[0] - r, c[0] + r, self.width);
        let ys = Self::span(c[1] - r, c[1] + r, self.height);
        for y in ys {
            for x in xs.clone() {
                let (dx, dy) = (x as f64 + 0.5 - c[0], y as f64 + 0.5 - c[1]);
                let s = (dx * dx + dy * dy).sqrt() / r;
                if s > 1.0 {
                    continue;
                }
                let shaded = if s > 0.78 {
                    [0.1; 3]
                } else {
                    let light = (0.5 + 0.5 * (1.0 - s * s).sqrt()) as f32;
                    color.map(|v| v * light)
                };
                // Slightly in front of a line through the same point.
                self.overlay_fragment(x, y, (c[2] - 1e-6) as f32, shaded);
            }
        }
    }

    /// Darken surface pixels where the depth jumps by more than `jump` (or the surface
    /// ends) within `reach` pixels: silhouettes and occluding contours.
    pub fn outline(&mut self, reach: usize, jump: f32, color: Rgb, strength: f32) {
        let (w, h) = (self.width, self.height);
        let mut edge = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                let z = self.depth[y * w + x];
                if !z.is_finite() {
                    continue;
                }
                let far = |xx: isize, yy: isize| {
                    if xx < 0 || yy < 0 || xx >= w as isize || yy >= h as isize {
                        return true;
                    }
                    let other = self.depth[yy as usize * w + xx as usize];
                    !other.is_finite() || other - z > jump
                };
                let (xi, yi, r) = (x as isize, y as isize, reach as isize);
                edge[y * w + x] =
                    far(xi - r, yi) || far(xi + r, yi) || far(xi, yi - r) || far(xi, yi + r);
            }
        }
        for (i, e) in edge.into_iter().enumerate() {
            if e {
                self.color[i] = to_u8(mix(to_f32(self.color[i]), color, strength));
            }
        }
    }

    /// Put the overlay onto the surface layer: overlay in front of the surface (within
    /// `tolerance` in depth) replaces it; overlay behind it shows at `1 − opacity`.
    pub fn composite(&mut self, opacity: f32, tolerance: f32) {
        for i in 0..self.color.len() {
            let z = self.overlay_depth[i];
            if !z.is_finite() {
                continue;
            }
            if z <= self.depth[i] + tolerance {
                self.color[i] = self.overlay[i];
            } else {
                let c = mix(
                    to_f32(self.color[i]),
                    to_f32(self.overlay[i]),
                    1.0 - opacity,
                );
                self.color[i] = to_u8(c);
            }
        }
    }

    /// Fill an axis-aligned rectangle on the surface layer (legends, chart frames).
    pub fn rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, color: Rgb) {
        let c = to_u8(color);
        for y in Self::span(y0, y1, self.height) {
            for x in Self::span(x0, x1, self.width) {
                self.color[y * self.width + x] = c;
            }
        }
    }

    /// A flat line of half width `w` drawn straight onto the surface layer (charts).
    pub fn flat_line(&mut self, a: [f64; 2], b: [f64; 2], w: f64, color: Rgb) {
        let c = to_u8(color);
        let xs = Self::span(a[0].min(b[0]) - w, a[0].max(b[0]) + w, self.width);
        let ys = Self::span(a[1].min(b[1]) - w, a[1].max(b[1]) + w, self.height);
        for y in ys {
            for x in xs.clone() {
                if closest_on_segment(x, y, a, b).1 <= w {
                    self.color[y * self.width + x] = c;
                }
            }
        }
    }

    /// Text with its top-left corner at (`x`, `y`), each font pixel `scale` canvas
    /// pixels, over a `halo` of one font pixel when given.
    pub fn text(
        &mut self,
        x: f64,
        y: f64,
        scale: usize,
        text: &str,
        color: Rgb,
        halo: Option<Rgb>,
    ) {
        let mut pass = |grow: isize, c: [u8; 3]| {
            for (k, ch) in text.chars().enumerate() {
                let gx = x as isize + (k * font::ADVANCE * scale) as isize;
                for row in 0..font::HEIGHT {
                    for col in 0..font::WIDTH {
                        if !font::is_set(ch, col, row) {
                            continue;
                        }
                        let x0 = gx + (col * scale) as isize - grow;
                        let y0 = y as isize + (row * scale) as isize - grow;
                        let n = scale as isize + 2 * grow;
                        for yy in y0.max(0)..(y0 + n).min(self.height as isize) {
                            for xx in x0.max(0)..(x0 + n).min(self.width as isize) {
                                self.color[yy as usize * self.width + xx as usize] = c;
                            }
                        }
                    }
                }
            }
        };
        if let Some(h) = halo {
            pass(scale.div_ceil(2) as isize + 1, to_u8(h));
        }
        pass(0, to_u8(color));
    }

    /// Average `factor × factor` blocks into final pixels, written into `out` (row
    /// stride `out_width`) at (`ox`, `oy`).
    pub fn reduce_into(
        &self,
        factor: usize,
        out: &mut [[u8; 3]],
        out_width: usize,
        ox: usize,
        oy: usize,
    ) {
        let (w, h) = (self.width / factor, self.height / factor);
        let n = (factor * factor) as u32;
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0u32; 3];
                for yy in 0..factor {
                    for xx in 0..factor {
                        let c = self.color[(y * factor + yy) * self.width + x * factor + xx];
                        for k in 0..3 {
                            sum[k] += u32::from(c[k]);
                        }
                    }
                }
                let i = (oy + y) * out_width + ox + x;
                if i < out.len() {
                    out[i] = sum.map(|s| ((s + n / 2) / n) as u8);
                }
            }
        }
    }
}
