//! The pipeline: the one module that composes the others.
//!
//! The method (see `ARCHITECTURE.md`) runs: input surface → volume mesh → distance field
//! and smoothing → critical points → neck loops. Each stage is a module that takes plain
//! data and returns plain data; only this module calls one stage with another's output.
//! Steps so far:
//! - [`prepare_input`] (submodule `input`) refuses what no stage can use, repairs what
//!   has one right answer (unreferenced vertices, faces that disagree with their
//!   neighbours, components facing into their solid) and says what it did and what is
//!   still unusual (open, non-manifold, crossing itself);
//! - [`volume_mesh`] (submodule `volume`) builds the tet mesh of the inside
//!   ([`Side::Inside`]) or of the shell between the surface and a bounding sphere
//!   ([`Side::Outside`]): it wraps the surface's signed distance (`distance`) as a
//!   `volume::Domain`, sizes the lattice to resolve thin parts and gaps, calls the
//!   stuffing mesher (`volume`) and checks the mesh's topology against the surface's,
//!   refining where they differ;
//! - [`critical_points`] computes the distance field on that mesh ([`distance_field`],
//!   through `distance`) and hands it to `morse` for smoothing, classification,
//!   tracking and saddle selection;
//! - [`find_necks`] runs the whole method on both sides and hands each side's saddles to
//!   `loops` (plane cut, tightening, selection), returning a [`NeckReport`].

mod input;
mod volume;

use std::time::Instant;

use serde::Serialize;

use crate::distance::SurfaceDistance;
use crate::error::{Error, Result};
use crate::geom::{norm, sub};
use crate::io;
use crate::loops::{self, DropReason, DroppedLoop, LoopKind, LoopOptions, NeckLoop, Role, Seed};
use crate::mesh::{MeshReport, SurfaceMesh};
use crate::morse::{self, MorseOptions, MorseResult, SaddleRole, Schedule, VertexType};
use crate::progress::{Progress, Silent};
use crate::tet::{TetMesh, VertexKind};

pub use input::{inspect_surface, load_surface, prepare_input, prepare_surface, PreparedSurface};
pub use volume::{
    default_h, expected_topology, volume_mesh, Mesher, TopologyCheck, VolumeOptions, VolumeReport,
    VolumeResult, MAX_ROUNDS,
};

/// Which volume to mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The solid bounded by the surface: handles.
    Inside,
    /// The shell between the surface and a bounding sphere: tunnels.
    Outside,
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
    morse::analyze(&volume.mesh, &field, &morse_options_for(options, volume))
}

/// The Morse options for one volume mesh: the scale space starts at twice its lattice
/// spacing unless the caller chose a smallest scale.
pub fn morse_options_for(options: &MorseOptions, volume: &VolumeResult) -> MorseOptions {
    let mut options = *options;
    if options.min_scale.is_none() {
        options.min_scale = Some(2.0 * volume.h);
    }
    options
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
    /// Whether the superlevel sweep kept `cycle_rank` essential cycles at every step
    /// (each step's `cycles_ok`; a cycle closed by a saddle is essential when no
    /// 1-saddle lower down fills it).
    pub cycles_ok: bool,
    /// The first Betti number (Z2) of the complex the sweep covers, from its cocycles:
    /// the surface's genus when the interior vertices kept its topology (a warning
    /// says when not).
    pub cycle_rank: usize,
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
    /// The Z2 rank of this side's loops against the surface's genus: on a genus-g
    /// surface, g independent handle loops and g tunnel loops make a homology basis.
    pub homology: HomologyCheck,
    /// Every 2-saddle track over scale (the barcode), with the selected ones marked.
    pub bars: Vec<morse::Bar>,
    /// Every critical point alive at the last step, with type, selection and
    /// persistence (see [`critical_point_cloud`]); not in the JSON.
    #[serde(skip)]
    pub critical: io::PointCloud,
    /// The volume mesh and the smoothed field on it, with
    /// [`NeckOptions::keep_volume`]; not in the JSON.
    #[serde(skip)]
    pub field: Option<VolumeField>,
}

/// The rank of one side's loop classes against the genus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct HomologyCheck {
    /// Total genus of the surface (`None` when a component's is undefined).
    pub genus: Option<i64>,
    /// Z2 rank of the classes of this side's loops.
    pub rank: usize,
    /// `rank == genus`.
    pub ok: bool,
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
    /// Whether any input face was turned round before meshing (an inverted mesh or
    /// component, faces that disagreed with their neighbours); see `notes`.
    pub flipped: bool,
    /// What was done to the input before meshing, one line each ([`prepare_input`]).
    pub notes: Vec<String>,
    /// The surface the method worked on: the input as [`prepare_input`] left it
    /// (unreferenced vertices removed, faces oriented); not in the JSON.
    #[serde(skip)]
    pub surface: SurfaceMesh,
    /// What the caller should know, one line each: what is unusual about the input
    /// (open, crossing itself, ...), each side's volume warnings (a topology that
    /// differs from the surface's, a budget that bound, ...).
    pub warnings: Vec<String>,
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

/// How many seeds lie near a crossing face: a corner of a crossing triangle within
/// [`CROSSING_REACH`] times the seed's distance to the surface (its loop's radius,
/// about), plus the triangle's longest side.
fn seeds_near(surface: &SurfaceMesh, crossing_faces: &[u32], seeds: &[Seed]) -> usize {
    if crossing_faces.is_empty() || seeds.is_empty() {
        return 0;
    }
    let positions: Vec<[f64; 3]> = seeds.iter().map(|s| s.position).collect();
    let radii = SurfaceDistance::new(surface).distances(&positions);
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

/// The loop stage's seeds from the Morse stage's selected 2-saddles, in their order:
/// the plane through each saddle's fitted position with its Hessian's positive
/// eigenvector as normal. A separating saddle whose bulge is below `min_bulge` is a
/// neck only if its loop opens out on both sides (`Seed::needs_opening`).
pub fn loop_seeds(result: &MorseResult) -> Vec<Seed> {
    result
        .saddles
        .iter()
        .map(|s| Seed {
            position: s.position,
            normal: s.normal,
            persistence: s.persistence,
            role: match s.role {
                SaddleRole::Separating => Some(Role::Separating),
                SaddleRole::CycleClosing => Some(Role::CycleClosing),
                // Only the paper schedule selects these (it ignores roles).
                SaddleRole::LocalCycle => None,
            },
            scales: (s.birth_scale, s.death_scale),
            bulge: s.bulge,
            lobe: s.lobe,
            // The paper's schedule keeps what it selects, as the paper does.
            needs_opening: result.schedule == Schedule::ScaleSpace
                && s.role == SaddleRole::Separating
                && !s.by_bulge,
        })
        .collect()
}

/// The whole method on a surface: [`prepare_input`], then for each side asked for,
/// volume mesh → distance field → smoothing and critical points → neck loops.
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
    options.morse.check()?;
    // 1. The input, once: repaired, oriented, its problems said.
    let prepared = prepare_input(surface.clone())?;
    let surface = &prepared.mesh;
    let surface_report = MeshReport::new(surface);
    let mut report = NeckReport {
        loops: Vec::new(),
        dropped: Vec::new(),
        morse: Vec::new(),
        timings: NeckTimings::default(),
        sides: Vec::new(),
        flipped: prepared.flipped,
        notes: prepared.notes.clone(),
        warnings: prepared.warnings.clone(),
        surface: surface.clone(),
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
        report.warnings.extend(volume.warnings.iter().cloned());
        progress.start(&format!("distance ({name})"), 0);
        let start = Instant::now();
        let field = distance_field(surface, &volume.mesh);
        let distance_seconds = start.elapsed().as_secs_f64();
        progress.finish();
        let morse_options = morse_options_for(&options.morse, &volume);
        let result = morse::analyze_with_progress(&volume.mesh, &field, &morse_options, progress)?;
        // The paper's schedule reproduces the paper's selection: no homology step.
        let loop_options = LoopOptions {
            homology_selection: options.loops.homology_selection
                && options.morse.schedule == Schedule::ScaleSpace,
            ..options.loops
        };
        // A surface that crosses itself is no place for a geodesic where it crosses:
        // the loop round the neck of two overlapping balls runs along the crossing, and
        // tightening on either ball alone slides it off. Where a neck lies by a
        // crossing, this side's loops are cut and tightened on the volume mesh's
        // boundary, the surface of the solid that was meshed.
        let seeds = loop_seeds(&result);
        let near = seeds_near(surface, &prepared.crossing_faces, &seeds);
        let boundary;
        let loop_surface = if near > 0 {
            boundary = meshed_boundary(&volume.mesh, side);
            report.warnings.push(format!(
                "{name}: {near} of {} necks lie where the surface crosses itself, so this side's loops are cut and tightened on the volume mesh's boundary ({} triangles, the surface of the solid meshed) instead of the input",
                seeds.len(),
                boundary.num_triangles()
            ));
            &boundary
        } else {
            surface
        };
        let found =
            loops::find_loops_with_progress(loop_surface, &seeds, kind, &loop_options, progress)?;

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

        let genus = surface_report
            .component_details
            .iter()
            .map(|c| c.genus)
            .sum::<Option<i64>>();
        // The swept complex should have the surface's genus as its H1 rank, and the
        // sweep should find every one of its classes at every level.
        let cycle_rank = result.cycle_rank as i64;
        if let Some(g) = genus.filter(|&g| g != cycle_rank) {
            report.warnings.push(format!(
                "{name}: the interior vertices of the volume mesh span a complex of H1 rank \
                 {cycle_rank} (Z2), the surface has genus {g}: the superlevel sweep sees \
                 cycles that are not the surface's (thin parts; --h may change it)"
            ));
        }
        let cycle_failure = result.steps.iter().find(|s| !s.cycles_ok);
        if let Some(s) = cycle_failure {
            report.warnings.push(format!(
                "{name}: the superlevel sweep keeps {} essential cycles at level {}, its \
                 complex has H1 rank {cycle_rank}",
                s.essential_cycles, s.step
            ));
        }
        report.morse.push(MorseCheck {
            side,
            ok: result.morse_failures().next().is_none(),
            surface_morse_expected: surface_morse_expected(&surface_report, side),
            morse_expected: result.morse_expected,
            cycles_ok: cycle_failure.is_none(),
            cycle_rank: result.cycle_rank,
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
        let classes: Vec<Vec<u64>> = found.loops.iter().map(NeckLoop::class).collect();
        let rank = crate::mesh::z2_rank(&classes);
        let homology = HomologyCheck {
            genus,
            rank,
            ok: genus == Some(rank as i64),
        };
        if let Some(g) = genus.filter(|&g| g != rank as i64) {
            report.warnings.push(format!(
                "{name}: the {kind} loops have Z2 rank {rank}, the surface has genus {g}",
                kind = match side {
                    Side::Inside => "handle",
                    Side::Outside => "tunnel",
                }
            ));
        }
        report.loops.extend(found.loops);
        report.sides.push(SideReport {
            homology,
            bars: result.bars.clone(),
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
