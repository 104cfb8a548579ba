//! Critical points of a piecewise-linear function on a tet mesh from vertex links
//! (paper sec. 4.1).
//!
//! Order: surface vertices come below every interior vertex, outer-sphere vertices
//! above, and otherwise `(f, index)` decides (so ties are broken and the
//! classification is exact). For an interior vertex `v`, its link is the triangles
//! opposite `v` in its tets; the *upper* (*lower*) link is the part of the link above
//! (below) `v`, and its components are counted using only link edges whose two ends are
//! on the same side. Types: regular (1 up, 1 low), maximum (0, 1), minimum (1, 0),
//! 1-saddle (1, 2), 2-saddle (2, 1), anything else degenerate (a monkey saddle; its
//! counts are kept).
//!
//! Morse check: adding `v` to the lower-star filtration changes χ by `1 − χ(lower link)`
//! (= (−1)^index for a non-degenerate critical point, 0 for a regular one). Since the
//! surface comes first, the sum over interior vertices is χ(T) − χ(surface part): for a
//! connected genus-g surface, g − 1 inside and g outside (see the issue 4 note).
//! Entry point: [`classify`].

use rayon::prelude::*;
use serde::Serialize;

use crate::tet::{TetMesh, VertexKind};

/// The type of a vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VertexType {
    /// Not interior (surface or outer sphere): not classified.
    Boundary,
    /// One upper and one lower link component.
    Regular,
    /// No upper link.
    Maximum,
    /// No lower link.
    Minimum,
    /// One upper, two lower components.
    Saddle1,
    /// Two upper, one lower component.
    Saddle2,
    /// Any other counts.
    Degenerate,
}

/// The classification of one vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct VertexClass {
    /// Its type.
    pub kind: VertexType,
    /// Components of the upper link.
    pub upper: u32,
    /// Components of the lower link.
    pub lower: u32,
    /// `1 − χ(lower link)`: its contribution to the Morse sum.
    pub euler_term: i32,
}

/// Every vertex's class, and the Morse sum over interior vertices.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Classification {
    /// One entry per mesh vertex.
    pub classes: Vec<VertexClass>,
    /// Σ over interior vertices of `1 − χ(lower link)`.
    pub morse_sum: i64,
}

impl Classification {
    /// How many vertices have this type.
    pub fn count(&self, kind: VertexType) -> usize {
        self.classes.iter().filter(|c| c.kind == kind).count()
    }
}

/// Classify every interior vertex of `mesh` for the field `f` (one value per vertex).
pub fn classify(mesh: &TetMesh, f: &[f64]) -> Classification {
    let rank = |v: u32| match mesh.kinds[v as usize] {
        VertexKind::Surface => 0u8,
        VertexKind::Interior => 1,
        VertexKind::Outer => 2,
    };
    let below = |a: u32, b: u32| {
        (rank(a), f[a as usize], a)
            .partial_cmp(&(rank(b), f[b as usize], b))
            .is_some_and(|o| o.is_lt())
    };
    let classes: Vec<VertexClass> = (0..mesh.num_vertices() as u32)
        .into_par_iter()
        .map_init(Scratch::default, |s, v| {
            if mesh.kinds[v as usize] != VertexKind::Interior {
                return VertexClass {
                    kind: VertexType::Boundary,
                    upper: 0,
                    lower: 0,
                    euler_term: 0,
                };
            }
            s.classify(mesh, v, &below)
        })
        .collect();
    let morse_sum = classes.iter().map(|c| i64::from(c.euler_term)).sum();
    Classification { classes, morse_sum }
}

/// Per-thread buffers, reused from vertex to vertex (no allocation in steady state).
#[derive(Default)]
struct Scratch {
    triangles: Vec<[u32; 3]>,
    vertices: Vec<u32>,
    edges: Vec<[u32; 2]>,
    parent: Vec<usize>,
    is_lower: Vec<bool>,
}

impl Scratch {
    fn classify(
        &mut self,
        mesh: &TetMesh,
        v: u32,
        below: &dyn Fn(u32, u32) -> bool,
    ) -> VertexClass {
        self.triangles.clear();
        for &t in mesh.vertex_tets(v as usize) {
            let tet = mesh.tets[t as usize];
            let mut tri = [0u32; 3];
            let mut k = 0;
            for &u in &tet {
                if u != v && k < 3 {
                    tri[k] = u;
                    k += 1;
                }
            }
            self.triangles.push(tri);
        }
        self.vertices.clear();
        self.vertices.extend(self.triangles.iter().flatten());
        self.vertices.sort_unstable();
        self.vertices.dedup();
        let local = |vs: &[u32], u: u32| vs.binary_search(&u).unwrap_or(0);
        self.is_lower.clear();
        self.is_lower
            .extend(self.vertices.iter().map(|&u| below(u, v)));
        self.edges.clear();
        for tri in &self.triangles {
            for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[0], tri[2])] {
                self.edges.push([a.min(b), a.max(b)]);
            }
        }
        self.edges.sort_unstable();
        self.edges.dedup();

        // Components of each side, through same-side link edges.
        self.parent.clear();
        self.parent.extend(0..self.vertices.len());
        let mut lower_edges = 0i32;
        for &[a, b] in &self.edges {
            let (i, j) = (local(&self.vertices, a), local(&self.vertices, b));
            if self.is_lower[i] == self.is_lower[j] {
                let (ri, rj) = (root(&mut self.parent, i), root(&mut self.parent, j));
                self.parent[ri.max(rj)] = ri.min(rj);
                if self.is_lower[i] {
                    lower_edges += 1;
                }
            }
        }
        let (mut upper, mut lower) = (0u32, 0u32);
        for i in 0..self.vertices.len() {
            if root(&mut self.parent, i) == i {
                if self.is_lower[i] {
                    lower += 1;
                } else {
                    upper += 1;
                }
            }
        }
        let lower_vertices = self.is_lower.iter().filter(|&&l| l).count() as i32;
        let lower_triangles = self
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&u| self.is_lower[local(&self.vertices, u)]))
            .count() as i32;
        let euler_lower = lower_vertices - lower_edges + lower_triangles;
        let kind = match (upper, lower) {
            (1, 1) => VertexType::Regular,
            (0, 1) => VertexType::Maximum,
            (1, 0) => VertexType::Minimum,
            (1, 2) => VertexType::Saddle1,
            (2, 1) => VertexType::Saddle2,
            _ => VertexType::Degenerate,
        };
        VertexClass {
            kind,
            upper,
            lower,
            euler_term: 1 - euler_lower,
        }
    }
}

fn root(p: &mut [usize], mut x: usize) -> usize {
    while p[x] != x {
        p[x] = p[p[x]];
        x = p[x];
    }
    x
}
