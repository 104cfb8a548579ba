//! The volume stage on a surface: one side of a closed surface as an implicit domain
//! ([`SurfaceInside`](super::SurfaceInside), in a [`Shell`](super::Shell) for the
//! outside), the sizing that resolves its thin parts and gaps
//! (`surface_sizing`), the mesher call, and the check that the mesh has the topology the
//! surface predicts (`prediction`), refining where it does not. TetGen, the paper's
//! mesher, is the alternative behind the `tetgen` feature (`volume::tetgen`).
//!
//! Topology comes first: necks are read off the volume mesh, so an extra tunnel through
//! a thin wall or a lost thin part is an extra or missing neck. [`volume_mesh`] (steps
//! 1–3 are the same for both sides: [`survey_surface`] makes them once, and
//! [`volume_mesh_surveyed`] does step 4 for one side):
//! 1. predicts the topology ([`expected_topology`]): per component of the inside (or of
//!    the shell) its χ and the χ of each boundary surface, from the surface's
//!    components, their genus and how they nest;
//! 2. measures at every surface vertex the thickness of the solid and the width of the
//!    gap in front of it (a ray along the vertex normal, then the inscribed ball touching
//!    there: the medial distance, which sees a wire's diameter where the ray sees a
//!    chord) and asks for cells half of that wherever it is below `2h`
//!    ([`SizingFeature`]s over the thin triangles, reaching into the part; no fixed
//!    floor where the topology is predicted: the memory budget sets it; where it is
//!    not, [`VolumeOptions::unchecked_min_cell`] × h, with a warning when it binds).
//!    Folds of the surface and places where it crosses itself are not parts, and are
//!    skipped;
//! 3. finds the creases and corners for the mesher to snap its boundary onto;
//! 4. meshes (`volume::stuff_volume`) and compares the mesh's topology with the
//!    prediction. Where they differ, it meshes again sized by the thickness sampled over
//!    the triangles too (`surface_sizing::sample_thickness`: long triangles, and where
//!    it changes between corners, such as a plate's thin rim drawn with triangles that
//!    reach across the plate; made once, for the first side that asks), then refines
//!    where the mesh shows why (pinches, swallowed boundary vertices, and surface
//!    vertices the mesh's boundary does not come near) and meshes again, up to
//!    [`MAX_ROUNDS`] meshings, keeping the mesh closest to the prediction. A difference
//!    that remains, or a budget that bound, is reported in [`VolumeResult::warnings`]
//!    with the figures, never dropped.
//!
//! Conventions: lengths in the surface's units; the outer sphere of a shell is centred
//! at the bounding box's centre with radius `sphere_scale` × half its diagonal.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::prediction::predict;
use super::refined::RefinedStats;
use super::sampled::SampledStats;
use super::surface_sizing::{
    measure_surface, sample_thickness, sharp_features, thin_part_sizing, ThicknessSamples,
    CELLS_ACROSS, MAX_SAMPLES, THIN_FACTOR,
};
use super::{
    spacing_floor, stuff_volume, SharpFeatures, Shell, SizingFeature, StuffingOptions,
    StuffingStats, SurfaceInside, VolumeMesh, DEFAULT_MAX_MEMORY,
};
use crate::distance::SurfaceDistance;
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, norm, scale, sub};
use crate::mesh::{MeshReport, Side, SurfaceMesh, Topology};
use crate::tet::{TetMesh, TetTopology, VertexKind};

/// Which volume mesher to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mesher {
    /// necklace's isosurface stuffing (default).
    Stuffing,
    /// TetGen with the paper's switches "pq1.2"; needs the `tetgen` cargo feature
    /// (AGPL-3.0).
    Tetgen,
    /// The Delaunay tetrahedralization of points sampled on the surface at its
    /// thickness and graded inside, carved by the surface (`sampled`; experimental).
    Sampled,
    /// Restricted Delaunay refinement from the same samples: cells labelled by the
    /// surface, refined until the boundary's faces and the cells are well shaped
    /// (`refined`; experimental).
    Refined,
}

/// Options of [`volume_mesh`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VolumeOptions {
    /// The mesher (default [`Mesher::Stuffing`]).
    pub mesher: Mesher,
    /// Lattice spacing along the surface, in the surface's units. `None` (default):
    /// [`default_h`]. Thin parts and gaps get finer cells whatever `h` is.
    pub h: Option<f64>,
    /// Outer sphere radius as a multiple of the bounding box's half diagonal (default
    /// 1.5), centred at the box centre.
    pub sphere_scale: f64,
    /// The memory budget of the mesh, in bytes (default 8 GB): tets at
    /// [`BYTES_PER_TET`](super::BYTES_PER_TET) each. Thin parts are not refined past
    /// it (a warning gives the floor), refinement for topology stops at it, and a mesh
    /// estimated above it even so is refused with the estimate, before the lattice is
    /// allocated. A run that meshes both sides gives each half
    /// (`pipeline::NeckOptions`).
    pub max_memory: u64,
    /// The quality step's target smallest dihedral angle, degrees (default 10).
    pub min_dihedral_deg: f64,
    /// The finest cell the stuffing mesher asks for on a side whose topology the
    /// surface does not predict (it crosses itself, or a component has no genus), as a
    /// fraction of `h` (default 0.25; 0 turns the bound off). There no topology check
    /// confirms what finer cells resolve, and the gaps measured at crossings, at
    /// vertices buried in another part and at slivers would otherwise set the cell size
    /// for the whole side; a warning gives the figures when the bound binds.
    pub unchecked_min_cell: f64,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            mesher: Mesher::Stuffing,
            h: None,
            sphere_scale: 1.5,
            max_memory: DEFAULT_MAX_MEMORY,
            min_dihedral_deg: 10.0,
            unchecked_min_cell: 0.25,
        }
    }
}

/// Most meshings of one side: the first, the one sized by the sampled thickness, and
/// refinements while the topology differs from the surface's.
pub const MAX_ROUNDS: usize = 5;

/// Cells along the curve where the surface crosses itself are this many times finer
/// than `h` (where [`VolumeOptions::unchecked_min_cell`] allows: such a side has no
/// predicted topology, and the default bound is h/4).
const CROSSING_REFINEMENT: f64 = 8.0;

/// The largest lattice spacing accepted, as a fraction of the bounding-box diagonal.
const MAX_H_FRACTION: f64 = 0.25;

/// The inside mesh's volume may differ from the volume the surface encloses by this
/// fraction before a warning says so (the boundary's chords cut off a little).
const VOLUME_TOLERANCE: f64 = 0.05;

/// A volume mesh of one side of a surface, with what describes it.
#[derive(Debug, Clone)]
pub struct VolumeResult {
    /// The tet mesh (vertex kinds: interior, surface, outer sphere).
    pub mesh: TetMesh,
    /// Which side.
    pub side: Side,
    /// The spacing used along the surface away from thin parts.
    pub h: f64,
    /// Centre and radius of the outer sphere (outside only).
    pub sphere: Option<([f64; 3], f64)>,
    /// The mesher used.
    pub mesher: Mesher,
    /// The memory budget it was meshed within, bytes.
    pub budget: u64,
    /// Whether that budget bound: it floored the cells of thin parts in one of the
    /// meshings, or refused a meshing the topology rounds asked for (a larger budget
    /// may give another mesh; when false, any larger budget gives this mesh).
    pub budget_bound: bool,
    /// The stuffing mesher's counts of the last round (`None` for TetGen).
    pub stats: Option<StuffingStats>,
    /// What the sampled mesher did (with [`Mesher::Sampled`]).
    pub sampled: Option<SampledStats>,
    /// What the refinement mesher did (with [`Mesher::Refined`]).
    pub refined: Option<RefinedStats>,
    /// Surface vertices whose part or gap is thinner than `2h`.
    pub thin_vertices: usize,
    /// Points on the surface's triangles where the thickness was measured besides
    /// its vertices (long triangles, and where it changes between corners), when the
    /// mesh was sized by them; 0 when sized by the vertices alone.
    pub thickness_samples: usize,
    /// The topology predicted from the surface and the one found.
    pub topology: TopologyCheck,
    /// Largest distance of a surface-kind vertex to the input surface, divided by the
    /// bounding-box diagonal.
    pub hausdorff_to_surface: f64,
    /// What the caller should know: a topology that still differs from the surface's,
    /// tets left below the dihedral target. One line each.
    pub warnings: Vec<String>,
    /// Wall-clock seconds, all rounds.
    pub seconds: f64,
}

/// The volume mesh's topology against the surface's prediction.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopologyCheck {
    /// What the surface predicts (`None` when it cannot: a component whose genus is
    /// undefined, or components that cross each other).
    pub expected: Option<TetTopology>,
    /// What the mesh has.
    pub found: TetTopology,
    /// Whether they agree (`None` without a prediction).
    pub matches: Option<bool>,
    /// Meshings done (1 when the first had the right topology).
    pub rounds: usize,
}

/// The default spacing: 1/64 of the bounding-box diagonal. Parts and gaps thinner
/// than `2h` are refined locally, so the rule needs no knowledge of the thinnest part.
pub fn default_h(surface: &SurfaceMesh) -> f64 {
    surface.bbox_diagonal() / 64.0
}

/// The summary of a volume mesh that `necklace volume --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// Connected components of the tet mesh.
    pub components: usize,
    /// Connected components of its boundary.
    pub boundary_components: usize,
    /// The topology against the surface's prediction.
    pub topology: TopologyCheck,
    /// Smallest dihedral angle, degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle, degrees.
    pub max_dihedral_deg: f64,
    /// All dihedral angles (six per tet) in 5° bins: `[0, 5)`, `[5, 10)`, … `[175, 180]`.
    pub dihedral_histogram: Vec<usize>,
    /// Tets whose smallest dihedral angle is below 8°, and below 10°.
    pub tets_below_8_deg: usize,
    /// Tets whose smallest dihedral angle is below 10°.
    pub tets_below_10_deg: usize,
    /// Largest distance of a surface vertex to the input surface / bbox diagonal.
    pub hausdorff_to_surface: f64,
    /// Sum of tet volumes.
    pub volume: f64,
    /// The mesher used.
    pub mesher: Mesher,
    /// The memory budget it was meshed within, bytes.
    #[serde(default)]
    pub budget: u64,
    /// Whether that budget bound (see [`VolumeResult::budget_bound`]).
    #[serde(default)]
    pub budget_bound: bool,
    /// Lattice spacing along the surface (stuffing).
    pub h: f64,
    /// Smallest cell used (thin parts; stuffing).
    pub finest_cell: f64,
    /// Surface vertices whose part or gap is thinner than `2h`.
    pub thin_vertices: usize,
    /// Points on the surface's triangles where the thickness was measured besides
    /// its vertices, when the mesh was sized by them (else 0).
    pub thickness_samples: usize,
    /// The stuffing mesher's counts (last round; absent for TetGen).
    pub stuffing: Option<StuffingStats>,
    /// What the sampled mesher did (with [`Mesher::Sampled`]).
    pub sampled: Option<SampledStats>,
    /// What the refinement mesher did (with [`Mesher::Refined`]).
    pub refined: Option<RefinedStats>,
    /// One line per thing to know (see [`VolumeResult::warnings`]).
    pub warnings: Vec<String>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl VolumeResult {
    /// Counts, invariants and quality of the mesh.
    pub fn report(&self) -> VolumeReport {
        let m = &self.mesh;
        let (interior, surface, outer) = m.kind_counts();
        let mut histogram = vec![0usize; 36];
        let (mut below_8, mut below_10) = (0, 0);
        let (mut lo, mut hi) = (180.0f64, 0.0f64);
        for t in 0..m.num_tets() {
            let angles = crate::tet::dihedral_angles_deg(m.corners(t));
            let smallest = angles.iter().copied().fold(180.0, f64::min);
            below_8 += usize::from(smallest < 8.0);
            below_10 += usize::from(smallest < 10.0);
            for a in angles {
                histogram[((a / 5.0) as usize).min(35)] += 1;
                lo = lo.min(a);
                hi = hi.max(a);
            }
        }
        if m.num_tets() == 0 {
            (lo, hi) = (0.0, 0.0);
        }
        let found = &self.topology.found;
        VolumeReport {
            side: self.side,
            vertices: m.num_vertices(),
            tets: m.num_tets(),
            interior_vertices: interior,
            surface_vertices: surface,
            outer_vertices: outer,
            euler_volume: found.euler(),
            euler_boundary: found.boundary_euler(),
            components: found.components.len(),
            boundary_components: found.boundary_components(),
            topology: self.topology.clone(),
            min_dihedral_deg: lo,
            max_dihedral_deg: hi,
            dihedral_histogram: histogram,
            tets_below_8_deg: below_8,
            tets_below_10_deg: below_10,
            hausdorff_to_surface: self.hausdorff_to_surface,
            volume: m.volume(),
            mesher: self.mesher,
            budget: self.budget,
            budget_bound: self.budget_bound,
            h: self.h,
            finest_cell: self.stats.map_or(0.0, |s| s.finest_cell),
            thin_vertices: self.thin_vertices,
            thickness_samples: self.thickness_samples,
            stuffing: self.stats,
            sampled: self.sampled,
            refined: self.refined,
            warnings: self.warnings.clone(),
            seconds: self.seconds,
        }
    }
}

/// Mesh one side of a closed, outward-oriented surface (see the module doc).
pub fn volume_mesh(
    surface: &SurfaceMesh,
    side: Side,
    options: &VolumeOptions,
) -> Result<VolumeResult> {
    let start = Instant::now();
    check_surface(surface)?;
    let distance = SurfaceDistance::of_surface(surface);
    let mut result = volume_mesh_with(surface, &distance, side, options)?;
    result.seconds = start.elapsed().as_secs_f64();
    Ok(result)
}

/// [`volume_mesh`] with the surface's distance structure built by the caller
/// ([`SurfaceDistance::of_surface`]: one per run, shared with the other stages).
pub fn volume_mesh_with(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    side: Side,
    options: &VolumeOptions,
) -> Result<VolumeResult> {
    let start = Instant::now();
    let survey = survey_surface(surface, distance, &MeshReport::new(surface), options)?;
    let mut result = volume_mesh_surveyed(surface, distance, &survey, side)?;
    result.seconds = start.elapsed().as_secs_f64();
    Ok(result)
}

/// What the volume stage measures on a surface before it meshes a side (steps 1–3 of
/// the module doc, and the crossing pairs of triangles). None of it depends on the
/// side, so a run that meshes both sides surveys once ([`survey_surface`]) and meshes
/// each from the survey ([`volume_mesh_surveyed`]); on a dense surface the survey is
/// most of the stage (a ray and an inscribed ball at every vertex).
#[derive(Debug, Clone)]
pub struct SurfaceSurvey {
    /// The options it was made for (the lattice spacing `h` resolved in `h`).
    pub options: VolumeOptions,
    /// The lattice spacing along the surface.
    pub h: f64,
    /// Surface vertices whose part or gap is thinner than `2h` (0 for TetGen, which
    /// is not sized).
    pub thin_vertices: usize,
    /// The surface's report (components, genus: the prediction's input).
    report: MeshReport,
    /// The crossing pairs of triangles.
    crossings: Vec<[u32; 2]>,
    /// What the stuffing mesher sizes and snaps by (`None` for TetGen).
    sizing: Option<SurfaceSizing>,
}

/// The stuffing mesher's part of a [`SurfaceSurvey`].
#[derive(Debug, Clone)]
struct SurfaceSizing {
    /// The lattice spacing the thickness was measured for (thin below `THIN_FACTOR` × h).
    h: f64,
    /// The thickness at the vertices and at the faces they do not see
    /// ([`measure_surface`]): where [`sample_thickness`] starts.
    measured: ThicknessSamples,
    /// Per vertex, the cell size asked for (half the thinner of the two, at most `h`).
    spacing: Vec<f64>,
    /// Thin parts and gaps as measured at the vertices and faces, and the crossing curve,
    /// as sizing features: for the mesh of the solid (0), of the gap (1), and of the
    /// solid without the gaps' floor (2: a side whose topology is not predicted, where
    /// no check would find a gap bridged at one cell across; see
    /// [`super::surface_sizing::GAP_FLOOR_OF_H`]).
    sizing: [Vec<SizingFeature>; 3],
    /// The crossing curve's sizing features alone.
    crossing_sizing: Vec<SizingFeature>,
    /// Vertices whose thickness is not measured (at crossings).
    skip: Vec<bool>,
    /// The sizing by the thickness sampled over the triangles too, for each side as
    /// `sizing`: made the first time the side asks (its vertices' sizing gave another
    /// topology).
    sampled: [std::sync::OnceLock<SampledSizing>; 3],
    /// The thickness sampled over the triangles ([`sample_thickness`]): made the first
    /// time a side asks (the sampled sizing, or the sampled mesher), then shared.
    samples: std::sync::OnceLock<ThicknessSamples>,
    /// Creases, corners and the crossing curve to snap onto.
    features: SharpFeatures,
    /// The surface's adjacency, for sampling.
    topology: Topology,
}

/// Survey a closed, outward-oriented surface for meshing its sides with `options`
/// (`report`: the surface's [`MeshReport`]; `distance`: its distance structure). Checks
/// the options first.
pub fn survey_surface(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    report: &MeshReport,
    options: &VolumeOptions,
) -> Result<SurfaceSurvey> {
    let (lo, hi) = check_surface(surface)?;
    let diagonal = norm(sub(hi, lo));
    let h = options.h.unwrap_or_else(|| default_h(surface));
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::invalid_argument(format!("h = {h} must be positive")));
    }
    if h > MAX_H_FRACTION * diagonal {
        return Err(Error::invalid_argument(format!(
            "h = {h:.3e} is above a quarter of the surface's bounding-box diagonal ({diagonal:.3e}): no lattice that coarse resolves the surface (the default is diagonal / 64)"
        )));
    }
    if !(options.sphere_scale > 1.0 && options.sphere_scale.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "sphere_scale = {} must exceed 1 (the sphere must enclose the surface)",
            options.sphere_scale
        )));
    }
    if !(0.0..=1.0).contains(&options.unchecked_min_cell) {
        return Err(Error::invalid_argument(format!(
            "unchecked_min_cell = {} must lie in [0, 1] (a fraction of h; 0 turns it off)",
            options.unchecked_min_cell
        )));
    }
    let crossings = match distance.crossings() {
        Some(recorded) => recorded.to_vec(),
        None => distance.self_intersections(&surface.triangles),
    };
    let sizing = match options.mesher {
        Mesher::Stuffing | Mesher::Sampled | Mesher::Refined => {
            Some(size_surface(surface, distance, &crossings, h))
        }
        Mesher::Tetgen => None,
    };
    let thin_vertices = sizing.as_ref().map_or(0, |s| {
        s.thickness()
            .iter()
            .filter(|t| t.iter().any(|x| x.is_finite()))
            .count()
    });
    Ok(SurfaceSurvey {
        options: *options,
        h,
        thin_vertices,
        report: report.clone(),
        crossings,
        sizing,
    })
}

/// Mesh one side of a surveyed surface (`surface` and `distance`: those the survey was
/// made of).
pub fn volume_mesh_surveyed(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    survey: &SurfaceSurvey,
    side: Side,
) -> Result<VolumeResult> {
    volume_mesh_within(
        surface,
        distance,
        survey,
        side,
        survey.options.max_memory,
        false,
    )
}

/// [`volume_mesh_surveyed`] within a memory budget of `max_memory` bytes instead of the
/// survey's, for a caller that tries a smaller budget first:
/// [`VolumeResult::budget_bound`] says whether a larger one could give another mesh, and
/// with `stop_when_bound` a meshing the budget binds ends the rounds that mesh again
/// for the topology (the caller meshes again within more).
pub fn volume_mesh_within(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    survey: &SurfaceSurvey,
    side: Side,
    max_memory: u64,
    stop_when_bound: bool,
) -> Result<VolumeResult> {
    let start = Instant::now();
    let options = &VolumeOptions {
        max_memory,
        ..survey.options
    };
    let h = survey.h;
    let (lo, hi) = check_surface(surface)?;
    let diagonal = norm(sub(hi, lo));
    let centre = scale(add(lo, hi), 0.5);
    let radius = options.sphere_scale * 0.5 * diagonal;
    let mut warnings = Vec::new();
    let crossings = &survey.crossings[..];
    let expected = if crossings.is_empty() {
        predict(surface, &survey.report, side)
    } else {
        warnings.push(format!(
            "the surface crosses itself ({} pairs of triangles): the {} volume is the solid its winding number encloses, whose topology the genus does not predict",
            crossings.len(),
            side.name()
        ));
        None
    };
    let mut sampled = None;
    let mut refined = None;
    let mut budget_bound = false;
    let (mesh, found, stats, rounds, samples) = match &survey.sizing {
        Some(sizing) if options.mesher == Mesher::Sampled => {
            let sphere = (side == Side::Outside).then_some((centre, radius));
            let (mesh, s) = match sampled_surface(surface, distance, sizing, sphere, h, options)? {
                (mesh, DelaunayStats::Sampled(s)) => (mesh, s),
                (_, DelaunayStats::Refined(_)) => unreachable!("the sampled mesher was asked for"),
            };
            if s.missing_triangles > 0 {
                warnings.push(format!(
                    "{} of the {} boundary triangles of the sampled {} volume mesh are not faces of its tetrahedralization after {} rounds of bisection: the carving may cross the surface there",
                    s.missing_triangles, s.boundary_triangles, side.name(), s.recovery_rounds
                ));
            }
            sampled = Some(s);
            let found = mesh.topology();
            (mesh, found, None, 1, 0)
        }
        Some(sizing) if options.mesher == Mesher::Refined => {
            let sphere = (side == Side::Outside).then_some((centre, radius));
            let (mesh, s) = match sampled_surface(surface, distance, sizing, sphere, h, options)? {
                (mesh, DelaunayStats::Refined(s)) => (mesh, s),
                (_, DelaunayStats::Sampled(_)) => {
                    unreachable!("the refinement mesher was asked for")
                }
            };
            if s.over_budget {
                budget_bound = true;
                warnings.push(format!(
                    "the refined {} volume mesh stopped at the memory budget ({}) before every face and cell was refined",
                    side.name(),
                    super::memory_text(options.max_memory as f64)
                ));
            }
            if s.non_manifold > 0 {
                warnings.push(format!(
                    "refinement of the {} volume mesh left its boundary not a manifold at {} edges or vertices (within the guard); pinch repair dropped {} tets there",
                    side.name(),
                    s.non_manifold,
                    s.pinch_tets
                ));
            }
            refined = Some(s);
            let found = mesh.topology();
            (mesh, found, None, 1, 0)
        }
        Some(sizing) => {
            let sphere = (side == Side::Outside).then_some((centre, radius));
            let (meshed, samples) = stuff_surface(
                surface,
                distance,
                sizing,
                sphere,
                h,
                options,
                &expected,
                stop_when_bound,
                &mut warnings,
            )?;
            budget_bound = meshed.budget_bound;
            let stuffed = meshed.mesh;
            (
                stuffed.mesh,
                meshed.found,
                Some(stuffed.stats),
                meshed.rounds,
                samples,
            )
        }
        None => {
            let mesh = tetgen_mesh(surface, side, centre, radius)?;
            let found = mesh.topology();
            (mesh, found, None, 1, 0)
        }
    };
    if mesh.num_tets() == 0 {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "the {} volume mesh is empty: no lattice point of spacing h = {h:.3e} fell inside (a part too thin for the budget, or a surface that encloses nothing); a smaller --h may help",
                side.name()
            ),
        ));
    }
    let matches = expected.as_ref().map(|e| *e == found);
    if expected.is_none() {
        warnings.push(format!(
            "the {} volume mesh has topology {found}, which the surface cannot confirm (it crosses itself, or a component has no genus)",
            side.name()
        ));
    }
    if side == Side::Inside && crossings.is_empty() {
        let enclosed = surface.signed_volume();
        let meshed = mesh.volume();
        if (meshed / enclosed - 1.0).abs() > VOLUME_TOLERANCE {
            warnings.push(format!(
                "the inside volume mesh holds {:.1} % of the volume the surface encloses ({meshed:.4e} of {enclosed:.4e}): parts thinner than its cells are lost or merged; a smaller --h may help",
                100.0 * meshed / enclosed
            ));
        }
    }
    if matches == Some(false) {
        warnings.push(format!(
            "the {} volume mesh's topology ({found}) differs from the surface's ({}) after {rounds} meshing{}: features below the resolution; a smaller --h may help",
            side.name(),
            expected.as_ref().map_or(String::new(), |e| e.to_string()),
            if rounds == 1 { "" } else { "s" },
        ));
    }
    if let Some(s) = stats {
        if let Some(floor) = s.spacing_floor {
            warnings.push(format!(
                "the memory budget of the {2} volume mesh ({0}, {1:.2e} tets; a run that meshes both sides gives each half of --max-memory) kept its cells from going below {floor:.3e}: parts or gaps thinner than {3:.3e} may have lost their topology (raise --max-memory)",
                super::memory_text(options.max_memory as f64),
                options.max_memory as f64 / super::BYTES_PER_TET,
                side.name(),
                CELLS_ACROSS * floor
            ));
        }
        let q = s.quality;
        if q.below_target_after > 0 {
            warnings.push(format!(
                "{} tets of the {} volume mesh keep a dihedral angle below {}° (smallest {:.2}°)",
                q.below_target_after,
                side.name(),
                q.target_deg,
                q.min_dihedral_after_deg
            ));
        }
    }
    let hausdorff = hausdorff_to_surface(&mesh, distance) / diagonal;

    Ok(VolumeResult {
        mesh,
        side,
        h,
        sphere: (side == Side::Outside).then_some((centre, radius)),
        mesher: options.mesher,
        budget: options.max_memory,
        budget_bound,
        stats,
        sampled,
        refined,
        thin_vertices: survey.thin_vertices,
        thickness_samples: samples,
        topology: TopologyCheck {
            expected,
            found,
            matches,
            rounds,
        },
        hausdorff_to_surface: hausdorff,
        warnings,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The surface's bounding box, or the error for a surface no volume can be meshed in:
/// no vertices, no triangles, all at one point.
fn check_surface(surface: &SurfaceMesh) -> Result<([f64; 3], [f64; 3])> {
    let invalid = |message: &str| Error::new(ErrorKind::InvalidMesh, message);
    let (lo, hi) = surface
        .bounding_box()
        .ok_or_else(|| invalid("the surface has no vertices"))?;
    if surface.triangles.is_empty() {
        return Err(invalid("the surface has no triangles"));
    }
    let diagonal = norm(sub(hi, lo));
    if diagonal.is_nan() || diagonal <= 0.0 {
        return Err(invalid("the surface is a single point"));
    }
    Ok((lo, hi))
}

/// The stuffing mesher's survey of a surface: thickness and gaps measured into sizing
/// features, creases (and the curve where the surface crosses itself) to snap onto.
fn size_surface(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    crossings: &[[u32; 2]],
    h: f64,
) -> SurfaceSizing {
    // Where the surface crosses itself a "thickness" measures the crossing: the
    // crossing triangles and the ring around them are not sized.
    let mut crossing = vec![false; surface.num_vertices()];
    for f in crossings.iter().flatten() {
        for &v in &surface.triangles[*f as usize] {
            crossing[v as usize] = true;
        }
    }
    let ring: Vec<u32> = surface
        .triangles
        .iter()
        .filter(|t| t.iter().any(|&v| crossing[v as usize]))
        .flatten()
        .copied()
        .collect();
    for v in ring {
        crossing[v as usize] = true;
    }
    let topology = Topology::new(surface);
    let measured = measure_surface(surface, &topology, distance, &crossing, THIN_FACTOR * h);
    let spacing: Vec<f64> = measured.thickness[..surface.num_vertices()]
        .iter()
        .map(|t| (t[0].min(t[1]) / CELLS_ACROSS).min(h))
        .collect();
    // Where the surface crosses itself, the solid's boundary has a crease along the
    // crossing curve (two overlapping balls meet in a concave ring): it is snapped onto
    // like any crease, with cells finer there so that the mesh's edges follow it
    // instead of zigzagging across it.
    let crossing_curve: Vec<[[f64; 3]; 2]> = crossings
        .iter()
        .filter_map(|&[f, g]| {
            crate::distance::crossing_segment(
                surface.corners(f as usize),
                surface.corners(g as usize),
            )
        })
        .collect();
    let mut features = sharp_features(surface, &topology);
    features.edges.extend(&crossing_curve);
    let crease_cell = h / CROSSING_REFINEMENT;
    let crossing_sizing: Vec<SizingFeature> = crossing_curve
        .iter()
        .map(|&[p, q]| SizingFeature {
            corners: [p, q, q],
            spacing: crease_cell,
            reach: 2.0 * crease_cell,
            toward: [0.0; 3],
        })
        .collect();
    let sizing = [0, 1, 2].map(|which| {
        let mut sizing = thin_part_sizing(&measured, covered_by(which), h, which == 0);
        sizing.extend(&crossing_sizing);
        sizing
    });
    SurfaceSizing {
        h,
        sizing,
        crossing_sizing,
        skip: crossing,
        sampled: Default::default(),
        samples: std::sync::OnceLock::new(),
        measured,
        spacing,
        features,
        topology,
    }
}

/// The side of the thickness that the mesh of [`SurfaceSizing`]'s sizing `which` covers:
/// the solid (0) for the meshes of the solid, the gap (1) for the shell's.
fn covered_by(which: usize) -> usize {
    usize::from(which == 1)
}

/// The sizing by the thickness sampled over the triangles ([`sample_thickness`]).
#[derive(Debug, Clone)]
struct SampledSizing {
    /// Thin parts and gaps as sampled, and the crossing curve, as sizing features.
    sizing: Vec<SizingFeature>,
    /// Points added besides the vertices.
    points: usize,
    /// Whether [`MAX_SAMPLES`] stopped the sampling.
    bound: bool,
}

impl SurfaceSizing {
    /// Per surface vertex, the thickness of the solid and the width of the gap (infinite
    /// where not thin).
    fn thickness(&self) -> &[[f64; 2]] {
        &self.measured.thickness[..self.spacing.len()]
    }

    /// The sizing by the thickness sampled over the triangles for the mesh `which` (as
    /// in `sizing`), made on the first call.
    fn sampled(
        &self,
        surface: &SurfaceMesh,
        distance: &SurfaceDistance,
        which: usize,
    ) -> &SampledSizing {
        self.sampled[which].get_or_init(|| {
            let samples = self.samples(surface, distance);
            let mut sizing = thin_part_sizing(samples, covered_by(which), self.h, which == 0);
            sizing.extend(&self.crossing_sizing);
            SampledSizing {
                sizing,
                points: samples.positions.len() - surface.num_vertices(),
                bound: samples.bound,
            }
        })
    }

    /// The thickness sampled over the triangles, made on the first call.
    fn samples(&self, surface: &SurfaceMesh, distance: &SurfaceDistance) -> &ThicknessSamples {
        self.samples.get_or_init(|| {
            sample_thickness(
                surface,
                &self.topology,
                distance,
                &self.measured,
                &self.skip,
                THIN_FACTOR * self.h,
            )
        })
    }
}

/// The stuffing mesher on one side of a sized surface (`sphere`: the outer sphere's
/// centre and radius for the shell, `None` inside): meshings until the topology
/// matches ([`mesh_until_topology_matches`]). Returns the mesh, its topology, the
/// meshings and the thickness samples it was sized by (0: the vertices alone).
#[allow(clippy::too_many_arguments)]
fn stuff_surface(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    surveyed: &SurfaceSizing,
    sphere: Option<([f64; 3], f64)>,
    h: f64,
    options: &VolumeOptions,
    expected: &Option<TetTopology>,
    stop_when_bound: bool,
    warnings: &mut Vec<String>,
) -> Result<(Meshed, usize)> {
    let mut spacing = surveyed.spacing.clone();
    let stuffing = StuffingOptions {
        h,
        max_memory: options.max_memory,
        min_dihedral_deg: options.min_dihedral_deg,
    };
    // The shell's sizing, the solid's with the gaps' floor where the topology is
    // checked, or without it.
    let which = match (sphere, expected) {
        (Some(_), _) => 1,
        (None, Some(_)) => 0,
        (None, None) => 2,
    };
    // Where no check can confirm the topology, no cell finer than this is asked for.
    let finest = match expected {
        None => options.unchecked_min_cell * h,
        Some(_) => 0.0,
    };
    let clamp = |f: &SizingFeature| SizingFeature {
        spacing: f.spacing.max(finest),
        ..*f
    };
    if sphere.is_none() {
        let bounded: Vec<SizingFeature> = surveyed.sizing[which].iter().map(clamp).collect();
        refuse_if_all_below_floor(&bounded, surveyed.thickness(), &stuffing)?;
    }
    if let Some(warning) = unchecked_floor_warning(&surveyed.sizing[which], finest, h, sphere) {
        warnings.push(warning);
    }
    let bounds = surface.bounding_box().unwrap_or_default();
    // One meshing with the vertices' sizing or the sampled one, and `extra`
    // (refinements from earlier rounds), inside or in the shell.
    let stuff = |sampled: bool, extra: &[SizingFeature]| {
        let sizing = if sampled {
            &surveyed.sampled(surface, distance, which).sizing
        } else {
            &surveyed.sizing[which]
        };
        let inside = SurfaceInside {
            distance,
            bounds,
            sizing: sizing.iter().chain(extra).map(clamp).collect(),
            features: surveyed.features.clone(),
        };
        match sphere {
            None => stuff_volume(&inside, &stuffing),
            Some((centre, radius)) => stuff_volume(&Shell::new(inside, centre, radius), &stuffing),
        }
    };
    let meshed = mesh_until_topology_matches(
        surface,
        &stuff,
        &mut spacing,
        expected,
        stop_when_bound,
        warnings,
    )?;
    let samples = if meshed.sampled {
        let sampled = surveyed.sampled(surface, distance, which);
        if sampled.bound {
            warnings.push(format!(
                "the thickness sampled over the triangles stopped at {} points (the bound is {MAX_SAMPLES}): the triangles left are sized by their corners",
                sampled.points
            ));
        }
        sampled.points
    } else {
        0
    };
    Ok((meshed, samples))
}

/// The warning that [`VolumeOptions::unchecked_min_cell`] bound on a side (`sphere`:
/// the shell's), or `None` when no feature of `sizing` asked for cells finer than
/// `finest`.
fn unchecked_floor_warning(
    sizing: &[SizingFeature],
    finest: f64,
    h: f64,
    sphere: Option<([f64; 3], f64)>,
) -> Option<String> {
    let below: Vec<f64> = sizing
        .iter()
        .map(|f| f.spacing)
        .filter(|&s| s < finest)
        .collect();
    let asked = below.iter().copied().reduce(f64::min)?;
    let side = if sphere.is_some() {
        "outside"
    } else {
        "inside"
    };
    Some(format!(
        "{side}: the topology is not predicted, so no cell was made finer than {finest:.3e} ({:.3} h, unchecked_min_cell): {} of {} sizing features asked for finer, down to {asked:.3e}; a part or gap thinner than that may be missed",
        finest / h,
        below.len(),
        sizing.len()
    ))
}

/// Mesh, compare with the prediction, and while the topology differs: mesh again sized
/// by the thickness sampled over the triangles (`stuff(true, ..)`: where the vertices
/// alone miss a thin part between them, or spread a thin rim's cells over long
/// triangles), then refine where the mesh shows a feature below the resolution (at
/// most [`MAX_ROUNDS`] meshings), keeping the mesh closest to the prediction; a round
/// that moves away from it ends the rounds. `spacing[v]` is the cell size asked for at
/// surface vertex `v` (halved where a round refines). A meshing the budget refuses ends
/// the rounds with the best mesh so far, and says so in `warnings`; with
/// `stop_when_bound`, so does any meshing the budget floored. Returns the mesh,
/// its topology, the meshings, and whether it was sized by the samples.
fn mesh_until_topology_matches(
    surface: &SurfaceMesh,
    stuff: &dyn Fn(bool, &[SizingFeature]) -> Result<VolumeMesh>,
    spacing: &mut [f64],
    expected: &Option<TetTopology>,
    stop_when_bound: bool,
    warnings: &mut Vec<String>,
) -> Result<Meshed> {
    let stuffed = stuff(false, &[])?;
    let found = stuffed.mesh.topology();
    let mut budget_bound = stuffed.stats.spacing_floor.is_some();
    let Some(expected) = expected else {
        return Ok(Meshed {
            mesh: stuffed,
            found,
            rounds: 1,
            sampled: false,
            budget_bound,
        });
    };
    let mut best_distance = topology_distance(&found, expected);
    let mut best = (stuffed, found, false);
    let mut rounds = 1;
    let budget_stop = |warnings: &mut Vec<String>, e: &Error| {
        warnings.push(format!(
            "refinement for topology stopped at the memory budget: {}",
            e.message()
        ))
    };
    // A caller that meshes again within a larger budget takes the meshing the
    // budget bound as it is: rounds within the same budget are its cost again.
    if best_distance > 0 && !(stop_when_bound && budget_bound) {
        // Tried even where the budget floored the first: the sampled sizing may ask
        // for fewer cells (a rim's over its own area only).
        rounds += 1;
        match stuff(true, &[]) {
            Ok(next) => {
                budget_bound |= next.stats.spacing_floor.is_some();
                let found = next.mesh.topology();
                let distance = topology_distance(&found, expected);
                if distance < best_distance {
                    best_distance = distance;
                    best = (next, found, true);
                }
            }
            Err(e) if e.kind() == ErrorKind::OverBudget => {
                budget_bound = true;
                budget_stop(warnings, &e);
            }
            Err(e) => return Err(e),
        }
    }
    // Where the budget already floors the spacing, finer cells are out of reach.
    let floored = best.0.stats.spacing_floor.is_some();
    let sampled = best.2;
    let mut extra = Vec::new();
    while best_distance > 0 && rounds < MAX_ROUNDS && !floored && !(stop_when_bound && budget_bound)
    {
        let refine = unresolved_features(surface, &best.0, spacing);
        if refine.is_empty() {
            break;
        }
        extra.extend(refine);
        rounds += 1;
        let next = match stuff(sampled, &extra) {
            Ok(next) => next,
            Err(e) if e.kind() == ErrorKind::OverBudget => {
                budget_bound = true;
                budget_stop(warnings, &e);
                break;
            }
            Err(e) => return Err(e),
        };
        budget_bound |= next.stats.spacing_floor.is_some();
        let found = next.mesh.topology();
        let distance = topology_distance(&found, expected);
        if distance > best_distance {
            break;
        }
        if distance < best_distance {
            best_distance = distance;
            best = (next, found, sampled);
        }
    }
    Ok(Meshed {
        mesh: best.0,
        found: best.1,
        rounds,
        sampled: best.2,
        budget_bound,
    })
}

/// What [`mesh_until_topology_matches`] made: the mesh kept, its topology, the
/// meshings, whether it was sized by the samples, and whether the budget bound any of
/// the meshings (floored its thin parts' cells, or refused it).
struct Meshed {
    mesh: VolumeMesh,
    found: TetTopology,
    rounds: usize,
    sampled: bool,
    budget_bound: bool,
}

/// Refuse at once when the budget floors the spacing above the thickness of every part
/// of the solid: the mesh would be empty (or nearly), after all the work.
fn refuse_if_all_below_floor(
    sizing: &[SizingFeature],
    thickness: &[[f64; 2]],
    options: &StuffingOptions,
) -> Result<()> {
    let Some(floor) = spacing_floor(sizing, options) else {
        return Ok(());
    };
    let thickest = thickness.iter().map(|t| t[0]).fold(0.0, f64::max);
    if thickest < floor {
        return Err(Error::new(
            ErrorKind::OverBudget,
            format!(
                "every part of the solid is thinner than {thickest:.3e}, but the memory budget of {} ({} tets) allows no cells below {floor:.3e}: raise it with --max-memory",
                super::memory_text(options.max_memory as f64),
                options.max_tets()
            ),
        ));
    }
    Ok(())
}

/// How far one topology is from another: the differences in components, χ, boundary
/// surfaces and their χ (0 exactly when they agree, up to the order of components).
fn topology_distance(a: &TetTopology, b: &TetTopology) -> i64 {
    if a == b {
        return 0;
    }
    let components = (a.components.len() as i64 - b.components.len() as i64).abs();
    let boundary = (a.boundary_components() as i64 - b.boundary_components() as i64).abs();
    (components
        + boundary
        + (a.euler() - b.euler()).abs()
        + (a.boundary_euler() - b.boundary_euler()).abs())
    .max(1)
}

/// Where a mesh shows features below its resolution, as sizing features at half the
/// spacing used there: its pinch sites, its swallowed boundary vertices, and the surface
/// vertices its boundary does not come within half a cell of (a thin part lost, or a
/// gap closed). Halves `spacing` at those vertices.
fn unresolved_features(
    surface: &SurfaceMesh,
    stuffed: &VolumeMesh,
    spacing: &mut [f64],
) -> Vec<SizingFeature> {
    let mut out: Vec<SizingFeature> = stuffed
        .pinches
        .iter()
        .chain(&stuffed.swallowed)
        .map(|&(p, s)| SizingFeature::point(p, 0.5 * s, 2.0 * s))
        .collect();
    let mesh = &stuffed.mesh;
    let boundary = SurfaceDistance::new(&SurfaceMesh {
        positions: mesh.positions.clone(),
        triangles: mesh.boundary_faces(),
    });
    let gaps = boundary.distances(&surface.positions);
    for (v, gap) in gaps.into_iter().enumerate() {
        if gap > 0.5 * spacing[v] {
            let s = spacing[v];
            out.push(SizingFeature::point(surface.positions[v], 0.5 * s, 2.0 * s));
            spacing[v] = 0.5 * s;
        }
    }
    out
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

/// The sampled mesher (`sampled`) on one side: the surface bisected to the spacing its
/// thickness and gaps ask for (at most `h`), the sphere at the shell's coarsest spacing,
/// both refined until their triangles are Delaunay faces.
fn sampled_surface(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    surveyed: &SurfaceSizing,
    sphere: Option<([f64; 3], f64)>,
    h: f64,
    options: &VolumeOptions,
) -> Result<(TetMesh, DelaunayStats)> {
    use super::refined::{mesh_refined, RefinedOptions};
    use super::sampled::{
        bisect_triangles, mesh_sampled, sphere_mesh, Sample, SampledOptions, SpacingField,
    };
    use super::Domain;
    // The thickness over the triangles, not only at their corners: a plate drawn
    // with long triangles is thin between its vertices too.
    let thickness = surveyed.samples(surface, distance);
    let vertices: Vec<Sample> = thickness
        .positions
        .iter()
        .zip(&thickness.thickness)
        .map(|(p, t)| Sample {
            position: *p,
            spacing: t[0].min(t[1]).min(h),
        })
        .collect();
    let field = SpacingField::new(&vertices, h);
    let mut boundary = bisect_triangles(&surface.positions, &surface.triangles, &field);
    let inside = SurfaceInside {
        distance,
        bounds: surface.bounding_box().unwrap_or_default(),
        sizing: Vec::new(),
        features: surveyed.features.clone(),
    };
    let sampled = SampledOptions {
        max_tets: (options.max_memory as f64 / super::BYTES_PER_TET) as usize,
        min_dihedral_deg: options.min_dihedral_deg,
        ..SampledOptions::default()
    };
    let refined = RefinedOptions {
        max_tets: sampled.max_tets,
        min_dihedral_deg: options.min_dihedral_deg,
        ..RefinedOptions::default()
    };
    let mesh = |domain: &dyn Domain, samples: &[Sample], field: &SpacingField, boundary| {
        if options.mesher == Mesher::Refined {
            mesh_refined(domain, samples, field, &refined)
                .map(|(m, s)| (m, DelaunayStats::Refined(s)))
        } else {
            mesh_sampled(domain, boundary, samples, field, &sampled)
                .map(|(m, s)| (m, DelaunayStats::Sampled(s)))
        }
    };
    match sphere {
        None => {
            let samples = boundary.samples(&field);
            mesh(&inside, &samples, &field, &boundary)
        }
        Some((centre, radius)) => {
            let shell = Shell::new(inside, centre, radius);
            let coarse = shell.coarsest_spacing(h);
            boundary.extend(&sphere_mesh(centre, radius, coarse));
            let samples = boundary.samples(&field);
            let field = SpacingField::new(&samples, coarse);
            let samples = boundary.samples(&field);
            mesh(&shell, &samples, &field, &boundary)
        }
    }
}

/// What one of the two Delaunay meshers did.
enum DelaunayStats {
    Sampled(SampledStats),
    Refined(RefinedStats),
}

#[cfg(feature = "tetgen")]
fn tetgen_mesh(
    surface: &SurfaceMesh,
    side: Side,
    centre: [f64; 3],
    radius: f64,
) -> Result<TetMesh> {
    match side {
        Side::Inside => super::tetgen::mesh_inside(surface),
        Side::Outside => super::tetgen::mesh_shell(surface, centre, radius),
    }
}

#[cfg(not(feature = "tetgen"))]
fn tetgen_mesh(_: &SurfaceMesh, _: Side, _: [f64; 3], _: f64) -> Result<TetMesh> {
    Err(Error::invalid_argument(
        "this necklace was built without the `tetgen` feature (cargo build --features tetgen; AGPL-3.0)",
    ))
}
