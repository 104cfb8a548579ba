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
    /// Build the adjacency of `mesh`. `O(F log F)`.
    pub fn new(mesh: &SurfaceMesh) -> Self {
        let nv = mesh.num_vertices();
        // Every triangle side as (undirected key, face, side), sorted by key.
        let mut sides: Vec<(u64, u32, u8)> = Vec::with_capacity(3 * mesh.num_triangles());
        for (f, t) in mesh.triangles.iter().enumerate() {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                if a != b {
                    let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                    sides.push((key, f as u32, i as u8));
                }
            }
        }
        sides.sort_unstable();

        let mut edges = Vec::new();
        let mut edge_face_start = vec![0u32];
        let mut edge_faces = Vec::with_capacity(sides.len());
        let mut face_edges = vec![[NO_EDGE; 3]; mesh.num_triangles()];
        for (i, &(key, f, side)) in sides.iter().enumerate() {
            if i == 0 || sides[i - 1].0 != key {
                if i > 0 {
                    edge_face_start.push(edge_faces.len() as u32);
                }
                edges.push([(key >> 32) as u32, key as u32]);
            }
            edge_faces.push(f);
            face_edges[f as usize][side as usize] = (edges.len() - 1) as u32;
        }
        if !edges.is_empty() {
            edge_face_start.push(edge_faces.len() as u32);
        }

        // Vertex -> faces, by counting sort.
        let vertex_faces = Csr::new(
            nv,
            mesh.triangles
                .iter()
                .enumerate()
                .flat_map(|(f, t)| t.map(|v| (v, f as u32))),
        );
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
