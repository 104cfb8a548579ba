//! The smoothed distance field and its critical points: which 2-saddles mark necks
//! (paper sections 3 and 4.1–4.2).
//!
//! Input: a [`TetMesh`] whose vertex kinds say which vertices are on the surface and on
//! the outer sphere, and a field with one value per vertex (the pipeline passes the
//! exact distance to the surface: 0 on surface vertices, the true distance on the outer
//! sphere). Every non-interior vertex is a Dirichlet vertex and keeps its value.
//! [`analyze`] then runs the method:
//! 1. assemble the cotangent stiffness `L` and lumped mass `M` ([`laplacian`]);
//! 2. take `N` implicit heat steps `(M + τL) F' = M F` ([`smoothing`]), `τ` given in
//!    units where the longest side of the surface's bounding box is 1 (the paper rescales
//!    the mesh to a unit box). When every Dirichlet value is 0 (inside), the map is
//!    linear, so `F` is rescaled to `max |F| = 1` after each step (thin parts decay by
//!    up to 1e-47 over 50 steps); with non-zero boundary values (outside) it is not;
//! 3. from step `initial_steps` on, classify every interior vertex by its link
//!    ([`critical`]), check the Morse sum against the mesh's topology, and track the
//!    critical points from step to step ([`tracking`]);
//! 4. keep the 2-saddles alive at step `N` that survived `min_persistence` steps and
//!    whose fitted Hessian has signature (−, −, +) ([`hessian`]); the eigenvector of the
//!    positive eigenvalue is the cutting-plane normal, the fitted quadratic's stationary
//!    point the saddle's position. Saddles closer than the matching radius are one neck
//!    (keep the most persistent). Every 2-saddle alive at `N` that is not kept is
//!    listed with the reason.
//!
//! Conventions: `L` is positive semidefinite (`l = −Δf`), `M` gives a quarter of each
//! tet's volume to each of its vertices; lengths in the mesh's units; steps are counted
//! from 1 (step `k` = the field after `k` heat steps).

pub mod critical;
pub mod hessian;
pub mod laplacian;
pub mod smoothing;
pub mod tracking;

use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::geom::{add, dot, norm, scale, sub};
use crate::progress::{Progress, Silent};
use crate::tet::{TetMesh, VertexKind};

pub use critical::{
    classify, expected_morse_sum, Classification, Links, MorseExpectation, VertexClass, VertexType,
};
pub use hessian::{hessian_at, Hessian};
pub use laplacian::{cotangent_stiffness, lumped_mass, SparseMatrix};
pub use smoothing::{implicit_step, HeatSolver, SolverOptions, StepReport};
pub use tracking::{CriticalPoint, StepEvents, Track, Tracker};

/// Options of [`analyze`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MorseOptions {
    /// Heat time step `τ` in units where the surface's bounding box has longest side 1
    /// (default 0.01, the paper's `λh`).
    pub tau: f64,
    /// Heat steps before the first classification (default 10, the paper's initial
    /// smoothing).
    pub initial_steps: usize,
    /// Last step `N` (default 20, the paper's "sm = 20").
    pub steps: usize,
    /// Steps a 2-saddle must have survived at step `N` to be selected (default 5;
    /// capped at `N − initial_steps`, so a run with `N = initial_steps` keeps every
    /// 2-saddle that passes the Hessian test).
    pub min_persistence: usize,
    /// Matching radius of the tracking, in multiples of the mean edge length at the
    /// critical point (default 2).
    pub track_radius: f64,
    /// The linear solver's stopping rule.
    pub solver: SolverOptions,
}

impl Default for MorseOptions {
    fn default() -> Self {
        MorseOptions {
            tau: 0.01,
            initial_steps: 10,
            steps: 20,
            min_persistence: 5,
            track_radius: 2.0,
            solver: SolverOptions::default(),
        }
    }
}

/// One classified step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepSummary {
    /// Heat steps taken.
    pub step: usize,
    /// Minima (none expected: the boundary comes first).
    pub minima: usize,
    /// Maxima.
    pub maxima: usize,
    /// 1-saddles.
    pub saddles1: usize,
    /// 2-saddles.
    pub saddles2: usize,
    /// Degenerate (monkey) saddles.
    pub monkeys: usize,
    /// Σ over interior vertices of `1 − χ(lower link)`.
    pub morse_sum: i64,
    /// What the mesh's topology says the sum must be ([`expected_morse_sum`]).
    pub morse_expected: i64,
    /// `morse_sum == morse_expected`.
    pub morse_ok: bool,
    /// Births, deaths, moves and cancellations since the previous classified step.
    pub events: StepEvents,
}

/// A selected 2-saddle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Saddle {
    /// Its vertex at step `N`.
    pub vertex: u32,
    /// The stationary point of the fitted quadratic (one Newton step from the vertex),
    /// or the vertex position when that step is longer than the matching radius.
    pub position: [f64; 3],
    /// The vertex position.
    pub vertex_position: [f64; 3],
    /// The smoothed field there at step `N`.
    pub value: f64,
    /// Step it was first seen.
    pub born: usize,
    /// Steps survived up to `N`.
    pub persistence: usize,
    /// The fitted Hessian.
    pub hessian: Hessian,
    /// Cutting-plane normal: the eigenvector of the positive eigenvalue.
    pub normal: [f64; 3],
}

/// Why a 2-saddle alive at step `N` was not selected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum RejectReason {
    /// It survived fewer than `min_persistence` steps.
    ShortLived {
        /// Steps survived.
        persistence: usize,
    },
    /// The fitted Hessian's signature is not (−, −, +).
    HessianSignature {
        /// Its eigenvalues, ascending.
        eigenvalues: [f64; 3],
    },
    /// No quadratic could be fitted (too few neighbours).
    NoFit,
    /// Another selected 2-saddle lies within the matching radius: one neck seen at
    /// several vertices (a lattice splits a smooth saddle into a cluster of discrete
    /// critical points). The one kept is the more persistent, then the one whose
    /// Newton step is shorter.
    Duplicate {
        /// Vertex of the 2-saddle kept.
        of: u32,
    },
}

/// A 2-saddle alive at step `N` that was not selected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RejectedSaddle {
    /// Its vertex at step `N`.
    pub vertex: u32,
    /// Its position.
    pub position: [f64; 3],
    /// Step first seen.
    pub born: usize,
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
    /// Tracking and Hessian fits.
    pub selection: f64,
}

/// Everything [`analyze`] found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MorseResult {
    /// Unknowns of the heat system (interior vertices).
    pub unknowns: usize,
    /// `τ` in mesh units (length²).
    pub tau: f64,
    /// Whether the field was rescaled after each step (all boundary values 0).
    pub rescaled: bool,
    /// The solver's report for every heat step (`solver[k]` is step `k + 1`).
    pub solver: Vec<StepReport>,
    /// One summary per classified step, `initial_steps..=N`.
    pub steps: Vec<StepSummary>,
    /// The selected 2-saddles, most persistent first, then by vertex.
    pub saddles: Vec<Saddle>,
    /// 2-saddles alive at step `N` that were not selected, and why.
    pub rejected: Vec<RejectedSaddle>,
    /// Every track of the run (those `alive` are the critical points at step `N`).
    #[serde(skip)]
    pub tracks: Vec<Track>,
    /// The field at step `N` (rescaled when `rescaled`).
    #[serde(skip)]
    pub field: Vec<f64>,
    /// The mesh's Morse sum and the Euler characteristics it comes from.
    pub morse_expected: MorseExpectation,
    /// Seconds per part.
    pub timings: MorseTimings,
}

impl MorseResult {
    /// The classified steps whose Morse sum is not what the topology says.
    pub fn morse_failures(&self) -> impl Iterator<Item = &StepSummary> {
        self.steps.iter().filter(|s| !s.morse_ok)
    }
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

    // 1. Operators, the reduced heat system and the links (assembled once).
    let start = Instant::now();
    let stiffness = cotangent_stiffness(mesh);
    let mass = lumped_mass(mesh);
    let fixed: Vec<bool> = (0..mesh.num_vertices())
        .map(|v| mesh.kinds[v] != VertexKind::Interior || mass[v] <= 0.0)
        .collect();
    let rescaled = (0..mesh.num_vertices()).all(|v| !fixed[v] || field[v] == 0.0);
    let unit = longest_side(mesh);
    let tau = options.tau * unit * unit;
    let mut solver = HeatSolver::new(&stiffness, &mass, &fixed, field, tau, options.solver);
    let links = Links::new(mesh)?;
    let morse_expected = expected_morse_sum(mesh);
    let mut timings = MorseTimings {
        assembly: start.elapsed().as_secs_f64(),
        ..MorseTimings::default()
    };

    // 2–3. Heat steps; from `initial_steps` on, classify and track.
    let mut f = field.to_vec();
    let mut reports = Vec::with_capacity(options.steps);
    let mut steps = Vec::new();
    let mut tracker = Tracker::new();
    progress.start("smoothing and critical points", options.steps as u64);
    for step in 1..=options.steps {
        progress.advance(1);
        let start = Instant::now();
        let (next, report) = solver.step(&f);
        f = next;
        if rescaled {
            rescale(&mut f);
        }
        reports.push(report);
        timings.smoothing += start.elapsed().as_secs_f64();
        if step < options.initial_steps {
            continue;
        }
        let start = Instant::now();
        let classification = links.classify(&f);
        timings.classification += start.elapsed().as_secs_f64();
        let start = Instant::now();
        let critical = critical_points(mesh, &classification, options.track_radius);
        let events = tracker.advance(step, &critical);
        steps.push(summarize(step, &classification, morse_expected.sum, events));
        timings.selection += start.elapsed().as_secs_f64();
    }

    progress.finish();

    // 4. Select the persistent 2-saddles with the right Hessian.
    let start = Instant::now();
    let min_persistence = options
        .min_persistence
        .min(options.steps - options.initial_steps);
    let (saddles, rejected) = select(
        mesh,
        &f,
        &tracker.tracks,
        min_persistence,
        options.track_radius,
    );
    timings.selection += start.elapsed().as_secs_f64();

    Ok(MorseResult {
        unknowns: solver.unknowns(),
        tau,
        rescaled,
        solver: reports,
        steps,
        saddles,
        rejected,
        tracks: tracker.tracks,
        field: f,
        morse_expected,
        timings,
    })
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
    if !(options.tau > 0.0 && options.tau.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "tau = {} must be positive",
            options.tau
        )));
    }
    if options.initial_steps == 0 || options.steps < options.initial_steps {
        return Err(Error::invalid_argument(format!(
            "steps = {} must be at least initial_steps = {} (and that at least 1)",
            options.steps, options.initial_steps
        )));
    }
    if !(options.track_radius > 0.0 && options.track_radius.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "track_radius = {} must be positive",
            options.track_radius
        )));
    }
    Ok(())
}

/// Longest side of the bounding box of the surface vertices (of all vertices when
/// there are none); 1 for an empty or flat-to-a-point mesh.
fn longest_side(mesh: &TetMesh) -> f64 {
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
    let side = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if side > 0.0 && side.is_finite() {
        side
    } else {
        1.0
    }
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
    c: &Classification,
    morse_expected: i64,
    events: StepEvents,
) -> StepSummary {
    StepSummary {
        step,
        minima: c.count(VertexType::Minimum),
        maxima: c.count(VertexType::Maximum),
        saddles1: c.count(VertexType::Saddle1),
        saddles2: c.count(VertexType::Saddle2),
        monkeys: c.count(VertexType::Degenerate),
        morse_sum: c.morse_sum,
        morse_expected,
        morse_ok: c.morse_sum == morse_expected,
        events,
    }
}

/// Split the 2-saddle tracks alive at the end into selected and rejected.
fn select(
    mesh: &TetMesh,
    f: &[f64],
    tracks: &[Track],
    min_persistence: usize,
    track_radius: f64,
) -> (Vec<Saddle>, Vec<RejectedSaddle>) {
    let mut saddles = Vec::new();
    let mut rejected = Vec::new();
    for track in tracks
        .iter()
        .filter(|t| t.alive && t.kind == VertexType::Saddle2)
    {
        let reject = |reason| RejectedSaddle {
            vertex: track.vertex,
            position: track.position,
            born: track.born,
            reason,
        };
        if track.persistence() < min_persistence {
            rejected.push(reject(RejectReason::ShortLived {
                persistence: track.persistence(),
            }));
            continue;
        }
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
                born: track.born,
                persistence: track.persistence(),
                hessian: h,
                normal: h.normal(),
            }),
        }
    }
    // Most persistent first, then the shortest Newton step: the order in which
    // duplicates give way.
    let step = |s: &Saddle| norm(sub(s.position, s.vertex_position));
    saddles.sort_by(|a, b| {
        b.persistence
            .cmp(&a.persistence)
            .then(step(a).total_cmp(&step(b)))
            .then(a.vertex.cmp(&b.vertex))
    });
    let mut kept: Vec<Saddle> = Vec::new();
    for s in saddles {
        let radius = track_radius * mean_edge_length(mesh, s.vertex as usize);
        match kept
            .iter()
            .find(|k| norm(sub(k.position, s.position)) <= radius)
        {
            Some(k) => rejected.push(RejectedSaddle {
                vertex: s.vertex,
                position: s.position,
                born: s.born,
                reason: RejectReason::Duplicate { of: k.vertex },
            }),
            None => kept.push(s),
        }
    }
    (kept, rejected)
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
