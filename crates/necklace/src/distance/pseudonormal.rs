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
//! just off its front and its back at four points, and the triangle decides locally only
//! when the four agree. Triangles of a crossing, the ring round them, those at a
//! non-manifold or degenerate corner, and those whose samples disagree (a coplanar part
//! touching them) leave the sign to the winding number at `p`.

use rayon::prelude::*;

use super::bvh::Bvh;
use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Per triangle (in tree order): the face normal, the normals of its edges `ab`, `bc`,
/// `ca`, and of its corners `a`, `b`, `c`; and the sign in front of it and behind it
/// (`[0, 0]`: not decided locally).
pub(super) struct Pseudonormals {
    normals: Vec<[[f64; 3]; 7]>,
    sides: Vec<[i8; 2]>,
}

/// Barycentric coordinates this close to 0 put the closest point on an edge or corner.
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
    /// one fan, and no triangle is degenerate (the conditions of the theorem, but for
    /// self-crossings, which the caller must rule out). With `local` on a surface that
    /// meets those conditions and has no crossing, the same; otherwise the triangles
    /// away from crossings and defects decide locally (see the module doc), and `None`
    /// when the triangles are not a closed chain or none decides.
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
        let manifold = !bad.contains(&true);
        let local = match local {
            Some(local) if !(manifold && local.crossings.is_empty()) => local,
            _ if manifold => return Some(Self::build(mesh, bvh, &topology, &face_normals, None)),
            _ => return None,
        };
        if !is_closed_chain(mesh, &topology) {
            return None;
        }
        // The crossing triangles and the ring round them.
        for [f, g] in local.crossings {
            for &v in mesh.triangles[*f as usize]
                .iter()
                .chain(&mesh.triangles[*g as usize])
            {
                bad[v as usize] = true;
            }
        }
        let pseudonormals = Self::build(mesh, bvh, &topology, &face_normals, Some((&bad, &local)));
        pseudonormals
            .sides
            .iter()
            .any(|s| s[0] != 0)
            .then_some(pseudonormals)
    }

    /// The normals, and the sides: all `[+1, −1]` without `local`; else read off the
    /// winding number on triangles with no `bad` corner.
    fn build(
        mesh: &SurfaceMesh,
        bvh: &Bvh,
        topology: &Topology,
        face_normals: &[Option<[f64; 3]>],
        local: Option<(&[bool], &Local<'_>)>,
    ) -> Pseudonormals {
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
        let (normals, sides) = bvh
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
                    None => [1, -1],
                    Some((bad, _)) if t.iter().any(|&v| bad[v as usize]) => [0, 0],
                    Some((_, local)) => sampled_sides(tri, out[0], local.winding),
                };
                (out, sides)
            })
            .unzip();
        Pseudonormals { normals, sides }
    }

    /// The sign (−1 inside, +1 outside) at `p` whose closest point `q` lies on the tree
    /// triangle `t` with corners `tri`; `None` when `p` is (numerically) on the surface
    /// or the pseudonormal is too close to perpendicular to `p − q` to tell.
    pub fn sign(&self, t: usize, tri: &[[f64; 3]; 3], q: [f64; 3], p: [f64; 3]) -> Option<f64> {
        let [a, b, c] = *tri;
        let (v0, v1, v2) = (sub(b, a), sub(c, a), sub(q, a));
        let (d00, d01, d11) = (dot(v0, v0), dot(v0, v1), dot(v1, v1));
        let (d20, d21) = (dot(v2, v0), dot(v2, v1));
        let denom = d00 * d11 - d01 * d01;
        if denom.is_nan() || denom <= 0.0 {
            return None;
        }
        let wb = (d11 * d20 - d01 * d21) / denom;
        let wc = (d00 * d21 - d01 * d20) / denom;
        let wa = 1.0 - wb - wc;
        let zero = [wa, wb, wc].map(|w| w.abs() <= FEATURE_EPSILON);
        let normals = &self.normals[t];
        let n = match zero {
            // On an edge: ab has wc = 0, bc has wa = 0, ca has wb = 0.
            [false, false, true] => normals[1],
            [true, false, false] => normals[2],
            [false, true, false] => normals[3],
            // At a corner: the one whose own coordinate is not 0.
            [false, true, true] => normals[4],
            [true, false, true] => normals[5],
            [true, true, false] => normals[6],
            _ => normals[0],
        };
        let d = sub(p, q);
        let s = dot(d, n);
        let scale_ = norm(d) * norm(n);
        if !(s.abs() > 1e-9 * scale_ && scale_ > 0.0) {
            return None;
        }
        let side = self.sides[t][if s > 0.0 { 0 } else { 1 }];
        (side != 0).then_some(side as f64)
    }
}

/// Whether every edge is used as often in one direction as in the other: then the
/// triangles bound, and the winding number is an integer off the surface. (A
/// degenerate triangle's self-loop side has no edge, and uses none.)
fn is_closed_chain(mesh: &SurfaceMesh, topology: &Topology) -> bool {
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
    balance.iter().all(|&b| b == 0)
}

/// The signs just in front of triangle `tri` (unit normal `n`) and just behind it, from
/// the winding number at four points of it (the centroid and a point towards each
/// corner) offset by a hundredth of its inradius; `[0, 0]` unless the four agree on
/// each side, each within [`INTEGER_TOLERANCE`] of an integer, or for a triangle too
/// thin for an offset above the coordinates' rounding.
fn sampled_sides(
    tri: &[[f64; 3]; 3],
    n: [f64; 3],
    winding: &(dyn Fn([f64; 3]) -> f64 + Sync),
) -> [i8; 2] {
    let [a, b, c] = *tri;
    let area2 = norm(cross(sub(b, a), sub(c, a)));
    let perimeter = norm(sub(b, a)) + norm(sub(c, b)) + norm(sub(a, c));
    let inradius = area2 / perimeter;
    let magnitude = tri.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let offset = SAMPLE_OFFSET * inradius;
    let too_thin = offset.is_nan() || offset <= 1e-9 * magnitude;
    if n == [0.0; 3] || too_thin {
        return [0, 0];
    }
    let at = |w: [f64; 3]| add(add(scale(a, w[0]), scale(b, w[1])), scale(c, w[2]));
    let third = 1.0 / 3.0;
    let points = [
        at([third; 3]),
        at([0.6, 0.2, 0.2]),
        at([0.2, 0.6, 0.2]),
        at([0.2, 0.2, 0.6]),
    ];
    [1.0, -1.0].map(|direction| {
        let mut value = None;
        for &x in &points {
            let w = winding(add(x, scale(n, direction * offset)));
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
