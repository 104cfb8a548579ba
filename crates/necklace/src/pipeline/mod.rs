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
//! - [`critical_points`] (submodule `critical`) computes the distance field on that
//!   mesh ([`distance_field`], through `distance`) and hands it to `morse` for
//!   smoothing, classification, tracking and saddle selection; [`find_critical_points`]
//!   is one side from the raw input to its saddles (`necklace critical`);
//! - [`find_necks`] runs the whole method on both sides and hands each side's saddles to
//!   `loops` (plane cut, tightening, selection), returning a [`NeckReport`] (its types
//!   live in submodule `report`; pictures and point clouds of it are `output`'s).

mod critical;
mod input;
mod report;
mod volume;

use std::time::Instant;

use crate::distance::SurfaceDistance;
use crate::error::{Error, Result};
use crate::loops::{self, DropReason, LoopOptions, NeckLoop, Role, Seed};
use crate::mesh::{MeshReport, Side, SurfaceMesh};
use crate::morse::{self, MorseOptions, MorseResult, SaddleRole, Schedule};
use crate::progress::{Progress, Silent};
use crate::tet::{TetMesh, VertexKind};

pub use critical::{
    critical_points, find_critical_points, morse_options_for, surface_morse_expected,
    CriticalReport, CriticalRun,
};
use input::seeds_near;
pub use input::{
    inspect_surface, load_surface, meshed_boundary, prepare_input, prepare_surface, PreparedSurface,
};
pub use report::{
    tracked_points, HomologyCheck, MorseCheck, NeckReport, NeckTimings, SideReport, StageTimings,
    TrackedPoint, VolumeField,
};
pub use volume::{
    default_h, expected_topology, volume_mesh, Mesher, TopologyCheck, VolumeOptions, VolumeReport,
    VolumeResult, MAX_ROUNDS,
};

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
        let name = side.name();
        // 2. The volume mesh of this side.
        progress.start(&format!("volume mesh ({name})"), 0);
        let volume = volume_mesh(surface, side, &options.volume);
        progress.finish();
        let volume = volume?;
        report.warnings.extend(volume.warnings.iter().cloned());
        // 3. The exact distance to the surface on its vertices.
        progress.start(&format!("distance ({name})"), 0);
        let start = Instant::now();
        let field = distance_field(surface, &volume.mesh);
        let distance_seconds = start.elapsed().as_secs_f64();
        progress.finish();
        // 4. Smoothing over scale, critical points, the neck 2-saddles.
        let morse_options = morse_options_for(&options.morse, &volume);
        let result = morse::analyze_with_progress(&volume.mesh, &field, &morse_options, progress)?;
        // 5. A loop per saddle: cut, tightened, selected. The paper's schedule
        // reproduces the paper's selection: no homology step.
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
            loops::find_loops_with_progress(loop_surface, &seeds, side, &loop_options, progress)?;

        // 6. Timings, the Morse and homology checks, and this side into the report.
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
                "{name}: the {} loops have Z2 rank {rank}, the surface has genus {g}",
                side.neck_name()
            ));
        }
        report.loops.extend(found.loops);
        report.sides.push(SideReport {
            homology,
            bars: result.bars.clone(),
            side,
            volume: volume.report(),
            unknowns: result.unknowns,
            critical: tracked_points(&result),
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
