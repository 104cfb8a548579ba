//! Inside/outside from the closest point: angle-weighted pseudonormals (Bærentzen &
//! Aanæs, "Signed distance computation using the angle weighted pseudonormal", 2005).
//!
//! For a closed, manifold, consistently oriented surface that does not cross itself,
//! the sign of `(p − q) · n` is the sign of the distance at `p`, where `q` is the closest
//! surface point and `n` the pseudonormal of the feature `q` lies on: the face's normal
//! inside a face, the sum of the two faces' normals on an edge, and at a vertex the sum
//! of its faces' normals weighted by their angles there. It costs nothing beyond the
//! closest point, where the winding number sums over the whole surface near it.
//!
//! **Surfaces that cross themselves** (overlapping parts, a bolt through a plate) or are
//! non-manifold at a few vertices keep the sign local on every triangle away from those
//! places. The open segment from `p` to its closest point `q` meets no surface (a point
//! of it on the surface would be closer), so `p` has the winding number of the side of
//! `q`'s triangle it lies on, next to `q`. Where the triangles form a closed chain (every
//! edge used as often in each direction), the winding number is an integer, constant on
//! each side of a triangle that nothing crosses or touches: it is read once per triangle,
//! just off its front and its back at four points whose nearest surface is the triangle
//! (closer in where another part lies a hair away), and the triangle decides locally
//! only when the four agree. Triangles of a crossing, the ring round them, those at a
//! non-manifold or degenerate corner, those of a fold (two faces with a common corner
//! that cross, which on an otherwise embedded surface takes it to this path too), those
//! of two parts that touch (a corner or an edge of one on the other, within
//! [`TOUCH_TOLERANCE`] of the diagonal: no crossing, yet
//! the winding number next to the contact is not the one off the triangle's middle, as
//! for a part buried in another but for one corner on its surface), and those whose
//! samples disagree leave the sign to the winding number at `p`.
//!
//! **Triangles that do not close** (holes, seams whose edges are used more often in one
//! direction than the other) make the winding number vary off the surface, but only
//! slowly far from those *unbalanced* edges: its gradient is the Biot–Savart integral
//! over them, at most `L / (4π r²)` at distance `r` from them (`L`: their length,
//! counted with their imbalance). A triangle then decides when the winding number just
//! off its centroid lies on one side of ½ by more than the change the bound allows along
//! the way to `p` (over the triangle, then along `p − q`); nearer the holes, the winding
//! number at `p` decides. One sample a side, not four: the bound covers the triangle
//! (`docs/decisions.md`).

use rayon::prelude::*;

use super::bvh::{segment_through, Bvh};
use crate::geom::{add, closest_on_segment, cross, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Per triangle (in tree order): the face normal, the normals of its edges `ab`, `bc`,
/// `ca`, and of its corners `a`, `b`, `c`; and the sign in front of it and behind it
/// (`[0, 0]`: not decided locally).
pub(super) struct Pseudonormals {
    normals: Vec<[[f64; 3]; 7]>,
    sides: Vec<[i8; 2]>,
    /// Where the triangles do not close: what bounds the winding number's change.
    open: Option<OpenChain>,
}

/// The bound on the winding number's change off a surface that does not close (see
/// the module doc), per tree triangle.
struct OpenChain {
    /// `L / 4π`: the unbalanced edges' length, each times its imbalance, over 4π.
    length: f64,
    /// Distance from the triangle's centroid to the nearest unbalanced edge, less
    /// [`OpenChain::extent`] (a lower bound for every point of the triangle).
    clearance: Vec<f64>,
    /// Largest distance from the triangle's centroid to a corner.
    extent: Vec<f64>,
    /// In front and behind: `|w − ½|` at the sample (0: undecided).
    margin: Vec<[f64; 2]>,
}

/// Allowance for the fast winding number's error on the samples (about 1e-3 of the
/// exact one away from the surface).
const FAST_ERROR: f64 = 0.05;

/// A closest point this close to a corner or an edge, as a fraction of the triangle's
/// longest edge (plus rounding at the coordinates' magnitude), lies on it.
const FEATURE_EPSILON: f64 = 1e-9;

/// The offset of a triangle's winding samples off its plane, as a fraction of its
/// inradius: far closer to it than to anything but a part touching it.
const SAMPLE_OFFSET: f64 = 1e-2;

/// A winding sample counts as the integer it is nearest when within this of it.
const INTEGER_TOLERANCE: f64 = 0.2;

/// Where the surface crosses itself or is not manifold: the crossing pairs of mesh faces
/// and the winding number, for [`Pseudonormals::new`] to decide the sign triangle by
/// triangle.
pub(super) struct Local<'a> {
    pub crossings: &'a [[u32; 2]],
    pub winding: &'a (dyn Fn([f64; 3]) -> f64 + Sync),
}

impl Pseudonormals {
    /// The pseudonormals of `mesh`. Without `local`: `None` unless every edge has
    /// exactly two faces that use it in opposite directions, every vertex's faces form
    /// one fan, no triangle is degenerate and no two faces with a common corner cross
    /// (the conditions of the theorem, but for crossings of faces without a common
    /// corner, which the caller must rule out). With `local` on a surface that
    /// meets those conditions and has no crossing, the same; otherwise the triangles
    /// away from crossings and defects decide locally (see the module doc), and `None`
    /// when none decides (on triangles that do not close, within the bound of the
    /// module doc).
    pub fn new(mesh: &SurfaceMesh, bvh: &Bvh, local: Option<Local<'_>>) -> Option<Pseudonormals> {
        if bvh.faces.len() != mesh.triangles.len() {
            return None;
        }
        let topology = Topology::new(mesh);
        let unit = |n: [f64; 3]| {
            let l = norm(n);
            (l > 0.0 && l.is_finite()).then(|| scale(n, 1.0 / l))
        };
        let face_normals: Vec<Option<[f64; 3]>> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|f| unit(mesh.face_normal_scaled(f)))
            .collect();
        // Vertices where the theorem's conditions fail.
        let mut bad = vec![false; mesh.num_vertices()];
        for e in topology
            .boundary_edges()
            .into_iter()
            .chain(topology.non_manifold_edges())
            .chain(topology.inconsistently_oriented_edges(mesh))
        {
            for v in topology.edges()[e] {
                bad[v as usize] = true;
            }
        }
        for v in topology.non_manifold_vertices(mesh) {
            bad[v] = true;
        }
        for (f, t) in mesh.triangles.iter().enumerate() {
            if face_normals[f].is_none() {
                for &v in t {
                    bad[v as usize] = true;
                }
            }
        }
        // Folds: faces with a corner in common that cross each other, which the
        // crossing test (of faces with none in common) does not see.
        for v in folded_vertices(mesh, bvh) {
            bad[v as usize] = true;
        }
        let manifold = !bad.contains(&true);
        let local = match local {
            Some(local) if !(manifold && local.crossings.is_empty()) => local,
            _ if manifold => return Some(Self::build(mesh, bvh, &topology, &face_normals, None).0),
            _ => return None,
        };
        let unbalanced = unbalanced_edges(mesh, &topology);
        // The crossing triangles and the ring round them.
        for [f, g] in local.crossings {
            for &v in mesh.triangles[*f as usize]
                .iter()
                .chain(&mesh.triangles[*g as usize])
            {
                bad[v as usize] = true;
            }
        }
        // Parts that touch without crossing: the winding number next to the contact
        // is not the one off the triangle's middle.
        for v in touching_vertices(mesh, bvh, TOUCH_TOLERANCE * bvh.diagonal()) {
            bad[v as usize] = true;
        }
        let open = !unbalanced.is_empty();
        let (mut pseudonormals, margin) = Self::build(
            mesh,
            bvh,
            &topology,
            &face_normals,
            Some((&bad, &local, open)),
        );
        if open {
            pseudonormals.open = Some(open_chain(bvh, &unbalanced, margin));
        }
        pseudonormals
            .sides
            .iter()
            .any(|s| s[0] != 0)
            .then_some(pseudonormals)
    }

    /// The normals, and the sides: all `[+1, −1]` without `local`; else read off the
    /// winding number on triangles with no `bad` corner, as integers on a closed chain
    /// ([`sampled_sides`]) or as sides of ½ with their margins where it is `open`
    /// ([`sampled_halves`]; the margins are returned, 0 elsewhere).
    fn build(
        mesh: &SurfaceMesh,
        bvh: &Bvh,
        topology: &Topology,
        face_normals: &[Option<[f64; 3]>],
        local: Option<(&[bool], &Local<'_>, bool)>,
    ) -> (Pseudonormals, Vec<[f64; 2]>) {
        let mut vertex_normals = vec![[0.0; 3]; mesh.num_vertices()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            let Some(normal) = face_normals[f] else {
                continue;
            };
            let p = t.map(|v| mesh.positions[v as usize]);
            for i in 0..3 {
                let e1 = sub(p[(i + 1) % 3], p[i]);
                let e2 = sub(p[(i + 2) % 3], p[i]);
                let angle = (dot(e1, e2) / (norm(e1) * norm(e2)))
                    .clamp(-1.0, 1.0)
                    .acos();
                let v = t[i] as usize;
                vertex_normals[v] = add(vertex_normals[v], scale(normal, angle));
            }
        }
        let (normals, (sides, margins)): (Vec<_>, (Vec<_>, Vec<_>)) = bvh
            .faces
            .par_iter()
            .zip(&bvh.tris)
            .map(|(&f, tri)| {
                let f = f as usize;
                let t = mesh.triangles[f];
                let mut out = [[0.0; 3]; 7];
                out[0] = face_normals[f].unwrap_or([0.0; 3]);
                for i in 0..3 {
                    if let Some(e) = topology.face_edge(f, i) {
                        out[1 + i] = topology.edge_faces(e).iter().fold([0.0; 3], |s, &g| {
                            add(s, face_normals[g as usize].unwrap_or([0.0; 3]))
                        });
                    }
                    out[4 + i] = vertex_normals[t[i] as usize];
                }
                let sides = match local {
                    None => ([1, -1], [0.0; 2]),
                    Some((bad, _, _)) if t.iter().any(|&v| bad[v as usize]) => ([0, 0], [0.0; 2]),
                    Some((_, local, false)) => {
                        (sampled_sides(tri, out[0], bvh, local.winding), [0.0; 2])
                    }
                    Some((_, local, true)) => sampled_halves(tri, out[0], bvh, local.winding),
                };
                (out, sides)
            })
            .unzip();
        let pseudonormals = Pseudonormals {
            normals,
            sides,
            open: None,
        };
        (pseudonormals, margins)
    }

    /// The sign (−1 inside, +1 outside) at `p` whose closest point `q` lies on the tree
    /// triangle `t` with corners `tri`; `None` when `p` is (numerically) on the surface
    /// or the pseudonormal is too close to perpendicular to `p − q` to tell.
    pub fn sign(&self, t: usize, tri: &[[f64; 3]; 3], q: [f64; 3], p: [f64; 3]) -> Option<f64> {
        let [a, b, c] = *tri;
        // The feature `q` lies on, by its distance to the corners and edges: barycentric
        // coordinates lose their digits on a needle (on a gear's face with a 0.02°
        // corner, a point on an edge came out 1.1e-9 inside it, and the face's normal
        // gave the wrong side of the sharp edge). Near an edge but inside, `p − q` is
        // along the face's normal, and the edge's pseudonormal (the sum of its faces')
        // gives the same sign unless the faces fold flat onto each other (a fold, not
        // decided here).
        let edges = [sub(b, a), sub(c, b), sub(a, c)];
        let longest = edges.iter().map(|e| norm(*e)).fold(0.0, f64::max);
        let magnitude = tri.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let tolerance = FEATURE_EPSILON * longest + 4.0 * f64::EPSILON * magnitude;
        if !(tolerance.is_finite() && longest > 0.0) {
            return None;
        }
        let near = |x: [f64; 3]| norm(sub(q, x)) <= tolerance;
        let normals = &self.normals[t];
        let n = if let Some(k) = [a, b, c].iter().position(|&x| near(x)) {
            normals[4 + k]
        } else {
            let off_edge =
                [(a, b), (b, c), (c, a)].map(|(x, y)| norm(sub(q, closest_on_segment(q, x, y))));
            let (k, off) = off_edge
                .iter()
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |best, (k, &o)| if o < best.1 { (k, o) } else { best },
                );
            if off <= tolerance {
                normals[1 + k]
            } else {
                normals[0]
            }
        };
        let d = sub(p, q);
        let s = dot(d, n);
        let scale_ = norm(d) * norm(n);
        if !(s.abs() > 1e-9 * scale_ && scale_ > 0.0) {
            return None;
        }
        let k = if s > 0.0 { 0 } else { 1 };
        let side = self.sides[t][k];
        if side == 0 {
            return None;
        }
        if let Some(open) = &self.open {
            // The change of the winding number from the samples to `p`: over the
            // triangle (at most twice its extent), then along `p − q`, all within
            // `clearance − |p − q|` of the unbalanced edges.
            let along = norm(d);
            let r = open.clearance[t] - along;
            if r.is_nan() || r <= 0.0 {
                return None;
            }
            let change = (2.0 * open.extent[t] + along) * open.length / (r * r) + FAST_ERROR;
            if change.is_nan() || change >= open.margin[t][k] {
                return None;
            }
        }
        Some(side as f64)
    }
}

/// Two triangles that share no vertex touch when a corner of one or a point of their
/// edges comes within this fraction of the bounding-box diagonal of the other.
const TOUCH_TOLERANCE: f64 = 1e-7;

/// The corners of the pairs of faces that have exactly one corner in common and cross
/// each other (the edge of one opposite that corner through the other): a fold, where a
/// face pokes through its neighbour's neighbour round a shared corner, so the surface
/// crosses itself there though no two faces without a common corner cross. (An edge
/// from the common corner meets the other face's plane only there, unless it lies in
/// it: tested, it would find folds in rounding wherever a fan is nearly flat.) Sorted,
/// without repeats.
fn folded_vertices(mesh: &SurfaceMesh, bvh: &Bvh) -> Vec<u32> {
    vertices_of_pairs(mesh, bvh, 0.0, |t, u, vt, vu| {
        let mut common = (0..3).filter(|&k| vu.contains(&vt[k]));
        let (Some(k), None) = (common.next(), common.next()) else {
            return false;
        };
        let Some(l) = (0..3).find(|&l| vu[l] == vt[k]) else {
            return false;
        };
        let opposite = |tri: &[[f64; 3]; 3], c: usize| (tri[(c + 1) % 3], tri[(c + 2) % 3]);
        let ((a, b), (c, d)) = (opposite(t, k), opposite(u, l));
        segment_through(a, b, u) || segment_through(c, d, t)
    })
}

/// The vertices of the pairs of triangles that share no vertex and touch: a corner of
/// one on the other, or an edge of one meeting an edge of the other, within
/// `tolerance`. A crossing meets along a segment and is found as one; a touch meets
/// at a point or along a shared plane, which the crossing test does not report, yet
/// the winding number changes there: a triangle buried in another part has the same
/// winding number on both sides off its middle, but not at a corner where that part's
/// surface touches it. Sorted, without repeats.
fn touching_vertices(mesh: &SurfaceMesh, bvh: &Bvh, tolerance: f64) -> Vec<u32> {
    vertices_of_pairs(mesh, bvh, tolerance, |t, u, vt, vu| {
        !vt.iter().any(|v| vu.contains(v)) && triangles_touch(t, u, tolerance)
    })
}

/// The corners of the pairs of faces whose boxes, grown by `grow`, meet and for which
/// `pair(corners, corners, vertices, vertices)` holds. Sorted, without repeats.
fn vertices_of_pairs(
    mesh: &SurfaceMesh,
    bvh: &Bvh,
    grow: f64,
    pair: impl Fn(&[[f64; 3]; 3], &[[f64; 3]; 3], [u32; 3], [u32; 3]) -> bool + Sync,
) -> Vec<u32> {
    let mut vertices: Vec<u32> = (0..bvh.tris.len())
        .into_par_iter()
        .map_init(Vec::new, |candidates, i| {
            let tri = &bvh.tris[i];
            let (lo, hi) = crate::geom::bounds(tri.iter().copied());
            candidates.clear();
            bvh.overlapping(lo.map(|x| x - grow), hi.map(|x| x + grow), candidates);
            let fi = bvh.faces[i];
            let vi = mesh.triangles[fi as usize];
            let mut out = Vec::new();
            for &j in candidates.iter() {
                let fj = bvh.faces[j];
                let vj = mesh.triangles[fj as usize];
                if fj > fi && pair(tri, &bvh.tris[j], vi, vj) {
                    out.extend(vi);
                    out.extend(vj);
                }
            }
            out
        })
        .flatten()
        .collect();
    vertices.sort_unstable();
    vertices.dedup();
    vertices
}

/// Whether a corner of either triangle lies within `tolerance` of the other, or an edge
/// of one within `tolerance` of an edge of the other.
fn triangles_touch(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], tolerance: f64) -> bool {
    let near = |p: [f64; 3], q: [f64; 3]| norm(sub(p, q)) <= tolerance;
    let corner_on = |t: &[[f64; 3]; 3], p: [f64; 3]| {
        near(p, crate::geom::closest_on_triangle(p, t[0], t[1], t[2]))
    };
    a.iter().any(|&p| corner_on(b, p))
        || b.iter().any(|&p| corner_on(a, p))
        || (0..3).any(|i| {
            (0..3).any(|j| {
                let (p, q) = segments_closest(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
                near(p, q)
            })
        })
}

/// The closest points of the segments `p0p1` and `q0q1` (Ericson, *Real-Time Collision
/// Detection*, 5.1.9; a zero-length segment is its point).
fn segments_closest(
    p0: [f64; 3],
    p1: [f64; 3],
    q0: [f64; 3],
    q1: [f64; 3],
) -> ([f64; 3], [f64; 3]) {
    let (d1, d2, r) = (sub(p1, p0), sub(q1, q0), sub(p0, q0));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let point = |o: [f64; 3], d: [f64; 3], t: f64| add(o, scale(d, t));
    if a <= 0.0 && e <= 0.0 {
        return (p0, q0);
    }
    let (s, t) = if a <= 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (point(p0, d1, s), point(q0, d2, t))
}

/// The edges used more often in one direction than in the other, with their ends and
/// imbalance: none exactly when the triangles bound, and the winding number is an
/// integer off the surface. (A degenerate triangle's self-loop side has no edge, and
/// uses none.)
fn unbalanced_edges(mesh: &SurfaceMesh, topology: &Topology) -> Vec<([f64; 3], [f64; 3], u32)> {
    let mut balance = vec![0i32; topology.num_edges()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for (i, &start) in t.iter().enumerate() {
            if let Some(e) = topology.face_edge(f, i) {
                balance[e] += if start == topology.edges()[e][0] {
                    1
                } else {
                    -1
                };
            }
        }
    }
    let at = |v: u32| mesh.positions[v as usize];
    balance
        .iter()
        .enumerate()
        .filter(|(_, &b)| b != 0)
        .map(|(e, &b)| {
            let [u, v] = topology.edges()[e];
            (at(u), at(v), b.unsigned_abs())
        })
        .collect()
}

/// The bound's parts on every tree triangle of `bvh` (the [`OpenChain`]), with the
/// samples' `margin`s ([`sampled_halves`]).
fn open_chain(
    bvh: &Bvh,
    unbalanced: &[([f64; 3], [f64; 3], u32)],
    margin: Vec<[f64; 2]>,
) -> OpenChain {
    let length = unbalanced
        .iter()
        .map(|&(a, b, k)| k as f64 * norm(sub(b, a)))
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI);
    // The unbalanced edges as degenerate triangles, for nearest-point queries.
    let edges = Bvh::build(
        unbalanced.iter().map(|&(a, b, _)| [a, b, b]).collect(),
        (0..unbalanced.len() as u32).collect(),
    );
    let (clearance, extent) = bvh
        .tris
        .par_iter()
        .map(|tri| {
            let centroid = scale(add(add(tri[0], tri[1]), tri[2]), 1.0 / 3.0);
            let extent = tri
                .iter()
                .map(|&c| norm(sub(c, centroid)))
                .fold(0.0, f64::max);
            let to_edges = edges
                .nearest(centroid)
                .map_or(f64::INFINITY, |n| n.2.sqrt());
            (to_edges - extent, extent)
        })
        .unzip();
    OpenChain {
        length,
        clearance,
        extent,
        margin,
    }
}

/// The signs just in front of triangle `tri` (unit normal `n`) and just behind it, from
/// the winding number at four points of it (the centroid and a point towards each
/// corner) offset by a hundredth of its inradius or less ([`sample_points`]); `[0, 0]`
/// unless the four agree on each side, each within [`INTEGER_TOLERANCE`] of an
/// integer, or for a triangle too thin for an offset above the coordinates' rounding.
fn sampled_sides(
    tri: &[[f64; 3]; 3],
    n: [f64; 3],
    bvh: &Bvh,
    winding: &(dyn Fn([f64; 3]) -> f64 + Sync),
) -> [i8; 2] {
    let Some(points) = sample_points(tri, n, bvh) else {
        return [0, 0];
    };
    points.map(|points| {
        let mut value = None;
        for x in points {
            let w = winding(x);
            let rounded = w.round();
            let off_integer =
                (w - rounded).abs().is_nan() || (w - rounded).abs() > INTEGER_TOLERANCE;
            if off_integer || value.is_some_and(|v| v != rounded) {
                return 0;
            }
            value = Some(rounded);
        }
        // Inside where the winding number is at least ½ (`SurfaceDistance::is_inside`).
        if value.is_some_and(|v| v >= 1.0) {
            -1
        } else {
            1
        }
    })
}

/// Where the triangles do not close: the side of ½ the winding number lies on just in
/// front of `tri`'s centroid and just behind it (the first points of [`sampled_sides`]),
/// and its distance from ½ (the margin).
fn sampled_halves(
    tri: &[[f64; 3]; 3],
    n: [f64; 3],
    bvh: &Bvh,
    winding: &(dyn Fn([f64; 3]) -> f64 + Sync),
) -> ([i8; 2], [f64; 2]) {
    let Some(points) = sample_points(tri, n, bvh) else {
        return ([0, 0], [0.0; 2]);
    };
    let halves = points.map(|points| {
        let w = winding(points[0]);
        match w {
            w if w >= 0.5 => (-1, w - 0.5),
            w if w < 0.5 => (1, 0.5 - w),
            _ => (0, 0.0), // NaN
        }
    });
    ([halves[0].0, halves[1].0], [halves[0].1, halves[1].1])
}

/// The four sample points of [`sampled_sides`] in front of `tri` and behind it, each
/// with `tri` for its nearest surface (no other triangle nearer than the offset: a part
/// lying a hair off the triangle, closer than [`SAMPLE_OFFSET`] × its inradius, would
/// lend the samples its winding number); the offset is cut by 16, twice, until they
/// are. `None` for a triangle without a normal, too thin for an offset above the
/// rounding, or with something nearer than the smallest offset.
fn sample_points(tri: &[[f64; 3]; 3], n: [f64; 3], bvh: &Bvh) -> Option<[[[f64; 3]; 4]; 2]> {
    let [a, b, c] = *tri;
    let area2 = norm(cross(sub(b, a), sub(c, a)));
    let perimeter = norm(sub(b, a)) + norm(sub(c, b)) + norm(sub(a, c));
    let inradius = area2 / perimeter;
    let magnitude = tri.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    if n == [0.0; 3] {
        return None;
    }
    let at = |w: [f64; 3]| add(add(scale(a, w[0]), scale(b, w[1])), scale(c, w[2]));
    let third = 1.0 / 3.0;
    let feet = [
        at([third; 3]),
        at([0.6, 0.2, 0.2]),
        at([0.2, 0.6, 0.2]),
        at([0.2, 0.2, 0.6]),
    ];
    for cut in [1.0, 1.0 / 16.0, 1.0 / 256.0] {
        let offset = cut * SAMPLE_OFFSET * inradius;
        if offset.is_nan() || offset <= 1e-9 * magnitude {
            return None;
        }
        let points =
            [1.0, -1.0].map(|direction| feet.map(|x| add(x, scale(n, direction * offset))));
        // Nothing but `tri` within the offset (less a margin for rounding).
        let limit = (offset * (1.0 - 1e-6)).powi(2);
        if points
            .iter()
            .flatten()
            .all(|&x| bvh.nearest_within(x, limit).is_none())
        {
            return Some(points);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::{winding, SurfaceDistance};

    /// Append the cube `[origin, origin + size]` (faces outward) to `mesh`.
    fn add_cube(mesh: &mut SurfaceMesh, origin: [f64; 3], size: [f64; 3]) {
        let o = mesh.positions.len() as u32;
        mesh.positions.extend(
            (0..8).map(|i: u32| [0, 1, 2].map(|k| origin[k] + size[k] * f64::from((i >> k) & 1))),
        );
        for t in [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ] {
            mesh.triangles.push(t.map(|v| o + v));
        }
    }

    /// Append the tetrahedron of `corners` (faces outward) to `mesh`.
    fn add_tetrahedron(mesh: &mut SurfaceMesh, corners: [[f64; 3]; 4]) {
        let o = mesh.positions.len() as u32;
        mesh.positions.extend(corners);
        let [a, b, c, d] = corners;
        let outward = dot(sub(d, a), cross(sub(b, a), sub(c, a))) < 0.0;
        for t in [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]] {
            let t = if outward { t } else { [t[0], t[2], t[1]] };
            mesh.triangles.push(t.map(|v| o + v));
        }
    }

    /// `mesh` with two tetrahedra that cross each other far from it (so that its
    /// triangles decide their sign locally), its tree and its local pseudonormals.
    fn deciding_locally(mut mesh: SurfaceMesh) -> (SurfaceMesh, Bvh, Pseudonormals) {
        add_tetrahedron(
            &mut mesh,
            [
                [16.0, 0.0, 0.0],
                [18.0, 0.0, 0.0],
                [16.0, 2.0, 0.0],
                [16.0, 0.0, 2.0],
            ],
        );
        add_tetrahedron(
            &mut mesh,
            [
                [16.5, 0.3, 0.3],
                [18.5, 0.3, 0.3],
                [16.5, 2.3, 0.3],
                [16.5, 0.3, 2.3],
            ],
        );
        let crossings = SurfaceDistance::new(&mesh).self_intersections(&mesh.triangles);
        assert!(!crossings.is_empty());
        let tris: Vec<[[f64; 3]; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| mesh.positions[v as usize]))
            .collect();
        let bvh = Bvh::build(tris, (0..mesh.triangles.len() as u32).collect());
        let winding = |p: [f64; 3]| winding::exact(&bvh, p);
        let local = Local {
            crossings: &crossings,
            winding: &winding,
        };
        let pseudonormals = Pseudonormals::new(&mesh, &bvh, Some(local)).expect("some decide");
        (mesh, bvh, pseudonormals)
    }

    /// A cube [0, 2]³ with a tetrahedron inside whose one corner is the cube's corner
    /// (2, 2, 2). The buried tetrahedron's faces have the solid on both sides off their
    /// middle, but the points of the cube's outer octant, whose closest point is that
    /// corner (a tie between the two parts), are outside: a face at the contact must not
    /// call them inside.
    #[test]
    fn a_face_that_touches_another_part_at_a_corner_does_not_decide_there() {
        let mut mesh = SurfaceMesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        };
        add_cube(&mut mesh, [0.0; 3], [2.0; 3]);
        add_tetrahedron(
            &mut mesh,
            [
                [2.0, 2.0, 2.0],
                [1.0, 1.6, 1.6],
                [1.6, 1.0, 1.6],
                [1.6, 1.6, 1.0],
            ],
        );
        let (_, bvh, pseudonormals) = deciding_locally(mesh);
        let winding = |p: [f64; 3]| winding::exact(&bvh, p);
        let corner = [2.0, 2.0, 2.0];
        let mut decided = 0;
        for (t, tri) in bvh.tris.iter().enumerate() {
            if !tri.contains(&corner) {
                continue;
            }
            for p in [[2.5, 2.5, 2.5], [2.1, 2.9, 2.3], [3.0, 2.01, 2.01]] {
                assert_eq!(winding(p).round(), 0.0);
                let sign = pseudonormals.sign(t, tri, corner, p);
                assert_ne!(sign, Some(-1.0), "face {} calls {p:?} inside", bvh.faces[t]);
                decided += usize::from(sign.is_some());
            }
        }
        // The cube's faces at the corner touch the tetrahedron there too, and leave
        // the sign to the winding number like the buried faces.
        assert_eq!(decided, 0);
        // Away from the contact the cube's faces decide: below the bottom face.
        let bottom = bvh
            .tris
            .iter()
            .position(|t| t.iter().all(|p| p[2] == 0.0) && t.contains(&[0.0, 0.0, 0.0]))
            .expect("a bottom face at the origin");
        let q = [0.5, 0.5, 0.0];
        let sign = pseudonormals.sign(bottom, &bvh.tris[bottom], q, [0.5, 0.5, -1.0]);
        assert_eq!(sign, Some(1.0));
    }

    /// Two cubes stacked with a gap of 10⁻³ between them, less than the samples'
    /// first offset (a hundredth of a face's inradius, 0.006 here) and far more than a
    /// touch: the lower cube's top faces read their winding number closer in, and call
    /// the gap outside.
    #[test]
    fn a_part_a_hair_away_does_not_lend_its_winding_number_to_the_samples() {
        let gap = 1e-3;
        let mut mesh = SurfaceMesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        };
        add_cube(&mut mesh, [0.0; 3], [2.0; 3]);
        add_cube(&mut mesh, [0.0, 0.0, 2.0 + gap], [2.0; 3]);
        let (_, bvh, pseudonormals) = deciding_locally(mesh);
        let mut decided = 0;
        for (t, tri) in bvh.tris.iter().enumerate() {
            if !tri.iter().all(|p| p[2] == 2.0) {
                continue;
            }
            for (x, y) in [(0.5, 1.0), (1.0, 0.5), (1.5, 1.0), (1.0, 1.5)] {
                let q = [x, y, 2.0];
                let on = crate::geom::closest_on_triangle(q, tri[0], tri[1], tri[2]);
                if norm(sub(on, q)) > 0.0 {
                    continue;
                }
                let sign = pseudonormals.sign(t, tri, q, [x, y, 2.0 + 0.5 * gap]);
                assert_eq!(sign, Some(1.0), "face {} at {q:?}", bvh.faces[t]);
                decided += 1;
            }
        }
        assert_eq!(decided, 4);
    }
}
