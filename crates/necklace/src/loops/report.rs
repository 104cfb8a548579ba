//! What the loop stage returns: each kept [`NeckLoop`] with its measures and
//! tightening diagnostics, each seed that gave none as a [`DroppedLoop`] with its
//! [`DropReason`] (one line by `Display`), and the stage's timings. Plain data,
//! serialized as `loops.json` describes.

use serde::{Deserialize, Serialize};

use super::{Initial, Lasso, MembraneFailure, Role, Seed, SurfacePoint, TightenStatus};
use crate::mesh::{Side, SurfaceMesh};

/// A neck loop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NeckLoop {
    /// The side whose volume the saddle came from: inside a handle, outside a tunnel
    /// (serialized `"handle"` / `"tunnel"`).
    #[serde(
        serialize_with = "Side::serialize_as_neck",
        deserialize_with = "Side::deserialize_from_neck"
    )]
    pub kind: Side,
    /// Closed polyline on the surface (first point not repeated).
    pub points: Vec<[f64; 3]>,
    /// The same points as surface locations (edge + parameter, or vertex). From
    /// [`find_necks`](crate::pipeline::find_necks), vertex indices are the input mesh's.
    pub surface_points: Vec<SurfacePoint>,
    /// Length of the tightened loop.
    pub length: f64,
    /// Length of the initial loop it started from.
    pub initial_length: f64,
    /// Which construction gave the initial loop.
    pub initial: Initial,
    /// A disk the loop bounds (not in the JSON; written as `membranes.ply`): for a
    /// membrane-built loop, the fan from the saddle to the membrane's sources and the
    /// strip from them to the loop; for a plane-built one, the cone from the saddle;
    /// empty for a linked one (it bounds no disk on its side).
    #[serde(skip)]
    pub membrane: SurfaceMesh,
    /// Signed distance along the cutting normal from the saddle to the plane that gave
    /// that loop: 0 unless the plane through the saddle had no curve around it, or a
    /// parallel plane gave a shorter loop of a cycle's class ([`LoopOptions::slide_steps`](super::LoopOptions::slide_steps)).
    pub plane_offset: f64,
    /// Length-weighted centroid of the polyline.
    pub center: [f64; 3],
    /// Unit normal of the best-fit plane (least squares), oriented so that the loop
    /// turns counter-clockwise around it.
    pub normal: [f64; 3],
    /// `length / 2π`.
    pub radius: f64,
    /// The best-fit circle and how far the loop strays from it (module
    /// [`lasso`](super::lasso)): what a grasp planner lassoes. Always present in what
    /// this version writes; absent only in a `loops.json` written before it existed.
    #[serde(default)]
    pub lasso: Option<Lasso>,
    /// The saddle it came from (a linked loop, [`Initial::Linked`]: its centroid).
    pub saddle: [f64; 3],
    /// Index of that saddle among the seeds (a linked loop has none: one past them).
    pub seed: usize,
    /// The saddle's persistence.
    pub persistence: usize,
    /// Seeds whose loops were duplicates of this one.
    pub duplicates: Vec<usize>,
    /// Its saddle's role, when known.
    pub role: Option<Role>,
    /// Scale (length) at which its saddle appeared under smoothing.
    pub birth_scale: f64,
    /// Scale at which its saddle was gone (`None`: alive at the largest scale).
    pub death_scale: Option<f64>,
    /// Separating: how much fatter the lobe it cuts off is than the neck.
    pub bulge: Option<f64>,
    /// Its Z2 homology class on the surface: one character per basis cycle of a
    /// tree–cotree basis (`2g` of them), `1` where it crosses that cycle an odd number
    /// of times. All `0` exactly when it separates the surface.
    pub homology: String,
    /// Whether it separates the surface (its class is 0).
    pub separating: bool,
    /// Separating: the areas of the two sides it cuts its surface component into,
    /// smaller first.
    pub areas: Option<[f64; 2]>,
    /// How much the surface opens out on each side, smaller first (module [`opening`](super::opening)):
    /// how much longer than the loop the curve one loop radius away is (0 on a
    /// cylinder, positive on both sides of a neck). `None` where it cannot be measured.
    pub opening: Option<[f64; 2]>,
    /// Its length over the circumference of the inscribed ball at its saddle (the exact
    /// distance there): 1 round a round neck, larger round a flat one.
    pub flatness: Option<f64>,
    /// Why it was kept, in words.
    pub reason: String,
    /// How tightening ended, and its geodesic diagnostics.
    pub tightening: TighteningReport,
}

impl NeckLoop {
    /// [`NeckLoop::homology`] as bits packed in `u64` words (for `mesh::z2_rank`).
    pub fn class(&self) -> Vec<u64> {
        let mut bits = vec![0u64; self.homology.len().div_ceil(64)];
        for (g, c) in self.homology.chars().enumerate() {
            if c == '1' {
                bits[g / 64] |= 1 << (g % 64);
            }
        }
        bits
    }
}

/// Diagnostics of the tightening of a kept loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TighteningReport {
    /// Converged or stalled.
    pub status: TightenStatus,
    /// Strip-update rounds.
    pub rounds: usize,
    /// Vertex updates.
    pub updates: usize,
    /// Largest turn across an edge (radians; 0 for straight).
    pub max_edge_turn: f64,
    /// Smallest side angle at a vertex passed through (radians; ≥ π for a geodesic).
    pub min_vertex_angle: f64,
    /// No vertex visited twice, no crossing segments.
    pub simple: bool,
}

/// Why a seed gave no loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum DropReason {
    /// No closed cut curve contains the saddle's projection.
    NoLoopAroundSaddle {
        /// Closed curves the plane through the saddle had.
        closed_curves: usize,
        /// Open curves (the surface has a boundary there).
        open_curves: usize,
        /// Parallel planes also tried, on each side ([`LoopOptions::plane_offsets`](super::LoopOptions::plane_offsets)).
        offsets_tried: usize,
        /// Their spacing, in the surface's units.
        offset_step: f64,
    },
    /// A seed that needs a disk ([`Seed::disk_only`](super::Seed::disk_only)): the
    /// curves around it had other curves inside them, or bounded a region of the other
    /// side ([`region_side`](super::cut::region_side)), on every plane tried.
    NoDiskAroundSaddle {
        /// Planes whose curve around the saddle had another inside it, or bounded a
        /// region of the other side.
        planes: usize,
        /// Parallel planes tried on each side.
        offsets_tried: usize,
    },
    /// The loop kept shrinking: it slid off a cap and is not a neck.
    Collapsed {
        /// Length of the plane-cut loop.
        initial_length: f64,
        /// Length when it was stopped.
        length: f64,
    },
    /// Tightening did not settle within the round limit.
    NotConverged {
        /// Rounds done.
        rounds: usize,
        /// Length when it was stopped.
        length: f64,
    },
    /// No plane had a curve around the saddle, and its membrane gave no loop either.
    NoMembraneLoop {
        /// What failed in the membrane.
        failure: MembraneFailure,
        /// Closed curves the plane through the saddle had.
        closed_curves: usize,
        /// Open curves.
        open_curves: usize,
        /// Parallel planes also tried, on each side.
        offsets_tried: usize,
    },
    /// The cut curve did not form a strip of an oriented manifold surface.
    InvalidStrip,
    /// The tightened loop visits a vertex twice or crosses itself.
    NotSimple {
        /// Its length.
        length: f64,
    },
    /// Longer than `max_length` × the bounding-box diagonal.
    TooLong {
        /// Its length.
        length: f64,
        /// The limit.
        limit: f64,
    },
    /// A cycle-closing saddle whose loop separates the surface: the cycle it closed is
    /// filled again lower down (noise next to a neck), not a handle or tunnel.
    NotEssential {
        /// Its length.
        length: f64,
    },
    /// A cycle-closing saddle whose loop's homology class is a sum of the classes of
    /// shorter kept loops: the same handle or tunnel seen again.
    SameCycle {
        /// Index of the kept loop with the same class, when the class is one loop's;
        /// `None` when it is a sum of several.
        of: Option<usize>,
        /// Its own length.
        length: f64,
    },
    /// A neck by its bulge whose loop cuts off the same lobe as a kept loop with a
    /// larger bulge ratio, in the same homology class: the same neck seen at another
    /// scale.
    SameLobe {
        /// Index of the seed kept.
        of: usize,
        /// Its own length.
        length: f64,
    },
    /// A separating saddle whose lobe bulges less than `min_bulge`, and is no fatter
    /// than the neck at all (bulge ≤ 1), or whose loop does not open out by
    /// [`LoopOptions::min_opening`](super::LoopOptions::min_opening) on both sides (a bump on a tube), or goes round a
    /// flat part ([`LoopOptions::max_flatness`](super::LoopOptions::max_flatness)): not a neck.
    NotANeck {
        /// Its lobe's bulge ratio.
        bulge: Option<f64>,
        /// The smaller side's opening (`None`: not measurable).
        opening: Option<f64>,
        /// Its length over the circumference of the inscribed ball at its saddle.
        flatness: Option<f64>,
        /// Its length.
        length: f64,
    },
    /// Found on a simplified copy of the surface (`length` there), but neither its plane
    /// (or membrane) nor its best-fit plane gave it again on the surface itself: no
    /// curve around the point (`tightening` `None`), tightening ended so, or it gave
    /// another loop (`other`: its length).
    NotTransferred {
        /// Its length on the simplified surface.
        length: f64,
        /// The length of a loop found instead that is not the same neck.
        other: Option<f64>,
        /// How the last tightening on the surface itself ended, when there was a curve.
        tightening: Option<TightenStatus>,
    },
    /// A duplicate of a kept loop.
    Duplicate {
        /// Index of the kept loop in `loops`.
        of: usize,
        /// Its own length.
        length: f64,
    },
}

impl std::fmt::Display for DropReason {
    /// One line for a person, e.g. `collapsed: 0.8123 -> 0.0312`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let or_dash = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3}"));
        match *self {
            DropReason::NoLoopAroundSaddle {
                closed_curves,
                open_curves,
                offsets_tried,
                offset_step,
            } => write!(
                f,
                "no loop around the saddle ({closed_curves} closed and {open_curves} open curves; {offsets_tried} parallel planes tried each side, {offset_step:.3e} apart)"
            ),
            DropReason::NoDiskAroundSaddle {
                planes,
                offsets_tried,
            } => write!(
                f,
                "no plane's curve around it bounds a disk of its side ({planes} had curves inside them or on the other side; {offsets_tried} parallel planes tried each side)"
            ),
            DropReason::Collapsed {
                initial_length,
                length,
            } => write!(f, "collapsed while tightening: {initial_length:.5} -> {length:.5}"),
            DropReason::NotConverged { rounds, length } => {
                write!(f, "not converged after {rounds} rounds (length {length:.5})")
            }
            DropReason::NoMembraneLoop {
                failure,
                closed_curves,
                open_curves,
                offsets_tried,
            } => write!(
                f,
                "no plane closes around it ({closed_curves} closed, {open_curves} open curves, {offsets_tried} planes tried each side) and its membrane gave no loop ({failure})"
            ),
            DropReason::InvalidStrip => write!(f, "the cut is not a strip of an oriented manifold surface"),
            DropReason::NotSimple { length } => {
                write!(f, "the tightened loop is not simple (length {length:.5})")
            }
            DropReason::TooLong { length, limit } => {
                write!(f, "too long: {length:.5} > {limit:.5}")
            }
            DropReason::NotEssential { length } => write!(
                f,
                "cycle-closing but its loop separates the surface: not a handle or tunnel (length {length:.5})"
            ),
            DropReason::SameCycle { of: Some(of), length } => {
                write!(f, "the same cycle as loop {of} (length {length:.5})")
            }
            DropReason::SameCycle { of: None, length } => {
                write!(f, "its class is a sum of kept loops' (length {length:.5})")
            }
            DropReason::SameLobe { of, length } => {
                write!(f, "cuts off the same lobe as seed {of} (length {length:.5})")
            }
            DropReason::NotTransferred {
                length,
                other,
                tightening,
            } => write!(
                f,
                "found on the simplified surface (length {length:.5}) but not on the surface itself: {}",
                match (other, tightening) {
                    (Some(other), _) => format!("its planes gave another loop (length {other:.5})"),
                    (None, Some(t)) => format!("tightening there ended {t:?}"),
                    (None, None) => "no curve of its planes goes around it".to_string(),
                }
            ),
            DropReason::NotANeck {
                bulge,
                opening,
                flatness,
                length,
            } => write!(
                f,
                "not a neck: bulge {}, opening {}, flatness {} (length {length:.5})",
                or_dash(bulge),
                or_dash(opening),
                or_dash(flatness)
            ),
            DropReason::Duplicate { of, length } => {
                write!(f, "duplicate of loop {of} (length {length:.5})")
            }
        }
    }
}

/// A seed that gave no loop, and why.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DroppedLoop {
    /// Inside (handle) or outside (tunnel), serialized `"handle"` / `"tunnel"`.
    #[serde(
        serialize_with = "Side::serialize_as_neck",
        deserialize_with = "Side::deserialize_from_neck"
    )]
    pub kind: Side,
    /// Index of the seed.
    pub seed: usize,
    /// The saddle position.
    pub saddle: [f64; 3],
    /// The saddle's persistence.
    pub persistence: usize,
    /// Why.
    #[serde(flatten)]
    pub reason: DropReason,
}

impl DroppedLoop {
    pub(super) fn new(kind: Side, seeds: &[Seed], seed: usize, reason: DropReason) -> DroppedLoop {
        DroppedLoop {
            kind,
            seed,
            saddle: seeds[seed].position,
            persistence: seeds[seed].persistence,
            reason,
        }
    }
}

/// Wall-clock seconds of the loop stage.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct LoopTimings {
    /// Topology and vertex angles of the surface.
    pub preparation: f64,
    /// Plane cuts and tightening of all seeds.
    pub cut_and_tighten: f64,
    /// Length filter, duplicates, ordering.
    pub selection: f64,
}

/// Loops and dropped seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopResult {
    /// Kept loops, by persistence (descending), then length.
    pub loops: Vec<NeckLoop>,
    /// Every seed that gave no kept loop.
    pub dropped: Vec<DroppedLoop>,
    /// Stage timings.
    pub timings: LoopTimings,
}
