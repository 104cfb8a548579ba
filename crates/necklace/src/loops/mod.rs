//! Neck loops on the surface (sec. 4.3 of the paper): from each selected 2-saddle, the
//! loop that lassos its neck.
//!
//! For every seed (a saddle position and its cutting-plane normal):
//! 1. [`cut`]: intersect the plane through the saddle with the input surface and keep the
//!    closed curve around the saddle (the smallest in-plane polygon containing it).
//!    Optionally ("lower link variation") try a few normals tilted around the given one
//!    and keep the shortest such curve. Where no curve of the plane through the saddle
//!    goes around it (a window of a curved lattice: the saddle sits below the wires' rim,
//!    and the plane passes under them), parallel planes up to
//!    [`LoopOptions::plane_offsets`] steps of [`LoopOptions::offset_step`] × diagonal
//!    away are tried, nearest first (+ before −), for a curve around the saddle's axis.
//!    Before those parallel planes, [`membrane`] builds the boundary of the saddle's
//!    membrane (its descending disk for the exact distance) and keeps it when it goes
//!    once around the saddle's axis ([`LoopOptions::membranes`]); each loop says which
//!    construction gave it (`initial`).
//! 2. [`tighten`](mod@tighten): shorten it into a closed geodesic, not tied to mesh edges. A loop that
//!    collapses (slides off a cap) or does not settle is dropped with its reason.
//! 3. Selection: drop loops longer than `max_length` × the bounding-box diagonal; keep
//!    one loop per neck (cycle-closing loops one per independent Z2 class, shortest
//!    first; necks by shape one per lobe and class, where a separating saddle whose lobe
//!    bulges less than the Morse stage's `min_bulge` is a neck only if its loop opens
//!    out on both sides by [`LoopOptions::min_opening`] ([`opening`]) round a roundish
//!    neck ([`LoopOptions::max_flatness`])); move each kept cycle-closing loop
//!    to the narrowest place of its handle or tunnel, whichever of its saddles the
//!    lattice gave: parallel planes up to [`LoopOptions::slide_steps`] ×
//!    [`LoopOptions::slide_step`] × diagonal away are cut and tightened, and the
//!    shortest loop of its class wins; merge duplicates (centres
//!    within `merge_distance` × diagonal and lengths within `merge_length`, or the same
//!    class and each within `merge_overlap` × radius of the other), keeping the
//!    highest persistence, then the shortest; order by persistence (descending), then
//!    length.
//!
//! Units are those of the surface. Every seed ends either as a loop or in `dropped` with
//! a reason. Seeds are processed in parallel; the result does not depend on the thread
//! count. Entry point: [`find_loops`].

pub mod classes;
pub mod cut;
pub mod membrane;
pub mod opening;
pub mod tighten;

use std::sync::OnceLock;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::distance::SurfaceDistance;
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, closest_on_segment, cross, dot, norm, scale, sub};
use crate::mesh::{HomologyBasis, Side, SurfaceMesh, Topology, Z2Basis};
use crate::progress::{Progress, Silent};
use cut::{closed_length, loop_around, plane_basis, plane_cut, Plane};
use membrane::membrane_loop;
pub use membrane::{MembraneFailure, MembraneOptions};
use opening::Openings;
use tighten::{tighten, SurfaceGeometry};
pub use tighten::{SurfacePoint, TightenOptions, TightenStatus, Tightened};

/// What the saddle of a seed does to the volume (see `morse::roles`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// It joins two lobes: its loop cuts off a part.
    Separating,
    /// It closes a cycle: its loop goes around a handle (inside) or tunnel (outside).
    CycleClosing,
}

/// Where a loop starts: a selected 2-saddle.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Seed {
    /// Saddle position (a point of the cutting plane).
    pub position: [f64; 3],
    /// Cutting-plane normal (need not be unit length, must be non-zero).
    pub normal: [f64; 3],
    /// Steps (levels) the saddle survived under smoothing.
    pub persistence: usize,
    /// Its role, when known. With [`LoopOptions::homology_selection`], cycle-closing
    /// seeds are kept one per independent homology class.
    pub role: Option<Role>,
    /// Scale (length) at which the saddle appeared, and the first at which it was gone
    /// (`None`: alive at the largest); 0 and `None` when unknown.
    pub scales: (f64, Option<f64>),
    /// How much fatter the lobe it cuts off is than the neck, when it was separating
    /// with a bulge that made it a neck (also for a cycle-closing saddle that was such
    /// a neck at other levels).
    pub bulge: Option<f64>,
    /// With `bulge`: an identifier of the lobe it cuts off (the maximum's track).
    pub lobe: Option<usize>,
    /// A separating saddle whose lobe bulges less than the Morse stage's `min_bulge`: a
    /// neck only if its loop opens out on both sides by [`LoopOptions::min_opening`]
    /// (module [`opening`]). Default false.
    pub needs_opening: bool,
}

/// Options of [`find_loops`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LoopOptions {
    /// Tightening options.
    pub tighten: TightenOptions,
    /// Extra cutting normals tried around the given one ("lower link variation"); the
    /// shortest initial loop wins. Default 0 (the Hessian normal only).
    pub normal_variations: usize,
    /// Tilt of those extra normals, radians. Default 0.2 (about 11°).
    pub variation_angle: f64,
    /// Loops longer than this × the bounding-box diagonal are dropped. Default π: a
    /// great circle of the ball whose diameter is the diagonal. (1.5 dropped the tunnel
    /// of a thin ring around a wide hole: the bent ring's is 1.8 diagonals long.)
    pub max_length: f64,
    /// Two loops whose centres are closer than this × the diagonal ... Default 0.01.
    pub merge_distance: f64,
    /// ... and whose lengths differ by less than this fraction are duplicates. Default 0.02.
    pub merge_length: f64,
    /// Two loops of the same class each within this × the smaller loop radius of the
    /// other everywhere are duplicates too (one neck reached from two saddles, e.g. on
    /// a short bar). Default 0.5.
    pub merge_overlap: f64,
    /// Keep one cycle-closing loop per independent Z2 homology class of the surface,
    /// the shortest first, and drop cycle-closing loops that separate it (their cycle
    /// is filled again lower down: noise). Default true.
    pub homology_selection: bool,
    /// When no curve of the plane through the saddle goes around it: how many parallel
    /// planes to try on each side. Default 16.
    pub plane_offsets: usize,
    /// Spacing of those planes, × the bounding-box diagonal. Default 0.00125 (so up to
    /// 2 % of the diagonal away). Fine, because the band of planes that go around a
    /// window with a curved rim can be thin: on the wire sphere, steps of 0.5 % jumped
    /// over it for 48 of the 96 windows.
    pub offset_step: f64,
    /// A kept cycle-closing loop is also cut and tightened from parallel planes up to
    /// this many `slide_step`s away on each side, and the shortest loop of its class
    /// replaces it: the narrowest place of its handle or tunnel, whichever saddle of the
    /// cycle the lattice gave. Default 8.
    pub slide_steps: usize,
    /// Spacing of those planes, × the bounding-box diagonal. Default 0.005 (so up to
    /// 4 % of the diagonal each way).
    pub slide_step: f64,
    /// When the saddle's membrane gives the initial loop. Default
    /// [`MembraneUse::WherePlanesFail`].
    pub membranes: MembraneUse,
    /// How membranes are built.
    pub membrane: MembraneOptions,
    /// Smallest opening on each side (module [`opening`]) of the loop of a seed that
    /// [`Seed::needs_opening`]: how much longer the curve one loop radius away is than
    /// the loop. Default 0.1: a cylinder gives 0, tube noise up to 0.05 on the shared
    /// models and shapes, the fertility's waist 0.16 and baby's neck 0.34.
    pub min_opening: f64,
    /// How far out the opening is measured, × the loop's radius `length / 2π`.
    /// Default 1.
    pub opening_reach: f64,
    /// A seed that [`Seed::needs_opening`] must also have a roundish neck: its loop no
    /// longer than this × the circumference of the inscribed ball at the saddle. Default
    /// 3: necks measure 1.0–2.3 on the shared models, while loops round a plate (the
    /// skull's cheek bones 7.6–16, the elephant's ear 6.3) open out on both sides too.
    pub max_flatness: f64,
}

/// When the saddle's membrane (module [`membrane`]) gives the initial loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MembraneUse {
    /// Never: planes only (the paper).
    Never,
    /// Where the plane through the saddle has no curve around it; parallel planes are
    /// tried after the membrane.
    WherePlanesFail,
    /// Always, instead of planes (to compare the two constructions).
    Always,
}

/// Which construction gave a loop's initial curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Initial {
    /// A plane cut (through the saddle, or parallel to it: see `plane_offset`).
    Plane,
    /// The boundary of the saddle's membrane.
    Membrane,
}

impl Default for LoopOptions {
    fn default() -> Self {
        LoopOptions {
            tighten: TightenOptions::default(),
            normal_variations: 0,
            variation_angle: 0.2,
            max_length: std::f64::consts::PI,
            merge_distance: 0.01,
            merge_length: 0.02,
            merge_overlap: 0.5,
            homology_selection: true,
            plane_offsets: 16,
            offset_step: 0.00125,
            slide_steps: 8,
            slide_step: 0.005,
            membranes: MembraneUse::WherePlanesFail,
            membrane: MembraneOptions::default(),
            min_opening: 0.1,
            opening_reach: 1.0,
            max_flatness: 3.0,
        }
    }
}

/// A neck loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NeckLoop {
    /// The side whose volume the saddle came from: inside a handle, outside a tunnel
    /// (serialized `"handle"` / `"tunnel"`).
    #[serde(serialize_with = "Side::serialize_as_neck")]
    pub kind: Side,
    /// Closed polyline on the surface (first point not repeated).
    pub points: Vec<[f64; 3]>,
    /// The same points as surface locations (edge + parameter, or vertex).
    pub surface_points: Vec<SurfacePoint>,
    /// Length of the tightened loop.
    pub length: f64,
    /// Length of the initial loop it started from.
    pub initial_length: f64,
    /// Which construction gave the initial loop.
    pub initial: Initial,
    /// A disk the loop bounds (not in the JSON; written as `membranes.ply`): for a
    /// membrane-built loop, the fan from the saddle to the membrane's sources and the
    /// strip from them to the loop; for a plane-built one, the cone from the saddle.
    #[serde(skip)]
    pub membrane: SurfaceMesh,
    /// Signed distance along the cutting normal from the saddle to the plane that gave
    /// that loop: 0 unless the plane through the saddle had no curve around it, or a
    /// parallel plane gave a shorter loop of a cycle's class ([`LoopOptions::slide_steps`]).
    pub plane_offset: f64,
    /// Length-weighted centroid of the polyline.
    pub center: [f64; 3],
    /// Unit normal of the best-fit plane (least squares), oriented so that the loop
    /// turns counter-clockwise around it.
    pub normal: [f64; 3],
    /// `length / 2π`.
    pub radius: f64,
    /// The saddle it came from.
    pub saddle: [f64; 3],
    /// Index of that saddle among the seeds.
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
    /// How much the surface opens out on each side, smaller first (module [`opening`]):
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum DropReason {
    /// No closed cut curve contains the saddle's projection.
    NoLoopAroundSaddle {
        /// Closed curves the plane through the saddle had.
        closed_curves: usize,
        /// Open curves (the surface has a boundary there).
        open_curves: usize,
        /// Parallel planes also tried, on each side ([`LoopOptions::plane_offsets`]).
        offsets_tried: usize,
        /// Their spacing, in the surface's units.
        offset_step: f64,
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
    /// [`LoopOptions::min_opening`] on both sides (a bump on a tube), or goes round a
    /// flat part ([`LoopOptions::max_flatness`]): not a neck.
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DroppedLoop {
    /// Inside (handle) or outside (tunnel), serialized `"handle"` / `"tunnel"`.
    #[serde(serialize_with = "Side::serialize_as_neck")]
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
    fn new(kind: Side, seeds: &[Seed], seed: usize, reason: DropReason) -> DroppedLoop {
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
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LoopTimings {
    /// Topology and vertex angles of the surface.
    pub preparation: f64,
    /// Plane cuts and tightening of all seeds.
    pub cut_and_tighten: f64,
    /// Length filter, duplicates, ordering.
    pub selection: f64,
}

/// Loops and dropped seeds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopResult {
    /// Kept loops, by persistence (descending), then length.
    pub loops: Vec<NeckLoop>,
    /// Every seed that gave no kept loop.
    pub dropped: Vec<DroppedLoop>,
    /// Stage timings.
    pub timings: LoopTimings,
}

/// Loops of `kind` around the necks marked by `seeds` on `surface` (the input surface,
/// not the volume mesh's boundary).
pub fn find_loops(
    surface: &SurfaceMesh,
    seeds: &[Seed],
    kind: Side,
    options: &LoopOptions,
) -> Result<LoopResult> {
    find_loops_with_progress(surface, None, seeds, kind, options, &Silent)
}

/// [`find_loops`], reporting each seed cut and tightened to `progress`. `distance` is
/// the surface's distance structure when the caller has one (the run's); without it,
/// one is built when a seed first needs closest points.
pub fn find_loops_with_progress(
    surface: &SurfaceMesh,
    distance: Option<&SurfaceDistance>,
    seeds: &[Seed],
    kind: Side,
    options: &LoopOptions,
    progress: &dyn Progress,
) -> Result<LoopResult> {
    check_inputs(surface, seeds, options)?;

    let start = Instant::now();
    let topology = Topology::new(surface);
    let geometry = SurfaceGeometry::new(surface, &topology);
    let basis = HomologyBasis::new(surface, &topology);
    let openings = Openings::new(surface, &topology, &geometry);
    let measures = Measures {
        surface,
        topology: &topology,
        basis: &basis,
        openings: &openings,
        reach: options.opening_reach,
    };
    let distance = LazyDistance {
        surface,
        given: distance,
        built: OnceLock::new(),
    };
    let preparation = start.elapsed().as_secs_f64();

    let start = Instant::now();
    progress.start("tightening", seeds.len() as u64);
    let outcomes: Vec<std::result::Result<Candidate, DropReason>> = seeds
        .par_iter()
        .map(|seed| {
            let outcome = loop_from_seed(surface, &topology, &geometry, &distance, seed, options)
                .map(|s| {
                    let mut c = measures.candidate(s.tightened, s.offset, s.initial);
                    c.sources = s.sources;
                    // The inscribed radius at the saddle: the exact distance there.
                    let inscribed = distance.get().distance(seed.position);
                    c.flatness = (inscribed > 0.0)
                        .then(|| c.tightened.length / (2.0 * std::f64::consts::PI * inscribed));
                    c
                });
            progress.advance(1);
            outcome
        })
        .collect();
    progress.finish();
    let cut_and_tighten = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let limit = options.max_length * surface.bbox_diagonal();
    let mut dropped = Vec::new();
    let mut candidates = Vec::new();
    for (i, outcome) in outcomes.into_iter().enumerate() {
        let drop = |reason| DroppedLoop::new(kind, seeds, i, reason);
        match outcome {
            Err(reason) => dropped.push(drop(reason)),
            Ok(c) if c.tightened.length > limit => dropped.push(drop(DropReason::TooLong {
                length: c.tightened.length,
                limit,
            })),
            Ok(c) => candidates.push((i, c)),
        }
    }
    let candidates = if options.homology_selection {
        one_per_neck(seeds, kind, candidates, options, &mut dropped)
    } else {
        candidates
    };
    let candidates: Vec<(usize, Candidate)> = candidates
        .into_par_iter()
        .map(|(i, c)| {
            let c = if seeds[i].role == Some(Role::CycleClosing) {
                narrowest(
                    surface, &topology, &geometry, &measures, &seeds[i], c, options,
                )
            } else {
                c
            };
            (i, c)
        })
        .collect();
    let loops = select(
        surface,
        seeds,
        kind,
        candidates,
        options,
        basis.len(),
        &mut dropped,
    );
    dropped.sort_by_key(|d| d.seed);
    let selection = start.elapsed().as_secs_f64();

    Ok(LoopResult {
        loops,
        dropped,
        timings: LoopTimings {
            preparation,
            cut_and_tighten,
            selection,
        },
    })
}

fn check_inputs(surface: &SurfaceMesh, seeds: &[Seed], options: &LoopOptions) -> Result<()> {
    let bad = |what: String| Err(Error::new(ErrorKind::InvalidArgument, what));
    if surface.triangles.is_empty() {
        return bad("the surface has no triangles".into());
    }
    for (i, s) in seeds.iter().enumerate() {
        let finite = s.position.iter().chain(&s.normal).all(|x| x.is_finite());
        if !finite || norm(s.normal) == 0.0 {
            return bad(format!(
                "seed {i} has a non-finite position or a zero normal"
            ));
        }
    }
    let t = &options.tighten;
    let positive = [
        options.max_length,
        options.merge_length,
        options.opening_reach,
        options.max_flatness,
        options.offset_step,
        options.slide_step,
        t.min_length_ratio,
        t.angle_tolerance,
    ];
    let non_negative = [
        options.merge_distance,
        options.merge_overlap,
        options.variation_angle,
        t.rel_tolerance,
    ];
    if positive.iter().any(|x| !(x.is_finite() && *x > 0.0))
        || non_negative.iter().any(|x| !(x.is_finite() && *x >= 0.0))
        || !options.min_opening.is_finite()
        || t.max_rounds == 0
    {
        return bad("loop options must be finite and positive (max_rounds at least 1)".into());
    }
    Ok(())
}

/// A tightened loop and how it started.
struct Start {
    tightened: Tightened,
    /// The cutting plane's offset from the saddle.
    offset: f64,
    /// Plane or membrane.
    initial: Initial,
    /// A membrane's sources; empty for a plane.
    sources: Vec<[f64; 3]>,
}

/// A tightened loop before selection.
struct Candidate {
    tightened: Tightened,
    /// The cutting plane's offset from the saddle.
    offset: f64,
    /// Plane or membrane.
    initial: Initial,
    /// A membrane's sources (see [`membrane::MembraneLoop::sources`]); empty for a plane.
    sources: Vec<[f64; 3]>,
    /// Its Z2 homology class.
    class: Vec<u64>,
    /// When it separates the surface: the areas of its sides.
    areas: Option<[f64; 2]>,
    /// The opening of its two sides, smaller first.
    opening: Option<[f64; 2]>,
    /// Its length over the circumference of the inscribed ball at its saddle.
    flatness: Option<f64>,
}

/// One loop per neck. Cycle-closing loops: one per independent homology class, shortest
/// first; those that separate the surface or repeat a class are dropped, unless the
/// saddle is also a neck by its bulge (a stick of a ball-and-stick model closes a
/// cycle at one scale and cuts off a ball at another). Necks by bulge: one per lobe
/// and homology class, the largest bulge first (a separating saddle's loop may go
/// around a cycle too, e.g. a stick between two balls on a cage).
fn one_per_neck(
    seeds: &[Seed],
    kind: Side,
    candidates: Vec<(usize, Candidate)>,
    options: &LoopOptions,
    dropped: &mut Vec<DroppedLoop>,
) -> Vec<(usize, Candidate)> {
    let (mut cycles, mut rest): (Vec<_>, Vec<_>) = candidates
        .into_iter()
        .partition(|(i, _)| seeds[*i].role == Some(Role::CycleClosing));
    // Cycles that are not necks by shape claim the classes first: a neck by shape is
    // kept anyway, so it should not take the class another cycle needs.
    cycles.sort_by(|(i, a), (j, b)| {
        (seeds[*i].bulge.is_some())
            .cmp(&seeds[*j].bulge.is_some())
            .then(a.tightened.length.total_cmp(&b.tightened.length))
            .then(i.cmp(j))
    });
    // But a cycle whose saddle lives less than a quarter as long as the longest-lived
    // one claims a class only if those necks by shape do not span it either. (In the
    // wire sphere's hollow a saddle living 3 of 32 levels took a class, with a loop 5.5
    // long round the hollow, before the two windows that are also necks by bulge, which
    // are kept anyway: 97 tunnel loops for 96 windows.)
    let longest = cycles
        .iter()
        .map(|(i, _)| seeds[*i].persistence)
        .max()
        .unwrap_or(0);
    let short_lived = |i: usize| 4 * seeds[i].persistence < longest;
    let by_shape: Vec<Vec<u64>> = cycles
        .iter()
        .filter(|(i, _)| seeds[*i].bulge.is_some())
        .map(|(_, c)| c.class.clone())
        .collect();
    let mut basis = Z2Basis::default();
    let mut kept: Vec<(usize, Vec<u64>)> = Vec::new();
    let mut necks = Vec::new();
    for (i, c) in cycles {
        let length = c.tightened.length;
        let spanned_by_shape = || {
            let mut both = basis.clone();
            for class in &by_shape {
                both.insert(class);
            }
            !both.insert(&c.class)
        };
        let reason = if c.class.iter().all(|w| *w == 0) {
            Some(DropReason::NotEssential { length })
        } else if short_lived(i) && seeds[i].bulge.is_none() && spanned_by_shape() {
            Some(DropReason::SameCycle { of: None, length })
        } else if basis.insert(&c.class) {
            None
        } else {
            Some(DropReason::SameCycle {
                of: kept.iter().find(|(_, k)| *k == c.class).map(|(j, _)| *j),
                length,
            })
        };
        match reason {
            Some(_) if seeds[i].bulge.is_some() => rest.push((i, c)),
            Some(reason) => dropped.push(DroppedLoop::new(kind, seeds, i, reason)),
            None => {
                kept.push((i, c.class.clone()));
                necks.push((i, c));
            }
        }
    }
    // Separating saddles that are not necks by their bulge must cut off a lobe fatter
    // than the neck (bulge > 1: not a bump whose top is the saddle's neighbour), and
    // open out on both sides round a roundish neck.
    let (rest, flat): (Vec<_>, Vec<_>) = rest.into_iter().partition(|(i, c)| {
        !seeds[*i].needs_opening
            || (seeds[*i].bulge.is_some_and(|b| b > 1.0)
                && c.opening.is_some_and(|o| o[0] >= options.min_opening)
                && c.flatness.is_some_and(|f| f <= options.max_flatness))
    });
    for (i, c) in flat {
        let reason = DropReason::NotANeck {
            bulge: seeds[i].bulge,
            opening: c.opening.map(|o| o[0]),
            flatness: c.flatness,
            length: c.tightened.length,
        };
        dropped.push(DroppedLoop::new(kind, seeds, i, reason));
    }
    // Necks by shape: one per (lobe, class), the largest bulge first.
    let mut rest = rest;
    rest.sort_by(|(i, _), (j, _)| {
        let bulge = |k: usize| seeds[k].bulge.unwrap_or(f64::INFINITY);
        bulge(*j).total_cmp(&bulge(*i)).then(i.cmp(j))
    });
    let mut by_lobe: Vec<(usize, usize, Vec<u64>)> = Vec::new();
    for (i, c) in rest {
        let same = seeds[i].lobe.and_then(|lobe| {
            by_lobe
                .iter()
                .find(|(l, _, class)| *l == lobe && *class == c.class)
                .map(|(_, j, _)| *j)
        });
        match same {
            Some(of) => dropped.push(DroppedLoop::new(
                kind,
                seeds,
                i,
                DropReason::SameLobe {
                    of,
                    length: c.tightened.length,
                },
            )),
            None => {
                if let Some(lobe) = seeds[i].lobe {
                    by_lobe.push((lobe, i, c.class.clone()));
                }
                necks.push((i, c));
            }
        }
    }
    necks
}

/// What a tightened loop is measured with: its homology class, the areas of its sides,
/// and how the surface opens out on them.
struct Measures<'a> {
    surface: &'a SurfaceMesh,
    topology: &'a Topology,
    basis: &'a HomologyBasis,
    openings: &'a Openings,
    /// [`LoopOptions::opening_reach`].
    reach: f64,
}

impl Measures<'_> {
    /// A tightened loop with its class, the areas of its sides when it separates, and
    /// its opening.
    fn candidate(&self, tightened: Tightened, offset: f64, initial: Initial) -> Candidate {
        let (surface, topology) = (self.surface, self.topology);
        let crossed = classes::crossings(surface, topology, &tightened.surface_points);
        let class = self.basis.class_of_crossings(crossed.iter().copied());
        let areas = class
            .iter()
            .all(|w| *w == 0)
            .then(|| classes::sides(surface, topology, &tightened.surface_points, &crossed))
            .flatten();
        let radius = tightened.length / (2.0 * std::f64::consts::PI);
        let opening = self.openings.of_loop(
            surface,
            topology,
            &tightened.surface_points,
            &tightened.points,
            &crossed,
            self.reach * radius,
        );
        Candidate {
            tightened,
            offset,
            initial,
            sources: Vec::new(),
            class,
            areas,
            opening,
            flatness: None,
        }
    }
}

/// The unit cutting normal of a seed, and the normals to try (it and its variations).
fn cutting_normals(seed: &Seed, options: &LoopOptions) -> ([f64; 3], Vec<[f64; 3]>) {
    let n = scale(seed.normal, 1.0 / norm(seed.normal));
    let mut normals = vec![n];
    let (u, v) = plane_basis(n);
    let k = options.normal_variations;
    for j in 0..k {
        let phi = 2.0 * std::f64::consts::PI * j as f64 / k as f64;
        let dir = add(scale(u, phi.cos()), scale(v, phi.sin()));
        let a = options.variation_angle;
        normals.push(add(scale(n, a.cos()), scale(dir, a.sin())));
    }
    (n, normals)
}

/// The surface's distance structure (closest points for membranes, the inscribed
/// radius at a saddle): the caller's, or built when a seed first needs it.
struct LazyDistance<'a> {
    surface: &'a SurfaceMesh,
    given: Option<&'a SurfaceDistance>,
    built: OnceLock<SurfaceDistance>,
}

impl LazyDistance<'_> {
    fn get(&self) -> &SurfaceDistance {
        match self.given {
            Some(distance) => distance,
            None => self
                .built
                .get_or_init(|| SurfaceDistance::new(self.surface)),
        }
    }
}

/// Cut, choose, tighten; also the offset of the plane that gave the loop, and whether a
/// plane or the membrane gave it. Order: the plane through the saddle, then (where
/// membranes are used) the membrane, then the parallel planes nearest first.
fn loop_from_seed(
    surface: &SurfaceMesh,
    topology: &Topology,
    geometry: &SurfaceGeometry,
    distance: &LazyDistance<'_>,
    seed: &Seed,
    options: &LoopOptions,
) -> std::result::Result<Start, DropReason> {
    let (n, normals) = cutting_normals(seed, options);
    let membrane = || {
        membrane_loop(
            surface,
            topology,
            distance.get(),
            seed.position,
            n,
            &options.membrane,
        )
        .map(|m| {
            let t = tighten(geometry, &m.crossings, &m.faces, &options.tighten);
            tightened(t).map(|t| Start {
                tightened: t,
                offset: 0.0,
                initial: Initial::Membrane,
                sources: m.sources,
            })
        })
    };
    if options.membranes == MembraneUse::Always {
        return membrane().unwrap_or_else(|failure| {
            Err(DropReason::NoMembraneLoop {
                failure,
                closed_curves: 0,
                open_curves: 0,
                offsets_tried: 0,
            })
        });
    }
    // The plane through the saddle first, then parallel ones nearest first.
    let step = options.offset_step * surface.bbox_diagonal();
    let offsets = std::iter::once(0.0)
        .chain((1..=options.plane_offsets).flat_map(|j| [j as f64 * step, -(j as f64) * step]));
    let (mut closed, mut open) = (0, 0);
    let mut failure = None;
    for offset in offsets {
        let point = add(seed.position, scale(n, offset));
        let best = around_point(surface, topology, &normals, point);
        if offset == 0.0 {
            (closed, open) = (best.1, best.2);
        }
        if let Some((_, curve)) = best.0 {
            let t = tighten(geometry, &curve.crossings, &curve.faces, &options.tighten);
            return tightened(t).map(|t| Start {
                tightened: t,
                offset,
                initial: Initial::Plane,
                sources: Vec::new(),
            });
        }
        if offset == 0.0 && options.membranes == MembraneUse::WherePlanesFail {
            match membrane() {
                Ok(result) => return result,
                Err(f) => failure = Some(f),
            }
        }
    }
    match failure {
        Some(failure) => Err(DropReason::NoMembraneLoop {
            failure,
            closed_curves: closed,
            open_curves: open,
            offsets_tried: options.plane_offsets,
        }),
        None => Err(DropReason::NoLoopAroundSaddle {
            closed_curves: closed,
            open_curves: open,
            offsets_tried: options.plane_offsets,
            offset_step: step,
        }),
    }
}

/// The shortest loop of `c`'s class over the parallel planes up to
/// [`LoopOptions::slide_steps`] × [`LoopOptions::slide_step`] from the one that gave `c`
/// (nearest first, + before −); `c` itself when none is shorter.
fn narrowest(
    surface: &SurfaceMesh,
    topology: &Topology,
    geometry: &SurfaceGeometry,
    measures: &Measures,
    seed: &Seed,
    c: Candidate,
    options: &LoopOptions,
) -> Candidate {
    let (n, normals) = cutting_normals(seed, options);
    let step = options.slide_step * surface.bbox_diagonal();
    let mut best = c;
    let start = best.offset;
    for j in 1..=options.slide_steps {
        for offset in [start + j as f64 * step, start - j as f64 * step] {
            let point = add(seed.position, scale(n, offset));
            let Some((_, curve)) = around_point(surface, topology, &normals, point).0 else {
                continue;
            };
            let t = tighten(geometry, &curve.crossings, &curve.faces, &options.tighten);
            let Ok(t) = tightened(t) else { continue };
            // Shorter beyond round-off: the same geodesic reached again does not move it.
            if t.length < best.tightened.length * (1.0 - 1e-6) {
                let mut other = measures.candidate(t, offset, Initial::Plane);
                if other.class == best.class {
                    other.flatness = best
                        .flatness
                        .map(|f| f * other.tightened.length / best.tightened.length);
                    best = other;
                }
            }
        }
    }
    best
}

/// The shortest closed curve around `point` over the planes through it with these
/// normals, and the closed and open curve counts of the first plane.
fn around_point(
    surface: &SurfaceMesh,
    topology: &Topology,
    normals: &[[f64; 3]],
    point: [f64; 3],
) -> (Option<(f64, cut::CutCurve)>, usize, usize) {
    let mut best: Option<(f64, cut::CutCurve)> = None;
    let (mut closed, mut open) = (0, 0);
    for (j, &normal) in normals.iter().enumerate() {
        let plane = Plane {
            origin: point,
            normal,
        };
        let mut curves = plane_cut(surface, topology, &plane);
        if j == 0 {
            closed = curves.iter().filter(|c| c.closed).count();
            open = curves.len() - closed;
        }
        if let Some(i) = loop_around(surface, topology, &plane, &curves, point) {
            let curve = curves.swap_remove(i);
            let length = closed_length(&curve.points(surface, topology));
            if best.as_ref().is_none_or(|(l, _)| length < *l) {
                best = Some((length, curve));
            }
        }
    }
    (best, closed, open)
}

/// A tightened loop, or why it is dropped.
fn tightened(t: Tightened) -> std::result::Result<Tightened, DropReason> {
    match t.status {
        TightenStatus::Converged | TightenStatus::Stalled if !t.simple => {
            Err(DropReason::NotSimple { length: t.length })
        }
        TightenStatus::Converged | TightenStatus::Stalled => Ok(t),
        TightenStatus::Collapsed => Err(DropReason::Collapsed {
            initial_length: t.initial_length,
            length: t.length,
        }),
        TightenStatus::NotConverged => Err(DropReason::NotConverged {
            rounds: t.rounds,
            length: t.length,
        }),
        TightenStatus::InvalidStrip => Err(DropReason::InvalidStrip),
    }
}

/// Order by persistence then length, and merge duplicates into the first of them.
fn select(
    surface: &SurfaceMesh,
    seeds: &[Seed],
    kind: Side,
    mut candidates: Vec<(usize, Candidate)>,
    options: &LoopOptions,
    basis_len: usize,
    dropped: &mut Vec<DroppedLoop>,
) -> Vec<NeckLoop> {
    candidates.sort_by(|(i, a), (j, b)| {
        seeds[*j]
            .persistence
            .cmp(&seeds[*i].persistence)
            .then(a.tightened.length.total_cmp(&b.tightened.length))
            .then(i.cmp(j))
    });
    let diagonal = surface.bbox_diagonal();
    let mut loops: Vec<NeckLoop> = Vec::new();
    for (i, c) in candidates {
        let Candidate {
            tightened: t,
            offset,
            initial,
            sources,
            class,
            areas,
            opening,
            flatness,
        } = c;
        let membrane =
            membrane::spanning_disk(seeds[i].position, seeds[i].normal, &sources, &t.points);
        let center = centroid(&t.points);
        let homology = class_string(&class, basis_len);
        let radius = t.length / (2.0 * std::f64::consts::PI);
        let duplicate_of = loops.iter().position(|l| {
            let close = norm(sub(l.center, center)) <= options.merge_distance * diagonal
                && (l.length - t.length).abs() <= options.merge_length * l.length.max(t.length);
            // The same neck reached from two saddles: the same class, and each loop
            // within half a radius of the other everywhere.
            let tolerance = options.merge_overlap * l.radius.min(radius);
            close
                || (l.homology == homology
                    && norm(sub(l.center, center)) <= l.radius + radius
                    && within(&l.points, &t.points, tolerance)
                    && within(&t.points, &l.points, tolerance))
        });
        if let Some(of) = duplicate_of {
            loops[of].duplicates.push(i);
            dropped.push(DroppedLoop::new(
                kind,
                seeds,
                i,
                DropReason::Duplicate {
                    of,
                    length: t.length,
                },
            ));
            continue;
        }
        let seed = seeds[i];
        let how = match t.status {
            TightenStatus::Converged => "a closed geodesic",
            _ => "a loop whose last round no longer shortened it",
        };
        let reason = format!(
            "saddle persistence {}; tightened in {} rounds from {:.6} to {:.6}, {}; shorter than {} x diagonal",
            seed.persistence, t.rounds, t.initial_length, t.length, how, options.max_length
        );
        loops.push(NeckLoop {
            kind,
            normal: best_fit_normal(&t.points, center),
            center,
            radius: t.length / (2.0 * std::f64::consts::PI),
            saddle: seed.position,
            seed: i,
            persistence: seed.persistence,
            duplicates: Vec::new(),
            role: seed.role,
            birth_scale: seed.scales.0,
            death_scale: seed.scales.1,
            bulge: seed.bulge,
            separating: class.iter().all(|w| *w == 0),
            homology,
            areas,
            opening,
            flatness,
            reason,
            tightening: TighteningReport {
                status: t.status,
                rounds: t.rounds,
                updates: t.updates,
                max_edge_turn: t.max_edge_turn,
                min_vertex_angle: t.min_vertex_angle,
                simple: t.simple,
            },
            length: t.length,
            initial_length: t.initial_length,
            initial,
            membrane,
            plane_offset: offset,
            points: t.points,
            surface_points: t.surface_points,
        });
    }
    loops
}

/// Whether every point of `a` lies within `tolerance` of the closed polyline `b`.
fn within(a: &[[f64; 3]], b: &[[f64; 3]], tolerance: f64) -> bool {
    let n = b.len();
    a.iter().all(|&p| {
        (0..n).any(|i| norm(sub(p, closest_on_segment(p, b[i], b[(i + 1) % n]))) <= tolerance)
    })
}

/// A class as one `0`/`1` character per basis cycle.
fn class_string(class: &[u64], len: usize) -> String {
    (0..len)
        .map(|g| {
            if class[g / 64] >> (g % 64) & 1 == 1 {
                '1'
            } else {
                '0'
            }
        })
        .collect()
}

/// Length-weighted centroid of a closed polyline (each segment counts at its midpoint).
pub fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len();
    let mut sum = [0.0; 3];
    let mut total = 0.0;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        let w = norm(sub(b, a));
        sum = add(sum, scale(add(a, b), 0.5 * w));
        total += w;
    }
    if total > 0.0 {
        scale(sum, 1.0 / total)
    } else {
        points.first().copied().unwrap_or([0.0; 3])
    }
}

/// Unit normal of the least-squares plane through the points (smallest principal axis of
/// their covariance), oriented along the loop's vector area.
pub fn best_fit_normal(points: &[[f64; 3]], center: [f64; 3]) -> [f64; 3] {
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for p in points {
        let d = nalgebra::Vector3::from(sub(*p, center));
        cov += d * d.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imin();
    let e = eig.eigenvectors.column(k);
    let mut normal = [e[0], e[1], e[2]];
    let n = points.len();
    let mut area = [0.0; 3];
    for i in 0..n {
        area = add(
            area,
            cross(sub(points[i], center), sub(points[(i + 1) % n], center)),
        );
    }
    if dot(area, normal) < 0.0 {
        normal = scale(normal, -1.0);
    }
    let l = norm(normal);
    if l > 0.0 {
        scale(normal, 1.0 / l)
    } else {
        normal
    }
}
