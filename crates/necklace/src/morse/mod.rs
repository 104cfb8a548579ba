//! The smoothed distance field and its critical points: which 2-saddles mark necks
//! (paper sections 3 and 4.1–4.2, judged across scales).
//!
//! Input: a [`TetMesh`] whose vertex kinds say which vertices are on the surface and on
//! the outer sphere, and a field with one value per vertex (the pipeline passes the
//! exact distance to the surface: 0 on surface vertices, the true distance on the outer
//! sphere). Every non-interior vertex is a Dirichlet vertex and keeps its value.
//! [`analyze`] then runs the method:
//! 1. assemble the cotangent stiffness `L` and lumped mass `M` ([`laplacian`], as
//!    [`SparseMatrix`]);
//! 2. take implicit heat steps `(M + τ_k L) F' = M F` ([`smoothing`]: the reduced
//!    Dirichlet system assembled once, [`HeatSolver::set_tau`] for each step's `τ`,
//!    conjugate gradients from a projected warm start, preconditioned by Jacobi or by
//!    [`multigrid`]) on one of two [`Schedule`]s:
//!    - **scale space** (default): heat times `t_k = s_k²` on a geometric sequence of
//!      scales `s_k` (lengths, the input's units) from `min_scale` (the pipeline passes
//!      twice the lattice spacing) to `max_scale` × the surface's bounding-box diagonal,
//!      `levels` of them, every one classified; step `k` takes `τ_k = t_k − t_{k−1}`;
//!    - **paper**: `steps` steps of one `τ` given in units where the longest side of the
//!      surface's bounding box is 1 (the paper rescales the mesh to a unit box),
//!      classified from step `initial_steps` on.
//!
//!    When every Dirichlet value is 0 (inside), the map is linear, so `F` is rescaled
//!    to `max |F| = 1` after each step (thin parts decay by up to 1e-47); with non-zero
//!    boundary values (outside) it is not;
//! 3. at every classified level, classify every interior vertex by its link ([`critical`]:
//!    [`Links`] built once, a vertex classified again only where its link changed sides,
//!    [`LinkSides`]), check the Morse sum against the mesh's topology
//!    ([`expected_morse_sum`], from its subcomplexes), track the critical points from level
//!    to level ([`tracking`]) — but not where the field has *drained* below
//!    [`MorseOptions::drained_floor`] (1e-8) of its largest value: there the solve's error,
//!    not the field, orders neighbouring values, so those critical points are only counted
//!    ([`StepSummary::drained`]) —, give every 2-saddle its topological role by a
//!    superlevel sweep ([`roles`]: separating with a bulge ratio, cycle-closing, or a local
//!    cycle: lattice noise; whether a closed cycle is essential by its Z2 class over a
//!    cocycle basis, [`cycles`], so the genus is known at every level) and fit its Hessian
//!    ([`hessian`]). This analysis of level `k` (mostly sequential) runs while level
//!    `k + 1`'s heat step (parallel) is solved (`rayon::join`); the two share nothing they
//!    write, so the result is that of running them in turn;
//! 4. select. Scale space: a 2-saddle track is a neck candidate when it lives at least
//!    `min_levels` levels, its Hessian has signature (−, −, +) at some level, and it is
//!    cycle-closing at such a level (then its *representative* level, where it is
//!    placed, is its first fitted one, the least smoothed), or separating (placed at
//!    the level of its largest bulge ratio); a track that only ever closes local cycles
//!    is noise. A separating candidate whose bulge reaches `min_bulge` is a neck by its
//!    lobe alone (`Saddle::by_bulge`); one below it is passed on all the same, and the
//!    loop stage keeps it only where its loop opens out on both sides (a waist, a
//!    baby's neck: `loops::opening`). Each candidate carries its largest bulge and the
//!    lobe (maximum track) it cuts off there, also when it is cycle-closing at other
//!    levels (then only a passing bulge). Paper: the 2-saddles
//!    alive at the last step that survived `min_persistence` steps and pass the Hessian
//!    test. In both, saddles closer than the matching radius are one neck (keep the
//!    most persistent), and every 2-saddle track not kept is listed with the reason.
//!    Which candidates are the same neck at another scale (the same cycle, or the same
//!    lobe in the same class) is decided on the surface, by the loops' homology
//!    classes (`loops`).
//!    Beside the selection, the scale space keeps its *completions*
//!    ([`MorseResult::completions`]): at every level, the vertices that close the
//!    essential cycles ([`Closer`]: a 2-saddle, or a degenerate saddle), followed from
//!    level to level within the matching radius, each with up to five cutting normals:
//!    the axis between the two parts of its upper link the cycle closes through
//!    ([`Links::upper_axis`]); the normal of the plane through it that holds the
//!    centroid and best-fit normal of the cycle itself (the shortest way round in the
//!    superlevel set, [`Sweep::cycle_through`], searched once per completion); and its
//!    Hessian's three eigenvectors. They are not necks by their
//!    shape; the pipeline cuts them only for the classes of the genus that the
//!    selected saddles' loops miss.
//!
//! The result, [`MorseResult`]: per level its counts and checks, the selected [`Saddle`]s,
//! every 2-saddle track not kept with its [`RejectReason`], the barcode ([`Bar`]: each
//! track's life over scale), the completions, the smoothed field and timings.
//!
//! Conventions: `L` is positive semidefinite (`l = −Δf`), `M` gives a quarter of each
//! tet's volume to each of its vertices; lengths in the mesh's units; scales are `√t`;
//! steps and levels are counted from 1 (step `k` = the field after `k` heat steps).

pub mod critical;
pub mod cycles;
pub mod hessian;
pub mod laplacian;
pub mod multigrid;
mod result;
pub mod roles;
mod selection;
pub mod smoothing;
pub mod tracking;

use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::progress::{Progress, Silent};
use crate::tet::{TetMesh, VertexKind};

pub use critical::{
    classify, expected_morse_sum, Classification, LinkSides, Links, MorseExpectation, VertexClass,
    VertexType,
};
use hessian::plane_normal;
pub use hessian::{hessian_at, Fit, Hessian};
pub use laplacian::{cotangent_stiffness, lumped_mass, SparseMatrix};
pub use result::{
    Bar, MorseResult, MorseTimings, NormalSource, RejectReason, RejectedSaddle, Saddle, StepSummary,
};
pub use roles::{Closer, CycleSearch, RoleAt, Roles, SaddleRole, Sweep};
use selection::{barcode, select_at_last_step, select_over_scales};
pub use smoothing::{
    implicit_step, HeatSolver, Preconditioner, SolverOptions, StepReport, MULTIGRID_MAX_UNKNOWNS,
    MULTIGRID_MIN_UNKNOWNS,
};
pub use tracking::{CriticalPoint, StepEvents, Track, Tracker};

/// Which heat times to classify at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Schedule {
    /// A geometric sequence of scales from `min_scale` to `max_scale` (default).
    ScaleSpace,
    /// The paper's fixed `τ`, `steps` steps, classified from `initial_steps` on.
    Paper,
}

/// Options of [`analyze`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MorseOptions {
    /// Which heat times to classify at (default [`Schedule::ScaleSpace`]).
    pub schedule: Schedule,
    /// Scale space: classified levels (default 32).
    pub levels: usize,
    /// Scale space: the smallest scale `√t`, in mesh units (default `None`: twice the
    /// median edge length of the mesh; the pipeline passes twice the lattice spacing).
    pub min_scale: Option<f64>,
    /// Scale space: the largest scale, as a fraction of the surface's bounding-box
    /// diagonal (default 0.25).
    pub max_scale: f64,
    /// Scale space: levels a 2-saddle track must live to be a neck (default 3: about
    /// 1.2× in scale at the default 32 levels over 8×).
    pub min_levels: usize,
    /// Scale space: smallest bulge ratio of a separating neck by its lobe alone: the
    /// unsmoothed distance (inscribed radius) near the lobe's maximum over the one near
    /// the saddle, at one level (default 1.5: above the bumps where tubes meet, up to
    /// 1.26 on the analytic shapes (a pretzel's junction) and 1.35 at the wire sphere's
    /// nodes). Thinner bulges a person calls necks (1.36 at the fertility's baby's neck,
    /// 1.10 at its mother's waist, where the body is flat) are judged by the loop stage
    /// instead, by how the surface opens out on both sides of their loops.
    pub min_bulge: f64,
    /// Paper: heat time step `τ` in units where the surface's bounding box has longest
    /// side 1 (default 0.01, the paper's `λh`).
    pub tau: f64,
    /// Paper: heat steps before the first classification (default 10, the paper's
    /// initial smoothing).
    pub initial_steps: usize,
    /// Paper: last step `N` (default 20, the paper's "sm = 20").
    pub steps: usize,
    /// Paper: steps a 2-saddle must have survived at step `N` to be selected (default
    /// 5; capped at `N − initial_steps`, so a run with `N = initial_steps` keeps every
    /// 2-saddle that passes the Hessian test).
    pub min_persistence: usize,
    /// Matching radius of the tracking, in multiples of the mean edge length at the
    /// critical point (default 2).
    pub track_radius: f64,
    /// The most heat steps (levels of the scale space, or the paper schedule's `steps`)
    /// a run may take (default [`DEFAULT_MAX_STEPS`]); more is refused with
    /// [`ErrorKind::OverBudget`](crate::error::ErrorKind::OverBudget) before any work.
    pub max_steps: usize,
    /// Where `|F|` is below this fraction of its largest value, its critical points are
    /// counted ([`StepSummary::drained`]) but not tracked: there the solve's error, not
    /// the field, orders neighbouring values (default 1e-8; raised to 100× the solver's
    /// tolerance when that is looser than 1e-10).
    ///
    /// Measured on the scorpion's inside: solved once at the default
    /// tolerance 1e-10 and once at 1e-13, the two fields' 2-saddles differ only at
    /// vertices below 6e-10 (most below 1e-11), and from the 12th of 32 levels on more
    /// than 95 % of its critical points lie below 1e-8 — thousands, where the thin legs
    /// have drained. A floor of 1e-7 loses the skull's right zygomatic arch (its saddle
    /// falls below it two levels after it appears); 1e-8 keeps both arches.
    pub drained_floor: f64,
    /// The linear solver's stopping rule and warm start (its `history` left at `None`
    /// takes six stored solutions on the scale space, three on the paper schedule).
    pub solver: SolverOptions,
}

impl MorseOptions {
    /// Check the options on their own (ranges, and the step budget): the errors
    /// [`analyze`] would return before doing any work.
    pub fn check(&self) -> Result<()> {
        let heat_steps = match self.schedule {
            Schedule::ScaleSpace => self.levels,
            Schedule::Paper => self.steps,
        };
        if heat_steps > self.max_steps {
            return Err(Error::new(
                crate::error::ErrorKind::OverBudget,
                format!(
                    "{heat_steps} heat steps are above the budget of {} (each is a linear solve over the whole volume); raise it with --max-steps",
                    self.max_steps
                ),
            ));
        }
        if !(self.tau > 0.0 && self.tau.is_finite()) {
            return Err(Error::invalid_argument(format!(
                "tau = {} must be positive",
                self.tau
            )));
        }
        if self.initial_steps == 0 || self.steps < self.initial_steps {
            return Err(Error::invalid_argument(format!(
                "steps = {} must be at least initial_steps = {} (and that at least 1)",
                self.steps, self.initial_steps
            )));
        }
        if !(self.track_radius > 0.0 && self.track_radius.is_finite()) {
            return Err(Error::invalid_argument(format!(
                "track_radius = {} must be positive",
                self.track_radius
            )));
        }
        if self.levels == 0 {
            return Err(Error::invalid_argument("levels must be at least 1"));
        }
        if !(self.max_scale > 0.0 && self.max_scale.is_finite()) {
            return Err(Error::invalid_argument(format!(
                "max_scale = {} must be positive",
                self.max_scale
            )));
        }
        if let Some(s) = self.min_scale {
            if !(s > 0.0 && s.is_finite()) {
                return Err(Error::invalid_argument(format!(
                    "min_scale = {s} must be positive"
                )));
            }
        }
        if !(0.0..1.0).contains(&self.drained_floor) {
            return Err(Error::invalid_argument(format!(
                "drained_floor = {} must be in [0, 1)",
                self.drained_floor
            )));
        }
        if !(self.min_bulge >= 1.0 && self.min_bulge.is_finite()) {
            return Err(Error::invalid_argument(format!(
                "min_bulge = {} must be at least 1",
                self.min_bulge
            )));
        }
        Ok(())
    }
}

/// The default budget of heat steps, [`MorseOptions::max_steps`]: 50 times the paper's
/// 20 steps, 30 times the scale space's 32 levels.
pub const DEFAULT_MAX_STEPS: usize = 1000;

/// Solutions the paper schedule's solver keeps for its initial guess: three, as when
/// that schedule was the default, so that it gives the same saddles as then.
const PAPER_HISTORY: usize = 3;

impl Default for MorseOptions {
    fn default() -> Self {
        MorseOptions {
            schedule: Schedule::ScaleSpace,
            levels: 32,
            min_scale: None,
            max_scale: 0.25,
            min_levels: 3,
            min_bulge: 1.5,
            tau: 0.01,
            initial_steps: 10,
            steps: 20,
            min_persistence: 5,
            track_radius: 2.0,
            max_steps: DEFAULT_MAX_STEPS,
            drained_floor: 1e-8,
            solver: SolverOptions::default(),
        }
    }
}

/// One heat step of a schedule.
#[derive(Debug, Clone, Copy)]
struct PlannedStep {
    /// `τ` in mesh units.
    tau: f64,
    /// Scale `√t` after it.
    scale: f64,
    /// Whether to classify after it.
    classify: bool,
}

/// A 2-saddle seen at one level, with what is needed to select it.
#[derive(Debug, Clone, Copy)]
struct Observation {
    step: usize,
    vertex: u32,
    position: [f64; 3],
    radius: f64,
    value: f64,
    role: RoleAt,
    /// The track of the younger maximum (separating).
    lobe: Option<usize>,
    hessian: Option<Hessian>,
}

/// What [`observe`] has gathered: per track, its saddle at every level it was seen
/// at; and the fits of the last level's saddles, which a saddle still there at the
/// next level takes again.
#[derive(Default)]
struct Observed {
    by_track: Vec<Vec<Observation>>,
    fits: HashMap<u32, Fit>,
}

/// The first vertex of a completion: one that closes an essential cycle at some level
/// (a 2-saddle or a degenerate saddle, [`Closer`]) with no completion within the
/// matching radius at the level before, and what it is cut with: the axis between the
/// two components of its upper link the cycle closes through ([`Links::upper_axis`]),
/// its Hessian, and the normal of the plane through it that holds its cycle's centre
/// and best-fit normal ([`cycle_normal`]).
#[derive(Debug, Clone, Copy)]
struct Closing {
    step: usize,
    vertex: u32,
    position: [f64; 3],
    value: f64,
    axis: [f64; 3],
    hessian: Hessian,
    cycle_normal: Option<[f64; 3]>,
}

/// A completion followed over levels: its first closing; where the last vertex that
/// followed it was, at which level, and the matching radius there; the levels it was
/// seen at.
#[derive(Debug, Clone, Copy)]
struct Followed {
    first: Closing,
    last_step: usize,
    last_position: [f64; 3],
    last_radius: f64,
    seen: usize,
}

/// Vertices a search for a closed cycle may visit ([`Sweep::cycle_through`]).
const CYCLE_SEARCH_LIMIT: usize = 500_000;

/// Smooth `field` on `mesh`, classify and track its critical points, and select the
/// 2-saddles that mark necks (see the module doc).
pub fn analyze(mesh: &TetMesh, field: &[f64], options: &MorseOptions) -> Result<MorseResult> {
    analyze_with_progress(mesh, field, options, &Silent)
}

/// [`analyze`], reporting each heat step (with its classification) to `progress`.
pub fn analyze_with_progress(
    mesh: &TetMesh,
    field: &[f64],
    options: &MorseOptions,
    progress: &dyn Progress,
) -> Result<MorseResult> {
    check_inputs(mesh, field, options)?;

    // 1. The adjacency and its cocycles, the operators, the reduced heat system and the
    //    links (once). The sweep first: building the cocycles takes several arrays the
    //    size of the mesh's triangles for a while, which would otherwise come on top of
    //    the solver and the links (a side's peak).
    let start = Instant::now();
    let sweep = Sweep::new(mesh);
    let stiffness = cotangent_stiffness(mesh);
    let mass = lumped_mass(mesh);
    let fixed: Vec<bool> = (0..mesh.num_vertices())
        .map(|v| mesh.kinds[v] != VertexKind::Interior || mass[v] <= 0.0)
        .collect();
    let rescaled = (0..mesh.num_vertices()).all(|v| !fixed[v] || field[v] == 0.0);
    let plan = plan_steps(mesh, options);
    let first_tau = plan.first().map_or(0.0, |p| p.tau);
    let solver_options = SolverOptions {
        history: options.solver.history.or(match options.schedule {
            Schedule::ScaleSpace => None,
            Schedule::Paper => Some(PAPER_HISTORY),
        }),
        ..options.solver
    };
    let mut solver = HeatSolver::new(&stiffness, &mass, &fixed, field, first_tau, solver_options);
    // The solver holds the free rows it needs; the whole matrix would stay for the
    // analysis's length.
    drop(stiffness);
    let floor = options
        .drained_floor
        .max(DRAINED * solver_options.tolerance);
    let links = Links::new(mesh)?;
    let mut sides = LinkSides::default();
    let morse_expected = expected_morse_sum(mesh);
    let mut timings = MorseTimings {
        assembly: start.elapsed().as_secs_f64(),
        ..MorseTimings::default()
    };

    // 2–3. Heat steps; at every classified one, classify, track, give roles, fit. A
    // level is analysed while the next level's heat step is solved: the analysis is
    // mostly sequential, the solve parallel, and neither reads what the other writes
    // (so the result is the one of doing them in turn).
    let solve = |solver: &mut HeatSolver, tau: f64, f: &[f64]| {
        let start = Instant::now();
        solver.set_tau(tau);
        let (mut next, report) = solver.step(f);
        if rescaled {
            rescale(&mut next);
        }
        (next, report, start.elapsed().as_secs_f64())
    };
    let mut f = field.to_vec();
    let mut reports = Vec::with_capacity(plan.len());
    let mut steps = Vec::new();
    let mut tracker = Tracker::new();
    let mut observed = Observed::default();
    let mut followed: Vec<Followed> = Vec::new();
    let mut cycles: Vec<Vec<[f64; 3]>> = Vec::new();
    progress.start("smoothing and critical points", plan.len() as u64);
    let mut solved = plan.first().map(|p| solve(&mut solver, p.tau, &f));
    for (k, planned) in plan.iter().enumerate() {
        let step = k + 1;
        progress.advance(1);
        let Some((level, report, seconds)) = solved.take() else {
            break;
        };
        reports.push(report);
        timings.smoothing += seconds;
        let analyse = || {
            if !planned.classify {
                return (0.0, 0.0);
            }
            let start = Instant::now();
            let classification = links.classify_again(&level, &mut sides);
            let classifying = start.elapsed().as_secs_f64();
            let start = Instant::now();
            let (critical, drained) =
                critical_points(mesh, &level, &classification, options.track_radius, floor);
            let events = tracker.advance(step, &critical);
            let roles = sweep.roles(&level, &classification, field);
            observe(
                mesh,
                &level,
                step,
                &critical,
                &roles.roles,
                &tracker,
                &mut observed,
            );
            let closed = record_closings(
                (mesh, &links, &sweep),
                &level,
                step,
                &roles.closers,
                options.track_radius,
                &mut followed,
                steps.is_empty(),
            );
            if steps.is_empty() {
                cycles = closed
                    .into_iter()
                    .flatten()
                    .map(|path| path.iter().map(|&u| mesh.positions[u as usize]).collect())
                    .collect();
            }
            steps.push(summarize(
                step,
                planned.scale,
                &classification,
                &roles,
                (morse_expected.sum, sweep.cycle_rank()),
                events,
                drained,
            ));
            (classifying, start.elapsed().as_secs_f64())
        };
        let next = || plan.get(k + 1).map(|p| solve(&mut solver, p.tau, &level));
        let ((classifying, selecting), next) = rayon::join(analyse, next);
        timings.classification += classifying;
        timings.selection += selecting;
        solved = next;
        f = level;
    }
    progress.finish();
    // The solver (the reduced matrix, the stored solutions and any multigrid levels)
    // is the analysis's largest structure, and the selection below does not read it:
    // only its figures are kept.
    let (unknowns, tau, multigrid) = (solver.unknowns(), solver.tau(), solver.multigrid().cloned());
    drop(solver);

    // 4. Select.
    let start = Instant::now();
    let scale_of = |step: usize| plan.get(step.wrapping_sub(1)).map(|p| p.scale);
    let selection = match options.schedule {
        Schedule::ScaleSpace => select_over_scales(
            mesh,
            &tracker.tracks,
            &observed.by_track,
            (&followed, plan.len()),
            options,
            &scale_of,
        ),
        Schedule::Paper => {
            let min_persistence = options
                .min_persistence
                .min(options.steps - options.initial_steps);
            select_at_last_step(
                mesh,
                &f,
                &tracker.tracks,
                &observed.by_track,
                min_persistence,
                (options.track_radius, options.min_bulge),
                &scale_of,
            )
        }
    };
    let bars = barcode(
        &tracker.tracks,
        &observed.by_track,
        &selection.saddles,
        &scale_of,
    );
    timings.selection += start.elapsed().as_secs_f64();

    Ok(MorseResult {
        schedule: options.schedule,
        unknowns,
        tau,
        rescaled,
        solver: reports,
        multigrid,
        steps,
        saddles: selection.saddles,
        rejected: selection.rejected,
        completions: selection.completions,
        bars,
        tracks: tracker.tracks,
        field: f,
        morse_expected,
        cycle_rank: sweep.cycle_rank(),
        cycles,
        timings,
    })
}

/// The heat steps of the schedule (see the module doc).
fn plan_steps(mesh: &TetMesh, options: &MorseOptions) -> Vec<PlannedStep> {
    match options.schedule {
        Schedule::Paper => {
            let unit = longest_side(mesh);
            let tau = options.tau * unit * unit;
            (1..=options.steps)
                .map(|step| PlannedStep {
                    tau,
                    scale: (step as f64 * tau).sqrt(),
                    classify: step >= options.initial_steps,
                })
                .collect()
        }
        Schedule::ScaleSpace => {
            let largest = options.max_scale * diagonal(mesh);
            let mut smallest = options
                .min_scale
                .unwrap_or_else(|| 2.0 * median_edge_length(mesh));
            if !(smallest > 0.0 && smallest < largest) {
                smallest = largest / 8.0;
            }
            let levels = options.levels;
            let mut previous_t = 0.0;
            (0..levels)
                .map(|k| {
                    let fraction = if levels > 1 {
                        k as f64 / (levels - 1) as f64
                    } else {
                        1.0
                    };
                    let scale = smallest * (largest / smallest).powf(fraction);
                    let t = scale * scale;
                    let tau = t - previous_t;
                    previous_t = t;
                    PlannedStep {
                        tau,
                        scale,
                        classify: true,
                    }
                })
                .collect()
        }
    }
}

/// Follow the completions to this level's vertices that close essential cycles: each
/// within the matching radius of a completion last seen at an earlier level follows
/// it, like a track (by vertex index, the first such completion); the others start
/// completions, measured here (axis, Hessian, cycle: only for these, not for every
/// closing at every level), where their upper link gives an axis and a quadratic fits.
/// With `keep_cycles` (the first level), returns every closer's cycle as a vertex path
/// (`None` where the search gave up), in vertex order; else nothing.
fn record_closings(
    (mesh, links, sweep): (&TetMesh, &Links, &Sweep),
    f: &[f64],
    step: usize,
    closers: &[Closer],
    track_radius: f64,
    followed: &mut Vec<Followed>,
    keep_cycles: bool,
) -> Vec<Option<Vec<u32>>> {
    let mut closers = closers.to_vec();
    closers.sort_by_key(|c| c.vertex);
    let mut fresh = Vec::new();
    for c in closers {
        let v = c.vertex as usize;
        let (position, radius) = (mesh.positions[v], track_radius * mean_edge_length(mesh, v));
        let follows = followed.iter_mut().find(|f| {
            f.last_step < step && norm(sub(f.last_position, position)) <= f.last_radius.max(radius)
        });
        match follows {
            Some(f) => {
                (f.last_step, f.last_position, f.last_radius) = (step, position, radius);
                f.seen += 1;
            }
            None => fresh.push((c, radius)),
        }
    }
    let measured: Vec<(Option<Followed>, Option<Vec<u32>>)> = fresh
        .into_par_iter()
        .map_init(CycleSearch::default, |search, (c, radius)| {
            let v = c.vertex as usize;
            let fit = links
                .upper_axis(v, f, &mesh.positions, c.through)
                .and_then(|axis| Some((axis, hessian_at(mesh, f, c.vertex)?)));
            // The cycle only where it is used: a completion's plane, or kept.
            let cycle = (keep_cycles || fit.is_some())
                .then(|| sweep.cycle_through(c, f, CYCLE_SEARCH_LIMIT, search))
                .flatten();
            let followed = fit.map(|(axis, hessian)| {
                let first = Closing {
                    step,
                    vertex: c.vertex,
                    position: mesh.positions[v],
                    value: f[v],
                    axis,
                    hessian,
                    cycle_normal: cycle
                        .as_deref()
                        .and_then(|path| cycle_normal(&mesh.positions, path)),
                };
                Followed {
                    first,
                    last_step: step,
                    last_position: first.position,
                    last_radius: radius,
                    seen: 1,
                }
            });
            (followed, cycle.filter(|_| keep_cycles))
        })
        .collect();
    let mut cycles = Vec::new();
    for (f, cycle) in measured {
        followed.extend(f);
        if keep_cycles {
            cycles.push(cycle);
        }
    }
    cycles
}

/// The normal of the plane through a cycle's first vertex that holds the cycle's
/// centroid and the normal of its best-fit plane: for a cycle round a hole, the plane
/// through the vertex and the hole's axis, which cuts the bar the vertex lies in
/// (the cycle's tangent there, had it been a circle). `None` when the vertex is at the
/// centroid or the cycle is straight.
fn cycle_normal(positions: &[[f64; 3]], path: &[u32]) -> Option<[f64; 3]> {
    let points: Vec<[f64; 3]> = path.iter().map(|&u| positions[u as usize]).collect();
    let centroid = scale(
        points.iter().fold([0.0; 3], |s, &p| add(s, p)),
        1.0 / points.len() as f64,
    );
    let normal = cross(plane_normal(&points, centroid), sub(points[0], centroid));
    let length = norm(normal);
    (length > 0.0 && length.is_finite()).then(|| scale(normal, 1.0 / length))
}

/// Record every 2-saddle of this level with its track, role, lobe and Hessian.
fn observe(
    mesh: &TetMesh,
    f: &[f64],
    step: usize,
    critical: &[CriticalPoint],
    roles: &[RoleAt],
    tracker: &Tracker,
    observed: &mut Observed,
) {
    let fits = &mut observed.fits;
    let alive_here = |kind: VertexType| -> Vec<(u32, usize)> {
        let mut v: Vec<(u32, usize)> = tracker
            .tracks
            .iter()
            .enumerate()
            .filter(|(_, t)| t.alive && t.last_seen == step && t.kind == kind)
            .map(|(i, t)| (t.vertex, i))
            .collect();
        v.sort_unstable();
        v
    };
    let saddle_tracks = alive_here(VertexType::Saddle2);
    let maximum_tracks = alive_here(VertexType::Maximum);
    let track_of = |list: &[(u32, usize)], v: u32| {
        list.binary_search_by_key(&v, |&(u, _)| u)
            .ok()
            .map(|i| list[i].1)
    };
    // A saddle observed at the last level too keeps its fit's factored matrix (most
    // saddles live on: on tm_1002_tray_bottom's inside, 15 000 to 25 000 a level, and
    // fitting them from scratch was a third of its run).
    let found: Vec<(usize, Observation, Option<Fit>)> = critical
        .par_iter()
        .filter(|p| p.kind == VertexType::Saddle2)
        .filter_map(|p| {
            let track = track_of(&saddle_tracks, p.vertex)?;
            let role = roles[roles.binary_search_by_key(&p.vertex, |r| r.vertex).ok()?];
            let fresh = if fits.contains_key(&p.vertex) {
                None
            } else {
                Fit::new(mesh, p.vertex)
            };
            let fit = fresh.as_ref().or_else(|| fits.get(&p.vertex));
            Some((
                track,
                Observation {
                    step,
                    vertex: p.vertex,
                    position: p.position,
                    radius: p.radius,
                    value: f[p.vertex as usize],
                    role,
                    lobe: role.younger_max.and_then(|m| track_of(&maximum_tracks, m)),
                    hessian: fit.and_then(|fit| fit.hessian(f)),
                },
                fresh,
            ))
        })
        .collect();
    let observations = &mut observed.by_track;
    if observations.len() < tracker.tracks.len() {
        observations.resize(tracker.tracks.len(), Vec::new());
    }
    // The fits of this level's saddles, for the next.
    let mut kept = HashMap::with_capacity(found.len());
    for (track, observation, fresh) in found {
        let v = observation.vertex;
        if let Some(fit) = fresh.or_else(|| fits.remove(&v)) {
            kept.insert(v, fit);
        }
        observations[track].push(observation);
    }
    *fits = kept;
}

fn check_inputs(mesh: &TetMesh, field: &[f64], options: &MorseOptions) -> Result<()> {
    if field.len() != mesh.num_vertices() {
        return Err(Error::invalid_argument(format!(
            "the field has {} values for {} vertices",
            field.len(),
            mesh.num_vertices()
        )));
    }
    if let Some(v) = field.iter().position(|x| !x.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "the field is not finite at vertex {v}"
        )));
    }
    options.check()
}

/// Bounding box of the surface vertices (of all vertices when there are none).
fn surface_box(mesh: &TetMesh) -> ([f64; 3], [f64; 3]) {
    let on_surface = |v: usize| mesh.kinds[v] == VertexKind::Surface;
    let any_surface = (0..mesh.num_vertices()).any(on_surface);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (v, p) in mesh.positions.iter().enumerate() {
        if any_surface && !on_surface(v) {
            continue;
        }
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Longest side of [`surface_box`]; 1 for an empty or flat-to-a-point mesh.
fn longest_side(mesh: &TetMesh) -> f64 {
    let (lo, hi) = surface_box(mesh);
    let side = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if side > 0.0 && side.is_finite() {
        side
    } else {
        1.0
    }
}

/// Diagonal of [`surface_box`]; 1 for an empty or flat-to-a-point mesh.
fn diagonal(mesh: &TetMesh) -> f64 {
    let (lo, hi) = surface_box(mesh);
    let d = norm(sub(hi, lo));
    if d > 0.0 && d.is_finite() {
        d
    } else {
        1.0
    }
}

/// Median length of the tets' edges (each tet's six, with repeats).
fn median_edge_length(mesh: &TetMesh) -> f64 {
    let mut lengths: Vec<f64> = mesh
        .tets
        .iter()
        .flat_map(|t| {
            const PAIRS: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
            PAIRS.map(|(a, b)| {
                norm(sub(
                    mesh.positions[t[a] as usize],
                    mesh.positions[t[b] as usize],
                ))
            })
        })
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let middle = lengths.len() / 2;
    *lengths.select_nth_unstable_by(middle, f64::total_cmp).1
}

/// Divide by the largest magnitude (nothing when the field is 0).
fn rescale(f: &mut [f64]) {
    let largest = f.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if largest > 0.0 && largest.is_finite() {
        f.iter_mut().for_each(|x| *x /= largest);
    }
}

/// The drained floor is at least this many times the solver's relative tolerance
/// ([`MorseOptions::drained_floor`]).
const DRAINED: f64 = 100.0;

/// The critical points of a classification of `f` that lie above `floor` × the largest
/// `|f|`, with their matching radii, and how many lie below it (drained).
fn critical_points(
    mesh: &TetMesh,
    f: &[f64],
    classification: &Classification,
    track_radius: f64,
    floor: f64,
) -> (Vec<CriticalPoint>, usize) {
    let threshold = floor * f.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut drained = 0;
    let points = classification
        .classes
        .iter()
        .enumerate()
        .filter(|(_, c)| !matches!(c.kind, VertexType::Regular | VertexType::Boundary))
        .filter(|&(v, _)| {
            let above = f[v].abs() > threshold;
            drained += usize::from(!above);
            above
        })
        .map(|(v, c)| CriticalPoint {
            vertex: v as u32,
            kind: c.kind,
            position: mesh.positions[v],
            radius: track_radius * mean_edge_length(mesh, v),
        })
        .collect();
    (points, drained)
}

/// Mean length of the edges at vertex `v` (each tet's edges at `v`, with repeats).
fn mean_edge_length(mesh: &TetMesh, v: usize) -> f64 {
    let p = mesh.positions[v];
    let (mut sum, mut count) = (0.0, 0usize);
    for &t in mesh.vertex_tets(v) {
        for &u in &mesh.tets[t as usize] {
            if u as usize != v {
                let q = mesh.positions[u as usize];
                sum +=
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                count += 1;
            }
        }
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

fn summarize(
    step: usize,
    scale: f64,
    c: &Classification,
    roles: &Roles,
    (morse_expected, cycle_rank): (i64, usize),
    events: StepEvents,
    drained: usize,
) -> StepSummary {
    let count = |role| roles.roles.iter().filter(|r| r.role == role).count();
    StepSummary {
        step,
        scale,
        separating: count(SaddleRole::Separating),
        cycle_closing: count(SaddleRole::CycleClosing),
        local_cycles: count(SaddleRole::LocalCycle),
        minima: c.count(VertexType::Minimum),
        maxima: c.count(VertexType::Maximum),
        saddles1: c.count(VertexType::Saddle1),
        saddles2: c.count(VertexType::Saddle2),
        monkeys: c.count(VertexType::Degenerate),
        morse_sum: c.morse_sum,
        morse_expected,
        morse_ok: c.morse_sum == morse_expected,
        essential_cycles: roles.essential_cycles,
        cycles_ok: roles.essential_cycles == cycle_rank,
        events,
        drained,
    }
}

/// `p − H⁻¹ g` from the fitted quadratic, when that step is no longer than `radius`
/// (and `H` is invertible); otherwise `p`.
fn newton_point(p: [f64; 3], h: &Hessian, radius: f64) -> [f64; 3] {
    // In the eigenbasis: step = −Σ (e_k · g / λ_k) e_k.
    let mut step = [0.0; 3];
    for k in 0..3 {
        let lambda = h.eigenvalues[k];
        if lambda == 0.0 || !lambda.is_finite() {
            return p;
        }
        let e = h.eigenvectors[k];
        step = add(step, scale(e, -dot(e, h.gradient) / lambda));
    }
    if norm(step) <= radius {
        add(p, step)
    } else {
        p
    }
}
