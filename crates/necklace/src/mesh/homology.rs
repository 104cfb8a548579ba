//! A Z2 homology basis of a closed surface by tree–cotree (Eppstein 2003), to name the
//! class of a closed curve on it.
//!
//! A spanning forest `T` of the vertices (breadth first from each component's lowest
//! vertex, through edges in index order), then a spanning forest `C` of the faces
//! through the edges not in `T`. Each edge in neither is a *generator*: with its two
//! tree paths it closes a cycle `z_i` of edges, and the `2g` cycles of a genus-`g`
//! component form a basis of its first homology over Z2. A closed curve on the surface
//! that crosses edges transversally has the class whose bit `i` is the parity of its
//! crossings with `z_i` (the intersection form is non-degenerate, so the bits determine
//! the class); a simple closed curve separates the surface if and only if all its bits
//! are 0. Entry points: [`HomologyBasis::new`], then
//! [`HomologyBasis::generators_through`] per crossed edge.

use std::collections::VecDeque;

use super::{SurfaceMesh, Topology};

/// The basis cycles `z_i`, stored per edge: which of them pass through it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HomologyBasis {
    generators: usize,
    edge_start: Vec<u32>,
    edge_generators: Vec<u32>,
}

impl HomologyBasis {
    /// Build the basis of a surface (every component; boundary edges and non-manifold
    /// edges never become generators).
    pub fn new(mesh: &SurfaceMesh, topology: &Topology) -> HomologyBasis {
        let edges = topology.edges();
        let nv = mesh.num_vertices();

        // Primal spanning forest: parent edge and depth per vertex.
        let mut in_tree = vec![false; edges.len()];
        let mut parent_edge = vec![u32::MAX; nv];
        let mut depth = vec![u32::MAX; nv];
        let mut queue = VecDeque::new();
        for root in 0..nv {
            if depth[root] != u32::MAX || topology.vertex_edges(root).is_empty() {
                continue;
            }
            depth[root] = 0;
            queue.push_back(root);
            while let Some(v) = queue.pop_front() {
                for &e in topology.vertex_edges(v) {
                    let [a, b] = edges[e as usize];
                    let u = if a as usize == v { b } else { a } as usize;
                    if depth[u] == u32::MAX {
                        depth[u] = depth[v] + 1;
                        parent_edge[u] = e;
                        in_tree[e as usize] = true;
                        queue.push_back(u);
                    }
                }
            }
        }

        // Dual spanning forest through the edges not in the primal one.
        let nf = mesh.num_triangles();
        let mut in_cotree = vec![false; edges.len()];
        let mut seen = vec![false; nf];
        for root in 0..nf {
            if seen[root] {
                continue;
            }
            seen[root] = true;
            queue.push_back(root);
            while let Some(f) = queue.pop_front() {
                for side in 0..3 {
                    let Some((g, e)) = topology.across(f, side) else {
                        continue;
                    };
                    if in_tree[e] {
                        continue;
                    }
                    if !seen[g] {
                        seen[g] = true;
                        in_cotree[e] = true;
                        queue.push_back(g);
                    }
                }
            }
        }

        // Generators and their cycles.
        let mut cycles: Vec<(u32, u32)> = Vec::new(); // (edge, generator)
        let mut generators = 0u32;
        for (e, &[a, b]) in edges.iter().enumerate() {
            if in_tree[e] || in_cotree[e] || topology.edge_faces(e).len() != 2 {
                continue;
            }
            cycles.push((e as u32, generators));
            let (mut x, mut y) = (a as usize, b as usize);
            while x != y {
                if depth[x] >= depth[y] {
                    let pe = parent_edge[x];
                    cycles.push((pe, generators));
                    let [p, q] = edges[pe as usize];
                    x = if p as usize == x { q } else { p } as usize;
                } else {
                    let pe = parent_edge[y];
                    cycles.push((pe, generators));
                    let [p, q] = edges[pe as usize];
                    y = if p as usize == y { q } else { p } as usize;
                }
            }
            generators += 1;
        }
        cycles.sort_unstable();
        let mut edge_start = vec![0u32; edges.len() + 1];
        for &(e, _) in &cycles {
            edge_start[e as usize + 1] += 1;
        }
        for e in 0..edges.len() {
            edge_start[e + 1] += edge_start[e];
        }
        HomologyBasis {
            generators: generators as usize,
            edge_start,
            edge_generators: cycles.into_iter().map(|(_, g)| g).collect(),
        }
    }

    /// Number of basis cycles (`2g` summed over the components).
    pub fn len(&self) -> usize {
        self.generators
    }

    /// Whether the surface has no handle at all.
    pub fn is_empty(&self) -> bool {
        self.generators == 0
    }

    /// The basis cycles through edge `e` (indices into the basis).
    pub fn generators_through(&self, e: usize) -> &[u32] {
        &self.edge_generators[self.edge_start[e] as usize..self.edge_start[e + 1] as usize]
    }

    /// The class of a curve given by the edges it crosses (with repeats): one bit per
    /// basis cycle, packed in `u64` words.
    pub fn class_of_crossings(&self, crossed: impl IntoIterator<Item = usize>) -> Vec<u64> {
        let mut bits = vec![0u64; self.generators.div_ceil(64)];
        for e in crossed {
            for &g in self.generators_through(e) {
                bits[g as usize / 64] ^= 1 << (g % 64);
            }
        }
        bits
    }
}

/// The rank over Z2 of a set of classes (as from
/// [`HomologyBasis::class_of_crossings`]).
pub fn z2_rank(classes: &[Vec<u64>]) -> usize {
    let mut basis = Z2Basis::default();
    classes.iter().filter(|c| basis.insert(c)).count()
}

/// An echelon basis over Z2, built one vector at a time.
#[derive(Debug, Clone, Default)]
pub struct Z2Basis {
    /// Reduced vectors with their leading bit.
    rows: Vec<(usize, Vec<u64>)>,
}

impl Z2Basis {
    /// Add `v` if it is independent of the vectors so far; whether it was.
    pub fn insert(&mut self, v: &[u64]) -> bool {
        let mut v = v.to_vec();
        self.reduce(&mut v);
        match leading_bit(&v) {
            Some(lead) => {
                self.rows.push((lead, v));
                true
            }
            None => false,
        }
    }

    /// Vectors inserted so far (the rank).
    pub fn rank(&self) -> usize {
        self.rows.len()
    }

    /// Reduce `v` modulo the span: afterwards no leading bit of the basis is set in it,
    /// and two vectors are equal modulo the span exactly when their reductions are.
    pub fn reduce(&self, v: &mut [u64]) {
        for (lead, row) in &self.rows {
            if v[lead / 64] >> (lead % 64) & 1 == 1 {
                for (x, r) in v.iter_mut().zip(row) {
                    *x ^= r;
                }
            }
        }
    }

    /// The leading bits of the basis vectors, in insertion order.
    pub fn leads(&self) -> impl Iterator<Item = usize> + '_ {
        self.rows.iter().map(|(lead, _)| *lead)
    }
}

fn leading_bit(v: &[u64]) -> Option<usize> {
    v.iter()
        .enumerate()
        .find(|(_, w)| **w != 0)
        .map(|(i, w)| 64 * i + w.trailing_zeros() as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A torus as a 4 × 4 grid with wrap-around.
    fn grid_torus(n: usize) -> SurfaceMesh {
        let idx = |i: usize, j: usize| ((i % n) * n + (j % n)) as u32;
        let mut positions = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (u, v) = (
                    i as f64 / n as f64 * std::f64::consts::TAU,
                    j as f64 / n as f64 * std::f64::consts::TAU,
                );
                positions.push([
                    (2.0 + v.cos()) * u.cos(),
                    (2.0 + v.cos()) * u.sin(),
                    v.sin(),
                ]);
            }
        }
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..n {
                triangles.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                triangles.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
            }
        }
        SurfaceMesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn a_torus_has_two_generators_and_a_tetrahedron_none() {
        let torus = grid_torus(5);
        let basis = HomologyBasis::new(&torus, &Topology::new(&torus));
        assert_eq!(basis.len(), 2);
        let tet = SurfaceMesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap();
        assert!(HomologyBasis::new(&tet, &Topology::new(&tet)).is_empty());
    }

    #[test]
    fn meridian_and_longitude_of_a_torus_are_independent_and_a_vertex_ring_is_zero() {
        let n = 5;
        let torus = grid_torus(n);
        let topology = Topology::new(&torus);
        let basis = HomologyBasis::new(&torus, &topology);
        let edge = |a: u32, b: u32| {
            topology
                .edges()
                .iter()
                .position(|e| *e == [a.min(b), a.max(b)])
                .unwrap()
        };
        let idx = |i: usize, j: usize| ((i % n) * n + (j % n)) as u32;
        // A dual curve around the tube at fixed i + 1/2 crosses the edges (i, j)–(i+1, j)
        // and the diagonals (i, j)–(i+1, j+1): a meridian.
        let meridian: Vec<usize> = (0..n)
            .flat_map(|j| [edge(idx(0, j), idx(1, j)), edge(idx(0, j), idx(1, j + 1))])
            .collect();
        // Around the ring at fixed j + 1/2: a longitude.
        let longitude: Vec<usize> = (0..n)
            .flat_map(|i| [edge(idx(i, 0), idx(i, 1)), edge(idx(i, 0), idx(i + 1, 1))])
            .collect();
        // Around one vertex: every edge at it once.
        let ring: Vec<usize> = (0..topology.num_edges())
            .filter(|&e| topology.edges()[e].contains(&idx(2, 2)))
            .collect();
        let m = basis.class_of_crossings(meridian);
        let l = basis.class_of_crossings(longitude);
        let r = basis.class_of_crossings(ring);
        assert!(m.iter().any(|w| *w != 0));
        assert!(l.iter().any(|w| *w != 0));
        assert!(r.iter().all(|w| *w == 0));
        assert_eq!(z2_rank(&[m.clone(), l.clone()]), 2);
        assert_eq!(z2_rank(&[m.clone(), m]), 1);
    }
}
