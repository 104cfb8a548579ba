//! The pipeline: the one module that composes the others.
//!
//! The method (see `ARCHITECTURE.md`) runs: input surface → volume mesh → distance field
//! and smoothing → critical points → neck loops. Each stage is a module that takes plain
//! data and returns plain data; only this module calls one stage with another's output.
//! Steps so far:
//! - [`prepare_surface`] checks that a mesh is a closed, manifold, consistently oriented
//!   surface and turns an inward-oriented one outward, saying so;
//! - [`volume_mesh`] builds the tet mesh of the inside ([`Side::Inside`]) or of the shell
//!   between the surface and a bounding sphere ([`Side::Outside`]): it wraps the surface's
//!   signed distance (`distance`) as a `volume::Domain`, with thin-part sizing from ray
//!   casts, and calls the stuffing mesher (`volume`);
//! - [`critical_points`] computes the distance field on that mesh ([`distance_field`],
//!   through `distance`) and hands it to `morse` for smoothing, classification,
//!   tracking and saddle selection;
//! - [`find_necks`] runs the whole method on both sides and hands each side's saddles to
//!   `loops` (plane cut, tightening, selection), returning a [`NeckReport`].

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::distance::SurfaceDistance;
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, dot, norm, scale, sub};
use crate::io;
use crate::loops::{self, DropReason, DroppedLoop, LoopKind, LoopOptions, NeckLoop, Seed};
use crate::mesh::{MeshReport, SurfaceMesh, Topology};
use crate::morse::{self, MorseOptions, MorseResult, VertexType};
use crate::progress::{Progress, Silent};
use crate::tet::{TetMesh, VertexKind};
use crate::volume::{self, Domain, StuffingOptions, StuffingStats};

/// A surface accepted as input to the method, with the report it was checked against.
#[derive(Debug, Clone)]
pub struct PreparedSurface {
    /// The mesh, outward-oriented.
    pub mesh: SurfaceMesh,
    /// The validity report of the mesh as given.
    pub report: MeshReport,
    /// Whether the faces were flipped because the input was oriented inward.
    pub flipped: bool,
}

/// Check that `mesh` is a closed, manifold, consistently oriented surface, and orient
/// it outward. Several components are allowed; each must be closed. An error names
/// every problem found.
pub fn prepare_surface(mut mesh: SurfaceMesh) -> Result<PreparedSurface> {
    let report = MeshReport::new(&mesh);
    let fatal = !(report.watertight && report.manifold && report.oriented);
    if mesh.triangles.is_empty() || fatal {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "not a closed manifold oriented surface: {}",
                report.problems().join("; ")
            ),
        ));
    }
    let flipped = report.outward == Some(false);
    if flipped {
        mesh.flip_orientation();
    }
    Ok(PreparedSurface {
        mesh,
        report,
        flipped,
    })
}

/// Orient a surface for volume meshing without requiring it to be closed: faces are
/// flipped when the signed volume is negative (an open or self-intersecting mesh is
/// still meshed as the solid its winding number describes). Returns the report of the
/// mesh as given and whether it was flipped.
pub fn orient_for_volume(mut mesh: SurfaceMesh) -> (SurfaceMesh, MeshReport, bool) {
    let report = MeshReport::new(&mesh);
    let flipped = report.signed_volume < 0.0;
    if flipped {
        mesh.flip_orientation();
    }
    (mesh, report, flipped)
}

/// Read a mesh file and [`prepare_surface`] it; errors name the file.
pub fn load_surface(path: impl AsRef<Path>) -> Result<PreparedSurface> {
    let path = path.as_ref();
    let mesh = io::read_mesh(path)?;
    prepare_surface(mesh).map_err(|e| e.in_file(path))
}

/// Which volume to mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The solid bounded by the surface: handles.
    Inside,
    /// The shell between the surface and a bounding sphere: tunnels.
    Outside,
}

/// Which volume mesher to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mesher {
    /// necklace's isosurface stuffing (default).
    Stuffing,
    /// TetGen with the paper's switches "pq1.2"; needs the `tetgen` cargo feature
    /// (AGPL-3.0).
    Tetgen,
}

/// Options of [`volume_mesh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeOptions {
    /// The mesher (default [`Mesher::Stuffing`]).
    pub mesher: Mesher,
    /// Lattice spacing along the surface, in the surface's units. `None` (default):
    /// [`default_h`].
    pub h: Option<f64>,
    /// Outer sphere radius as a multiple of the bounding box's half diagonal (default
    /// 1.5), centred at the box centre.
    pub sphere_scale: f64,
    /// How many halvings below `h` thin parts may ask for (default 3: `h/8`).
    pub refine_levels: u32,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            mesher: Mesher::Stuffing,
            h: None,
            sphere_scale: 1.5,
            refine_levels: 3,
        }
    }
}

/// A volume mesh of one side of a surface, with what describes it.
#[derive(Debug, Clone)]
pub struct VolumeResult {
    /// The tet mesh (vertex kinds: interior, surface, outer sphere).
    pub mesh: TetMesh,
    /// Which side.
    pub side: Side,
    /// The spacing used.
    pub h: f64,
    /// Centre and radius of the outer sphere (outside only).
    pub sphere: Option<([f64; 3], f64)>,
    /// The mesher used.
    pub mesher: Mesher,
    /// The stuffing mesher's counts (`None` for TetGen).
    pub stats: Option<StuffingStats>,
    /// Sizing points asked for by thin parts.
    pub thin_points: usize,
    /// Outside, connected surface only: enclosed pockets (components touching no
    /// outer-sphere vertex, gaps below the resolution) that were dropped.
    pub dropped_pockets: usize,
    /// Largest distance of a surface-kind vertex to the input surface, divided by the
    /// bounding-box diagonal.
    pub hausdorff_to_surface: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The default spacing: 1/64 of the bounding-box diagonal. Parts thinner than about
/// `2h` are refined locally (see [`VolumeOptions::refine_levels`]), so the rule needs
/// no knowledge of the thinnest part.
pub fn default_h(surface: &SurfaceMesh) -> f64 {
    surface.bbox_diagonal() / 64.0
}

/// The summary of a volume mesh that `necklace volume --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VolumeReport {
    /// Which side was meshed.
    pub side: Side,
    /// Vertex count.
    pub vertices: usize,
    /// Tet count.
    pub tets: usize,
    /// Vertices strictly inside the region.
    pub interior_vertices: usize,
    /// Vertices on the input surface.
    pub surface_vertices: usize,
    /// Vertices on the outer sphere.
    pub outer_vertices: usize,
    /// χ of the tet mesh (V − E + F − T).
    pub euler_volume: i64,
    /// χ of its boundary surface (twice `euler_volume` for a 3-manifold with boundary).
    pub euler_boundary: i64,
    /// Smallest dihedral angle, degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle, degrees.
    pub max_dihedral_deg: f64,
    /// Largest distance of a surface vertex to the input surface / bbox diagonal.
    pub hausdorff_to_surface: f64,
    /// Sum of tet volumes.
    pub volume: f64,
    /// The mesher used.
    pub mesher: Mesher,
    /// Lattice spacing along the surface (stuffing).
    pub h: f64,
    /// Smallest cell used (thin parts; stuffing).
    pub finest_cell: f64,
    /// Sizing points from thin parts.
    pub thin_points: usize,
    /// Tets inverted by warping (0 when all is well).
    pub inverted_tets: usize,
    /// Tets dropped to undo sub-resolution pinches.
    pub pinch_tets_removed: usize,
    /// Enclosed pockets dropped from a shell.
    pub dropped_pockets: usize,
    /// Connected components of the tet mesh.
    pub components: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl VolumeResult {
    /// Counts, invariants and quality of the mesh.
    pub fn report(&self) -> VolumeReport {
        let m = &self.mesh;
        let (interior, surface, outer) = m.kind_counts();
        let (min_dihedral, max_dihedral) = m.dihedral_range_deg().unwrap_or((0.0, 0.0));
        let boundary = SurfaceMesh {
            positions: m.positions.clone(),
            triangles: m.boundary_faces(),
        };
        let euler_boundary = MeshReport::new(&boundary)
            .component_details
            .iter()
            .map(|c| c.euler)
            .sum();
        VolumeReport {
            side: self.side,
            vertices: m.num_vertices(),
            tets: m.num_tets(),
            interior_vertices: interior,
            surface_vertices: surface,
            outer_vertices: outer,
            euler_volume: m.euler_characteristic(),
            euler_boundary,
            min_dihedral_deg: min_dihedral,
            max_dihedral_deg: max_dihedral,
            hausdorff_to_surface: self.hausdorff_to_surface,
            volume: m.volume(),
            mesher: self.mesher,
            h: self.h,
            finest_cell: self.stats.map_or(0.0, |s| s.finest_cell),
            thin_points: self.thin_points,
            inverted_tets: self.stats.map_or(0, |s| s.inverted_tets),
            pinch_tets_removed: self.stats.map_or(0, |s| s.pinch_tets_removed),
            dropped_pockets: self.dropped_pockets,
            components: m.tet_components().1,
            seconds: self.seconds,
        }
    }
}

/// Mesh one side of a closed, outward-oriented surface (see [`prepare_surface`]).
pub fn volume_mesh(
    surface: &SurfaceMesh,
    side: Side,
    options: &VolumeOptions,
) -> Result<VolumeResult> {
    let start = Instant::now();
    let (lo, hi) = surface
        .bounding_box()
        .ok_or_else(|| Error::new(ErrorKind::InvalidMesh, "the surface has no vertices"))?;
    if surface.triangles.is_empty() {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            "the surface has no triangles",
        ));
    }
    let diagonal = norm(sub(hi, lo));
    if diagonal.is_nan() || diagonal <= 0.0 {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            "the surface is a single point",
        ));
    }
    let h = options.h.unwrap_or_else(|| default_h(surface));
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::invalid_argument(format!("h = {h} must be positive")));
    }
    if !(options.sphere_scale > 1.0 && options.sphere_scale.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "sphere_scale = {} must exceed 1 (the sphere must enclose the surface)",
            options.sphere_scale
        )));
    }

    let distance = SurfaceDistance::new(surface);
    let centre = scale(add(lo, hi), 0.5);
    let radius = options.sphere_scale * 0.5 * diagonal;
    let (mut mesh, stats, thin_points) = match options.mesher {
        Mesher::Stuffing => {
            let sizing = thin_part_sizing(surface, &distance, h);
            let thin_points = sizing.len();
            let domain = SurfaceDomain {
                distance: &distance,
                side,
                centre,
                radius,
                bounds: (lo, hi),
                sizing,
            };
            let stuffing = StuffingOptions {
                h,
                refine_levels: options.refine_levels,
            };
            let stuffed = volume::stuff_volume(&domain, &stuffing)?;
            (stuffed.mesh, Some(stuffed.stats), thin_points)
        }
        Mesher::Tetgen => (tetgen_mesh(surface, side, centre, radius)?, None, 0),
    };
    // With several surface components a pocket may be a real cavity: keep them all.
    let connected = Topology::new(surface).components(surface).1 == 1;
    let dropped_pockets = if side == Side::Outside && connected {
        drop_enclosed_pockets(&mut mesh)
    } else {
        0
    };
    let hausdorff = hausdorff_to_surface(&mesh, &distance) / diagonal;

    Ok(VolumeResult {
        mesh,
        side,
        h,
        sphere: (side == Side::Outside).then_some((centre, radius)),
        mesher: options.mesher,
        stats,
        thin_points,
        dropped_pockets,
        hausdorff_to_surface: hausdorff,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The distance field of the method (paper sec. 3): the exact distance from every
/// vertex of `mesh` to `surface`, 0 on surface-kind vertices. Outer-sphere vertices keep
/// their true distance (a Dirichlet value that lets the field keep rising to the
/// sphere; setting them to 0 would make a ridge of spurious critical points halfway
/// out).
pub fn distance_field(surface: &SurfaceMesh, mesh: &TetMesh) -> Vec<f64> {
    let distance = SurfaceDistance::new(surface);
    let mut f = distance.distances(&mesh.positions);
    for (value, kind) in f.iter_mut().zip(&mesh.kinds) {
        if *kind == VertexKind::Surface {
            *value = 0.0;
        }
    }
    f
}

/// The critical points of one side: the distance field of `volume`'s mesh to
/// `surface`, smoothed, classified, tracked, and its neck 2-saddles selected
/// (`morse::analyze`).
pub fn critical_points(
    surface: &SurfaceMesh,
    volume: &VolumeResult,
    options: &MorseOptions,
) -> Result<MorseResult> {
    let field = distance_field(surface, &volume.mesh);
    morse::analyze(&volume.mesh, &field, options)
}

/// What `necklace critical --json` prints: the volume mesh's summary and the Morse
/// stage's result, with what the input surface's topology predicts for the Morse sum.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalReport<'a> {
    /// Which side.
    pub side: Side,
    /// The volume mesh the field lives on.
    pub volume: VolumeReport,
    /// `Σ_i (g_i − 1)` inside, one more outside, over the input surface's components:
    /// the Morse sum when the volume mesh has the surface's topology (`None` when a
    /// component's genus is unknown). Each step's `morse_expected` comes from the mesh
    /// itself; the two differ when the mesher changed the topology (see `volume`).
    pub surface_morse_expected: Option<i64>,
    /// Smoothing, per-step counts and checks, selected and rejected 2-saddles.
    #[serde(flatten)]
    pub morse: &'a MorseResult,
}

/// The Morse sum a surface's topology predicts for one side (see
/// [`CriticalReport::surface_morse_expected`]).
pub fn surface_morse_expected(report: &MeshReport, side: Side) -> Option<i64> {
    let mut sum = i64::from(side == Side::Outside);
    for component in &report.component_details {
        sum += component.genus? - 1;
    }
    Some(sum)
}

/// The critical points of a Morse result as a point cloud: every critical point at the
/// last step with its `type` (0 minimum, 1 1-saddle, 2 2-saddle, 3 maximum, 4
/// degenerate), `selected` (1 for the selected 2-saddles) and `persistence` (steps
/// survived); colours blue maxima, red 2-saddles, green 1-saddles, black the rest, and
/// yellow the selected 2-saddles.
pub fn critical_point_cloud(result: &MorseResult) -> io::PointCloud {
    let mut cloud = io::PointCloud::default();
    let mut kinds = Vec::new();
    let mut selected = Vec::new();
    let mut persistence = Vec::new();
    let mut colors = Vec::new();
    for track in result.tracks.iter().filter(|t| t.alive) {
        let is_selected = result.saddles.iter().any(|s| s.vertex == track.vertex);
        let (code, color) = match track.kind {
            VertexType::Minimum => (0.0, [0, 0, 0]),
            VertexType::Saddle1 => (1.0, [0, 160, 0]),
            VertexType::Saddle2 if is_selected => (2.0, [255, 210, 0]),
            VertexType::Saddle2 => (2.0, [220, 0, 0]),
            VertexType::Maximum => (3.0, [0, 60, 220]),
            _ => (4.0, [0, 0, 0]),
        };
        cloud.positions.push(track.position);
        kinds.push(code);
        selected.push(if is_selected { 1.0 } else { 0.0 });
        persistence.push(track.persistence() as f64);
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

/// Drop the components of a shell that reach no outer-sphere vertex: the shell around
/// a *connected* surface is connected, so such pockets are gaps below the lattice
/// resolution. Returns how many were dropped.
fn drop_enclosed_pockets(mesh: &mut TetMesh) -> usize {
    let (component, count) = mesh.tet_components();
    if count < 2 {
        return 0;
    }
    let mut reaches_outer = vec![false; count];
    for (t, tet) in mesh.tets.iter().enumerate() {
        if tet
            .iter()
            .any(|&v| mesh.kinds[v as usize] == VertexKind::Outer)
        {
            reaches_outer[component[t] as usize] = true;
        }
    }
    let keep: Vec<bool> = component
        .iter()
        .map(|&c| reaches_outer[c as usize])
        .collect();
    *mesh = mesh.retain_tets(&keep);
    reaches_outer.iter().filter(|&&r| !r).count()
}

/// Largest distance of a surface-kind vertex of `mesh` to the input surface.
fn hausdorff_to_surface(mesh: &TetMesh, distance: &SurfaceDistance) -> f64 {
    let surface_vertices: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .zip(&mesh.kinds)
        .filter(|(_, k)| **k == VertexKind::Surface)
        .map(|(p, _)| *p)
        .collect();
    distance
        .distances(&surface_vertices)
        .into_iter()
        .fold(0.0, f64::max)
}

#[cfg(feature = "tetgen")]
fn tetgen_mesh(
    surface: &SurfaceMesh,
    side: Side,
    centre: [f64; 3],
    radius: f64,
) -> Result<TetMesh> {
    match side {
        Side::Inside => crate::tetgen::mesh_inside(surface),
        Side::Outside => crate::tetgen::mesh_shell(surface, centre, radius),
    }
}

#[cfg(not(feature = "tetgen"))]
fn tetgen_mesh(_: &SurfaceMesh, _: Side, _: [f64; 3], _: f64) -> Result<TetMesh> {
    Err(Error::invalid_argument(
        "this necklace was built without the `tetgen` feature (cargo build --features tetgen; AGPL-3.0)",
    ))
}

/// One side of a surface as an implicit domain for the stuffing mesher.
struct SurfaceDomain<'a> {
    distance: &'a SurfaceDistance,
    side: Side,
    centre: [f64; 3],
    radius: f64,
    bounds: ([f64; 3], [f64; 3]),
    sizing: Vec<([f64; 3], f64)>,
}

impl SurfaceDomain<'_> {
    fn sphere_value(&self, p: [f64; 3]) -> f64 {
        norm(sub(p, self.centre)) - self.radius
    }

    /// Whether `p` is nearer the outer sphere than the surface.
    fn nearer_the_sphere(&self, p: [f64; 3]) -> bool {
        let to_sphere = self.sphere_value(p).abs();
        let limit = to_sphere + 1e-12 * self.radius;
        self.distance.distance_within(p, limit) > to_sphere
    }

    fn combine(&self, p: [f64; 3], signed: f64) -> f64 {
        match self.side {
            Side::Inside => signed,
            Side::Outside => (-signed).max(self.sphere_value(p)),
        }
    }
}

impl Domain for SurfaceDomain<'_> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.combine(p, self.distance.signed_distance(p))
    }

    fn values(&self, points: &[[f64; 3]]) -> Vec<f64> {
        let signed = self.distance.signed_distances(points);
        points
            .iter()
            .zip(signed)
            .map(|(&p, s)| self.combine(p, s))
            .collect()
    }

    fn values_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        let signed = self.distance.signed_distances_within(points, band);
        points
            .iter()
            .zip(signed)
            .map(|(&p, s)| self.combine(p, s))
            .collect()
    }

    fn crossing(&self, a: [f64; 3], b: [f64; 3]) -> Option<f64> {
        let (sa, sb) = (self.sphere_value(a), self.sphere_value(b));
        if self.side == Side::Outside && (sa < 0.0) != (sb < 0.0) {
            // The outer sphere: solve |a + t (b − a) − c| = R.
            let d = sub(b, a);
            let m = sub(a, self.centre);
            let (qa, qb, qc) = (
                dot(d, d),
                2.0 * dot(m, d),
                dot(m, m) - self.radius * self.radius,
            );
            let disc = qb * qb - 4.0 * qa * qc;
            if qa <= 0.0 || disc < 0.0 {
                return None;
            }
            let roots = [
                (-qb - disc.sqrt()) / (2.0 * qa),
                (-qb + disc.sqrt()) / (2.0 * qa),
            ];
            return roots.into_iter().find(|t| *t > 0.0 && *t < 1.0);
        }
        // The surface: the first hit of the segment. A segment through a hole of an
        // open mesh hits nothing; the mesher then searches the winding-number jump.
        self.distance.ray_hit(a, sub(b, a), 1.0).map(|(t, _)| t)
    }

    fn boundary_kind(&self, p: [f64; 3]) -> VertexKind {
        match self.side {
            Side::Inside => VertexKind::Surface,
            Side::Outside => {
                if self.nearer_the_sphere(p) {
                    VertexKind::Outer
                } else {
                    VertexKind::Surface
                }
            }
        }
    }

    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        match self.side {
            Side::Inside => self.bounds,
            Side::Outside => (
                self.centre.map(|c| c - self.radius),
                self.centre.map(|c| c + self.radius),
            ),
        }
    }

    fn sizing(&self) -> Vec<([f64; 3], f64)> {
        self.sizing.clone()
    }

    fn coarsest_spacing(&self, h: f64) -> f64 {
        match self.side {
            Side::Inside => h,
            Side::Outside => (self.radius / 8.0).max(h),
        }
    }

    fn spacing_near(&self, p: [f64; 3], h: f64) -> f64 {
        // The outer sphere is only a container: an eighth of its radius is detail enough.
        if self.side == Side::Outside && self.sphere_value(p).abs() < self.distance.distance(p) {
            (self.radius / 8.0).max(h)
        } else {
            h
        }
    }
}

/// Where the solid or a gap between parts of the surface is thinner than `3h`, ask for
/// spacing ≤ thickness / 3 so that lattice vertices stay strictly inside after warping
/// (warping moves a vertex by up to 0.41 of an edge). Thickness at a surface vertex: the distance along the inward and the
/// outward vertex normal to the next surface hit.
fn thin_part_sizing(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    h: f64,
) -> Vec<([f64; 3], f64)> {
    let mut normals = vec![[0.0; 3]; surface.num_vertices()];
    for f in 0..surface.num_triangles() {
        let n = surface.face_normal_scaled(f);
        for &v in &surface.triangles[f] {
            normals[v as usize] = add(normals[v as usize], n);
        }
    }
    // Both sides matter whichever side is meshed: a thin solid part is lost from the
    // shell just as a thin gap is lost from the solid.
    let mut out = Vec::new();
    for (v, &p) in surface.positions.iter().enumerate() {
        let len = norm(normals[v]);
        if len.is_nan() || len <= 0.0 {
            continue;
        }
        for direction in [-1.0, 1.0] {
            let d = scale(normals[v], direction / len);
            let origin = add(p, scale(d, 1e-6 * h));
            if let Some((t, _)) = distance.ray_hit(origin, d, 3.0 * h) {
                let spacing = t / 3.0;
                out.push((p, spacing));
                out.push((add(p, scale(d, 0.5 * t)), spacing));
            }
        }
    }
    out
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
        assert!(!ok.flipped);
        mesh.flip_orientation();
        let fixed = prepare_surface(mesh).unwrap();
        assert!(fixed.flipped);
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

/// Options of [`find_necks`]: which sides, and each stage's options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeckOptions {
    /// Look for handles (inside). Default true.
    pub handles: bool,
    /// Look for tunnels (outside). Default true.
    pub tunnels: bool,
    /// Volume meshing.
    pub volume: VolumeOptions,
    /// Smoothing, classification and saddle selection.
    pub morse: MorseOptions,
    /// Plane cut, tightening and loop selection.
    pub loops: LoopOptions,
    /// Keep each side's volume mesh and smoothed field in the report
    /// ([`SideReport::field`]), e.g. to write `field.vtu`. Default false (they can be
    /// large).
    pub keep_volume: bool,
}

impl Default for NeckOptions {
    fn default() -> Self {
        NeckOptions {
            handles: true,
            tunnels: true,
            volume: VolumeOptions::default(),
            morse: MorseOptions::default(),
            loops: LoopOptions::default(),
            keep_volume: false,
        }
    }
}

/// Wall-clock seconds per stage of one side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTimings {
    /// Volume mesh.
    pub volume_mesh: f64,
    /// Exact distance field on its vertices.
    pub distance: f64,
    /// Assembly and heat steps.
    pub smoothing: f64,
    /// Classification, tracking and the Hessian test.
    pub critical_points: f64,
    /// Plane cuts, tightening and selection.
    pub loops: f64,
    /// Sum of the above.
    pub total: f64,
}

/// The Morse check of one side: every classified step, and whether all held.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MorseCheck {
    /// Which side.
    pub side: Side,
    /// Whether `morse_sum == morse_expected` at every step.
    pub ok: bool,
    /// What the surface's genus predicts (see [`CriticalReport`]).
    pub surface_morse_expected: Option<i64>,
    /// The mesh's own expectation (χ of its subcomplexes).
    pub morse_expected: morse::MorseExpectation,
    /// Per-step counts and checks.
    pub steps: Vec<morse::StepSummary>,
}

/// One side's intermediate results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SideReport {
    /// Which side.
    pub side: Side,
    /// The volume mesh's summary.
    pub volume: VolumeReport,
    /// Interior vertices (unknowns of the heat system).
    pub unknowns: usize,
    /// The selected 2-saddles (the loops' seeds, in this order).
    pub saddles: Vec<morse::Saddle>,
    /// 2-saddles not selected, with reasons.
    pub rejected: Vec<morse::RejectedSaddle>,
    /// Seconds per stage.
    pub timings: StageTimings,
    /// Every critical point alive at the last step, with type, selection and
    /// persistence (see [`critical_point_cloud`]); not in the JSON.
    #[serde(skip)]
    pub critical: io::PointCloud,
    /// The volume mesh and the smoothed field on it, with
    /// [`NeckOptions::keep_volume`]; not in the JSON.
    #[serde(skip)]
    pub field: Option<VolumeField>,
}

/// A volume mesh with a scalar per vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeField {
    /// The tet mesh.
    pub mesh: TetMesh,
    /// One value per vertex.
    pub values: Vec<f64>,
}

/// What [`find_necks`] found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NeckReport {
    /// Handle loops, then tunnel loops, each by persistence then length.
    pub loops: Vec<NeckLoop>,
    /// Saddles that gave no kept loop, with reasons (`Duplicate::of` indexes `loops`).
    pub dropped: Vec<DroppedLoop>,
    /// The Morse check of each side.
    pub morse: Vec<MorseCheck>,
    /// Seconds per stage, per side, and the sum over sides.
    pub timings: NeckTimings,
    /// Per side: volume mesh, saddles, stage timings.
    pub sides: Vec<SideReport>,
    /// Whether the input faces pointed inward and were flipped before meshing.
    pub flipped: bool,
}

/// Stage timings per side and in total.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct NeckTimings {
    /// Inside (handles), when run.
    pub handles: Option<StageTimings>,
    /// Outside (tunnels), when run.
    pub tunnels: Option<StageTimings>,
    /// Sum over the sides run.
    pub total: StageTimings,
}

/// The loop stage's seeds from the Morse stage's selected 2-saddles, in their order:
/// the plane through each saddle's fitted position with its Hessian's positive
/// eigenvector as normal.
pub fn loop_seeds(result: &MorseResult) -> Vec<Seed> {
    result
        .saddles
        .iter()
        .map(|s| Seed {
            position: s.position,
            normal: s.normal,
            persistence: s.persistence,
        })
        .collect()
}

/// The whole method on a closed, outward-oriented surface (see [`prepare_surface`]):
/// for each side asked for, volume mesh → distance field → smoothing and critical
/// points → neck loops on `surface`.
pub fn find_necks(surface: &SurfaceMesh, options: &NeckOptions) -> Result<NeckReport> {
    find_necks_with_progress(surface, options, &Silent)
}

/// [`find_necks`], reporting the stages that can take long (volume mesh, distance,
/// smoothing steps, tightening) to `progress`.
pub fn find_necks_with_progress(
    surface: &SurfaceMesh,
    options: &NeckOptions,
    progress: &dyn Progress,
) -> Result<NeckReport> {
    if !options.handles && !options.tunnels {
        return Err(Error::invalid_argument(
            "nothing to do: ask for handles, tunnels or both",
        ));
    }
    if surface.triangles.is_empty() {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            "the surface has no triangles",
        ));
    }
    // Inward-facing input is turned round rather than meshed inside out (a copy only
    // then).
    let surface_report = MeshReport::new(surface);
    let flipped = surface_report.signed_volume < 0.0;
    let turned;
    let surface = if flipped {
        turned = orient_for_volume(surface.clone()).0;
        &turned
    } else {
        surface
    };
    let mut report = NeckReport {
        loops: Vec::new(),
        dropped: Vec::new(),
        morse: Vec::new(),
        timings: NeckTimings::default(),
        sides: Vec::new(),
        flipped,
    };
    let sides = [
        (Side::Inside, options.handles),
        (Side::Outside, options.tunnels),
    ];
    for (side, wanted) in sides {
        if !wanted {
            continue;
        }
        let kind = match side {
            Side::Inside => LoopKind::Handle,
            Side::Outside => LoopKind::Tunnel,
        };
        let name = match side {
            Side::Inside => "inside",
            Side::Outside => "outside",
        };
        progress.start(&format!("volume mesh ({name})"), 0);
        let volume = volume_mesh(surface, side, &options.volume);
        progress.finish();
        let volume = volume?;
        progress.start(&format!("distance ({name})"), 0);
        let start = Instant::now();
        let field = distance_field(surface, &volume.mesh);
        let distance_seconds = start.elapsed().as_secs_f64();
        progress.finish();
        let result = morse::analyze_with_progress(&volume.mesh, &field, &options.morse, progress)?;
        let found = loops::find_loops_with_progress(
            surface,
            &loop_seeds(&result),
            kind,
            &options.loops,
            progress,
        )?;

        let t = &result.timings;
        let l = &found.timings;
        let mut timings = StageTimings {
            volume_mesh: volume.seconds,
            distance: distance_seconds,
            smoothing: t.assembly + t.smoothing,
            critical_points: t.classification + t.selection,
            loops: l.preparation + l.cut_and_tighten + l.selection,
            total: 0.0,
        };
        timings.total = timings.volume_mesh
            + timings.distance
            + timings.smoothing
            + timings.critical_points
            + timings.loops;
        let sum = &mut report.timings.total;
        sum.volume_mesh += timings.volume_mesh;
        sum.distance += timings.distance;
        sum.smoothing += timings.smoothing;
        sum.critical_points += timings.critical_points;
        sum.loops += timings.loops;
        sum.total += timings.total;
        match side {
            Side::Inside => report.timings.handles = Some(timings),
            Side::Outside => report.timings.tunnels = Some(timings),
        }

        report.morse.push(MorseCheck {
            side,
            ok: result.morse_failures().next().is_none(),
            surface_morse_expected: surface_morse_expected(&surface_report, side),
            morse_expected: result.morse_expected,
            steps: result.steps.clone(),
        });
        // Loops of this side follow those already listed: shift duplicate references.
        let offset = report.loops.len();
        report
            .dropped
            .extend(found.dropped.into_iter().map(|mut d| {
                if let DropReason::Duplicate { of, .. } = &mut d.reason {
                    *of += offset;
                }
                d
            }));
        report.loops.extend(found.loops);
        report.sides.push(SideReport {
            side,
            volume: volume.report(),
            unknowns: result.unknowns,
            critical: critical_point_cloud(&result),
            saddles: result.saddles,
            rejected: result.rejected,
            timings,
            field: options.keep_volume.then_some(VolumeField {
                mesh: volume.mesh,
                values: result.field,
            }),
        });
    }
    Ok(report)
}
