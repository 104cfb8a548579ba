//! The pipeline: the one module that composes the others.
//!
//! The method (see `ARCHITECTURE.md`) runs: input surface → volume mesh → distance field
//! and smoothing → critical points → neck loops. Each stage is a module that takes plain
//! data and returns plain data; only this module calls one stage with another's output.
//! The recipe, [`find_necks`]:
//! 1. [`prepare_input`] / [`prepare_input_with`] (submodule `input`, [`InputOptions`])
//!    welds boundary corners closer than [`DEFAULT_WELD`] × the diagonal ([`weld_input`],
//!    also what `info` reads), refuses what no stage can use (also a surface with no
//!    volume, a soup or open sheets, by a winding-number sample of its triangles),
//!    repairs what has one right answer (unreferenced vertices, faces that disagree with
//!    their neighbours, components facing into their solid, by nesting), counts
//!    self-intersections, says what it did and what is still unusual (open,
//!    non-manifold, crossing itself), and builds the surface's one distance structure
//!    (`distance`) that every later step shares; the prepared mesh's `MeshReport` is
//!    made once and handed on ([`PreparedSurface::mesh_report`]). Then (step 1b,
//!    submodule `working`) a dense closed surface that does not cross itself is
//!    simplified (`simplify`), and the copy used when it has the input's genus and does
//!    not cross itself ([`NeckReport::simplified`]); the loops are carried back to the
//!    input (`loops::transfer_loops`);
//! 2. per side ([`Side::Inside`] for handles, [`Side::Outside`] for tunnels; `find_side`),
//!    the volume mesh (`volume::volume_mesh_surveyed`: the surface as a `volume::Domain`,
//!    sized for thin parts, its topology checked against the surface's), from the one
//!    survey of the surface both sides share (`volume::survey_surface`: thickness and gaps
//!    at every vertex, creases, crossings; made before the sides start);
//! 3. the exact distance field on its vertices ([`volume_field`]: [`distance_field`], but
//!    where the surface crosses itself and a vertex's nearest surface point is buried
//!    in the solid, its distance to the solid's boundary as meshed);
//! 4. smoothing over scale, critical points and the neck 2-saddles (`morse`);
//! 5. a loop per saddle ([`loop_seeds`]; `loops`: plane cut, tightening, selection; on the
//!    volume mesh's boundary, [`meshed_boundary`], where a neck lies by a self-crossing);
//!    where those loops span fewer classes than the genus, loops from the Morse stage's
//!    completions (the vertices that close essential cycles without passing as necks: walls
//!    a cell or two thick give them no 2-saddle Hessian), each kept only where its plane
//!    bounds a disk of its side and it adds a class (`loops::complete_classes`); where they
//!    span more, the seeds cut again keeping only curves that bound disks
//!    (`Seed::disk_only`); these cuts share a `loops::LoopMemo`, so that what they
//!    repeat of each other is done once;
//! 6. the Morse and homology checks, and the side into the [`NeckReport`] (built side by
//!    side, with per-stage timings, critical points ([`tracked_points`]) and, with
//!    `keep_volume`, the volume field; its types, [`SideReport`] and [`TrackedPoint`] among
//!    them, live in submodule `report`; pictures and point clouds of it are `output`'s);
//! 7. the loops' surface points renumbered to the input's vertices.
//!
//! The two sides run at the same time (`rayon::join`, each reporting on its own
//! [`Lane`]; `sides_at_once: false` runs them one after the other): their volume meshes,
//! then their analyses (steps 3–6), which run one after the other where the two meshes
//! are large ([`NeckOptions::at_once_max_tets`]; with budget steps each side meshes and
//! analyses in turns). Each side's stage timings are laps of its own clock, so they add
//! up to the side's time; the run's `seconds` is its own wall clock (less than the
//! input's time, [`NeckTimings::input`], plus both sides').
//! [`find_necks_with_progress`] reports progress; the crate re-exports [`find_necks`]
//! with [`NeckOptions`] as `necklace::Options`.
//!
//! Besides: [`inspect_surface`] (what `info` prints); [`prepare_surface`] (closed manifold
//! surfaces only) and [`load_surface`]; [`distance_field`]. [`find_critical_points`] and
//! [`critical_points`] / [`critical_points_with`] (submodule `critical`,
//! [`CriticalReport`]) are steps 1–4 for one side (input, volume, exact distance,
//! `morse::analyze`), what `necklace critical` runs. [`segment_along_loops`] (submodule
//! `segmenting`) cuts the surface along loops (`segment`), what `necklace segment` runs.
//! [`repair`] / [`repair_with_progress`] (submodule `repairing`, plan in
//! `docs/design-repair.md`; [`RepairOptions`], [`RepairTarget`], [`RepairReport`]) runs
//! `find_necks`, then cuts along the loops shortest first, one [`cut_along_loop`] at a time
//! (the `surgery` pieces and `segment`), each checked (valid, the same components, the
//! genus one lower, no crossings) or skipped with its reason, and runs `find_necks` again
//! while the genus is above the target; what `necklace repair` runs.

mod critical;
mod input;
mod repairing;
mod report;
mod segmenting;
mod working;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;
use std::time::Instant;

use crate::distance::SurfaceDistance;
use crate::error::{Error, ErrorKind, Result};
use crate::loops::{self, LoopMemo, LoopOptions, LoopResult, LoopSurface, NeckLoop, Role, Seed};
use crate::mesh::{Side, SurfaceMesh};
use crate::morse::{self, MorseOptions, MorseResult, Saddle, SaddleRole, Schedule};
use crate::progress::{Lane, Progress, Silent};
use crate::simplify::SimplifyOptions;
use crate::tet::{TetMesh, VertexKind};
use crate::volume::{
    survey_surface, volume_mesh_within, SurfaceSurvey, VolumeOptions, VolumeResult,
};

pub use critical::{
    critical_points, critical_points_with, find_critical_points, morse_options_for,
    surface_morse_expected, CriticalReport, CriticalRun,
};
use input::seeds_near;
pub use input::{
    inspect_surface, load_surface, meshed_boundary, prepare_input, prepare_input_with,
    prepare_surface, weld_input, InputOptions, PreparedSurface, WeldedInput, DEFAULT_WELD,
};
pub use repairing::{
    cut_along_loop, loop_on_surface, repair, repair_with_progress, Cut, RepairLoop,
    RepairOperation, RepairOptions, RepairReport, RepairSkip, RepairTarget,
};
use report::SideRun;
pub use report::{
    tracked_points, HomologyCheck, MorseCheck, NeckReport, NeckTimings, SideReport, SimplifyReport,
    StageTimings, TrackedPoint, VolumeField,
};
pub use segmenting::segment_along_loops;
use working::prepare_run;

/// The distance field of the method (paper sec. 3): the exact distance from every
/// vertex of `mesh` to the surface of `distance`, 0 on surface-kind vertices.
/// Outer-sphere vertices keep their true distance (a Dirichlet value that lets the
/// field keep rising to the sphere; setting them to 0 would make a ridge of spurious
/// critical points halfway out).
pub fn distance_field(distance: &SurfaceDistance, mesh: &TetMesh) -> Vec<f64> {
    let mut f = distance.distances(&mesh.positions);
    for (value, kind) in f.iter_mut().zip(&mesh.kinds) {
        if *kind == VertexKind::Surface {
            *value = 0.0;
        }
    }
    f
}

/// The Morse function on one side's volume mesh: [`distance_field`], the exact
/// distance to the surface of `distance`. Where that surface crosses itself (its
/// crossings recorded), its triangles are not all the boundary of the solid its
/// winding number encloses: a part buried in another would put a valley of the field,
/// down to 0, inside the solid, and 2-saddles round it (two unit balls 1.6 apart had
/// two neck saddles, 1 apart a dozen by the buried caps, for the one at the crossing
/// circle's centre). There a vertex whose distance to the mesh's own boundary on the
/// surface ([`meshed_boundary`]: the solid's boundary as meshed) exceeds its distance to
/// the surface by more than [`BURIED_DEPTH`] `× h` has its nearest surface point buried,
/// and takes the distance to the boundary instead; elsewhere the exact one stays.
pub fn volume_field(distance: &SurfaceDistance, volume: &VolumeResult) -> Vec<f64> {
    let boundary = crosses_itself(distance).then(|| meshed_boundary(&volume.mesh, volume.side));
    field_of_solid(distance, volume, boundary.as_ref())
}

/// Whether the surface of `distance` has crossings recorded.
fn crosses_itself(distance: &SurfaceDistance) -> bool {
    distance.crossings().is_some_and(|c| !c.is_empty())
}

/// [`volume_field`] with the mesh's boundary on the surface made by the caller (`None`
/// where the surface does not cross itself).
fn field_of_solid(
    distance: &SurfaceDistance,
    volume: &VolumeResult,
    boundary: Option<&SurfaceMesh>,
) -> Vec<f64> {
    let mut field = distance_field(distance, &volume.mesh);
    let Some(boundary) = boundary else {
        return field;
    };
    let boundary = distance_field(&SurfaceDistance::new(boundary), &volume.mesh);
    let depth = BURIED_DEPTH * volume.h;
    for (value, to_boundary) in field.iter_mut().zip(boundary) {
        if to_boundary > *value + depth {
            *value = to_boundary;
        }
    }
    field
}

/// See [`volume_field`]: a buried part nearer than this many `h` to the solid's
/// boundary is not told from the boundary (the crossing curve's cells are `h / 8`).
pub const BURIED_DEPTH: f64 = 0.125;

/// Options of [`find_necks`]: which sides, and each stage's options.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// With both sides: run them at the same time (default true; each side's own work
    /// is parallel only in parts, so two cores do about 1.25x better). False runs one
    /// after the other, with the larger side's peak memory instead of both sides'.
    /// The results are the same.
    pub sides_at_once: bool,
    /// With both sides at once and no budget steps: the two volume meshes are made at
    /// the same time, and their analyses (distance field, Morse stage, loops) run at
    /// the same time only while the meshes hold at most this many tets together
    /// (default 5 M), else one after the other. Most of a side's peak memory is its
    /// analysis, about 300 bytes a tet: both at once would pass 1.5 GB. On
    /// ps_mk3_bed.stl (8.1 M tets) one after the other took 1384 MiB instead of
    /// 2229 MiB, and up to a third more time (`docs/decisions.md`). The results are
    /// the same.
    pub at_once_max_tets: usize,
    /// When a dense surface is simplified for the volume, field and saddles (the loops
    /// are cut again and tightened on the input; `simplify`).
    pub simplify: SimplifyOptions,
    /// The input step: which corners are welded ([`InputOptions`]).
    pub input: InputOptions,
    /// Mesh each side of a surface whose genus is known within a sixteenth, then a
    /// quarter of its memory budget before the whole, keeping the first mesh whose
    /// budget did not bind or whose topology and loop rank match the surface's (default
    /// false: within the whole budget at once). The budget floors the cells of thin
    /// parts: on real models it, not the surface, sets the mesh's size; but a coarse
    /// mesh with the right topology and ranks can still miss necks (one of the
    /// buckyball's 32 windows), so the steps are asked for.
    pub budget_steps: bool,
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
            sides_at_once: true,
            at_once_max_tets: 5_000_000,
            simplify: SimplifyOptions::default(),
            input: InputOptions::default(),
            budget_steps: false,
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
        .map(|s| seed_of(s, result.schedule))
        .collect()
}

/// The seeds of the Morse stage's completions (`MorseResult::completions`: essential
/// cycle-closing saddles without a 2-saddle Hessian), cut with their upper link's
/// axis as normal.
pub fn completion_seeds(result: &MorseResult) -> Vec<Seed> {
    result
        .completions
        .iter()
        .map(|s| seed_of(s, result.schedule).needing_a_disk())
        .collect()
}

fn seed_of(s: &Saddle, schedule: Schedule) -> Seed {
    Seed {
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
        needs_opening: schedule == Schedule::ScaleSpace
            && s.role == SaddleRole::Separating
            && !s.by_bulge,
        disk_only: false,
    }
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
    let mut clock = Stopwatch::start();
    // 1. The input, once: repaired, oriented, its problems said, its distance
    //    structure built for every stage of the run.
    // 1b. A dense surface: a simplified copy for the stages that need only its shape
    //     (the loops are cut again and tightened on the input), made at the same time.
    let dense = options.simplify.applies_to(surface.num_triangles());
    if dense {
        progress.start("input and simplification", 0);
    }
    let run = prepare_run(surface, &options.input, &options.simplify);
    if dense {
        progress.finish();
    }
    let (prepared, working) = run?;
    let mut report = NeckReport::new(&prepared);
    if let Some(w) = &working {
        report.notes.extend(w.notes.iter().cloned());
        report.warnings.extend(w.warnings.iter().cloned());
        report.simplified = w.report;
        report.timings.simplify = w.seconds;
    }
    report.timings.input = clock.lap();
    let carry = working.as_ref().and_then(|w| {
        Some(Carry {
            copy: w.prepared.as_ref()?,
            prepared: &prepared,
            surface: OnceLock::new(),
        })
    });
    let work = carry.as_ref().map_or(&prepared, |c| c.copy);
    // 2a. What the volume stage measures on the surface: the same for both sides, so
    //     measured once (on a dense surface most of the volume stage).
    progress.start("surface survey", 0);
    let survey = survey_surface(
        &work.mesh,
        &work.distance,
        &work.mesh_report,
        &side_volume_options(options),
    );
    progress.finish();
    let survey = survey?;
    report.timings.survey = clock.lap();
    // 2–6. Each side asked for, both at the same time (each side's own work is
    //      parallel too, but partly sequential: the sweeps, small solves); the inside
    //      (handles) first in the report.
    // A side that fails stops the other at its next stage (its error is the run's).
    let failed = AtomicBool::new(false);
    let run = |side: Side, lane: usize| {
        let progress = Lane {
            to: progress,
            lane,
            label: side.name(),
        };
        let found = find_side(
            work,
            carry.as_ref(),
            &survey,
            side,
            options,
            &progress,
            &failed,
        );
        if found.is_err() {
            failed.store(true, Ordering::Relaxed);
        }
        found
    };
    let runs = match (options.handles, options.tunnels) {
        // Budget steps mesh and analyse each side in turns.
        (true, true) if options.sides_at_once && options.budget_steps => {
            let (inside, outside) = rayon::join(|| run(Side::Inside, 0), || run(Side::Outside, 1));
            vec![inside, outside]
        }
        (true, true) if options.sides_at_once => {
            find_both_sides(work, carry.as_ref(), &survey, options, progress, &failed)
        }
        (true, true) => vec![run(Side::Inside, 0), run(Side::Outside, 1)],
        (true, false) => vec![run(Side::Inside, 0)],
        _ => vec![run(Side::Outside, 0)],
    };
    let mut sides = Vec::new();
    for found in runs {
        // `None`: stopped because the other side failed; its error comes in turn.
        if let Some(found) = found? {
            sides.push(found);
        }
    }
    // 6b. Classes that bound on a side but no disk there (a knotted part): from the
    //     other side's loops and cycles.
    if options.loops.homology_selection && options.morse.schedule == Schedule::ScaleSpace {
        link_sides(&prepared, carry.as_ref(), &options.loops, &mut sides);
    }
    for mut found in sides {
        rank_warning(&prepared, &mut found);
        report.add_side(found);
    }
    clock.lap();
    report.timings.seconds = clock.total();
    // 7. Loops located on the input's vertices (preparing may have dropped unused ones).
    report.index_by_input(&prepared.input_vertex);
    Ok(report)
}

/// Both sides without budget steps: their volume meshes at the same time, then their
/// analyses (steps 3–6), at the same time while the two meshes hold at most
/// [`NeckOptions::at_once_max_tets`] tets, else the inside's then the outside's, with
/// the peak memory of one analysis instead of both. The results are the same either
/// way; each side's timings leave out its wait.
fn find_both_sides(
    prepared: &PreparedSurface,
    carry: Option<&Carry>,
    survey: &SurfaceSurvey,
    options: &NeckOptions,
    progress: &dyn Progress,
    failed: &AtomicBool,
) -> Vec<Result<Option<SideRun>>> {
    let lane = |side: Side| Lane {
        to: progress,
        lane: usize::from(side == Side::Outside),
        label: side.name(),
    };
    let mesh = |side: Side| {
        let budget = survey.options.max_memory;
        let (volume, clock, seconds) =
            mesh_side(prepared, survey, side, budget, false, &lane(side));
        if volume.is_err() {
            failed.store(true, Ordering::Relaxed);
        }
        volume.map(|v| (v, clock, seconds))
    };
    let genus = surface_genus(prepared);
    let analyse = |side: Side, meshed: Result<(VolumeResult, Stopwatch, f64)>| {
        let (volume, mut clock, seconds) = meshed?;
        if failed.load(Ordering::Relaxed) {
            return Ok(None);
        }
        clock.resume();
        let found = analyse_side(
            prepared,
            carry,
            side,
            options,
            &lane(side),
            failed,
            volume,
            genus,
            clock,
        );
        if found.is_err() {
            failed.store(true, Ordering::Relaxed);
        }
        found.map(|run| {
            run.map(|mut run| {
                run.report.timings.volume_mesh = seconds;
                run
            })
        })
    };
    let (inside, outside) = rayon::join(|| mesh(Side::Inside), || mesh(Side::Outside));
    let tets = |m: &Result<(VolumeResult, Stopwatch, f64)>| {
        m.as_ref().map_or(0, |(v, _, _)| v.mesh.num_tets())
    };
    if tets(&inside) + tets(&outside) <= options.at_once_max_tets {
        let (inside, outside) = rayon::join(
            || analyse(Side::Inside, inside),
            || analyse(Side::Outside, outside),
        );
        vec![inside, outside]
    } else {
        let inside = analyse(Side::Inside, inside);
        vec![inside, analyse(Side::Outside, outside)]
    }
}

/// The volume options of each side: `options.volume` with its memory budget shared by
/// the sides meshed at the same time (half each when both are).
fn side_volume_options(options: &NeckOptions) -> VolumeOptions {
    let at_once = if options.handles && options.tunnels && options.sides_at_once {
        2
    } else {
        1
    };
    VolumeOptions {
        max_memory: options.volume.max_memory / at_once,
        ..options.volume
    }
}

/// The input surface, when the method runs on a simplified copy of it: the loops found
/// on the copy are carried back to it (`loops::transfer_loops`), with what the loop
/// stage needs of it built once for both sides.
struct Carry<'a> {
    /// The simplified copy the stages work on.
    copy: &'a PreparedSurface,
    /// The input.
    prepared: &'a PreparedSurface,
    /// What the loop stage needs of the input, built by the first side to need it.
    surface: OnceLock<LoopSurface>,
}

/// The smallest budget [`budget_steps`] tries first: 100 MB, 250 000 tets.
const SMALLEST_STEP: u64 = 100_000_000;

/// The memory budgets a side is meshed within, smallest first: with `steps`, a
/// sixteenth and a quarter of `max_memory` (those of at least [`SMALLEST_STEP`]) before
/// `max_memory` itself.
fn budget_steps(max_memory: u64, steps: bool) -> Vec<u64> {
    let mut budgets: Vec<u64> = [max_memory / 16, max_memory / 4]
        .into_iter()
        .filter(|&b| steps && b >= SMALLEST_STEP)
        .collect();
    budgets.push(max_memory);
    budgets
}

/// The genus the surface predicts: the sum of its components' (`None` where one has
/// none).
fn surface_genus(prepared: &PreparedSurface) -> Option<i64> {
    prepared
        .mesh_report
        .component_details
        .iter()
        .map(|c| c.genus)
        .sum()
}

/// Step 2 of [`find_necks`]: the volume mesh of one side within `max_memory`, on a
/// clock started for the side, and its seconds (the clock's first lap).
fn mesh_side(
    prepared: &PreparedSurface,
    survey: &SurfaceSurvey,
    side: Side,
    max_memory: u64,
    stop_when_bound: bool,
    progress: &dyn Progress,
) -> (Result<VolumeResult>, Stopwatch, f64) {
    let mut clock = Stopwatch::start();
    progress.start("volume mesh", 0);
    let volume = volume_mesh_within(
        &prepared.mesh,
        &prepared.distance,
        survey,
        side,
        max_memory,
        stop_when_bound,
    );
    progress.finish();
    let seconds = clock.lap();
    (volume, clock, seconds)
}

/// One side of the method on a prepared surface, meshed from the run's `survey`: steps
/// 2–6 of [`find_necks`]; with `carry`, the loops carried back to the input. `None`
/// when `stop` was raised (the other side failed) before one of its stages.
///
/// With [`NeckOptions::budget_steps`] and a surface whose genus is known, the side is
/// meshed within a sixteenth, then a quarter of its budget before the whole
/// ([`budget_steps`]), and the first result is kept whose budget did not bind, or whose
/// volume topology and loop rank match the surface's: the budget floors the cells of
/// thin parts, and a part thinner than the floor is where a mesh loses the topology.
/// A step whose budget bound without a topology to check it by is not analysed; the
/// steps' time is in the side's timings, and a note says which step was kept and why.
fn find_side(
    prepared: &PreparedSurface,
    carry: Option<&Carry>,
    survey: &SurfaceSurvey,
    side: Side,
    options: &NeckOptions,
    progress: &dyn Progress,
    stop: &AtomicBool,
) -> Result<Option<SideRun>> {
    let stopped = || stop.load(Ordering::Relaxed);
    let name = side.name();
    let genus = surface_genus(prepared);
    // Steps only where the mesh's topology can be checked: a genus, and no crossings.
    let checkable = genus.is_some() && prepared.distance.crossings().is_none_or(<[_]>::is_empty);
    let budget = survey.options.max_memory;
    let budgets = budget_steps(budget, options.budget_steps && checkable);
    let mut spent = StageTimings::default();
    let mut notes = Vec::new();
    for (i, &within) in budgets.iter().enumerate() {
        let last = i + 1 == budgets.len();
        // 2. The volume mesh of this side.
        let (volume, clock, volume_seconds) =
            mesh_side(prepared, survey, side, within, !last, progress);
        if stopped() {
            return Ok(None);
        }
        let step = format!(
            "{name}: within {} of its budget of {} (--max-memory)",
            crate::volume::memory_text(within as f64),
            crate::volume::memory_text(budget as f64)
        );
        let next =
            || crate::volume::memory_text(budgets.get(i + 1).copied().unwrap_or(budget) as f64);
        let volume = match volume {
            Err(e) if !last && e.kind() == ErrorKind::OverBudget => {
                notes.push(format!(
                    "{step} {}: meshed again within {}",
                    e.message(),
                    next()
                ));
                spent.volume_mesh += volume_seconds;
                spent.total += volume_seconds;
                continue;
            }
            volume => volume?,
        };
        if !last && volume.budget_bound && volume.topology.matches != Some(true) {
            notes.push(match volume.topology.matches {
                None => format!(
                    "{step} the budget bound the volume mesh, and the surface predicts no topology to check it by: meshed again within {}",
                    next()
                ),
                _ => format!(
                    "{step} the budget bound the volume mesh and its topology differs from the surface's: meshed again within {}",
                    next()
                ),
            });
            spent.volume_mesh += volume_seconds;
            spent.total += volume_seconds;
            continue;
        }
        let Some(mut run) = analyse_side(
            prepared, carry, side, options, progress, stop, volume, genus, clock,
        )?
        else {
            return Ok(None);
        };
        run.report.timings.volume_mesh = volume_seconds;
        let bound = run.report.volume.budget_bound;
        let homology = run.report.homology;
        if last || !bound || homology.ok {
            if bound && !last {
                notes.push(format!(
                    "{step} the budget floored the cells of thin parts, and the volume's topology and the {} loops' Z2 rank ({}) match the surface's: the finer meshes the budget allows were not made (without --budget-steps they are)",
                    side.neck_name(),
                    homology.rank
                ));
            }
            run.report.timings.add(&spent);
            run.notes = notes;
            return Ok(Some(run));
        }
        notes.push(format!(
            "{step} the {} loops have Z2 rank {} for genus {}: meshed again within {}",
            side.neck_name(),
            homology.rank,
            genus.unwrap_or_default(),
            next()
        ));
        spent.add(&run.report.timings);
    }
    unreachable!("the last budget step always returns")
}

/// Steps 3–6 of [`find_side`] on the side's `volume` mesh (made in the first lap of
/// `clock`): the distance field, the Morse stage, the loops and the checks.
#[allow(clippy::too_many_arguments)]
fn analyse_side(
    prepared: &PreparedSurface,
    carry: Option<&Carry>,
    side: Side,
    options: &NeckOptions,
    progress: &dyn Progress,
    stop: &AtomicBool,
    volume: VolumeResult,
    genus: Option<i64>,
    mut clock: Stopwatch,
) -> Result<Option<SideRun>> {
    let stopped = || stop.load(Ordering::Relaxed);
    let surface = &prepared.mesh;
    let name = side.name();
    let mut warnings = volume.warnings.clone();

    // 3. The exact distance to the surface on its vertices (to the solid's boundary as
    //    meshed, where the surface crosses itself).
    progress.start("distance", 0);
    // The solid's boundary as meshed, made once for the field and the loops.
    let solid_boundary =
        crosses_itself(&prepared.distance).then(|| meshed_boundary(&volume.mesh, side));
    let field = field_of_solid(&prepared.distance, &volume, solid_boundary.as_ref());
    progress.finish();
    let distance_seconds = clock.lap();
    if stopped() {
        return Ok(None);
    }

    // 4. Smoothing over scale, critical points, the neck 2-saddles.
    let morse_options = morse_options_for(&options.morse, &volume);
    let result = morse::analyze_with_progress(&volume.mesh, &field, &morse_options, progress)?;
    let morse_seconds = clock.lap();
    if stopped() {
        return Ok(None);
    }

    // 5. A loop per saddle: cut, tightened, selected. The paper's schedule reproduces
    // the paper's selection: no homology step.
    let loop_options = LoopOptions {
        homology_selection: options.loops.homology_selection
            && options.morse.schedule == Schedule::ScaleSpace,
        ..options.loops
    };
    // A surface that crosses itself is no place for a geodesic where it crosses: the
    // loop round the neck of two overlapping balls runs along the crossing, and
    // tightening on either ball alone slides it off. Where a neck lies by a crossing,
    // this side's loops are cut and tightened on the volume mesh's boundary, the
    // surface of the solid that was meshed.
    let seeds = loop_seeds(&result);
    let near = seeds_near(prepared, &seeds);
    let boundary =
        (near > 0).then(|| solid_boundary.unwrap_or_else(|| meshed_boundary(&volume.mesh, side)));
    if let Some(boundary) = &boundary {
        warnings.push(format!(
            "{name}: {near} of {} necks lie where the surface crosses itself, so this side's loops are cut and tightened on the volume mesh's boundary ({} triangles, the surface of the solid meshed) instead of the input",
            seeds.len(),
            boundary.num_triangles()
        ));
    }
    let cutter = LoopCutter {
        surface: boundary.as_ref().unwrap_or(surface),
        distance: boundary.is_none().then_some(&prepared.distance),
        carry,
        side,
        options: &loop_options,
        progress,
    };
    let (found, completed_with) = match genus.filter(|_| loop_options.homology_selection) {
        Some(g) => loops_to_genus(
            &cutter,
            &seeds,
            &completion_seeds(&result),
            g,
            &mut warnings,
        )?,
        None => (cutter.cut(&seeds, &LoopMemo::default())?, false),
    };
    let mut saddles = result.saddles.clone();
    if completed_with {
        saddles.extend(result.completions.iter().copied());
    }

    // 6. The Morse and homology checks.
    let surface_report = &prepared.mesh_report;
    // The swept complex should have the surface's genus as its H1 rank, and the sweep
    // should find every one of its classes at every level.
    let cycle_rank = result.cycle_rank as i64;
    // Where the surface crosses itself, its components' genus is not the solid's.
    let crossing = prepared.distance.crossings().map_or(0, <[_]>::len);
    if let Some(g) = genus.filter(|&g| g != cycle_rank) {
        warnings.push(if crossing > 0 {
            format!(
                "{name}: the interior vertices of the volume mesh span a complex of H1 rank \
                 {cycle_rank} (Z2); the surface's components have genus {g}, but it crosses \
                 itself ({crossing} pairs of triangles), so the solid it bounds may have another"
            )
        } else {
            format!(
                "{name}: the interior vertices of the volume mesh span a complex of H1 rank \
                 {cycle_rank} (Z2), the surface has genus {g}: the superlevel sweep sees \
                 cycles that are not the surface's (thin parts; --h may change it)"
            )
        });
    }
    let cycle_failure = result.steps.iter().find(|s| !s.cycles_ok);
    if let Some(s) = cycle_failure {
        warnings.push(format!(
            "{name}: the superlevel sweep keeps {} essential cycles at level {}, its \
             complex has H1 rank {cycle_rank}",
            s.essential_cycles, s.step
        ));
    }
    let morse_check = MorseCheck {
        side,
        ok: result.morse_failures().next().is_none(),
        surface_morse_expected: surface_morse_expected(surface_report, side),
        morse_expected: result.morse_expected,
        cycles_ok: cycle_failure.is_none(),
        cycle_rank: result.cycle_rank,
        steps: result.steps.clone(),
    };
    // The rank's warning is given once the other side's linked search has run
    // ([`link_sides`]).
    let rank = loop_rank(&found.loops);
    let homology = HomologyCheck {
        genus,
        rank,
        ok: genus == Some(rank as i64),
    };

    // The side's timings: laps of one clock, so they add up to its wall time; the
    // Morse stage's own split tells smoothing (the heat steps, during which the level
    // before is analysed) from critical points (the rest of it).
    let smoothing = result.timings.assembly + result.timings.smoothing;
    let timings = StageTimings {
        volume_mesh: 0.0,
        distance: distance_seconds,
        smoothing,
        critical_points: morse_seconds - smoothing,
        loops: clock.lap(),
        total: clock.total(),
    };
    let side_report = SideReport {
        homology,
        bars: result.bars.clone(),
        side,
        volume: volume.report(),
        unknowns: result.unknowns,
        preconditioner: if result.multigrid.is_some() {
            morse::Preconditioner::Multigrid
        } else {
            morse::Preconditioner::Jacobi
        },
        iterations: result.solver.iter().map(|step| step.iterations).sum(),
        critical: tracked_points(&result),
        saddles,
        rejected: result.rejected,
        timings,
        field: options.keep_volume.then_some(VolumeField {
            mesh: volume.mesh,
            values: result.field,
        }),
    };
    Ok(Some(SideRun {
        report: side_report,
        morse: morse_check,
        loops: found.loops,
        dropped: found.dropped,
        warnings,
        notes: Vec::new(),
        cycles: result.cycles,
    }))
}

/// The loop stage for one side's seeds: on `surface` (the input, or the volume mesh's
/// boundary where a neck lies by a self-crossing; `distance` is the input's), and with
/// `carry`, carried back from the simplified copy to the input.
struct LoopCutter<'a> {
    surface: &'a SurfaceMesh,
    distance: Option<&'a SurfaceDistance>,
    carry: Option<&'a Carry<'a>>,
    side: Side,
    options: &'a LoopOptions,
    progress: &'a dyn Progress,
}

impl LoopCutter<'_> {
    /// The loops of `seeds`; `memo` carries what the side's earlier cuts found.
    fn cut(&self, seeds: &[Seed], memo: &LoopMemo) -> Result<LoopResult> {
        let (surface, options) = (self.surface, self.options);
        let found = loops::find_loops_with_progress(
            surface,
            self.distance,
            seeds,
            self.side,
            options,
            memo,
            self.progress,
        )?;
        // On a simplified copy: the same planes cut the input, and the loops are
        // tightened there.
        match self.carry {
            Some(c) => {
                let input = &c.prepared;
                let to = c.surface.get_or_init(|| LoopSurface::new(&input.mesh));
                loops::transfer_loops(&input.mesh, to, &input.distance, seeds, found, options)
            }
            None => Ok(found),
        }
    }
}

/// The loops of `seeds`, brought to the side's `genus` where they span another number
/// of classes; and whether the `completions` were cut (their seeds then follow
/// `seeds`' in the result's numbering).
/// 1. Fewer classes than the genus: loops from the completions (the vertices that close
///    the missing classes but fail as necks: walls a cell or two thick give them no
///    2-saddle Hessian), each kept where it adds a class (`loops::complete_classes`).
/// 2. More: some loop bounds no disk on this side (its plane's curve has another inside
///    it: a cross-section with holes). Every seed is cut again keeping only curves that
///    bound disks, and completed; taken, with a warning, when nearer the genus.
///
/// The cuts share a [`LoopMemo`]: the strict pass cuts the first pass's planes and
/// tightens most of its curves again, only further where they shrink.
fn loops_to_genus(
    cutter: &LoopCutter,
    seeds: &[Seed],
    completions: &[Seed],
    genus: i64,
    warnings: &mut Vec<String>,
) -> Result<(LoopResult, bool)> {
    let off_genus = |found: &LoopResult| loop_rank(&found.loops) as i64 - genus;
    // The cuts below repeat each other's planes and tightenings.
    let memo = LoopMemo::default();
    let completed = |seeds: &[Seed]| -> Result<(LoopResult, bool)> {
        let mut found = cutter.cut(seeds, &memo)?;
        let complete = off_genus(&found) < 0 && !completions.is_empty();
        if complete {
            let extra = cutter.cut(completions, &memo)?;
            loops::complete_classes(&mut found, extra, seeds.len());
        }
        Ok((found, complete))
    };
    let first = completed(seeds)?;
    let over = off_genus(&first.0);
    if over <= 0 {
        return Ok(first);
    }
    let strict: Vec<Seed> = seeds.iter().map(|s| s.needing_a_disk()).collect();
    let again = completed(&strict)?;
    let d = off_genus(&again.0);
    if d.abs() >= over {
        return Ok(first);
    }
    warnings.push(format!(
        "{}: the loops spanned {over} classes more than the genus; cut again keeping only plane curves that bound a disk on this side (now {d:+})",
        cutter.side.name()
    ));
    Ok(again)
}

/// Where a side's loops span fewer classes than the genus and the other side's span it
/// all, the loops of the missing classes that bound no disk on the side, from the other
/// side's loops and cycles ([`loops::linked`]), on the input (where the loops are). Not
/// for a surface that crosses itself, whose genus is not the solid's.
fn link_sides(
    prepared: &PreparedSurface,
    carry: Option<&Carry>,
    options: &LoopOptions,
    sides: &mut [SideRun],
) {
    let [a, b] = sides else { return };
    if prepared.distance.crossings().is_some_and(|c| !c.is_empty()) {
        return;
    }
    for first in [true, false] {
        let (this, other) = if first {
            (&mut *a, &*b)
        } else {
            (&mut *b, &*a)
        };
        let (homology, side) = (this.report.homology, this.report.side);
        let Some(genus) = homology.genus.filter(|&g| g > homology.rank as i64) else {
            continue;
        };
        let start = Instant::now();
        let built;
        let surface = match carry {
            Some(c) => c.surface.get_or_init(|| LoopSurface::new(&prepared.mesh)),
            None => {
                built = LoopSurface::new(&prepared.mesh);
                &built
            }
        };
        let first_seed = this.report.saddles.len();
        let linked = loops::linked::linked_loops(
            &prepared.mesh,
            surface,
            side,
            &this.loops,
            &other.loops,
            &other.cycles,
            genus as usize,
            first_seed,
            options,
        );
        if !linked.loops.is_empty() {
            let n = linked.loops.len();
            this.notes.push(format!(
                "{}: {n} {} loop{} of classes that bound no disk on this side (a knotted part), from the {} side's loops and cycles",
                side.name(),
                side.neck_name(),
                if n == 1 { "" } else { "s" },
                other.report.side.name()
            ));
        }
        this.loops.extend(linked.loops);
        this.warnings.extend(linked.shortfalls);
        let rank = loop_rank(&this.loops);
        this.report.homology = HomologyCheck {
            rank,
            ok: rank as i64 == genus,
            ..homology
        };
        let seconds = start.elapsed().as_secs_f64();
        this.report.timings.loops += seconds;
        this.report.timings.total += seconds;
    }
}

/// The warning of a side whose loops' Z2 rank is not the surface's genus.
fn rank_warning(prepared: &PreparedSurface, run: &mut SideRun) {
    let HomologyCheck { genus, rank, .. } = run.report.homology;
    let Some(g) = genus.filter(|&g| g != rank as i64) else {
        return;
    };
    let (name, neck) = (run.report.side.name(), run.report.side.neck_name());
    let crossing = prepared.distance.crossings().map_or(0, <[_]>::len);
    run.warnings.push(if crossing > 0 {
        format!(
            "{name}: the {neck} loops have Z2 rank {rank}; the surface's components have genus {g}, but it crosses itself ({crossing} pairs of triangles), so the solid it bounds may have another"
        )
    } else {
        format!("{name}: the {neck} loops have Z2 rank {rank}, the surface has genus {g}")
    });
}

/// The Z2 rank of the loops' homology classes.
fn loop_rank(loops: &[NeckLoop]) -> usize {
    let classes: Vec<Vec<u64>> = loops.iter().map(NeckLoop::class).collect();
    crate::mesh::z2_rank(&classes)
}

/// A wall clock read in laps: each lap is the time since the one before, so the laps
/// of a run add up to its total.
struct Stopwatch {
    start: Instant,
    last: Instant,
}

impl Stopwatch {
    fn start() -> Self {
        let now = Instant::now();
        Stopwatch {
            start: now,
            last: now,
        }
    }

    /// Seconds since the last lap (or the start).
    fn lap(&mut self) -> f64 {
        let now = Instant::now();
        let seconds = (now - self.last).as_secs_f64();
        self.last = now;
        seconds
    }

    /// Leave the time since the last lap out of the laps and the total (a wait).
    fn resume(&mut self) {
        let now = Instant::now();
        self.start += now - self.last;
        self.last = now;
    }

    /// Seconds from the start to the last lap: the sum of the laps.
    fn total(&self) -> f64 {
        (self.last - self.start).as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_steps_are_a_sixteenth_and_a_quarter_then_the_whole_above_the_smallest() {
        let g = 1_000_000_000;
        assert_eq!(budget_steps(4 * g, true), vec![g / 4, g, 4 * g]);
        assert_eq!(budget_steps(4 * g, false), vec![4 * g]);
        // A sixteenth of 1 GB is below the smallest step: a quarter, then the whole.
        assert_eq!(budget_steps(g, true), vec![g / 4, g]);
        assert_eq!(budget_steps(SMALLEST_STEP, true), vec![SMALLEST_STEP]);
    }
}
