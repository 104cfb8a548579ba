//! Line charts for benchmark figures (seconds against volume size, like the paper's
//! Fig. 12): linear axes from zero with round tick values, a light grid, one line with
//! square markers per series, a legend, a title and axis names. Entry point: [`chart`].

use super::raster::Canvas;
use super::{font, Image};
use crate::error::{Error, Result};

/// One line of a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// sRGB colour.
    pub color: [u8; 3],
    /// (x, y) points, drawn in this order.
    pub points: Vec<[f64; 2]>,
}

/// A chart.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chart {
    /// Written above the plot.
    pub title: String,
    /// Name of the horizontal axis.
    pub x_label: String,
    /// Name of the vertical axis.
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
}

/// A round step giving about `target` intervals over `0..max`.
fn tick_step(max: f64, target: f64) -> f64 {
    let raw = max / target;
    let magnitude = 10f64.powf(raw.log10().floor());
    let fraction = raw / magnitude;
    let nice = if fraction <= 1.0 {
        1.0
    } else if fraction <= 2.0 {
        2.0
    } else if fraction <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// The tick label of `v`, centred on `x`, its top at `y`.
pub(super) fn centred_tick_label(canvas: &mut Canvas, x: f64, y: f64, scale: usize, v: f64) {
    let text = tick_text(v);
    let width = (font::text_width(&text) * scale) as f64;
    canvas.text(x - 0.5 * width, y, scale, &text, [0.3; 3], None);
}

/// A tick value in few characters: 250K, 1.5M, 0.25.
pub(super) fn tick_text(v: f64) -> String {
    let trim = |s: String| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    if v.abs() >= 1e6 {
        trim(format!("{:.2}", v / 1e6)) + "M"
    } else if v.abs() >= 1e3 {
        trim(format!("{:.1}", v / 1e3)) + "K"
    } else {
        trim(format!("{v:.3}"))
    }
}

/// Draw `chart` into a `width × height` picture.
pub fn chart(chart: &Chart, width: u32, height: u32) -> Result<Image> {
    if !(200..=8192).contains(&width) || !(150..=8192).contains(&height) {
        return Err(Error::invalid_argument(
            "chart size must be at least 200 × 150 pixels",
        ));
    }
    let points = chart.series.iter().flat_map(|s| &s.points);
    if points
        .clone()
        .any(|p| !p[0].is_finite() || !p[1].is_finite())
    {
        return Err(Error::invalid_argument("chart has non-finite values"));
    }
    let x_max = points.clone().map(|p| p[0]).fold(0.0, f64::max);
    let y_max = points.map(|p| p[1]).fold(0.0, f64::max);
    let (x_max, y_max) = (
        if x_max > 0.0 { x_max } else { 1.0 },
        if y_max > 0.0 { y_max } else { 1.0 },
    );
    let (x_step, y_step) = (tick_step(x_max, 5.0), tick_step(y_max, 5.0));
    let (x_top, y_top) = (
        (x_max / x_step).ceil() * x_step,
        (y_max / y_step).ceil() * y_step,
    );

    let ss = 3usize;
    let (w, h) = (width as usize * ss, height as usize * ss);
    let mut canvas = Canvas::new(w, h, [1.0; 3]);
    let scale = ((width as f64 / 300.0).round().max(1.0) as usize) * ss;
    let glyph = (font::HEIGHT * scale) as f64;
    let (left, right) = (0.13 * w as f64, 0.96 * w as f64);
    let (top, bottom) = (0.14 * h as f64, 0.86 * h as f64);
    let sx = |x: f64| left + (right - left) * x / x_top;
    let sy = |y: f64| bottom - (bottom - top) * y / y_top;
    let line = ss as f64;

    // Grid and tick labels.
    let mut v = 0.0;
    while v <= y_top * (1.0 + 1e-9) {
        canvas.flat_line([left, sy(v)], [right, sy(v)], line * 0.6, [0.88; 3]);
        let text = tick_text(v);
        let tw = (font::text_width(&text) * scale) as f64;
        canvas.text(
            left - tw - glyph,
            sy(v) - 0.5 * glyph,
            scale,
            &text,
            [0.3; 3],
            None,
        );
        v += y_step;
    }
    let mut v = 0.0;
    while v <= x_top * (1.0 + 1e-9) {
        canvas.flat_line([sx(v), top], [sx(v), bottom], line * 0.6, [0.88; 3]);
        centred_tick_label(&mut canvas, sx(v), bottom + 0.6 * glyph, scale, v);
        v += x_step;
    }
    canvas.flat_line([left, bottom], [right, bottom], line, [0.2; 3]);
    canvas.flat_line([left, top], [left, bottom], line, [0.2; 3]);

    // Names.
    let title_w = (font::text_width(&chart.title) * scale) as f64;
    canvas.text(
        0.5 * (left + right - title_w),
        0.03 * h as f64,
        scale,
        &chart.title,
        [0.1; 3],
        None,
    );
    let x_w = (font::text_width(&chart.x_label) * scale) as f64;
    canvas.text(
        0.5 * (left + right - x_w),
        bottom + 2.2 * glyph,
        scale,
        &chart.x_label,
        [0.2; 3],
        None,
    );
    canvas.text(
        left - 0.5 * glyph,
        top - 2.0 * glyph,
        scale,
        &chart.y_label,
        [0.2; 3],
        None,
    );

    // Lines, markers, legend.
    for s in &chart.series {
        let color = s.color.map(|c| f32::from(c) / 255.0);
        for pair in s.points.windows(2) {
            canvas.flat_line(
                [sx(pair[0][0]), sy(pair[0][1])],
                [sx(pair[1][0]), sy(pair[1][1])],
                1.5 * line,
                color,
            );
        }
        let m = 2.5 * line;
        for p in &s.points {
            canvas.rect(
                sx(p[0]) - m,
                sy(p[1]) - m,
                sx(p[0]) + m,
                sy(p[1]) + m,
                color,
            );
        }
    }
    let mut y = top + glyph;
    for s in &chart.series {
        let color = s.color.map(|c| f32::from(c) / 255.0);
        canvas.rect(left + glyph, y, left + 2.5 * glyph, y + glyph, color);
        canvas.text(
            left + 3.2 * glyph,
            y,
            scale,
            &s.name,
            [0.15; 3],
            Some([1.0; 3]),
        );
        y += 1.6 * glyph;
    }

    let mut pixels = vec![[0u8; 3]; width as usize * height as usize];
    canvas.reduce_into(ss, &mut pixels, width as usize, 0, 0);
    Ok(Image {
        width,
        height,
        pixels,
    })
}
