//! Volume meshing by isosurface stuffing on a graded BCC lattice.
//!
//! Computes a [`TetMesh`] of a region given implicitly by a [`Domain`]: a function that
//! is negative inside the region, zero on its boundary and 1-Lipschitz (a signed
//! distance, or the max of signed distances for an intersection). For the method this is
//! the solid inside the input surface (handles) or the shell between the surface and a
//! bounding sphere (tunnels): [`SurfaceInside`] and [`Shell`] (`domains`; a [`Shell`]
//! takes any solid, the tests' analytic shells too). This replaces the paper's TetGen
//! step (sec. 4, "preprocessing"). TetGen itself is `volume::tetgen`, behind the `tetgen`
//! feature (AGPL-3.0): the switches "pq1.2" inside and for the shell, through `tritet`,
//! which no other module names.
//!
//! On a surface, [`volume_mesh`] / [`volume_mesh_with`] (`surface`) is the whole stage:
//! the topology the surface predicts ([`expected_topology`]: from the components' genus
//! and nesting), thickness and gaps measured by rays and inscribed balls (at the vertices
//! and at the middles of faces their normals do not see) into sizing features, and
//! creases and corners to snap onto (`surface_sizing`), then meshing
//! (below); where the first mesh's topology differs from the prediction, a meshing sized
//! by the thickness sampled over the triangles too (those that are long or whose corners
//! disagree; made once, for the first side that asks), then refinement rounds. The
//! measures do not depend on the side: [`survey_surface`] makes them once (thickness
//! and gaps at every vertex, creases, crossings, the report the prediction reads) and
//! [`volume_mesh_surveyed`] meshes a side from them (the pipeline meshes both sides from
//! one survey): a thin part or gap gets two cells across, but a thin part of the solid
//! one (at most `h / 2`) in the shell's mesh, which only has to stay out of it, and a
//! gap no finer than `h / 4` (and a quarter of the solid's thickness beside it) in the
//! solid's mesh, which holds no field there.
//!
//! Steps (Labelle & Shewchuk, "Isosurface Stuffing", SIGGRAPH 2007):
//! 1. `octree`: an octree, balanced bottom-up, whose cells have size `h` wherever the
//!    boundary may pass (|f(centre)| < half-diagonal; [`Domain::spacing_near`] may ask for
//!    less detail on parts of the boundary; the 2:1 balance grades the rest), as small as
//!    the domain's [`SizingFeature`]s ask where they reach (thin parts and gaps: no fixed
//!    floor; `sizing` passes each cell the features that reach it, level by level), and
//!    coarser away from the boundary. The memory budget ([`StuffingOptions::max_memory`] at
//!    [`BYTES_PER_TET`], the peak of a whole run measured per tet; in tets
//!    [`StuffingOptions::max_tets`]) is held three times: the features' estimate,
//!    calibrated on one octree (`calibrated_floor`: the estimate alone counts overlapping
//!    regions several times), sets a floor on their spacing ([`spacing_floor`]; reported in
//!    [`StuffingStats::spacing_floor`]), a tree or a mesh still over it raises the floor
//!    and starts again, and a run over it without thin parts to coarsen is refused with the
//!    figure ([`ErrorKind::OverBudget`]), before the lattice is allocated. A tree is given
//!    up within the level that crosses the budget (it goes in eighths, unbalanced), and
//!    says what it would have given stopped at each level it reached: below `h` only thin
//!    parts split cells, and a floor of a level's cell size splits none of that size, so
//!    the next floor is the size of the finest level that fits. The pipeline
//!    gives each of two sides meshed at once half of [`VolumeOptions::max_memory`]. A
//!    cell whose parent's value is larger than the distance between their centres has
//!    the parent's sign, and the domain is told so ([`Domain::values_within_signed`]):
//!    far from a surface that crosses itself, the sign is most of a value's cost.
//! 2. `background`: the octree's BCC tetrahedralisation (graded, conforming).
//! 3. `stuffing`: domain values at the lattice vertices, cut points on sign-changing
//!    edges (the domain's ray hits, else regula falsi), warping of vertices too close to
//!    a cut point (the paper's α everywhere), and the stencils that fill each background
//!    tet with its inside part.
//! 4. `repair`: pinches below the lattice resolution (tets touching along an edge or at
//!    a vertex only) are undone by dropping the smaller side; their places are returned
//!    ([`VolumeMesh::pinches`]) so a caller can refine there and mesh again (the
//!    pipeline does, while the topology differs from the surface's). Boundary vertices
//!    the tets closed round become interior ([`VolumeMesh::swallowed`]). Then `chords`:
//!    an edge between two boundary vertices across the inside (a part about one cell
//!    thick) is split at its midpoint, so that the interior vertices keep the region's
//!    topology (the Morse analysis sweeps them, the boundary held fixed).
//! 5. `features`: boundary vertices near the domain's sharp corners and creases
//!    ([`Domain::sharp_features`]) are moved onto them, so small polyhedral parts keep
//!    their volume.
//! 6. `quality`: where a graded transition or a guarded warp left a tet with a small
//!    dihedral angle, its vertices are moved (inside freely, on the boundary along it) to
//!    raise the smallest angle of their stars to [`StuffingOptions::min_dihedral_deg`]
//!    (10° by default).
//!
//! A second mesher, experimental ([`Mesher::Sampled`], `--mesher sampled`): `sampled`
//! bisects the surface to the spacing its thickness asks for, adds interior points from
//! an octree graded by the distance to it, takes the Delaunay tetrahedralization of both
//! (`delaunay`: Bowyer–Watson with Shewchuk's exact predicates, points added in batches,
//! the only place in `volume` that names `robust`), bisects boundary triangles until they are its faces
//! (pairs flipped where it took the other diagonal), keeps the tets whose centroid is
//! inside, then runs `chords` and `quality` with the samples fixed; [`SampledStats`] go
//! in the report, and a warning where triangles stay unrecovered.
//!
//! A third, experimental too ([`Mesher::Refined`], `--mesher refined`): `refined`
//! inserts the same samples into one Delaunay tetrahedralization (`delaunay`, whose
//! cavity and fill steps it drives), labels each cell by the domain's sign at its
//! circumcentre, takes as boundary the faces whose dual Voronoi edge crosses the
//! domain's boundary, and refines boundary faces (size, angle, corners off it) before
//! cells (radius–edge ratio, size; a circumcentre in a boundary face's surface ball is
//! replaced by that ball's centre), with manifold repair and a guard against
//! non-termination; then `repair`, `chords` and `quality`. [`RefinedStats`] go in the
//! report, and warnings where the budget or the guard left work undone.
//!
//! Conventions: lengths in the domain's units; output tets positively oriented; vertex
//! kinds from the sign (inside: interior) and [`Domain::boundary_kind`] (on the zero
//! set). Entry points: [`stuff_volume`] for any domain, [`volume_mesh`] for a surface.

mod background;
mod chords;
mod delaunay;
mod domains;
mod features;
mod octree;
mod prediction;
mod quality;
mod refined;
mod repair;
mod sampled;
mod sizing;
mod stuffing;
mod surface;
mod surface_sizing;
#[cfg(feature = "tetgen")]
pub mod tetgen;

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::error::{Error, ErrorKind, Result};
use crate::tet::{renumber_used, TetMesh, VertexKind};
pub use domains::{Domain, Shell, SurfaceInside};
pub use features::SharpFeatures;
use octree::{Cell, Key, Octree};
pub use prediction::expected_topology;
pub use quality::QualityStats;
pub use refined::RefinedStats;
pub use sampled::SampledStats;
use sizing::clamp_spacing;
pub use sizing::{spacing_floor, SizingFeature};
pub use surface::{
    default_h, survey_surface, volume_mesh, volume_mesh_surveyed, volume_mesh_with,
    volume_mesh_within, Mesher, SurfaceSurvey, TopologyCheck, VolumeOptions, VolumeReport,
    VolumeResult, MAX_ROUNDS,
};

/// Options of the stuffing mesher.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StuffingOptions {
    /// Lattice spacing (cell size) along the boundary where no sizing feature asks for
    /// less, in the domain's units.
    pub h: f64,
    /// The memory budget, in bytes (default [`DEFAULT_MAX_MEMORY`]): at most
    /// [`StuffingOptions::max_tets`] tets, [`BYTES_PER_TET`] each, estimated before the
    /// lattice is allocated. A run estimated above it is refused with the estimate.
    pub max_memory: u64,
    /// The quality step raises every tet's smallest dihedral angle to at least this
    /// many degrees where it can (default 10; 0 turns the step off).
    pub min_dihedral_deg: f64,
}

/// The default memory budget of a run: 8 GB (20 million tets at [`BYTES_PER_TET`],
/// 10 million for each side when both are meshed at once). The wire sphere of the
/// shared models needs 10.3 million tets (2.6 inside, 7.8 outside; 4.4 GB measured) to
/// keep its 95 handles and 95 tunnels with the stuffing mesher; at 4 GB it keeps 83
/// tunnels.
pub const DEFAULT_MAX_MEMORY: u64 = 8_000_000_000;

/// Bytes of peak memory per volume tet of a whole run (the mesh, its Laplacian and
/// smoothing, the Morse analysis and the loops): measured 380 on the real models
/// (`docs/decisions.md`, the memory budget), rounded up. Budgets in bytes are turned into
/// tets with it.
pub const BYTES_PER_TET: f64 = 400.0;

/// A memory size for messages: `4.00 GB`, `512 MB`, `400 kB` (powers of 1000).
pub fn memory_text(bytes: f64) -> String {
    if bytes >= 1e9 {
        format!("{:.2} GB", bytes / 1e9)
    } else if bytes >= 1e6 {
        format!("{:.0} MB", bytes / 1e6)
    } else {
        format!("{:.0} kB", bytes / 1e3)
    }
}

impl StuffingOptions {
    /// Spacing `h`, the default budget and quality target.
    pub fn new(h: f64) -> Self {
        StuffingOptions {
            h,
            max_memory: DEFAULT_MAX_MEMORY,
            min_dihedral_deg: 10.0,
        }
    }

    /// The most tets the memory budget allows.
    pub fn max_tets(&self) -> usize {
        (self.max_memory as f64 / BYTES_PER_TET) as usize
    }
}

/// Counts that describe a stuffing run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StuffingStats {
    /// Spacing along the boundary.
    pub h: f64,
    /// Smallest cell size used.
    pub finest_cell: f64,
    /// Sizing features the domain gave.
    pub sizing_features: usize,
    /// The budget's floor on the spacing features may ask for, when it bound (thin
    /// parts finer than it were meshed at it; their topology may be lost).
    pub spacing_floor: Option<f64>,
    /// The tet count estimated from the octree before meshing.
    pub estimated_tets: usize,
    /// Meshings the budget's floor search tried, the last the one kept (1 where the
    /// first fitted; a tree the calibration built and found over counts too).
    pub attempts: usize,
    /// Octree leaves.
    pub octree_leaves: usize,
    /// Background lattice vertices and tets.
    pub background_vertices: usize,
    /// Background tets.
    pub background_tets: usize,
    /// Lattice vertices warped onto the boundary.
    pub warped_vertices: usize,
    /// Warps refused because they would have flattened a background tet.
    pub refused_warps: usize,
    /// Cut points used as boundary vertices.
    pub cut_points: usize,
    /// Output tets that warping made non-positive (0 unless the guarantees fail).
    pub inverted_tets: usize,
    /// Tets dropped to undo pinches below the lattice resolution.
    pub pinch_tets_removed: usize,
    /// Interior vertices those drops left on the boundary (now boundary vertices,
    /// slightly inside the true surface).
    pub exposed_vertices: usize,
    /// Boundary vertices enclosed by tets, now interior (see [`VolumeMesh::swallowed`]).
    pub swallowed_vertices: usize,
    /// Edges between two boundary vertices across the inside, split at their midpoint
    /// so that the interior vertices keep the region's topology (`chords`).
    pub chords_split: usize,
    /// Boundary vertices moved onto a sharp corner or crease.
    pub snapped_vertices: usize,
    /// What the quality step did.
    pub quality: QualityStats,
    /// Seconds per step: octree, background, lattice values, stuffing, repair, features,
    /// quality (of the meshing that was kept).
    pub seconds: [f64; 7],
}

/// A stuffed volume mesh and its statistics.
#[derive(Debug, Clone)]
pub struct VolumeMesh {
    /// The tet mesh.
    pub mesh: TetMesh,
    /// What the run did.
    pub stats: StuffingStats,
    /// Where pinch repair had to drop tets, with the lattice spacing there: features
    /// below the resolution (a caller may refine there and mesh again).
    pub pinches: Vec<([f64; 3], f64)>,
    /// Vertices on the boundary (warped onto it, or on it) that no boundary face
    /// touches, with the lattice spacing there: the tets closed round them, swallowing
    /// a gap below the resolution (typically at the tip of a narrow wedge of the
    /// outside). They are interior vertices of the mesh.
    pub swallowed: Vec<([f64; 3], f64)>,
}

/// Tets per octree leaf: 12 on a uniform BCC lattice (each leaf owns three faces, four
/// tets each), more where the lattice is graded (cones at transitions; 15 measured
/// on the wire sphere's shell).
const TETS_PER_LEAF: f64 = 15.0;

/// A leaf of the octree, wholly outside the region or not, in tets of the budget: its
/// slots in the tree's tables (the leaves, the centre values, the corners and the level
/// lists) take about a tet's [`BYTES_PER_TET`] while the tree is built and
/// tetrahedralized (about 370 bytes a leaf measured on mf_Offset1's inside, most of its
/// leaves dead). The tets' count binds first wherever dead leaves are few.
const TETS_PER_CELL: f64 = 1.0;

/// Most halvings of `h` a sizing feature may ask for (the integer grid's resolution).
const MAX_LEVELS: u32 = 30;

/// Mesh `domain` by isosurface stuffing with spacing `options.h` along its boundary.
pub fn stuff_volume(domain: &dyn Domain, options: &StuffingOptions) -> Result<VolumeMesh> {
    let h = options.h;
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::invalid_argument(format!("h = {h} must be positive")));
    }
    if options.max_tets() == 0 {
        return Err(Error::invalid_argument(format!(
            "max_memory = {} bytes leaves no room for a single tet ({BYTES_PER_TET} bytes)",
            options.max_memory
        )));
    }
    let (lo, hi) = domain.bounds();
    if (0..3).any(|k| !(lo[k].is_finite() && hi[k].is_finite() && hi[k] >= lo[k])) {
        return Err(Error::invalid_argument(
            "the domain's bounds are not finite",
        ));
    }
    let features: Vec<SizingFeature> = domain
        .sizing()
        .into_iter()
        .filter(|f| f.is_valid() && f.spacing < h)
        .collect();

    // 1–3. Octree, background lattice, stuffing, within the budget: the finest
    // spacing the features may ask for is the floor that fits their estimate, that
    // estimate calibrated on an octree; a tree or a mesh still over the budget
    // coarsens the floor (to the finest level of that tree that fits, when it names
    // one) and starts again.
    // The cells' centre values the trees have evaluated, for the next tree: the same
    // cell (the root is the same whatever the floor) has the same value.
    let mut values = CentreValues::default();
    let Calibration {
        mut floor,
        fits,
        over,
    } = calibrated_floor(domain, options, &features, lo, hi, &mut values)?;
    // The calibration's tree at that floor over the budget is the first attempt's
    // failure: it would build the same tree again.
    let mut known_failure = over;
    let mut attempts = 0;
    let (lattice, features) = loop {
        let clamped = clamp_spacing(&features, floor);
        attempts += 1;
        let attempt = match known_failure.take() {
            Some(failed) => Err(failed),
            None => stuff_lattice(domain, options, &clamped, lo, hi, &mut values),
        };
        match attempt {
            Ok(lattice) => break (lattice, clamped),
            Err(Failed::OverBudget {
                estimate,
                truncations,
                expected_fit,
                error,
            }) => {
                if floor.is_some_and(|f| f >= h) || clamped.is_empty() {
                    return Err(error);
                }
                let finest = clamped.iter().map(|f| f.spacing).fold(h, f64::min);
                // The finest level at which the failed tree, stopped there, fits: a
                // floor of that level's cell size builds that tree. At least half as
                // coarse again as the failed floor, so that the search moves on.
                let stopped = truncations
                    .iter()
                    .filter(|t| {
                        t.size >= 1.5 * finest
                            && t.size <= h
                            && t.estimated_tets <= options.max_tets() as f64
                    })
                    .map(|t| t.size)
                    .reduce(f64::min);
                let fits = fits.filter(|&fits| fits > finest);
                let next = match (stopped, fits) {
                    // The finer of the two: a floor whose tree was built and fitted is
                    // known to fit; the level only estimated to.
                    (Some(stopped), fits) => fits.map_or(stopped, |fits| stopped.min(fits)),
                    // Halfway (on a log scale) to the floor whose tree fitted, and that
                    // floor itself once within a factor 2 of the one that failed: cells
                    // are powers of two, so a floor between them would mostly build the
                    // failed tree again (`docs/decisions.md`, Volume mesh).
                    (None, Some(fits)) => {
                        if fits <= 2.0 * finest {
                            fits
                        } else {
                            (fits * finest).sqrt()
                        }
                    }
                    // Tets grow like the inverse square of the spacing along a surface:
                    // coarsen by the square root of the excess (a quarter more at
                    // least).
                    (None, None) => {
                        let excess = estimate / options.max_tets() as f64;
                        (finest * excess.sqrt().max(1.25) * 1.1).min(h)
                    }
                };
                // Floors below the level the failed mesh's own count says fits build
                // trees as much over: where features finer than that cover little (the
                // zero-width gaps at a crossing), the steps above would try each.
                floor = Some(match expected_fit {
                    Some(level) => next.max(fits.map_or(level, |fits| level.min(fits))),
                    None => next,
                });
            }
            Err(failed) => return Err(failed.error()),
        }
    };
    let Lattice {
        grid,
        tree,
        keys,
        background_tets,
        mut stuffed,
        mut seconds,
    } = lattice;
    let keys = &keys;
    let mut clock = Instant::now();
    let mut lap = |i: usize| {
        seconds[i] = clock.elapsed().as_secs_f64();
        clock = Instant::now();
    };

    // 4. Pinches below the lattice resolution.
    let mut interior: Vec<bool> = stuffed.signs.iter().map(|&s| s < 0).collect();
    let repair = repair::repair_pinches(&stuffed.positions, &mut stuffed.tets, &interior);
    for &v in &repair.exposed {
        interior[v as usize] = false;
    }
    // A boundary vertex the tets close round lies inside the mesh: it is interior now
    // (on the true surface, but no boundary face touches it).
    for &v in &repair.buried {
        interior[v as usize] = true;
    }
    let site = |&v: &u32| {
        (
            stuffed.positions[v as usize],
            grid.spacing_at(&tree.octree, keys, v),
        )
    };
    let pinches = repair.sites.iter().map(site).collect();
    let swallowed = repair.buried.iter().map(site).collect();
    // Edges across parts about a cell thick: an interior vertex at each midpoint.
    let chords_split =
        chords::split_chords(&mut stuffed.positions, &mut stuffed.tets, &mut interior);
    lap(4);

    // 5. Sharp features: boundary vertices onto the corners and creases.
    let exposed: HashSet<u32> = repair.exposed.iter().copied().collect();
    let on_boundary: Vec<bool> = (0..stuffed.positions.len())
        .map(|v| !interior[v] && !exposed.contains(&(v as u32)))
        .collect();
    let snapped = features::snap(
        &mut stuffed.positions,
        &stuffed.tets,
        &on_boundary,
        &domain.sharp_features(),
    );
    lap(5);

    // 6. Quality: lift the smallest dihedral angles where transitions left them low.
    let mobility: Vec<quality::Mobility> = (0..stuffed.positions.len())
        .map(|v| {
            if interior[v] {
                quality::Mobility::Free
            } else if exposed.contains(&(v as u32)) || snapped[v] {
                quality::Mobility::Fixed
            } else {
                quality::Mobility::OnBoundary
            }
        })
        .collect();
    let quality = quality::improve(
        &mut stuffed.positions,
        &stuffed.tets,
        &mobility,
        &|p| domain.project(p),
        options.min_dihedral_deg,
    );
    lap(6);
    let mesh = compact(domain, &stuffed.positions, &stuffed.tets, &interior)?;
    if mesh.num_tets() == 0 {
        let finest = grid.finest_cell(&tree.octree);
        // Where the budget floored the spacing, the budget is why.
        return Err(match floor {
            Some(floor) => Error::new(
                ErrorKind::OverBudget,
                format!(
                    "the volume mesh is empty: the memory budget of {} allows no cells below {floor:.3e}, and no lattice vertex at that spacing lies inside the region: raise it with --max-memory",
                    memory_text(options.max_memory as f64)
                ),
            ),
            None => Error::new(
                ErrorKind::InvalidMesh,
                format!(
                    "the volume mesh is empty: no lattice vertex at spacing {finest:.3e} lies inside the region"
                ),
            ),
        });
    }

    Ok(VolumeMesh {
        mesh,
        pinches,
        swallowed,
        stats: StuffingStats {
            h,
            finest_cell: grid.finest_cell(&tree.octree),
            sizing_features: features.len(),
            spacing_floor: floor,
            estimated_tets: tree.estimated_tets,
            attempts,
            octree_leaves: tree.leaves,
            background_vertices: keys.len(),
            background_tets,
            warped_vertices: stuffed.warped,
            refused_warps: stuffed.refused_warps,
            cut_points: stuffed.cut_points,
            inverted_tets: stuffed.inverted,
            pinch_tets_removed: repair.removed_tets,
            exposed_vertices: repair.exposed.len(),
            swallowed_vertices: repair.buried.len(),
            chords_split,
            snapped_vertices: snapped.iter().filter(|&&x| x).count(),
            quality,
            seconds,
        },
    })
}

/// The floor on the features' spacing that fits the budget. The features' own
/// estimate ([`spacing_floor`]) counts every feature's region whole, where neighbours'
/// regions overlap and half of them lie on the other side of the surface: at the floor
/// it set for 20 million tets, the octree counted 4.0 million inside the wire sphere,
/// 6.7 million outside it and 0.54 million inside `ps_mk3s_gantry.stl`, so a floor from
/// it alone binds where the budget has room. Where it binds, the octree at that floor
/// (which fits the budget, the estimate being high) gives the ratio of its count to the
/// estimate's, and the floor is found again with the estimate scaled by that ratio and
/// a tenth (at most 1, at least 1/16). No floor: none needed. Also the floor whose octree was
/// seen to fit, if any, and the octree's failure where it did not (the first attempt,
/// at the same floor, takes it instead of building the same tree again).
fn calibrated_floor(
    domain: &dyn Domain,
    options: &StuffingOptions,
    features: &[SizingFeature],
    lo: [f64; 3],
    hi: [f64; 3],
    values: &mut CentreValues,
) -> Result<Calibration> {
    let Some(floor) = spacing_floor(features, options) else {
        return Ok(Calibration {
            floor: None,
            fits: None,
            over: None,
        });
    };
    let clamped = clamp_spacing(features, Some(floor));
    let grid = Grid::new(lo, hi, options.h, &clamped)?;
    let tree = match build_octree(domain, &grid, &clamped, options, values) {
        Ok(tree) => tree,
        Err(failed @ Failed::OverBudget { .. }) => {
            return Ok(Calibration {
                floor: Some(floor),
                fits: None,
                over: Some(failed),
            })
        }
        Err(Failed::Other(e)) => return Err(e),
    };
    let estimate = sizing::feature_estimate(features, floor);
    let estimated_tets = tree.estimated_tets;
    // The first attempt's tree (a floor as fine or finer) takes this one's values.
    values.take(&grid, tree.centre_values);
    // A tenth more than the tree counted: the ratio grows as the floor falls (the
    // features' regions overlap less). More margin would save the attempts that fall
    // back, but land a power of two coarser than the budget allows (measured on the
    // wire sphere inside at 4 GB: twice the ratio gave 0.41 M tets and 88 of its 95
    // handles, this 2.57 M and all 95).
    let ratio = (1.1 * estimated_tets as f64 / estimate).clamp(1.0 / 16.0, 1.0);
    let calibrated = sizing::spacing_floor_scaled(features, options, ratio).map(|f| f.min(floor));
    Ok(Calibration {
        floor: calibrated,
        fits: Some(floor),
        over: None,
    })
}

/// What [`calibrated_floor`] found: the floor to start from, the floor whose tree
/// fitted the budget (if one did), and the failure of the tree at `floor` when it did
/// not (that tree need not be built again).
struct Calibration {
    floor: Option<f64>,
    fits: Option<f64>,
    over: Option<Failed>,
}

/// Steps 1 to 3 with the given features: the octree, its background lattice, the
/// values at its vertices and the stuffed tets; `OverBudget` when the tree or the tets
/// exceed [`StuffingOptions::max_tets`].
fn stuff_lattice(
    domain: &dyn Domain,
    options: &StuffingOptions,
    features: &[SizingFeature],
    lo: [f64; 3],
    hi: [f64; 3],
    values: &mut CentreValues,
) -> std::result::Result<Lattice, Failed> {
    let mut clock = Instant::now();
    let mut seconds = [0.0; 7];
    let mut lap = |i: usize| {
        seconds[i] = clock.elapsed().as_secs_f64();
        clock = Instant::now();
    };
    let grid = Grid::new(lo, hi, options.h, features)?;
    let tree = build_octree(domain, &grid, features, options, values)?;
    // A tree that fitted is the last one built, unless its stuffing is over the
    // budget (rare): the earlier trees' values go.
    *values = CentreValues::default();
    lap(0);

    let background = background::tetrahedralize(&tree.octree, &|c| tree.is_dead(&grid, c));
    let positions: Vec<[f64; 3]> = background.keys.iter().map(|&k| grid.point(k)).collect();
    lap(1);

    // Only signs matter at lattice vertices (cut points are found on the true function).
    let values = lattice_values(domain, &grid, &tree, &background.keys, &positions);
    // The centre values have served (the dead cells, the lattice's signs): their table,
    // as large as the tree's, is not held through the stuffing, on thin models the
    // volume stage's peak. What is kept of the tree cannot tell dead cells any more.
    let Tree {
        octree,
        centre_values,
        leaves,
        estimated_tets,
        truncations,
    } = tree;
    drop(centre_values);
    let tree = Built {
        octree,
        leaves,
        estimated_tets,
        truncations,
    };
    lap(2);

    // The paper's α on every edge.
    let keys = &background.keys;
    let alpha = |a: u32, b: u32| {
        let (ka, kb) = (keys[a as usize], keys[b as usize]);
        let axis_parallel = (0..3).filter(|&k| ka[k] != kb[k]).count() == 1;
        if axis_parallel {
            stuffing::ALPHA_LONG
        } else {
            stuffing::ALPHA_SHORT
        }
    };
    let value = |p: [f64; 3]| domain.value(p);
    let crossing = |a: [f64; 3], b: [f64; 3]| domain.crossing(a, b);
    let stuffed = stuffing::stuff(
        &value,
        &crossing,
        positions,
        &values,
        &alpha,
        &background.tets,
    );
    lap(3);
    if stuffed.tets.len() > options.max_tets() {
        return Err(over_budget(
            stuffed.tets.len() as f64,
            Vec::new(),
            expected_fit_level(&tree.truncations, stuffed.tets.len(), options),
            options,
            grid.finest_cell(&tree.octree),
        ));
    }
    Ok(Lattice {
        grid,
        tree,
        background_tets: background.tets.len(),
        keys: background.keys,
        stuffed,
        seconds,
    })
}

/// What steps 1 to 3 made (see [`stuff_lattice`]).
struct Lattice {
    grid: Grid,
    tree: Built,
    keys: Vec<Key>,
    background_tets: usize,
    stuffed: stuffing::Stuffed,
    seconds: [f64; 7],
}

/// The integer grid of the octree: one unit is half the smallest cell any feature
/// asks for, so corners, centres and face centres of every cell are integer points.
struct Grid {
    h: f64,
    unit: f64,
    origin: [f64; 3],
    root: Cell,
}

impl Grid {
    fn new(lo: [f64; 3], hi: [f64; 3], h: f64, features: &[SizingFeature]) -> Result<Grid> {
        let finest = features.iter().map(|f| f.spacing).fold(h, f64::min);
        let levels = (h / finest).log2().ceil().clamp(0.0, MAX_LEVELS as f64) as u32;
        let unit = h / f64::from(1u32 << levels) / 2.0;
        let h_units = 2i64 << levels;
        let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max) + 4.0 * h;
        let mut root_size = h_units;
        while (root_size as f64) * unit < extent {
            root_size *= 2;
            if root_size > (1i64 << 52) {
                return Err(Error::invalid_argument(format!(
                    "h = {h:.3e} is too small for a domain of extent {extent:.3e}"
                )));
            }
        }
        // Centre the root on the domain.
        let mid = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let origin = mid.map(|m| m - 0.5 * root_size as f64 * unit);
        Ok(Grid {
            h,
            unit,
            origin,
            root: Cell {
                origin: [0, 0, 0],
                size: root_size,
            },
        })
    }

    fn point(&self, k: Key) -> [f64; 3] {
        [
            self.origin[0] + k[0] as f64 * self.unit,
            self.origin[1] + k[1] as f64 * self.unit,
            self.origin[2] + k[2] as f64 * self.unit,
        ]
    }

    fn length(&self, units: i64) -> f64 {
        units as f64 * self.unit
    }

    fn finest_cell(&self, tree: &Octree) -> f64 {
        self.length(
            tree.leaves()
                .iter()
                .map(|c| c.size)
                .min()
                .unwrap_or(self.root.size),
        )
    }

    /// The size of the leaf around lattice vertex `v` (a cut point takes the spacing
    /// `h` of the boundary; pinch sites are reported with it).
    fn spacing_at(&self, tree: &Octree, keys: &[Key], v: u32) -> f64 {
        keys.get(v as usize)
            .and_then(|&k| tree.leaf_containing(k))
            .map_or(self.h, |leaf| self.length(leaf.size))
    }
}

/// Half a cell's diagonal, in lengths: the farthest a point of the cell is from its
/// centre.
fn half_diagonal(size: f64) -> f64 {
    0.5 * 3f64.sqrt() * size
}

/// Whether a cell of half diagonal `half_diagonal` whose centre has the value `f` lies
/// wholly outside the region (`f` beyond the half diagonal; `f` is 1-Lipschitz).
fn beyond_cell(f: f64, half_diagonal: f64) -> bool {
    f > half_diagonal * (1.0 + 1e-9)
}

impl Tree {
    /// Whether `cell` was seen to lie wholly outside the region (its centre's value
    /// beyond its half diagonal): tets touching only such leaves produce nothing. A cell
    /// not evaluated (made by the balance) is not. Derived from the centre values
    /// rather than kept in a set of its own: on a thin solid most of the tree's cells
    /// are dead, and a set of them was a hash table as large as the tree.
    fn is_dead(&self, grid: &Grid, cell: &Cell) -> bool {
        self.centre_values
            .get(&cell.center())
            .is_some_and(|&f| beyond_cell(f, half_diagonal(grid.length(cell.size))))
    }
}

/// The octree and what its construction learned about the domain.
struct Tree {
    octree: Octree,
    /// The value at every evaluated cell's centre, by key (a key is the centre of at
    /// most one cell; exact below the cell's band, else a bound of the right sign). It
    /// also tells the dead cells ([`Tree::is_dead`]).
    centre_values: HashMap<Key, f64>,
    leaves: usize,
    estimated_tets: usize,
    /// The tree stopped at each level (the last is the whole tree, before balance).
    truncations: Vec<Truncation>,
}

/// A [`Tree`] once its centre values are dropped: its cells and counts.
struct Built {
    octree: Octree,
    leaves: usize,
    estimated_tets: usize,
    truncations: Vec<Truncation>,
}

/// Where the stuffing of a tree that fitted the budget was over it: the finest level at
/// which that tree, stopped there, fits, its levels' estimates scaled to the tets the
/// stuffing gave ([`scaled_to`]). `None` where no level below `h` fits.
fn expected_fit_level(
    truncations: &[Truncation],
    stuffed: usize,
    options: &StuffingOptions,
) -> Option<f64> {
    scaled_to(truncations, stuffed as f64)
        .iter()
        .filter(|t| t.size <= options.h && t.estimated_tets <= options.max_tets() as f64)
        .map(|t| t.size)
        .reduce(f64::min)
}

/// A whole tree's levels ([`Truncation`]s, the last the whole tree before the 2:1
/// balance) with their estimates scaled so that the last counts `total`: what the
/// balance, or the stuffing, added to the whole is taken to add to every level in the
/// same proportion. Unscaled where the last estimates nothing.
fn scaled_to(truncations: &[Truncation], total: f64) -> Vec<Truncation> {
    let ratio = truncations
        .last()
        .filter(|t| t.estimated_tets > 0.0)
        .map_or(1.0, |t| total / t.estimated_tets);
    truncations
        .iter()
        .map(|t| Truncation {
            estimated_tets: t.estimated_tets * ratio,
            ..*t
        })
        .collect()
}

/// A meshing attempt that failed: over the budget (with the estimate that was), or for
/// another reason.
enum Failed {
    OverBudget {
        estimate: f64,
        /// What the tree would have been, stopped at each level it built (empty
        /// where the stuffing, not the tree, was over).
        truncations: Vec<Truncation>,
        /// Where the stuffing was over: the finest level of its tree expected to fit
        /// ([`expected_fit_level`]).
        expected_fit: Option<f64>,
        error: Error,
    },
    Other(Error),
}

/// An octree stopped at one level: where no cell of that level is split for a thin
/// part, the tree a floor of `size` builds (below the spacing `h`, only thin parts split
/// cells, and a floor of a cell's size splits none of its size: `build_octree`).
#[derive(Debug, Clone, Copy)]
struct Truncation {
    /// The level's cell size.
    size: f64,
    /// The tets that tree would give, estimated as `build_octree` estimates a whole
    /// tree's (before the 2:1 balance, which adds some).
    estimated_tets: f64,
}

impl From<Error> for Failed {
    fn from(e: Error) -> Failed {
        Failed::Other(e)
    }
}

impl Failed {
    fn error(self) -> Error {
        match self {
            Failed::OverBudget { error: e, .. } | Failed::Other(e) => e,
        }
    }
}

fn over_budget(
    estimate: f64,
    truncations: Vec<Truncation>,
    expected_fit: Option<f64>,
    options: &StuffingOptions,
    finest: f64,
) -> Failed {
    Failed::OverBudget {
        estimate,
        truncations,
        expected_fit,
        error: Error::new(
            ErrorKind::OverBudget,
            format!(
                "the volume mesh would take about {estimate:.2e} tets' memory (its tets, or its octree's cells where they weigh more; smallest cells {finest:.2e}), about {} at {BYTES_PER_TET} bytes a tet, over the memory budget of {}: raise it with --max-memory, or pass a larger --h",
                memory_text(estimate * BYTES_PER_TET),
                memory_text(options.max_memory as f64)
            ),
        ),
    }
}

/// A level whose count scaled from its first parts passes the leaves allowed by this
/// factor is over the budget without the rest (the parts are samples; the count is a
/// lower bound on the tree's): ps_mk3s_gantry's inside within 2 GB spent 4.0 of its
/// failed tree's 6.2 s on the part of a level it evaluated, 2.2 times over, before the
/// leaves counted passed the leaves allowed.
const SAMPLED_EXCESS: f64 = 1.25;

/// The leaves an octree under construction has so far, against the budget, and what
/// the tree would give stopped at each level ([`Truncation`]).
///
/// The next level has eight cells for each split one, and a split cell is counted as
/// one leaf more (it was split where the boundary may pass or a thin part asks, so it
/// leaves at least one leaf that gives tets, but for a thin part's split wholly
/// outside): past the leaves allowed the tree is over the budget whatever follows.
/// Leaves wholly outside give no tets (inside a thin solid most of the tree is outside
/// it), but every leaf takes its slots in the tree's tables while the tree is built and
/// tetrahedralized, about a tet's bytes ([`TETS_PER_CELL`]): the leaves of every kind
/// count against the budget too, eight for each split cell.
struct LeafCount {
    max_leaves: usize,
    /// The leaves of every kind the budget allows ([`TETS_PER_CELL`]).
    max_cells: usize,
    /// Leaves of every kind in the finished levels.
    finished_cells: usize,
    /// This level's cells so far, and those of them not split.
    level_cells: usize,
    unsplit_cells: usize,
    /// Leaves not wholly outside in the finished levels: inside, crossed (the boundary
    /// may cross them).
    finished: [usize; 2],
    /// This level's cell size, its leaves and split cells so far, and its cells not
    /// wholly outside (all of them leaves were the tree stopped here) and those of
    /// them not split, inside and crossed.
    size: f64,
    leaves: usize,
    split: usize,
    level: [usize; 2],
    unsplit: [usize; 2],
    truncations: Vec<Truncation>,
    /// The tets (or the tables' bytes in tets, if more) counted when the tree was given
    /// up (the level's count scaled from the part of it evaluated).
    too_big: Option<f64>,
}

impl LeafCount {
    /// Leaves give at least half a leaf's tets each: `max_tets` allows this many.
    fn new(max_tets: usize) -> Self {
        LeafCount {
            max_leaves: (max_tets as f64 / (0.5 * TETS_PER_LEAF)) as usize + 1,
            max_cells: (max_tets as f64 / TETS_PER_CELL) as usize,
            finished_cells: 0,
            level_cells: 0,
            unsplit_cells: 0,
            finished: [0; 2],
            size: 0.0,
            leaves: 0,
            split: 0,
            level: [0; 2],
            unsplit: [0; 2],
            truncations: Vec::new(),
            too_big: None,
        }
    }

    fn start_level(&mut self, size: f64) {
        (self.size, self.leaves, self.split) = (size, 0, 0);
        (self.level, self.unsplit) = ([0; 2], [0; 2]);
        (self.level_cells, self.unsplit_cells) = (0, 0);
    }

    /// One cell of the level: split or not, and `crossed` (whether the boundary may
    /// cross it) unless it is wholly outside.
    fn add(&mut self, split: bool, crossed: Option<bool>) {
        self.level_cells += 1;
        if split {
            self.split += 1;
        } else {
            self.unsplit_cells += 1;
        }
        if let Some(crossed) = crossed {
            let k = usize::from(crossed);
            self.level[k] += 1;
            if !split {
                self.leaves += 1;
                self.unsplit[k] += 1;
            }
        }
    }

    /// After a part of the level (`share` of its cells so far): whether the tree is
    /// over the budget (then it is given up, and the level stopped here is the last
    /// truncation, its counts scaled to the whole level). Over when the leaves counted
    /// pass the leaves allowed, or when the level's count scaled from its part passes
    /// them by [`SAMPLED_EXCESS`] (the parts are samples of the level); the same for
    /// the leaves of every kind.
    fn over(&mut self, share: f64) -> bool {
        let finished = self.finished[0] + self.finished[1];
        let scaled = finished as f64 + (self.leaves + self.split) as f64 / share;
        let cells = self.finished_cells + self.unsplit_cells + 8 * self.split;
        let cells_scaled =
            self.finished_cells as f64 + (self.unsplit_cells + 8 * self.split) as f64 / share;
        let over = finished + self.leaves + self.split > self.max_leaves
            || scaled > SAMPLED_EXCESS * self.max_leaves as f64
            || cells > self.max_cells
            || cells_scaled > SAMPLED_EXCESS * self.max_cells as f64;
        if over || share >= 1.0 {
            let [inside, crossed] = self.level.map(|n| n as f64 / share);
            let tets = TETS_PER_LEAF
                * ((self.finished[0] as f64 + inside) + 0.5 * (self.finished[1] as f64 + crossed));
            // Stopped here, every cell of the level is a leaf.
            let stopped_cells = self.finished_cells as f64 + self.level_cells as f64 / share;
            self.truncations.push(Truncation {
                size: self.size,
                estimated_tets: tets.max(stopped_cells * TETS_PER_CELL),
            });
        }
        if over {
            let leaves = finished + ((self.leaves + self.split) as f64 / share) as usize;
            self.too_big =
                Some((0.5 * TETS_PER_LEAF * leaves as f64).max(cells_scaled * TETS_PER_CELL));
        }
        over
    }

    fn end_level(&mut self) {
        self.finished[0] += self.unsplit[0];
        self.finished[1] += self.unsplit[1];
        self.finished_cells += self.unsplit_cells;
    }
}

/// Refine from the root, level by level: a cell is split while the boundary may pass
/// through it and it is larger than the spacing wanted there, or while a sizing
/// feature that reaches it asks for smaller cells. Then balance, and estimate the tets.
fn build_octree(
    domain: &dyn Domain,
    grid: &Grid,
    features: &[SizingFeature],
    options: &StuffingOptions,
    known: &mut CentreValues,
) -> std::result::Result<Tree, Failed> {
    let h = grid.h;
    let coarsest = domain.coarsest_spacing(h).max(h);
    // Leaves not wholly outside give at least half a leaf's tets each, and every leaf
    // takes about a tet's bytes in the tables: past either count the tree is over the
    // budget whatever follows ([`LeafCount`]).
    let mut count = LeafCount::new(options.max_tets());
    let mut centre_values: HashMap<Key, f64> = HashMap::default();
    let mut lists = sizing::FeatureLists::new(features, grid.root, h);
    let to_point = |k: Key| grid.point(k);
    let octree = Octree::build_unless(grid.root, |cells| {
        // All cells of one level have the same size.
        let size = grid.length(cells.first().map_or(0, |c| c.size));
        let half_diagonal = half_diagonal(size);
        let thin = lists.level(cells, &to_point, grid.unit);
        // In up to eight interleaved parts (`level_parts`), each a sample of the whole
        // level: past the leaves allowed, or once the part evaluated, scaled to the
        // level, is well past them ([`LeafCount::over`]), the rest of the level is not
        // evaluated (a level costs a distance per cell; figures in
        // `docs/decisions.md`, Volume mesh), the next level not built, nor the tree
        // balanced.
        count.start_level(size);
        let mut decisions = vec![false; cells.len()];
        let mut evaluated = 0;
        for part in level_parts(cells.len()) {
            // The values an earlier tree evaluated, and the others.
            let mut values: Vec<f64> = part
                .iter()
                .map(|&i| known.get(grid.point(cells[i].center())).unwrap_or(f64::NAN))
                .collect();
            let unknown: Vec<usize> = (0..part.len()).filter(|&j| values[j].is_nan()).collect();
            let centres: Vec<[f64; 3]> = unknown
                .iter()
                .map(|&j| grid.point(cells[part[j]].center()))
                .collect();
            // A cell's centre is half its diagonal from its parent's: where the
            // parent's value is larger (f is 1-Lipschitz; a value beyond the band is a
            // bound), no boundary lies between them and the sign is the parent's.
            let signs: Vec<i8> = unknown
                .iter()
                .map(|&j| {
                    octree::parent(grid.root, cells[part[j]])
                        .and_then(|parent| centre_values.get(&parent.center()))
                        .filter(|f| f.abs() > half_diagonal * (1.0 + 1e-9))
                        .map_or(0, |f| if *f < 0.0 { -1 } else { 1 })
                })
                .collect();
            let found = domain.values_within_signed(&centres, half_diagonal + coarsest, &signs);
            for (&j, f) in unknown.iter().zip(found) {
                values[j] = f;
            }
            for (&i, f) in part.iter().zip(values) {
                let cell = &cells[i];
                centre_values.insert(cell.center(), f);
                let is_dead = beyond_cell(f, half_diagonal);
                // Cell sizes are powers of two: take the one nearest the spacing asked
                // for (within a factor √2). Else only where the boundary may pass (f is
                // 1-Lipschitz). A margin of one more cell (`half_diagonal + wanted`)
                // keeps a band of fine cells 3–4 h thick on each side: 15–30 % more
                // unknowns and the same loops, angles and topology on the shared
                // models.
                let split = thin[i] * std::f64::consts::SQRT_2 < size
                    || (f.abs() < half_diagonal
                        && size
                            > domain.spacing_near(grid.point(cell.center()), h).max(h)
                                * (1.0 + 1e-9));
                count.add(split, (!is_dead).then_some(f >= -half_diagonal));
                decisions[i] = split;
            }
            evaluated += part.len();
            if count.over(evaluated as f64 / cells.len() as f64) {
                return None;
            }
        }
        count.end_level();
        Some(decisions)
    });
    let (Some(octree), None) = (octree, count.too_big) else {
        // The next tree of the search (a coarser floor) takes the values.
        known.take(grid, centre_values);
        let finest = count.truncations.last().map_or(h, |t| t.size);
        let estimate = count.too_big.unwrap_or(0.0);
        return Err(over_budget(
            estimate,
            count.truncations,
            None,
            options,
            finest,
        ));
    };
    let leaves = octree.leaves();
    // Leaves inside give all their tets, leaves the boundary may cross about half.
    let (mut inside, mut crossed) = (0usize, 0usize);
    for leaf in &leaves {
        let half_diagonal = half_diagonal(grid.length(leaf.size));
        match centre_values.get(&leaf.center()) {
            Some(&f) if beyond_cell(f, half_diagonal) => {}
            Some(&f) if f < -half_diagonal => inside += 1,
            _ => crossed += 1,
        }
    }
    let estimated_tets = (TETS_PER_LEAF * (inside as f64 + 0.5 * crossed as f64)) as usize;
    let finest = grid.length(
        leaves
            .iter()
            .map(|c| c.size)
            .min()
            .unwrap_or(grid.root.size),
    );
    // The tets, or the tables' share where the leaves of every kind weigh more.
    let weight = (estimated_tets as f64).max(leaves.len() as f64 * TETS_PER_CELL);
    if weight > options.max_tets() as f64 {
        known.take(grid, centre_values);
        // The balance added cells round the finest ones: the levels are taken to grow
        // in the same proportion, so that a floor at a level still over is not tried
        // (`docs/decisions.md`, Volume mesh).
        return Err(over_budget(
            weight,
            scaled_to(&count.truncations, weight),
            None,
            options,
            finest,
        ));
    }
    Ok(Tree {
        leaves: leaves.len(),
        octree,
        centre_values,
        estimated_tets,
        truncations: count.truncations,
    })
}

/// Cell centre values by position (bit for bit), kept from one octree to the next
/// within a floor search. A point is the centre of at most one cell size of the root
/// (the grids of different floors share the root and its origin, and scale their
/// units by powers of two, so positions agree to the bit), and a cell's value depends
/// only on the cell (the distance within its band, the sign from its parent's): a
/// later tree takes it instead of evaluating it again. On a budget-bound model the
/// tree that fits is the failed tree's upper levels. A tree that is not kept (over the
/// budget, or the calibration's) hands its values over ([`CentreValues::take`]).
#[derive(Default)]
struct CentreValues(HashMap<[u64; 3], f64>);

impl CentreValues {
    fn get(&self, p: [f64; 3]) -> Option<f64> {
        self.0.get(&p.map(f64::to_bits)).copied()
    }

    /// Keeps the values of a tree on `grid` (by key) for the next tree.
    fn take(&mut self, grid: &Grid, values: HashMap<Key, f64>) {
        self.0.reserve(values.len());
        for (k, f) in values {
            self.0.insert(grid.point(k).map(f64::to_bits), f);
        }
    }
}

/// The parts a level of `n` cells is evaluated in: up to eight, of at least
/// [`MIN_PART`] cells each, interleaved so that each is a sample of the whole level. A
/// level lists the eight children of each split cell together, parents in the order of
/// the level above: cell `i` goes to part `(i + i / 8) mod parts`, one child of each
/// parent in every part (of eight), the child turning from parent to parent.
fn level_parts(n: usize) -> Vec<Vec<usize>> {
    let parts = (n / MIN_PART).clamp(1, 8);
    let mut out = vec![Vec::with_capacity(n / parts + 1); parts];
    for i in 0..n {
        out[(i + i / 8) % parts].push(i);
    }
    out
}

/// The fewest cells a part of a level ([`level_parts`]) holds, but for a level smaller
/// than it: a sample this large scales to the level within a few per cent.
const MIN_PART: usize = 1 << 14;

/// The domain's value at each lattice vertex. The centre of a cell evaluated while
/// building the tree (a leaf's centre, or a corner its parent's centre became) has its
/// value already; a vertex inside a leaf whose centre value exceeds the half diagonal
/// has that sign (the function is 1-Lipschitz); only the others are evaluated, exactly
/// within `h`.
fn lattice_values(
    domain: &dyn Domain,
    grid: &Grid,
    tree: &Tree,
    keys: &[Key],
    positions: &[[f64; 3]],
) -> Vec<f64> {
    let mut values = vec![0.0; positions.len()];
    let mut unknown = Vec::new();
    for (v, &k) in keys.iter().enumerate() {
        if let Some(&f) = tree.centre_values.get(&k) {
            if f != 0.0 {
                values[v] = f;
                continue;
            }
        }
        let known = tree.octree.leaf_containing(k).and_then(|leaf| {
            let f = *tree.centre_values.get(&leaf.center())?;
            let half_diagonal = half_diagonal(grid.length(leaf.size));
            (f.abs() > half_diagonal * (1.0 + 1e-6))
                .then(|| f.signum() * (f.abs() - half_diagonal).max(1e-6 * half_diagonal))
        });
        match known {
            Some(f) => values[v] = f,
            None => unknown.push(v),
        }
    }
    let points: Vec<[f64; 3]> = unknown.iter().map(|&v| positions[v]).collect();
    for (&v, f) in unknown.iter().zip(domain.values_within(&points, grid.h)) {
        values[v] = f;
    }
    values
}

/// The tet mesh of the kept tets over the vertices they use, in index order, with
/// vertex kinds: interior where the sign was negative, else the domain's boundary kind.
fn compact(
    domain: &dyn Domain,
    positions: &[[f64; 3]],
    tets: &[[u32; 4]],
    interior: &[bool],
) -> Result<TetMesh> {
    let (new_id, used) = renumber_used(positions.len(), tets);
    let out_positions: Vec<[f64; 3]> = used.iter().map(|&v| positions[v as usize]).collect();
    let kinds = used
        .iter()
        .map(|&v| {
            if interior[v as usize] {
                VertexKind::Interior
            } else {
                domain.boundary_kind(positions[v as usize])
            }
        })
        .collect();
    let tets: Vec<[u32; 4]> = tets.iter().map(|t| t.map(|v| new_id[v as usize])).collect();
    TetMesh::new(out_positions, tets, kinds)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slab `|z| ≤ 0.1` in the box `|x|, |y| ≤ 1`, whose mid-plane asks for cells of
    /// `spacing` within `0.1` of it: a thin part everywhere.
    struct Slab {
        spacing: f64,
    }

    impl Domain for Slab {
        fn value(&self, p: [f64; 3]) -> f64 {
            (p[2].abs() - 0.1)
                .max(p[0].abs() - 1.0)
                .max(p[1].abs() - 1.0)
        }
        fn boundary_kind(&self, _p: [f64; 3]) -> crate::tet::VertexKind {
            crate::tet::VertexKind::Surface
        }
        fn bounds(&self) -> ([f64; 3], [f64; 3]) {
            ([-1.0, -1.0, -0.1], [1.0, 1.0, 0.1])
        }
        fn sizing(&self) -> Vec<SizingFeature> {
            let corners = [
                [-1.0, -1.0, 0.0],
                [1.0, -1.0, 0.0],
                [1.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ];
            [[0, 1, 2], [0, 2, 3]]
                .map(|t| SizingFeature {
                    corners: t.map(|i| corners[i]),
                    spacing: self.spacing,
                    reach: 0.1,
                    toward: [0.0; 3],
                })
                .to_vec()
        }
    }

    fn tree_at(
        slab: &Slab,
        floor: Option<f64>,
        options: &StuffingOptions,
    ) -> std::result::Result<Tree, Failed> {
        let features = clamp_spacing(&slab.sizing(), floor);
        let (lo, hi) = slab.bounds();
        let grid = Grid::new(lo, hi, options.h, &features).unwrap();
        build_octree(
            slab,
            &grid,
            &features,
            options,
            &mut CentreValues::default(),
        )
    }

    #[test]
    fn a_tree_over_the_budget_names_the_finest_level_that_fits() {
        let slab = Slab { spacing: 1e-3 };
        let options = StuffingOptions {
            max_memory: (200_000.0 * BYTES_PER_TET) as u64,
            ..StuffingOptions::new(0.25)
        };
        let Err(Failed::OverBudget { truncations, .. }) = tree_at(&slab, None, &options) else {
            panic!("the finest tree fits a budget it cannot fit");
        };
        // Level by level, halving, with more tets at every finer level.
        for pair in truncations.windows(2) {
            assert!((pair[0].size / pair[1].size - 2.0).abs() < 1e-12);
            assert!(pair[1].estimated_tets >= pair[0].estimated_tets);
        }
        let fitting = truncations
            .iter()
            .rev()
            .find(|t| t.size <= options.h && t.estimated_tets <= options.max_tets() as f64)
            .copied()
            .expect("a level below h fits");
        // A floor of that level's size builds the tree stopped there (its finest cells
        // are that size; the 2:1 balance only adds tets) ...
        let roomy = StuffingOptions {
            max_memory: u64::MAX,
            ..options
        };
        let Ok(tree) = tree_at(&slab, Some(fitting.size), &roomy) else {
            panic!("no tree at the level that fits");
        };
        let (lo, hi) = slab.bounds();
        let grid = Grid::new(
            lo,
            hi,
            options.h,
            &clamp_spacing(&slab.sizing(), Some(fitting.size)),
        )
        .unwrap();
        assert!((grid.finest_cell(&tree.octree) / fitting.size - 1.0).abs() < 1e-12);
        assert!(tree.estimated_tets as f64 >= fitting.estimated_tets);
        // ... and half of it, one level finer, is over the budget.
        assert!(matches!(
            tree_at(&slab, Some(0.5 * fitting.size), &options),
            Err(Failed::OverBudget { .. })
        ));
        // The whole search lands there (or a level coarser, where the balance or the
        // stuffing took the level over) and within the budget.
        let mesh = stuff_volume(&slab, &options).unwrap();
        assert!(mesh.mesh.num_tets() <= options.max_tets());
        let finest = mesh.stats.finest_cell;
        assert!(
            finest <= 2.0 * fitting.size * (1.0 + 1e-12),
            "finest cell {finest}, level that fits {}",
            fitting.size
        );
    }

    /// A domain that counts the points it is asked for.
    struct Counted<'a> {
        inner: &'a dyn Domain,
        points: std::sync::atomic::AtomicUsize,
    }

    impl Domain for Counted<'_> {
        fn value(&self, p: [f64; 3]) -> f64 {
            self.points
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.inner.value(p)
        }
        fn boundary_kind(&self, p: [f64; 3]) -> crate::tet::VertexKind {
            self.inner.boundary_kind(p)
        }
        fn bounds(&self) -> ([f64; 3], [f64; 3]) {
            self.inner.bounds()
        }
        fn sizing(&self) -> Vec<SizingFeature> {
            self.inner.sizing()
        }
    }

    #[test]
    fn a_tree_built_after_another_takes_its_values_and_is_the_same_tree() {
        let slab = Slab { spacing: 1e-3 };
        let options = StuffingOptions::new(0.25);
        let counted = Counted {
            inner: &slab,
            points: 0.into(),
        };
        let build = |floor: f64, known: &mut CentreValues| {
            let features = clamp_spacing(&slab.sizing(), Some(floor));
            let (lo, hi) = slab.bounds();
            let grid = Grid::new(lo, hi, options.h, &features).unwrap();
            let Ok(tree) = build_octree(&counted, &grid, &features, &options, known) else {
                panic!("a tree over a budget of {} tets", options.max_tets());
            };
            let mut values: Vec<([u64; 3], u64)> = tree
                .centre_values
                .iter()
                .map(|(&k, &f)| (grid.point(k).map(f64::to_bits), f.to_bits()))
                .collect();
            values.sort_unstable();
            let mut dead: Vec<[u64; 3]> = tree
                .octree
                .leaves()
                .iter()
                .filter(|c| tree.is_dead(&grid, c))
                .map(|c| grid.point(c.center()).map(f64::to_bits))
                .collect();
            dead.sort_unstable();
            let leaves: Vec<([u64; 3], u64)> = tree
                .octree
                .leaves()
                .iter()
                .map(|c| {
                    (
                        grid.point(c.center()).map(f64::to_bits),
                        grid.length(c.size).to_bits(),
                    )
                })
                .collect();
            let estimated = tree.estimated_tets;
            // Handed over as the search hands over a tree it does not keep.
            let mut handed = CentreValues::default();
            handed.take(&grid, tree.centre_values);
            ((leaves, dead, values, estimated), handed)
        };
        let points = || counted.points.load(std::sync::atomic::Ordering::Relaxed);
        // Alone, the finer tree evaluates every cell centre it has.
        let (alone, _) = build(0.03, &mut CentreValues::default());
        let alone_points = points();
        assert_eq!(alone_points, alone.2.len());
        // After a coarser tree, with its values: the same leaves, dead cells, values
        // (to the bit) and estimate, and only the centres the coarser tree lacked.
        let (coarse, mut known) = build(0.1, &mut CentreValues::default());
        let before = points();
        let (after, _) = build(0.03, &mut known);
        assert!(after == alone, "the tree changed with the values kept");
        let shared = coarse
            .2
            .iter()
            .filter(|v| alone.2.binary_search(v).is_ok())
            .count();
        assert!(shared > 0 && shared < alone.2.len());
        assert_eq!(points() - before, alone_points - shared);
    }

    #[test]
    fn a_level_goes_in_interleaved_parts_that_cover_it_once() {
        for n in [
            0,
            1,
            7,
            MIN_PART - 1,
            3 * MIN_PART + 5,
            8 * MIN_PART,
            20 * MIN_PART + 3,
        ] {
            let parts = level_parts(n);
            assert_eq!(parts.len(), (n / MIN_PART).clamp(1, 8));
            let mut all: Vec<usize> = parts.concat();
            all.sort_unstable();
            assert_eq!(all, (0..n).collect::<Vec<_>>(), "{n} cells");
            if parts.len() == 8 {
                // One child of each parent (eight cells in a row) in every part, the
                // child turning from parent to parent.
                for (j, part) in parts.iter().enumerate() {
                    for (p, &i) in part.iter().take(n / 8).enumerate() {
                        assert_eq!(i / 8, p);
                        assert_eq!(i % 8, (j + 8 - p % 8) % 8);
                    }
                }
            }
        }
    }

    #[test]
    fn a_level_whose_part_scales_well_over_the_budget_gives_the_tree_up() {
        // 800 leaves allowed: a part of an eighth with 60 leaves and 60 splits scales
        // to 960 (1.2 times), with 70 and 60 to 1 040 (1.3 times).
        let max_tets = (799.5 * 0.5 * TETS_PER_LEAF) as usize;
        for (leaves, over) in [(60, false), (70, true)] {
            let mut count = LeafCount::new(max_tets);
            assert_eq!(count.max_leaves, 800);
            count.start_level(1.0);
            for k in 0..leaves + 60 {
                count.add(k < 60, Some(k % 2 == 0));
            }
            assert_eq!(count.over(0.125), over, "{leaves} leaves in the part");
            if over {
                assert_eq!(count.too_big, Some(0.5 * TETS_PER_LEAF * 1040.0));
                let last = count.truncations.last().expect("the level stopped here");
                assert_eq!(last.size, 1.0);
            }
        }
        // Counted leaves past the leaves allowed give it up whatever the share.
        let mut count = LeafCount::new(max_tets);
        count.start_level(1.0);
        for _ in 0..801 {
            count.add(false, Some(true));
        }
        assert!(count.over(1.0));
    }

    #[test]
    fn leaves_wholly_outside_count_against_the_budget_by_their_tables() {
        // 1 000 tets allow 1 000 leaves of any kind, and 134 that give tets.
        let max_tets = 1_000;
        let cells = (max_tets as f64 / TETS_PER_CELL) as usize;
        // Dead leaves give no tets, but past the cells allowed the tree is over.
        let mut count = LeafCount::new(max_tets);
        count.start_level(1.0);
        for _ in 0..cells {
            count.add(false, None);
        }
        assert!(!count.over(1.0), "as many dead leaves as allowed");
        count.end_level();
        count.start_level(0.5);
        count.add(false, None);
        assert!(count.over(1.0), "one dead leaf more");
        assert_eq!(count.too_big, Some((cells + 1) as f64 * TETS_PER_CELL));
        // Stopped at either level, the tree weighs its leaves, not its (no) tets.
        let weights: Vec<f64> = count.truncations.iter().map(|t| t.estimated_tets).collect();
        assert_eq!(weights, vec![cells as f64, (cells + 1) as f64]);
        // A split dead cell leaves eight leaves at least.
        let mut count = LeafCount::new(max_tets);
        count.start_level(1.0);
        for _ in 0..cells / 8 + 1 {
            count.add(true, None);
        }
        assert!(count.over(1.0), "{} splits", cells / 8 + 1);
    }

    #[test]
    fn a_stuffing_over_the_budget_expects_a_fit_where_its_own_count_scaled_says() {
        // Levels of a tree whose estimate undercounted: the stuffing gave 20 000 tets
        // where its finest level estimated 16 000 (a quarter more at every level).
        let options = StuffingOptions {
            max_memory: (10_000.0 * BYTES_PER_TET) as u64,
            ..StuffingOptions::new(0.5)
        };
        let levels = [
            (1.0, 300.0),
            (0.5, 1_000.0),
            (0.25, 4_000.0),
            (0.125, 16_000.0),
        ]
        .map(|(size, estimated_tets)| Truncation {
            size,
            estimated_tets,
        });
        // 0.25 scales to 5 000 (fits), 0.125 to 20 000 (over); 1.0 is above h.
        assert_eq!(expected_fit_level(&levels, 20_000, &options), Some(0.25));
        // A stuffing that gave half the estimate fits at the finest level.
        assert_eq!(expected_fit_level(&levels, 8_000, &options), Some(0.125));
        // Where no level below h fits, none is named.
        assert_eq!(expected_fit_level(&levels, 1_000_000, &options), None);
        assert_eq!(expected_fit_level(&[], 20_000, &options), None);
        // The balance's share (a tree built whole that counts twice its last level)
        // goes to every level alike.
        let scaled = scaled_to(&levels, 32_000.0);
        for (t, s) in levels.iter().zip(&scaled) {
            assert_eq!((s.size, s.estimated_tets), (t.size, 2.0 * t.estimated_tets));
        }
        let empty = [0.5, 0.25].map(|size| Truncation {
            size,
            estimated_tets: 0.0,
        });
        assert_eq!(scaled_to(&empty, 1_000.0)[1].estimated_tets, 0.0);
    }

    #[test]
    fn a_tree_that_gives_up_is_not_built() {
        let root = Cell {
            origin: [0; 3],
            size: 64,
        };
        let mut levels = 0;
        let given_up = Octree::build_unless(root, |cells| {
            levels += 1;
            (levels < 3).then(|| vec![true; cells.len()])
        });
        assert!(given_up.is_none());
        assert_eq!(levels, 3);
        let whole = Octree::build_unless(root, |cells| Some(vec![cells[0].size > 16; cells.len()]));
        assert_eq!(whole.map(|t| t.leaves().len()), Some(64));
    }
}
