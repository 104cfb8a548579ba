//! Sharp features: boundary vertices snapped onto the domain's corners and creases.
//!
//! Stuffing puts every boundary vertex on the boundary, but only where a lattice edge
//! crosses it, so a sharp corner or crease of the domain is cut off by a chamfer about a
//! cell wide. On a small polyhedral part (a tetrahedron a few cells across) that loses a
//! fifth of its volume. This step moves, for every corner the domain names
//! ([`SharpFeatures`]), the nearest boundary vertex within two edge lengths onto it,
//! and then every boundary vertex within an edge length of a crease onto the crease
//! (measured in: a 4-cell tetrahedron then keeps its volume exactly where it lost a
//! fifth), each move only when all
//! tets around the vertex keep a dihedral angle of at least [`MIN_ANGLE_DEG`] (or their
//! old smallest one, if lower). Moved vertices are reported so the quality step leaves
//! them where they are (Isosurface stuffing improved, Doran 2013, matches features the
//! same way).
//!
//! Entry point: [`snap`]; lengths in the domain's units.

use crate::distance::SurfaceDistance;
use crate::geom::{norm, sub};
use crate::mesh::Csr;
use crate::mesh::SurfaceMesh;

/// Corners and creases of a domain's boundary that the mesh should reproduce.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SharpFeatures {
    /// Points where creases meet (or end).
    pub corners: Vec<[f64; 3]>,
    /// Crease segments.
    pub edges: Vec<[[f64; 3]; 2]>,
}

/// A snap may not make any tet around the vertex flatter than this (or than the
/// flattest one was before, when that is lower).
pub(crate) const MIN_ANGLE_DEG: f64 = 12.0;

/// Boundary vertices closer to a crease than their mean edge length are moved onto it.
const CREASE_CAPTURE: f64 = 1.0;
/// A corner takes the nearest boundary vertex within twice its mean edge length.
const CORNER_CAPTURE: f64 = 2.0;

/// Move boundary vertices (`boundary[v]`) onto the corners and creases of `features`;
/// returns which vertices moved.
pub(crate) fn snap(
    positions: &mut [[f64; 3]],
    tets: &[[u32; 4]],
    boundary: &[bool],
    features: &SharpFeatures,
) -> Vec<bool> {
    let mut snapped = vec![false; positions.len()];
    if features.corners.is_empty() && features.edges.is_empty() {
        return snapped;
    }
    let stars = Csr::new(
        positions.len(),
        tets.iter()
            .enumerate()
            .flat_map(|(t, tet)| tet.map(|v| (v, t as u32))),
    );
    let mean_edge: Vec<f64> = (0..positions.len())
        .map(|v| {
            let (mut sum, mut n) = (0.0, 0.0);
            for &t in stars.get(v) {
                for &u in &tets[t as usize] {
                    if u as usize != v {
                        sum += norm(sub(positions[u as usize], positions[v]));
                        n += 1.0;
                    }
                }
            }
            if n > 0.0 {
                sum / n
            } else {
                0.0
            }
        })
        .collect();
    let candidates: Vec<u32> = (0..positions.len() as u32)
        .filter(|&v| boundary[v as usize] && mean_edge[v as usize] > 0.0)
        .collect();

    // Corners: each takes the nearest boundary vertex within reach.
    let corner_set = point_set(&features.corners);
    let mut claims: Vec<(usize, f64, u32)> = Vec::new();
    for &v in &candidates {
        let p = positions[v as usize];
        let reach = CORNER_CAPTURE * mean_edge[v as usize];
        let c = corner_set.closest_point(p);
        if c.distance < reach {
            claims.push((c.face as usize, c.distance, v));
        }
    }
    claims.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut corner_taken = vec![false; features.corners.len()];
    for (corner, _, v) in claims {
        if corner_taken[corner] || snapped[v as usize] {
            continue;
        }
        let target = features.corners[corner];
        if try_move(positions, tets, stars.get(v as usize), v, target) {
            corner_taken[corner] = true;
            snapped[v as usize] = true;
        }
    }

    // Creases: the vertices close to one, onto their closest point on it.
    let edge_set = segment_set(&features.edges);
    for &v in &candidates {
        if snapped[v as usize] {
            continue;
        }
        let p = positions[v as usize];
        let c = edge_set.closest_point(p);
        if c.distance > 0.0 && c.distance < CREASE_CAPTURE * mean_edge[v as usize] {
            let target = c.point;
            if try_move(positions, tets, stars.get(v as usize), v, target) {
                snapped[v as usize] = true;
            }
        }
    }
    snapped
}

/// Move `v` to `target` if every tet of its star stays positive with its smallest
/// dihedral angle at least [`MIN_ANGLE_DEG`] (or the star's old smallest angle).
fn try_move(
    positions: &mut [[f64; 3]],
    tets: &[[u32; 4]],
    star: &[u32],
    v: u32,
    target: [f64; 3],
) -> bool {
    let smallest = |positions: &[[f64; 3]], at: [f64; 3]| {
        star.iter()
            .map(|&t| {
                let p = tets[t as usize].map(|u| if u == v { at } else { positions[u as usize] });
                super::quality::score(p)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let before = smallest(positions, positions[v as usize]);
    let after = smallest(positions, target);
    let floor = MIN_ANGLE_DEG.to_radians().sin().min(before);
    if after > 0.0 && after >= floor {
        positions[v as usize] = target;
        true
    } else {
        false
    }
}

/// Points as a searchable set (each a degenerate triangle; `face` is the point's index).
fn point_set(points: &[[f64; 3]]) -> SurfaceDistance {
    let mesh = SurfaceMesh {
        positions: points.to_vec(),
        triangles: (0..points.len() as u32).map(|i| [i, i, i]).collect(),
    };
    SurfaceDistance::new(&mesh)
}

/// Segments as a searchable set (each a degenerate triangle).
fn segment_set(segments: &[[[f64; 3]; 2]]) -> SurfaceDistance {
    let mesh = SurfaceMesh {
        positions: segments.iter().flatten().copied().collect(),
        triangles: (0..segments.len() as u32)
            .map(|i| [2 * i, 2 * i + 1, 2 * i + 1])
            .collect(),
    };
    SurfaceDistance::new(&mesh)
}
