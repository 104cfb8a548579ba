//! `view.html`: one self-contained page to turn the shape round, look at its loops and
//! ask what each is. No network at view time: the data (the surface, the
//! loops, the saddles, the barcode) is embedded as JSON, the surface's arrays as
//! base64 little-endian `Float32` / `Uint32`, every coordinate relative to the
//! surface's bounding-box centre (`offset`), and the WebGL code is our own
//! (`viewer.html`, no library). A surface above [`DISPLAY_TRIANGLES`] is decimated for
//! display (the `simplify` stage, which keeps its topology), and the page says so.
//!
//! Entry points: [`html_page`] (the page as a string) and [`write_html`].

use std::path::Path;

use serde_json::{json, Value};

use super::{HANDLE_COLOR, SADDLE_COLOR, TUNNEL_COLOR};
use crate::error::{Error, ErrorKind, Result};
use crate::mesh::{Side, SurfaceMesh};
use crate::pipeline::NeckReport;
use crate::simplify::{simplify, SimplifyOptions};

/// The most triangles the page draws; a denser surface is decimated toward this for
/// display (software WebGL in a headless browser, and laptops, stay interactive), as
/// far as the simplifier's default error bound (a thousandth of the diagonal) allows;
/// the page says how many it drew.
pub const DISPLAY_TRIANGLES: usize = 300_000;

/// The page's template: HTML, CSS and the viewer's JavaScript, with the data's place
/// marked.
const TEMPLATE: &str = include_str!("viewer.html");
const DATA_MARK: &str = "__NECKLACE_DATA__";

/// What the page shows of the surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HtmlSummary {
    /// Triangles drawn.
    pub shown_triangles: usize,
    /// Triangles of the surface.
    pub triangles: usize,
}

/// The page for `report`, whose loops lie on `surface`; `name` titles it (the mesh
/// file's name).
pub fn html_page(
    name: &str,
    surface: &SurfaceMesh,
    report: &NeckReport,
) -> Result<(String, HtmlSummary)> {
    let shown = display_surface(surface, DISPLAY_TRIANGLES)?;
    let summary = HtmlSummary {
        shown_triangles: shown.num_triangles(),
        triangles: surface.num_triangles(),
    };
    let data = page_data(name, surface, &shown, report);
    let text = serde_json::to_string(&data).map_err(|e| {
        Error::new(
            ErrorKind::Unsupported,
            format!("cannot encode the page's data: {e}"),
        )
    })?;
    // Inside <script>, "</" could close the element early.
    let text = text.replace("</", "<\\/");
    Ok((TEMPLATE.replacen(DATA_MARK, &text, 1), summary))
}

/// Write [`html_page`] to `path`.
pub fn write_html(
    path: &Path,
    name: &str,
    surface: &SurfaceMesh,
    report: &NeckReport,
) -> Result<HtmlSummary> {
    let (page, summary) = html_page(name, surface, report)?;
    crate::file::write_atomic(path, page.as_bytes())?;
    Ok(summary)
}

/// The surface as drawn: itself, or decimated to `budget` triangles.
fn display_surface(surface: &SurfaceMesh, budget: usize) -> Result<SurfaceMesh> {
    if surface.num_triangles() <= budget {
        return Ok(surface.clone());
    }
    let options = SimplifyOptions {
        target: budget,
        ..SimplifyOptions::default()
    };
    Ok(simplify(surface, &options)?.mesh)
}

fn color(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Everything the page reads (see `viewer.html`).
fn page_data(name: &str, surface: &SurfaceMesh, shown: &SurfaceMesh, report: &NeckReport) -> Value {
    let count = |kind: Side| report.loops.iter().filter(|l| l.kind == kind).count();
    let title = super::title(name, surface, count(Side::Inside), count(Side::Outside));
    let note = display_note(surface, shown);
    // Coordinates about the box's centre: single precision far from the origin would
    // round a small mesh's vertices visibly.
    let (lo, hi) = surface.bounding_box().unwrap_or(([0.0; 3], [0.0; 3]));
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let local = |p: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| p[k] - centre[k]) };
    let positions: Vec<f32> = shown
        .positions
        .iter()
        .flat_map(|&p| local(p))
        .map(|x| x as f32)
        .collect();
    let triangles: Vec<u32> = shown.triangles.iter().flatten().copied().collect();
    let loops: Vec<Value> = report
        .loops
        .iter()
        .enumerate()
        .map(|(i, l)| {
            json!({
                "index": i,
                "kind": Side::neck_name(l.kind),
                "role": l.role,
                "separating": l.separating,
                "length": l.length,
                "birth_scale": l.birth_scale,
                "death_scale": l.death_scale,
                "bulge": l.bulge,
                "center": local(l.center),
                "radius": l.radius,
                "saddle": local(l.saddle),
                "points": l.points.iter().flat_map(|&p| local(p)).collect::<Vec<_>>(),
            })
        })
        .collect();
    // Bars of every 2-saddle track; a neck's bar names its loop.
    let bars: Vec<Value> = report
        .sides
        .iter()
        .flat_map(|side| {
            side.bars
                .iter()
                .filter(|b| b.birth_scale > 0.0)
                .map(move |b| {
                    let neck = b.saddle.and_then(|saddle| {
                        report.loops.iter().position(|l| {
                            l.kind == side.side
                                && (l.seed == saddle || l.duplicates.contains(&saddle))
                        })
                    });
                    json!({
                        "side": Side::neck_name(side.side),
                        "birth": b.birth_scale,
                        "death": b.death_scale,
                        "loop": neck,
                    })
                })
        })
        .collect();
    json!({
        "title": title,
        "note": note,
        "mesh": {
            "positions": base64(&positions.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>()),
            "triangles": base64(&triangles.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>()),
        },
        "loops": loops,
        "saddles": report.loops.iter().map(|l| local(l.saddle)).collect::<Vec<_>>(),
        // What was subtracted from every coordinate above.
        "offset": centre,
        "bars": bars,
        "colors": {
            "handle": color(HANDLE_COLOR),
            "tunnel": color(TUNNEL_COLOR),
            "saddle": color(SADDLE_COLOR),
        },
    })
}

/// What the page says when it draws the surface decimated.
fn display_note(surface: &SurfaceMesh, shown: &SurfaceMesh) -> Option<String> {
    (shown.num_triangles() < surface.num_triangles()).then(|| {
        format!(
            "The surface is shown decimated for display: {} of its {} triangles (the loops are on the full surface).",
            shown.num_triangles(),
            surface.num_triangles()
        )
    })
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_surface_over_the_budget_is_drawn_decimated_and_the_page_says_so() {
        use crate::shapes::{Shape, ShapeKind};
        let surface = Shape::new(ShapeKind::Dumbbell).mesh().unwrap();
        assert!(surface.num_triangles() > 8000);
        // Down toward the budget, as far as the simplifier's error bound (a thousandth of
        // the diagonal: below a pixel) lets it go.
        let shown = display_surface(&surface, 4000).unwrap();
        assert!(
            shown.num_triangles() < surface.num_triangles() * 3 / 4,
            "{}",
            shown.num_triangles()
        );
        // Decimation keeps the shape's topology: still a sphere.
        let chi = shown.num_vertices() as i64 - 3 * shown.num_triangles() as i64 / 2
            + shown.num_triangles() as i64;
        assert_eq!(chi, 2);
        let note = display_note(&surface, &shown).unwrap();
        assert!(
            note.contains(&format!(
                "{} of its {}",
                shown.num_triangles(),
                surface.num_triangles()
            )),
            "{note}"
        );
        assert!(display_surface(&surface, 1_000_000).unwrap() == surface);
        assert!(display_note(&surface, &surface).is_none());
    }

    #[test]
    fn base64_matches_the_rfc_examples() {
        // RFC 4648, section 10.
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }

    #[test]
    fn the_template_has_one_place_for_the_data_and_loads_nothing() {
        assert_eq!(TEMPLATE.matches(DATA_MARK).count(), 1);
        for remote in [
            "src=\"http",
            "href=\"http",
            "src=\"//",
            "@import",
            "fetch(",
            "XMLHttpRequest",
            "<link",
        ] {
            assert!(
                !TEMPLATE.contains(remote),
                "the page must not load {remote}"
            );
        }
    }
}
