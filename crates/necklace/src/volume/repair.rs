//! Pinch repair: make the boundary of a stuffed tet mesh a 2-manifold.
//!
//! Stuffing decides from the signs at lattice vertices alone. Where the surface has a
//! feature below the lattice spacing (a sharp reflex crease, a slit), the inside can
//! touch itself along an edge or at a vertex whose neighbourhood is partly outside:
//! several fans of tets around one edge, or several groups of tets around one vertex
//! connected only through it, or a tunnel of the outside pinched to a single vertex.
//! Each edge or vertex pinch keeps its group of largest volume and drops the other
//! tets; a pinched tunnel loses the star of its vertex (the tunnel opens). Rounds repeat
//! until no pinch is left (a few at most). Interior vertices
//! that a dropped tet leaves on the boundary become boundary vertices; both counts are
//! reported.

use rayon::prelude::*;

use crate::geom::{cross, dot, sub};
use crate::mesh::Csr;

/// What the repair changed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Repair {
    /// Tets dropped.
    pub removed_tets: usize,
    /// Interior vertices left on the boundary.
    pub exposed: Vec<u32>,
    /// The pinched vertices of the first round (where the features below the
    /// resolution are), in index order.
    pub sites: Vec<u32>,
    /// Vertices on the boundary (not interior) that no boundary face touches: their
    /// star closed round them, so a gap or part below the resolution was swallowed
    /// there. In index order.
    pub buried: Vec<u32>,
}

const MAX_ROUNDS: usize = 20;

/// Remove tets until no edge or vertex of the boundary is pinched; `interior[v]` says
/// which vertices were strictly inside before.
///
/// Every check is local to a vertex star (all tets with a face at `v` contain `v`), so
/// after the first round only the vertices of dropped tets are looked at again.
pub(crate) fn repair_pinches(
    positions: &[[f64; 3]],
    tets: &mut Vec<[u32; 4]>,
    interior: &[bool],
) -> Repair {
    let n = positions.len();
    let stars = Csr::new(
        n,
        tets.iter()
            .enumerate()
            .flat_map(|(t, tet)| tet.map(|v| (v, t as u32))),
    );
    let mut alive = vec![true; tets.len()];
    // Before any drop, the boundary vertices are exactly the used non-interior ones
    // (an interior vertex has its whole star).
    let mut candidates: Vec<u32> = (0..n as u32)
        .filter(|&v| !interior[v as usize] && !stars.get(v as usize).is_empty())
        .collect();
    let mut touched: Vec<u32> = Vec::new();

    let mut repair = Repair::default();
    for _ in 0..MAX_ROUNDS {
        // Vertices are checked independently (in parallel); the sorted union of what
        // they drop does not depend on the thread count.
        let per_vertex: Vec<(u32, Option<Vec<u32>>)> = candidates
            .par_iter()
            .map_init(Scratch::default, |scratch, &v| {
                let star: Vec<u32> = stars
                    .get(v as usize)
                    .iter()
                    .copied()
                    .filter(|&t| alive[t as usize])
                    .collect();
                (v, scratch.pinch_at(positions, tets, &star, v))
            })
            .collect();
        if repair.removed_tets == 0 {
            for (v, d) in &per_vertex {
                match d {
                    None if !stars.get(*v as usize).is_empty() => repair.buried.push(*v),
                    Some(d) if !d.is_empty() => repair.sites.push(*v),
                    _ => {}
                }
            }
        }
        let mut drop: Vec<u32> = per_vertex
            .into_iter()
            .flat_map(|(_, d)| d.unwrap_or_default())
            .collect();
        drop.sort_unstable();
        drop.dedup();
        if drop.is_empty() {
            break;
        }
        repair.removed_tets += drop.len();
        candidates.clear();
        for &t in &drop {
            alive[t as usize] = false;
            candidates.extend(tets[t as usize]);
        }
        candidates.sort_unstable();
        candidates.dedup();
        touched.extend_from_slice(&candidates);
    }
    // Interior vertices next to a dropped tet that now have a boundary face.
    touched.sort_unstable();
    touched.dedup();
    for v in touched.into_iter().filter(|&v| interior[v as usize]) {
        let mut faces: Vec<[u32; 3]> = stars
            .get(v as usize)
            .iter()
            .filter(|&&t| alive[t as usize])
            .flat_map(|&t| faces_of(&tets[t as usize]))
            .filter(|f| f.contains(&v))
            .collect();
        faces.sort_unstable();
        let mut on_boundary = false;
        runs(&faces, |_, count| on_boundary |= count == 1);
        if on_boundary {
            repair.exposed.push(v);
        }
    }
    if repair.removed_tets > 0 {
        let mut i = 0;
        tets.retain(|_| {
            i += 1;
            alive[i - 1]
        });
    }
    repair
}

fn volume(positions: &[[f64; 3]], t: &[u32; 4]) -> f64 {
    let [a, b, c, d] = t.map(|v| positions[v as usize]);
    dot(sub(b, a), cross(sub(c, a), sub(d, a))) / 6.0
}

/// Sorted runs of equal items: calls `f(item, count)` once per distinct item.
pub(super) fn runs<T: PartialEq + Copy>(sorted: &[T], mut f: impl FnMut(T, usize)) {
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i + 1;
        while j < sorted.len() && sorted[j] == sorted[i] {
            j += 1;
        }
        f(sorted[i], j - i);
        i = j;
    }
}

/// The four faces of a tet, each with sorted vertices.
pub(super) fn faces_of(t: &[u32; 4]) -> [[u32; 3]; 4] {
    let mut s = *t;
    s.sort_unstable();
    [
        [s[1], s[2], s[3]],
        [s[0], s[2], s[3]],
        [s[0], s[1], s[3]],
        [s[0], s[1], s[2]],
    ]
}

/// Number of fans formed by the boundary faces at `v` (faces sharing an edge at `v`).
fn fans(faces: &[[u32; 3]], v: u32) -> usize {
    let mut parent: Vec<usize> = (0..faces.len()).collect();
    let mut spokes: Vec<(u32, usize)> = Vec::with_capacity(2 * faces.len());
    for (k, f) in faces.iter().enumerate() {
        for &w in f {
            if w != v {
                spokes.push((w, k));
            }
        }
    }
    spokes.sort_unstable();
    for pair in spokes.windows(2) {
        if pair[0].0 == pair[1].0 {
            let (a, b) = (root(&mut parent, pair[0].1), root(&mut parent, pair[1].1));
            parent[a.max(b)] = a.min(b);
        }
    }
    (0..faces.len())
        .filter(|&k| root(&mut parent, k) == k)
        .count()
}

fn root(p: &mut [usize], mut x: usize) -> usize {
    while p[x] != x {
        p[x] = p[p[x]];
        x = p[x];
    }
    x
}

/// Reusable buffers for grouping the tets of a star.
#[derive(Default)]
struct Scratch {
    parent: Vec<usize>,
    faces: Vec<([u32; 3], usize)>,
}

impl Scratch {
    /// The tets to drop at vertex `v` with (alive) star `star`: minority fans of each
    /// pinched edge at `v` (more than two boundary faces), minority groups of the star,
    /// or the whole star when its boundary faces form several fans. `None` when no
    /// boundary face touches `v`.
    fn pinch_at(
        &mut self,
        positions: &[[f64; 3]],
        tets: &[[u32; 4]],
        star: &[u32],
        v: u32,
    ) -> Option<Vec<u32>> {
        // Boundary faces at v: faces through v used by one tet of the star.
        let mut faces: Vec<[u32; 3]> = star
            .iter()
            .flat_map(|&t| faces_of(&tets[t as usize]))
            .filter(|f| f.contains(&v))
            .collect();
        faces.sort_unstable();
        let mut boundary = Vec::new();
        runs(&faces, |f, count| {
            if count == 1 {
                boundary.push(f);
            }
        });
        if boundary.is_empty() {
            return None;
        }
        let mut out = Vec::new();
        // Edges at v with more than two boundary faces.
        let mut others: Vec<u32> = boundary
            .iter()
            .flat_map(|f| f.iter().copied().filter(move |&w| w != v))
            .collect();
        others.sort_unstable();
        let mut pinched = Vec::new();
        runs(&others, |w, count| {
            if count > 2 {
                pinched.push(w);
            }
        });
        for w in pinched {
            let edge_star: Vec<u32> = star
                .iter()
                .copied()
                .filter(|&t| tets[t as usize].contains(&w))
                .collect();
            for g in self.minority_groups(positions, tets, &edge_star, &[v, w]) {
                out.extend(g);
            }
        }
        let groups = self.minority_groups(positions, tets, star, &[v]);
        if !groups.is_empty() {
            for g in groups {
                out.extend(g);
            }
        } else if fans(&boundary, v) > 1 {
            out.extend_from_slice(star);
        }
        Some(out)
    }

    /// The groups of `star` (connected through faces that contain all of `through`)
    /// other than the one of largest volume; empty when the star is one group.
    fn minority_groups(
        &mut self,
        positions: &[[f64; 3]],
        tets: &[[u32; 4]],
        star: &[u32],
        through: &[u32],
    ) -> Vec<Vec<u32>> {
        self.parent.clear();
        self.parent.extend(0..star.len());
        self.faces.clear();
        for (i, &t) in star.iter().enumerate() {
            for f in faces_of(&tets[t as usize]) {
                if through.iter().all(|v| f.contains(v)) {
                    self.faces.push((f, i));
                }
            }
        }
        self.faces.sort_unstable();
        for k in 1..self.faces.len() {
            if self.faces[k].0 == self.faces[k - 1].0 {
                let (a, b) = (
                    root(&mut self.parent, self.faces[k].1),
                    root(&mut self.parent, self.faces[k - 1].1),
                );
                self.parent[a.max(b)] = a.min(b);
            }
        }
        let roots: Vec<usize> = (0..star.len()).map(|i| root(&mut self.parent, i)).collect();
        let mut distinct = roots.clone();
        distinct.sort_unstable();
        distinct.dedup();
        if distinct.len() < 2 {
            return Vec::new();
        }
        let mut groups: Vec<Vec<u32>> = vec![Vec::new(); distinct.len()];
        let mut volumes = vec![0.0; distinct.len()];
        for (i, &r) in roots.iter().enumerate() {
            let g = distinct.binary_search(&r).unwrap_or(0);
            groups[g].push(star[i]);
            volumes[g] += volume(positions, &tets[star[i] as usize]);
        }
        let best = (0..groups.len())
            .max_by(|&i, &j| volumes[i].total_cmp(&volumes[j]).then(j.cmp(&i)))
            .unwrap_or(0);
        groups.swap_remove(best);
        groups
    }
}
