//! Membrane loops: the initial loop around a saddle where no plane through it
//! closes around it (a hole whose rim rises and falls, a window with curved wires).
//!
//! The membrane of a 2-saddle is its descending 2-manifold: the points whose steepest
//! ascent ends at the saddle, a disk spanning the neck whose boundary on the surface is
//! the neck loop. We build it for the exact distance to the surface, whose steepest
//! descent from a point runs straight to the point's closest surface point:
//! 1. *ring*: points at radius `ring_radius × d(saddle)` around the saddle in the plane
//!    normal to the cutting normal (the saddle's two descending directions span that
//!    plane); inside the empty ball of radius d(saddle), so in the volume;
//! 2. *landing*: each ring point's closest surface point; where two neighbours land
//!    farther apart than `landing_gap × d(saddle)`, the ring is refined between them, up
//!    to `max_refinements` halvings of the angle step. Neighbours still apart at the
//!    finest step lie on both sides of a medial sheet (the two walls of a slot): there
//!    the membrane runs along the sheet to the slot's end, so the ray from the saddle
//!    through the ring between them lands there too;
//! 3. *join*: consecutive landing triangles by shortest paths across edges (Dijkstra on
//!    the dual graph, centroid to centroid); where the closest point jumps (across the
//!    medial axis of a flat neck) this path goes around the rim between the two sides;
//! 4. *clean*: drop back-and-forth steps and split the face cycle where it visits a
//!    face twice, keeping the shortest part that goes once around the saddle's axis;
//! 5. *check*: the curve (through its edge midpoints) winds once around the axis
//!    through the saddle along the normal, projected on the ring's plane.
//!
//! Units are those of the surface. The result is in the form [`super::tighten::tighten`]
//! takes (crossings at edge midpoints and the faces between them), together with the
//! ring and its landing points, which span the membrane. Entry point: [`membrane_loop`].

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use serde::{Deserialize, Serialize};

use super::cut::{plane_basis, Crossing};
use crate::distance::{Closest, SurfaceDistance};
use crate::geom::{add, dot, lerp, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Options of [`membrane_loop`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MembraneOptions {
    /// Ring radii to try, as fractions of the saddle's distance to the surface, in
    /// order; the first whose boundary goes once around the axis wins. Default
    /// `[0.5, 0.8, 0.25]`: a saddle off the neck's axis by δ needs a ring wider than δ.
    pub ring_radii: [f64; 3],
    /// Ring points to start with. Default 64.
    pub ring_points: usize,
    /// Neighbouring landings farther apart than this × d(saddle) get a ring point
    /// between them. Default 0.1.
    pub landing_gap: f64,
    /// At most this many halvings of the starting angle step. Default 6.
    pub max_refinements: usize,
    /// A join between two landings gives up after settling this many triangles.
    /// Default 200 000.
    pub max_settled: usize,
}

impl Default for MembraneOptions {
    fn default() -> Self {
        MembraneOptions {
            ring_radii: [0.5, 0.8, 0.25],
            ring_points: 64,
            landing_gap: 0.1,
            max_refinements: 6,
            max_settled: 200_000,
        }
    }
}

/// A membrane's initial loop.
#[derive(Debug, Clone, PartialEq)]
pub struct MembraneLoop {
    /// Crossings in order along the loop (edge midpoints).
    pub crossings: Vec<Crossing>,
    /// `faces[i]` lies between `crossings[i]` and `crossings[i + 1]` (cyclically).
    pub faces: Vec<u32>,
    /// Where each landing descended from, in order: a point of the ring around the
    /// saddle, or of a medial sheet walked out from it.
    pub sources: Vec<[f64; 3]>,
    /// Each source's closest surface point.
    pub landings: Vec<[f64; 3]>,
}

/// Why no membrane loop was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MembraneFailure {
    /// The saddle lies on the surface (or the surface has no triangles).
    OnSurface,
    /// Two landings could not be joined across edges (a boundary, a non-manifold edge
    /// or another component between them).
    NotClosed,
    /// The path joining two landings is hidden from both by the surface: the membrane
    /// would pass through the solid (a knotted ridge: the trefoil's tunnel bounds a
    /// Seifert surface, not a disk).
    NotEmbedded,
    /// The closed curve does not go once around the saddle's axis for any ring radius:
    /// the descending disk does not span a neck there.
    NotAround,
}

impl std::fmt::Display for MembraneFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            MembraneFailure::OnSurface => "the saddle lies on the surface",
            MembraneFailure::NotClosed => "its landings could not be joined",
            MembraneFailure::NotEmbedded => "it would pass through the solid",
            MembraneFailure::NotAround => "it does not go once around the saddle",
        })
    }
}

/// The initial loop around the saddle at `saddle` with unit cutting normal `normal`,
/// from its membrane (see the module documentation).
pub fn membrane_loop(
    surface: &SurfaceMesh,
    topology: &Topology,
    dual: &DualGraph,
    distance: &SurfaceDistance,
    saddle: [f64; 3],
    normal: [f64; 3],
    options: &MembraneOptions,
) -> Result<MembraneLoop, MembraneFailure> {
    let d = distance.distance(saddle);
    if !(d.is_finite() && d > 0.0) {
        return Err(MembraneFailure::OnSurface);
    }
    let axis = Axis::new(saddle, normal);
    let mut failure = MembraneFailure::NotAround;
    for &radius in &options.ring_radii {
        let (ring, landings) = ring_and_landings(distance, &axis, radius * d, d, options);
        let faces: Vec<u32> = landings.iter().map(|c| c.face).collect();
        let cycle = match join(dual, distance, &ring, &faces, options.max_settled) {
            Ok(cycle) => cycle,
            Err(f) => {
                failure = f;
                continue;
            }
        };
        let Some(cycle) = once_around(surface, topology, &axis, cycle) else {
            continue;
        };
        let crossings = cycle
            .iter()
            .enumerate()
            .map(|(i, &f)| Crossing {
                edge: shared_edge(topology, cycle[(i + cycle.len() - 1) % cycle.len()], f)
                    .expect("consecutive faces share an edge"),
                t: 0.5,
            })
            .collect();
        return Ok(MembraneLoop {
            crossings,
            faces: cycle,
            sources: ring,
            landings: landings.iter().map(|c| c.point).collect(),
        });
    }
    Err(failure)
}

/// A disk bounded by the closed polyline `boundary` (a tightened loop): the fan from
/// `saddle` to the closed polygon `sources` and the strip from it to the boundary, the two
/// polygons matched by arc length from the boundary point nearest `sources[0]` and in the
/// same sense around the axis (`saddle`, `normal`); without sources, the cone from the
/// saddle. Vertices: the saddle, the sources, the boundary; consistently oriented, and
/// χ = 1 by construction.
pub fn spanning_disk(
    saddle: [f64; 3],
    normal: [f64; 3],
    sources: &[[f64; 3]],
    boundary: &[[f64; 3]],
) -> SurfaceMesh {
    let mut positions = vec![saddle];
    let mut triangles = Vec::new();
    let fan = |ring: std::ops::Range<usize>, triangles: &mut Vec<[u32; 3]>| {
        let n = ring.len();
        for k in 0..n {
            let (a, b) = (ring.start + k, ring.start + (k + 1) % n);
            triangles.push([0, a as u32, b as u32]);
        }
    };
    if sources.len() < 3 {
        positions.extend_from_slice(boundary);
        fan(1..positions.len(), &mut triangles);
        return SurfaceMesh {
            positions,
            triangles,
        };
    }
    let axis = Axis::new(saddle, scale(normal, 1.0 / norm(normal)));
    let mut boundary = boundary.to_vec();
    if axis.winding(sources) * axis.winding(&boundary) < 0 {
        boundary.reverse();
    }
    let start = (0..boundary.len())
        .min_by(|&a, &b| {
            let d = |k: usize| norm(sub(boundary[k], sources[0]));
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    boundary.rotate_left(start);
    let (m, k) = (sources.len(), boundary.len());
    positions.extend_from_slice(sources);
    positions.extend_from_slice(&boundary);
    fan(1..1 + m, &mut triangles);
    // Strip: walk both polygons by their arc-length fractions.
    let fractions = |poly: &[[f64; 3]]| {
        let n = poly.len();
        let mut acc = vec![0.0; n + 1];
        for i in 0..n {
            acc[i + 1] = acc[i] + norm(sub(poly[(i + 1) % n], poly[i]));
        }
        let total = acc[n].max(f64::MIN_POSITIVE);
        acc.into_iter().map(|x| x / total).collect::<Vec<f64>>()
    };
    let (fs, fb) = (fractions(sources), fractions(&boundary));
    let s = |i: usize| (1 + i % m) as u32;
    let b = |j: usize| (1 + m + j % k) as u32;
    let (mut i, mut j) = (0, 0);
    while i < m || j < k {
        if j == k || (i < m && fs[i + 1] <= fb[j + 1]) {
            triangles.push([s(i + 1), s(i), b(j)]);
            i += 1;
        } else {
            triangles.push([s(i), b(j), b(j + 1)]);
            j += 1;
        }
    }
    SurfaceMesh {
        positions,
        triangles,
    }
}

/// The line through the saddle along the cutting normal, with a basis of its normal
/// plane.
struct Axis {
    origin: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
}

impl Axis {
    fn new(origin: [f64; 3], normal: [f64; 3]) -> Axis {
        let (u, v) = plane_basis(normal);
        Axis { origin, u, v }
    }

    fn ring_point(&self, radius: f64, angle: f64) -> [f64; 3] {
        let dir = add(scale(self.u, angle.cos()), scale(self.v, angle.sin()));
        add(self.origin, scale(dir, radius))
    }

    /// Angle of `p` around the axis.
    fn angle(&self, p: [f64; 3]) -> f64 {
        let d = sub(p, self.origin);
        dot(d, self.v).atan2(dot(d, self.u))
    }

    /// Turns of the closed polyline around the axis, rounded.
    fn winding(&self, points: &[[f64; 3]]) -> i64 {
        let n = points.len();
        let mut total = 0.0;
        for i in 0..n {
            let mut step = self.angle(points[(i + 1) % n]) - self.angle(points[i]);
            if step > std::f64::consts::PI {
                step -= std::f64::consts::TAU;
            } else if step < -std::f64::consts::PI {
                step += std::f64::consts::TAU;
            }
            total += step;
        }
        (total / std::f64::consts::TAU).round() as i64
    }
}

/// The ring of `radius` around the axis and its landings, refined where neighbours land
/// more than `landing_gap × d` apart.
fn ring_and_landings(
    distance: &SurfaceDistance,
    axis: &Axis,
    radius: f64,
    d: f64,
    options: &MembraneOptions,
) -> (Vec<[f64; 3]>, Vec<Closest>) {
    let n = options.ring_points.max(3);
    let step = std::f64::consts::TAU / n as f64;
    let gap = options.landing_gap * d;
    let land = |angle: f64| {
        let p = axis.ring_point(radius, angle);
        (p, distance.closest_point(p))
    };
    let mut ring = Vec::new();
    let mut landings = Vec::new();
    for i in 0..n {
        let (a0, a1) = (i as f64 * step, (i + 1) as f64 * step);
        // Depth-first refinement of [a0, a1); only its start point is emitted.
        let mut stack = vec![(a0, land(a0), a1, land(a1), 0)];
        while let Some((a, la, b, lb, depth)) = stack.pop() {
            let far = norm(sub(la.1.point, lb.1.point)) > gap;
            if far && depth < options.max_refinements {
                let m = 0.5 * (a + b);
                let lm = land(m);
                stack.push((m, lm, b, lb, depth + 1));
                stack.push((a, la, m, lm, depth + 1));
                continue;
            }
            ring.push(la.0);
            landings.push(la.1);
            if far {
                // Still apart at the finest step: the ring crosses a medial sheet (a
                // slot whose two walls the neighbours land on). The membrane follows the
                // sheet out to the slot's end: walk it and land both walls on the way.
                let m = 0.5 * (a + b);
                let p = axis.ring_point(radius, m);
                for (source, landing) in sheet_walk(distance, p, sub(p, axis.origin), d, la.1.point)
                {
                    ring.push(source);
                    landings.push(landing);
                }
            }
        }
    }
    (ring, landings)
}

/// Walk the medial sheet from `start` (a point on it between two walls) in direction
/// `dir` until the sheet meets the surface: the landings on the wall nearer `from`
/// outwards, the end, then the other wall's inwards. Each step re-centres the point
/// between the walls (its closest point, and the ray away from it) and moves on by half
/// the local half-width along the sheet; the walk ends where the nearest wall lies ahead
/// (the slot's end), where no other wall is hit, or after 256 steps.
fn sheet_walk(
    distance: &SurfaceDistance,
    start: [f64; 3],
    dir: [f64; 3],
    d: f64,
    from: [f64; 3],
) -> Vec<([f64; 3], Closest)> {
    let mut p = start;
    let mut dir = scale(dir, 1.0 / norm(dir));
    type Landed = ([f64; 3], Closest);
    let (mut near, mut far): (Vec<Landed>, Vec<Landed>) = (Vec::new(), Vec::new());
    let mut end = None;
    for _ in 0..256 {
        let a = distance.closest_point(p);
        if a.face == Closest::NO_FACE || a.distance <= 1e-3 * d {
            end = Some((p, a));
            break;
        }
        let to_a = sub(a.point, p);
        if dot(to_a, dir) > 0.5 * a.distance {
            end = Some((p, a));
            break;
        }
        let u = scale(to_a, -1.0 / a.distance);
        let Some((t, face)) = distance.ray_hit(p, u, f64::INFINITY) else {
            end = Some((p, a));
            break;
        };
        let b = Closest {
            point: add(p, scale(u, t)),
            distance: t,
            face,
        };
        let half = 0.5 * (a.distance + t);
        // Which wall is on `from`'s side.
        let centre = add(a.point, scale(u, half));
        let a_is_near = match near.last() {
            None => norm(sub(a.point, from)) <= norm(sub(b.point, from)),
            Some((_, n)) => norm(sub(a.point, n.point)) <= norm(sub(b.point, n.point)),
        };
        let (n, f) = if a_is_near { (a, b) } else { (b, a) };
        near.push((centre, n));
        far.push((centre, f));
        let along = sub(dir, scale(u, dot(dir, u)));
        if norm(along) < 1e-6 {
            break;
        }
        dir = scale(along, 1.0 / norm(along));
        p = add(centre, scale(dir, 0.5 * half));
    }
    near.extend(end);
    near.extend(far.into_iter().rev());
    near
}

/// The closed cycle of faces through the landing faces in order, each joined to the next
/// by a shortest path across edges; back-and-forth steps removed. `None` when a join
/// fails or a landing has no face.
///
/// The membrane between two landings is the fan from their sources (the ring or sheet
/// points they descended from) to the path joining them; it must not pass through the
/// surface. A path face that neither source sees is [`MembraneFailure::NotEmbedded`]:
/// the joining path went round the other side of a part, as on a knotted tube, whose
/// tunnel bounds a Seifert surface but no disk.
fn join(
    dual: &DualGraph,
    distance: &SurfaceDistance,
    sources: &[[f64; 3]],
    landing_faces: &[u32],
    max_settled: usize,
) -> Result<Vec<u32>, MembraneFailure> {
    if landing_faces.contains(&Closest::NO_FACE) {
        return Err(MembraneFailure::NotClosed);
    }
    let sees = |from: [f64; 3], f: u32| {
        let dir = sub(dual.centroids[f as usize], from);
        distance.ray_hit(from, dir, 0.8).is_none()
    };
    let mut cycle: Vec<u32> = Vec::new();
    let n = landing_faces.len();
    for i in 0..n {
        let j = (i + 1) % n;
        let (a, b) = (landing_faces[i], landing_faces[j]);
        let path = dual_path(dual, a, b, max_settled).ok_or(MembraneFailure::NotClosed)?;
        if path.len() > 2
            && path[1..path.len() - 1]
                .iter()
                .any(|&f| !sees(sources[i], f) && !sees(sources[j], f))
        {
            return Err(MembraneFailure::NotEmbedded);
        }
        // The path's last face is the next path's first.
        cycle.extend_from_slice(&path[..path.len() - 1]);
    }
    Ok(without_backtracking(cycle))
}

/// The graph the face-path searches (`dual_path`) run on: per face of a surface, its
/// centroid and the faces across its manifold edges. Built once per surface
/// ([`DualGraph::new`], `O(F)`): a search on a crossing model's meshed boundary settles
/// tens of thousands of faces, each step reading its neighbours' centroids and
/// neighbours (one table look-up each, not three corners and two edge tables).
#[derive(Debug, Clone)]
pub struct DualGraph {
    /// Per face: the mean of its corners.
    centroids: Vec<[f64; 3]>,
    /// Per face: the face across each side (from corner `i` to `i + 1`), or
    /// [`DualGraph::NONE`] where that edge is not manifold.
    across: Vec<[u32; 3]>,
}

impl DualGraph {
    /// No face across a side.
    const NONE: u32 = u32::MAX;

    /// The dual graph of `surface`, whose topology is `topology`.
    pub fn new(surface: &SurfaceMesh, topology: &Topology) -> DualGraph {
        let centroids = surface
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| surface.positions[v as usize]);
                scale(add(add(a, b), c), 1.0 / 3.0)
            })
            .collect();
        let across = (0..surface.triangles.len())
            .map(|f| {
                [0, 1, 2].map(|i| {
                    topology
                        .across(f, i)
                        .map_or(DualGraph::NONE, |(g, _)| g as u32)
                })
            })
            .collect();
        DualGraph { centroids, across }
    }

    /// Faces adjacent to `f` across its manifold edges, in side order.
    fn neighbours(&self, f: u32) -> impl Iterator<Item = u32> + '_ {
        self.across[f as usize]
            .into_iter()
            .filter(|&g| g != DualGraph::NONE)
    }
}

pub(super) fn shared_edge(topology: &Topology, f: u32, g: u32) -> Option<u32> {
    (0..3)
        .filter_map(|i| topology.face_edge(f as usize, i))
        .find(|&e| topology.edge_faces(e).contains(&g))
        .map(|e| e as u32)
}

/// Shortest path of faces from `a` to `b` (both included) across manifold edges, by
/// centroid distance; `None` when `b` is not reached within `max_settled` faces. A*
/// with the straight distance to `b`'s centroid, which never overestimates (and is
/// consistent: a step's length bounds the change of the distance), so the path is a
/// shortest one and only faces towards `b` are searched. The faces' labels live in a
/// per-thread [`Search`], reused across calls: a membrane's joins are many and mostly
/// short, but on a crossing model's meshed boundary one in a hundred settles 40–90 k
/// faces (a hash map there was most of the join's time).
pub(super) fn dual_path(dual: &DualGraph, a: u32, b: u32, max_settled: usize) -> Option<Vec<u32>> {
    if a == b {
        return Some(vec![a]);
    }
    SEARCH.with_borrow_mut(|search| {
        search.start(dual.centroids.len());
        let centroid = |f: u32| dual.centroids[f as usize];
        let target = centroid(b);
        let estimate = |c: [f64; 3]| norm(sub(target, c));
        // Non-negative floats order like their bit patterns.
        let mut heap = BinaryHeap::new();
        search.set(a, 0.0, a);
        heap.push(Reverse((estimate(centroid(a)).to_bits(), a)));
        let mut settled = 0;
        while let Some(Reverse((_, f))) = heap.pop() {
            if f == b {
                let mut path = vec![b];
                let mut x = b;
                while x != a {
                    x = search.get(x)?.1;
                    path.push(x);
                }
                path.reverse();
                return Some(path);
            }
            settled += 1;
            if settled > max_settled {
                return None;
            }
            let df = search.get(f)?.0;
            let cf = centroid(f);
            for g in dual.neighbours(f) {
                let cg = centroid(g);
                let dg = df + norm(sub(cg, cf));
                if search.get(g).is_none_or(|(old, _)| dg < old) {
                    search.set(g, dg, f);
                    heap.push(Reverse(((dg + estimate(cg)).to_bits(), g)));
                }
            }
        }
        None
    })
}

thread_local! {
    /// [`dual_path`]'s labels, one per thread.
    static SEARCH: std::cell::RefCell<Search> = std::cell::RefCell::default();
}

/// Per face: the distance from the search's start and the previous face, valid where
/// the face's stamp is the current search's (no clearing between searches).
#[derive(Debug, Default)]
struct Search {
    stamp: Vec<u32>,
    label: Vec<(f64, u32)>,
    current: u32,
}

impl Search {
    /// A new search over `faces` faces: no face labelled.
    fn start(&mut self, faces: usize) {
        if self.stamp.len() < faces {
            self.stamp.resize(faces, 0);
            self.label.resize(faces, (0.0, 0));
        }
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            // After 2³² searches: forget every stamp.
            self.stamp.fill(0);
            self.current = 1;
        }
    }

    fn get(&self, f: u32) -> Option<(f64, u32)> {
        (self.stamp.get(f as usize) == Some(&self.current)).then(|| self.label[f as usize])
    }

    fn set(&mut self, f: u32, distance: f64, previous: u32) {
        if let Some(stamp) = self.stamp.get_mut(f as usize) {
            *stamp = self.current;
            self.label[f as usize] = (distance, previous);
        }
    }
}

/// The cyclic face sequence without steps that go straight back (… f g f … → … f …)
/// and without a face repeated next to itself.
pub(super) fn without_backtracking(cycle: Vec<u32>) -> Vec<u32> {
    let mut stack: Vec<u32> = Vec::with_capacity(cycle.len());
    for f in cycle {
        if stack.last() == Some(&f) {
            continue;
        }
        if stack.len() >= 2 && stack[stack.len() - 2] == f {
            stack.pop();
            continue;
        }
        stack.push(f);
    }
    // The same across the seam.
    loop {
        let n = stack.len();
        if n >= 2 && stack[0] == stack[n - 1] {
            stack.pop();
        } else if n >= 3 && stack[1] == stack[n - 1] {
            stack.pop();
            stack.remove(0);
        } else if n >= 3 && stack[0] == stack[n - 2] {
            stack.pop();
            stack.pop();
        } else {
            return stack;
        }
    }
}

/// Split the face cycle wherever it visits a face twice and keep the shortest simple
/// part that goes once around the axis.
fn once_around(
    surface: &SurfaceMesh,
    topology: &Topology,
    axis: &Axis,
    cycle: Vec<u32>,
) -> Option<Vec<u32>> {
    let mut pending = vec![cycle];
    let mut best: Option<(f64, Vec<u32>)> = None;
    while let Some(c) = pending.pop() {
        let c = without_backtracking(c);
        if c.len() < 3 {
            continue;
        }
        let mut first: HashMap<u32, usize> = HashMap::new();
        let repeat = c
            .iter()
            .enumerate()
            .find_map(|(j, &f)| first.insert(f, j).map(|i| (i, j)));
        if let Some((i, j)) = repeat {
            pending.push(c[i..j].to_vec());
            pending.push(c[j..].iter().chain(&c[..i]).copied().collect());
            continue;
        }
        let points = midpoints(surface, topology, &c);
        if axis.winding(&points).abs() != 1 {
            continue;
        }
        let length = super::cut::closed_length(&points);
        if best.as_ref().is_none_or(|(l, _)| length < *l) {
            best = Some((length, c));
        }
    }
    best.map(|(_, c)| c)
}

/// The midpoints of the edges between consecutive faces of a cycle.
fn midpoints(surface: &SurfaceMesh, topology: &Topology, cycle: &[u32]) -> Vec<[f64; 3]> {
    let n = cycle.len();
    (0..n)
        .map(|i| {
            let e = shared_edge(topology, cycle[(i + n - 1) % n], cycle[i])
                .expect("consecutive faces share an edge");
            let [a, b] = topology.edges()[e as usize];
            lerp(
                surface.positions[a as usize],
                surface.positions[b as usize],
                0.5,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn back_and_forth_steps_are_removed_also_across_the_seam() {
        assert_eq!(without_backtracking(vec![1, 2, 3, 2, 4]), vec![1, 2, 4]);
        assert_eq!(without_backtracking(vec![1, 2, 2, 3]), vec![1, 2, 3]);
        assert_eq!(without_backtracking(vec![5, 1, 2, 3, 1]), vec![1, 2, 3]);
        assert_eq!(without_backtracking(vec![1, 2, 3, 4, 1]), vec![1, 2, 3, 4]);
    }

    #[test]
    fn face_paths_on_the_icosahedron_follow_its_dual_dodecahedron() {
        let (corners, faces) = crate::geom::icosahedron();
        let surface = SurfaceMesh::new(corners.to_vec(), faces.to_vec()).unwrap();
        let topology = Topology::new(&surface);
        let dual = DualGraph::new(&surface, &topology);
        for f in 0..20u32 {
            let around: Vec<u32> = dual.neighbours(f).collect();
            // Every face has three neighbours, each of which has it back, and its
            // centroid is the mean of its corners.
            assert_eq!(around.len(), 3);
            assert!(around.iter().all(|&g| dual.neighbours(g).any(|h| h == f)));
            let mean = scale(
                faces[f as usize]
                    .iter()
                    .fold([0.0; 3], |m, &v| add(m, corners[v as usize])),
                1.0 / 3.0,
            );
            assert!(norm(sub(mean, dual.centroids[f as usize])) < 1e-12);
            // The dodecahedron's graph has diameter 5: a shortest path reaches every
            // face in at most 5 steps, each between neighbours, and the opposite face
            // (centroid through the centre) in exactly 5.
            for g in 0..20u32 {
                let path = dual_path(&dual, f, g, 100).unwrap();
                assert_eq!((path[0], *path.last().unwrap()), (f, g));
                assert!(path.len() <= 6);
                assert!(path
                    .windows(2)
                    .all(|w| dual.neighbours(w[0]).any(|h| h == w[1])));
                let (a, b) = (dual.centroids[f as usize], dual.centroids[g as usize]);
                if norm(add(a, b)) < 1e-9 {
                    assert_eq!(path.len(), 6);
                }
            }
        }
        // A search that may settle one face gives up on a face three steps away.
        let far = (0..20u32)
            .find(|&g| dual_path(&dual, 0, g, 100).unwrap().len() == 4)
            .unwrap();
        assert_eq!(dual_path(&dual, 0, far, 1), None);
    }

    #[test]
    fn winding_counts_turns_around_the_axis() {
        let axis = Axis::new([0.0; 3], [0.0, 0.0, 1.0]);
        let circle = |c: [f64; 3], k: usize| -> Vec<[f64; 3]> {
            (0..k)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / k as f64;
                    [c[0] + a.cos(), c[1] + a.sin(), (2.0 * a).cos()]
                })
                .collect()
        };
        assert_eq!(axis.winding(&circle([0.0; 3], 16)).abs(), 1);
        assert_eq!(axis.winding(&circle([3.0, 0.0, 0.0], 16)), 0);
    }
}
