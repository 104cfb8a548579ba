//! What the Morse stage returns ([`MorseResult`]): per classified level its counts and
//! checks ([`StepSummary`]), the selected neck 2-saddles ([`Saddle`]: where, the cutting
//! normal, role, bulge, scales), every 2-saddle track not kept with its
//! [`RejectReason`], the barcode ([`Bar`]), the smoothed field and timings. Plain data.

use serde::{Deserialize, Serialize};

use super::multigrid::HierarchyInfo;
use super::{Hessian, MorseExpectation, SaddleRole, Schedule, StepEvents, StepReport, Track};

/// One classified step (a level of the scale space).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
    /// What the mesh's topology says the sum must be ([`expected_morse_sum`](super::expected_morse_sum)).
    pub morse_expected: i64,
    /// `morse_sum == morse_expected`.
    pub morse_ok: bool,
    /// Cycles the superlevel sweep closed that live for ever (their classes are
    /// independent; the rest are filled lower down: noise, or second copies). See
    /// [`roles`](super::roles).
    pub essential_cycles: usize,
    /// `essential_cycles` equals [`MorseResult::cycle_rank`]: every class of the swept
    /// complex is born at a saddle of this level.
    pub cycles_ok: bool,
    /// Births, deaths, moves and cancellations since the previous classified step.
    pub events: StepEvents,
    /// Critical points (of any type, counted above) where the field has drained below
    /// [`MorseOptions::drained_floor`](super::MorseOptions::drained_floor) of its largest
    /// value: not tracked, since there their type is the solver's noise.
    #[serde(default)]
    pub drained: usize,
}

/// A selected 2-saddle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
    /// [`roles`](super::roles)); false when every cycle it closed was noise or a second copy.
    pub essential: bool,
    /// The fitted Hessian (for a completion, of any signature).
    pub hessian: Hessian,
    /// Cutting-plane normal: the eigenvector of the positive eigenvalue, or for a
    /// completion one of its cutting directions (`normal_from`).
    pub normal: [f64; 3],
    /// Where `normal` comes from.
    #[serde(default)]
    pub normal_from: NormalSource,
}

/// Where a saddle's cutting normal comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalSource {
    /// The fitted Hessian's positive eigenvector: a selected saddle.
    #[default]
    Hessian,
    /// The axis between the two components of its upper link
    /// ([`Links::upper_axis`](super::Links::upper_axis)) that its cycle closes
    /// through: a completion's first cut.
    UpperLink,
    /// The plane through it that holds its cycle's centroid and best-fit normal (the
    /// cycle it closes, found in the superlevel set): a completion cut across the bar
    /// it lies in, round the hole its cycle goes round.
    Cycle,
    /// An eigenvector of its Hessian (`index` in ascending eigenvalue order): a
    /// completion cut in another direction.
    Eigenvector {
        /// Which eigenvector.
        index: usize,
    },
}

impl Saddle {
    /// This saddle, not selected after all, and why.
    pub(super) fn rejected(&self, reason: RejectReason) -> RejectedSaddle {
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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

/// Wall-clock seconds of each part of [`analyze`](super::analyze). A level is analysed
/// (classified, tracked, given roles) while the next level's heat step is solved, so
/// `smoothing`, `classification` and `selection` overlap: their sum exceeds the wall
/// clock of the whole.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
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

/// Everything [`analyze`](super::analyze) found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// With the multigrid preconditioner: its levels' sizes (`None` with Jacobi).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multigrid: Option<HierarchyInfo>,
    /// One summary per classified step.
    pub steps: Vec<StepSummary>,
    /// The selected 2-saddles, most persistent first, then by vertex.
    pub saddles: Vec<Saddle>,
    /// 2-saddle tracks that were not selected, and why (paper: those alive at `N`).
    pub rejected: Vec<RejectedSaddle>,
    /// Scale space: the vertices that close the essential cycles (the genus's classes)
    /// at each level, 2-saddles or degenerate saddles, followed over the levels within
    /// the matching radius; each at its first level, cut up to five ways in a row (its
    /// upper link's axis, its cycle's plane where it has one, its Hessian's three
    /// eigenvectors: `normal_from`), most persistent first. Not necks by their shape
    /// (walls a lattice cell or two thick give the quadratic fit no 2-saddle; a
    /// degenerate saddle is no track), but each closes a class the surface has: the
    /// pipeline cuts loops from them only when the selected saddles' loops miss some of
    /// the genus's classes. Empty on the paper's schedule.
    #[serde(default)]
    pub completions: Vec<Saddle>,
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
    /// its topology ([`cycles`](super::cycles)).
    pub cycle_rank: usize,
    /// The cycles closed at the first classified level, one per vertex that closes an
    /// essential cycle there (in vertex order), each a closed polyline through the
    /// volume mesh's vertices that stays in the side (the closer, then the fewest edges
    /// round through vertices above it): a basis of H₁ of the side (Z2) when there are
    /// `cycle_rank` of them. A cycle whose search gave up is left out. What the other
    /// side's loops are linked against ([`loops::linked`](crate::loops::linked)).
    #[serde(skip)]
    pub cycles: Vec<Vec<[f64; 3]>>,
    /// Seconds per part.
    pub timings: MorseTimings,
}

/// One 2-saddle track over scale.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
