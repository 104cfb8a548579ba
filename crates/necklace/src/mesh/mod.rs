//! Surface meshes: the plain data every stage starts from, and its validity report.
//!
//! A [`SurfaceMesh`] is a triangle soup with shared vertices: `positions` (f64, in the
//! input's units) and `triangles` (three `u32` vertex indices each, counter-clockwise seen
//! from outside for an outward-oriented mesh). Nothing is precomputed; topology is built
//! on demand by [`Topology::new`] (edges and their faces, vertex-to-face adjacency,
//! components) and summarised by [`MeshReport::new`], which is what `necklace info`
//! prints (validity, genus per component, a flat surface, coordinates too large).
//! [`HomologyBasis::new`] gives a Z2 homology basis (tree–cotree) to name the class of a
//! closed curve on the surface from the edges it crosses; [`Z2Basis`] and [`z2_rank`]
//! compare such classes.
//!
//! Also here: [`Side`], the one name of the two regions a surface bounds (inside,
//! outside) for every stage, a loop's kind (handle, tunnel) being its side; [`Csr`], the
//! crate's one adjacency-list type (topology, tets, the mesher's stars); and the repairs
//! that keep the shape: [`weld`] (boundary corners within a tolerance merged, collapsed
//! triangles removed), [`remove_unreferenced`] and [`orient_consistently`] (libigl's
//! `bfs_orient`).
//!
//! Conventions:
//! - An *edge* is an unordered vertex pair used by at least one triangle; a *boundary
//!   edge* has one incident face, a *non-manifold edge* three or more.
//! - A vertex is *non-manifold* when its incident faces form more than one fan (faces
//!   around the vertex connected through edges at the vertex), i.e. its link is not a
//!   single cycle or path.
//! - *Oriented* means every interior edge is used in opposite directions by its two faces
//!   (and no directed edge is used twice).
//! - Components are connected components of the edge graph over referenced vertices.
//! - Genus per component: from χ = V − E + F = 2 − 2g − b (b = boundary loops), defined
//!   only for manifold, oriented components.
//! - The signed volume (divergence theorem) is positive for an outward-oriented closed mesh.

mod csr;
#[cfg(test)]
pub(crate) mod fixtures;
mod homology;
mod repair;
mod report;
mod side;
mod topology;

pub use csr::Csr;
pub use homology::{z2_rank, HomologyBasis, Z2Basis};
pub use repair::{orient_consistently, remove_unreferenced, weld, Reorientation, Welding};
pub use report::{ComponentReport, MeshReport, MAX_COORDINATE};
pub use side::Side;
pub use topology::Topology;
pub(crate) use topology::{find, union};

use crate::error::{Error, ErrorKind, Result};
use crate::geom::{cross, dot, norm, sub};

/// A triangle mesh: vertex positions and triangles as vertex-index triples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceMesh {
    /// Vertex positions, in the input's units.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

/// An error naming the first vertex with a NaN or infinite coordinate.
pub(crate) fn check_finite(positions: &[[f64; 3]]) -> Result<()> {
    match positions
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        Some(i) => Err(Error::new(
            ErrorKind::NonFinite,
            format!("vertex {i} has a non-finite coordinate"),
        )),
        None => Ok(()),
    }
}

impl SurfaceMesh {
    /// Build a mesh, checking that every index is in range and every coordinate finite.
    pub fn new(positions: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        check_finite(&positions)?;
        let n = positions.len();
        for (f, t) in triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
                return Err(Error::new(
                    ErrorKind::IndexOutOfRange,
                    format!("triangle {f} uses vertex {v}, but there are {n} vertices"),
                ));
            }
        }
        Ok(SurfaceMesh {
            positions,
            triangles,
        })
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `f`.
    pub fn corners(&self, f: usize) -> [[f64; 3]; 3] {
        let t = self.triangles[f];
        [
            self.positions[t[0] as usize],
            self.positions[t[1] as usize],
            self.positions[t[2] as usize],
        ]
    }

    /// Axis-aligned bounding box `(min, max)` of the vertices; `None` for no vertices.
    pub fn bounding_box(&self) -> Option<([f64; 3], [f64; 3])> {
        let first = *self.positions.first()?;
        let mut lo = first;
        let mut hi = first;
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Some((lo, hi))
    }

    /// Length of the bounding-box diagonal (0 for an empty mesh).
    pub fn bbox_diagonal(&self) -> f64 {
        match self.bounding_box() {
            Some((lo, hi)) => norm(sub(hi, lo)),
            None => 0.0,
        }
    }

    /// Signed enclosed volume (sum of signed tetrahedra against the origin). Positive
    /// for a closed, outward-oriented mesh; meaningful only for closed meshes.
    pub fn signed_volume(&self) -> f64 {
        // Accumulate against the first vertex to limit cancellation far from the origin.
        let Some(&o) = self.positions.first() else {
            return 0.0;
        };
        let mut six_v = 0.0;
        for f in 0..self.triangles.len() {
            let [a, b, c] = self.corners(f);
            six_v += dot(sub(a, o), cross(sub(b, o), sub(c, o)));
        }
        six_v / 6.0
    }

    /// Twice the area vector of triangle `f` (cross product of two edges).
    pub fn face_normal_scaled(&self, f: usize) -> [f64; 3] {
        let [a, b, c] = self.corners(f);
        cross(sub(b, a), sub(c, a))
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|f| 0.5 * norm(self.face_normal_scaled(f)))
            .sum()
    }

    /// Reverse the orientation of every triangle.
    pub fn flip_orientation(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }
}
