//! A mesher by restricted Delaunay refinement: points are added to one Delaunay
//! tetrahedralization until its cells, labelled inside or outside by the domain, bound
//! the domain with well-shaped faces on its boundary and well-shaped cells inside.
//!
//! Isosurface stuffing needs lattice cells of half a part's thickness in all three
//! directions along every thin part and gap; here the points follow the boundary, and a
//! plate costs its area over its thickness squared with a small constant (see
//! `docs/design-mesher.md`). This replaces the paper's TetGen step (sec. 4) like
//! stuffing does. It is the approach of CGAL's Mesh_3 for implicit domains (Oudot,
//! Rineau & Yvinec, IMR 2005; Jamin et al., ACM TOMS 2015), written from the papers:
//! - **Cells are labelled** by the domain's sign at their circumcentre (a tet with a
//!   far point is outside). The mesh is the inside cells; its boundary is the faces
//!   between an inside and an outside cell.
//! - **A face is on the boundary** when its dual Voronoi edge (the segment between its
//!   two cells' circumcentres) crosses the domain's boundary: the crossing is the face's
//!   *surface centre*, and the ball round it through the face's corners (its *surface
//!   ball*) holds no point. Where the two cells have the same label the edge may still
//!   cross twice (a thin plate or slit between two circumcentres); the domain's ray
//!   cast ([`Domain::crossing`]) finds that, and the crossing is inserted.
//! - **Facet refinement** (first, always): a boundary face is refined, by inserting its
//!   surface centre, when its surface ball is wider than
//!   [`RefinedOptions::facet_size`] of the spacing there, when its smallest angle is
//!   under [`RefinedOptions::facet_angle_deg`], or when a corner is not on the boundary.
//! - **Cell refinement**: an inside cell whose radius–edge ratio is over
//!   [`RefinedOptions::radius_edge`] or whose circumradius is over
//!   [`RefinedOptions::cell_size`] of the spacing at its circumcentre gets its
//!   circumcentre, unless that lies in a boundary face's surface ball: then the face's
//!   surface centre is inserted instead (Ruppert's rule: the boundary is never
//!   encroached).
//! - **Manifold repair**: when no face or cell is left to refine, a boundary edge with
//!   more than two boundary faces, or a boundary vertex whose faces are not one fan,
//!   gets the surface centre of its widest face, and refinement goes on.
//! - **Termination guard**: nothing is inserted closer to a vertex than
//!   [`RefinedOptions::guard`] of the spacing there (the ball's radius is that
//!   distance); such an element is *accepted bad* and counted in
//!   [`RefinedStats::accepted_bad`]. The memory budget bounds the tets; where it binds,
//!   [`RefinedStats::over_budget`] says so.
//!
//! The spacing is the sampled mesher's [`SpacingField`] (the thickness and gaps at the
//! boundary, graded away from it), and the seeds are its boundary samples (the
//! surface's triangles bisected to the spacing, and the sphere's for a shell). After
//! refinement, `chords` splits edges between boundary vertices across the inside (a
//! thin part keeps an interior vertex), and `quality` moves interior vertices to raise
//! the smallest dihedral angles.
//!
//! **Status: experimental** (`--mesher refined`). Conventions: lengths in the domain's
//! units; output tets positively oriented as in [`crate::tet`]; the insertion is
//! sequential, so the result does not depend on the thread count. Entry point:
//! [`mesh_refined`].

use std::collections::VecDeque;
use std::time::Instant;

use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;
use serde::{Deserialize, Serialize};

use super::chords::split_chords;
use super::delaunay::{Cavity, Triangulation, FAR_POINTS, NONE};
use super::quality::{improve, score, Mobility, QualityStats};
use super::repair::repair_pinches;
use super::sampled::{vertex_kinds, Sample, SpacingField};
use super::Domain;
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, cross, dot, scale, sub};
use crate::tet::{renumber_used, TetMesh};

/// Options of [`mesh_refined`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefinedOptions {
    /// A boundary face's surface ball may be at most this fraction of the spacing at its
    /// centre in radius (default 0.45: under half a thin part's thickness, so that its
    /// mid-surface stays outside every ball and can hold an interior vertex).
    pub facet_size: f64,
    /// A boundary face's smallest angle, degrees, below which it is refined (default 20).
    pub facet_angle_deg: f64,
    /// An inside cell's largest circumradius over shortest edge (default 2).
    pub radius_edge: f64,
    /// An inside cell's circumradius may be at most this fraction of the spacing at its
    /// circumcentre (default 1).
    pub cell_size: f64,
    /// No point is inserted closer to a vertex than this fraction of the spacing there
    /// (default 0.1): the termination guard.
    pub guard: f64,
    /// Most live tets (the memory budget): refinement stops there, and says so.
    pub max_tets: usize,
    /// The quality step's target smallest dihedral angle, degrees (default 10; 0: off).
    pub min_dihedral_deg: f64,
}

impl Default for RefinedOptions {
    fn default() -> Self {
        RefinedOptions {
            facet_size: 0.45,
            facet_angle_deg: 20.0,
            radius_edge: 2.0,
            cell_size: 1.0,
            guard: 0.1,
            max_tets: usize::MAX,
            min_dihedral_deg: 10.0,
        }
    }
}

/// What a run of the refinement mesher (`volume::refined`, `--mesher refined`) did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RefinedStats {
    /// Boundary samples inserted first.
    pub seeds: usize,
    /// Surface centres inserted (boundary faces refined, encroachments, double
    /// crossings, manifold repair).
    pub surface_points: usize,
    /// Of those, crossings of a Voronoi edge whose two cells have the same label.
    pub double_crossings: usize,
    /// Of those, inserted for a non-manifold edge or vertex of the boundary.
    pub manifold_repairs: usize,
    /// Circumcentres of inside cells inserted.
    pub circumcentres: usize,
    /// Circumcentres refused because they lay in a boundary face's surface ball.
    pub encroachments: usize,
    /// Times a face or cell was found bad but its point lay within the guard of a
    /// vertex, so it was left (an element is counted at each evaluation).
    pub accepted_bad: usize,
    /// Whether refinement stopped at the memory budget (`max_tets`).
    pub over_budget: bool,
    /// Boundary edges and vertices still not manifold at the end.
    pub non_manifold: usize,
    /// Tets of the final Delaunay tetrahedralization (without the far points).
    pub delaunay_tets: usize,
    /// Tets labelled inside and kept (the mesh, before chords).
    pub kept_tets: usize,
    /// Tets labelled inside with four boundary vertices and a volume under `FLAT` (10⁻⁹)
    /// times the longest edge cubed (a flat sliver on a planar part of the boundary).
    pub flat_slivers: usize,
    /// Boundary vertices of the mesh that are not boundary samples or surface centres.
    pub off_boundary: usize,
    /// Tets dropped to undo pinches of the boundary (see `repair`).
    pub pinch_tets: usize,
    /// Chords split (see `chords`).
    pub chords_split: usize,
    /// What the quality step did.
    pub quality: QualityStats,
    /// Seconds: seeding, refinement, labelling and kinds, chords and quality.
    pub seconds: [f64; 4],
}

/// A boundary face's surface ball.
#[derive(Debug, Clone, Copy)]
struct Ball {
    centre: [f64; 3],
    radius2: f64,
}

/// What refinement keeps per tet slot.
#[derive(Debug, Clone, Copy)]
struct Cell {
    circumcentre: [f64; 3],
    radius2: f64,
    inside: bool,
    /// Bumped whenever the slot gets a new tet (queue entries name a generation).
    generation: u32,
    /// Per face (opposite corner `i`): its surface ball, when the face is on the
    /// boundary.
    balls: [Option<Ball>; 4],
}

impl Default for Cell {
    fn default() -> Self {
        Cell {
            circumcentre: [0.0; 3],
            radius2: 0.0,
            inside: false,
            generation: 0,
            balls: [None; 4],
        }
    }
}

/// A point to insert, valid while the named tets are unchanged.
#[derive(Debug, Clone, Copy)]
struct Pending {
    point: [f64; 3],
    tets: [(u32, u32); 2],
    kind: PointKind,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum PointKind {
    /// A boundary face's surface centre.
    Surface,
    /// A crossing of a Voronoi edge between two cells of one label.
    DoubleCrossing,
}

/// Mesh `domain` by restricted Delaunay refinement from `samples` (points on its
/// boundary), with the spacing `field` (see the module doc).
pub fn mesh_refined(
    domain: &dyn Domain,
    samples: &[Sample],
    field: &SpacingField,
    options: &RefinedOptions,
) -> Result<(TetMesh, RefinedStats)> {
    if samples.len() < 4 {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!("{} boundary samples cannot bound a volume", samples.len()),
        ));
    }
    let clock = Instant::now();
    let mut refiner = Refiner::new(domain, field, options);
    refiner.seed(samples);
    refiner.stats.seconds[0] = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    refiner.refine();
    refiner.stats.seconds[1] = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let (mut positions, mut tets, on_boundary) = refiner.inside_tets();
    let mut stats = refiner.stats;
    stats.seconds[2] = clock.elapsed().as_secs_f64();
    if tets.is_empty() {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            "the refined volume mesh is empty: no cell's circumcentre is inside",
        ));
    }

    let clock = Instant::now();
    let mut interior: Vec<bool> = on_boundary.iter().map(|b| !b).collect();
    // Pinches the guard left (an edge or vertex where the inside touches itself):
    // the smaller side goes, as for stuffing.
    let repair = repair_pinches(&positions, &mut tets, &interior);
    stats.pinch_tets = repair.removed_tets;
    for &v in &repair.exposed {
        interior[v as usize] = false;
    }
    for &v in &repair.buried {
        interior[v as usize] = true;
    }
    let (new_of_old, old_of_new) = renumber_used(positions.len(), &tets);
    tets.iter_mut()
        .for_each(|t| *t = t.map(|v| new_of_old[v as usize]));
    positions = old_of_new.iter().map(|&v| positions[v as usize]).collect();
    interior = old_of_new.iter().map(|&v| interior[v as usize]).collect();
    stats.chords_split = split_chords(&mut positions, &mut tets, &mut interior);
    // Boundary vertices stay, but for those of flat or inverted tets (four boundary
    // points coplanar up to rounding, as across a right-angled crease sampled
    // symmetrically, and what splitting them made): they slide along the boundary.
    let mut mobility: Vec<Mobility> = interior
        .iter()
        .map(|&inside| {
            if inside {
                Mobility::Free
            } else {
                Mobility::Fixed
            }
        })
        .collect();
    for t in &tets {
        if score(t.map(|v| positions[v as usize])) <= 0.0 {
            for &v in t {
                if !interior[v as usize] {
                    mobility[v as usize] = Mobility::OnBoundary;
                }
            }
        }
    }
    if options.min_dihedral_deg > 0.0 {
        stats.quality = improve(
            &mut positions,
            &tets,
            &mobility,
            &|p| domain.project(p),
            options.min_dihedral_deg,
        );
    }
    let kinds = vertex_kinds(domain, &positions, &interior);
    stats.seconds[3] = clock.elapsed().as_secs_f64();
    let mesh = TetMesh::new(positions, tets, kinds)?;
    Ok((mesh, stats))
}

/// The refinement's state: the triangulation, per slot what it keeps, the queues.
struct Refiner<'a> {
    domain: &'a dyn Domain,
    field: &'a SpacingField,
    options: &'a RefinedOptions,
    t: Triangulation,
    /// Per triangulation vertex: whether it lies on the domain's boundary.
    on_boundary: Vec<bool>,
    cells: Vec<Cell>,
    /// Per slot, the insertion that made it last (to evaluate a shared face once).
    made_at: Vec<u32>,
    insertion: u32,
    facets: VecDeque<Pending>,
    cells_to_split: VecDeque<(u32, u32)>,
    live: usize,
    /// The domain's box, widened a little: outside it every point is outside.
    bounds: ([f64; 3], [f64; 3]),
    stats: RefinedStats,
}

impl<'a> Refiner<'a> {
    fn new(domain: &'a dyn Domain, field: &'a SpacingField, options: &'a RefinedOptions) -> Self {
        let (lo, hi) = domain.bounds();
        let t = Triangulation::new(lo, hi);
        let margin = 1e-6 * (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let bounds = (lo.map(|c| c - margin), hi.map(|c| c + margin));
        let mut refiner = Refiner {
            domain,
            field,
            options,
            on_boundary: vec![false; t.points.len()],
            cells: Vec::new(),
            made_at: Vec::new(),
            insertion: 0,
            facets: VecDeque::new(),
            cells_to_split: VecDeque::new(),
            live: 1,
            bounds,
            stats: RefinedStats::default(),
            t,
        };
        refiner.made(&[0]);
        refiner
    }

    /// Insert the boundary samples, in Morton order (their faces and cells are
    /// evaluated as they come, and queued).
    ///
    /// The tets are evaluated once all samples are in (most tets made on the way are
    /// gone by then): circumcentres and labels, then faces, each in parallel.
    fn seed(&mut self, samples: &[Sample]) {
        let points: Vec<[f64; 3]> = samples.iter().map(|s| s.position).collect();
        let (lo, hi) = crate::geom::bounds(points.iter().copied());
        for i in super::delaunay::morton_order(&points, lo, hi) {
            let v = self.t.points.len() as u32;
            self.t.points.push(points[i as usize]);
            match self.t.cavity(v) {
                Ok(cavity) => {
                    self.on_boundary.push(true);
                    let made = self.t.fill(v, &cavity);
                    self.live = self.live + made.len() - cavity.tets.len();
                    self.stats.seeds += 1;
                }
                Err(_) => {
                    self.t.points.pop();
                }
            }
        }
        let live: Vec<u32> = (0..self.t.tets.len() as u32)
            .filter(|&s| self.t.alive[s as usize])
            .collect();
        self.cells.resize(self.t.tets.len(), Cell::default());
        self.made_at.resize(self.t.tets.len(), 0);
        let spheres: Vec<([f64; 3], f64)> = live
            .par_iter()
            .map(|&s| circumsphere(self.t.tets[s as usize].map(|v| self.t.points[v as usize])))
            .collect();
        let far = FAR_POINTS as u32;
        let labelled: Vec<bool> = live
            .iter()
            .zip(&spheres)
            .map(|(&s, (c, _))| {
                self.t.tets[s as usize].iter().all(|&v| v >= far) && in_box(*c, self.bounds)
            })
            .collect();
        let asked: Vec<[f64; 3]> = spheres
            .iter()
            .zip(&labelled)
            .filter(|(_, &l)| l)
            .map(|(c, _)| c.0)
            .collect();
        let mut values = self.domain.values(&asked).into_iter();
        for ((&s, &(circumcentre, radius2)), &l) in live.iter().zip(&spheres).zip(&labelled) {
            let inside = l
                && values
                    .next()
                    .is_some_and(|v| v < -LABEL_TOLERANCE * radius2.sqrt());
            let generation = self.cells[s as usize].generation.wrapping_add(1);
            self.cells[s as usize] = Cell {
                circumcentre,
                radius2,
                inside,
                generation,
                balls: [None; 4],
            };
        }
        let faces: Vec<(u32, usize)> = live
            .iter()
            .flat_map(|&s| (0..4).map(move |i| (s, i)))
            .filter(|&(s, i)| {
                let n = self.t.neighbours[s as usize][i];
                n != NONE && n > s
            })
            .collect();
        let this = &*self;
        let crossings: Vec<Option<[f64; 3]>> = faces
            .par_iter()
            .map(|&(s, i)| this.face_crossing(s, i))
            .collect();
        for (&(s, i), crossing) in faces.iter().zip(crossings) {
            self.set_face(s, i, crossing);
        }
        for &s in &live {
            self.cell(s);
        }
    }

    /// Refine until no face or cell is bad (or all bad ones are guarded), the boundary
    /// is manifold, or the budget binds.
    fn refine(&mut self) {
        loop {
            while !self.stats.over_budget {
                if let Some(p) = self.facets.pop_front() {
                    if self.valid(&p) && self.insert(p.point, true) {
                        self.stats.surface_points += 1;
                        if p.kind == PointKind::DoubleCrossing {
                            self.stats.double_crossings += 1;
                        }
                    }
                } else if let Some((slot, generation)) = self.cells_to_split.pop_front() {
                    self.split_cell(slot, generation);
                } else {
                    break;
                }
            }
            if self.stats.over_budget {
                break;
            }
            let repairs = self.manifold_repairs();
            if repairs.is_empty() {
                break;
            }
            let mut inserted = 0;
            for p in repairs {
                if self.insert(p, true) {
                    inserted += 1;
                }
            }
            self.stats.surface_points += inserted;
            self.stats.manifold_repairs += inserted;
            if inserted == 0 {
                break;
            }
        }
        self.stats.non_manifold = self.non_manifold_places().len();
    }

    /// Whether a pending point's tets are still the ones it was found in.
    fn valid(&self, p: &Pending) -> bool {
        p.tets.iter().all(|&(slot, generation)| {
            slot == NONE
                || (self.t.alive[slot as usize]
                    && self.cells[slot as usize].generation == generation)
        })
    }

    /// Split an inside cell at its circumcentre, or insert the surface centre of the
    /// boundary face whose surface ball holds the circumcentre.
    fn split_cell(&mut self, slot: u32, generation: u32) {
        let s = slot as usize;
        if !self.t.alive[s] || self.cells[s].generation != generation {
            return;
        }
        let c = self.cells[s].circumcentre;
        let v = self.t.points.len() as u32;
        self.t.points.push(c);
        let cavity = match self.t.cavity(v) {
            Ok(cavity) => cavity,
            Err(_) => {
                self.t.points.pop();
                return;
            }
        };
        // Any boundary face of the cavity's tets whose surface ball holds the point.
        let encroached = cavity.tets.iter().find_map(|&t| {
            self.cells[t as usize]
                .balls
                .iter()
                .flatten()
                .find(|b| dist2(b.centre, c) < b.radius2)
                .copied()
        });
        match encroached {
            Some(ball) => {
                self.t.points.pop();
                self.stats.encroachments += 1;
                if ball.radius2.sqrt() < self.options.guard * self.field.at(ball.centre) {
                    self.stats.accepted_bad += 1;
                } else if self.insert(ball.centre, true) {
                    self.stats.surface_points += 1;
                }
            }
            None => {
                self.apply(v, &cavity, false);
                self.stats.circumcentres += 1;
            }
        }
    }

    /// Insert `p`; false if a vertex is already there (or `p` is not finite).
    fn insert(&mut self, p: [f64; 3], on_boundary: bool) -> bool {
        if !p.iter().all(|c| c.is_finite()) {
            return false;
        }
        let v = self.t.points.len() as u32;
        self.t.points.push(p);
        match self.t.cavity(v) {
            Ok(cavity) => {
                self.apply(v, &cavity, on_boundary);
                true
            }
            Err(_) => {
                self.t.points.pop();
                false
            }
        }
    }

    fn apply(&mut self, v: u32, cavity: &Cavity, on_boundary: bool) {
        debug_assert_eq!(self.on_boundary.len(), v as usize);

        self.on_boundary.push(on_boundary);
        let made = self.t.fill(v, cavity);
        self.live = self.live + made.len() - cavity.tets.len();
        if self.live > self.options.max_tets {
            self.stats.over_budget = true;
        }
        self.made(&made);
    }

    /// Evaluate new tets: their circumcentres and labels, then their faces and cells.
    fn made(&mut self, made: &[u32]) {
        self.insertion += 1;
        let stamp = self.insertion;
        let far = FAR_POINTS as u32;
        for &s in made {
            let s = s as usize;
            if self.cells.len() <= s {
                self.cells.resize(s + 1, Cell::default());
                self.made_at.resize(s + 1, 0);
            }
            self.made_at[s] = stamp;
            let tet = self.t.tets[s];
            let p = tet.map(|v| self.t.points[v as usize]);
            let (centre, radius2) = circumsphere(p);
            let inside = tet.iter().all(|&v| v >= far)
                && in_box(centre, self.bounds)
                && match self.inherited_label(s as u32, centre, stamp) {
                    Some(inside) => inside,
                    None => self.label_value(centre, radius2) < -LABEL_TOLERANCE * radius2.sqrt(),
                };
            let generation = self.cells[s].generation.wrapping_add(1);
            self.cells[s] = Cell {
                circumcentre: centre,
                radius2,
                inside,
                generation,
                balls: [None; 4],
            };
        }
        for &s in made {
            for i in 0..4 {
                let n = self.t.neighbours[s as usize][i];
                if n != NONE && self.made_at[n as usize] == stamp && n < s {
                    continue;
                }
                self.face(s, i);
            }
            self.cell(s);
        }
    }

    /// Evaluate the face of tet `s` opposite corner `i`: on the boundary or not, its
    /// surface ball (kept on both sides), and whether it must be refined.
    fn face(&mut self, s: u32, i: usize) {
        if self.t.neighbours[s as usize][i] == NONE {
            return;
        }
        let crossing = self.face_crossing(s, i);
        self.set_face(s, i, crossing);
    }

    /// Where the dual Voronoi edge of tet `s`'s face opposite corner `i` crosses the
    /// boundary: the crossing between cells of two labels, the first crossing between
    /// cells of one label (a double crossing), or none.
    fn face_crossing(&self, s: u32, i: usize) -> Option<[f64; 3]> {
        let n = self.t.neighbours[s as usize][i];
        let (a, b) = (&self.cells[s as usize], &self.cells[n as usize]);
        let (c1, c2) = (a.circumcentre, b.circumcentre);
        if a.inside != b.inside {
            Some(self.crossing(c1, c2, a.inside))
        } else {
            // Only the part within the domain's box can cross its boundary (a cell on
            // the hull has its circumcentre far out).
            clip(c1, c2, self.bounds).and_then(|(p, q)| {
                self.domain
                    .crossing(p, q)
                    .map(|t| add(p, scale(sub(q, p), t)))
            })
        }
    }

    /// Keep the face's surface ball (if it is on the boundary), and queue its point if
    /// the face must be refined.
    fn set_face(&mut self, s: u32, i: usize, crossing: Option<[f64; 3]>) {
        let n = self.t.neighbours[s as usize][i];
        if n == NONE {
            return;
        }
        let j = self.t.neighbours[n as usize]
            .iter()
            .position(|&m| m == s)
            .expect("neighbours point at each other");
        let (a, b) = (self.cells[s as usize], self.cells[n as usize]);
        let corners: Vec<u32> = (0..4)
            .filter(|&k| k != i)
            .map(|k| self.t.tets[s as usize][k])
            .collect();
        let tets = [(s, a.generation), (n, b.generation)];
        let ball = crossing.map(|centre| Ball {
            centre,
            radius2: dist2(centre, self.t.points[corners[0] as usize]),
        });
        let boundary = a.inside != b.inside;
        self.cells[s as usize].balls[i] = ball.filter(|_| boundary);
        self.cells[n as usize].balls[j] = ball.filter(|_| boundary);
        let Some(ball) = ball else { return };
        if corners.iter().any(|&v| (v as usize) < FAR_POINTS) {
            return;
        }
        let spacing = self.field.at(ball.centre);
        let radius = ball.radius2.sqrt();
        let bad = if !boundary {
            true
        } else {
            let p = [0, 1, 2].map(|k| self.t.points[corners[k] as usize]);
            radius > self.options.facet_size * spacing
                || corners.iter().any(|&v| !self.on_boundary[v as usize])
                || has_angle_below(p, self.options.facet_angle_deg.to_radians().cos())
        };
        if !bad {
            return;
        }
        if radius < self.options.guard * spacing {
            self.stats.accepted_bad += 1;
            return;
        }
        self.facets.push_back(Pending {
            point: ball.centre,
            tets,
            kind: if boundary {
                PointKind::Surface
            } else {
                PointKind::DoubleCrossing
            },
        });
    }

    /// The label of new tet `s` (circumcentre `centre`) from its old neighbour across
    /// the face opposite the new vertex, where the segment between their circumcentres
    /// crosses no boundary, cast both ways (a ray skips hits at its very start). `None`
    /// where that cannot be said: no such neighbour, a crossing, or a tet of four
    /// boundary vertices (a flat one has its circumcentre on the boundary, where
    /// [`LABEL_TOLERANCE`] decides).
    fn inherited_label(&self, s: u32, centre: [f64; 3], stamp: u32) -> Option<bool> {
        let tet = self.t.tets[s as usize];
        if tet.iter().all(|&v| self.on_boundary[v as usize]) {
            return None;
        }
        let v = (self.t.points.len() - 1) as u32;
        let i = tet.iter().position(|&c| c == v)?;
        let n = self.t.neighbours[s as usize][i];
        if n == NONE
            || self.made_at[n as usize] == stamp
            || self.t.tets[n as usize]
                .iter()
                .any(|&c| (c as usize) < FAR_POINTS)
        {
            return None;
        }
        let from = self.cells[n as usize].circumcentre;
        if !in_box(from, self.bounds) {
            return None;
        }
        let crosses = self.domain.crossing(from, centre).is_some()
            || self.domain.crossing(centre, from).is_some();
        (!crosses).then_some(self.cells[n as usize].inside)
    }

    /// The domain's value at a cell's circumcentre, exact within a quarter of its
    /// circumradius of the boundary and of the right sign beyond (only the sign
    /// labels the cell, and far from the boundary it is cheaper than the distance).
    fn label_value(&self, centre: [f64; 3], radius2: f64) -> f64 {
        self.domain
            .values_within(&[centre], LABEL_BAND * radius2.sqrt())[0]
    }

    /// Queue tet `s` for splitting if it is inside and badly shaped or too large.
    fn cell(&mut self, s: u32) {
        let cell = self.cells[s as usize];
        if !cell.inside {
            return;
        }
        let p = self.t.tets[s as usize].map(|v| self.t.points[v as usize]);
        let radius = cell.radius2.sqrt();
        let shortest = (0..4)
            .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
            .map(|(a, b)| dist2(p[a], p[b]))
            .fold(f64::INFINITY, f64::min)
            .sqrt();
        let spacing = self.field.at(cell.circumcentre);
        let bad = radius > self.options.radius_edge * shortest
            || radius > self.options.cell_size * spacing;
        if !bad {
            return;
        }
        if radius < self.options.guard * spacing {
            self.stats.accepted_bad += 1;
            return;
        }
        self.cells_to_split.push_back((s, cell.generation));
    }

    /// Where the segment from `a` (inside when `a_inside`) to `b` (the other label)
    /// crosses the boundary: the domain's ray cast, else bisection of its sign.
    fn crossing(&self, a: [f64; 3], b: [f64; 3], a_inside: bool) -> [f64; 3] {
        let (a, b) = clip(a, b, self.bounds).unwrap_or((a, b));
        if let Some(t) = self.domain.crossing(a, b) {
            return add(a, scale(sub(b, a), t));
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let inside = self.domain.value(add(a, scale(sub(b, a), mid))) < 0.0;
            if inside == a_inside {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        add(a, scale(sub(b, a), 0.5 * (lo + hi)))
    }

    /// The boundary faces: (inside tet, corner opposite), each once.
    fn boundary_faces(&self) -> Vec<(u32, usize)> {
        let mut faces = Vec::new();
        for (s, cell) in self.cells.iter().enumerate() {
            if !self.t.alive[s] || !cell.inside {
                continue;
            }
            for i in 0..4 {
                let n = self.t.neighbours[s][i];
                if n == NONE || !self.cells[n as usize].inside {
                    faces.push((s as u32, i));
                }
            }
        }
        faces
    }

    /// The boundary's non-manifold places: per edge with more than two faces and per
    /// vertex whose faces are not one fan, the faces there.
    fn non_manifold_places(&self) -> Vec<Vec<(u32, usize)>> {
        let faces = self.boundary_faces();
        let corners = |&(s, i): &(u32, usize)| -> [u32; 3] {
            let t = self.t.tets[s as usize];
            let mut c = [0u32; 3];
            let mut k = 0;
            for (m, &v) in t.iter().enumerate() {
                if m != i {
                    c[k] = v;
                    k += 1;
                }
            }
            c
        };
        let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::default();
        let mut by_vertex: HashMap<u32, Vec<usize>> = HashMap::default();
        for (f, face) in faces.iter().enumerate() {
            let c = corners(face);
            for k in 0..3 {
                let (u, w) = (c[k], c[(k + 1) % 3]);
                by_edge.entry((u.min(w), u.max(w))).or_default().push(f);
                by_vertex.entry(c[k]).or_default().push(f);
            }
        }
        let mut places: Vec<Vec<usize>> = by_edge
            .values()
            .filter(|fs| fs.len() > 2)
            .cloned()
            .collect();
        for (&v, fs) in &by_vertex {
            // The link: the edges opposite `v` in its faces; one fan is one cycle.
            let mut link: HashMap<u32, Vec<u32>> = HashMap::default();
            for &f in fs {
                let c = corners(&faces[f]);
                let others: Vec<u32> = c.iter().copied().filter(|&u| u != v).collect();
                link.entry(others[0]).or_default().push(others[1]);
                link.entry(others[1]).or_default().push(others[0]);
            }
            let start = *link.keys().min().expect("a face");
            let mut seen = vec![start];
            let mut stack = vec![start];
            while let Some(u) = stack.pop() {
                for &w in &link[&u] {
                    if !seen.contains(&w) {
                        seen.push(w);
                        stack.push(w);
                    }
                }
            }
            if seen.len() < link.len() {
                places.push(fs.clone());
            }
        }
        places.sort_unstable();
        places
            .into_iter()
            .map(|fs| fs.into_iter().map(|f| faces[f]).collect())
            .collect()
    }

    /// Per non-manifold place, the surface centre of its widest face (not guarded).
    fn manifold_repairs(&mut self) -> Vec<[f64; 3]> {
        let mut points: Vec<[f64; 3]> = Vec::new();
        for faces in self.non_manifold_places() {
            let widest = faces
                .iter()
                .filter_map(|&(s, i)| self.cells[s as usize].balls[i])
                .max_by(|a, b| a.radius2.total_cmp(&b.radius2));
            let Some(ball) = widest else { continue };
            if ball.radius2.sqrt() < self.options.guard * self.field.at(ball.centre) {
                self.stats.accepted_bad += 1;
                continue;
            }
            if !points.contains(&ball.centre) {
                points.push(ball.centre);
            }
        }
        points
    }

    /// The inside tets, renumbered from 0 and positively oriented, their positions, and
    /// which vertices are on their boundary.
    fn inside_tets(&mut self) -> (Vec<[f64; 3]>, Vec<[u32; 4]>, Vec<bool>) {
        let far = FAR_POINTS as u32;
        self.stats.delaunay_tets = (0..self.cells.len())
            .filter(|&s| self.t.alive[s] && self.t.tets[s].iter().all(|&v| v >= far))
            .count();
        let inside: Vec<usize> = (0..self.cells.len())
            .filter(|&s| self.t.alive[s] && self.cells[s].inside)
            .collect();
        // A flat tet of four boundary vertices (on a planar part of the boundary) adds
        // no volume, and splitting its chords at their midpoints could invert it: the
        // labels keep them out (see [`LABEL_TOLERANCE`]); they are counted.
        let flat = |s: &usize| {
            let t = self.t.tets[*s];
            t.iter().all(|&v| self.on_boundary[v as usize])
                && relative_volume(t.map(|v| self.t.points[v as usize])) < FLAT
        };
        self.stats.flat_slivers = inside.iter().filter(|s| flat(s)).count();
        let kept: Vec<[u32; 4]> = inside
            .iter()
            // Shewchuk's positive orientation is our negative one.
            .map(|&s| {
                let t = self.t.tets[s];
                [t[1], t[0], t[2], t[3]]
            })
            .collect();
        self.stats.kept_tets = kept.len();
        let (new_of_old, old_of_new) = renumber_used(self.t.points.len(), &kept);
        let tets: Vec<[u32; 4]> = kept
            .iter()
            .map(|t| t.map(|v| new_of_old[v as usize]))
            .collect();
        let positions: Vec<[f64; 3]> = old_of_new
            .iter()
            .map(|&v| self.t.points[v as usize])
            .collect();
        let mut on_boundary = vec![false; positions.len()];
        for f in crate::tet::boundary_faces_of(tets.iter().copied()) {
            for v in f {
                on_boundary[v as usize] = true;
            }
        }
        self.stats.off_boundary = (0..positions.len())
            .filter(|&v| on_boundary[v] && !self.on_boundary[old_of_new[v] as usize])
            .count();
        (positions, tets, on_boundary)
    }
}

fn in_box(p: [f64; 3], (lo, hi): ([f64; 3], [f64; 3])) -> bool {
    (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k])
}

/// The part of the segment `a`–`b` within the box (`None`: it misses the box).
fn clip(a: [f64; 3], b: [f64; 3], (lo, hi): ([f64; 3], [f64; 3])) -> Option<([f64; 3], [f64; 3])> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (u, w) = ((lo[k] - a[k]) / d, (hi[k] - a[k]) / d);
        t0 = t0.max(u.min(w));
        t1 = t1.min(u.max(w));
    }
    if t0 > t1 || !t0.is_finite() || !t1.is_finite() {
        return None;
    }
    let at = |t: f64| add(a, scale(sub(b, a), t));
    Some((at(t0), at(t1)))
}

/// A cell is inside when the domain's value at its circumcentre is below minus this
/// times its circumradius. A flat sliver of four points on a planar part of the
/// boundary (their coordinates off the plane by rounding) has its circumcentre on the
/// boundary: it is outside, so the boundary passes beneath it (either side bounds the
/// same volume, and an inside one would be flat in the mesh).
pub const LABEL_TOLERANCE: f64 = 1e-9;

/// A cell's label asks for the domain's exact value within this fraction of its
/// circumradius of the boundary (and only its sign beyond).
const LABEL_BAND: f64 = 0.25;

/// A tet's volume over its longest edge cubed, under which four boundary vertices make
/// a flat sliver (six times a regular tet's is 0.118; refined slivers of real meshes
/// stay above 1e-3, flat ones on a plane fall under 1e-12).
pub const FLAT: f64 = 1e-9;

/// Six times a tet's signed volume over its longest edge cubed.
fn relative_volume(p: [[f64; 3]; 4]) -> f64 {
    let volume = dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0])));
    let longest = (0..4)
        .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
        .map(|(a, b)| dist2(p[a], p[b]))
        .fold(0.0, f64::max);
    volume.abs() / longest.powf(1.5)
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

/// A tet's circumcentre and squared circumradius (relative to its first corner). A tet
/// too flat for the formula in floating point (its circumcentre not finite) gets its
/// centroid and the largest squared distance from it to a corner.
fn circumsphere(p: [[f64; 3]; 4]) -> ([f64; 3], f64) {
    let (u, v, w) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let det = 2.0 * dot(u, cross(v, w));
    let num = add(
        add(scale(cross(v, w), dot(u, u)), scale(cross(w, u), dot(v, v))),
        scale(cross(u, v), dot(w, w)),
    );
    let offset = scale(num, 1.0 / det);
    let centre = add(p[0], offset);
    if centre.iter().all(|c| c.is_finite()) {
        return (centre, dot(offset, offset));
    }
    let centroid = scale(add(add(p[0], p[1]), add(p[2], p[3])), 0.25);
    let radius2 = p.iter().map(|&q| dist2(q, centroid)).fold(0.0, f64::max);
    (centroid, radius2)
}

/// Whether a triangle has an angle whose cosine is above `cos_bound` (an angle below
/// the bound's angle, for bounds up to 90°).
fn has_angle_below(p: [[f64; 3]; 3], cos_bound: f64) -> bool {
    (0..3).any(|k| {
        let (a, b) = (sub(p[(k + 1) % 3], p[k]), sub(p[(k + 2) % 3], p[k]));
        let d = dot(a, b);
        // cos > bound, without the square roots: d > bound·|a||b|.
        d > 0.0 && d * d > cos_bound * cos_bound * dot(a, a) * dot(b, b)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circumsphere_passes_through_the_four_corners_and_a_flat_tet_gets_a_finite_one() {
        let p = [
            [0.1, 0.2, 0.3],
            [2.0, 0.1, -0.4],
            [0.3, 1.7, 0.2],
            [-0.2, 0.4, 1.9],
        ];
        let (c, r2) = circumsphere(p);
        for q in p {
            assert!((dist2(c, q) - r2).abs() < 1e-12 * r2, "{q:?}");
        }
        let flat = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let (c, r2) = circumsphere(flat);
        assert!(c.iter().all(|x| x.is_finite()) && r2.is_finite() && r2 > 0.0);
        assert_eq!(relative_volume(flat), 0.0);
        assert!(relative_volume(p) > FLAT);
    }

    #[test]
    fn a_triangle_has_an_angle_below_a_bound_when_its_smallest_is() {
        let cos20 = 20f64.to_radians().cos();
        let equilateral = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.75f64.sqrt(), 0.0]];
        assert!(!has_angle_below(equilateral, cos20));
        assert!(has_angle_below(equilateral, 61f64.to_radians().cos()));
        let needle = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.1, 0.0]];
        assert!(has_angle_below(needle, cos20));
        let obtuse = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.2, 0.0]];
        // Angles 21.8°, 21.8° and 136.4°.
        assert!(!has_angle_below(obtuse, cos20));
        assert!(has_angle_below(obtuse, 22f64.to_radians().cos()));
    }

    #[test]
    fn a_segment_is_clipped_to_the_box_or_missed() {
        let unit = ([0.0; 3], [1.0; 3]);
        let (a, b) = clip([-1.0, 0.5, 0.5], [3.0, 0.5, 0.5], unit).expect("it crosses");
        assert_eq!((a, b), ([0.0, 0.5, 0.5], [1.0, 0.5, 0.5]));
        assert!(clip([-1.0, 2.0, 0.5], [3.0, 2.0, 0.5], unit).is_none());
        assert!(clip([2.0, 2.0, 2.0], [3.0, 3.0, 3.0], unit).is_none());
        let inside = ([0.2, 0.3, 0.4], [0.6, 0.7, 0.8]);
        assert_eq!(clip(inside.0, inside.1, unit), Some(inside));
    }
}
