//! Edge and vertex adjacency of a [`SurfaceMesh`], built once on demand.

use super::{Csr, SurfaceMesh};

/// Adjacency of a triangle mesh: unique undirected edges with their incident faces,
/// the edges of each face, and the faces and edges around each vertex (all in CSR
/// form).
///
/// Self-loop "edges" of degenerate triangles (a triangle that repeats a vertex index)
/// are left out; such triangles are counted by the report as degenerate.
#[derive(Debug, Clone)]
pub struct Topology {
    num_vertices: usize,
    edges: Vec<[u32; 2]>,
    edge_face_start: Vec<u32>,
    edge_faces: Vec<u32>,
    face_edges: Vec<[u32; 3]>,
    vertex_faces: Csr,
    vertex_edges: Csr,
}

const NO_EDGE: u32 = u32::MAX;

impl Topology {
    /// Build the adjacency of `mesh`. `O(F)` (a sort per vertex of its few sides).
    pub fn new(mesh: &SurfaceMesh) -> Self {
        let nv = mesh.num_vertices();
        // Vertex -> faces, by counting sort (each vertex's faces in ascending order).
        let vertex_faces = Csr::new(
            nv,
            mesh.triangles
                .iter()
                .enumerate()
                .flat_map(|(f, t)| t.map(|v| (v, f as u32))),
        );
        // Every triangle side belongs to its lower vertex. Vertex by vertex, its sides
        // (upper vertex, face, side) sorted give its edges in key order and each edge's
        // faces in face order: the order of one sort of all sides, without that sort.
        let mut edges = Vec::new();
        let mut edge_face_start = vec![0u32];
        let mut edge_faces = Vec::with_capacity(3 * mesh.num_triangles());
        let mut face_edges = vec![[NO_EDGE; 3]; mesh.num_triangles()];
        let mut sides: Vec<(u32, u32, u8)> = Vec::new();
        for a in 0..nv {
            sides.clear();
            let mut previous = None;
            for &f in vertex_faces.get(a) {
                // A face that repeats `a` is listed once per corner: its sides once.
                if previous == Some(f) {
                    continue;
                }
                previous = Some(f);
                let t = mesh.triangles[f as usize];
                for i in 0..3 {
                    let (u, w) = (t[i], t[(i + 1) % 3]);
                    if u != w && u.min(w) as usize == a {
                        sides.push((u.max(w), f, i as u8));
                    }
                }
            }
            sides.sort_unstable();
            for (k, &(b, f, side)) in sides.iter().enumerate() {
                if k == 0 || sides[k - 1].0 != b {
                    if !edges.is_empty() {
                        edge_face_start.push(edge_faces.len() as u32);
                    }
                    edges.push([a as u32, b]);
                }
                edge_faces.push(f);
                face_edges[f as usize][side as usize] = (edges.len() - 1) as u32;
            }
        }
        if !edges.is_empty() {
            edge_face_start.push(edge_faces.len() as u32);
        }

        // Vertex -> edges, in edge order.
        let vertex_edges = Csr::new(
            nv,
            edges
                .iter()
                .enumerate()
                .flat_map(|(i, e)| e.map(|v| (v, i as u32))),
        );

        Topology {
            num_vertices: nv,
            edges,
            edge_face_start,
            edge_faces,
            face_edges,
            vertex_faces,
            vertex_edges,
        }
    }

    /// Number of faces.
    pub fn num_faces(&self) -> usize {
        self.face_edges.len()
    }

    /// Number of unique undirected edges.
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }

    /// The edges as sorted vertex pairs `[a, b]` with `a < b`.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Faces incident to edge `e` (a face appears twice if it uses the edge twice).
    pub fn edge_faces(&self, e: usize) -> &[u32] {
        let (s, t) = (self.edge_face_start[e], self.edge_face_start[e + 1]);
        &self.edge_faces[s as usize..t as usize]
    }

    /// Edge index of side `i` (from corner `i` to corner `i+1`) of face `f`, or `None`
    /// for the self-loop side of a degenerate triangle.
    pub fn face_edge(&self, f: usize, i: usize) -> Option<usize> {
        let e = self.face_edges[f][i];
        (e != NO_EDGE).then_some(e as usize)
    }

    /// The face across side `i` of face `f` (from corner `i` to corner `i+1`) and the
    /// edge they share, when that edge is manifold (exactly two faces).
    pub fn across(&self, f: usize, i: usize) -> Option<(usize, usize)> {
        let e = self.face_edge(f, i)?;
        match *self.edge_faces(e) {
            [a, b] if a as usize == f => Some((b as usize, e)),
            [a, b] if b as usize == f => Some((a as usize, e)),
            _ => None,
        }
    }

    /// Faces incident to vertex `v` (a face appears once per corner at `v`).
    pub fn vertex_faces(&self, v: usize) -> &[u32] {
        self.vertex_faces.get(v)
    }

    /// Edges at vertex `v`, in edge order.
    pub fn vertex_edges(&self, v: usize) -> &[u32] {
        self.vertex_edges.get(v)
    }

    /// Edges with exactly one incident face.
    pub fn boundary_edges(&self) -> Vec<usize> {
        (0..self.num_edges())
            .filter(|&e| self.edge_faces(e).len() == 1)
            .collect()
    }

    /// Edges with three or more incident faces.
    pub fn non_manifold_edges(&self) -> Vec<usize> {
        (0..self.num_edges())
            .filter(|&e| self.edge_faces(e).len() > 2)
            .collect()
    }

    /// Edges whose faces do not use them in opposite directions: an interior edge
    /// traversed the same way by both faces, or any edge traversed twice in one direction.
    pub fn inconsistently_oriented_edges(&self, mesh: &SurfaceMesh) -> Vec<usize> {
        (0..self.num_edges())
            .filter(|&e| {
                let [a, _] = self.edges[e];
                let mut forward = 0;
                let mut backward = 0;
                for &f in self.edge_faces(e) {
                    let t = mesh.triangles[f as usize];
                    for (i, &start) in t.iter().enumerate() {
                        if self.face_edges[f as usize][i] as usize == e {
                            if start == a {
                                forward += 1;
                            } else {
                                backward += 1;
                            }
                        }
                    }
                }
                forward > 1 || backward > 1
            })
            .collect()
    }

    /// Vertices whose incident faces form more than one fan (faces connected through
    /// edges at the vertex): their link is not a single cycle or path.
    pub fn non_manifold_vertices(&self, mesh: &SurfaceMesh) -> Vec<usize> {
        let mut out = Vec::new();
        let mut parent: Vec<usize> = Vec::new();
        let mut spokes: Vec<(u32, usize)> = Vec::new();
        for v in 0..self.num_vertices {
            let faces = self.vertex_faces(v);
            if faces.len() < 2 {
                continue;
            }
            // Union the faces around v that share a spoke edge (v, w).
            parent.clear();
            parent.extend(0..faces.len());
            spokes.clear();
            for (k, &f) in faces.iter().enumerate() {
                for &w in &mesh.triangles[f as usize] {
                    if w as usize != v {
                        spokes.push((w, k));
                    }
                }
            }
            spokes.sort_unstable();
            for pair in spokes.windows(2) {
                if pair[0].0 == pair[1].0 {
                    union(&mut parent, pair[0].1, pair[1].1);
                }
            }
            let fans = (0..faces.len())
                .filter(|&k| find(&mut parent, k) == k)
                .count();
            if fans > 1 {
                out.push(v);
            }
        }
        out
    }

    /// Connected components of the edge graph: a component id per vertex (`None` for
    /// vertices no triangle uses) and the number of components. Ids follow the order
    /// of each component's lowest vertex.
    pub fn components(&self, mesh: &SurfaceMesh) -> (Vec<Option<u32>>, usize) {
        let mut parent: Vec<usize> = (0..self.num_vertices).collect();
        for t in &mesh.triangles {
            union(&mut parent, t[0] as usize, t[1] as usize);
            union(&mut parent, t[1] as usize, t[2] as usize);
        }
        let mut used = vec![false; self.num_vertices];
        for t in &mesh.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        let mut id_of_root = vec![u32::MAX; self.num_vertices];
        let mut ids = vec![None; self.num_vertices];
        let mut count = 0usize;
        for v in 0..self.num_vertices {
            if !used[v] {
                continue;
            }
            let r = find(&mut parent, v);
            if id_of_root[r] == u32::MAX {
                id_of_root[r] = count as u32;
                count += 1;
            }
            ids[v] = Some(id_of_root[r]);
        }
        (ids, count)
    }
}

/// Union-find `find` with path halving.
pub(crate) fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// Union-find `union` (the smaller root becomes the parent, so results are deterministic).
pub(crate) fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi] = lo;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A torus of 7 × 5 quads, each split in two, its vertices numbered in a scrambled
    /// order (topology needs no positions, but the mesh carries some).
    fn grid_torus() -> SurfaceMesh {
        let (n, m) = (7u32, 5u32);
        let id = |i: u32, j: u32| ((i % n) * m + (j % m)) * 13 % (n * m);
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..m {
                let [a, b, c, d] = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        SurfaceMesh {
            positions: (0..n * m).map(|v| [v as f64, 0.0, 0.0]).collect(),
            triangles,
        }
    }

    /// Edges, each edge's faces, and each face's edges.
    type Adjacency = (Vec<[u32; 2]>, Vec<Vec<u32>>, Vec<[u32; 3]>);

    /// The edges, their faces and the faces' edges by the definition: every triangle
    /// side keyed by its sorted endpoints, all sides sorted by (key, face, side).
    fn by_one_sort(mesh: &SurfaceMesh) -> Adjacency {
        let mut sides = Vec::new();
        for (f, t) in mesh.triangles.iter().enumerate() {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                if a != b {
                    sides.push(([a.min(b), a.max(b)], f as u32, i));
                }
            }
        }
        sides.sort_unstable();
        let (mut edges, mut faces) = (Vec::<[u32; 2]>::new(), Vec::<Vec<u32>>::new());
        let mut face_edges = vec![[NO_EDGE; 3]; mesh.num_triangles()];
        for (key, f, i) in sides {
            if edges.last() != Some(&key) {
                edges.push(key);
                faces.push(Vec::new());
            }
            faces.last_mut().unwrap().push(f);
            face_edges[f as usize][i] = (edges.len() - 1) as u32;
        }
        (edges, faces, face_edges)
    }

    #[test]
    fn adjacency_is_that_of_one_sort_of_all_sides() {
        let mut mesh = grid_torus();
        let n = mesh.num_vertices() as u32;
        // A degenerate triangle (a repeated vertex), a third face on an edge, and an
        // unused vertex.
        let [a, b, c] = mesh.triangles[0];
        mesh.triangles.push([a, b, a]);
        mesh.triangles.push([b, a, c]);
        mesh.triangles.push([c, c, c]);
        mesh.positions.push([9.0, 9.0, 9.0]);
        let topology = Topology::new(&mesh);
        let (edges, faces, face_edges) = by_one_sort(&mesh);
        assert_eq!(topology.edges(), &edges[..]);
        for (e, expected) in faces.iter().enumerate() {
            assert_eq!(topology.edge_faces(e), &expected[..], "edge {e}");
        }
        assert_eq!(topology.face_edges, face_edges);
        assert!(topology.vertex_faces(n as usize).is_empty());
        for (e, edge) in edges.iter().enumerate() {
            for &v in edge {
                assert!(topology.vertex_edges(v as usize).contains(&(e as u32)));
            }
        }
    }
}
