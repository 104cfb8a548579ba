//! What a loop does to the surface: the edges it crosses, its Z2 homology class, and
//! the areas of the two sides it cuts the surface into.
//!
//! A tightened loop is a cyclic sequence of [`SurfacePoint`]s; each segment between two
//! consecutive points lies in one face (for a segment along an edge, the lower-indexed
//! of its faces). The loop *crosses* the edge of a point on an edge when the faces
//! before and after it differ; at a vertex it crosses the edges met when turning around
//! the vertex from the face before to the face after (either way round: the two differ
//! by a small loop around the vertex, which meets every cycle of edges an even number
//! of times, so the class is the same). Entry points: [`crossings`], [`sides`].

use crate::mesh::{SurfaceMesh, Topology};

use super::tighten::SurfacePoint;

/// The edges a closed loop crosses (with repeats).
pub fn crossings(
    surface: &SurfaceMesh,
    topology: &Topology,
    points: &[SurfacePoint],
) -> Vec<usize> {
    let n = points.len();
    // `faces[i]` holds the segment from point `i` to point `i + 1`.
    let faces: Vec<usize> = (0..n)
        .map(|i| segment_face(surface, topology, points[i], points[(i + 1) % n]))
        .collect();
    let mut crossed = Vec::new();
    for i in 0..n {
        let (before, after) = (faces[(i + n - 1) % n], faces[i]);
        if before == after {
            continue;
        }
        match points[i] {
            SurfacePoint::Edge { edge, .. } => {
                if let Some(e) = edge_index(surface, topology, edge[0], edge[1]) {
                    crossed.push(e);
                }
            }
            SurfacePoint::Vertex { vertex } => {
                turn_around(surface, topology, vertex, before, after, &mut crossed)
            }
        }
    }
    crossed
}

/// The areas of the two sides of a loop on its surface component, smaller first.
/// Vertices flood across every edge the loop does not cross, from the two ends of the
/// first crossed edge, never through a vertex the loop passes; each face gives a third
/// of its area to the side of each corner (corners on the loop give theirs to neither).
/// `None` when both floods meet (the loop does not separate) or it crosses nothing.
pub fn sides(
    surface: &SurfaceMesh,
    topology: &Topology,
    points: &[SurfacePoint],
    crossed: &[usize],
) -> Option<[f64; 2]> {
    let mut blocked = vec![false; topology.num_edges()];
    for &e in crossed {
        blocked[e] = true;
    }
    let mut side = vec![0u8; surface.num_vertices()];
    const ON_LOOP: u8 = 3;
    for p in points {
        if let SurfacePoint::Vertex { vertex } = p {
            side[*vertex as usize] = ON_LOOP;
        }
    }
    let first = topology.edges()[*crossed.first()?];
    for (s, &root) in first.iter().enumerate() {
        let label = s as u8 + 1;
        match side[root as usize] {
            0 => side[root as usize] = label,
            _ => return None,
        }
        let mut stack = vec![root as usize];
        while let Some(v) = stack.pop() {
            for &f in topology.vertex_faces(v) {
                let t = surface.triangles[f as usize];
                let k = t.iter().position(|&u| u as usize == v).unwrap_or(0);
                for (side_index, u) in [(k, t[(k + 1) % 3]), ((k + 2) % 3, t[(k + 2) % 3])] {
                    let Some(e) = topology.face_edge(f as usize, side_index) else {
                        continue;
                    };
                    if blocked[e] {
                        continue;
                    }
                    match side[u as usize] {
                        0 => {
                            side[u as usize] = label;
                            stack.push(u as usize);
                        }
                        l if l == label || l == ON_LOOP => {}
                        _ => return None,
                    }
                }
            }
        }
    }
    let mut area = [0.0; 2];
    for (f, t) in surface.triangles.iter().enumerate() {
        let third = face_area(surface, f) / 3.0;
        for &v in t {
            if let l @ 1..=2 = side[v as usize] {
                area[usize::from(l) - 1] += third;
            }
        }
    }
    Some(if area[0] <= area[1] {
        area
    } else {
        [area[1], area[0]]
    })
}

fn face_area(surface: &SurfaceMesh, f: usize) -> f64 {
    0.5 * crate::geom::norm(surface.face_normal_scaled(f))
}

/// The vertices a point lies on: one (a vertex) or two (an edge).
pub(super) fn carrier(p: SurfacePoint) -> ([u32; 2], usize) {
    match p {
        SurfacePoint::Edge { edge, .. } => (edge, 2),
        SurfacePoint::Vertex { vertex } => ([vertex, vertex], 1),
    }
}

/// The lowest-indexed face containing both points' carriers (the first face of `p`'s
/// carrier when none does, which a valid loop never needs).
fn segment_face(
    surface: &SurfaceMesh,
    topology: &Topology,
    p: SurfacePoint,
    q: SurfacePoint,
) -> usize {
    let (pv, pn) = carrier(p);
    let (qv, qn) = carrier(q);
    let candidates = topology.vertex_faces(pv[0] as usize);
    let contains = |f: u32, v: u32| surface.triangles[f as usize].contains(&v);
    candidates
        .iter()
        .copied()
        .filter(|&f| pv[..pn].iter().chain(&qv[..qn]).all(|&v| contains(f, v)))
        .min()
        .or_else(|| candidates.iter().copied().min())
        .map_or(0, |f| f as usize)
}

/// The edge between vertices `a` and `b`, if any.
fn edge_index(surface: &SurfaceMesh, topology: &Topology, a: u32, b: u32) -> Option<usize> {
    for &f in topology.vertex_faces(a as usize) {
        let t = surface.triangles[f as usize];
        for k in 0..3 {
            let (x, y) = (t[k], t[(k + 1) % 3]);
            if (x == a && y == b) || (x == b && y == a) {
                return topology.face_edge(f as usize, k);
            }
        }
    }
    None
}

/// Turn around `v` from face `from` to face `to`, always leaving a face across its side
/// from `v` to the next corner, and push the edges crossed.
fn turn_around(
    surface: &SurfaceMesh,
    topology: &Topology,
    v: u32,
    from: usize,
    to: usize,
    crossed: &mut Vec<usize>,
) {
    let valence = topology.vertex_faces(v as usize).len();
    let mut f = from;
    for _ in 0..=valence {
        if f == to {
            return;
        }
        let t = surface.triangles[f];
        let Some(k) = t.iter().position(|&u| u == v) else {
            return;
        };
        let Some(e) = topology.face_edge(f, k) else {
            return;
        };
        crossed.push(e);
        let faces = topology.edge_faces(e);
        if faces.len() != 2 {
            return;
        }
        f = if faces[0] as usize == f {
            faces[1]
        } else {
            faces[0]
        } as usize;
    }
}
