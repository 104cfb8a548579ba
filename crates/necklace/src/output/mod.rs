//! The files a run writes, for the viewers people already have, and the picture of it.
//! Like [`pipeline`](crate::pipeline), this module composes others (it reads the
//! pipeline's [`NeckReport`] and draws with [`render`]); no stage
//! imports it.
//!
//! A run's folder ([`write_run`]):
//! - `loops.obj`: each loop a closed `l` polyline, named `handle_3` / `tunnel_5` after its
//!   kind and index (Blender, MeshLab, any OBJ reader);
//! - `loops.ply`: the same loops as PLY vertices and bare edges, each vertex carrying
//!   `loop` (its loop's index) and its kind's colour (trimesh, MeshLab, CloudCompare);
//! - `loops.vtp`: the loops as VTK polylines with cell data `loop` and `kind` (0
//!   handle, 1 tunnel; ParaView, pyvista); `loops.vtu`: the same as 2-point line cells
//!   (meshio, which reads no `.vtp`);
//! - `membranes.ply`: a disk each loop bounds (see `NeckLoop::membrane`), one component
//!   per loop, each face carrying `loop` (the loop's index);
//! - `loops.json`: the whole report with a `version` field (schema: `docs/output.md`);
//! - `critical.ply`: every critical point at the last smoothing step of each side, with
//!   `type`, `selected`, `persistence`, `side` and colours (see
//!   [`critical_point_cloud`]);
//! - `view.html` (with `html`): the interactive page ([`html_page`]: the surface, the
//!   loops and saddles in WebGL, a table of the loops, the barcode, a scale slider; one
//!   self-contained page, the data as JSON with base64 arrays, our own viewer
//!   `viewer.html`; a surface above [`DISPLAY_TRIANGLES`] decimated through `simplify`);
//! - `view.png` with a picture, and beside it `barcode.png`: one bar per 2-saddle track
//!   of each side over scale, the necks in their kind's colour; `field.vtu` (volume meshes of both sides with the
//!   smoothed field and the side per vertex, for ParaView) with the volume kept.
//!
//! A repair (`necklace repair --png`): [`repair_picture`], the input and the output
//! side by side with the removed loops.
//!
//! A segmentation (`necklace segment`): [`write_segmentation`] (the surface cut along
//! the loops as PLY, each face carrying `segment`) and [`segments_json`].
//!
//! Units: the input mesh's; coordinates in its frame. Entry points: [`write_run`],
//! [`report_json`] and back [`read_report_json`] / [`report_from_json`] (the report types
//! derive `Deserialize`), [`read_run_json`] (for `necklace view`), [`loop_scene`],
//! [`read_loops_json`] and [`read_points_json`] (for `necklace render`).

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

mod html;

pub use html::{html_page, write_html, HtmlSummary, DISPLAY_TRIANGLES};

use crate::error::{Error, ErrorKind, Result};
use crate::io;
use crate::mesh::{Side, SurfaceMesh};
use crate::morse::VertexType;
use crate::pipeline::{NeckReport, RepairReport, TrackedPoint};
use crate::render::{self, Curve, Dot, LegendEntry, Mark, RenderOptions, Scene};
use crate::segment::Segmentation;
use crate::tet::TetMesh;

/// The version of the JSON written by [`report_json`]; raised when a field changes
/// meaning or disappears (new fields do not raise it).
pub const JSON_VERSION: u64 = 2;

/// Colour of handle loops in pictures and PLY files (vermilion).
pub const HANDLE_COLOR: [u8; 3] = [213, 62, 30];
/// Colour of tunnel loops (blue).
pub const TUNNEL_COLOR: [u8; 3] = [30, 100, 200];
/// Colour of saddle dots (gold).
pub const SADDLE_COLOR: [u8; 3] = [245, 190, 20];

/// The colour of a loop kind.
pub fn kind_color(kind: Side) -> [u8; 3] {
    match kind {
        Side::Inside => HANDLE_COLOR,
        Side::Outside => TUNNEL_COLOR,
    }
}

/// What [`write_run`] writes besides the loops and critical points.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OutputOptions {
    /// Draw `view.png` with these options. Default none.
    pub picture: Option<RenderOptions>,
    /// Write `field.vtu` (needs a report made with `keep_volume`). Default false.
    pub volume: bool,
    /// Write `view.html`, the interactive page ([`html_page`]). Default false.
    pub html: bool,
}

/// The report as JSON: `version`, `input` (the file, when given), `units`, then every
/// field of [`NeckReport`].
pub fn report_json(report: &NeckReport, input: Option<&Path>) -> Result<Value> {
    let fields = serde_json::to_value(report).map_err(|e| {
        Error::new(
            ErrorKind::Unsupported,
            format!("cannot encode the report: {e}"),
        )
    })?;
    let mut out = json!({
        "version": JSON_VERSION,
        "input": input.map(|p| p.display().to_string()),
        "units": "input mesh units; coordinates in the input mesh's frame",
    });
    if let (Some(out), Value::Object(fields)) = (out.as_object_mut(), fields) {
        out.extend(fields);
    }
    Ok(out)
}

/// Read a report back from the JSON of [`report_json`] (a `loops.json`). Fields the
/// JSON leaves out (the surface, membranes, critical points, volume fields) are empty.
pub fn report_from_json(value: Value) -> Result<NeckReport> {
    serde_json::from_value(value)
        .map_err(|e| Error::new(ErrorKind::Syntax, format!("not a necklace report: {e}")))
}

/// [`report_from_json`] of a file.
pub fn read_report_json(path: impl AsRef<Path>) -> Result<NeckReport> {
    let path = path.as_ref();
    report_from_json(read_json(path)?).map_err(|e| e.in_file(path))
}

/// A run's `loops.json` read back: the report, and the mesh file it names (`input`),
/// if any.
pub fn read_run_json(path: impl AsRef<Path>) -> Result<(NeckReport, Option<PathBuf>)> {
    let path = path.as_ref();
    let value = read_json(path)?;
    let input = value
        .get("input")
        .and_then(Value::as_str)
        .map(PathBuf::from);
    let report = report_from_json(value).map_err(|e| e.in_file(path))?;
    Ok((report, input))
}

/// A loop as drawn: its kind and points.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopCurve {
    /// Handle or tunnel.
    pub kind: Side,
    /// The closed polyline (last point joins the first).
    pub points: Vec<[f64; 3]>,
}

/// The loops of a report, in its order.
pub fn loop_curves(report: &NeckReport) -> Vec<LoopCurve> {
    report
        .loops
        .iter()
        .map(|l| LoopCurve {
            kind: l.kind,
            points: l.points.clone(),
        })
        .collect()
}

/// The membranes of all loops as one mesh, one component per loop, and the index of
/// each face's loop.
pub fn membranes(report: &NeckReport) -> (SurfaceMesh, Vec<i32>) {
    let mut mesh = SurfaceMesh {
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    let mut labels = Vec::new();
    for (i, l) in report.loops.iter().enumerate() {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend_from_slice(&l.membrane.positions);
        mesh.triangles
            .extend(l.membrane.triangles.iter().map(|t| t.map(|v| v + base)));
        labels.extend(std::iter::repeat_n(i as i32, l.membrane.triangles.len()));
    }
    (mesh, labels)
}

/// How far outside the surface's bounding box a loop read from a file may reach, as a
/// fraction of the box's diagonal (see [`check_overlay`]).
pub const LOOP_SLACK: f64 = 0.01;

/// Check that loops and saddles read from files belong to `surface`: every loop has at
/// least three points and lies in the surface's bounding box (a neck loop lies on the
/// surface; up to [`LOOP_SLACK`] of the diagonal is let through for a loop written to
/// a few digits, or found on a copy of the surface), and every saddle within one
/// bounding-box diagonal of the box (a tunnel's saddle is off the surface; farther,
/// the picture would frame the stray points and the surface would shrink to a dot).
/// Either way, most likely the file of another mesh.
pub fn check_overlay(
    surface: &SurfaceMesh,
    loops: &[LoopCurve],
    saddles: &[[f64; 3]],
) -> Result<()> {
    let (lo, hi) = surface
        .bounding_box()
        .ok_or_else(|| Error::new(ErrorKind::InvalidMesh, "the surface has no vertices"))?;
    let diagonal = surface.bbox_diagonal();
    let away = |p: &[f64; 3]| {
        let d: f64 = (0..3)
            .map(|k| (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0).powi(2))
            .sum::<f64>()
            .sqrt();
        d / diagonal.max(f64::MIN_POSITIVE)
    };
    for (i, l) in loops.iter().enumerate() {
        if l.points.len() < 3 {
            return Err(Error::invalid_argument(format!(
                "loop {i} has {} points: a closed loop needs at least 3",
                l.points.len()
            )));
        }
        let far = l.points.iter().map(away).fold(0.0, f64::max);
        if far > LOOP_SLACK {
            return Err(Error::invalid_argument(format!(
                "loop {i} reaches {:.3} % of the diagonal outside the mesh's bounding box (at most {} % is let through): are these the loops of another mesh?",
                100.0 * far,
                100.0 * LOOP_SLACK
            )));
        }
    }
    if let Some((i, far)) = saddles
        .iter()
        .map(away)
        .enumerate()
        .find(|&(_, far)| far > 1.0)
    {
        return Err(Error::invalid_argument(format!(
            "saddle {i} lies {far:.3e} bounding-box diagonals outside the mesh: are these the saddles of another mesh?"
        )));
    }
    Ok(())
}

/// The picture's scene: the surface, each loop in its kind's colour labelled by its
/// index, `saddles` as dots, a legend of the kinds present (and of the dots), and a
/// title: `name` (the mesh file's name), the surface's counts and the loops'.
pub fn loop_scene<'a>(
    name: &str,
    surface: &'a SurfaceMesh,
    loops: &[LoopCurve],
    saddles: &[[f64; 3]],
) -> Scene<'a> {
    let mut legend = Vec::new();
    let count = |kind: Side| loops.iter().filter(|l| l.kind == kind).count();
    for kind in [Side::Inside, Side::Outside] {
        if count(kind) > 0 {
            legend.push(LegendEntry {
                text: format!("{} loop", Side::neck_name(kind)),
                color: kind_color(kind),
                mark: Mark::Line,
            });
        }
    }
    if !saddles.is_empty() {
        legend.push(LegendEntry {
            text: "saddle (the centre of a neck)".to_string(),
            color: SADDLE_COLOR,
            mark: Mark::Dot,
        });
    }
    let title = title(name, surface, count(Side::Inside), count(Side::Outside));
    Scene {
        title: Some(title),
        mesh: surface,
        curves: loops
            .iter()
            .enumerate()
            .map(|(i, l)| Curve {
                points: l.points.clone(),
                closed: true,
                color: kind_color(l.kind),
                label: Some(i.to_string()),
            })
            .collect(),
        dots: saddles
            .iter()
            .map(|&position| Dot {
                position,
                color: SADDLE_COLOR,
            })
            .collect(),
        legend,
    }
}

/// `necklace repair`'s picture: the input (left) and the output (right), each with
/// the removed loops in their kind's colour, labelled by operation; `options.size` is
/// each half's width.
pub fn repair_picture(
    name: &str,
    input: &SurfaceMesh,
    output: &SurfaceMesh,
    report: &RepairReport,
    options: &RenderOptions,
) -> Result<render::Image> {
    let curves: Vec<LoopCurve> = report
        .operations
        .iter()
        .map(|op| LoopCurve {
            kind: op.neck.kind,
            points: op.points.clone(),
        })
        .collect();
    let mut halves = Vec::new();
    for (surface, when, genus) in [
        (input, "before", report.genus[0]),
        (output, "after", report.genus[1]),
    ] {
        let mut scene = loop_scene(name, surface, &curves, &[]);
        scene.title = Some(format!("{name} {when}: genus {genus}"));
        halves.push(render::render(&scene, options)?.image);
    }
    Ok(halves[0].beside(&halves[1], options.background))
}

/// Write a segmentation as binary PLY: the refined surface (the loops are edges of it),
/// each face carrying `segment` (its segment's id).
pub fn write_segmentation(path: &Path, segmentation: &Segmentation) -> Result<()> {
    let labels: Vec<i32> = segmentation
        .segment_of
        .iter()
        .map(|&s| i32::try_from(s).unwrap_or(i32::MAX))
        .collect();
    io::write_labelled_mesh_ply(path, &segmentation.mesh, "segment", &labels)
}

/// The segments as JSON: `{"segments": [...]}` with each [`Segment`](crate::segment::Segment)'s fields
/// (`docs/output.md`).
pub fn segments_json(segmentation: &Segmentation) -> Result<Value> {
    let segments = serde_json::to_value(&segmentation.segments).map_err(|e| {
        Error::new(
            ErrorKind::Unsupported,
            format!("cannot encode the segments: {e}"),
        )
    })?;
    Ok(json!({ "segments": segments }))
}

/// The title of a picture or page: the mesh's name and its counts, and the loops'.
fn title(name: &str, surface: &SurfaceMesh, handles: usize, tunnels: usize) -> String {
    let plural =
        |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    format!(
        "{name}: {}, {}, {}, {}",
        plural(surface.num_vertices(), "vertex", "vertices"),
        plural(surface.num_triangles(), "triangle", "triangles"),
        plural(handles, "handle", "handles"),
        plural(tunnels, "tunnel", "tunnels")
    )
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    crate::file::write_atomic(path, text.as_bytes())
}

/// Write a run's files into `dir` (created if missing); returns the paths written.
pub fn write_run(
    dir: &Path,
    surface: &SurfaceMesh,
    report: &NeckReport,
    options: &OutputOptions,
    input: Option<&Path>,
) -> Result<Vec<PathBuf>> {
    crate::file::check_output_folder(dir)?;
    let mut written = Vec::new();
    let curves = loop_curves(report);

    let path = dir.join("loops.obj");
    let lines: Vec<Vec<[f64; 3]>> = curves.iter().map(|c| c.points.clone()).collect();
    let names: Vec<String> = curves
        .iter()
        .enumerate()
        .map(|(i, c)| format!("{}_{i}", Side::neck_name(c.kind)))
        .collect();
    io::write_polylines(&path, &lines, &names)?;
    written.push(path);

    let path = dir.join("loops.ply");
    let colors: Vec<[u8; 3]> = curves.iter().map(|c| kind_color(c.kind)).collect();
    io::write_polylines_ply(&path, &lines, &colors)?;
    written.push(path);

    let kinds: Vec<i32> = curves.iter().map(|c| side_code(c.kind) as i32).collect();
    for name in ["loops.vtp", "loops.vtu"] {
        let path = dir.join(name);
        io::write_polylines_vtk(&path, &lines, &kinds)?;
        written.push(path);
    }

    if !report.loops.is_empty() {
        let path = dir.join("membranes.ply");
        let (mesh, labels) = membranes(report);
        io::write_labelled_mesh_ply(&path, &mesh, "loop", &labels)?;
        written.push(path);
    }

    let path = dir.join("loops.json");
    let value = report_json(report, input)?;
    let text = serde_json::to_string_pretty(&value).map_err(|e| {
        Error::new(
            ErrorKind::Unsupported,
            format!("cannot encode the report: {e}"),
        )
    })?;
    write_text(&path, &(text + "\n"))?;
    written.push(path);

    let path = dir.join("critical.ply");
    io::write_point_cloud(&path, &critical_cloud(report))?;
    written.push(path);

    // The mesh's name, for the picture's and the page's titles.
    let name = input.and_then(Path::file_name).map_or_else(
        || "surface".to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    if let Some(picture) = &options.picture {
        let path = dir.join("view.png");
        let saddles: Vec<[f64; 3]> = report.loops.iter().map(|l| l.saddle).collect();
        let scene = loop_scene(&name, surface, &curves, &saddles);
        let rendered = render::render(&scene, picture)?;
        rendered.image.write_png(&path)?;
        written.push(path);
        if let Some(image) = barcode_picture(report)? {
            let path = dir.join("barcode.png");
            image.write_png(&path)?;
            written.push(path);
        }
    }

    if options.html {
        let path = dir.join("view.html");
        write_html(&path, &name, surface, report)?;
        written.push(path);
    }

    if options.volume {
        let path = dir.join("field.vtu");
        let (mesh, values, side) = merged_field(report)?;
        io::write_tet_mesh(&path, &mesh, &[("field", &values), ("side", &side)])?;
        written.push(path);
    }
    Ok(written)
}

/// The barcode of the scale space (`None` when no side has a bar, e.g. the paper's
/// schedule, whose tracks have no scale).
pub fn barcode_picture(report: &NeckReport) -> Result<Option<render::Image>> {
    let panels: Vec<render::barcode::BarPanel> = report
        .sides
        .iter()
        .filter(|s| s.bars.iter().any(|b| b.birth_scale > 0.0))
        .map(|s| {
            let (name, color, kind) = match s.side {
                Side::Inside => ("inside: handle necks in colour", HANDLE_COLOR, Side::Inside),
                Side::Outside => (
                    "outside: tunnel necks in colour",
                    TUNNEL_COLOR,
                    Side::Outside,
                ),
            };
            // A neck: a selected saddle whose loop was kept.
            let kept: Vec<usize> = report
                .loops
                .iter()
                .filter(|l| l.kind == kind)
                .flat_map(|l| std::iter::once(l.seed).chain(l.duplicates.iter().copied()))
                .collect();
            render::barcode::BarPanel {
                title: format!("{name}, {} tracks", s.bars.len()),
                color,
                bars: s
                    .bars
                    .iter()
                    .filter(|b| b.birth_scale > 0.0)
                    .map(|b| render::barcode::BarSpan {
                        birth: b.birth_scale,
                        death: b.death_scale,
                        highlight: b.saddle.is_some_and(|i| kept.contains(&i)),
                    })
                    .collect(),
            }
        })
        .collect();
    if panels.is_empty() {
        return Ok(None);
    }
    // The right edge: the last scale any bar starts or ends at (alive bars reach it).
    let max_scale = panels
        .iter()
        .flat_map(|p| p.bars.iter().flat_map(|b| [Some(b.birth), b.death]))
        .flatten()
        .fold(0.0, f64::max);
    render::barcode::barcode(&panels, max_scale, 1000, 700).map(Some)
}

fn side_code(side: Side) -> f64 {
    match side {
        Side::Inside => 0.0,
        Side::Outside => 1.0,
    }
}

/// Critical points as a point cloud: each one's `type` (0 minimum, 1 1-saddle, 2
/// 2-saddle, 3 maximum, 4 degenerate), `selected` (1 for the selected 2-saddles) and
/// `persistence` (steps survived); colours blue maxima, red 2-saddles, green
/// 1-saddles, black the rest, and yellow the selected 2-saddles.
pub fn critical_point_cloud(points: &[TrackedPoint]) -> io::PointCloud {
    let mut cloud = io::PointCloud::default();
    let mut kinds = Vec::new();
    let mut selected = Vec::new();
    let mut persistence = Vec::new();
    let mut colors = Vec::new();
    for p in points {
        let (code, color) = match p.kind {
            VertexType::Minimum => (0.0, [0, 0, 0]),
            VertexType::Saddle1 => (1.0, [0, 160, 0]),
            VertexType::Saddle2 if p.selected => (2.0, [255, 210, 0]),
            VertexType::Saddle2 => (2.0, [220, 0, 0]),
            VertexType::Maximum => (3.0, [0, 60, 220]),
            _ => (4.0, [0, 0, 0]),
        };
        cloud.positions.push(p.position);
        kinds.push(code);
        selected.push(if p.selected { 1.0 } else { 0.0 });
        persistence.push(p.persistence as f64);
        colors.push(color);
    }
    cloud.scalars = vec![
        ("type".into(), kinds),
        ("selected".into(), selected),
        ("persistence".into(), persistence),
    ];
    cloud.colors = Some(colors);
    cloud
}

/// The critical points of every side in one cloud, with a `side` field (0 inside,
/// 1 outside).
fn critical_cloud(report: &NeckReport) -> io::PointCloud {
    let mut cloud = io::PointCloud::default();
    let mut colors = Vec::new();
    let mut sides = Vec::new();
    for s in &report.sides {
        let c = critical_point_cloud(&s.critical);
        let c = &c;
        cloud.positions.extend_from_slice(&c.positions);
        for (name, values) in &c.scalars {
            match cloud.scalars.iter_mut().find(|(n, _)| n == name) {
                Some((_, all)) => all.extend_from_slice(values),
                None => cloud.scalars.push((name.clone(), values.clone())),
            }
        }
        colors.extend(
            c.colors
                .clone()
                .unwrap_or_else(|| vec![[0, 0, 0]; c.positions.len()]),
        );
        sides.extend(std::iter::repeat_n(side_code(s.side), c.positions.len()));
    }
    let n = cloud.positions.len();
    // A field missing on one side would be short: pad, so every field has n values.
    for (_, values) in &mut cloud.scalars {
        values.resize(n, 0.0);
    }
    cloud.scalars.push(("side".into(), sides));
    cloud.colors = Some(colors);
    cloud
}

/// Both sides' volume meshes as one mesh, with the smoothed field and the side.
fn merged_field(report: &NeckReport) -> Result<(TetMesh, Vec<f64>, Vec<f64>)> {
    let mut positions = Vec::new();
    let mut tets = Vec::new();
    let mut kinds = Vec::new();
    let mut values = Vec::new();
    let mut side = Vec::new();
    for s in &report.sides {
        let Some(field) = &s.field else {
            return Err(Error::invalid_argument(
                "the volume was not kept: run with keep_volume (--volume) to write field.vtu",
            ));
        };
        let offset = positions.len() as u32;
        positions.extend_from_slice(&field.mesh.positions);
        kinds.extend_from_slice(&field.mesh.kinds);
        tets.extend(field.mesh.tets.iter().map(|t| t.map(|v| v + offset)));
        values.extend_from_slice(&field.values);
        side.extend(std::iter::repeat_n(
            side_code(s.side),
            field.mesh.positions.len(),
        ));
    }
    Ok((TetMesh::new(positions, tets, kinds)?, values, side))
}

fn read_json(path: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::new(ErrorKind::Io, format!("cannot read: {e}")).in_file(path))?;
    let value: Value = serde_json::from_str(&text).map_err(|e| {
        Error::new(ErrorKind::Syntax, format!("not JSON: {e}"))
            .at_line(e.line())
            .in_file(path)
    })?;
    if let Some(v) = value.get("version").and_then(Value::as_u64) {
        if v > JSON_VERSION {
            return Err(Error::new(
                ErrorKind::Unsupported,
                format!("JSON version {v} is newer than this necklace reads ({JSON_VERSION})"),
            )
            .in_file(path));
        }
    }
    Ok(value)
}

fn point(value: &Value) -> Option<[f64; 3]> {
    let a = value.as_array()?;
    if a.len() != 3 {
        return None;
    }
    let p = [a[0].as_f64()?, a[1].as_f64()?, a[2].as_f64()?];
    p.iter().all(|v| v.is_finite()).then_some(p)
}

/// The loops of a `loops.json` file (see `docs/output.md`).
pub fn read_loops_json(path: impl AsRef<Path>) -> Result<Vec<LoopCurve>> {
    let path = path.as_ref();
    let value = read_json(path)?;
    let bad = |m: String| Error::new(ErrorKind::Syntax, m).in_file(path);
    let loops = value
        .get("loops")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("no \"loops\" array: not a necklace loops.json".into()))?;
    loops
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let kind = match l
                .get("kind")
                .and_then(Value::as_str)
                .and_then(Side::from_neck_name)
            {
                Some(side) => side,
                None => {
                    return Err(bad(format!(
                        "loop {i}: \"kind\" is not \"handle\" or \"tunnel\""
                    )))
                }
            };
            let points = l
                .get("points")
                .and_then(Value::as_array)
                .and_then(|ps| ps.iter().map(point).collect::<Option<Vec<_>>>())
                .ok_or_else(|| bad(format!("loop {i}: \"points\" is not a list of [x, y, z]")))?;
            Ok(LoopCurve { kind, points })
        })
        .collect()
}

/// Saddle positions from the JSON of `necklace critical --json` (its `saddles`) or of a
/// `loops.json` (the `saddles` of each of its `sides`).
pub fn read_points_json(path: impl AsRef<Path>) -> Result<Vec<[f64; 3]>> {
    let path = path.as_ref();
    let value = read_json(path)?;
    let mut lists: Vec<&Value> = Vec::new();
    if let Some(s) = value.get("saddles") {
        lists.push(s);
    }
    if let Some(sides) = value.get("sides").and_then(Value::as_array) {
        lists.extend(sides.iter().filter_map(|s| s.get("saddles")));
    }
    if lists.is_empty() {
        return Err(Error::new(
            ErrorKind::Syntax,
            "no \"saddles\": expected the JSON of `necklace critical --json` or a loops.json",
        )
        .in_file(path));
    }
    let mut points = Vec::new();
    for list in lists {
        let items = list.as_array().map(Vec::as_slice).unwrap_or_default();
        for (i, s) in items.iter().enumerate() {
            let p = s.get("position").and_then(point).ok_or_else(|| {
                Error::new(
                    ErrorKind::Syntax,
                    format!("saddle {i}: no \"position\" [x, y, z]"),
                )
                .in_file(path)
            })?;
            points.push(p);
        }
    }
    Ok(points)
}
