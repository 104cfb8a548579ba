//! Local quadratic fit of a vertex field and its Hessian (paper sec. 4.2, "local
//! approximation-based selection").
//!
//! Around vertex `v` at `p`, fit `f(p + d) ≈ c + g·d + ½ dᵀ H d` by least squares over
//! `v` and its one-ring (its two-ring when the one-ring has fewer than 10 vertices; ten
//! coefficients need ten samples). Offsets are scaled to unit size before the solve
//! (SVD, so a degenerate neighbourhood gives a minimum-norm answer instead of a
//! failure) and `H` is scaled back. `H`'s eigenvalues, ascending, with unit
//! eigenvectors: a 2-saddle of the field has signature (−, −, +), and the eigenvector of
//! the positive eigenvalue is the neck's cutting-plane normal. Units: field units per
//! length². Entry point: [`hessian_at`]; a vertex fitted for many fields keeps its
//! factored matrix in a [`Fit`].

use nalgebra::{DMatrix, DVector, Dyn, Matrix3, SymmetricEigen, SVD};
use serde::{Deserialize, Serialize};

use crate::tet::TetMesh;

/// The fitted Hessian at a vertex.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Hessian {
    /// Eigenvalues, ascending.
    pub eigenvalues: [f64; 3],
    /// Unit eigenvector of each eigenvalue, its largest component made positive.
    pub eigenvectors: [[f64; 3]; 3],
    /// Gradient of the fitted quadratic at the vertex.
    pub gradient: [f64; 3],
    /// Number of samples fitted.
    pub samples: usize,
}

impl Hessian {
    /// Signature (−, −, +): two negative eigenvalues and one positive.
    pub fn is_two_saddle(&self) -> bool {
        self.eigenvalues[0] < 0.0 && self.eigenvalues[1] < 0.0 && self.eigenvalues[2] > 0.0
    }

    /// Eigenvector of the largest eigenvalue (the cutting-plane normal of a 2-saddle).
    pub fn normal(&self) -> [f64; 3] {
        self.eigenvectors[2]
    }
}

/// Fit the Hessian of `f` at vertex `v` (see the module doc). `None` when the
/// neighbourhood has fewer than 10 vertices even with the two-ring, or a value is
/// not finite.
pub fn hessian_at(mesh: &TetMesh, f: &[f64], v: u32) -> Option<Hessian> {
    Fit::new(mesh, v)?.hessian(f)
}

/// The part of the fit at a vertex that does not depend on the field: its samples and
/// the factored (SVD) design matrix of their scaled offsets. A vertex fitted at many
/// levels of the scale space factors it once; [`Fit::hessian`] then solves for each
/// field, with the result [`hessian_at`] gives. About 3 KB a vertex.
pub struct Fit {
    samples: Vec<u32>,
    scale: f64,
    svd: SVD<f64, Dyn, Dyn>,
}

impl Fit {
    /// The samples around `v` and their design matrix, factored; `None` when the
    /// neighbourhood has fewer than 10 vertices even with the two-ring, or no extent.
    pub fn new(mesh: &TetMesh, v: u32) -> Option<Fit> {
        // `neighbours` includes the seeds: the one-ring plus `v`.
        let mut samples = neighbours(mesh, &[v]);
        if samples.len() < 11 {
            samples = neighbours(mesh, &samples);
        }
        if samples.len() < 10 {
            return None;
        }
        let centre = mesh.positions[v as usize];
        let offsets: Vec<[f64; 3]> = samples
            .iter()
            .map(|&u| {
                let p = mesh.positions[u as usize];
                [p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]]
            })
            .collect();
        let scale = offsets
            .iter()
            .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
            .fold(0.0, f64::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        Some(Fit {
            svd: design(&offsets, scale).svd(true, true),
            samples,
            scale,
        })
    }

    /// The Hessian of `f` at the vertex; `None` when a sample's value is not finite or
    /// the fit fails.
    pub fn hessian(&self, f: &[f64]) -> Option<Hessian> {
        let values: Vec<f64> = self.samples.iter().map(|&u| f[u as usize]).collect();
        if values.iter().any(|x| !x.is_finite()) {
            return None;
        }
        solve(&self.svd, &values, self.scale)
    }
}

/// The unit normal of the least-squares plane through `points` about `center` (the
/// eigenvector of their scatter's smallest eigenvalue), its sign arbitrary.
pub(super) fn plane_normal(points: &[[f64; 3]], center: [f64; 3]) -> [f64; 3] {
    let scatter = points.iter().fold(Matrix3::zeros(), |m, p| {
        let d = nalgebra::Vector3::new(p[0] - center[0], p[1] - center[1], p[2] - center[2]);
        m + d * d.transpose()
    });
    let eigen = SymmetricEigen::new(scatter);
    let e = eigen.eigenvectors.column(eigen.eigenvalues.imin());
    [e[0], e[1], e[2]]
}

/// `v` and every vertex sharing a tet with one of `seeds`, sorted.
fn neighbours(mesh: &TetMesh, seeds: &[u32]) -> Vec<u32> {
    let mut out: Vec<u32> = seeds.to_vec();
    for &s in seeds {
        for &t in mesh.vertex_tets(s as usize) {
            out.extend(mesh.tets[t as usize]);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The least-squares design matrix of a quadratic in the offsets (scaled by `scale`):
/// one row per sample, ten coefficients.
fn design(offsets: &[[f64; 3]], scale: f64) -> DMatrix<f64> {
    DMatrix::from_fn(offsets.len(), 10, |i, j| {
        let [x, y, z] = offsets[i].map(|c| c / scale);
        match j {
            0 => 1.0,
            1 => x,
            2 => y,
            3 => z,
            4 => 0.5 * x * x,
            5 => 0.5 * y * y,
            6 => 0.5 * z * z,
            7 => x * y,
            8 => x * z,
            _ => y * z,
        }
    })
}

/// The least-squares quadratic through the samples' `values`, given the SVD of their
/// design matrix, and its Hessian (scaled back by `scale`).
fn solve(svd: &SVD<f64, Dyn, Dyn>, values: &[f64], scale: f64) -> Option<Hessian> {
    let rows = values.len();
    let b = DVector::from_column_slice(values);
    let coefficients = svd.solve(&b, 1e-12).ok()?;
    let c = |k: usize| coefficients[k];
    let s2 = scale * scale;
    let h = Matrix3::new(c(4), c(7), c(8), c(7), c(5), c(9), c(8), c(9), c(6)) / s2;
    if h.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let eigen = SymmetricEigen::new(h);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    let eigenvalues = order.map(|i| eigen.eigenvalues[i]);
    let eigenvectors = order.map(|i| {
        let e = eigen.eigenvectors.column(i);
        let mut v = [e[0], e[1], e[2]];
        let largest = (0..3)
            .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
            .unwrap_or(0);
        if v[largest] < 0.0 {
            v = v.map(|x| -x);
        }
        v
    });
    Some(Hessian {
        eigenvalues,
        eigenvectors,
        gradient: [c(1) / scale, c(2) / scale, c(3) / scale],
        samples: rows,
    })
}
