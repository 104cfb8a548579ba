//! Pictures without a display: a software rasterizer that draws a surface with curves
//! (neck loops) and dots (saddles) from several directions into one PNG, and line charts
//! for benchmarks ([`chart`]). Not part of the paper's method; it draws its figures.
//!
//! What a picture shows: a title band (when the scene has a title), the surface shaded
//! (Lambert with a key and a fill light fixed to the camera, a little ambient and
//! specular, outlines where the depth jumps), curves as shaded tubes of constant screen
//! width with a label (the loop's index) beside each, placed so that no two labels, the
//! legend and the view's name overlap ([`labels`]), dots as small balls, and a legend
//! of lines and dots. Overlay hidden behind the surface shows through at `1 − opacity`, so
//! the back half of a loop and the saddles inside the solid stay visible. Each view is an
//! orthographic projection framed to the scene's bounding box; views are laid out in a
//! grid (1, 2 or 3 in a row, 4 as 2 × 2). Everything is drawn at `supersample` times the
//! resolution and box-filtered down, which anti-aliases edges, lines and text.
//!
//! Parts: `raster` (the supersampled canvas: a z-buffered surface shaded from its
//! interpolated corner normals, an overlay of tubes and dots with its own depth,
//! compositing, outlines, text), `font` (a 5 × 7 bitmap), [`labels`] (greedy placement:
//! beside the curve, clear of the other labels, the legend and the view's name, else on
//! rings with a leader line), [`chart`], and [`barcode`] (the scale space's barcodes).
//! PNG through the `png` crate, which no other module names.
//!
//! Conventions: world coordinates are the mesh's; pixel x to the right, y down; colours
//! are sRGB bytes. Entry point: [`render`] → [`Rendered`] (the [`Image`] and, per tile,
//! its [`Projection`], so callers can find where a world point landed);
//! [`Image::write_png`] encodes it.

pub mod barcode;
pub mod chart;
mod font;
pub mod labels;
mod raster;

use std::path::Path;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;
use labels::{label_anchors, place_labels, LabelRequest};
use raster::{Canvas, Rgb};

/// A direction to look from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum View {
    /// From (1, 0.8, 1.3): the one-view default.
    ThreeQuarter,
    /// From +z, y up.
    Front,
    /// From +x, y up.
    Side,
    /// From +y, −z up.
    Top,
}

impl View {
    /// The views in the order `--views N` takes them.
    pub const ALL: [View; 4] = [View::ThreeQuarter, View::Front, View::Side, View::Top];

    /// Unit vectors (forward into the scene, screen up).
    fn axes(self) -> ([f64; 3], [f64; 3]) {
        match self {
            View::ThreeQuarter => {
                let eye: [f64; 3] = [1.0, 0.8, 1.3];
                let n = (eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2]).sqrt();
                ([-eye[0] / n, -eye[1] / n, -eye[2] / n], [0.0, 1.0, 0.0])
            }
            View::Front => ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            View::Side => ([-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            View::Top => ([0.0, -1.0, 0.0], [0.0, 0.0, -1.0]),
        }
    }

    /// Upper-case name, as written in the picture.
    pub fn name(self) -> &'static str {
        match self {
            View::ThreeQuarter => "THREE-QUARTER",
            View::Front => "FRONT",
            View::Side => "SIDE",
            View::Top => "TOP",
        }
    }
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot3(a, a).sqrt();
    if n > 0.0 {
        a.map(|v| v / n)
    } else {
        a
    }
}

/// An orthographic camera framed to a box: world point → tile pixel (x right, y down)
/// and depth (world units, growing away from the viewer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Screen right, screen up and forward (into the scene), unit vectors.
    pub right: [f64; 3],
    /// Screen up.
    pub up: [f64; 3],
    /// Viewing direction.
    pub forward: [f64; 3],
    /// The world point drawn at the tile's centre.
    pub center: [f64; 3],
    /// Pixels per world unit.
    pub scale: f64,
    /// Tile side in pixels.
    pub size: f64,
}

impl Projection {
    /// Frame the box `[lo, hi]` in a square tile of `size` pixels seen from `view`,
    /// leaving `margin` (a fraction of the tile) free on every side.
    pub fn framed(view: View, lo: [f64; 3], hi: [f64; 3], size: f64, margin: f64) -> Projection {
        let (forward, up_hint) = view.axes();
        let right = normalize(cross3(forward, up_hint));
        let up = cross3(right, forward);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for corner in 0..8 {
            let p = [0, 1, 2].map(|k| if corner >> k & 1 == 1 { hi[k] } else { lo[k] });
            let (x, y) = (dot3(p, right), dot3(p, up));
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        let extent = (x1 - x0).max(y1 - y0).max(1e-12);
        let mid = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        // Shift the centre within the view plane to the middle of the projected box.
        let along = dot3(mid, forward);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let center = [0, 1, 2].map(|k| cx * right[k] + cy * up[k] + along * forward[k]);
        Projection {
            right,
            up,
            forward,
            center,
            scale: size * (1.0 - 2.0 * margin) / extent,
            size,
        }
    }

    /// Tile pixel x, y and depth of a world point.
    pub fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let d = [
            p[0] - self.center[0],
            p[1] - self.center[1],
            p[2] - self.center[2],
        ];
        [
            0.5 * self.size + self.scale * dot3(d, self.right),
            0.5 * self.size - self.scale * dot3(d, self.up),
            dot3(d, self.forward),
        ]
    }

    /// A world direction in camera coordinates (x right, y up, z toward the viewer).
    fn camera_direction(&self, n: [f64; 3]) -> [f64; 3] {
        [
            dot3(n, self.right),
            dot3(n, self.up),
            -dot3(n, self.forward),
        ]
    }
}

/// A polyline to draw over the surface (a neck loop).
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Its points in world coordinates.
    pub points: Vec<[f64; 3]>,
    /// Whether the last point joins the first.
    pub closed: bool,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Text written beside it (its index), if any.
    pub label: Option<String>,
}

/// A point to draw as a small ball (a saddle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dot {
    /// World position.
    pub position: [f64; 3],
    /// sRGB colour.
    pub color: [u8; 3],
}

/// What to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene<'a> {
    /// The surface.
    pub mesh: &'a SurfaceMesh,
    /// Curves over it.
    pub curves: Vec<Curve>,
    /// Dots.
    pub dots: Vec<Dot>,
    /// Legend entries, drawn in the lower left corner of the picture.
    pub legend: Vec<LegendEntry>,
    /// A line of text across the top of the picture (the mesh and its counts), if any.
    pub title: Option<String>,
}

/// One line of the legend: a mark in a colour and what it stands for.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendEntry {
    /// What the mark stands for.
    pub text: String,
    /// sRGB colour.
    pub color: [u8; 3],
    /// How it is drawn: as a curve or as a dot.
    pub mark: Mark,
}

/// The shape of a legend mark.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// A short bar, like a curve.
    Line,
    /// A disc, like a dot.
    Dot,
}

/// How to draw it.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels; the height follows from the layout. Default 1200.
    pub size: u32,
    /// Number of views, 1 to 4 (three-quarter, front, side, top in that order). Default 4.
    pub views: usize,
    /// Opacity of the surface over curves and dots behind it, 0 to 1: 1 hides them,
    /// 0 draws them as if in front. Default 0.7.
    pub opacity: f64,
    /// Samples per pixel along each axis (anti-aliasing). Default 3.
    pub supersample: u32,
    /// Curve width as a fraction of a tile's side. Default 0.009.
    pub line_width: f64,
    /// Dot diameter as a fraction of a tile's side. Default 0.02.
    pub dot_size: f64,
    /// Surface colour (sRGB). Default a light warm grey.
    pub surface_color: [u8; 3],
    /// Background colour (sRGB). Default white.
    pub background: [u8; 3],
    /// Whether to write each tile's view name. Default true.
    pub view_names: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            size: 1200,
            views: 4,
            opacity: 0.7,
            supersample: 3,
            line_width: 0.009,
            dot_size: 0.02,
            surface_color: [206, 204, 198],
            background: [255, 255, 255],
            view_names: true,
        }
    }
}

/// An RGB picture.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels, top row first.
    pub pixels: Vec<[u8; 3]>,
}

impl Image {
    /// The pixel at (`x`, `y`), if inside.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        (x < self.width && y < self.height).then(|| self.pixels[(y * self.width + x) as usize])
    }

    /// PNG bytes (8-bit RGB).
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            let fail = |e: png::EncodingError| {
                Error::new(ErrorKind::Internal, format!("cannot encode PNG: {e}"))
            };
            let mut writer = encoder.write_header().map_err(fail)?;
            writer
                .write_image_data(self.pixels.as_flattened())
                .map_err(fail)?;
        }
        Ok(bytes)
    }

    /// This picture with `right` beside it, the shorter one padded below with
    /// `background`.
    pub fn beside(&self, right: &Image, background: [u8; 3]) -> Image {
        let (width, height) = (self.width + right.width, self.height.max(right.height));
        let mut pixels = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for (image, w) in [(self, self.width), (right, right.width)] {
                pixels.extend((0..w).map(|x| image.pixel(x, y).unwrap_or(background)));
            }
        }
        Image {
            width,
            height,
            pixels,
        }
    }

    /// Write as a PNG file; errors name the file.
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        check_png_name(path)?;
        let bytes = self.encode_png().map_err(|e| e.in_file(path))?;
        crate::file::write_atomic(path, &bytes)
    }

    /// Read an 8-bit RGB or RGBA PNG (for checking pictures in tests).
    pub fn read_png(path: impl AsRef<Path>) -> Result<Image> {
        let path = path.as_ref();
        let fail = |m: String| Error::new(ErrorKind::Syntax, m).in_file(path);
        let file = std::fs::File::open(path)
            .map_err(|e| Error::new(ErrorKind::Io, format!("cannot read: {e}")).in_file(path))?;
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .map_err(|e| fail(format!("not a PNG: {e}")))?;
        let mut data = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader
            .next_frame(&mut data)
            .map_err(|e| fail(format!("bad PNG: {e}")))?;
        let channels = match (info.color_type, info.bit_depth) {
            (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
            (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
            _ => return Err(fail("only 8-bit RGB or RGBA PNG is read".into())),
        };
        let pixels = data[..info.buffer_size()]
            .chunks_exact(channels)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        Ok(Image {
            width: info.width,
            height: info.height,
            pixels,
        })
    }
}

/// One view's place in the picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Tile {
    /// Which view.
    pub view: View,
    /// Left and top pixel of the tile in the image.
    pub origin: [u32; 2],
    /// Its camera (pixels relative to `origin`).
    pub projection: Projection,
}

/// A rendered picture and where each view went.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The picture.
    pub image: Image,
    /// The views, in drawing order.
    pub tiles: Vec<Tile>,
}

impl Rendered {
    /// Image pixel (x, y) of a world point in tile `tile`.
    pub fn pixel_of(&self, tile: usize, p: [f64; 3]) -> [f64; 2] {
        let t = &self.tiles[tile];
        let q = t.projection.project(p);
        [q[0] + f64::from(t.origin[0]), q[1] + f64::from(t.origin[1])]
    }
}

/// Columns and rows of the grid for `views` views.
fn layout(views: usize) -> (usize, usize) {
    match views {
        4 => (2, 2),
        n => (n, 1),
    }
}

fn check(scene: &Scene, options: &RenderOptions) -> Result<()> {
    let bad = |m: &str| Err(Error::invalid_argument(m.to_string()));
    if !(1..=4).contains(&options.views) {
        return bad("views must be 1 to 4");
    }
    if !(64..=8192).contains(&options.size) {
        return bad("size must be 64 to 8192 pixels");
    }
    if !(1..=4).contains(&options.supersample) {
        return bad("supersample must be 1 to 4");
    }
    if !(0.0..=1.0).contains(&options.opacity) {
        return bad("opacity must be between 0 and 1");
    }
    if !(options.line_width > 0.0
        && options.line_width < 0.2
        && options.dot_size > 0.0
        && options.dot_size < 0.2)
    {
        return bad("line width and dot size must be between 0 and 0.2 of a view");
    }
    let finite = |p: &[f64; 3]| p.iter().all(|v| v.is_finite());
    if scene.mesh.triangles.is_empty() {
        return bad("nothing to draw: the mesh has no triangles");
    }
    if !scene.mesh.positions.iter().all(finite)
        || !scene.curves.iter().flat_map(|c| &c.points).all(finite)
        || !scene.dots.iter().all(|d| finite(&d.position))
    {
        return bad("scene has non-finite coordinates");
    }
    Ok(())
}

/// Area-weighted vertex normals.
fn vertex_normals(mesh: &SurfaceMesh) -> Vec<[f64; 3]> {
    let mut normals = vec![[0.0; 3]; mesh.positions.len()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        let n = mesh.face_normal_scaled(f);
        for &v in t {
            for k in 0..3 {
                normals[v as usize][k] += n[k];
            }
        }
    }
    normals.into_iter().map(normalize).collect()
}

fn rgb(c: [u8; 3]) -> Rgb {
    c.map(|v| f32::from(v) / 255.0)
}

/// A key and a fill light fixed to the camera (camera coordinates, unit vectors), and
/// the key's half vector toward the viewer.
struct Lights {
    key: [f64; 3],
    fill: [f64; 3],
    half: [f64; 3],
}

impl Lights {
    fn new() -> Lights {
        let key = normalize([-0.45, 0.55, 0.7]);
        Lights {
            key,
            fill: normalize([0.6, -0.25, 0.75]),
            half: normalize([key[0], key[1], key[2] + 1.0]),
        }
    }

    /// Lambert from both lights, ambient and a little specular; two-sided (a normal
    /// facing away is turned round).
    fn shade(&self, n: [f64; 3], base: Rgb) -> Rgb {
        let mut n = normalize(n);
        if n[2] < 0.0 {
            n = n.map(|v| -v);
        }
        let diffuse = 0.24 + 0.62 * dot3(n, self.key).max(0.0) + 0.2 * dot3(n, self.fill).max(0.0);
        let specular = 0.16 * dot3(n, self.half).max(0.0).powi(40);
        base.map(|c| (c * diffuse as f32 + specular as f32).min(1.0))
    }
}

/// The bounding box of everything drawn.
fn scene_bounds(scene: &Scene) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    let points = scene
        .mesh
        .positions
        .iter()
        .chain(scene.curves.iter().flat_map(|c| &c.points))
        .chain(scene.dots.iter().map(|d| &d.position));
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Draw `scene` as `options` say.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<Rendered> {
    check(scene, options)?;
    let (cols, rows) = layout(options.views);
    let tile = options.size as usize / cols;
    let title_scale = text_scale(tile as f64);
    let band = if scene.title.is_some() {
        (2.2 * (font::HEIGHT * title_scale) as f64).ceil() as usize
    } else {
        0
    };
    let (width, height) = (tile * cols, tile * rows + band);
    let (lo, hi) = scene_bounds(scene);
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let normals = vertex_normals(scene.mesh);
    let mut tiles: Vec<Tile> = View::ALL[..options.views]
        .iter()
        .enumerate()
        .map(|(i, &view)| Tile {
            view,
            origin: [
                ((i % cols) * tile) as u32,
                ((i / cols) * tile + band) as u32,
            ],
            projection: Projection::framed(view, lo, hi, tile as f64, 0.07),
        })
        .collect();
    // One scale for all views, so sizes compare across them.
    let common = tiles
        .iter()
        .map(|t| t.projection.scale)
        .fold(f64::INFINITY, f64::min);
    for t in &mut tiles {
        t.projection.scale = common;
    }
    // The legend goes in the lower left tile.
    let legend_tile = (rows - 1) * cols;
    let canvases: Vec<Canvas> = tiles
        .par_iter()
        .enumerate()
        .map(|(i, t)| draw_view(scene, options, &normals, t, diagonal, i == legend_tile))
        .collect();
    let mut pixels = vec![[0u8; 3]; width * height];
    let ss = options.supersample as usize;
    if let Some(title) = &scene.title {
        let mut canvas = Canvas::new(width * ss, band * ss, rgb(options.background));
        let pad = 0.6 * (font::HEIGHT * title_scale * ss) as f64;
        canvas.text(pad, pad, title_scale * ss, title, [0.15; 3], None);
        canvas.reduce_into(ss, &mut pixels, width, 0, 0);
    }
    for (canvas, t) in canvases.iter().zip(&tiles) {
        canvas.reduce_into(
            ss,
            &mut pixels,
            width,
            t.origin[0] as usize,
            t.origin[1] as usize,
        );
    }
    Ok(Rendered {
        image: Image {
            width: width as u32,
            height: height as u32,
            pixels,
        },
        tiles,
    })
}

/// One tile at supersampled resolution.
fn draw_view(
    scene: &Scene,
    options: &RenderOptions,
    normals: &[[f64; 3]],
    tile: &Tile,
    diagonal: f64,
    legend: bool,
) -> Canvas {
    let projection = &tile.projection;
    let ss = f64::from(options.supersample);
    let size = (projection.size * ss) as usize;
    let mut canvas = Canvas::new(size, size, rgb(options.background));
    let to_canvas = |p: [f64; 3]| {
        let q = projection.project(p);
        [q[0] * ss, q[1] * ss, q[2]]
    };

    // Surface.
    let screen: Vec<[f64; 3]> = scene.mesh.positions.iter().map(|&p| to_canvas(p)).collect();
    let camera_normals: Vec<[f64; 3]> = normals
        .iter()
        .map(|&n| projection.camera_direction(n))
        .collect();
    let base = rgb(options.surface_color);
    let lights = Lights::new();
    for t in &scene.mesh.triangles {
        let [a, b, c] = t.map(|v| v as usize);
        canvas.triangle(
            [screen[a], screen[b], screen[c]],
            [camera_normals[a], camera_normals[b], camera_normals[c]],
            |n| lights.shade(n, base),
        );
    }
    let reach = options.supersample as usize;
    canvas.outline(reach, (0.03 * diagonal) as f32, [0.25, 0.25, 0.25], 0.75);

    // Curves and dots.
    let half_width = 0.5 * options.line_width * projection.size * ss;
    for curve in &scene.curves {
        let points: Vec<[f64; 3]> = curve.points.iter().map(|&p| to_canvas(p)).collect();
        let n = points.len();
        let segments = if curve.closed { n } else { n.saturating_sub(1) };
        for i in 0..segments {
            canvas.segment(points[i], points[(i + 1) % n], half_width, rgb(curve.color));
        }
        if n == 1 {
            canvas.segment(points[0], points[0], half_width, rgb(curve.color));
        }
    }
    let radius = 0.5 * options.dot_size * projection.size * ss;
    for d in &scene.dots {
        canvas.dot(to_canvas(d.position), radius, rgb(d.color));
    }
    canvas.composite(options.opacity as f32, (0.02 * diagonal) as f32);

    // Text: view name, legend, then the labels round them.
    let text_scale = text_scale(projection.size) * options.supersample as usize;
    let glyph_h = (font::HEIGHT * text_scale) as f64;
    let text_w = |text: &str, scale: usize| (font::text_width(text) * scale) as f64;
    let pad = 0.025 * size as f64;
    let mut taken = Vec::new();
    if options.view_names {
        let small = (text_scale * 2 / 3).max(1);
        canvas.text(pad, pad, small, tile.view.name(), [0.45; 3], None);
        let h = (font::HEIGHT * small) as f64;
        taken.push([pad, pad, pad + text_w(tile.view.name(), small), pad + h]);
    }
    if legend && !scene.legend.is_empty() {
        let line = glyph_h * 1.6;
        let top = size as f64 - pad - line * scene.legend.len() as f64;
        let mut y = top;
        let mut right = pad;
        for entry in &scene.legend {
            let color = rgb(entry.color);
            match entry.mark {
                Mark::Line => canvas.rect(pad, y, pad + 2.0 * glyph_h, y + glyph_h, color),
                Mark::Dot => {
                    let centre = [pad + glyph_h, y + 0.5 * glyph_h];
                    canvas.flat_line(centre, centre, 0.5 * glyph_h, color);
                }
            }
            let x = pad + 2.6 * glyph_h;
            canvas.text(x, y, text_scale, &entry.text, [0.2; 3], None);
            right = right.max(x + text_w(&entry.text, text_scale));
            y += line;
        }
        taken.push([pad, top, right, y]);
    }
    let labelled: Vec<(&Curve, &String)> = scene
        .curves
        .iter()
        .filter_map(|c| c.label.as_ref().map(|l| (c, l)))
        .collect();
    let requests: Vec<LabelRequest> = labelled
        .iter()
        .map(|(curve, label)| LabelRequest {
            size: [text_w(label, text_scale), glyph_h],
            anchors: label_anchors(&curve.points, &to_canvas),
        })
        .collect();
    let bounds = [0.0, 0.0, size as f64, size as f64];
    let margin = (font::ADVANCE * text_scale) as f64;
    let placements = place_labels(&requests, &taken, bounds, 2.0 * half_width, margin);
    let white = Some([1.0; 3]);
    for ((curve, label), placement) in labelled.iter().zip(&placements) {
        let dark = rgb(curve.color).map(|c| c * 0.7);
        let [x0, y0, x1, y1] = placement.rect;
        if let Some(anchor) = placement.leader {
            let from = [anchor[0].clamp(x0, x1), anchor[1].clamp(y0, y1)];
            canvas.flat_line(from, anchor, 0.35 * half_width, dark);
        }
        canvas.text(x0, y0, text_scale, label, dark, white);
    }
    canvas
}

/// Font pixels per character pixel for a view `side` pixels wide (before supersampling).
fn text_scale(side: f64) -> usize {
    (side / 220.0).round().max(1.0) as usize
}

/// A picture is written as PNG only: refuse another extension (PNG bytes in a `.jpg`
/// would open nowhere).
pub fn check_png_name(path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() == Some("png") {
        Ok(())
    } else {
        Err(Error::new(
            ErrorKind::UnknownFormat,
            "pictures are written as PNG only: use a .png file name",
        )
        .in_file(path))
    }
}
