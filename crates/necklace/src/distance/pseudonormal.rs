//! Inside/outside from the closest point: angle-weighted pseudonormals (Bærentzen &
//! Aanæs, "Signed distance computation using the angle weighted pseudonormal", 2005).
//!
//! For a closed, manifold, consistently oriented surface that does not cross itself,
//! the sign of `(p − q) · n` is the sign of the distance at `p`, where `q` is the closest
//! surface point and `n` the pseudonormal of the feature `q` lies on: the face's normal
//! inside a face, the sum of the two faces' normals on an edge, and at a vertex the sum
//! of its faces' normals weighted by their angles there. It costs nothing beyond the
//! closest point, where the winding number sums over the whole surface near it.

use rayon::prelude::*;

use super::bvh::Bvh;
use crate::geom::{add, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Per triangle (in tree order): the face normal, the normals of its edges `ab`, `bc`,
/// `ca`, and of its corners `a`, `b`, `c`.
pub(super) struct Pseudonormals {
    normals: Vec<[[f64; 3]; 7]>,
}

/// Barycentric coordinates this close to 0 put the closest point on an edge or corner.
const FEATURE_EPSILON: f64 = 1e-9;

impl Pseudonormals {
    /// The pseudonormals of `mesh`, or `None` unless every edge has exactly two faces
    /// that use it in opposite directions, every vertex's faces form one fan, and no
    /// triangle is degenerate (the conditions of the theorem, but for self-crossings,
    /// which the caller must rule out).
    pub fn new(mesh: &SurfaceMesh, bvh: &Bvh) -> Option<Pseudonormals> {
        let topology = Topology::new(mesh);
        if !topology.boundary_edges().is_empty()
            || !topology.non_manifold_edges().is_empty()
            || !topology.inconsistently_oriented_edges(mesh).is_empty()
            || !topology.non_manifold_vertices(mesh).is_empty()
            || bvh.faces.len() != mesh.triangles.len()
        {
            return None;
        }
        let unit = |n: [f64; 3]| {
            let l = norm(n);
            (l > 0.0 && l.is_finite()).then(|| scale(n, 1.0 / l))
        };
        let face_normals: Vec<[f64; 3]> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|f| unit(mesh.face_normal_scaled(f)))
            .collect::<Option<_>>()?;
        let mut vertex_normals = vec![[0.0; 3]; mesh.num_vertices()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            let p = t.map(|v| mesh.positions[v as usize]);
            for i in 0..3 {
                let e1 = sub(p[(i + 1) % 3], p[i]);
                let e2 = sub(p[(i + 2) % 3], p[i]);
                let angle = (dot(e1, e2) / (norm(e1) * norm(e2)))
                    .clamp(-1.0, 1.0)
                    .acos();
                let v = t[i] as usize;
                vertex_normals[v] = add(vertex_normals[v], scale(face_normals[f], angle));
            }
        }
        let normals = bvh
            .faces
            .par_iter()
            .map(|&f| {
                let f = f as usize;
                let t = mesh.triangles[f];
                let mut out = [[0.0; 3]; 7];
                out[0] = face_normals[f];
                for i in 0..3 {
                    let e = topology.face_edge(f, i)?;
                    let sum = topology
                        .edge_faces(e)
                        .iter()
                        .fold([0.0; 3], |s, &g| add(s, face_normals[g as usize]));
                    out[1 + i] = sum;
                    out[4 + i] = vertex_normals[t[i] as usize];
                }
                Some(out)
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Pseudonormals { normals })
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
        (s.abs() > 1e-9 * scale_ && scale_ > 0.0).then(|| s.signum())
    }
}
