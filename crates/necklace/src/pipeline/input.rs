//! The input step of the method: a mesh as read becomes the surface every stage works
//! on, and everything done to it on the way is said.
//!
//! [`prepare_input`] refuses what no stage can work with, one line naming the problem:
//! no triangles, coordinates so large that volumes overflow ([`MAX_COORDINATE`]), all
//! vertices at one point, a closed surface that encloses no volume (a doubled sheet).
//! It repairs what has one right answer, each repair a note:
//! 0. corners closer than [`InputOptions::weld`] times the bounding-box diagonal are
//!    welded into one vertex (`mesh::weld`: STL stores each triangle's corners apart,
//!    exporters round, OBJ and PLY duplicate positions along texture seams), and the
//!    triangles that this collapses are removed ([`weld_input`]);
//! 1. vertices no triangle uses are removed (they would set the bounding box, and with
//!    it the lattice spacing and the smoothing scales);
//! 2. faces are turned to agree with their neighbours, per component
//!    (`mesh::orient_consistently`, libigl's `bfs_orient`);
//! 3. each closed component is turned to face away from the solid it bounds: an
//!    outermost component outward, a cavity inside it inward, a part inside the cavity
//!    outward again (by how the components nest, from winding numbers), so that no
//!    component is silently meshed as empty space.
//!
//! What it cannot repair is a warning, and the method goes on with the solid the winding
//! number describes: an open or non-manifold surface, a non-orientable component, and a
//! surface that crosses itself (whose loops are then tightened on the volume mesh's
//! boundary, see `find_necks`). [`inspect_surface`] is the report `necklace info`
//! prints: [`MeshReport::new`] plus the two measures that need the `distance` service
//! (components facing the wrong way, crossing triangles).

use std::path::Path;

use crate::distance::{nesting, SurfaceDistance};
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{norm, sub};
use crate::io;
use crate::loops::Seed;
use crate::mesh::{
    orient_consistently, remove_unreferenced, weld, MeshReport, Reorientation, Side, SurfaceMesh,
    Welding, MAX_COORDINATE,
};
use crate::tet::{TetMesh, VertexKind};

/// Corners closer than this fraction of the bounding-box diagonal are one point, by
/// default ([`InputOptions::weld`]): far below any feature the method resolves (the
/// lattice spacing is 1/64 of the diagonal) and far above the `6e-17` an exporter writes
/// for 0. Single precision rounds each coordinate by up to 6e-8 of itself: corners that
/// an exporter rounded apart that far need a larger `--weld` (1e-6, say).
pub const DEFAULT_WELD: f64 = 1e-8;

/// Options of the input step ([`prepare_input_with`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InputOptions {
    /// Weld corners closer than this fraction of the bounding-box diagonal into one
    /// vertex (default [`DEFAULT_WELD`]; `Some(0.0)` welds only equal positions; `None`
    /// keeps the vertices as given).
    pub weld: Option<f64>,
}

impl InputOptions {
    /// The error for options no input step can use (a negative or non-finite weld
    /// tolerance).
    pub fn check(&self) -> Result<()> {
        match self.weld {
            Some(w) if !(w.is_finite() && w >= 0.0) => Err(Error::invalid_argument(format!(
                "weld = {w} must be a fraction of the diagonal, 0 or more (--no-weld turns welding off)"
            ))),
            _ => Ok(()),
        }
    }
}

impl Default for InputOptions {
    fn default() -> Self {
        InputOptions {
            weld: Some(DEFAULT_WELD),
        }
    }
}

/// What [`weld_input`] did: the welded mesh, for each of its vertices the input's
/// index, the counts, and the note that says them (`None` when nothing was merged).
#[derive(Debug, Clone)]
pub struct WeldedInput {
    /// The mesh with the merged vertices removed (the others in their order).
    pub mesh: SurfaceMesh,
    /// For each vertex of `mesh`, its index in the input.
    pub input_vertex: Vec<u32>,
    /// The counts (all 0 when welding is off or merged nothing).
    pub welding: Welding,
    /// One line for the notes, when anything was merged.
    pub note: Option<String>,
}

/// Step 0 of the input step: `mesh` with its corners welded as `options` say
/// (`mesh::weld`), and the note that says how many were merged and how many triangles
/// collapsed.
pub fn weld_input(mesh: SurfaceMesh, options: &InputOptions) -> WeldedInput {
    let unchanged = |mesh: SurfaceMesh, welding: Welding| WeldedInput {
        input_vertex: (0..mesh.positions.len() as u32).collect(),
        mesh,
        welding,
        note: None,
    };
    let Some(relative) = options.weld else {
        return unchanged(mesh, Welding::default());
    };
    let tolerance = relative * mesh.bbox_diagonal();
    let (welded, input_vertex, what) = weld(&mesh, tolerance);
    if what.merged == 0 {
        return unchanged(mesh, what);
    }
    let collapsed = match what.collapsed_faces {
        0 => String::new(),
        1 => "; removed 1 triangle that it collapsed".into(),
        n => format!("; removed {n} triangles that it collapsed"),
    };
    let note = format!(
        "welded {} corners into others within {:.3e} ({relative:e} of the bounding-box diagonal; --no-weld keeps them){collapsed}",
        what.merged, what.tolerance
    );
    WeldedInput {
        mesh: welded,
        input_vertex,
        welding: what,
        note: Some(note),
    }
}

/// A surface accepted as input to the method, with what was done to it.
#[derive(Debug, Clone)]
pub struct PreparedSurface {
    /// The mesh: no unreferenced vertices, faces consistently oriented, each closed
    /// component facing away from the solid it bounds.
    pub mesh: SurfaceMesh,
    /// The report of the mesh as given ([`inspect_surface`]).
    pub report: MeshReport,
    /// The report of `mesh`, the surface the stages work on ([`MeshReport::new`]; the
    /// genus the checks compare with).
    pub mesh_report: MeshReport,
    /// Whether any face was turned round to point outward (a whole inverted mesh, an
    /// inverted component, or faces that disagreed with their neighbours).
    pub flipped: bool,
    /// The triangles that cross another (sorted, each once; empty for an embedded
    /// surface), as indices into `mesh`'s faces (the input's, in their order, less the
    /// ones welding collapsed).
    pub crossing_faces: Vec<u32>,
    /// The distance structure of `mesh`, with its crossing pairs and the pseudonormal
    /// sign wherever it decides ([`SurfaceDistance::of_surface`]): built once, and
    /// shared by every stage of the run.
    pub distance: SurfaceDistance,
    /// For each vertex of `mesh`, its index in the input (the input's vertices that a
    /// face uses after welding, in their order; a welded vertex is the first of those
    /// merged into it; faces keep their order, less those welding collapsed).
    pub input_vertex: Vec<u32>,
    /// The repairs made, one line each.
    pub notes: Vec<String>,
    /// What is still unusual about the surface, one line each.
    pub warnings: Vec<String>,
}

/// [`MeshReport::new`] plus, per component, whether it faces into the solid it bounds
/// (`inward_components`, and `outward` judged by it) and the number of crossing
/// triangle pairs (`self_intersections`).
pub fn inspect_surface(mesh: &SurfaceMesh) -> MeshReport {
    inspect(mesh, Signs::Now).report
}

/// Whether the prepared surface's distance structure answers inside/outside at once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Signs {
    /// Fast winding number, and the pseudonormal sign where the surface allows it.
    Now,
    /// Only where the surface has several components (their nesting needs winding
    /// numbers); otherwise exact winding numbers until [`add_signs`] (a dense surface
    /// about to be simplified: the stages that ask signs work on the copy).
    Later,
}

/// What [`inspect`] finds.
struct Inspection {
    /// [`inspect_surface`]'s report.
    report: MeshReport,
    /// [`MeshReport::new`] alone (without the measures that need the distance service).
    plain: MeshReport,
    /// The crossing pairs of triangles.
    crossings: Vec<[u32; 2]>,
    /// The distance structure that found them (`None` for a mesh refused anyway).
    distance: Option<SurfaceDistance>,
}

/// [`inspect_surface`], with the plain report, the crossing pairs of triangles and the
/// distance structure that found them.
fn inspect(mesh: &SurfaceMesh, signs: Signs) -> Inspection {
    let plain = MeshReport::new(mesh);
    let mut report = plain.clone();
    if mesh.triangles.is_empty() || report.max_abs_coordinate > MAX_COORDINATE {
        return Inspection {
            report,
            plain,
            crossings: Vec::new(),
            distance: None,
        };
    }
    let mut distance = SurfaceDistance::without_winding(mesh);
    if signs == Signs::Now || plain.components > 1 {
        distance.add_winding();
    }
    let crossings = distance.self_intersections(&mesh.triangles);
    report.self_intersections = Some(crossings.len());
    if report.outward.is_some() && crossings.is_empty() {
        if let Some(wrong) = facing_wrong_way(mesh, &report) {
            let k = wrong.iter().filter(|&&w| w).count();
            report.inward_components = Some(k);
            report.outward = Some(k == 0);
        }
    }
    Inspection {
        report,
        plain,
        crossings,
        distance: Some(distance),
    }
}

/// Check a mesh, repair what has one right answer and say what was done (see the
/// module doc), with the default [`InputOptions`]. Open, non-manifold or self-crossing
/// input is accepted with warnings.
pub fn prepare_input(input: SurfaceMesh) -> Result<PreparedSurface> {
    prepare_input_with(input, &InputOptions::default())
}

/// [`prepare_input`] with the given options.
pub fn prepare_input_with(input: SurfaceMesh, options: &InputOptions) -> Result<PreparedSurface> {
    prepare(input, options, Signs::Now)
}

/// [`prepare_input_with`], its distance structure with or without signs.
pub(super) fn prepare(
    input: SurfaceMesh,
    options: &InputOptions,
    signs: Signs,
) -> Result<PreparedSurface> {
    // 0. Corners that are one point.
    options.check()?;
    let WeldedInput {
        mesh: input,
        input_vertex: welded_from,
        note: welded,
        ..
    } = weld_input(input, options);
    let Inspection {
        report,
        plain,
        crossings,
        distance,
    } = inspect(&input, signs);
    refuse_unusable(&report)?;
    let mut notes: Vec<String> = welded.into_iter().collect();
    let mut warnings = Vec::new();

    // 1. Unreferenced vertices.
    let (mut mesh, kept) = remove_unreferenced(&input);
    let removed = input.positions.len() - kept.len();
    let input_vertex: Vec<u32> = kept.iter().map(|&v| welded_from[v as usize]).collect();
    if removed > 0 {
        notes.push(format!(
            "removed {removed} vertices that no face uses (they would have set the bounding box)"
        ));
    }

    // 2. Faces that disagree with their neighbours (none where every edge of a
    //    manifold without degenerate faces is used once each way: no walk needed).
    let turned = if plain.manifold && plain.oriented && plain.degenerate_faces == 0 {
        Reorientation::default()
    } else {
        let (consistent, turned) = orient_consistently(&mesh);
        mesh = consistent;
        turned
    };
    if turned.flipped_faces > 0 {
        notes.push(format!(
            "turned {} faces round to agree with their neighbours ({} component{})",
            turned.flipped_faces,
            turned.components,
            if turned.components == 1 { "" } else { "s" }
        ));
    }
    if turned.non_orientable > 0 {
        warnings.push(format!(
            "{} component{} cannot be oriented (a Möbius band or a Klein bottle): meshed as the winding number says",
            turned.non_orientable,
            if turned.non_orientable == 1 { "" } else { "s" }
        ));
    }

    // 3. Components that face into the solid they bound. (A report is a pass over
    //    the whole mesh: each is made again only where the mesh has changed.)
    let oriented = if mesh == input {
        plain
    } else {
        MeshReport::new(&mesh)
    };
    let mut flipped_components = 0;
    if oriented.outward.is_some() {
        let wrong = if report.self_intersections == Some(0) {
            facing_wrong_way(&mesh, &oriented)
        } else {
            None
        };
        let wrong = wrong.unwrap_or_else(|| {
            // Crossing or unnestable components: the whole mesh by its volume.
            vec![oriented.signed_volume < 0.0; oriented.components]
        });
        flipped_components = flip_components(&mut mesh, &wrong);
        if flipped_components == oriented.components {
            notes.push("faces flipped to point outward".into());
        } else if flipped_components > 0 {
            notes.push(format!(
                "flipped {flipped_components} of {} components that faced into the solid they bound",
                oriented.components
            ));
        }
    } else if oriented.signed_volume < 0.0 {
        // Open or non-manifold: the total volume is the only guide.
        mesh.flip_orientation();
        flipped_components = oriented.components;
        notes.push("faces flipped to point outward (negative volume)".into());
    }
    let after = if flipped_components == 0 {
        oriented
    } else {
        MeshReport::new(&mesh)
    };
    if after.flat {
        return Err(flat_error(&after));
    }

    // What is left.
    let self_intersections = crossings.len();
    let mut crossing_faces: Vec<u32> = crossings.iter().flatten().copied().collect();
    crossing_faces.sort_unstable();
    crossing_faces.dedup();
    for problem in after.problems() {
        let said_below = problem.starts_with("crosses itself");
        if !said_below && !problem.ends_with("connected components") {
            warnings.push(problem);
        }
    }
    if self_intersections > 0 {
        warnings.push(format!(
            "the surface crosses itself ({self_intersections} pairs of triangles): the method works on the solid its winding number encloses"
        ));
    }
    // The run's distance structure: the one that inspected the input when nothing was
    // changed, else one of the repaired mesh.
    let mut distance = match distance {
        Some(d) if mesh == input && signs == Signs::Later => d.recording(crossings),
        Some(d) if mesh == input => d.with_crossings(&mesh, crossings),
        _ => SurfaceDistance::of_surface(&mesh),
    };
    refuse_without_volume(&mesh, &after, &mut distance)?;
    Ok(PreparedSurface {
        mesh,
        report,
        mesh_report: after,
        distance,
        flipped: turned.flipped_faces > 0 || flipped_components > 0,
        crossing_faces,
        input_vertex,
        notes,
        warnings,
    })
}

/// Give a surface prepared with [`Signs::Later`] the signs [`prepare_input`] gives:
/// the fast winding number, and the pseudonormal sign wherever it decides.
pub(super) fn add_signs(prepared: &mut PreparedSurface) {
    prepared.distance.add_winding();
    prepared.distance.use_pseudonormal_sign(&prepared.mesh);
}

/// Check that `mesh` is a closed, manifold surface and [`prepare_input`] it. An error
/// names every problem found.
pub fn prepare_surface(mesh: SurfaceMesh) -> Result<PreparedSurface> {
    let report = MeshReport::new(&mesh);
    if mesh.triangles.is_empty() || !(report.watertight && report.manifold) {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "not a closed manifold surface: {}",
                report.problems().join("; ")
            ),
        ));
    }
    prepare_input(mesh)
}

/// Read a mesh file and [`prepare_input`] it; errors name the file.
pub fn load_surface(path: impl AsRef<Path>) -> Result<PreparedSurface> {
    let path = path.as_ref();
    let mesh = io::read_mesh(path)?;
    prepare_input(mesh).map_err(|e| e.in_file(path))
}

/// The errors for a mesh no stage can work with.
fn refuse_unusable(report: &MeshReport) -> Result<()> {
    let invalid = |message: String| Err(Error::new(ErrorKind::InvalidMesh, message));
    if report.faces == 0 {
        return invalid("the mesh has no triangles".into());
    }
    if report.max_abs_coordinate > MAX_COORDINATE {
        return invalid(format!(
            "coordinates up to {:.3e} are too large: above {MAX_COORDINATE:.0e} areas and volumes overflow; scale the mesh down",
            report.max_abs_coordinate
        ));
    }
    if report.flat {
        return Err(flat_error(report));
    }
    Ok(())
}

/// Triangles sampled (evenly through the faces) to judge whether an open surface bounds
/// a solid ([`refuse_without_volume`]).
const BOUNDING_SAMPLES: usize = 2000;

/// An open surface bounds a solid when at least this share of its sampled triangles
/// lie between the inside and the outside of the winding number.
const MIN_BOUNDING_SHARE: f64 = 0.5;

/// The error for input that has no volume to mesh, found in well under a second: no
/// component is closed, and fewer than [`MIN_BOUNDING_SHARE`] of its triangles (a
/// sample of [`BOUNDING_SAMPLES`]) have the solid (winding number ≥ ½) on one side
/// only, the mark of open sheets (both sides outside: a chair drawn as panels) and
/// triangle soups (random sides). A scan with holes, or a solid split at texture
/// seams, passes: nearly all its triangles separate in from out. Closed surfaces are
/// not asked (a flat one is refused as flat). Builds the winding number's expansions
/// when `distance` has none.
fn refuse_without_volume(
    mesh: &SurfaceMesh,
    report: &MeshReport,
    distance: &mut SurfaceDistance,
) -> Result<()> {
    let closed = report
        .component_details
        .iter()
        .any(|c| c.boundary_loops == 0 && c.genus.is_some());
    if closed || mesh.triangles.is_empty() {
        return Ok(());
    }
    distance.add_winding();
    let step = mesh.num_triangles().div_ceil(BOUNDING_SAMPLES).max(1);
    let offset = 1e-4 * report.bbox_diagonal;
    let (mut sampled, mut bounding) = (0usize, 0usize);
    for f in (0..mesh.num_triangles()).step_by(step) {
        let n = mesh.face_normal_scaled(f);
        let length = norm(n);
        if !(length > 0.0 && length.is_finite()) {
            continue;
        }
        let c = mesh.corners(f);
        let centroid = [0, 1, 2].map(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0);
        let at = |sign: f64| {
            let p = [0, 1, 2].map(|k| centroid[k] + sign * offset * n[k] / length);
            distance.winding_number(p) >= 0.5
        };
        sampled += 1;
        if at(-1.0) != at(1.0) {
            bounding += 1;
        }
    }
    let share = bounding as f64 / sampled.max(1) as f64;
    if sampled > 0 && share >= MIN_BOUNDING_SHARE {
        return Ok(());
    }
    let what = if report.non_manifold_edges > report.edges / 4 {
        "sheets glued along their edges"
    } else if report.components * 2 > report.faces {
        "a triangle soup"
    } else {
        "open sheets"
    };
    Err(Error::new(
        ErrorKind::InvalidMesh,
        format!(
            "the surface encloses no volume: it looks like {what} (no component is closed, and {bounding} of {sampled} sampled triangles have the solid its winding number encloses on one side, under {:.0} %)",
            100.0 * MIN_BOUNDING_SHARE
        ),
    ))
}

fn flat_error(report: &MeshReport) -> Error {
    let why = if report.bbox_diagonal == 0.0 {
        "all its vertices are at one point"
    } else {
        "it is flat (a doubled sheet, signed volume 0)"
    };
    Error::new(
        ErrorKind::InvalidMesh,
        format!("the surface encloses no volume: {why}"),
    )
}

/// Per component of a closed, manifold, oriented, embedded mesh, whether it faces into
/// the solid it bounds: at even nesting depth (outermost, or a part inside a cavity) it
/// should enclose positive volume, at odd depth (a cavity) negative. `None` when the
/// components cannot be nested (two of them cross).
fn facing_wrong_way(mesh: &SurfaceMesh, report: &MeshReport) -> Option<Vec<bool>> {
    let parent = nesting(mesh, report)?;
    let depth = |mut i: usize| {
        let mut d = 0;
        while let Some(p) = parent[i] {
            d += 1;
            i = p;
            if d > parent.len() {
                break;
            }
        }
        d
    };
    Some(
        report
            .component_details
            .iter()
            .enumerate()
            .map(|(i, c)| (c.signed_volume > 0.0) != (depth(i) % 2 == 0))
            .collect(),
    )
}

/// Turn round every component marked in `which` (components as `Topology::components`
/// numbers them); returns how many were turned.
fn flip_components(mesh: &mut SurfaceMesh, which: &[bool]) -> usize {
    if !which.iter().any(|&w| w) {
        return 0;
    }
    let (component_of, _) = crate::mesh::Topology::new(mesh).components(mesh);
    for t in &mut mesh.triangles {
        if component_of[t[0] as usize].is_some_and(|c| which[c as usize]) {
            t.swap(1, 2);
        }
    }
    which.iter().filter(|&&w| w).count()
}

// Where the surface crosses itself: which seeds lie there, and the surface their loops
// are tightened on instead.

/// How many seeds lie near a crossing face: a corner of a crossing triangle within
/// [`CROSSING_REACH`] times the seed's distance to the surface (its loop's radius,
/// about), plus the triangle's longest side.
pub(super) fn seeds_near(surface: &PreparedSurface, seeds: &[Seed]) -> usize {
    let crossing_faces = &surface.crossing_faces;
    if crossing_faces.is_empty() || seeds.is_empty() {
        return 0;
    }
    let positions: Vec<[f64; 3]> = seeds.iter().map(|s| s.position).collect();
    let radii = surface.distance.distances(&positions);
    let surface = &surface.mesh;
    let crossing: Vec<[[f64; 3]; 3]> = crossing_faces
        .iter()
        .map(|&f| surface.corners(f as usize))
        .collect();
    positions
        .iter()
        .zip(&radii)
        .filter(|(p, r)| {
            crossing.iter().any(|t| {
                // A corner within reach, give or take the triangle's size.
                let size = (0..3)
                    .map(|i| norm(sub(t[i], t[(i + 1) % 3])))
                    .fold(0.0, f64::max);
                t.iter()
                    .any(|c| norm(sub(*c, **p)) < CROSSING_REACH * **r + size)
            })
        })
        .count()
}

/// See [`seeds_near`].
const CROSSING_REACH: f64 = 4.0;

/// The part of a volume mesh's boundary on the input surface (its surface-kind
/// faces, not the outer sphere), oriented like the surface (outward from the solid),
/// without unused vertices.
pub fn meshed_boundary(mesh: &TetMesh, side: Side) -> SurfaceMesh {
    let on_surface = |f: &[u32; 3]| {
        f.iter()
            .all(|&v| mesh.kinds[v as usize] == VertexKind::Surface)
    };
    let triangles = mesh
        .boundary_faces()
        .into_iter()
        .filter(on_surface)
        .map(|f| match side {
            Side::Inside => f,
            // The shell's boundary faces point out of the shell, into the solid.
            Side::Outside => [f[0], f[2], f[1]],
        })
        .collect();
    let all = SurfaceMesh {
        positions: mesh.positions.clone(),
        triangles,
    };
    crate::mesh::remove_unreferenced(&all).0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> SurfaceMesh {
        SurfaceMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn an_inward_surface_is_flipped_and_says_so() {
        let mut mesh = tetrahedron();
        let ok = prepare_surface(mesh.clone()).unwrap();
        assert!(!ok.flipped && ok.notes.is_empty());
        mesh.flip_orientation();
        let fixed = prepare_surface(mesh).unwrap();
        assert!(fixed.flipped);
        assert_eq!(fixed.notes, ["faces flipped to point outward"]);
        assert!(fixed.mesh.signed_volume() > 0.0);
    }

    #[test]
    fn an_open_surface_is_refused_with_its_problems() {
        let mut mesh = tetrahedron();
        mesh.triangles.pop();
        let err = prepare_surface(mesh).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidMesh);
        assert!(err.to_string().contains("3 boundary edges"), "{err}");
    }
}
