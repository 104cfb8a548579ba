//! Plane cut of a surface (sec. 4.3, first step): the closed curves where a plane meets
//! the triangles, as cyclic sequences of edge crossings, and the choice of the curve
//! around a point of the plane.
//!
//! Conventions: a vertex's side is the sign of `n · (p − c)`; a vertex exactly on the
//! plane counts as on the positive side (symbolic perturbation: the plane is moved by an
//! infinitesimal amount towards −n), so every edge is either crossed once or not at all
//! and every triangle is crossed by 0 or 2 of its edges, whatever the input. A crossing is
//! `(edge, t)` with the point `(1 − t)·a + t·b` for the edge's vertices `[a, b]` as stored
//! by [`Topology`]; a vertex on the plane gives exactly `t = 0` or `t = 1`.
//!
//! Entry points: [`plane_cut`] (or [`Cutter::cut`] with the surface's [`EdgeTree`]),
//! [`loop_around`], [`encloses_another`], [`region_side`]; where only the curve round a
//! point matters, [`Cutter::cut_round`] and [`Cutter::encloses_another_round`], which
//! walk only the curves near it.

pub use crate::geom::plane_basis;
use crate::geom::{dot, lerp, norm, sub};
use crate::mesh::{Side, SurfaceMesh, Topology};
use rustc_hash::FxHashSet;

/// A plane through `origin` with unit `normal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point of the plane.
    pub origin: [f64; 3],
    /// Unit normal.
    pub normal: [f64; 3],
}

/// Where a cut curve crosses a mesh edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Edge index in the [`Topology`].
    pub edge: u32,
    /// Parameter along the edge's stored vertex pair, in `[0, 1]`.
    pub t: f64,
}

/// One curve of a plane cut.
#[derive(Debug, Clone, PartialEq)]
pub struct CutCurve {
    /// Crossings in order along the curve.
    pub crossings: Vec<Crossing>,
    /// `faces[i]` is the triangle between `crossings[i]` and `crossings[i + 1]`
    /// (cyclically for a closed curve).
    pub faces: Vec<u32>,
    /// Whether the curve closes; an open curve ends at a boundary or non-manifold edge.
    pub closed: bool,
}

impl CutCurve {
    /// The 3D points of the crossings.
    pub fn points(&self, mesh: &SurfaceMesh, topology: &Topology) -> Vec<[f64; 3]> {
        self.crossings
            .iter()
            .map(|c| crossing_point(mesh, topology, *c))
            .collect()
    }
}

/// 3D point of a crossing.
pub fn crossing_point(mesh: &SurfaceMesh, topology: &Topology, c: Crossing) -> [f64; 3] {
    let [a, b] = topology.edges()[c.edge as usize];
    lerp(mesh.positions[a as usize], mesh.positions[b as usize], c.t)
}

/// Length of a closed polyline.
pub fn closed_length(points: &[[f64; 3]]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| norm(sub(points[(i + 1) % n], points[i])))
        .sum()
}

/// All curves where `plane` meets the surface. Closed curves on a closed manifold mesh;
/// open curves where the surface has a boundary or non-manifold edge. `O(V + F)`;
/// [`Cutter::cut`] gives the same curves visiting only the edges near the plane.
pub fn plane_cut(mesh: &SurfaceMesh, topology: &Topology, plane: &Plane) -> Vec<CutCurve> {
    let crossed: Vec<u32> = (0..topology.num_edges() as u32)
        .filter(|&e| crosses(mesh, topology, plane, e as usize))
        .collect();
    cut_edges(mesh, topology, plane, &crossed)
}

/// A surface with its edges in a bounding-box tree ([`EdgeTree`]), for plane cuts that
/// cost what they cross: on a dense surface most planes cross a few hundred of its
/// million edges.
#[derive(Clone, Copy)]
pub struct Cutter<'a> {
    /// The surface.
    pub mesh: &'a SurfaceMesh,
    /// Its topology.
    pub topology: &'a Topology,
    /// Its edges' tree.
    pub tree: &'a EdgeTree,
}

impl Cutter<'_> {
    /// The curves of [`plane_cut`], in the same order, with the same crossings.
    pub fn cut(&self, plane: &Plane) -> Vec<CutCurve> {
        let mut near = Vec::new();
        self.tree.near_plane(plane, &mut near);
        // Only the crossed ones need the order: sorting them alone sorts a fraction.
        near.retain(|&e| crosses(self.mesh, self.topology, plane, e as usize));
        near.sort_unstable();
        cut_edges(self.mesh, self.topology, plane, &near)
    }

    /// The curves of [`Cutter::cut`] that may go round the plane's origin, in the same
    /// order, with the same crossings: every curve that [`loop_around`] can pick for the
    /// origin is among them (on a surface whose every edge lies in two faces; on others,
    /// every curve).
    ///
    /// A curve round the origin crosses the line through it along the plane's first
    /// basis vector `u` ([`plane_basis`]) on its positive side: one of its segments,
    /// in a triangle, has ends on both sides of the line along `u`, and so one of that
    /// triangle's two crossed edges has ends on both sides of the plane through the
    /// line with normal `v`, or within rounding of it. Only the curves through such
    /// edges, which the edge tree finds near the line, are walked.
    pub fn cut_round(&self, plane: &Plane) -> Vec<CutCurve> {
        if !self.tree.two_faces_per_edge {
            return self.cut(plane);
        }
        let (mesh, topology) = (self.mesh, self.topology);
        let (_, v) = plane_basis(plane.normal);
        let margin = self.tree.rounding;
        let across = |w: u32| dot(v, sub(mesh.positions[w as usize], plane.origin));
        let mut near = Vec::new();
        self.tree.near(plane, &[(v, 0.0, 0.0)], &mut near);
        near.retain(|&e| {
            let [a, b] = topology.edges()[e as usize];
            let (ya, yb) = (across(a), across(b));
            ya.min(yb) <= margin
                && ya.max(yb) >= -margin
                && crosses(mesh, topology, plane, e as usize)
        });
        match self.curves_through(plane, &near) {
            Some(curves) => curves,
            None => self.cut(plane),
        }
    }

    /// Whether another closed curve of the plane lies inside `curve`, a closed curve of
    /// it: [`encloses_another`] over the curves of [`Cutter::cut`]. A curve counts as
    /// inside by its first point (its crossing of lowest edge index), which lies in
    /// `curve`'s bounding rectangle in the plane if inside it: only the curves through
    /// edges near that rectangle are walked, one at a time, until one lies inside.
    pub fn encloses_another_round(&self, plane: &Plane, curve: &CutCurve) -> bool {
        let (mesh, topology) = (self.mesh, self.topology);
        let (u, v) = plane_basis(plane.normal);
        let project = projection(plane);
        let poly = in_plane(mesh, topology, plane, curve);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &poly {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // Outside the rectangle a point is outside the polygon (the crossing-number test
        // counts an even number of crossings there): only points within it are tested.
        let inside = |p: [f64; 3]| {
            let q = project(p);
            (0..2).all(|k| q[k] >= lo[k] && q[k] <= hi[k]) && area_and_contains(&poly, q).1
        };
        if self.tree.two_faces_per_edge {
            let mut near = Vec::new();
            self.tree
                .near(plane, &[(u, lo[0], hi[0]), (v, lo[1], hi[1])], &mut near);
            near.retain(|&e| crosses(mesh, topology, plane, e as usize));
            near.sort_unstable();
            let own = curve.crossings.first().map(|c| c.edge);
            let is_crossed = |g: usize| crosses(mesh, topology, plane, g);
            let mut walked = FxHashSet::default();
            let mut walks_closed = true;
            let found = near.iter().any(|&seed| {
                let seed = seed as usize;
                if walked.contains(&seed) || !walks_closed {
                    return false;
                }
                let Some((edges, _)) = cycle(seed, topology, &is_crossed) else {
                    walks_closed = false;
                    return false;
                };
                walked.extend(edges.iter().copied());
                let lowest = edges.iter().copied().min().unwrap_or(seed);
                Some(lowest as u32) != own
                    && inside(crossing_point(
                        mesh,
                        topology,
                        crossing(mesh, topology, plane, lowest),
                    ))
            });
            if found || walks_closed {
                return found;
            }
        }
        self.cut(plane).iter().any(|c| {
            c.closed
                && c.crossings.first() != curve.crossings.first()
                && c.crossings
                    .first()
                    .is_some_and(|&x| inside(crossing_point(mesh, topology, x)))
        })
    }

    /// The curves of [`Cutter::cut`] through the crossed edges `seeds` (in increasing
    /// order), in its order; `None` where a walk does not close (only on surfaces
    /// without [`EdgeTree::two_faces_per_edge`]).
    fn curves_through(&self, plane: &Plane, seeds: &[u32]) -> Option<Vec<CutCurve>> {
        let (mesh, topology) = (self.mesh, self.topology);
        let is_crossed = |g: usize| crosses(mesh, topology, plane, g);
        // Each curve through a seed, walked once, then from its edge of lowest index.
        let mut walked: Vec<(Vec<usize>, Vec<u32>)> = Vec::new();
        let mut seen = FxHashSet::default();
        for &seed in seeds {
            let seed = seed as usize;
            if seen.contains(&seed) {
                continue;
            }
            let (edges, faces) = cycle(seed, topology, &is_crossed)?;
            seen.extend(edges.iter().copied());
            let (lowest, _) = edges.iter().enumerate().min_by_key(|&(_, &e)| e)?;
            walked.push(from_edge(edges, faces, lowest, topology));
        }
        walked.sort_unstable_by_key(|(edges, _)| edges[0]);
        let curves = walked
            .into_iter()
            .map(|(edges, faces)| CutCurve {
                crossings: edges
                    .into_iter()
                    .map(|e| crossing(mesh, topology, plane, e))
                    .collect(),
                faces,
                closed: true,
            })
            .collect();
        Some(curves)
    }
}

/// The closed curve of crossed edges through `start`, walked as [`cut_edges`] walks it
/// (through `start`'s first face first): its edges and the faces between them. `None`
/// where the walk does not come back to `start` (an open or non-manifold fan).
fn cycle(
    start: usize,
    topology: &Topology,
    is_crossed: &impl Fn(usize) -> bool,
) -> Option<(Vec<usize>, Vec<u32>)> {
    let mut edges = vec![start];
    let mut faces = Vec::new();
    let mut face = *topology.edge_faces(start).first()? as usize;
    let mut edge = start;
    loop {
        let next = other_crossed(topology, face, edge, is_crossed)?;
        faces.push(face as u32);
        if next == start {
            return Some((edges, faces));
        }
        if edges.len() > topology.num_edges() {
            return None;
        }
        edges.push(next);
        face = match *topology.edge_faces(next) {
            [a, b] if a as usize == face => b,
            [a, _] => a,
            _ => return None,
        } as usize;
        edge = next;
    }
}

/// The closed curve `edges` (with `faces[i]` between `edges[i]` and `edges[i + 1]`)
/// started at `edges[at]` and walked through that edge's first face first, as
/// [`cut_edges`] gives it when `edges[at]` is its crossed edge of lowest index.
fn from_edge(
    edges: Vec<usize>,
    faces: Vec<u32>,
    at: usize,
    topology: &Topology,
) -> (Vec<usize>, Vec<u32>) {
    let n = edges.len();
    let first_face = topology.edge_faces(edges[at])[0];
    if faces[at] == first_face {
        let edges = (0..n).map(|i| edges[(at + i) % n]).collect();
        let faces = (0..n).map(|i| faces[(at + i) % n]).collect();
        (edges, faces)
    } else {
        // Backwards: from `edges[at]` through the face before it.
        let edges = (0..n).map(|i| edges[(at + n - i) % n]).collect();
        let faces = (0..n).map(|i| faces[(at + 2 * n - 1 - i) % n]).collect();
        (edges, faces)
    }
}

/// Whether `plane` crosses edge `e`: its ends lie on different sides (the module's side
/// rule).
fn crosses(mesh: &SurfaceMesh, topology: &Topology, plane: &Plane, e: usize) -> bool {
    let positive = |v: u32| dot(plane.normal, sub(mesh.positions[v as usize], plane.origin)) >= 0.0;
    let [a, b] = topology.edges()[e];
    positive(a) != positive(b)
}

/// The crossed edge of face `f` other than `e` (exactly one by the side rule).
fn other_crossed(
    topology: &Topology,
    f: usize,
    e: usize,
    is_crossed: impl Fn(usize) -> bool,
) -> Option<usize> {
    (0..3)
        .filter_map(|i| topology.face_edge(f, i))
        .find(|&g| g != e && is_crossed(g))
}

/// Where `plane` crosses edge `e`.
fn crossing(mesh: &SurfaceMesh, topology: &Topology, plane: &Plane, e: usize) -> Crossing {
    let [a, b] = topology.edges()[e];
    let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
    let (da, db) = (
        dot(plane.normal, sub(pa, plane.origin)),
        dot(plane.normal, sub(pb, plane.origin)),
    );
    // t measured from a; for a vertex on the plane (d = 0, positive side) t is exactly 0 or 1.
    let t = if da == 0.0 {
        0.0
    } else if db == 0.0 {
        1.0
    } else {
        (da / (da - db)).clamp(0.0, 1.0)
    };
    Crossing { edge: e as u32, t }
}

/// The curves where `plane` meets the surface, from `crossed`: the indices of the edges
/// it crosses ([`crosses`]), in increasing order. Each curve starts at its crossed edge
/// of lowest index.
fn cut_edges(
    mesh: &SurfaceMesh,
    topology: &Topology,
    plane: &Plane,
    crossed: &[u32],
) -> Vec<CutCurve> {
    let other_crossed =
        |f: usize, e: usize| other_crossed(topology, f, e, |g| crosses(mesh, topology, plane, g));
    let make = |e: usize| crossing(mesh, topology, plane, e);

    let mut visited = Visited {
        crossed,
        seen: vec![false; crossed.len()],
    };
    let mut curves = Vec::new();
    for (i, &start) in crossed.iter().enumerate() {
        let start = start as usize;
        if visited.seen[i] {
            continue;
        }
        // Walk one way; if the walk hits an open edge, walk the other way from `start` too.
        let forward = walk(start, 0, topology, &other_crossed, &mut visited);
        let (mut edges, mut faces, closed) = forward;
        if !closed {
            let (back_edges, back_faces, _) =
                walk(start, 1, topology, &other_crossed, &mut visited);
            // back walk goes start -> ... ; reverse it in front of the forward part.
            let mut e: Vec<usize> = back_edges.into_iter().skip(1).rev().collect();
            let mut f: Vec<u32> = back_faces.into_iter().rev().collect();
            e.extend(edges);
            f.extend(faces);
            edges = e;
            faces = f;
        }
        curves.push(CutCurve {
            crossings: edges.into_iter().map(make).collect(),
            faces,
            closed,
        });
    }
    curves
}

/// Which crossed edges a cut has walked: a flag per crossed edge (in increasing order).
struct Visited<'a> {
    crossed: &'a [u32],
    seen: Vec<bool>,
}

impl Visited<'_> {
    fn slot(&self, e: usize) -> usize {
        self.crossed
            .binary_search(&(e as u32))
            .expect("a walk follows crossed edges only")
    }

    /// Marks edge `e` walked; whether it was not yet.
    fn first_visit(&mut self, e: usize) -> bool {
        let i = self.slot(e);
        !std::mem::replace(&mut self.seen[i], true)
    }
}

/// A surface's edges in a tree of bounding boxes (median splits along the widest
/// axis), for the edges a plane may cross ([`Cutter`]). Built once per surface,
/// `O(E log E)`.
#[derive(Debug, Clone)]
pub struct EdgeTree {
    /// Flattened depth first: an inner node's left child follows it, its right child is
    /// at `right`.
    nodes: Vec<EdgeNode>,
    /// Edge indices, each leaf's a run of them.
    edges: Vec<u32>,
    /// Whether every edge lies in two distinct faces and every face has three edges:
    /// then a plane's crossed edges form disjoint closed curves ([`Cutter::cut_round`]).
    two_faces_per_edge: bool,
    /// A bound, far above it, on the rounding of a point's coordinates along a
    /// direction as this module computes them: 1e-9 of the largest coordinate or
    /// extent of the surface.
    rounding: f64,
}

#[derive(Debug, Clone, Copy)]
struct EdgeNode {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: its first edge in `EdgeTree::edges`; inner: its right child's index.
    first: u32,
    /// Leaf: its number of edges; inner: 0.
    count: u32,
}

/// Edges per leaf, at most.
const LEAF_EDGES: usize = 8;

impl EdgeTree {
    /// The tree of `topology`'s edges on `mesh`.
    pub fn new(mesh: &SurfaceMesh, topology: &Topology) -> EdgeTree {
        let ends = topology.edges();
        let two_faces_per_edge = (0..ends.len())
            .all(|e| matches!(*topology.edge_faces(e), [f, g] if f != g))
            && (0..topology.num_faces())
                .all(|f| (0..3).all(|i| topology.face_edge(f, i).is_some()));
        let mut tree = EdgeTree {
            nodes: Vec::with_capacity(2 * ends.len() / LEAF_EDGES + 1),
            edges: (0..ends.len() as u32).collect(),
            two_faces_per_edge,
            rounding: 0.0,
        };
        if !ends.is_empty() {
            tree.build(mesh, ends, 0, ends.len());
            let root = tree.nodes[0];
            let largest = (0..3)
                .map(|k| root.lo[k].abs().max(root.hi[k].abs()) + (root.hi[k] - root.lo[k]))
                .fold(0.0, f64::max);
            tree.rounding = 1e-9 * largest;
        }
        tree
    }

    /// Adds the node over `edges[from..to]` and its subtree.
    fn build(&mut self, mesh: &SurfaceMesh, ends: &[[u32; 2]], from: usize, to: usize) {
        let at = |v: u32| mesh.positions[v as usize];
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &e in &self.edges[from..to] {
            for p in ends[e as usize].map(at) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let node = self.nodes.len();
        self.nodes.push(EdgeNode {
            lo,
            hi,
            first: from as u32,
            count: (to - from) as u32,
        });
        if to - from <= LEAF_EDGES {
            return;
        }
        let axis = (0..3)
            .max_by(|&i, &j| (hi[i] - lo[i]).total_cmp(&(hi[j] - lo[j])))
            .unwrap_or(0);
        // Twice the edge's midpoint along the axis.
        let centre = |e: u32| {
            let [a, b] = ends[e as usize];
            at(a)[axis] + at(b)[axis]
        };
        let mid = (from + to) / 2;
        self.edges[from..to].select_nth_unstable_by(mid - from, |&a, &b| {
            centre(a).total_cmp(&centre(b)).then(a.cmp(&b))
        });
        self.nodes[node].count = 0;
        self.build(mesh, ends, from, mid);
        self.nodes[node].first = self.nodes.len() as u32;
        self.build(mesh, ends, mid, to);
    }

    /// Appends every edge whose box the plane may meet: a superset of the edges it
    /// crosses (the box test is widened by far more than the rounding of the side test).
    fn near_plane(&self, plane: &Plane, out: &mut Vec<u32>) {
        self.near(plane, &[], out);
    }

    /// Appends every edge whose box the plane may meet within `ranges`: for each
    /// `(w, lo, hi)`, where `w · (p − origin)` may lie in `[lo, hi]` for a point `p`
    /// of the box (widened by twice [`EdgeTree::rounding`]).
    fn near(&self, plane: &Plane, ranges: &[([f64; 3], f64, f64)], out: &mut Vec<u32>) {
        if self.nodes.is_empty() {
            return;
        }
        // Signed distance of a box's centre along `n`, the reach of its half extents,
        // and the size of both.
        let reach = |node: &EdgeNode, n: [f64; 3]| {
            let (mut d, mut r, mut size) = (0.0, 0.0, 0.0);
            for (k, nk) in n.iter().enumerate() {
                let c = 0.5 * (node.lo[k] + node.hi[k]) - plane.origin[k];
                let e = 0.5 * (node.hi[k] - node.lo[k]);
                d += nk * c;
                r += nk.abs() * e;
                size += nk.abs() * (c.abs() + e);
            }
            (d, r, size)
        };
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = self.nodes[i];
            let (d, r, size) = reach(&node, plane.normal);
            if d.abs() > r + 1e-9 * size {
                continue;
            }
            let margin = 2.0 * self.rounding;
            if ranges.iter().any(|&(w, lo, hi)| {
                let (d, r, _) = reach(&node, w);
                d + r < lo - margin || d - r > hi + margin
            }) {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                out.extend_from_slice(&self.edges[first..first + node.count as usize]);
            } else {
                stack.push(node.first as usize);
                stack.push(i + 1);
            }
        }
    }
}

/// Follow crossed edges from `start` leaving through its `side`-th face. Returns the
/// edges (starting with `start`), the faces between them, and whether the walk closed.
fn walk(
    start: usize,
    side: usize,
    topology: &Topology,
    other_crossed: &impl Fn(usize, usize) -> Option<usize>,
    visited: &mut Visited,
) -> (Vec<usize>, Vec<u32>, bool) {
    let mut edges = vec![start];
    let mut faces = Vec::new();
    visited.first_visit(start);
    let start_faces = topology.edge_faces(start);
    if start_faces.len() != 2 || side >= start_faces.len() {
        return (edges, faces, false);
    }
    let mut face = start_faces[side] as usize;
    let mut edge = start;
    loop {
        let Some(next) = other_crossed(face, edge) else {
            return (edges, faces, false);
        };
        faces.push(face as u32);
        if next == start {
            return (edges, faces, true);
        }
        if !visited.first_visit(next) {
            // Only possible through a non-manifold fan; stop rather than loop forever.
            return (edges, faces, false);
        }
        edges.push(next);
        let ef = topology.edge_faces(next);
        if ef.len() != 2 {
            return (edges, faces, false);
        }
        face = if ef[0] as usize == face { ef[1] } else { ef[0] } as usize;
        edge = next;
    }
}

/// A point's coordinates in the plane: along the basis ([`plane_basis`]) from its origin.
fn projection(plane: &Plane) -> impl Fn([f64; 3]) -> [f64; 2] + '_ {
    let (u, v) = plane_basis(plane.normal);
    move |p| {
        let d = sub(p, plane.origin);
        [dot(d, u), dot(d, v)]
    }
}

/// A curve's points in plane coordinates ([`projection`]).
fn in_plane(
    mesh: &SurfaceMesh,
    topology: &Topology,
    plane: &Plane,
    curve: &CutCurve,
) -> Vec<[f64; 2]> {
    let project = projection(plane);
    curve
        .points(mesh, topology)
        .into_iter()
        .map(project)
        .collect()
}

/// Signed area and whether `point` is inside, for a closed polygon in plane coordinates.
fn area_and_contains(poly: &[[f64; 2]], point: [f64; 2]) -> (f64, bool) {
    let n = poly.len();
    let mut area = 0.0;
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        area += a[0] * b[1] - a[1] * b[0];
        // Crossing-number test with the half-open rule on y.
        if (a[1] > point[1]) != (b[1] > point[1]) {
            let x = a[0] + (point[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if point[0] < x {
                inside = !inside;
            }
        }
    }
    (0.5 * area, inside)
}

/// Whether another closed curve of the plane lies inside closed curve `i`: then the
/// region of the plane that curve `i` bounds is not a disk of one side of the surface
/// (it has islands of the other), and the curve need not bound on that side.
pub fn encloses_another(
    mesh: &SurfaceMesh,
    topology: &Topology,
    plane: &Plane,
    curves: &[CutCurve],
    i: usize,
) -> bool {
    let project = projection(plane);
    let poly = in_plane(mesh, topology, plane, &curves[i]);
    curves.iter().enumerate().any(|(j, c)| {
        j != i
            && c.closed
            && c.points(mesh, topology)
                .first()
                .is_some_and(|&p| area_and_contains(&poly, project(p)).1)
    })
}

/// The side of the surface that the region of the plane bounded by closed curve `curve`
/// lies on next to the curve: inside the solid where the outward normals of the faces
/// it crosses, projected into the plane, point out of the region on the whole (a
/// cross-section of a part), outside where they point into it (a hole's). Each of the
/// curve's segments counts by its length. With [`encloses_another`] false the whole
/// region is on that side.
pub fn region_side(
    mesh: &SurfaceMesh,
    topology: &Topology,
    plane: &Plane,
    curve: &CutCurve,
) -> Side {
    let (u, v) = plane_basis(plane.normal);
    let poly = in_plane(mesh, topology, plane, curve);
    let n = poly.len();
    let (mut area, mut outward) = (0.0, 0.0);
    for (k, &face) in curve.faces.iter().enumerate().take(n) {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        area += a[0] * b[1] - a[1] * b[0];
        let normal = mesh.face_normal_scaled(face as usize);
        let scale = norm(normal);
        if scale.is_nan() || scale <= 0.0 {
            continue;
        }
        let m = [dot(normal, u) / scale, dot(normal, v) / scale];
        // The segment's right-hand normal, as long as the segment: out of the region
        // for a counter-clockwise polygon.
        let right = [b[1] - a[1], a[0] - b[0]];
        outward += m[0] * right[0] + m[1] * right[1];
    }
    if outward * area > 0.0 {
        Side::Inside
    } else {
        Side::Outside
    }
}

/// Index of the closed curve around `point` (a point of the plane): among the closed
/// curves whose in-plane polygon contains the point's projection, the one of smallest
/// area. `None` when no closed curve contains it.
pub fn loop_around(
    mesh: &SurfaceMesh,
    topology: &Topology,
    plane: &Plane,
    curves: &[CutCurve],
    point: [f64; 3],
) -> Option<usize> {
    let target = projection(plane)(point);
    let mut best: Option<(usize, f64)> = None;
    for (i, curve) in curves.iter().enumerate() {
        if !curve.closed || curve.crossings.len() < 3 {
            continue;
        }
        let poly = in_plane(mesh, topology, plane, curve);
        let (area, inside) = area_and_contains(&poly, target);
        if inside && best.is_none_or(|(_, a)| area.abs() < a) {
            best = Some((i, area.abs()));
        }
    }
    best.map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A torus round the z axis (radii 2 and 0.5), outward, `n × n` quads.
    fn torus(n: usize) -> SurfaceMesh {
        use std::f64::consts::TAU;
        let mut positions = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (u, v) = (TAU * i as f64 / n as f64, TAU * j as f64 / n as f64);
                let rho = 2.0 + 0.5 * v.cos();
                positions.push([rho * u.cos(), rho * u.sin(), 0.5 * v.sin()]);
            }
        }
        let at = |i: usize, j: usize| ((i % n) * n + j % n) as u32;
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        SurfaceMesh::new(positions, triangles).unwrap()
    }

    /// The side of the curve round `point` in the plane through it with `normal`.
    fn side_around(mesh: &SurfaceMesh, point: [f64; 3], normal: [f64; 3]) -> Side {
        let topology = Topology::new(mesh);
        let plane = Plane {
            origin: point,
            normal,
        };
        let curves = plane_cut(mesh, &topology, &plane);
        let i = loop_around(mesh, &topology, &plane, &curves, point).unwrap();
        assert!(!encloses_another(mesh, &topology, &plane, &curves, i));
        region_side(mesh, &topology, &plane, &curves[i])
    }

    #[test]
    fn a_tube_section_is_inside_and_the_hole_outside_whatever_the_orientation() {
        let mut mesh = torus(24);
        assert!(mesh.signed_volume() > 0.0, "the fixture is outward");
        // The tube's cross-section round its core, and the disk across the hole.
        let tube = ([2.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let hole = ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(side_around(&mesh, tube.0, tube.1), Side::Inside);
        assert_eq!(side_around(&mesh, hole.0, hole.1), Side::Outside);
        // The plane's normal turned round reverses the curve, not its side.
        assert_eq!(side_around(&mesh, tube.0, [0.0, -1.0, 0.0]), Side::Inside);
        assert_eq!(side_around(&mesh, hole.0, [0.0, 0.0, -1.0]), Side::Outside);
        // Inward-facing triangles swap the sides.
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        assert_eq!(side_around(&mesh, tube.0, tube.1), Side::Outside);
        assert_eq!(side_around(&mesh, hole.0, hole.1), Side::Inside);
    }
}
