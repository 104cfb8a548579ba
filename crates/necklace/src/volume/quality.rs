//! Quality: raise the small dihedral angles that graded transitions leave.
//!
//! Stuffing proves its angle bounds on the uniform BCC lattice. Where the lattice
//! changes size (around thin parts) the background tets are cones of other shapes, and
//! a warp there may be refused to keep them from flattening; a few output tets then get
//! dihedral angles of a few degrees. This step moves the vertices of every tet whose
//! smallest dihedral angle is below the target: interior vertices anywhere, boundary
//! vertices along the boundary (each trial point projected back onto it), vertices a
//! pinch repair exposed not at all. A move is taken only when it raises the smallest
//! angle over the vertex's whole star, so no tet gets worse than the worst tet it
//! started from and none inverts (a compass search: 26 directions, or 8 along the
//! boundary, at three step lengths). Vertices are visited one at a time in index order,
//! so the result does not depend on the thread count.
//!
//! Entry point: [`improve`]. Angles in degrees.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::geom::{add, cross, dot, norm, plane_basis, scale, sub};
use crate::mesh::Csr;
use crate::tet::boundary_faces_of;

/// How a vertex may move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mobility {
    /// Strictly inside: anywhere its star stays valid.
    Free,
    /// On the boundary: along it (trial points are projected onto it).
    OnBoundary,
    /// Not at all (a vertex left on the boundary by pinch repair, off the true surface).
    Fixed,
}

/// What the quality step did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct QualityStats {
    /// The target smallest dihedral angle, degrees (0: the step was off).
    pub target_deg: f64,
    /// Tets below the target before the step.
    pub below_target_before: usize,
    /// Tets below the target after it.
    pub below_target_after: usize,
    /// Smallest dihedral angle before the step, degrees.
    pub min_dihedral_before_deg: f64,
    /// Smallest dihedral angle after it, degrees.
    pub min_dihedral_after_deg: f64,
    /// Vertex moves made.
    pub moves: usize,
    /// Rounds over the bad tets.
    pub rounds: usize,
}

/// Most rounds over the tets below the target.
const MAX_ROUNDS: usize = 12;
/// Most accepted moves of one vertex per visit.
const MAX_MOVES_PER_VISIT: usize = 12;
/// Trial step lengths, as fractions of the mean edge length at the vertex.
const STEPS: [f64; 3] = [0.25, 0.08, 0.025];

/// Move vertices until every tet's smallest dihedral angle reaches `target_deg` or no
/// move helps any more; `project` maps a point onto the boundary.
pub(crate) fn improve(
    positions: &mut [[f64; 3]],
    tets: &[[u32; 4]],
    mobility: &[Mobility],
    project: &(dyn Fn([f64; 3]) -> [f64; 3] + Sync),
    target_deg: f64,
) -> QualityStats {
    let target = target_deg.to_radians().sin();
    let tet_score =
        |positions: &[[f64; 3]], t: usize| score(tets[t].map(|v| positions[v as usize]));
    let mut scores: Vec<f64> = {
        let positions = &*positions;
        (0..tets.len())
            .into_par_iter()
            .map(|t| tet_score(positions, t))
            .collect()
    };
    let below = |scores: &[f64]| scores.iter().filter(|&&s| s < target).count();
    let mut stats = QualityStats {
        target_deg,
        below_target_before: below(&scores),
        min_dihedral_before_deg: smallest_angle_deg(&scores),
        ..QualityStats::default()
    };
    let mut bad: Vec<usize> = (0..tets.len()).filter(|&t| scores[t] < target).collect();
    if target_deg > 0.0 && !bad.is_empty() {
        let stars = Csr::new(
            positions.len(),
            tets.iter()
                .enumerate()
                .flat_map(|(t, tet)| tet.map(|v| (v, t as u32))),
        );
        while !bad.is_empty() && stats.rounds < MAX_ROUNDS {
            stats.rounds += 1;
            let mut vertices: Vec<u32> = bad.iter().flat_map(|&t| tets[t]).collect();
            vertices.sort_unstable();
            vertices.dedup();
            let mut moved = 0;
            let mut touched: Vec<usize> = Vec::new();
            for v in vertices {
                let star = stars.get(v as usize);
                let n = improve_vertex(positions, tets, star, v, mobility[v as usize], project);
                if n > 0 {
                    moved += n;
                    touched.extend(star.iter().map(|&t| t as usize));
                }
            }
            stats.moves += moved;
            if moved == 0 {
                break;
            }
            for t in touched {
                scores[t] = tet_score(positions, t);
            }
            // A move never lowers its star's worst tet, but may take another tet of the
            // star below the target (never below the star's old worst).
            bad = (0..tets.len()).filter(|&t| scores[t] < target).collect();
        }
    }
    stats.below_target_after = below(&scores);
    stats.min_dihedral_after_deg = smallest_angle_deg(&scores);
    stats
}

/// The smallest dihedral angle over tets with these scores (a tet's smallest dihedral
/// angle is at most 70.5°, so it is the arcsine of its score), degrees; 0 when a tet is
/// flat or inverted, 180 for no tets.
fn smallest_angle_deg(scores: &[f64]) -> f64 {
    match scores.iter().copied().reduce(f64::min) {
        None => 180.0,
        Some(s) if s <= 0.0 => 0.0,
        Some(s) => s.min(1.0).asin().to_degrees(),
    }
}

/// Compass search for vertex `v`: returns the number of moves made.
fn improve_vertex(
    positions: &mut [[f64; 3]],
    tets: &[[u32; 4]],
    star: &[u32],
    v: u32,
    mobility: Mobility,
    project: &(dyn Fn([f64; 3]) -> [f64; 3] + Sync),
) -> usize {
    if mobility == Mobility::Fixed || star.is_empty() {
        return 0;
    }
    let star_score = |positions: &[[f64; 3]], at: [f64; 3]| {
        star.iter()
            .map(|&t| {
                score(tets[t as usize].map(|u| if u == v { at } else { positions[u as usize] }))
            })
            .fold(f64::INFINITY, f64::min)
    };
    let p0 = positions[v as usize];
    let mut edge_sum = 0.0;
    let mut edge_count = 0.0;
    for &t in star {
        for &u in &tets[t as usize] {
            if u != v {
                edge_sum += norm(sub(positions[u as usize], p0));
                edge_count += 1.0;
            }
        }
    }
    let mean_edge = edge_sum / edge_count;
    let directions = match mobility {
        Mobility::Free => free_directions(),
        _ => tangent_directions(boundary_normal(positions, tets, star, v)),
    };
    let mut best = star_score(positions, p0);
    let mut moves = 0;
    for step in STEPS {
        let length = step * mean_edge;
        while moves < MAX_MOVES_PER_VISIT {
            let here = positions[v as usize];
            let mut choice: Option<([f64; 3], f64)> = None;
            for &d in &directions {
                let mut q = add(here, scale(d, length));
                if mobility == Mobility::OnBoundary {
                    q = project(q);
                }
                if !q.iter().all(|c| c.is_finite()) {
                    continue;
                }
                let s = star_score(positions, q);
                // (Relative to the magnitude: an inverted star, at −1, must not
                // accept a move that leaves it inverted.)
                let base = choice.map_or(best, |c| c.1);
                if s > base + 1e-9 * base.abs() + 1e-12 {
                    choice = Some((q, s));
                }
            }
            match choice {
                Some((q, s)) => {
                    positions[v as usize] = q;
                    best = s;
                    moves += 1;
                }
                None => break,
            }
        }
    }
    moves
}

/// The 26 unit directions to the neighbours of a cube's centre.
fn free_directions() -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(26);
    for i in 0..27 {
        let d = [
            (i % 3) as f64 - 1.0,
            ((i / 3) % 3) as f64 - 1.0,
            (i / 9) as f64 - 1.0,
        ];
        let n = norm(d);
        if n > 0.0 {
            out.push(scale(d, 1.0 / n));
        }
    }
    out
}

/// Eight unit directions in the plane normal to `n` (all 26 when `n` is zero).
fn tangent_directions(n: [f64; 3]) -> Vec<[f64; 3]> {
    let len = norm(n);
    if !(len > 0.0 && len.is_finite()) {
        return free_directions();
    }
    let (u, w) = plane_basis(scale(n, 1.0 / len));
    (0..8)
        .map(|k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            add(scale(u, a.cos()), scale(w, a.sin()))
        })
        .collect()
}

/// The area-weighted normal of the boundary faces at `v` (faces of its star used by
/// one tet of the star).
fn boundary_normal(positions: &[[f64; 3]], tets: &[[u32; 4]], star: &[u32], v: u32) -> [f64; 3] {
    boundary_faces_of(star.iter().map(|&t| tets[t as usize]))
        .into_iter()
        .filter(|f| f.contains(&v))
        .fold([0.0; 3], |n, f| {
            let [a, b, c] = f.map(|u| positions[u as usize]);
            add(n, cross(sub(b, a), sub(c, a)))
        })
}

/// The quality of a tet: the sine of its smallest acute dihedral angle (an obtuse angle
/// counts as 1: a tet with an angle near 180° has another near 0), and −1 for a tet
/// that is flat or inverted. Monotone in the smallest dihedral angle below 90°.
pub(crate) fn score(p: [[f64; 3]; 4]) -> f64 {
    let [a, b, c, d] = p;
    if dot(sub(b, a), cross(sub(c, a), sub(d, a))) <= 0.0 {
        return -1.0;
    }
    // Outward (unnormalised) normals of the faces opposite each vertex.
    let normals = [
        cross(sub(c, b), sub(d, b)),
        cross(sub(d, a), sub(c, a)),
        cross(sub(b, a), sub(d, a)),
        cross(sub(c, a), sub(b, a)),
    ];
    let mut worst = 1.0f64;
    for (k, l) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
        let (nk, nl) = (normals[k], normals[l]);
        // The dihedral angle θ at the edge shared by faces k and l: cos θ = −n̂k·n̂l.
        let cos = -dot(nk, nl);
        if cos > 0.0 {
            let sin = norm(cross(nk, nl));
            let scale = norm(nk) * norm(nl);
            worst = worst.min(sin / scale);
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_score_is_the_sine_of_the_smallest_angle() {
        // The corner tet of a cube: three right angles at the origin, three of 54.7°
        // along the slanted face.
        let corner = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let smallest = crate::tet::dihedral_angles_deg(corner)
            .into_iter()
            .fold(180.0, f64::min);
        assert!((score(corner) - smallest.to_radians().sin()).abs() < 1e-12);
        let mut flipped = corner;
        flipped.swap(2, 3);
        assert_eq!(score(flipped), -1.0);
    }

    #[test]
    fn a_sliver_is_lifted_by_moving_its_free_vertex() {
        // A unit square split into two tets by an apex barely above its centre: fixed
        // corners, a free apex that can rise.
        let mut positions = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, 0.02],
        ];
        let tets = vec![[0, 1, 2, 4], [0, 2, 3, 4]];
        let mobility = vec![
            Mobility::Fixed,
            Mobility::Fixed,
            Mobility::Fixed,
            Mobility::Fixed,
            Mobility::Free,
        ];
        let stats = improve(&mut positions, &tets, &mobility, &|p| p, 20.0);
        assert!(stats.min_dihedral_before_deg < 5.0, "{stats:?}");
        assert!(stats.min_dihedral_after_deg >= 20.0, "{stats:?}");
        assert_eq!(stats.below_target_after, 0);
    }

    #[test]
    fn a_vertex_whose_star_stays_inverted_wherever_it_goes_is_not_moved() {
        // Two tets on one triangle with the apex on both: above the plane one is
        // inverted, below it the other, so no move can help. A move must not be taken
        // for the star's score of −1 staying −1 (the vertex walked off along a
        // direction of the compass, step after step).
        let apex = [0.2, 0.3, 1.0];
        let mut positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], apex];
        let tets = vec![[0, 1, 2, 3], [1, 0, 2, 3]];
        let mobility = vec![
            Mobility::Fixed,
            Mobility::Fixed,
            Mobility::Fixed,
            Mobility::Free,
        ];
        let stats = improve(&mut positions, &tets, &mobility, &|p| p, 10.0);
        assert_eq!(stats.moves, 0, "{stats:?}");
        assert_eq!(positions[3], apex);
    }
}
