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
//!    construction gave it (`initial`). Where the plane through a cycle-closing saddle
//!    cuts a loop that separates the surface (a saddle on a plateau of the distance, in
//!    a bar wider than it is thick, whose Hessian does not tell the bar's direction),
//!    planes through it turned over a hemisphere are cut, and the shortest loop of a
//!    non-zero class that bounds a disk of the side replaces it
//!    ([`LoopOptions::turned_planes`]).
//! 2. [`tighten`](mod@tighten): shorten it into a closed geodesic, not tied to mesh edges. A loop that
//!    collapses (slides off a cap) or does not settle is dropped with its reason.
//! 3. Selection: drop loops longer than `max_length` × the bounding-box diagonal; keep one
//!    loop per neck (cycle-closing loops one per independent Z2 class, shortest first;
//!    necks by shape one per lobe and class, where a separating saddle whose lobe bulges
//!    less than the Morse stage's `min_bulge` is a neck only if its loop opens out on both
//!    sides by [`LoopOptions::min_opening`] ([`opening`]) round a roundish neck
//!    ([`LoopOptions::max_flatness`]: its length against the inscribed ball at the saddle,
//!    from the `distance` service)); move each kept cycle-closing loop to the narrowest
//!    place of its handle or tunnel, whichever of its saddles the lattice gave: parallel
//!    planes up to [`LoopOptions::slide_steps`] × [`LoopOptions::slide_step`] × diagonal
//!    away are cut and tightened, and the shortest loop of its class wins; merge duplicates
//!    (centres within `merge_distance` × diagonal and lengths within `merge_length`, or the
//!    same class and each within `merge_overlap` × radius of the other), keeping the
//!    highest persistence, then the shortest; order by persistence (descending), then
//!    length.
//! 4. [`lasso`]: each kept loop's best-fit circle and how far the loop strays from it.
//!
//! A seed may need a disk ([`Seed::disk_only`]: the Morse stage's completions, saddles
//! not selected as necks): its plane's curve around it is kept only where no other
//! curve of the plane lies inside it ([`cut::encloses_another`]) and the region it
//! bounds lies on the seed's side ([`cut::region_side`]), so that the loop bounds a disk
//! of that side (a handle or tunnel loop whatever the saddle); planes are cut (through
//! it, then parallel ones), no membrane, and its tightening may shrink it any amount.
//! [`complete_classes`] adds such loops to a result where they add a class.
//!
//! Also here: [`classes`] (the edges a loop crosses, its Z2 class, the areas of its
//! sides); [`LoopSurface`] (a surface's topology, homology basis and openings, built
//! once); [`LoopMemo`] (what one search of a surface hands the next: the same loops,
//! with the tightenings and empty planes they share done once); the result types
//! [`NeckLoop`], [`DroppedLoop`] and [`DropReason`]; and [`transfer_loops`]: loops
//! found on a simplified copy rebuilt on the input (the same plane or membrane, else
//! the strip of faces under the copy's loop, else its best-fit plane), tightened and
//! measured there, and kept only as the same neck (length within
//! 5 %, centre within half a radius), else dropped as [`DropReason::NotTransferred`].
//!
//! Units are those of the surface. Every seed ends either as a loop or in `dropped` with
//! a reason. Seeds are processed in parallel; the result does not depend on the thread
//! count. Entry point: [`find_loops`].

pub mod classes;
pub mod cut;
pub mod lasso;
pub mod linked;
pub mod membrane;
mod memo;
pub mod opening;
mod report;
mod selection;
mod surface;
mod transfer;

pub use lasso::{fit_lasso, Lasso};
pub use report::{DropReason, DroppedLoop, LoopResult, LoopTimings, NeckLoop, TighteningReport};
pub use selection::{best_fit_normal, centroid, complete_classes};
use selection::{neck_loop, one_per_neck, select};
pub use surface::LoopSurface;
pub use transfer::transfer_loops;
pub mod tighten;

use std::sync::OnceLock;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::distance::SurfaceDistance;
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, norm, scale};
use crate::mesh::{HomologyBasis, Side, SurfaceMesh, Topology};
use crate::progress::{Progress, Silent};
use cut::{closed_length, encloses_another, loop_around, plane_basis, Cutter, Plane};
use membrane::{membrane_loop, DualGraph};
pub use membrane::{MembraneFailure, MembraneOptions};
use memo::CurveCounts;
pub use memo::{LoopMemo, MAX_REMEMBERED_BYTES};
use opening::Openings;
use tighten::SurfaceGeometry;
pub use tighten::{SurfacePoint, TightenOptions, TightenStatus, Tightened};

/// What the saddle of a seed does to the volume (see `morse::roles`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// It joins two lobes: its loop cuts off a part.
    Separating,
    /// It closes a cycle: its loop goes around a handle (inside) or tunnel (outside).
    CycleClosing,
}

/// Where a loop starts: a selected 2-saddle.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
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
    /// Keep a plane's curve around the saddle only where no other curve of the plane
    /// lies inside it: the region of the plane it bounds is then a disk of the seed's
    /// side, so the loop bounds a disk there (a handle loop inside, a tunnel loop
    /// outside) whatever the saddle. For a saddle the Morse stage did not select as a
    /// neck (`MorseResult::completions`). A curve whose region lies on the other side
    /// (a parallel plane's point moved across the surface) is passed over too; no
    /// membrane is tried, as a membrane's loop is not checked. Default false.
    #[serde(default)]
    pub disk_only: bool,
}

impl Seed {
    /// The same seed with [`Seed::disk_only`] set.
    pub fn needing_a_disk(self) -> Seed {
        Seed {
            disk_only: true,
            ..self
        }
    }
}

/// Options of [`find_loops`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
    /// Where the plane through a cycle-closing saddle cuts a loop that separates the
    /// surface (its class is 0), planes through the saddle in this many directions over
    /// a hemisphere round the saddle's normal are cut, and the shortest loop of a non-zero
    /// class that bounds a disk of the side replaces it ([`Initial::TurnedPlane`]). A
    /// bar of a plate wider than the plate is thick lies on a plateau of the distance,
    /// whose Hessian does not tell the bar's direction: the plane through the saddle
    /// between the plate's middle hole and a corner hole of tm_plate_holes cut across
    /// the whole plate. Default 64 (0 turns no plane).
    pub turned_planes: usize,
}

/// When the saddle's membrane (module [`membrane`]) gives the initial loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Initial {
    /// A plane cut (through the saddle, or parallel to it: see `plane_offset`).
    Plane,
    /// The boundary of the saddle's membrane.
    Membrane,
    /// A plane through the saddle turned from its normal: the shortest essential loop
    /// over [`LoopOptions::turned_planes`] directions, where the saddle's own plane cut
    /// a separating one.
    TurnedPlane,
    /// No saddle: the shortest closed path of edges in a class that bounds on the side
    /// but no disk there (module [`linked`]).
    Linked,
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
            turned_planes: 64,
        }
    }
}

/// Loops of `kind` around the necks marked by `seeds` on `surface` (the input surface,
/// not the volume mesh's boundary).
pub fn find_loops(
    surface: &SurfaceMesh,
    seeds: &[Seed],
    kind: Side,
    options: &LoopOptions,
) -> Result<LoopResult> {
    find_loops_with_progress(
        surface,
        None,
        seeds,
        kind,
        options,
        &LoopMemo::default(),
        &Silent,
    )
}

/// [`find_loops`], reporting each seed cut and tightened to `progress`. `distance` is
/// the surface's distance structure when the caller has one (the run's); without it,
/// one is built when a seed first needs closest points. `memo` holds what earlier
/// searches of `surface` with the same options found ([`LoopMemo`]: the same loops,
/// with less work where the searches repeat each other).
pub fn find_loops_with_progress(
    surface: &SurfaceMesh,
    distance: Option<&SurfaceDistance>,
    seeds: &[Seed],
    kind: Side,
    options: &LoopOptions,
    memo: &LoopMemo,
    progress: &dyn Progress,
) -> Result<LoopResult> {
    check_inputs(surface, seeds, options)?;

    let start = Instant::now();
    let prepared = memo.surface(surface);
    let basis = &prepared.basis;
    let geometry = prepared.geometry(surface);
    let measures = prepared.measures(surface, options);
    let cutter = prepared.cutter(surface);
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
            let measured = |s: Start| {
                let mut c =
                    measures.candidate(s.tightened, s.offset, s.initial, seed.needs_opening);
                c.sources = s.sources;
                c.normal = s.normal;
                // The inscribed radius at the saddle: the exact distance there.
                let inscribed = distance.get().distance(seed.position);
                c.flatness = (inscribed > 0.0)
                    .then(|| c.tightened.length / (2.0 * std::f64::consts::PI * inscribed));
                c
            };
            let outcome = loop_from_seed(
                (&cutter, &prepared.dual),
                &geometry,
                &distance,
                memo,
                seed,
                kind,
                options,
            )
            .map(measured)
            .map(|c| {
                let separates = c.class.iter().all(|w| *w == 0);
                if separates && seed.role == Some(Role::CycleClosing) {
                    turned(&cutter, &geometry, &measures, memo, seed, options).map_or(c, measured)
                } else {
                    c
                }
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
                    &cutter, &geometry, &measures, memo, &seeds[i], kind, c, options,
                )
            } else {
                c
            };
            (i, c)
        })
        .collect();
    let mut loops = select(
        surface,
        seeds,
        kind,
        candidates,
        options,
        basis.len(),
        &mut dropped,
    );
    // Openings are measured where selection reads them (`Seed::needs_opening`), and
    // for the loops kept: most candidates are dropped, and a long one's band is wide.
    let openings: Vec<Option<[f64; 2]>> = loops
        .par_iter()
        .map(|l| match l.opening {
            None if !seeds[l.seed].needs_opening => measures.opening(l),
            measured => measured,
        })
        .collect();
    for (l, opening) in loops.iter_mut().zip(openings) {
        l.opening = opening;
    }
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
    /// The unit normal of the plane that gave it (the saddle's for a membrane).
    normal: [f64; 3],
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
    /// The unit normal of the plane that gave it (the saddle's for a membrane).
    normal: [f64; 3],
    /// Its Z2 homology class.
    class: Vec<u64>,
    /// When it separates the surface: the areas of its sides.
    areas: Option<[f64; 2]>,
    /// The opening of its two sides, smaller first.
    opening: Option<[f64; 2]>,
    /// Its length over the circumference of the inscribed ball at its saddle.
    flatness: Option<f64>,
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
    /// How the surface opens out on the sides of a kept loop (module [`opening`]).
    fn opening(&self, l: &NeckLoop) -> Option<[f64; 2]> {
        let crossed = classes::crossings(self.surface, self.topology, &l.surface_points);
        self.opening_of(&l.surface_points, &l.points, l.length, &crossed)
    }

    /// The opening of a loop through `points` (at `positions`), of this `length`, that
    /// crosses the edges `crossed`, measured out to [`LoopOptions::opening_reach`] × its
    /// radius.
    fn opening_of(
        &self,
        points: &[SurfacePoint],
        positions: &[[f64; 3]],
        length: f64,
        crossed: &[usize],
    ) -> Option<[f64; 2]> {
        let reach = self.reach * (length / (2.0 * std::f64::consts::PI));
        let (surface, topology) = (self.surface, self.topology);
        self.openings
            .of_loop(surface, topology, points, positions, crossed, reach)
    }

    /// A tightened loop's Z2 homology class.
    fn class_of(&self, tightened: &Tightened) -> Vec<u64> {
        let crossed = classes::crossings(self.surface, self.topology, &tightened.surface_points);
        self.basis.class_of_crossings(crossed)
    }

    /// A tightened loop with its class, the areas of its sides when it separates, and
    /// (with `opening`) its opening; else that is left `None`, for [`Measures::opening`]
    /// once the loop is kept.
    fn candidate(
        &self,
        tightened: Tightened,
        offset: f64,
        initial: Initial,
        opening: bool,
    ) -> Candidate {
        let (surface, topology) = (self.surface, self.topology);
        let crossed = classes::crossings(surface, topology, &tightened.surface_points);
        let class = self.basis.class_of_crossings(crossed.iter().copied());
        let areas = class
            .iter()
            .all(|w| *w == 0)
            .then(|| classes::sides(surface, topology, &tightened.surface_points, &crossed))
            .flatten();
        let opening = opening
            .then(|| {
                let (points, positions) = (&tightened.surface_points, &tightened.points);
                self.opening_of(points, positions, tightened.length, &crossed)
            })
            .flatten();
        Candidate {
            tightened,
            offset,
            initial,
            sources: Vec::new(),
            normal: [0.0; 3],
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
    (cutter, dual): (&Cutter, &DualGraph),
    geometry: &SurfaceGeometry,
    distance: &LazyDistance<'_>,
    memo: &LoopMemo,
    seed: &Seed,
    kind: Side,
    options: &LoopOptions,
) -> std::result::Result<Start, DropReason> {
    let (surface, topology) = (cutter.mesh, cutter.topology);
    let (n, normals) = cutting_normals(seed, options);
    let membrane = || {
        membrane_loop(
            surface,
            topology,
            dual,
            distance.get(),
            seed.position,
            n,
            &options.membrane,
        )
        .map(|m| {
            let t = memo.tighten(geometry, &m.crossings, &m.faces, &options.tighten);
            tightened(t).map(|t| Start {
                tightened: t,
                offset: 0.0,
                initial: Initial::Membrane,
                sources: m.sources,
                normal: n,
            })
        })
    };
    if options.membranes == MembraneUse::Always && !seed.disk_only {
        return membrane().unwrap_or_else(|failure| {
            Err(DropReason::NoMembraneLoop {
                failure,
                closed_curves: 0,
                open_curves: 0,
                offsets_tried: 0,
            })
        });
    }
    // The plane through the saddle first, then parallel ones nearest first. (A seed
    // that needs a disk keeps to planes: a membrane's loop is not checked for islands.)
    let step = options.offset_step * surface.bbox_diagonal();
    let tried = options.plane_offsets;
    let disk = seed.disk_only.then_some(kind);
    let offsets =
        std::iter::once(0.0).chain((1..=tried).flat_map(|j| [j as f64 * step, -(j as f64) * step]));
    let mut counts = None;
    let mut not_disks = 0;
    let mut failure = None;
    for offset in offsets {
        let point = add(seed.position, scale(n, offset));
        // The saddle's plane's curves are counted only for a seed that gets no loop.
        let best = around_point(cutter, memo, &normals, point, disk, false);
        if offset == 0.0 {
            counts = best.1;
        }
        not_disks += best.2;
        if let Some((_, curve)) = best.0 {
            let t = memo.tighten(
                geometry,
                &curve.crossings,
                &curve.faces,
                &tightening(seed, options),
            );
            return tightened(t).map(|t| Start {
                tightened: t,
                offset,
                initial: Initial::Plane,
                sources: Vec::new(),
                normal: n,
            });
        }
        if offset == 0.0 && options.membranes == MembraneUse::WherePlanesFail && !seed.disk_only {
            match membrane() {
                Ok(result) => return result,
                Err(f) => failure = Some(f),
            }
        }
    }
    let (closed, open) = counts.unwrap_or_else(|| {
        let point = add(seed.position, scale(n, 0.0));
        around_point(cutter, memo, &normals, point, disk, true)
            .1
            .unwrap_or_default()
    });
    match failure {
        None if not_disks > 0 => Err(DropReason::NoDiskAroundSaddle {
            planes: not_disks,
            offsets_tried: tried,
        }),
        Some(failure) => Err(DropReason::NoMembraneLoop {
            failure,
            closed_curves: closed,
            open_curves: open,
            offsets_tried: tried,
        }),
        None => Err(DropReason::NoLoopAroundSaddle {
            closed_curves: closed,
            open_curves: open,
            offsets_tried: tried,
            offset_step: step,
        }),
    }
}

/// The shortest tightened loop of a non-zero class over planes through the saddle in
/// [`LoopOptions::turned_planes`] directions (a Fibonacci hemisphere round the seed's
/// normal), among curves around the saddle that enclose no other curve of their plane
/// (so the loop bounds a disk of the seed's side). The cut curves are ranked by length
/// and tightened shortest first, until one keeps a non-zero class; `None` when none
/// does.
fn turned(
    cutter: &Cutter,
    geometry: &SurfaceGeometry,
    measures: &Measures,
    memo: &LoopMemo,
    seed: &Seed,
    options: &LoopOptions,
) -> Option<Start> {
    let (surface, topology) = (cutter.mesh, cutter.topology);
    /// Tightened at most this many of the shortest essential curves.
    const TRIED: usize = 4;
    let k = options.turned_planes;
    let n = scale(seed.normal, 1.0 / norm(seed.normal));
    let (u, v) = plane_basis(n);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut curves: Vec<(f64, usize, [f64; 3], cut::CutCurve)> = (0..k)
        .into_par_iter()
        .filter_map(|j| {
            let z = (j as f64 + 0.5) / k as f64;
            let (r, phi) = ((1.0 - z * z).sqrt(), golden * j as f64);
            let normal = add(
                scale(n, z),
                add(scale(u, r * phi.cos()), scale(v, r * phi.sin())),
            );
            let plane = Plane {
                origin: seed.position,
                normal,
            };
            let mut cut = cutter.cut(&plane);
            let i = loop_around(surface, topology, &plane, &cut, seed.position)?;
            if encloses_another(surface, topology, &plane, &cut, i) {
                return None;
            }
            let curve = cut.swap_remove(i);
            let class = measures
                .basis
                .class_of_crossings(curve.crossings.iter().map(|c| c.edge as usize));
            if class.iter().all(|w| *w == 0) {
                return None;
            }
            let length = closed_length(&curve.points(surface, topology));
            Some((length, j, normal, curve))
        })
        .collect();
    curves.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    curves
        .into_iter()
        .take(TRIED)
        .find_map(|(_, _, normal, curve)| {
            let t = memo.tighten(
                geometry,
                &curve.crossings,
                &curve.faces,
                &tightening(seed, options),
            );
            let t = tightened(t).ok()?;
            let crossed = classes::crossings(surface, topology, &t.surface_points);
            let class = measures.basis.class_of_crossings(crossed);
            class.iter().any(|w| *w != 0).then_some(Start {
                tightened: t,
                offset: 0.0,
                initial: Initial::TurnedPlane,
                sources: Vec::new(),
                normal,
            })
        })
}

/// The shortest loop of `c`'s class over the parallel planes up to
/// [`LoopOptions::slide_steps`] × [`LoopOptions::slide_step`] from the one that gave `c`
/// (nearest first, + before −); `c` itself when none is shorter.
///
/// A plane's curve of another class is not tightened: tightening is a homotopy on the
/// surface, so it keeps the curve's class (a parallel plane 4 % of the diagonal away
/// can cut round a whole part, a long curve that is most of the tightening's work). The
/// winner alone is measured (opening, areas), once.
#[allow(clippy::too_many_arguments)]
fn narrowest(
    cutter: &Cutter,
    geometry: &SurfaceGeometry,
    measures: &Measures,
    memo: &LoopMemo,
    seed: &Seed,
    kind: Side,
    c: Candidate,
    options: &LoopOptions,
) -> Candidate {
    let surface = cutter.mesh;
    let (n, normals) = match c.initial {
        Initial::TurnedPlane | Initial::Linked => (c.normal, vec![c.normal]),
        Initial::Plane | Initial::Membrane => cutting_normals(seed, options),
    };
    let step = options.slide_step * surface.bbox_diagonal();
    let start = c.offset;
    let offsets: Vec<f64> = (1..=options.slide_steps)
        .flat_map(|j| [start + j as f64 * step, start - j as f64 * step])
        .collect();
    // Each plane's loop on its own (in parallel: a dense surface makes every cut and
    // tightening long), then the shortest in the order above.
    let loops: Vec<Option<Tightened>> = offsets
        .par_iter()
        .map(|&offset| {
            let point = add(seed.position, scale(n, offset));
            let (_, curve) = around_point(
                cutter,
                memo,
                &normals,
                point,
                seed.disk_only.then_some(kind),
                false,
            )
            .0?;
            let crossed = curve.crossings.iter().map(|x| x.edge as usize);
            if measures.basis.class_of_crossings(crossed) != c.class {
                return None;
            }
            let t = memo.tighten(
                geometry,
                &curve.crossings,
                &curve.faces,
                &tightening(seed, options),
            );
            tightened(t).ok()
        })
        .collect();
    let mut best: Option<(f64, Tightened)> = None;
    let (mut length, mut flatness) = (c.tightened.length, c.flatness);
    for (offset, t) in offsets.into_iter().zip(loops) {
        let Some(t) = t else { continue };
        // Shorter beyond round-off: the same geodesic reached again does not move it.
        if t.length < length * (1.0 - 1e-6) && measures.class_of(&t) == c.class {
            flatness = flatness.map(|f| f * t.length / length);
            length = t.length;
            best = Some((offset, t));
        }
    }
    match best {
        None => c,
        Some((offset, t)) => Candidate {
            normal: c.normal,
            flatness,
            ..measures.candidate(t, offset, c.initial, seed.needs_opening)
        },
    }
}

/// The shortest closed curve around `point` over the planes through it with these
/// normals, the closed and open curve counts of the first plane when `counted` (or
/// known), and the planes passed over for `disk`. With `disk` ([`Seed::disk_only`]: the
/// side the loop must bound a disk of), a curve with another one inside it, or whose
/// region of the plane lies on the other side ([`cut::region_side`]: `point` was moved
/// across the surface), is passed over. Unless `counted`, only the curves that may go
/// round `point` ([`Cutter::cut_round`]), and for `disk` those that may lie inside the
/// one round it ([`Cutter::encloses_another_round`]), are walked: the same curve is
/// found.
fn around_point(
    cutter: &Cutter,
    memo: &LoopMemo,
    normals: &[[f64; 3]],
    point: [f64; 3],
    disk: Option<Side>,
    counted: bool,
) -> (Option<(f64, cut::CutCurve)>, Option<CurveCounts>, usize) {
    match memo.no_curve_round(point, normals) {
        Some(Some(counts)) => return (None, Some(counts), 0),
        Some(None) if !counted => return (None, None, 0),
        _ => {}
    }
    let (surface, topology) = (cutter.mesh, cutter.topology);
    let only_round = !counted;
    let mut best: Option<(f64, cut::CutCurve)> = None;
    let mut counts = None;
    let mut not_disks = 0;
    for (j, &normal) in normals.iter().enumerate() {
        let plane = Plane {
            origin: point,
            normal,
        };
        let mut curves = if only_round {
            cutter.cut_round(&plane)
        } else {
            cutter.cut(&plane)
        };
        if j == 0 && !only_round {
            let closed = curves.iter().filter(|c| c.closed).count();
            counts = Some((closed, curves.len() - closed));
        }
        if let Some(i) = loop_around(surface, topology, &plane, &curves, point) {
            if let Some(side) = disk {
                // The side first: it reads the curve alone, the islands the plane round it.
                let not_disk = cut::region_side(surface, topology, &plane, &curves[i]) != side
                    || if only_round {
                        cutter.encloses_another_round(&plane, &curves[i])
                    } else {
                        encloses_another(surface, topology, &plane, &curves, i)
                    };
                if not_disk {
                    not_disks += 1;
                    continue;
                }
            }
            let curve = curves.swap_remove(i);
            let length = closed_length(&curve.points(surface, topology));
            if best.as_ref().is_none_or(|(l, _)| length < *l) {
                best = Some((length, curve));
            }
        }
    }
    if best.is_none() && not_disks == 0 {
        memo.remember_no_curve(point, normals, counts);
    }
    (best, counts, not_disks)
}

/// The tightening options for a seed's loops: a seed that needs a disk
/// ([`Seed::disk_only`]) may shrink to any length (its curve bounds a disk, so a loop
/// that slides off a cap ends separating, and is dropped for that), the rest as given.
fn tightening(seed: &Seed, options: &LoopOptions) -> TightenOptions {
    if seed.disk_only {
        TightenOptions {
            min_length_ratio: f64::MIN_POSITIVE,
            ..options.tighten
        }
    } else {
        options.tighten
    }
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
