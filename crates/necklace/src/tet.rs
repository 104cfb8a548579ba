//! Tetrahedral meshes: the plain data the volume stages pass along.
//!
//! A [`TetMesh`] holds vertex positions, tetrahedra (four `u32` vertex indices each,
//! positively oriented: `(b − a) · ((c − a) × (d − a)) > 0`), and per vertex its
//! [`VertexKind`]: interior, on the input surface, or on the outer bounding sphere (the
//! outer boundary of an exterior shell). The vertex-to-tet adjacency (CSR) is built by
//! [`TetMesh::new`] for the stages that walk vertex stars.
//!
//! Queries: volumes, boundary faces, Euler characteristic χ = V − E + F − T, dihedral
//! angles, components, [`TetMesh::topology`] ([`TetTopology`]: per component its χ and
//! the χ of each boundary surface), and [`TetMesh::classify_boundary`] for meshes read
//! from files, which carry no vertex kinds. [`renumber_used`] is the crate's one tet
//! compaction (the vertices the tets use, renumbered in order).

use std::collections::HashMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, ErrorKind, Result};
use crate::geom::{cross, dot, norm, sub};
use crate::mesh::{check_finite, find, union, Csr};

/// Where a vertex of a tet mesh lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VertexKind {
    /// Strictly inside the meshed region.
    Interior,
    /// On the input surface.
    Surface,
    /// On the outer boundary of an exterior shell (the bounding sphere).
    Outer,
}

/// A tetrahedral mesh with vertex kinds and vertex-to-tet adjacency.
#[derive(Debug, Clone, PartialEq)]
pub struct TetMesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Tetrahedra, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// Kind of each vertex.
    pub kinds: Vec<VertexKind>,
    vertex_tets: Csr,
}

impl TetMesh {
    /// Build a tet mesh; checks index ranges, finite coordinates and one kind per vertex,
    /// and builds the vertex-to-tet adjacency.
    pub fn new(
        positions: Vec<[f64; 3]>,
        tets: Vec<[u32; 4]>,
        kinds: Vec<VertexKind>,
    ) -> Result<TetMesh> {
        let n = positions.len();
        if kinds.len() != n {
            return Err(Error::new(
                ErrorKind::CountMismatch,
                format!("{} vertex kinds for {n} vertices", kinds.len()),
            ));
        }
        check_finite(&positions)?;
        for (t, tet) in tets.iter().enumerate() {
            if let Some(&v) = tet.iter().find(|&&v| v as usize >= n) {
                return Err(Error::new(
                    ErrorKind::IndexOutOfRange,
                    format!("tet {t} uses vertex {v}, but there are {n} vertices"),
                ));
            }
        }
        let vertex_tets = Csr::new(
            n,
            tets.iter()
                .enumerate()
                .flat_map(|(t, tet)| tet.map(|v| (v, t as u32))),
        );
        Ok(TetMesh {
            positions,
            tets,
            kinds,
            vertex_tets,
        })
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of tetrahedra.
    pub fn num_tets(&self) -> usize {
        self.tets.len()
    }

    /// The tets that use vertex `v`.
    pub fn vertex_tets(&self, v: usize) -> &[u32] {
        self.vertex_tets.get(v)
    }

    /// Number of vertices of each kind: (interior, surface, outer).
    pub fn kind_counts(&self) -> (usize, usize, usize) {
        let count = |k| self.kinds.iter().filter(|&&x| x == k).count();
        (
            count(VertexKind::Interior),
            count(VertexKind::Surface),
            count(VertexKind::Outer),
        )
    }

    /// The four corner positions of tet `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 4] {
        self.tets[t].map(|v| self.positions[v as usize])
    }

    /// Signed volume of tet `t` (positive when positively oriented).
    pub fn tet_volume(&self, t: usize) -> f64 {
        let [a, b, c, d] = self.corners(t);
        dot(sub(b, a), cross(sub(c, a), sub(d, a))) / 6.0
    }

    /// Sum of the signed tet volumes.
    pub fn volume(&self) -> f64 {
        (0..self.num_tets()).map(|t| self.tet_volume(t)).sum()
    }

    /// Faces with exactly one tet, oriented with their normal pointing out of the mesh
    /// (counter-clockwise seen from outside).
    pub fn boundary_faces(&self) -> Vec<[u32; 3]> {
        boundary_faces_of(self.tets.iter().copied())
    }

    /// Euler characteristic V − E + F − T over the vertices used by tets.
    pub fn euler_characteristic(&self) -> i64 {
        self.euler_characteristic_where(&vec![true; self.num_vertices()])
    }

    /// Euler characteristic of the full subcomplex on the vertices with `keep[v]`: the
    /// vertices, edges, faces and tets of the mesh all of whose vertices are kept
    /// (vertices counted only when a tet uses them). Each simplex is counted at its
    /// lowest vertex, from that vertex's tets, in parallel.
    pub fn euler_characteristic_where(&self, keep: &[bool]) -> i64 {
        (0..self.num_vertices())
            .into_par_iter()
            .filter(|&v| keep[v] && !self.vertex_tets(v).is_empty())
            .map_init(EulerScratch::default, |scratch, v| {
                self.euler_at(v, keep, scratch)
            })
            .sum()
    }

    /// The simplices of the kept subcomplex whose lowest vertex is `v` (kept and used),
    /// counted with their signs: 1 − edges + faces − tets.
    fn euler_at(&self, v: usize, keep: &[bool], scratch: &mut EulerScratch) -> i64 {
        let v32 = v as u32;
        let kept_above = |u: u32| u > v32 && keep[u as usize];
        let (edges, faces) = (&mut scratch.edges, &mut scratch.faces);
        edges.clear();
        faces.clear();
        let mut tets = 0i64;
        for &t in self.vertex_tets(v) {
            let mut others = [0u32; 3];
            let mut k = 0;
            for &u in &self.tets[t as usize] {
                if u != v32 && k < 3 {
                    others[k] = u;
                    k += 1;
                }
            }
            others.sort_unstable();
            let above = others.map(kept_above);
            edges.extend(others.iter().zip(above).filter(|x| x.1).map(|x| *x.0));
            for (a, b) in [(0, 1), (0, 2), (1, 2)] {
                if above[a] && above[b] {
                    faces.push([others[a], others[b]]);
                }
            }
            if above.iter().all(|&x| x) {
                tets += 1;
            }
        }
        edges.sort_unstable();
        edges.dedup();
        faces.sort_unstable();
        // A face used by one tet is on the boundary (two tets share every other face).
        scratch.boundary.clear();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j] == faces[i] {
                j += 1;
            }
            if j - i == 1 {
                scratch.boundary.push([v32, faces[i][0], faces[i][1]]);
            }
            i = j;
        }
        faces.dedup();
        1 - edges.len() as i64 + faces.len() as i64 - tets
    }

    /// The topology of the mesh: per connected component its χ and the χ of each of its
    /// boundary surfaces (see [`TetTopology`]).
    pub fn topology(&self) -> TetTopology {
        let (tet_component, count) = self.tet_components();
        let mut vertex_component = vec![u32::MAX; self.num_vertices()];
        for (t, tet) in self.tets.iter().enumerate() {
            for &v in tet {
                vertex_component[v as usize] = tet_component[t];
            }
        }
        let all = vec![true; self.num_vertices()];
        // Per vertex: its share of χ and the boundary faces whose lowest vertex it is.
        let per_vertex: Vec<(u32, i64, Vec<[u32; 3]>)> = (0..self.num_vertices())
            .into_par_iter()
            .filter(|&v| !self.vertex_tets(v).is_empty())
            .map_init(EulerScratch::default, |scratch, v| {
                let euler = self.euler_at(v, &all, scratch);
                (vertex_component[v], euler, scratch.boundary.clone())
            })
            .collect();
        let mut components = vec![
            ComponentTopology {
                euler: 0,
                boundary_eulers: Vec::new(),
            };
            count
        ];
        let mut faces: Vec<[u32; 3]> = Vec::new();
        for (c, e, boundary) in per_vertex {
            components[c as usize].euler += e;
            faces.extend(boundary);
        }
        // Boundary surfaces: boundary faces joined across shared edges.
        let mut parent: Vec<usize> = (0..faces.len()).collect();
        let mut edge_faces: Vec<([u32; 2], usize)> = Vec::with_capacity(3 * faces.len());
        for (f, face) in faces.iter().enumerate() {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                let (u, w) = (face[a], face[b]);
                edge_faces.push(([u.min(w), u.max(w)], f));
            }
        }
        edge_faces.sort_unstable();
        for pair in edge_faces.windows(2) {
            if pair[0].0 == pair[1].0 {
                union(&mut parent, pair[0].1, pair[1].1);
            }
        }
        // Per boundary surface (by its root face): its tet component, vertices, edges
        // and face count.
        #[derive(Default)]
        struct Surface {
            component: u32,
            vertices: Vec<u32>,
            edges: usize,
            faces: i64,
        }
        let mut surfaces: HashMap<usize, Surface> = HashMap::new();
        for (f, face) in faces.iter().enumerate() {
            let entry = surfaces
                .entry(find(&mut parent, f))
                .or_insert_with(|| Surface {
                    component: vertex_component[face[0] as usize],
                    ..Surface::default()
                });
            entry.vertices.extend_from_slice(face);
            entry.faces += 1;
        }
        // Each boundary edge once (its faces are in the same surface).
        let mut edge_root: Vec<([u32; 2], usize)> = edge_faces
            .iter()
            .map(|&(e, f)| (e, find(&mut parent, f)))
            .collect();
        edge_root.dedup_by_key(|x| x.0);
        for (_, root) in edge_root {
            if let Some(entry) = surfaces.get_mut(&root) {
                entry.edges += 1;
            }
        }
        for mut surface in surfaces.into_values() {
            surface.vertices.sort_unstable();
            surface.vertices.dedup();
            let euler = surface.vertices.len() as i64 - surface.edges as i64 + surface.faces;
            components[surface.component as usize]
                .boundary_eulers
                .push(euler);
        }
        TetTopology::new(components)
    }

    /// Connected components of the tets (through shared vertices): a component id per
    /// tet, numbered in order of first appearance, and the count.
    pub fn tet_components(&self) -> (Vec<u32>, usize) {
        let mut parent: Vec<usize> = (0..self.num_vertices()).collect();
        for t in &self.tets {
            for k in 1..4 {
                union(&mut parent, t[0] as usize, t[k] as usize);
            }
        }
        let mut id_of_root = vec![u32::MAX; self.num_vertices()];
        let mut count = 0u32;
        let ids = self
            .tets
            .iter()
            .map(|t| {
                let r = find(&mut parent, t[0] as usize);
                if id_of_root[r] == u32::MAX {
                    id_of_root[r] = count;
                    count += 1;
                }
                id_of_root[r]
            })
            .collect();
        (ids, count as usize)
    }

    /// The mesh made of the tets with `keep[t]`, without the vertices no kept tet uses
    /// (vertex order otherwise kept).
    pub fn retain_tets(&self, keep: &[bool]) -> TetMesh {
        let tets: Vec<[u32; 4]> = self
            .tets
            .iter()
            .zip(keep)
            .filter(|(_, &k)| k)
            .map(|(t, _)| *t)
            .collect();
        let (new_id, used) = renumber_used(self.num_vertices(), &tets);
        let positions = used.iter().map(|&v| self.positions[v as usize]).collect();
        let kinds = used.iter().map(|&v| self.kinds[v as usize]).collect();
        let tets = tets.iter().map(|t| t.map(|v| new_id[v as usize])).collect();
        // Indices are remapped from a valid mesh, so construction cannot fail.
        TetMesh::new(positions, tets, kinds).unwrap_or_else(|_| unreachable!())
    }

    /// Smallest and largest dihedral angle over all tets, in degrees (`None` for no tets).
    pub fn dihedral_range_deg(&self) -> Option<(f64, f64)> {
        let mut range: Option<(f64, f64)> = None;
        for t in 0..self.num_tets() {
            for angle in dihedral_angles_deg(self.corners(t)) {
                range = Some(match range {
                    None => (angle, angle),
                    Some((lo, hi)) => (lo.min(angle), hi.max(angle)),
                });
            }
        }
        range
    }

    /// For a mesh read from a file: vertices on boundary faces are `Surface`, the rest
    /// `Interior`; when the boundary has several components, the one that encloses the
    /// others (largest bounding box) is `Outer` (an exterior shell).
    pub fn classify_boundary(positions: &[[f64; 3]], tets: &[[u32; 4]]) -> Vec<VertexKind> {
        let mut kinds = vec![VertexKind::Interior; positions.len()];
        let mesh = TetMesh {
            positions: positions.to_vec(),
            tets: tets.to_vec(),
            kinds: kinds.clone(),
            vertex_tets: Csr::default(),
        };
        let faces = mesh.boundary_faces();
        // Components of the boundary surface, by union-find over face corners.
        let mut parent: Vec<usize> = (0..positions.len()).collect();
        let mut on_boundary = vec![false; positions.len()];
        for f in &faces {
            for &v in f {
                on_boundary[v as usize] = true;
            }
            union(&mut parent, f[0] as usize, f[1] as usize);
            union(&mut parent, f[0] as usize, f[2] as usize);
        }
        // Each component's bounding-box diagonal; the largest encloses the others.
        let mut boxes: HashMap<usize, ([f64; 3], [f64; 3])> = HashMap::new();
        for v in (0..positions.len()).filter(|&v| on_boundary[v]) {
            let p = positions[v];
            let b = boxes.entry(find(&mut parent, v)).or_insert((p, p));
            for (k, &c) in p.iter().enumerate() {
                b.0[k] = b.0[k].min(c);
                b.1[k] = b.1[k].max(c);
            }
        }
        let outer_root = (boxes.len() > 1)
            .then(|| {
                boxes
                    .iter()
                    .map(|(&r, b)| (norm(sub(b.1, b.0)), r))
                    .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)))
                    .map(|x| x.1)
            })
            .flatten();
        for v in (0..positions.len()).filter(|&v| on_boundary[v]) {
            kinds[v] = if Some(find(&mut parent, v)) == outer_root {
                VertexKind::Outer
            } else {
                VertexKind::Surface
            };
        }
        kinds
    }
}

/// Reusable buffers of [`TetMesh::euler_at`].
#[derive(Default)]
struct EulerScratch {
    edges: Vec<u32>,
    faces: Vec<[u32; 2]>,
    /// The boundary faces found at the vertex (lowest vertex first).
    boundary: Vec<[u32; 3]>,
}

/// The topology of a tet mesh (or the one a surface predicts for it): its connected
/// components, each with its Euler characteristic and those of its boundary surfaces.
/// Components are sorted (by χ, then by their boundary list), so two topologies
/// compare equal exactly when they agree component by component.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TetTopology {
    /// One entry per connected component.
    pub components: Vec<ComponentTopology>,
}

/// One connected component of a [`TetTopology`].
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ComponentTopology {
    /// χ = V − E + F − T of the component (for a 3-manifold, half the sum of its
    /// boundary surfaces' χ).
    pub euler: i64,
    /// χ = 2 − 2g of each boundary surface, largest first.
    pub boundary_eulers: Vec<i64>,
}

impl TetTopology {
    /// Sort the components (and each one's boundary list) into the canonical order.
    pub fn new(mut components: Vec<ComponentTopology>) -> TetTopology {
        for c in &mut components {
            c.boundary_eulers.sort_unstable_by(|a, b| b.cmp(a));
        }
        components.sort_unstable();
        TetTopology { components }
    }

    /// χ of the whole mesh.
    pub fn euler(&self) -> i64 {
        self.components.iter().map(|c| c.euler).sum()
    }

    /// Number of boundary surfaces.
    pub fn boundary_components(&self) -> usize {
        self.components
            .iter()
            .map(|c| c.boundary_eulers.len())
            .sum()
    }

    /// χ of the whole boundary.
    pub fn boundary_euler(&self) -> i64 {
        self.components
            .iter()
            .flat_map(|c| &c.boundary_eulers)
            .sum()
    }
}

impl std::fmt::Display for TetTopology {
    /// `3 components (χ 1 | 1 boundary: 2), ...`: counts and χ per component.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} component{}, χ {}, {} boundary surface{}",
            self.components.len(),
            if self.components.len() == 1 { "" } else { "s" },
            self.euler(),
            self.boundary_components(),
            if self.boundary_components() == 1 {
                ""
            } else {
                "s"
            },
        )?;
        // Genus of each boundary surface, when the list is short enough to read.
        if self.boundary_components() <= 8 {
            let genera: Vec<String> = self
                .components
                .iter()
                .flat_map(|c| &c.boundary_eulers)
                .map(|&e| {
                    if e % 2 == 0 {
                        format!("{}", (2 - e) / 2)
                    } else {
                        format!("χ{e}")
                    }
                })
                .collect();
            write!(f, " of genus {}", genera.join(", "))?;
        }
        Ok(())
    }
}

/// The six dihedral angles of a tetrahedron, in degrees.
pub fn dihedral_angles_deg(p: [[f64; 3]; 4]) -> [f64; 6] {
    // The angle at edge (i, j) is between the faces (i, j, k) and (i, j, l).
    let pairs = [
        (0, 1, 2, 3),
        (0, 2, 1, 3),
        (0, 3, 1, 2),
        (1, 2, 0, 3),
        (1, 3, 0, 2),
        (2, 3, 0, 1),
    ];
    pairs.map(|(i, j, k, l)| {
        let e = sub(p[j], p[i]);
        let n1 = cross(e, sub(p[k], p[i]));
        let n2 = cross(e, sub(p[l], p[i]));
        let (a, b) = (norm(n1), norm(n2));
        if a == 0.0 || b == 0.0 {
            return 0.0;
        }
        (dot(n1, n2) / (a * b)).clamp(-1.0, 1.0).acos().to_degrees()
    })
}

/// The renumbering that drops the vertices no tet uses: each old vertex's new index
/// (`u32::MAX` where unused) and the old index of each kept vertex, in index order.
pub fn renumber_used(num_vertices: usize, tets: &[[u32; 4]]) -> (Vec<u32>, Vec<u32>) {
    let mut new_id = vec![u32::MAX; num_vertices];
    for t in tets {
        for &v in t {
            new_id[v as usize] = 0;
        }
    }
    let mut used = Vec::new();
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = used.len() as u32;
            used.push(v as u32);
        }
    }
    (new_id, used)
}

/// The faces used by exactly one of `tets` (positively oriented), oriented outward,
/// sorted by their vertex sets: the boundary of a mesh, or of a vertex's star.
pub fn boundary_faces_of(tets: impl IntoIterator<Item = [u32; 4]>) -> Vec<[u32; 3]> {
    // The faces of a positively oriented tet (a, b, c, d), outward.
    let mut faces: Vec<([u32; 3], [u32; 3])> = Vec::new();
    for [a, b, c, d] in tets {
        for f in [[b, c, d], [a, d, c], [a, b, d], [a, c, b]] {
            let mut key = f;
            key.sort_unstable();
            faces.push((key, f));
        }
    }
    faces.sort_unstable_by_key(|x| x.0);
    let mut out = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j - i == 1 {
            out.push(faces[i].1);
        }
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_tets() -> TetMesh {
        // The unit cube as 6 Kuhn tets around the diagonal 0-7 (corner bits x=1, y=2, z=4).
        let positions: Vec<[f64; 3]> = (0..8)
            .map(|c| [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64])
            .collect();
        let mut tets = Vec::new();
        for path in [[1, 3], [1, 5], [2, 3], [2, 6], [4, 5], [4, 6]] {
            let mut t = [0u32, path[0], path[1], 7];
            let m =
                TetMesh::new(positions.clone(), vec![t], vec![VertexKind::Interior; 8]).unwrap();
            if m.tet_volume(0) < 0.0 {
                t.swap(2, 3);
            }
            tets.push(t);
        }
        let kinds = TetMesh::classify_boundary(&positions, &tets);
        TetMesh::new(positions, tets, kinds).unwrap()
    }

    #[test]
    fn a_cube_of_six_tets_has_the_right_invariants() {
        let m = cube_tets();
        assert!((m.volume() - 1.0).abs() < 1e-14);
        assert_eq!(m.euler_characteristic(), 1);
        assert_eq!(m.boundary_faces().len(), 12);
        assert_eq!(m.kind_counts(), (0, 8, 0));
        let (lo, hi) = m.dihedral_range_deg().unwrap();
        assert!(
            (lo - 45.0).abs() < 1e-9 && (hi - 90.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        // Boundary faces point outward: their signed volume against the centre is positive.
        let c = [0.5; 3];
        for f in m.boundary_faces() {
            let [a, b, d] = f.map(|v| m.positions[v as usize]);
            assert!(dot(sub(a, c), cross(sub(b, c), sub(d, c))) > 0.0);
        }
        for v in 0..8 {
            assert!(!m.vertex_tets(v).is_empty());
        }
    }

    #[test]
    fn the_topology_counts_components_and_boundary_surfaces() {
        let cube = cube_tets();
        let t = cube.topology();
        assert_eq!(
            t,
            TetTopology::new(vec![ComponentTopology {
                euler: 1,
                boundary_eulers: vec![2]
            }])
        );
        assert_eq!(
            (t.euler(), t.boundary_components(), t.boundary_euler()),
            (1, 1, 2)
        );
        // Two cubes apart: two components, listed in the canonical order.
        let mut positions = cube.positions.clone();
        positions.extend(cube.positions.iter().map(|p| [p[0] + 2.0, p[1], p[2]]));
        let mut tets = cube.tets.clone();
        tets.extend(cube.tets.iter().map(|t| t.map(|v| v + 8)));
        let kinds = TetMesh::classify_boundary(&positions, &tets);
        let two = TetMesh::new(positions, tets, kinds).unwrap().topology();
        assert_eq!(two.components.len(), 2);
        assert_eq!((two.euler(), two.boundary_components()), (2, 2));
        assert_eq!(
            two.to_string(),
            "2 components, χ 2, 2 boundary surfaces of genus 0, 0"
        );
    }

    #[test]
    fn regular_tetrahedron_dihedrals() {
        let s = 1.0 / 2f64.sqrt();
        let p = [
            [1.0, 0.0, -s],
            [-1.0, 0.0, -s],
            [0.0, 1.0, s],
            [0.0, -1.0, s],
        ];
        for a in dihedral_angles_deg(p) {
            assert!((a - (1.0f64 / 3.0).acos().to_degrees()).abs() < 1e-9);
        }
    }
}
