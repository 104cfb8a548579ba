//! The smoothed distance field and its critical points: which 2-saddles mark necks
//! (paper sections 3 and 4.1–4.2, judged across scales as in issue 13).
//!
//! Input: a [`TetMesh`] whose vertex kinds say which vertices are on the surface and on
//! the outer sphere, and a field with one value per vertex (the pipeline passes the
//! exact distance to the surface: 0 on surface vertices, the true distance on the outer
//! sphere). Every non-interior vertex is a Dirichlet vertex and keeps its value.
//! [`analyze`] then runs the method:
//! 1. assemble the cotangent stiffness `L` and lumped mass `M` ([`laplacian`]);
//! 2. take implicit heat steps `(M + τ_k L) F' = M F` ([`smoothing`]) on one of two
//!    [`Schedule`]s:
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
//! 3. at every classified level, classify every interior vertex by its link
//!    ([`critical`]), check the Morse sum against the mesh's topology, track the
//!    critical points from level to level ([`tracking`]), give every 2-saddle its
//!    topological role by a superlevel sweep ([`roles`]: separating with a bulge ratio,
//!    cycle-closing, or a local cycle: lattice noise) and fit its Hessian ([`hessian`]);
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
//!
//! Conventions: `L` is positive semidefinite (`l = −Δf`), `M` gives a quarter of each
//! tet's volume to each of its vertices; lengths in the mesh's units; scales are `√t`;
//! steps and levels are counted from 1 (step `k` = the field after `k` heat steps).

pub mod critical;
pub mod cycles;
pub mod hessian;
pub mod laplacian;
pub mod roles;
pub mod smoothing;
pub mod tracking;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::geom::{add, dot, norm, scale, sub};
use crate::progress::{Progress, Silent};
use crate::tet::{TetMesh, VertexKind};

pub use critical::{
    classify, expected_morse_sum, Classification, LinkSides, Links, MorseExpectation, VertexClass,
    VertexType,
};
pub use hessian::{hessian_at, Hessian};
pub use laplacian::{cotangent_stiffness, lumped_mass, SparseMatrix};
pub use roles::{RoleAt, Roles, SaddleRole, Sweep};
pub use smoothing::{implicit_step, HeatSolver, SolverOptions, StepReport};
pub use tracking::{CriticalPoint, StepEvents, Track, Tracker};

/// Which heat times to classify at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Schedule {
    /// A geometric sequence of scales from `min_scale` to `max_scale` (default).
    ScaleSpace,
    /// The paper's fixed `τ`, `steps` steps, classified from `initial_steps` on.
    Paper,
}

/// Options of [`analyze`].
#[derive(Debug, Clone, Copy, PartialEq)]
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
            solver: SolverOptions::default(),
        }
    }
}

/// One classified step (a level of the scale space).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepSummary {
    /// Heat steps taken (the level, counted from 1).
    pub step: usize,
    /// Its scale `√t`, mesh units (`t` = the heat time summed over the steps).
    pub scale: f64,
    /// Minima (none expected: the boundary comes first).
    pub minima: usize,
    /// Maxima.
    pub maxima: usize,
    /// 1-saddles.
    pub saddles1: usize,
    /// 2-saddles.
    pub saddles2: usize,
    /// 2-saddles that join two lobes.
    pub separating: usize,
    /// 2-saddles that close a cycle.
    pub cycle_closing: usize,
    /// 2-saddles that close a cycle within a few edges of themselves (lattice noise).
    pub local_cycles: usize,
    /// Degenerate (monkey) saddles.
    pub monkeys: usize,
    /// Σ over interior vertices of `1 − χ(lower link)`.
    pub morse_sum: i64,
    /// What the mesh's topology says the sum must be ([`expected_morse_sum`]).
    pub morse_expected: i64,
    /// `morse_sum == morse_expected`.
    pub morse_ok: bool,
    /// Cycles the superlevel sweep closed that live for ever (their classes are
    /// independent; the rest are filled lower down: noise, or second copies). See
    /// [`roles`].
    pub essential_cycles: usize,
    /// `essential_cycles` equals [`MorseResult::cycle_rank`]: every class of the swept
    /// complex is born at a saddle of this level.
    pub cycles_ok: bool,
    /// Births, deaths, moves and cancellations since the previous classified step.
    pub events: StepEvents,
}

/// A selected 2-saddle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Saddle {
    /// Its vertex at its representative step.
    pub vertex: u32,
    /// The stationary point of the fitted quadratic (one Newton step from the vertex),
    /// or the vertex position when that step is longer than the matching radius.
    pub position: [f64; 3],
    /// The vertex position.
    pub vertex_position: [f64; 3],
    /// The smoothed field there at its representative step.
    pub value: f64,
    /// Its representative step: the one its position and normal are read at
    /// (step `N` on the paper's schedule).
    pub step: usize,
    /// That step's scale `√t`.
    pub scale: f64,
    /// Step it was first seen.
    pub born: usize,
    /// Steps survived after the first (up to `N` on the paper's schedule; its whole
    /// life on the scale space).
    pub persistence: usize,
    /// Scale at which it appeared.
    pub birth_scale: f64,
    /// Scale of the first level it is no longer seen at (`None`: alive at the largest).
    pub death_scale: Option<f64>,
    /// What it does to the superlevel sets: cycle-closing if it is at any fitted level
    /// (scale space), else separating; at step `N` on the paper's schedule.
    pub role: SaddleRole,
    /// The largest bulge ratio over the levels where it was separating: always for a
    /// separating saddle (`None` when the lobe is the outer sphere's); for a
    /// cycle-closing one only when it reaches `min_bulge` (it is then a neck by its
    /// shape as well as a cycle).
    pub bulge: Option<f64>,
    /// Whether that bulge reaches `min_bulge`: a neck by the shape of its lobe. A
    /// separating saddle below it is selected all the same, and the loop stage keeps
    /// it only where its loop opens out on both sides (`loops::opening`).
    pub by_bulge: bool,
    /// With `bulge`: the track of the maximum of the lobe it cuts off at that level.
    pub lobe: Option<usize>,
    /// Cycle-closing: at some fitted level (its representative step on the paper's
    /// schedule) the cycle it closed was essential, never filled again (see
    /// [`roles`]); false when every cycle it closed was noise or a second copy.
    pub essential: bool,
    /// The fitted Hessian.
    pub hessian: Hessian,
    /// Cutting-plane normal: the eigenvector of the positive eigenvalue.
    pub normal: [f64; 3],
}

impl Saddle {
    /// This saddle, not selected after all, and why.
    fn rejected(&self, reason: RejectReason) -> RejectedSaddle {
        RejectedSaddle {
            vertex: self.vertex,
            position: self.position,
            born: self.born,
            birth_scale: self.birth_scale,
            death_scale: self.death_scale,
            reason,
        }
    }
}

/// Why a 2-saddle track was not selected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum RejectReason {
    /// It survived fewer than `min_persistence` steps (`min_levels` levels).
    ShortLived {
        /// Steps survived.
        persistence: usize,
    },
    /// The fitted Hessian's signature is not (−, −, +) (at any level of its life).
    HessianSignature {
        /// Its eigenvalues, ascending.
        eigenvalues: [f64; 3],
    },
    /// No quadratic could be fitted (too few neighbours).
    NoFit,
    /// At every level where its Hessian fits, it closes only a cycle within a few
    /// edges of itself, with no separating 2-saddle there: lattice noise.
    LocalCycle,
    /// Separating, but the lobe it cuts off is no fatter than the neck (bulge ≤ 1: the
    /// lobe's top is a neighbour of the saddle): a bump, not a part.
    LowBulge {
        /// Its largest bulge ratio.
        bulge: f64,
    },
    /// Another selected 2-saddle lies within the matching radius: one neck seen at
    /// several vertices (a lattice splits a smooth saddle into a cluster of discrete
    /// critical points). The one kept is the more persistent, then the one whose
    /// Newton step is shorter.
    Duplicate {
        /// Vertex of the 2-saddle kept.
        of: u32,
    },
}

impl std::fmt::Display for RejectReason {
    /// One line for a person, e.g. `short-lived: 2 levels`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            RejectReason::ShortLived { persistence } => {
                write!(f, "short-lived: {persistence} steps")
            }
            RejectReason::HessianSignature {
                eigenvalues: [a, b, c],
            } => write!(
                f,
                "Hessian signature is not (-, -, +): eigenvalues {a:.3e}, {b:.3e}, {c:.3e}"
            ),
            RejectReason::NoFit => write!(f, "no quadratic fit (too few neighbours)"),
            RejectReason::LocalCycle => write!(f, "closes only a local cycle: lattice noise"),
            RejectReason::LowBulge { bulge } => {
                write!(f, "a bump, not a part: bulge {bulge:.3} <= 1")
            }
            RejectReason::Duplicate { of } => write!(f, "duplicate of the saddle at vertex {of}"),
        }
    }
}

/// A 2-saddle track that was not selected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RejectedSaddle {
    /// Its vertex (at its last step, or its representative one).
    pub vertex: u32,
    /// Its position.
    pub position: [f64; 3],
    /// Step first seen.
    pub born: usize,
    /// Scale at which it appeared.
    pub birth_scale: f64,
    /// Scale of the first level it is no longer seen at (`None`: alive at the largest).
    pub death_scale: Option<f64>,
    /// Why.
    #[serde(flatten)]
    pub reason: RejectReason,
}

/// Wall-clock seconds of each part of [`analyze`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct MorseTimings {
    /// `L`, `M`, the reduced system and the links.
    pub assembly: f64,
    /// All heat steps.
    pub smoothing: f64,
    /// All classifications.
    pub classification: f64,
    /// Tracking, roles and Hessian fits.
    pub selection: f64,
}

/// Everything [`analyze`] found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MorseResult {
    /// The schedule run.
    pub schedule: Schedule,
    /// Unknowns of the heat system (interior vertices).
    pub unknowns: usize,
    /// `τ` in mesh units (length²) on the paper's schedule; the last step's on the
    /// scale space.
    pub tau: f64,
    /// Whether the field was rescaled after each step (all boundary values 0).
    pub rescaled: bool,
    /// The solver's report for every heat step (`solver[k]` is step `k + 1`).
    pub solver: Vec<StepReport>,
    /// One summary per classified step.
    pub steps: Vec<StepSummary>,
    /// The selected 2-saddles, most persistent first, then by vertex.
    pub saddles: Vec<Saddle>,
    /// 2-saddle tracks that were not selected, and why (paper: those alive at `N`).
    pub rejected: Vec<RejectedSaddle>,
    /// Every 2-saddle track of the run with its scale interval: the barcode.
    pub bars: Vec<Bar>,
    /// Every track of the run (those `alive` are the critical points at the last step).
    #[serde(skip)]
    pub tracks: Vec<Track>,
    /// The field at the last step (rescaled when `rescaled`).
    #[serde(skip)]
    pub field: Vec<f64>,
    /// The mesh's Morse sum and the Euler characteristics it comes from.
    pub morse_expected: MorseExpectation,
    /// The dimension of H₁ (Z2) of the complex the superlevel sweep covers (interior
    /// vertices, outer sphere coned off): the surface's genus when the volume mesh kept
    /// its topology ([`cycles`]).
    pub cycle_rank: usize,
    /// Seconds per part.
    pub timings: MorseTimings,
}

/// One 2-saddle track over scale.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bar {
    /// Scale at which it appeared.
    pub birth_scale: f64,
    /// Scale of the first level it is no longer seen at (`None`: alive at the largest).
    pub death_scale: Option<f64>,
    /// Whether it was cycle-closing at any level of its life.
    pub cycle_closing: bool,
    /// Its vertex when last seen.
    pub vertex: u32,
    /// Whether it was selected.
    pub selected: bool,
    /// When selected: its index in [`MorseResult::saddles`].
    pub saddle: Option<usize>,
}

impl MorseResult {
    /// The classified steps whose Morse sum is not what the topology says.
    pub fn morse_failures(&self) -> impl Iterator<Item = &StepSummary> {
        self.steps.iter().filter(|s| !s.morse_ok)
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

    // 1. Operators, the reduced heat system, the links and the adjacency (once).
    let start = Instant::now();
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
    let links = Links::new(mesh)?;
    let mut sides = LinkSides::default();
    let sweep = Sweep::new(mesh);
    let morse_expected = expected_morse_sum(mesh);
    let mut timings = MorseTimings {
        assembly: start.elapsed().as_secs_f64(),
        ..MorseTimings::default()
    };

    // 2–3. Heat steps; at every classified one, classify, track, give roles, fit.
    let mut f = field.to_vec();
    let mut reports = Vec::with_capacity(plan.len());
    let mut steps = Vec::new();
    let mut tracker = Tracker::new();
    let mut observations: Vec<Vec<Observation>> = Vec::new();
    progress.start("smoothing and critical points", plan.len() as u64);
    for (k, planned) in plan.iter().enumerate() {
        let step = k + 1;
        progress.advance(1);
        let start = Instant::now();
        solver.set_tau(planned.tau);
        let (next, report) = solver.step(&f);
        f = next;
        if rescaled {
            rescale(&mut f);
        }
        reports.push(report);
        timings.smoothing += start.elapsed().as_secs_f64();
        if !planned.classify {
            continue;
        }
        let start = Instant::now();
        let classification = links.classify_again(&f, &mut sides);
        timings.classification += start.elapsed().as_secs_f64();
        let start = Instant::now();
        let critical = critical_points(mesh, &classification, options.track_radius);
        let events = tracker.advance(step, &critical);
        let roles = sweep.roles(&f, &classification, field);
        observe(
            mesh,
            &f,
            step,
            &critical,
            &roles.roles,
            &tracker,
            &mut observations,
        );
        steps.push(summarize(
            step,
            planned.scale,
            &classification,
            &roles,
            (morse_expected.sum, sweep.cycle_rank()),
            events,
        ));
        timings.selection += start.elapsed().as_secs_f64();
    }
    progress.finish();

    // 4. Select.
    let start = Instant::now();
    let scale_of = |step: usize| plan.get(step.wrapping_sub(1)).map(|p| p.scale);
    let (saddles, rejected) = match options.schedule {
        Schedule::ScaleSpace => {
            select_over_scales(mesh, &tracker.tracks, &observations, options, &scale_of)
        }
        Schedule::Paper => {
            let min_persistence = options
                .min_persistence
                .min(options.steps - options.initial_steps);
            select_at_last_step(
                mesh,
                &f,
                &tracker.tracks,
                &observations,
                min_persistence,
                (options.track_radius, options.min_bulge),
                &scale_of,
            )
        }
    };
    let bars = barcode(&tracker.tracks, &observations, &saddles, &scale_of);
    timings.selection += start.elapsed().as_secs_f64();

    Ok(MorseResult {
        schedule: options.schedule,
        unknowns: solver.unknowns(),
        tau: solver.tau(),
        rescaled,
        solver: reports,
        steps,
        saddles,
        rejected,
        bars,
        tracks: tracker.tracks,
        field: f,
        morse_expected,
        cycle_rank: sweep.cycle_rank(),
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

/// Record every 2-saddle of this level with its track, role, lobe and Hessian.
fn observe(
    mesh: &TetMesh,
    f: &[f64],
    step: usize,
    critical: &[CriticalPoint],
    roles: &[RoleAt],
    tracker: &Tracker,
    observations: &mut Vec<Vec<Observation>>,
) {
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
    let found: Vec<(usize, Observation)> = critical
        .par_iter()
        .filter(|p| p.kind == VertexType::Saddle2)
        .filter_map(|p| {
            let track = track_of(&saddle_tracks, p.vertex)?;
            let role = roles[roles.binary_search_by_key(&p.vertex, |r| r.vertex).ok()?];
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
                    hessian: hessian_at(mesh, f, p.vertex),
                },
            ))
        })
        .collect();
    if observations.len() < tracker.tracks.len() {
        observations.resize(tracker.tracks.len(), Vec::new());
    }
    for (track, observation) in found {
        observations[track].push(observation);
    }
}

/// The scale-space selection (see the module doc).
fn select_over_scales(
    mesh: &TetMesh,
    tracks: &[Track],
    observations: &[Vec<Observation>],
    options: &MorseOptions,
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> (Vec<Saddle>, Vec<RejectedSaddle>) {
    let mut candidates = Vec::new();
    let mut rejected = Vec::new();
    for (t, track) in tracks.iter().enumerate() {
        if track.kind != VertexType::Saddle2 {
            continue;
        }
        let Some(seen) = observations.get(t).filter(|o| !o.is_empty()) else {
            continue;
        };
        let last = seen[seen.len() - 1];
        let birth_scale = scale_of(track.born).unwrap_or(0.0);
        let death_scale = if track.alive {
            None
        } else {
            scale_of(track.last_seen + 1)
        };
        let reject = |o: &Observation, reason| RejectedSaddle {
            vertex: o.vertex,
            position: o.position,
            born: track.born,
            birth_scale,
            death_scale,
            reason,
        };
        if track.persistence() + 1 < options.min_levels {
            rejected.push(reject(
                &last,
                RejectReason::ShortLived {
                    persistence: track.persistence(),
                },
            ));
            continue;
        }
        let fitted: Vec<(&Observation, Hessian)> = seen
            .iter()
            .filter_map(|o| o.hessian.filter(|h| h.is_two_saddle()).map(|h| (o, h)))
            .collect();
        if fitted.is_empty() {
            let reason = match seen.iter().rev().find_map(|o| o.hessian) {
                Some(h) => RejectReason::HessianSignature {
                    eigenvalues: h.eigenvalues,
                },
                None => RejectReason::NoFit,
            };
            rejected.push(reject(&last, reason));
            continue;
        }
        let cycle = fitted
            .iter()
            .find(|(o, _)| o.role.role == SaddleRole::CycleClosing);
        // The separating level of the largest bulge (the outer sphere's lobe counts as
        // infinitely fat), the earlier on ties.
        let widest = fitted
            .iter()
            .filter(|(o, _)| o.role.role == SaddleRole::Separating)
            .max_by(|a, b| {
                let bulge = |o: &Observation| o.role.bulge.unwrap_or(f64::INFINITY);
                bulge(a.0)
                    .total_cmp(&bulge(b.0))
                    .then(b.0.step.cmp(&a.0.step))
            });
        let widest_bulge = widest.map(|(o, _)| o.role.bulge.unwrap_or(f64::INFINITY));
        let (o, h, role) = match (cycle, widest) {
            // Cycle-closing: placed at its first fitted level, the least smoothed
            // (heat moves a window's saddle inwards as the scale grows).
            (Some(_), _) => (fitted[0].0, fitted[0].1, SaddleRole::CycleClosing),
            (None, None) => {
                rejected.push(reject(&last, RejectReason::LocalCycle));
                continue;
            }
            // Separating: placed at its level of the largest bulge. Below `min_bulge` it
            // is still a candidate, which the loop stage keeps if its loop opens out on
            // both sides (`loops::opening`); but not when its lobe is no fatter than the
            // neck at all.
            (None, Some(&(o, h))) => {
                let bulge = widest_bulge.unwrap_or(f64::INFINITY);
                if bulge <= 1.0 {
                    rejected.push(reject(o, RejectReason::LowBulge { bulge }));
                    continue;
                }
                (o, h, SaddleRole::Separating)
            }
        };
        let by_bulge = widest_bulge.is_some_and(|b| b >= options.min_bulge);
        // A neck by its shape: separating, or cycle-closing and separating with a
        // passing bulge at another level.
        let necked = widest
            .filter(|(w, _)| {
                role == SaddleRole::Separating
                    || w.role.bulge.is_some_and(|b| b >= options.min_bulge)
            })
            .map(|(w, _)| w);
        candidates.push(Saddle {
            vertex: o.vertex,
            position: newton_point(o.position, &h, o.radius),
            vertex_position: o.position,
            value: o.value,
            step: o.step,
            scale: scale_of(o.step).unwrap_or(0.0),
            born: track.born,
            persistence: track.persistence(),
            birth_scale,
            death_scale,
            role,
            bulge: necked.and_then(|w| w.role.bulge),
            by_bulge,
            lobe: necked.and_then(|w| w.lobe),
            essential: fitted.iter().any(|(o, _)| o.role.essential),
            hessian: h,
            normal: h.normal(),
        });
    }
    let (kept, duplicates) = merge_close(mesh, candidates, options.track_radius);
    rejected.extend(duplicates);
    (kept, rejected)
}

/// The paper's selection: the 2-saddle tracks alive at the last step.
fn select_at_last_step(
    mesh: &TetMesh,
    f: &[f64],
    tracks: &[Track],
    observations: &[Vec<Observation>],
    min_persistence: usize,
    (track_radius, min_bulge): (f64, f64),
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> (Vec<Saddle>, Vec<RejectedSaddle>) {
    let mut saddles = Vec::new();
    let mut rejected = Vec::new();
    for (t, track) in tracks
        .iter()
        .enumerate()
        .filter(|(_, t)| t.alive && t.kind == VertexType::Saddle2)
    {
        let birth_scale = scale_of(track.born).unwrap_or(0.0);
        let reject = |reason| RejectedSaddle {
            vertex: track.vertex,
            position: track.position,
            born: track.born,
            birth_scale,
            death_scale: None,
            reason,
        };
        if track.persistence() < min_persistence {
            rejected.push(reject(RejectReason::ShortLived {
                persistence: track.persistence(),
            }));
            continue;
        }
        let last = observations.get(t).and_then(|o| o.last());
        match hessian_at(mesh, f, track.vertex) {
            None => rejected.push(reject(RejectReason::NoFit)),
            Some(h) if !h.is_two_saddle() => {
                rejected.push(reject(RejectReason::HessianSignature {
                    eigenvalues: h.eigenvalues,
                }))
            }
            Some(h) => saddles.push(Saddle {
                vertex: track.vertex,
                position: newton_point(track.position, &h, track.radius),
                vertex_position: track.position,
                value: f[track.vertex as usize],
                step: track.last_seen,
                scale: scale_of(track.last_seen).unwrap_or(0.0),
                born: track.born,
                persistence: track.persistence(),
                birth_scale,
                death_scale: None,
                role: last.map_or(SaddleRole::CycleClosing, |o| o.role.role),
                bulge: last.and_then(|o| o.role.bulge),
                by_bulge: last
                    .and_then(|o| o.role.bulge)
                    .is_some_and(|b| b >= min_bulge),
                lobe: last.and_then(|o| o.lobe),
                essential: last.is_some_and(|o| o.role.essential),
                hessian: h,
                normal: h.normal(),
            }),
        }
    }
    let (kept, duplicates) = merge_close(mesh, saddles, track_radius);
    rejected.extend(duplicates);
    (kept, rejected)
}

/// Saddles within the matching radius of a more persistent one (then one with a
/// shorter Newton step; a neck by its cycle or bulge before one the loop stage still
/// judges) are duplicates of it. Returns the kept ones in that order, and the
/// duplicates.
fn merge_close(
    mesh: &TetMesh,
    mut saddles: Vec<Saddle>,
    track_radius: f64,
) -> (Vec<Saddle>, Vec<RejectedSaddle>) {
    let step = |s: &Saddle| norm(sub(s.position, s.vertex_position));
    // A saddle that is a neck already (by its cycle or its bulge) before one that the
    // loop stage still has to judge.
    let pending = |s: &Saddle| s.role == SaddleRole::Separating && !s.by_bulge;
    saddles.sort_by(|a, b| {
        pending(a)
            .cmp(&pending(b))
            .then(b.persistence.cmp(&a.persistence))
            .then(step(a).total_cmp(&step(b)))
            .then(a.vertex.cmp(&b.vertex))
            .then(a.step.cmp(&b.step))
    });
    let mut kept: Vec<Saddle> = Vec::new();
    let mut rejected = Vec::new();
    for s in saddles {
        let radius = track_radius * mean_edge_length(mesh, s.vertex as usize);
        match kept
            .iter()
            .find(|k| norm(sub(k.position, s.position)) <= radius)
        {
            Some(k) => rejected.push(s.rejected(RejectReason::Duplicate { of: k.vertex })),
            None => kept.push(s),
        }
    }
    (kept, rejected)
}

/// One bar per 2-saddle track that was observed, by birth scale.
fn barcode(
    tracks: &[Track],
    observations: &[Vec<Observation>],
    saddles: &[Saddle],
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> Vec<Bar> {
    let mut bars: Vec<Bar> = tracks
        .iter()
        .enumerate()
        .filter(|(t, track)| {
            track.kind == VertexType::Saddle2 && observations.get(*t).is_some_and(|o| !o.is_empty())
        })
        .map(|(t, track)| {
            let seen = &observations[t];
            let saddle = saddles.iter().position(|s| {
                s.born == track.born
                    && seen
                        .iter()
                        .any(|o| o.vertex == s.vertex && o.step == s.step)
            });
            Bar {
                birth_scale: scale_of(track.born).unwrap_or(0.0),
                death_scale: if track.alive {
                    None
                } else {
                    scale_of(track.last_seen + 1)
                },
                cycle_closing: seen.iter().any(|o| o.role.role == SaddleRole::CycleClosing),
                vertex: track.vertex,
                selected: saddle.is_some(),
                saddle,
            }
        })
        .collect();
    bars.sort_by(|a, b| {
        a.birth_scale
            .total_cmp(&b.birth_scale)
            .then(a.vertex.cmp(&b.vertex))
    });
    bars
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

/// The critical points of a classification, with their matching radii.
fn critical_points(
    mesh: &TetMesh,
    classification: &Classification,
    track_radius: f64,
) -> Vec<CriticalPoint> {
    classification
        .classes
        .iter()
        .enumerate()
        .filter(|(_, c)| !matches!(c.kind, VertexType::Regular | VertexType::Boundary))
        .map(|(v, c)| CriticalPoint {
            vertex: v as u32,
            kind: c.kind,
            position: mesh.positions[v],
            radius: track_radius * mean_edge_length(mesh, v),
        })
        .collect()
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
