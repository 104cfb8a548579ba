//! Barcode pictures of the scale space: one horizontal bar per 2-saddle track,
//! from the scale it appeared at to the first it was gone, on a logarithmic scale axis;
//! the tracks selected as necks are drawn in colour, the rest in grey. One panel per
//! side (handles inside, tunnels outside), bars sorted by birth. Entry point:
//! [`barcode`].

use super::chart::{centred_tick_label, tick_text};
use super::raster::Canvas;
use super::{font, Image};
use crate::error::{Error, Result};

/// One bar: a track's scale interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarSpan {
    /// Scale (length) at which it appeared.
    pub birth: f64,
    /// First scale at which it was gone (`None`: alive at the largest scale).
    pub death: Option<f64>,
    /// Drawn in the panel's colour (a neck) rather than grey.
    pub highlight: bool,
}

/// One panel: a title, a colour for its highlighted bars, and the bars.
#[derive(Debug, Clone, PartialEq)]
pub struct BarPanel {
    /// Written above the panel.
    pub title: String,
    /// sRGB colour of the highlighted bars.
    pub color: [u8; 3],
    /// The bars.
    pub bars: Vec<BarSpan>,
}

/// Draw the panels stacked in a `width × height` picture, on one logarithmic axis
/// from the smallest birth to `max_scale` (bars alive at the end reach the right edge).
pub fn barcode(panels: &[BarPanel], max_scale: f64, width: u32, height: u32) -> Result<Image> {
    if !(200..=8192).contains(&width) || !(150..=8192).contains(&height) || panels.is_empty() {
        return Err(Error::invalid_argument(
            "a barcode needs a panel and at least 200 × 150 pixels",
        ));
    }
    let all = panels.iter().flat_map(|p| &p.bars);
    let bad = |x: f64| !(x.is_finite() && x > 0.0);
    if !(max_scale.is_finite() && max_scale > 0.0)
        || all
            .clone()
            .any(|b| bad(b.birth) || b.death.is_some_and(bad))
    {
        return Err(Error::invalid_argument(
            "barcode scales must be finite and positive",
        ));
    }
    let lo = all.map(|b| b.birth).fold(max_scale, f64::min);
    let hi = if max_scale > lo { max_scale } else { lo * 2.0 };

    let ss = 3usize;
    let (w, h) = (width as usize * ss, height as usize * ss);
    let mut canvas = Canvas::new(w, h, [1.0; 3]);
    let scale = ((width as f64 / 300.0).round().max(1.0) as usize) * ss;
    let glyph = (font::HEIGHT * scale) as f64;
    let (left, right) = (0.06 * w as f64, 0.96 * w as f64);
    let (top, bottom) = (0.04 * h as f64, h as f64 - 4.0 * glyph);
    let sx = |s: f64| left + (right - left) * (s / lo).ln() / (hi / lo).ln();
    let line = ss as f64;

    // The two ends, then ticks at 1, 2, 5 × 10^k clear of them, with a light grid.
    for (v, at) in [(lo, left), (hi, right)] {
        let text = tick_text(v);
        let tw = (font::text_width(&text) * scale) as f64;
        let x = if at == left { left } else { right - tw };
        canvas.text(x, bottom + 0.6 * glyph, scale, &text, [0.3; 3], None);
    }
    let clear = 0.1 * (right - left);
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in [1.0, 2.0, 5.0] {
            let v = m * decade;
            if v < lo || v > hi || sx(v) - left < clear || right - sx(v) < clear {
                continue;
            }
            canvas.flat_line([sx(v), top], [sx(v), bottom], line * 0.5, [0.9; 3]);
            centred_tick_label(&mut canvas, sx(v), bottom + 0.6 * glyph, scale, v);
        }
        decade *= 10.0;
    }
    let label = "scale (length, log axis)";
    let lw = (font::text_width(label) * scale) as f64;
    canvas.text(
        0.5 * (left + right - lw),
        bottom + 2.2 * glyph,
        scale,
        label,
        [0.2; 3],
        None,
    );

    // Panels share the height in proportion to their bars (with room for a title).
    let rows: usize = panels.iter().map(|p| p.bars.len().max(1)).sum();
    let titles = panels.len() as f64 * 2.0 * glyph;
    let per_row = ((bottom - top - titles) / rows as f64).max(0.0);
    let mut y = top;
    for panel in panels {
        canvas.text(left, y + 0.3 * glyph, scale, &panel.title, [0.1; 3], None);
        y += 2.0 * glyph;
        let color = panel.color.map(|c| f32::from(c) / 255.0);
        let mut bars = panel.bars.clone();
        bars.sort_by(|a, b| a.birth.total_cmp(&b.birth));
        let thickness = (0.7 * per_row).max(1.0);
        for b in &bars {
            let end = b.death.map_or(right, |d| sx(d.min(hi)));
            let c = if b.highlight { color } else { [0.72; 3] };
            canvas.rect(
                sx(b.birth),
                y,
                end.max(sx(b.birth) + line),
                y + thickness,
                c,
            );
            y += per_row;
        }
        if bars.is_empty() {
            y += per_row;
        }
        canvas.flat_line(
            [left, y + 0.2 * per_row],
            [right, y + 0.2 * per_row],
            line * 0.5,
            [0.6; 3],
        );
    }

    let mut pixels = vec![[0u8; 3]; width as usize * height as usize];
    canvas.reduce_into(ss, &mut pixels, width as usize, 0, 0);
    Ok(Image {
        width,
        height,
        pixels,
    })
}
