//! Surface simplification: a coarser copy of a dense closed surface, for the stages that
//! only need its shape (the paper's speed-up of sec. 5, Fig. 16: "with the mesh
//! simplification, all the procedures involved run faster").
//!
//! The volume mesh, the distance field and the saddles depend on the shape at the
//! lattice's resolution (`h`, by default 1/64 of the bounding-box diagonal), not on how
//! finely that shape is triangulated. A surface of a million triangles costs the survey,
//! the mesher's sizing and every distance query in proportion to its size all the same.
//! `pipeline` runs the method on the copy made here (for a surface above
//! [`SimplifyOptions::above`] triangles: `pipeline::working`) and carries the loops back
//! to the original by cutting it with the same planes (`loops::transfer_loops`).
//!
//! Method: Garland and Heckbert's quadric error metric, edge collapses in rounds.
//! - The vertices are first put in Morton order of their positions and the triangles in
//!   the order of their lowest corner, so that neighbours on the surface are neighbours
//!   in memory: the sequential sweep below is bound by memory latency, and a scattered
//!   input order (a subdivided mesh appends its new vertices) made it twice as slow. The
//!   copy's order then does not depend on the input's either.
//! - Each vertex starts with the sum of the quadrics of its triangles' planes (unit
//!   normals, not weighted by area), so the error of a position is the sum of its
//!   squared distances to the original planes merged into it: its square root bounds
//!   the distance to each of those planes.
//! - A round prices every edge's collapse at once (in parallel), takes as its threshold
//!   the price of the collapses still needed (at most a third of the edges: the cheap
//!   ones go first), and then makes, in the edges' order, every collapse up to it
//!   whose ends have not changed in this round, so that every price used is exact. A
//!   round that makes none takes every edge up to the error bound next time. (A priority queue, cheapest
//!   first, gave the same surfaces 3–4× slower on 1.5 M triangles: its pops are
//!   cache misses.)
//! - An edge `a b` collapses to the best of: the quadric's minimiser (where its 3×3
//!   system is well conditioned and the point stays within the edge's length of its
//!   midpoint), `a`, `b` and the midpoint; ties keep the earlier in that order but for
//!   the minimiser.
//! - A collapse is refused when it would change the topology (the link condition: the
//!   two ends share exactly the two vertices opposite the edge, and neither of those
//!   has only three neighbours), turn a triangle by more than 60° or make it
//!   degenerate, or leave a vertex with more than [`MAX_STAR`] triangles.
//! - It stops at [`SimplifyOptions::target`] triangles, or before the first collapse
//!   whose error exceeds [`SimplifyOptions::max_error`] × diagonal, or when no valid
//!   collapse is left; [`Simplified::stop`] says which.
//!
//! Conventions: closed, manifold, consistently oriented input (the pipeline uses the
//! copy of no other surface); faces keep their orientation; units are the surface's. The
//! result is the same for any thread count (each edge priced on its own, the collapses
//! made in one sequential sweep in face order). Entry point: [`simplify`].

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::mesh::{Csr, SurfaceMesh};

/// Options of [`simplify`] and when the pipeline uses it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimplifyOptions {
    /// The pipeline simplifies surfaces with more triangles than this; 0 never does.
    /// Default 200 000: the shared models (at most 98 000) are used as they are.
    pub above: usize,
    /// Stop at this many triangles. Default 30 000, the size of the shared models (the
    /// Botijo 23 000, the kitten 20 000): on a roundish shape an edge about the default
    /// lattice spacing (1/64 of the diagonal), so that the survey and the distance
    /// queries cost what they cost there. Where the shape needs more, the error bound
    /// stops it first. (50 000 gave the same loops on the dense Botijo and kitten, 0.35 s
    /// slower.)
    pub target: usize,
    /// Largest allowed error of a collapse (the square root of its quadric error: the
    /// root of the summed squared distances to the original planes it replaces), × the
    /// bounding-box diagonal. Default 1e-3, 1/16 of the default lattice spacing.
    pub max_error: f64,
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        SimplifyOptions {
            above: 200_000,
            target: 30_000,
            max_error: 1e-3,
        }
    }
}

impl SimplifyOptions {
    /// Whether a surface of `triangles` triangles is simplified.
    pub fn applies_to(&self, triangles: usize) -> bool {
        self.above > 0 && triangles > self.above
    }
}

/// What stopped the collapses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "by")]
pub enum Stop {
    /// The target triangle count was reached.
    Target,
    /// The next collapse's error (surface units) exceeded the bound.
    ErrorBound { next_error: f64, bound: f64 },
    /// No collapse was left that keeps the topology and the triangles' orientation.
    NoValidCollapse,
}

/// A simplified surface and how it was made.
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// The simplified surface (vertices renumbered, faces in their original order).
    pub mesh: SurfaceMesh,
    /// Triangles before and after.
    pub triangles: (usize, usize),
    /// The largest error of a collapse made (surface units; see
    /// [`SimplifyOptions::max_error`]).
    pub max_error: f64,
    /// What stopped it.
    pub stop: Stop,
    /// Collapses refused: by the link condition, by a triangle turned or degenerate,
    /// by a vertex that would have more than [`MAX_STAR`] triangles (or its own
    /// count in the input, where that is more).
    pub refused: (usize, usize, usize),
}

/// A simplified copy of the closed, manifold, oriented `surface` (see the module doc).
/// Other surfaces are accepted too (only manifold edges collapse), as long as every
/// triangle names three distinct vertices of the mesh and every coordinate is finite.
pub fn simplify(surface: &SurfaceMesh, options: &SimplifyOptions) -> Result<Simplified> {
    let bound = options.max_error * surface.bbox_diagonal();
    if !(options.max_error.is_finite() && options.max_error > 0.0) || options.target < 4 {
        return Err(Error::invalid_argument(
            "simplification needs a positive error bound and a target of at least 4 triangles",
        ));
    }
    // Any mesh may come here (the pipeline simplifies the input while it is being
    // checked): indices must be usable; other problems only make a copy not used.
    crate::mesh::check_finite(&surface.positions)?;
    let n = surface.num_vertices();
    let unusable = |t: &[u32; 3]| {
        t.iter().any(|&v| v as usize >= n) || t[0] == t[1] || t[1] == t[2] || t[2] == t[0]
    };
    if let Some(f) = surface.triangles.iter().position(unusable) {
        return Err(Error::invalid_argument(format!(
            "simplification needs three distinct vertices of the mesh per triangle; triangle {f} has not"
        )));
    }
    let mut state = Collapser::new(spatial_order(surface));
    let mut faces = surface.num_triangles();
    let mut max_error = 0.0f64;
    let mut refused = (0, 0, 0);
    // Rounds: every edge's collapse priced at once; then, in the edges' order (the
    // faces'), every collapse up to the round's threshold whose ends have not changed
    // in this round (so every price used is exact). The threshold is the price of the
    // collapses still needed, at most a third of the edges: cheap ones go first.
    let bound_bits = (bound * bound).to_bits();
    let mut widen = false;
    let stop = loop {
        if faces <= options.target {
            break Stop::Target;
        }
        let priced: Vec<Collapse> = state
            .edges()
            .par_iter()
            .map(|&(a, b)| state.price(a, b))
            .collect();
        let mut errors: Vec<u64> = priced.iter().map(|c| c.error).collect();
        let Some(&cheapest) = errors.iter().min() else {
            break Stop::NoValidCollapse;
        };
        if cheapest > bound_bits {
            break Stop::ErrorBound {
                next_error: f64::from_bits(cheapest).sqrt(),
                bound,
            };
        }
        let needed = (faces - options.target).div_ceil(2);
        let threshold = if widen {
            bound_bits
        } else {
            let k = needed.clamp(1, errors.len().div_ceil(3)) - 1;
            (*errors.select_nth_unstable(k).1).min(bound_bits)
        };
        let mut changed = vec![false; state.positions.len()];
        let before = faces;
        for c in priced {
            if faces <= options.target {
                break;
            }
            let (a, b) = (c.remove, c.keep);
            if c.error > threshold || changed[a as usize] || changed[b as usize] {
                continue;
            }
            if !state.vertex_faces.fit(a, b) {
                refused.2 += 1;
                continue;
            }
            if !state.link_condition(a, b) {
                refused.0 += 1;
                continue;
            }
            if !state.keeps_triangles(a, b, c.target) {
                refused.1 += 1;
                continue;
            }
            state.collapse(a, b, c.target);
            changed[a as usize] = true;
            changed[b as usize] = true;
            faces -= 2;
            max_error = max_error.max(f64::from_bits(c.error).sqrt());
        }
        // Nothing made up to the threshold: the next round takes every edge up to
        // the bound; nothing made then either: done.
        if faces == before && widen {
            break Stop::NoValidCollapse;
        }
        widen = faces == before;
    };
    Ok(Simplified {
        mesh: state.into_mesh(),
        triangles: (surface.num_triangles(), faces),
        max_error,
        stop,
        refused,
    })
}

/// The surface with its vertices in Morton order of their positions (21 bits per axis
/// over the bounding box's largest side) and its faces in the order of their lowest
/// corner (see the module doc).
fn spatial_order(surface: &SurfaceMesh) -> SurfaceMesh {
    let (lo, hi) = surface.bounding_box().unwrap_or(([0.0; 3], [0.0; 3]));
    let extent = (0..3)
        .map(|i| hi[i] - lo[i])
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let code = |p: [f64; 3]| {
        let mut key = 0u64;
        let q = [0, 1, 2].map(|i| (((p[i] - lo[i]) / extent).clamp(0.0, 1.0) * 2097151.0) as u64);
        for bit in (0..21).rev() {
            for c in q {
                key = (key << 1) | ((c >> bit) & 1);
            }
        }
        key
    };
    let mut order: Vec<(u64, u32)> = surface
        .positions
        .par_iter()
        .enumerate()
        .map(|(v, &p)| (code(p), v as u32))
        .collect();
    order.par_sort_unstable();
    let mut index = vec![0u32; order.len()];
    for (new, &(_, old)) in order.iter().enumerate() {
        index[old as usize] = new as u32;
    }
    let positions = order
        .iter()
        .map(|&(_, v)| surface.positions[v as usize])
        .collect();
    let mut triangles: Vec<[u32; 3]> = surface
        .triangles
        .par_iter()
        .map(|t| t.map(|v| index[v as usize]))
        .collect();
    triangles.par_sort_unstable_by_key(|t| (*t.iter().min().expect("three corners"), *t));
    SurfaceMesh {
        positions,
        triangles,
    }
}

/// A symmetric 4×4 quadric: `xx xy xz xw yy yz yw zz zw ww`.
#[derive(Debug, Clone, Copy, Default)]
struct Quadric([f64; 10]);

impl Quadric {
    /// The squared distance to the plane `n · x + d = 0` (`n` unit).
    fn plane(n: [f64; 3], d: f64) -> Quadric {
        let [a, b, c] = n;
        Quadric([
            a * a,
            a * b,
            a * c,
            a * d,
            b * b,
            b * c,
            b * d,
            c * c,
            c * d,
            d * d,
        ])
    }

    fn add(&self, o: &Quadric) -> Quadric {
        let mut q = self.0;
        for (x, y) in q.iter_mut().zip(&o.0) {
            *x += y;
        }
        Quadric(q)
    }

    fn error(&self, p: [f64; 3]) -> f64 {
        let q = &self.0;
        let [x, y, z] = p;
        let e = q[0] * x * x
            + 2.0 * q[1] * x * y
            + 2.0 * q[2] * x * z
            + 2.0 * q[3] * x
            + q[4] * y * y
            + 2.0 * q[5] * y * z
            + 2.0 * q[6] * y
            + q[7] * z * z
            + 2.0 * q[8] * z
            + q[9];
        e.max(0.0)
    }

    /// The minimiser, where the 3×3 part is well conditioned.
    fn minimiser(&self) -> Option<[f64; 3]> {
        let q = &self.0;
        let m = [[q[0], q[1], q[2]], [q[1], q[4], q[5]], [q[2], q[5], q[7]]];
        let r = [-q[3], -q[6], -q[8]];
        let det = dot(m[0], cross(m[1], m[2]));
        let size = m.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
        if size == 0.0 || det.abs() <= 1e-9 * size * size * size {
            return None;
        }
        // Cramer's rule.
        let col = |j: usize, v: [f64; 3]| {
            let mut c = m;
            for i in 0..3 {
                c[i][j] = v[i];
            }
            dot(c[0], cross(c[1], c[2])) / det
        };
        Some([col(0, r), col(1, r), col(2, r)])
    }
}

/// The collapse of an edge: `remove` merged into `keep` at `target`, and its error
/// (squared, as bits: non-negative floats order as their bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Collapse {
    error: u64,
    remove: u32,
    keep: u32,
    target: Position,
}

/// A position stored by its bits, so that entries are `Ord`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Position([u64; 3]);

impl Position {
    fn new(p: [f64; 3]) -> Position {
        Position(p.map(f64::to_bits))
    }

    fn get(self) -> [f64; 3] {
        self.0.map(f64::from_bits)
    }
}

/// The mesh being simplified: positions, faces (`None` once removed), each vertex's
/// faces and quadric.
struct Collapser {
    positions: Vec<[f64; 3]>,
    faces: Vec<Option<[u32; 3]>>,
    vertex_faces: Stars,
    quadrics: Vec<Quadric>,
    /// Scratch marks of the link condition, and the last mark used.
    stamps: Vec<u32>,
    stamp: u32,
    /// The faces moving in a collapse.
    scratch: Vec<u32>,
}

impl Collapser {
    fn new(surface: SurfaceMesh) -> Collapser {
        let n = surface.num_vertices();
        let incidence = Csr::new(
            n,
            surface
                .triangles
                .iter()
                .enumerate()
                .flat_map(|(f, t)| t.iter().map(move |&v| (v, f as u32))),
        );
        // Each face's plane (none for a degenerate face), then each vertex's sum over
        // its faces in face order.
        let planes: Vec<Option<Quadric>> = (0..surface.num_triangles())
            .into_par_iter()
            .map(|f| {
                let normal = surface.face_normal_scaled(f);
                let length = norm(normal);
                (length > 0.0).then(|| {
                    let n = scale(normal, 1.0 / length);
                    let p = surface.positions[surface.triangles[f][0] as usize];
                    Quadric::plane(n, -dot(n, p))
                })
            })
            .collect();
        let quadrics = (0..n)
            .into_par_iter()
            .map(|v| {
                incidence
                    .get(v)
                    .iter()
                    .filter_map(|&f| planes[f as usize])
                    .fold(Quadric::default(), |q, p| q.add(&p))
            })
            .collect();
        let vertex_faces = Stars::new(n, |v| incidence.get(v));
        Collapser {
            faces: surface.triangles.iter().map(|&t| Some(t)).collect(),
            positions: surface.positions,
            vertex_faces,
            quadrics,
            stamps: vec![0; n],
            stamp: 0,
            scratch: Vec::new(),
        }
    }

    /// Each edge once, as `(a, b)` with `a < b`, in face order.
    fn edges(&self) -> Vec<(u32, u32)> {
        self.faces
            .iter()
            .flatten()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .filter(|(a, b)| a < b)
            .collect()
    }

    fn face(&self, f: u32) -> [u32; 3] {
        self.faces[f as usize].expect("a vertex lists only live faces")
    }

    /// The collapse of the edge `a b`: its best point and direction.
    fn price(&self, a: u32, b: u32) -> Collapse {
        let q = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let mid = scale(add(pa, pb), 0.5);
        let mut best = (q.error(pa), pa, b, a);
        for (p, keep, remove) in [(pb, a, b), (mid, b, a)] {
            let e = q.error(p);
            if e < best.0 {
                best = (e, p, keep, remove);
            }
        }
        let reach = norm(sub(pa, pb));
        if let Some(p) = q.minimiser().filter(|&p| norm(sub(p, mid)) <= reach) {
            let e = q.error(p);
            if e < best.0 {
                best = (e, p, b, a);
            }
        }
        let (error, target, keep, remove) = best;
        Collapse {
            error: error.to_bits(),
            remove,
            keep,
            target: Position::new(target),
        }
    }

    /// Whether collapsing the edge `a b` keeps the surface a manifold of the same
    /// topology: the edge has two triangles, `a` and `b` share exactly the two vertices
    /// opposite it as neighbours, and each of those keeps at least three.
    fn link_condition(&mut self, a: u32, b: u32) -> bool {
        // Stamp the neighbours of `a`, then count those of `b` among them.
        self.stamp += 1;
        let stamp = self.stamp;
        let mut on_edge = 0;
        for &f in self.vertex_faces.get(a) {
            let t = self.faces[f as usize].expect("a live face");
            on_edge += usize::from(t.contains(&b));
            for u in t {
                self.stamps[u as usize] = stamp;
            }
        }
        // A manifold edge: exactly two triangles (a collapse removes them).
        if on_edge != 2 {
            return false;
        }
        // Each shared neighbour once (its stamp taken back when met).
        let mut shared = [u32::MAX; 2];
        let mut count = 0;
        for &f in self.vertex_faces.get(b) {
            for u in self.faces[f as usize].expect("a live face") {
                if u != a && u != b && self.stamps[u as usize] == stamp {
                    self.stamps[u as usize] = stamp - 1;
                    if count == 2 {
                        return false;
                    }
                    shared[count] = u;
                    count += 1;
                }
            }
        }
        if count < 2 {
            return false;
        }
        let [c, d] = shared;
        let opposite = |v: u32| {
            self.vertex_faces.get(a).iter().any(|&f| {
                let t = self.face(f);
                t.contains(&b) && t.contains(&v)
            })
        };
        let roomy = |v: u32| self.vertex_faces.get(v).len() > 3;
        opposite(c) && opposite(d) && roomy(c) && roomy(d)
    }

    /// Whether moving `a` and `b` to `target` keeps every remaining triangle around
    /// them turned by at most 60° and not degenerate.
    fn keeps_triangles(&self, a: u32, b: u32, target: Position) -> bool {
        let p = target.get();
        [a, b].iter().all(|&v| {
            self.vertex_faces.get(v).iter().all(|&f| {
                let t = self.face(f);
                if t.contains(&a) && t.contains(&b) {
                    return true;
                }
                let corners = t.map(|u| self.positions[u as usize]);
                let moved = t.map(|u| {
                    if u == v {
                        p
                    } else {
                        self.positions[u as usize]
                    }
                });
                let before = triangle_normal(corners);
                let after = triangle_normal(moved);
                let (lb, la) = (norm(before), norm(after));
                let longest = (0..3)
                    .map(|i| norm(sub(moved[i], moved[(i + 1) % 3])))
                    .fold(0.0, f64::max);
                // Degenerate: its area against its longest edge's square.
                la > 1e-6 * longest * longest && dot(before, after) >= 0.5 * lb * la
            })
        })
    }

    /// Merge `a` into `b` at `target`.
    fn collapse(&mut self, a: u32, b: u32, target: Position) {
        let mut moved = std::mem::take(&mut self.scratch);
        moved.clear();
        let mut gone = [u32::MAX; 2];
        for &f in self.vertex_faces.get(a) {
            let t = self.faces[f as usize].expect("a live face");
            if t.contains(&b) {
                gone[usize::from(gone[0] != u32::MAX)] = f;
            } else {
                moved.push(f);
            }
        }
        self.vertex_faces.clear(a);
        // The two faces on the edge leave their corners' lists (`b` and the opposite
        // vertices on a manifold; whatever they are on other input).
        for f in gone.into_iter().filter(|&f| f != u32::MAX) {
            for v in self.face(f) {
                if v != a {
                    self.vertex_faces.remove(v, f);
                }
            }
            self.faces[f as usize] = None;
        }
        for &f in &moved {
            let t = self.faces[f as usize].as_mut().expect("a live face");
            for u in t.iter_mut() {
                if *u == a {
                    *u = b;
                }
            }
        }
        self.vertex_faces.extend(b, &moved);
        self.scratch = moved;
        self.positions[b as usize] = target.get();
        self.quadrics[b as usize] = self.quadrics[b as usize].add(&self.quadrics[a as usize]);
    }

    /// The live faces, with the live vertices renumbered in their order.
    fn into_mesh(self) -> SurfaceMesh {
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::new();
        for (v, (slot, &p)) in index.iter_mut().zip(&self.positions).enumerate() {
            if !self.vertex_faces.get(v as u32).is_empty() {
                *slot = positions.len() as u32;
                positions.push(p);
            }
        }
        let triangles = self
            .faces
            .into_iter()
            .flatten()
            .map(|t| t.map(|v| index[v as usize]))
            .collect();
        SurfaceMesh {
            positions,
            triangles,
        }
    }
}

/// A simplified vertex keeps at most this many triangles (or as many as it had, where
/// that is more): each vertex's list then sits in one place (a collapse that would
/// exceed it is refused), and no needle fans grow around one vertex.
pub const MAX_STAR: usize = 16;

/// Each vertex's triangles, in slots of its own: `cap[v]` from `start[v]`, `len[v]`
/// of them used.
struct Stars {
    start: Vec<usize>,
    cap: Vec<u32>,
    len: Vec<u32>,
    slots: Vec<u32>,
}

impl Stars {
    /// Room for [`MAX_STAR`] triangles per vertex (more where `of(v)` has more).
    fn new<'a>(n: usize, of: impl Fn(usize) -> &'a [u32]) -> Stars {
        let cap: Vec<u32> = (0..n).map(|v| of(v).len().max(MAX_STAR) as u32).collect();
        let mut start = Vec::with_capacity(n + 1);
        let mut total = 0usize;
        for &c in &cap {
            start.push(total);
            total += c as usize;
        }
        start.push(total);
        let mut slots = vec![u32::MAX; total];
        let mut len = vec![0u32; n];
        for v in 0..n {
            let faces = of(v);
            slots[start[v]..start[v] + faces.len()].copy_from_slice(faces);
            len[v] = faces.len() as u32;
        }
        Stars {
            start,
            cap,
            len,
            slots,
        }
    }

    fn get(&self, v: u32) -> &[u32] {
        let s = self.start[v as usize];
        &self.slots[s..s + self.len[v as usize] as usize]
    }

    /// Whether `b` has room for the triangles of `a` but the two they share.
    fn fit(&self, a: u32, b: u32) -> bool {
        let (la, lb) = (self.len[a as usize], self.len[b as usize]);
        la + lb <= self.cap[b as usize] + 4
    }

    fn clear(&mut self, v: u32) {
        self.len[v as usize] = 0;
    }

    /// Remove triangle `f` from `v`'s list, keeping the order of the rest.
    fn remove(&mut self, v: u32, f: u32) {
        let s = self.start[v as usize];
        let l = self.len[v as usize] as usize;
        if let Some(i) = self.slots[s..s + l].iter().position(|&g| g == f) {
            self.slots.copy_within(s + i + 1..s + l, s + i);
            self.len[v as usize] -= 1;
        }
    }

    /// Append `faces` to `v`'s list (room checked by [`Stars::fit`]).
    fn extend(&mut self, v: u32, faces: &[u32]) {
        debug_assert!(self.len[v as usize] as usize + faces.len() <= self.cap[v as usize] as usize);
        let s = self.start[v as usize] + self.len[v as usize] as usize;
        self.slots[s..s + faces.len()].copy_from_slice(faces);
        self.len[v as usize] += faces.len() as u32;
    }
}

fn triangle_normal(c: [[f64; 3]; 3]) -> [f64; 3] {
    cross(sub(c[1], c[0]), sub(c[2], c[0]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::octahedron;
    use crate::mesh::MeshReport;

    /// Every triangle split into four at its edge midpoints: the same shape.
    fn split(mesh: &SurfaceMesh) -> SurfaceMesh {
        let mut positions = mesh.positions.clone();
        let mut mids = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| {
            *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = scale(add(positions[a as usize], positions[b as usize]), 0.5);
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut triangles = Vec::new();
        for &[a, b, c] in &mesh.triangles {
            let (ab, bc, ca) = (
                mid(a, b, &mut positions),
                mid(b, c, &mut positions),
                mid(c, a, &mut positions),
            );
            triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        SurfaceMesh {
            positions,
            triangles,
        }
    }

    #[test]
    fn a_split_surface_collapses_back_without_error() {
        let octahedron = octahedron();
        let dense = split(&split(&octahedron));
        assert_eq!(dense.num_triangles(), 128);
        let options = SimplifyOptions {
            target: 8,
            max_error: 1e-9,
            ..Default::default()
        };
        let s = simplify(&dense, &options).unwrap();
        // The 60 collapses that undo the splits are flat: no error, down to 8.
        assert_eq!(s.stop, Stop::Target);
        assert_eq!(s.triangles, (128, 8));
        assert!(s.max_error < 1e-12, "{}", s.max_error);
        let report = MeshReport::new(&s.mesh);
        assert!(report.is_valid_solid());
        assert!((s.mesh.signed_volume() - octahedron.signed_volume()).abs() < 1e-9);
    }

    #[test]
    fn the_error_bound_stops_it_and_says_so() {
        let dense = split(&split(&octahedron()));
        let options = SimplifyOptions {
            target: 4,
            max_error: 1e-6,
            ..Default::default()
        };
        let s = simplify(&dense, &options).unwrap();
        let Stop::ErrorBound { next_error, bound } = s.stop else {
            panic!("{:?}", s.stop)
        };
        assert!(next_error > bound);
        // Every flat collapse was made, nothing beyond the bound.
        assert_eq!(s.triangles.1, 8);
        assert!(s.max_error <= bound);
    }

    #[test]
    fn the_thread_count_does_not_change_it() {
        // A sphere: every collapse is curved.
        let mut dense = split(&split(&split(&octahedron())));
        for p in &mut dense.positions {
            *p = scale(*p, 1.0 / norm(*p));
        }
        let options = SimplifyOptions {
            target: 60,
            max_error: 1.0,
            ..Default::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| simplify(&dense, &options).unwrap())
        };
        let one = run(1);
        assert!(one.max_error > 0.0, "curved collapses were made");
        assert_eq!(one, run(3));
    }

    #[test]
    fn a_mesh_that_is_not_a_closed_manifold_is_simplified_without_a_panic() {
        // A triangle given twice (its edges have three triangles and pass the
        // neighbour test), an edge with three triangles, a bowtie vertex and an open
        // border, next to a closed part; and a triangle with a repeated vertex is an
        // error.
        let mut mesh = split(&split(&octahedron()));
        let twice: Vec<[u32; 3]> = mesh.triangles.iter().step_by(7).copied().collect();
        mesh.triangles.extend(twice);
        let n = mesh.positions.len() as u32;
        mesh.positions
            .extend([[3.0, 0.0, 0.0], [3.0, 1.0, 0.0], [3.0, 0.0, 1.0]]);
        mesh.triangles
            .extend([[0, 2, n], [0, 2, n + 1], [0, 2, n + 2], [0, n, n + 1]]);
        let options = SimplifyOptions {
            target: 4,
            max_error: 10.0,
            ..Default::default()
        };
        let s = simplify(&mesh, &options).unwrap();
        assert!(s.triangles.1 < s.triangles.0);
        assert!(s
            .mesh
            .triangles
            .iter()
            .flatten()
            .all(|&v| (v as usize) < s.mesh.num_vertices()));
        mesh.triangles.push([1, 1, 2]);
        assert!(simplify(&mesh, &options).is_err());
    }

    #[test]
    fn a_tetrahedron_is_as_far_as_a_sphere_goes() {
        let s = simplify(
            &split(&octahedron()),
            &SimplifyOptions {
                target: 4,
                max_error: 10.0,
                ..Default::default()
            },
        )
        .unwrap();
        let report = MeshReport::new(&s.mesh);
        assert!(report.is_valid_solid());
        assert_eq!(s.mesh.num_triangles(), 4);
        assert!(s.mesh.signed_volume() > 0.0, "orientation kept");
    }
}
