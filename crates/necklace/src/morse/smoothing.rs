//! Implicit heat steps `(M + τL) F' = M F` with Dirichlet values (paper sec. 3.3).
//!
//! Fixed vertices keep their values; the free ones solve the reduced system
//! `(M + τL)_ff F'_f = M_f F_f − τ L_fd F_d` by conjugate gradients with a Jacobi
//! (diagonal) preconditioner, warm-started from the current field. Matrix-vector
//! products run rows in parallel; dot products are summed sequentially, so the result
//! does not depend on the thread count. Entry point: [`implicit_step`].

use serde::Serialize;

use super::laplacian::SparseMatrix;

/// Stopping rule of the conjugate-gradient solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverOptions {
    /// Relative residual `|r| / |b|` at which to stop (default 1e-10).
    pub tolerance: f64,
    /// Iteration cap (default 2000).
    pub max_iterations: usize,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            tolerance: 1e-10,
            max_iterations: 2000,
        }
    }
}

/// What one implicit step did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepReport {
    /// CG iterations.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Whether the tolerance was reached.
    pub converged: bool,
}

/// One implicit Euler step of the heat equation: returns the new field (fixed vertices
/// unchanged) and the solver's report. `stiffness` is `L` (positive semidefinite),
/// `mass` the lumped mass, `fixed[v]` marks Dirichlet vertices.
pub fn implicit_step(
    stiffness: &SparseMatrix,
    mass: &[f64],
    fixed: &[bool],
    field: &[f64],
    tau: f64,
    options: &SolverOptions,
) -> (Vec<f64>, StepReport) {
    let n = stiffness.n;
    // A x = (M + τL) x on free rows, with x zero on fixed vertices.
    let apply = |x: &[f64]| -> Vec<f64> {
        let lx = stiffness.mul_vec(x);
        (0..n)
            .map(|i| {
                if fixed[i] {
                    0.0
                } else {
                    mass[i] * x[i] + tau * lx[i]
                }
            })
            .collect()
    };
    // b = M F − τ L F_d on free rows (F_d: the field with free entries zeroed).
    let dirichlet: Vec<f64> = (0..n)
        .map(|i| if fixed[i] { field[i] } else { 0.0 })
        .collect();
    let l_dirichlet = stiffness.mul_vec(&dirichlet);
    let b: Vec<f64> = (0..n)
        .map(|i| {
            if fixed[i] {
                0.0
            } else {
                mass[i] * field[i] - tau * l_dirichlet[i]
            }
        })
        .collect();
    let diagonal: Vec<f64> = (0..n)
        .map(|i| {
            if fixed[i] {
                1.0
            } else {
                mass[i] + tau * stiffness.get(i, i)
            }
        })
        .collect();

    // Warm start from the current field (free part).
    let mut x: Vec<f64> = (0..n)
        .map(|i| if fixed[i] { 0.0 } else { field[i] })
        .collect();
    let ax = apply(&x);
    let mut r: Vec<f64> = (0..n).map(|i| b[i] - ax[i]).collect();
    let b_norm = dot(&b, &b).sqrt().max(f64::MIN_POSITIVE);
    let mut z: Vec<f64> = (0..n).map(|i| r[i] / diagonal[i]).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut report = StepReport {
        iterations: 0,
        residual: dot(&r, &r).sqrt() / b_norm,
        converged: false,
    };
    while report.residual > options.tolerance && report.iterations < options.max_iterations {
        let ap = apply(&p);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        for i in 0..n {
            z[i] = r[i] / diagonal[i];
        }
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
        report.iterations += 1;
        report.residual = dot(&r, &r).sqrt() / b_norm;
    }
    report.converged = report.residual <= options.tolerance;
    let out = (0..n)
        .map(|i| if fixed[i] { field[i] } else { x[i] })
        .collect();
    (out, report)
}

/// Sequential dot product (a fixed summation order).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
