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
//! length². Entry point: [`hessian_at`].

use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen};
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
    let values: Vec<f64> = samples.iter().map(|&u| f[u as usize]).collect();
    if values.iter().any(|x| !x.is_finite()) {
        return None;
    }
    fit(&offsets, &values, scale)
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

/// Least-squares quadratic through `(offset, value)` samples; `scale` normalises the
/// offsets.
fn fit(offsets: &[[f64; 3]], values: &[f64], scale: f64) -> Option<Hessian> {
    let rows = offsets.len();
    let a = DMatrix::from_fn(rows, 10, |i, j| {
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
    });
    let b = DVector::from_column_slice(values);
    let coefficients = a.svd(true, true).solve(&b, 1e-12).ok()?;
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
