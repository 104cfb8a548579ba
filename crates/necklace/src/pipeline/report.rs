//! What a run reports: per side the volume mesh's summary, the Morse check, the saddles
//! and the loops' homology rank; in all, the loops, the drops with their reasons, the
//! notes on the input and the warnings, and stage timings. Plain data, built by
//! [`find_necks`](super::find_necks) and `necklace critical`; `output` writes it.

use serde::{Deserialize, Serialize};

use super::PreparedSurface;
use crate::loops::{DropReason, DroppedLoop, NeckLoop, SurfacePoint};
use crate::mesh::{Side, SurfaceMesh};
use crate::morse::{self, MorseResult, VertexType};
use crate::simplify::Stop;
use crate::tet::TetMesh;
use crate::volume::VolumeReport;

/// A critical point alive at the last level of a run, as the report keeps it (the
/// picture and `critical.ply` are drawn from these by `output`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackedPoint {
    /// Where it is at the last level.
    pub position: [f64; 3],
    /// Its type there.
    pub kind: VertexType,
    /// Whether it is one of the selected neck 2-saddles.
    pub selected: bool,
    /// Levels (steps) it lived.
    pub persistence: usize,
}

/// Every critical point alive at the last level of `result`, with its type, whether it
/// was selected and its persistence.
pub fn tracked_points(result: &MorseResult) -> Vec<TrackedPoint> {
    result
        .tracks
        .iter()
        .filter(|t| t.alive)
        .map(|track| TrackedPoint {
            position: track.position,
            kind: track.kind,
            selected: result.saddles.iter().any(|s| s.vertex == track.vertex),
            persistence: track.persistence(),
        })
        .collect()
}

/// Wall-clock seconds per stage of one side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimings {
    /// Volume mesh.
    pub volume_mesh: f64,
    /// Exact distance field on its vertices.
    pub distance: f64,
    /// Assembly and heat steps.
    pub smoothing: f64,
    /// Classification, tracking and the Hessian test.
    pub critical_points: f64,
    /// Plane cuts, tightening and selection, and the side's checks.
    pub loops: f64,
    /// The side's wall-clock time: the sum of the above (they are laps of one clock).
    pub total: f64,
}

impl StageTimings {
    pub(super) fn add(&mut self, other: &StageTimings) {
        self.volume_mesh += other.volume_mesh;
        self.distance += other.distance;
        self.smoothing += other.smoothing;
        self.critical_points += other.critical_points;
        self.loops += other.loops;
        self.total += other.total;
    }
}

/// The Morse check of one side: every classified step, and whether all held.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MorseCheck {
    /// Which side.
    pub side: Side,
    /// Whether `morse_sum == morse_expected` at every step.
    pub ok: bool,
    /// What the surface's genus predicts (see [`CriticalReport`](super::CriticalReport)).
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SideReport {
    /// Which side.
    pub side: Side,
    /// The volume mesh's summary.
    pub volume: VolumeReport,
    /// Interior vertices (unknowns of the heat system).
    pub unknowns: usize,
    /// The preconditioner the heat steps' solves ran with: `jacobi` or `multigrid`
    /// (what [`morse::Preconditioner::Auto`] chose for `unknowns`).
    pub preconditioner: morse::Preconditioner,
    /// Conjugate-gradient iterations over all heat steps.
    pub iterations: usize,
    /// The selected 2-saddles (the loops' seeds, in this order), then, when their loops
    /// missed classes of the genus, the Morse stage's completions that were cut for
    /// them (`normal_from` other than the Hessian).
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
    /// persistence ([`tracked_points`]); not in the JSON.
    #[serde(skip)]
    pub critical: Vec<TrackedPoint>,
    /// The volume mesh and the smoothed field on it, with
    /// [`NeckOptions::keep_volume`](super::NeckOptions::keep_volume); not in the JSON.
    #[serde(skip)]
    pub field: Option<VolumeField>,
}

/// The rank of one side's loop classes against the genus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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

/// What [`find_necks`](super::find_necks) found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// What was done to the input before meshing, one line each ([`prepare_input`](super::prepare_input)).
    pub notes: Vec<String>,
    /// The surface the method worked on: the input as [`prepare_input`](super::prepare_input) left it
    /// (unreferenced vertices removed, faces oriented); not in the JSON.
    #[serde(skip)]
    pub surface: SurfaceMesh,
    /// When the input was dense enough to be simplified: what simplification did, and
    /// whether the volume, field and saddle stages worked on the copy.
    #[serde(default)]
    pub simplified: Option<SimplifyReport>,
    /// What the caller should know, one line each: what is unusual about the input
    /// (open, crossing itself, ...), each side's volume warnings (a topology that
    /// differs from the surface's, a budget that bound, ...).
    pub warnings: Vec<String>,
}

/// Stage timings per side and in total.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct NeckTimings {
    /// The input step: checks, repairs, and the surface's distance structure.
    pub input: f64,
    /// The volume stage's survey of the surface, shared by both sides (thickness and
    /// gaps at every vertex, creases, crossings); the sides' `volume_mesh` is the
    /// meshing alone.
    #[serde(default)]
    pub survey: f64,
    /// Inside (handles), when run.
    pub handles: Option<StageTimings>,
    /// Outside (tunnels), when run.
    pub tunnels: Option<StageTimings>,
    /// Sum over the sides run.
    pub total: StageTimings,
    /// Simplifying a dense surface (`simplified`), 0 when it was not. It runs at the
    /// same time as the input step, so it is part of `input`'s wall clock.
    #[serde(default)]
    pub simplify: f64,
    /// The whole run's wall clock: `input` + `survey` + `total.total` when the sides
    /// run one after the other, less when they run at the same time.
    pub seconds: f64,
}

/// What simplifying a dense input did (`simplify`; [`NeckReport::simplified`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimplifyReport {
    /// Triangles of the input and of the simplified copy.
    pub triangles: [usize; 2],
    /// The largest error of a collapse made, in the surface's units (the root of the
    /// summed squared distances to the input planes it replaced).
    pub max_error: f64,
    /// What stopped the simplification: the target, the error bound, or no collapse
    /// left that keeps the topology.
    pub stop: Stop,
    /// Whether the copy was used (false: it crossed itself or lost a handle; the
    /// warnings say which, and every stage worked on the input).
    pub used: bool,
}

/// What one side of [`find_necks`](super::find_necks) found, before it joins the report.
pub(super) struct SideRun {
    pub report: SideReport,
    pub morse: MorseCheck,
    pub loops: Vec<NeckLoop>,
    pub dropped: Vec<DroppedLoop>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
    /// The Morse stage's cycles of this side ([`crate::morse::MorseResult::cycles`]):
    /// what the other side's linked search needs.
    pub cycles: Vec<Vec<[f64; 3]>>,
}

impl NeckReport {
    /// The report of a run on `prepared` before any side: its notes and warnings.
    pub(super) fn new(prepared: &PreparedSurface) -> Self {
        NeckReport {
            loops: Vec::new(),
            dropped: Vec::new(),
            morse: Vec::new(),
            timings: NeckTimings::default(),
            sides: Vec::new(),
            flipped: prepared.flipped,
            notes: prepared.notes.clone(),
            surface: prepared.mesh.clone(),
            warnings: prepared.warnings.clone(),
            simplified: None,
        }
    }

    /// Renumber the loops' surface points from the prepared surface's vertices to the
    /// input's (`input_vertex[v]` for prepared vertex `v`).
    pub(super) fn index_by_input(&mut self, input_vertex: &[u32]) {
        let map = |v: u32| input_vertex.get(v as usize).copied().unwrap_or(v);
        for l in &mut self.loops {
            for p in &mut l.surface_points {
                match p {
                    SurfacePoint::Edge { edge, .. } => *edge = edge.map(map),
                    SurfacePoint::Vertex { vertex } => *vertex = map(*vertex),
                }
            }
        }
    }

    /// Add a side: its loops follow those already listed (duplicate references
    /// shifted), its timings add to the total.
    pub(super) fn add_side(&mut self, side: SideRun) {
        let offset = self.loops.len();
        self.dropped.extend(side.dropped.into_iter().map(|mut d| {
            if let DropReason::Duplicate { of, .. } = &mut d.reason {
                *of += offset;
            }
            d
        }));
        self.loops.extend(side.loops);
        self.warnings.extend(side.warnings);
        self.notes.extend(side.notes);
        self.morse.push(side.morse);
        let timings = side.report.timings;
        self.timings.total.add(&timings);
        match side.report.side {
            Side::Inside => self.timings.handles = Some(timings),
            Side::Outside => self.timings.tunnels = Some(timings),
        }
        self.sides.push(side.report);
    }
}
