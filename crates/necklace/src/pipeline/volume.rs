//! The volume stage on a surface: one side of a closed surface as an implicit domain,
//! the sizing that resolves its thin parts and gaps, the mesher call, and the check that
//! the mesh has the topology the surface predicts, refining where it does not.
//!
//! Topology comes first: necks are read off the volume mesh, so an extra tunnel through
//! a thin wall or a lost thin part is an extra or missing neck. [`volume_mesh`]:
//! 1. predicts the topology ([`expected_topology`]): per component of the inside (or of
//!    the shell) its χ and the χ of each boundary surface, from the surface's
//!    components, their genus and how they nest;
//! 2. measures at every surface vertex the thickness of the solid and the width of the
//!    gap in front of it (a ray along the vertex normal, then the inscribed ball touching
//!    there: the medial distance, which sees a wire's diameter where the ray sees a
//!    chord) and asks for cells half of that wherever it is below `2h`
//!    ([`SizingFeature`]s over the thin triangles, reaching into the part; no fixed
//!    floor: the tet budget sets it). Folds of the surface and places where it crosses
//!    itself are not parts, and are skipped;
//! 3. finds the creases and corners for the mesher to snap its boundary onto;
//! 4. meshes (`volume::stuff_volume`), compares the mesh's topology with the
//!    prediction, and where they differ refines where the mesh shows why (pinches,
//!    swallowed boundary vertices, and surface vertices the mesh's boundary does not
//!    come near) and meshes again, up to [`MAX_ROUNDS`] times, keeping the mesh closest
//!    to the prediction. A difference that remains, or a budget that bound, is reported
//!    in [`VolumeResult::warnings`] with the figures, never dropped.
//!
//! Conventions: lengths in the surface's units; the outer sphere of a shell is centred
//! at the bounding box's centre with radius `sphere_scale` × half its diagonal.

use std::time::Instant;

use serde::Serialize;

use crate::distance::SurfaceDistance;
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, dot, norm, scale, sub};
use crate::mesh::{MeshReport, Side, SurfaceMesh, Topology};
use crate::tet::{ComponentTopology, TetMesh, TetTopology, VertexKind};
use crate::volume::{self, Domain, SharpFeatures, SizingFeature, StuffingOptions, StuffingStats};

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
    /// [`default_h`]. Thin parts and gaps get finer cells whatever `h` is.
    pub h: Option<f64>,
    /// Outer sphere radius as a multiple of the bounding box's half diagonal (default
    /// 1.5), centred at the box centre.
    pub sphere_scale: f64,
    /// The most tets the mesh may have (default 20 million): a run estimated above it
    /// is refused with the estimate, and refinement for topology stops at it.
    pub max_tets: usize,
    /// The quality step's target smallest dihedral angle, degrees (default 10).
    pub min_dihedral_deg: f64,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            mesher: Mesher::Stuffing,
            h: None,
            sphere_scale: 1.5,
            max_tets: volume::DEFAULT_MAX_TETS,
            min_dihedral_deg: 10.0,
        }
    }
}

/// Most meshings of one side: the first, and refinements while the topology differs
/// from the surface's.
pub const MAX_ROUNDS: usize = 4;

/// Cells along the curve where the surface crosses itself are this many times finer
/// than `h`.
const CROSSING_REFINEMENT: f64 = 8.0;

/// The largest lattice spacing accepted, as a fraction of the bounding-box diagonal.
const MAX_H_FRACTION: f64 = 0.25;

/// The inside mesh's volume may differ from the volume the surface encloses by this
/// fraction before a warning says so (the boundary's chords cut off a little).
const VOLUME_TOLERANCE: f64 = 0.05;

/// Parts and gaps thinner than this many `h` get finer cells (at `h`, two cells across).
const THIN_FACTOR: f64 = 2.0;

/// Cells across a thin part or gap. Warping moves a vertex by at most 0.36 of a cell,
/// so two cells across leave a core of more than a cell whose lattice vertices stay
/// inside and connect along the part. (Where that is not enough, the topology check
/// finds it and refines.)
const CELLS_ACROSS: f64 = 2.0;

/// A contact of the inscribed ball counts as the opposite wall (not the surface curving
/// next to the vertex) when it is at least this angle round the ball from the vertex.
const MIN_SEPARATION_DEG: f64 = 120.0;

/// A part or gap thinner than 1/`FOLD_RATIO` of the shortest edge at a vertex is taken
/// for a fold of the surface there, not refined for: a real thin part is drawn with
/// edges not much longer than its thickness somewhere around it (a plate's rim, a
/// wire's section).
const FOLD_RATIO: f64 = 20.0;

/// An edge whose two faces' normals differ by more than this is a crease.
const CREASE_DEG: f64 = 40.0;

/// Most shrinking steps of the inscribed ball at a vertex (each a closest-point query);
/// a ball still shrinking after them is taken as not thin.
const MEDIAL_STEPS: usize = 8;

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
    /// The stuffing mesher's counts of the last round (`None` for TetGen).
    pub stats: Option<StuffingStats>,
    /// Surface vertices whose part or gap is thinner than `2h`.
    pub thin_vertices: usize,
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
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
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
    /// Lattice spacing along the surface (stuffing).
    pub h: f64,
    /// Smallest cell used (thin parts; stuffing).
    pub finest_cell: f64,
    /// Surface vertices whose part or gap is thinner than `2h`.
    pub thin_vertices: usize,
    /// The stuffing mesher's counts (last round; absent for TetGen).
    pub stuffing: Option<StuffingStats>,
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
            h: self.h,
            finest_cell: self.stats.map_or(0.0, |s| s.finest_cell),
            thin_vertices: self.thin_vertices,
            stuffing: self.stats,
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

    let mut distance = SurfaceDistance::new(surface);
    let centre = scale(add(lo, hi), 0.5);
    let radius = options.sphere_scale * 0.5 * diagonal;
    let mut warnings = Vec::new();
    let crossings = distance.self_intersections(&surface.triangles);
    let expected = if crossings.is_empty() {
        // A closed manifold that does not cross itself: the closest point tells the
        // sign (exact, and much cheaper near the surface than the winding number).
        distance.use_pseudonormal_sign(surface);
        predict(surface, side)
    } else {
        warnings.push(format!(
            "the surface crosses itself ({} pairs of triangles): the {} volume is the solid its winding number encloses, whose topology the genus does not predict",
            crossings.len(),
            side.name()
        ));
        None
    };
    let (mesh, found, stats, thin_vertices, rounds) = match options.mesher {
        Mesher::Stuffing => {
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
            let thickness = thickness(surface, &topology, &distance, &crossing, THIN_FACTOR * h);
            let thin_vertices = thickness
                .iter()
                .filter(|t| t.iter().any(|x| x.is_finite()))
                .count();
            let mut spacing: Vec<f64> = thickness
                .iter()
                .map(|t| (t[0].min(t[1]) / CELLS_ACROSS).min(h))
                .collect();
            // Where the surface crosses itself, the solid's boundary has a crease along
            // the crossing curve (two overlapping balls meet in a concave ring): it is
            // snapped onto like any crease, with cells finer there so that the mesh's
            // edges follow it instead of zigzagging across it.
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
            let mut sizing = thin_part_sizing(surface, &thickness);
            let crease_cell = h / CROSSING_REFINEMENT;
            sizing.extend(crossing_curve.iter().map(|&[p, q]| SizingFeature {
                corners: [p, q, q],
                spacing: crease_cell,
                reach: 2.0 * crease_cell,
                toward: [0.0; 3],
            }));
            let mut domain = SurfaceDomain {
                distance: &distance,
                side,
                centre,
                radius,
                bounds: (lo, hi),
                sizing,
                features,
            };
            let stuffing = StuffingOptions {
                h,
                max_tets: options.max_tets,
                min_dihedral_deg: options.min_dihedral_deg,
            };
            if side == Side::Inside {
                refuse_if_all_below_floor(&domain.sizing, &thickness, &stuffing)?;
            }
            let (stuffed, found, rounds) = mesh_until_topology_matches(
                surface,
                &mut domain,
                &mut spacing,
                &stuffing,
                &expected,
                &mut warnings,
            )?;
            (
                stuffed.mesh,
                found,
                Some(stuffed.stats),
                thin_vertices,
                rounds,
            )
        }
        Mesher::Tetgen => {
            let mesh = tetgen_mesh(surface, side, centre, radius)?;
            let found = mesh.topology();
            (mesh, found, None, 0, 1)
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
                "the tet budget ({} tets) kept cells of the {} volume mesh from going below {floor:.3e}: parts or gaps thinner than {:.3e} may have lost their topology (raise --max-tets)",
                options.max_tets,
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
    let hausdorff = hausdorff_to_surface(&mesh, &distance) / diagonal;

    Ok(VolumeResult {
        mesh,
        side,
        h,
        sphere: (side == Side::Outside).then_some((centre, radius)),
        mesher: options.mesher,
        stats,
        thin_vertices,
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

/// Mesh, compare with the prediction, refine where the mesh shows a feature below the
/// resolution, and mesh again while the topology differs (at most [`MAX_ROUNDS`]
/// meshings), keeping the mesh closest to the prediction; a round that moves away from
/// it ends the rounds. `spacing[v]` is the cell size asked for at surface vertex `v`
/// (halved where a round refines). A refinement the budget refuses ends the rounds with
/// the best mesh so far, and says so in `warnings`.
fn mesh_until_topology_matches(
    surface: &SurfaceMesh,
    domain: &mut SurfaceDomain<'_>,
    spacing: &mut [f64],
    options: &StuffingOptions,
    expected: &Option<TetTopology>,
    warnings: &mut Vec<String>,
) -> Result<(volume::VolumeMesh, TetTopology, usize)> {
    let stuffed = volume::stuff_volume(domain, options)?;
    let found = stuffed.mesh.topology();
    let Some(expected) = expected else {
        return Ok((stuffed, found, 1));
    };
    let mut best_distance = topology_distance(&found, expected);
    // Where the budget already floors the spacing, finer cells are out of reach.
    let floored = stuffed.stats.spacing_floor.is_some();
    let mut best = (stuffed, found);
    let mut rounds = 1;
    while best_distance > 0 && rounds < MAX_ROUNDS && !floored {
        let refine = unresolved_features(surface, &best.0, spacing);
        if refine.is_empty() {
            break;
        }
        domain.sizing.extend(refine);
        rounds += 1;
        let next = match volume::stuff_volume(domain, options) {
            Ok(next) => next,
            Err(e) if e.kind() == ErrorKind::OverBudget => {
                warnings.push(format!(
                    "refinement for topology stopped at the tet budget: {}",
                    e.message()
                ));
                break;
            }
            Err(e) => return Err(e),
        };
        let found = next.mesh.topology();
        let distance = topology_distance(&found, expected);
        if distance > best_distance {
            break;
        }
        if distance < best_distance {
            best_distance = distance;
            best = (next, found);
        }
    }
    Ok((best.0, best.1, rounds))
}

/// Refuse at once when the budget floors the spacing above the thickness of every part
/// of the solid: the mesh would be empty (or nearly), after all the work.
fn refuse_if_all_below_floor(
    sizing: &[SizingFeature],
    thickness: &[[f64; 2]],
    options: &StuffingOptions,
) -> Result<()> {
    let Some(floor) = volume::spacing_floor(sizing, options) else {
        return Ok(());
    };
    let thickest = thickness.iter().map(|t| t[0]).fold(0.0, f64::max);
    if thickest < floor {
        return Err(Error::new(
            ErrorKind::OverBudget,
            format!(
                "every part of the solid is thinner than {thickest:.3e}, but the budget of {} tets allows no cells below {floor:.3e}: raise it with --max-tets",
                options.max_tets
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
    stuffed: &volume::VolumeMesh,
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

/// The topology a closed, embedded surface predicts for one side's volume: inside,
/// one component per outward-facing surface component, bounded by it and by the
/// inward-facing components (cavities) directly inside it; outside, the shell bounded
/// by the outer sphere and the outermost components, plus one component per cavity,
/// bounded by it and the components directly inside it. `None` when a component's
/// genus is undefined or the surface crosses itself.
pub fn expected_topology(surface: &SurfaceMesh, side: Side) -> Option<TetTopology> {
    let distance = SurfaceDistance::new(surface);
    if !distance.self_intersections(&surface.triangles).is_empty() {
        return None;
    }
    predict(surface, side)
}

/// [`expected_topology`] of a surface known not to cross itself.
fn predict(surface: &SurfaceMesh, side: Side) -> Option<TetTopology> {
    let report = MeshReport::new(surface);
    let comps = &report.component_details;
    if comps.is_empty() || comps.iter().any(|c| c.genus.is_none() || c.faces == 0) {
        return None;
    }
    let parent = nesting(surface, &report)?;
    let outward: Vec<bool> = comps.iter().map(|c| c.signed_volume > 0.0).collect();
    // A region of space is bounded by one "owner" component and the components whose
    // parent is that owner; inside regions are owned by outward components, outside
    // regions by cavities (and the outer sphere, owner `None`).
    let mut regions: Vec<ComponentTopology> = Vec::new();
    let owners: Vec<Option<usize>> = match side {
        Side::Inside => (0..comps.len()).filter(|&i| outward[i]).map(Some).collect(),
        Side::Outside => std::iter::once(None)
            .chain((0..comps.len()).filter(|&i| !outward[i]).map(Some))
            .collect(),
    };
    for owner in owners {
        let mut boundary: Vec<i64> = match owner {
            Some(o) => vec![comps[o].euler],
            None => vec![2],
        };
        for (i, c) in comps.iter().enumerate() {
            if parent[i] == owner && Some(i) != owner {
                // A child must face the other way from its owner (an outward solid
                // inside a cavity, a cavity inside a solid).
                if owner.is_some_and(|o| outward[o] == outward[i])
                    || (owner.is_none() && !outward[i])
                {
                    return None;
                }
                boundary.push(c.euler);
            }
        }
        let euler = boundary.iter().sum::<i64>() / 2;
        regions.push(ComponentTopology {
            euler,
            boundary_eulers: boundary,
        });
    }
    Some(TetTopology::new(regions))
}

/// The component directly enclosing each component of the surface (`None` for the
/// outermost), by the winding number of each component's triangles at points of the
/// others. `None` when two components cross (a component partly inside another).
pub(super) fn nesting(surface: &SurfaceMesh, report: &MeshReport) -> Option<Vec<Option<usize>>> {
    let n = report.component_details.len();
    if n == 1 {
        return Some(vec![None]);
    }
    let (component_of, _) = Topology::new(surface).components(surface);
    let mut triangles: Vec<Vec<[u32; 3]>> = vec![Vec::new(); n];
    let mut vertices: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in &surface.triangles {
        if let Some(c) = component_of[t[0] as usize] {
            triangles[c as usize].push(*t);
        }
    }
    for (v, c) in component_of.iter().enumerate() {
        if let Some(c) = c {
            vertices[*c as usize].push(v as u32);
        }
    }
    let boxes: Vec<([f64; 3], [f64; 3])> = vertices
        .iter()
        .map(|vs| {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for &v in vs {
                let p = surface.positions[v as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo, hi)
        })
        .collect();
    let volume = |i: usize| report.component_details[i].signed_volume.abs();
    let mut parent = vec![None; n];
    let mut distances: Vec<Option<SurfaceDistance>> = vec![None; n];
    for i in 0..n {
        for j in 0..n {
            let (bi, bj) = (boxes[i], boxes[j]);
            let overlap = (0..3).all(|k| bi.0[k] <= bj.1[k] && bj.0[k] <= bi.1[k]);
            if i == j || !overlap || volume(j) <= volume(i) {
                continue;
            }
            let dj = distances[j].get_or_insert_with(|| {
                SurfaceDistance::new(&SurfaceMesh {
                    positions: surface.positions.clone(),
                    triangles: triangles[j].clone(),
                })
            });
            // Up to 16 vertices spread over component i: all in or all out of j.
            let step = (vertices[i].len() / 16).max(1);
            let inside: Vec<bool> = vertices[i]
                .iter()
                .step_by(step)
                .map(|&v| dj.winding_number(surface.positions[v as usize]).abs() > 0.5)
                .collect();
            if inside.iter().all(|&x| x) {
                // The smallest enclosing component is the direct parent.
                if parent[i].is_none_or(|p: usize| volume(j) < volume(p)) {
                    parent[i] = Some(j);
                }
            } else if inside.iter().any(|&x| x) {
                return None;
            }
        }
    }
    Some(parent)
}

/// For each surface vertex (but those marked `skip`), the thickness of the solid and the
/// width of the gap in front of it, each when below `limit` (else infinity). On each
/// side, a ray along the vertex normal looks for the other wall within `limit`;
/// where it finds one, the thickness is the diameter of the largest ball touching the
/// surface at the vertex whose other contact lies across the part (shrinking-ball
/// medial distance, started from the ray's chord), or the chord where no ball tells. A
/// contact or hit on a triangle at the vertex does not count, nor a thickness below
/// 1/[`FOLD_RATIO`] of the vertex's shortest edge (a fold, not a part).
fn thickness(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    skip: &[bool],
    limit: f64,
) -> Vec<[f64; 2]> {
    use rayon::prelude::*;
    let mut normals = vec![[0.0; 3]; surface.num_vertices()];
    for f in 0..surface.num_triangles() {
        let n = surface.face_normal_scaled(f);
        for &v in &surface.triangles[f] {
            normals[v as usize] = add(normals[v as usize], n);
        }
    }
    (0..surface.num_vertices())
        .into_par_iter()
        .map(|v| {
            let len = norm(normals[v]);
            let faces = topology.vertex_faces(v);
            if faces.is_empty() || skip[v] || len.is_nan() || len <= 0.0 {
                return [f64::INFINITY; 2];
            }
            let p = surface.positions[v];
            // The shortest edge at v: a wall much closer than it is a fold of the
            // surface at v (a crease folded flat, a scanning defect), not a part.
            let shortest = faces
                .iter()
                .flat_map(|&f| surface.triangles[f as usize])
                .filter(|&u| u as usize != v)
                .map(|u| norm(sub(surface.positions[u as usize], p)))
                .fold(f64::INFINITY, f64::min);
            let v32 = v as u32;
            let far = |face: u32| {
                surface
                    .triangles
                    .get(face as usize)
                    .is_some_and(|t| !t.contains(&v32))
            };
            [-1.0, 1.0].map(|direction| {
                let d = scale(normals[v], direction / len);
                // A ray that meets no other wall within the limit leaves room for a ball
                // of the limit's diameter: not thin on this side.
                let Some((hit, face)) = distance.ray_hit(p, d, limit) else {
                    return f64::INFINITY;
                };
                if !far(face) {
                    return f64::INFINITY;
                }
                // The ball's diameter is the thickness across a plate or a wire whatever
                // the vertex normal (the ray's chord is only a bound on it).
                let ball = 2.0 * medial_radius(distance, p, d, 0.5 * hit, &far);
                let t = if ball.is_finite() { ball } else { hit };
                if t < limit && t * FOLD_RATIO >= shortest {
                    t
                } else {
                    f64::INFINITY
                }
            })
        })
        .collect()
}

/// The radius of the largest ball (up to `r_max`) touching the surface at `q` with its
/// centre along the unit direction `d`, by shrinking (Ma, Bae & Ponchio 2012): start at
/// `r_max`; while the ball holds a surface point `x`, shrink it to the ball through `q`
/// and `x`. A contact counts as across the part when it is at least
/// [`MIN_SEPARATION_DEG`] round the ball from `q` and on a triangle `far` from `q`;
/// the radius of the last such shrink is returned (infinity for none), and shrinking
/// stops at the first contact that does not count after one that did.
fn medial_radius(
    distance: &SurfaceDistance,
    q: [f64; 3],
    d: [f64; 3],
    r_max: f64,
    far: &dyn Fn(u32) -> bool,
) -> f64 {
    let min_cos = MIN_SEPARATION_DEG.to_radians().cos();
    let mut r = r_max;
    let mut across = f64::INFINITY;
    for _ in 0..MEDIAL_STEPS {
        let c = add(q, scale(d, r));
        let x = distance.closest_point(c);
        if x.distance.is_nan() || x.distance >= r * (1.0 - 1e-9) {
            break;
        }
        let (cq, cx) = (sub(q, c), sub(x.point, c));
        let separation = dot(cq, cx) / (norm(cq) * norm(cx));
        let qx = sub(x.point, q);
        let den = 2.0 * dot(d, qx);
        if den.is_nan() || den <= 0.0 {
            break;
        }
        let next = dot(qx, qx) / den;
        if next.is_nan() || next >= r {
            break;
        }
        if separation <= min_cos && far(x.face) {
            across = next;
        } else if across.is_finite() {
            break;
        }
        r = next;
    }
    across
}

/// Sizing features where the surface is thin, for each side (the solid behind it, the
/// gap in front): over each triangle whose three corners are thin on that side (a
/// plate, a wire, the walls of a slit), cells of 1/[`CELLS_ACROSS`] of its middle
/// corner's thickness, so the part is resolved between its vertices too; at a thin
/// vertex that no such triangle sizes as finely (on the rim of a thin region, alone, or
/// thinner than its neighbours), a point with its own. Each faces its side and reaches
/// half the thickness and one cell more: to the middle of the part or gap (the other
/// wall's features reach the rest), and one cell out the other way. The octree's 2:1
/// balance grades the cells around them.
fn thin_part_sizing(surface: &SurfaceMesh, thickness: &[[f64; 2]]) -> Vec<SizingFeature> {
    let unit = |n: [f64; 3], sign: f64| {
        let l = norm(n);
        if l > 0.0 && l.is_finite() {
            scale(n, sign / l)
        } else {
            [0.0; 3]
        }
    };
    let mut normals = vec![[0.0; 3]; surface.num_vertices()];
    for f in 0..surface.num_triangles() {
        let n = surface.face_normal_scaled(f);
        for &v in &surface.triangles[f] {
            normals[v as usize] = add(normals[v as usize], n);
        }
    }
    let mut out = Vec::new();
    // Side 0 is the solid (against the outward normal), side 1 the gap.
    for (side, sign) in [(0, -1.0), (1, 1.0)] {
        let feature = |corners: [[f64; 3]; 3], t: f64, reach: f64, toward: [f64; 3]| {
            let spacing = t / CELLS_ACROSS;
            SizingFeature {
                corners,
                spacing,
                reach: 0.5 * reach + spacing,
                toward,
            }
        };
        // Per vertex: the coarsest thickness a triangle over it was sized for (infinite
        // when some triangle at it is not all thin).
        let mut covered_by = vec![0.0f64; thickness.len()];
        for (f, tri) in surface.triangles.iter().enumerate() {
            let mut t = tri.map(|v| thickness[v as usize][side]);
            let all_thin = t.iter().all(|x| x.is_finite());
            t.sort_unstable_by(f64::total_cmp);
            // The middle corner: one outlier corner neither coarsens nor refines it.
            let sized = if all_thin { t[1] } else { f64::INFINITY };
            for &v in tri {
                covered_by[v as usize] = covered_by[v as usize].max(sized);
            }
            if all_thin {
                out.push(feature(
                    tri.map(|v| surface.positions[v as usize]),
                    t[1],
                    t[2],
                    unit(surface.face_normal_scaled(f), sign),
                ));
            }
        }
        for (v, t) in thickness.iter().enumerate() {
            let t = t[side];
            if t.is_finite() && t * std::f64::consts::SQRT_2 < covered_by[v] {
                out.push(feature(
                    [surface.positions[v]; 3],
                    t,
                    t,
                    unit(normals[v], sign),
                ));
            }
        }
    }
    out
}

/// The surface's creases (edges whose two faces turn by more than [`CREASE_DEG`]) and
/// corners (vertices where other than two creases meet: a crease's end, or three and
/// more), for the mesher to snap its boundary onto.
fn sharp_features(surface: &SurfaceMesh, topology: &Topology) -> SharpFeatures {
    let min_cos = CREASE_DEG.to_radians().cos();
    let normals: Vec<[f64; 3]> = (0..surface.num_triangles())
        .map(|f| {
            let n = surface.face_normal_scaled(f);
            let l = norm(n);
            if l > 0.0 {
                scale(n, 1.0 / l)
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let mut creases_at = vec![0u32; surface.num_vertices()];
    let mut features = SharpFeatures::default();
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        let faces = topology.edge_faces(e);
        if faces.len() != 2 {
            continue;
        }
        let (n0, n1) = (normals[faces[0] as usize], normals[faces[1] as usize]);
        if n0 == [0.0; 3] || n1 == [0.0; 3] || dot(n0, n1) >= min_cos {
            continue;
        }
        features
            .edges
            .push([surface.positions[a as usize], surface.positions[b as usize]]);
        creases_at[a as usize] += 1;
        creases_at[b as usize] += 1;
    }
    for (v, &n) in creases_at.iter().enumerate() {
        if n == 1 || n >= 3 {
            features.corners.push(surface.positions[v]);
        }
    }
    features
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
    sizing: Vec<SizingFeature>,
    features: SharpFeatures,
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

    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        if self.side == Side::Outside && self.nearer_the_sphere(p) {
            let r = sub(p, self.centre);
            let len = norm(r);
            if len > 0.0 {
                return add(self.centre, scale(r, self.radius / len));
            }
        }
        let closest = self.distance.closest_point(p);
        if closest.point.iter().all(|c| c.is_finite()) {
            closest.point
        } else {
            p
        }
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

    fn sizing(&self) -> Vec<SizingFeature> {
        self.sizing.clone()
    }

    fn sharp_features(&self) -> SharpFeatures {
        self.features.clone()
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
