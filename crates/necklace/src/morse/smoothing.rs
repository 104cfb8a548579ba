//! Implicit heat steps `(M + τL) F' = M F` with Dirichlet values (paper sec. 4.2).
//!
//! Fixed vertices keep their values; the free ones solve the reduced system
//! `(M + τL)_ff F'_f = M_f F_f − τ L_fd F_d`, of which `L_ff` is assembled once
//! ([`HeatSolver::new`]; `M + τL` is applied from it and the diagonal `M_f`, never
//! stored) and which is solved every step ([`HeatSolver::step`]) by conjugate
//! gradients, warm-started from the current field, with one of two preconditioners ([`Preconditioner`]): the
//! diagonal (Jacobi), or a smoothed-aggregation multigrid V-cycle
//! ([`multigrid`](super::multigrid), built once for all `τ`); by default the second
//! from [`MULTIGRID_MIN_UNKNOWNS`] to [`MULTIGRID_MAX_UNKNOWNS`] unknowns, the first
//! outside. The reduced matrix is symmetric positive definite (mass > 0 on every vertex
//! of a tet). Matrix-vector products run rows in parallel; dot products sum fixed-size
//! chunks in a fixed order, so the result does not depend on the thread count.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::laplacian::{chunked_dot as dot, row_products, LinearOperator, SparseMatrix, CHUNK};
use super::multigrid::{Hierarchy, HierarchyInfo, Workspace};

/// The preconditioner of the conjugate-gradient solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preconditioner {
    /// Multigrid from [`MULTIGRID_MIN_UNKNOWNS`] to [`MULTIGRID_MAX_UNKNOWNS`] unknowns,
    /// Jacobi outside (default). The two give the same field to the solve's tolerance;
    /// which one ran is in the result ([`HeatSolver::multigrid`]).
    #[default]
    Auto,
    /// The diagonal: one pass over the matrix per iteration. With the projected warm
    /// start it needs 20–210 iterations per level on the shared models, and its count
    /// grows little with the mesh, since the scale space's first `τ` shrink with `h`.
    Jacobi,
    /// One smoothed-aggregation V-cycle per iteration ([`multigrid`](super::multigrid)):
    /// 5–8× fewer iterations than Jacobi, each about 4–5× the cost, plus a setup and
    /// more memory. It loses on small meshes (os_cow's 82 k and 124 k unknowns,
    /// tm_featuretype) and gains on meshes of several hundred thousand unknowns
    /// (`docs/decisions.md`, Smoothing and solver).
    Multigrid,
}

/// The unknowns from which [`Preconditioner::Auto`] takes multigrid: below, its setup
/// and dearer iterations cost more than its fewer iterations save.
pub const MULTIGRID_MIN_UNKNOWNS: usize = 300_000;

/// The unknowns from which [`Preconditioner::Auto`] keeps Jacobi again: the hierarchy
/// takes about 130 bytes an unknown beside the side's analysis, and the largest real
/// models (tm_cycloidal.ply's inside, 1.10 M unknowns) would pass 2 GB with it.
pub const MULTIGRID_MAX_UNKNOWNS: usize = 1_000_000;

impl Preconditioner {
    /// Whether a solve of `unknowns` unknowns uses the multigrid V-cycle.
    pub fn multigrid_for(self, unknowns: usize) -> bool {
        match self {
            Preconditioner::Auto => {
                (MULTIGRID_MIN_UNKNOWNS..MULTIGRID_MAX_UNKNOWNS).contains(&unknowns)
            }
            Preconditioner::Jacobi => false,
            Preconditioner::Multigrid => true,
        }
    }
}

/// Stopping rule and warm start of the conjugate-gradient solve.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverOptions {
    /// Relative residual `|r| / |b|` at which to stop (default 1e-10).
    pub tolerance: f64,
    /// Iteration cap (default 2000).
    pub max_iterations: usize,
    /// Solutions kept for the initial guess, at least 1 (default `None`: six; the
    /// Morse stage's paper schedule takes three, as its first runs did, so that it
    /// reproduces them: the choice moves saddles near its persistence threshold).
    pub history: Option<usize>,
    /// The preconditioner (default [`Preconditioner::Auto`]).
    pub preconditioner: Preconditioner,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            tolerance: 1e-10,
            max_iterations: 2000,
            history: None,
            preconditioner: Preconditioner::Auto,
        }
    }
}

/// `a · (M x + τ L x)` with `M` the diagonal `mass` and `l_x = L x`, summed over
/// fixed chunks in a fixed order like [`dot`] (thread-count independent).
fn energy_dot(a: &[f64], x: &[f64], l_x: &[f64], mass: &[f64], tau: f64) -> f64 {
    let partial: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(x.par_chunks(CHUNK))
        .zip(l_x.par_chunks(CHUNK))
        .zip(mass.par_chunks(CHUNK))
        .map(|(((a, x), l_x), mass)| {
            a.iter()
                .zip(x)
                .zip(l_x)
                .zip(mass)
                .map(|(((a, x), l), m)| a * (m * x + tau * l))
                .sum()
        })
        .collect();
    partial.iter().sum()
}

/// What one implicit step did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// CG iterations.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Whether the tolerance was reached.
    pub converged: bool,
}

/// The reduced heat-step system of one mesh, boundary values and time step.
#[derive(Debug, Clone)]
pub struct HeatSolver {
    /// Global index of each free (unknown) vertex.
    free: Vec<u32>,
    /// `L_ff` in free indices, with an entry on every row's diagonal (at
    /// `diagonal_index`): `(M + τL)_ff` is applied from it and `M_f` ([`HeatMatrix`]),
    /// never assembled, as its values would be the side's largest array again.
    stiffness: SparseMatrix,
    diagonal_index: Vec<usize>,
    /// `L_fd F_d` (without `τ`).
    boundary_stiffness: Vec<f64>,
    tau: f64,
    /// `1 / diag(M + τL)_ff`.
    inverse_diagonal: Vec<f64>,
    /// `M_f`.
    mass: Vec<f64>,
    /// `τ L_fd F_d`.
    boundary: Vec<f64>,
    options: SolverOptions,
    /// The last few solutions `x` and their stiffness products `L_ff x`, newest last:
    /// the space the next initial guess is taken from. With `M_f` they give `A x` for
    /// any `τ` without a pass over the matrix.
    history: Vec<(Vec<f64>, Vec<f64>)>,
    /// The multigrid hierarchy, when the preconditioner is multigrid.
    multigrid: Option<Hierarchy>,
}

/// Solutions kept for the initial guess. On the scale space (32 solves with growing
/// `τ`) six instead of three cut the CG iterations by 28–33 % (boot: 3892 → 2805
/// inside, 2337 → 1564 outside); more than about eight gain nothing, as the stored
/// solutions become nearly dependent.
const HISTORY: usize = 6;

impl HeatSolver {
    /// Assemble the reduced system. `stiffness` is `L` (positive semidefinite), `mass`
    /// the lumped mass, `fixed[v]` marks Dirichlet vertices whose values are taken from
    /// `boundary_values`.
    pub fn new(
        stiffness: &SparseMatrix,
        mass: &[f64],
        fixed: &[bool],
        boundary_values: &[f64],
        tau: f64,
        options: SolverOptions,
    ) -> HeatSolver {
        let n = stiffness.n;
        let free: Vec<u32> = (0..n as u32).filter(|&v| !fixed[v as usize]).collect();
        let mut local = vec![u32::MAX; n];
        for (i, &v) in free.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        // The free rows' free entries, and a diagonal where a row has none: reserved
        // once at that length, as the matrix is the run's largest array.
        let entries: usize = free
            .iter()
            .map(|&v| {
                let row = || stiffness.row(v as usize).map(|(c, _)| c);
                row().filter(|&c| local[c as usize] != u32::MAX).count()
                    + usize::from(!row().any(|c| c == v))
            })
            .sum();
        let mut row_start = Vec::with_capacity(free.len() + 1);
        row_start.push(0usize);
        let mut cols = Vec::with_capacity(entries);
        let mut stiffness_values = Vec::with_capacity(entries);
        let mut diagonal_index = vec![usize::MAX; free.len()];
        let mut boundary_stiffness = Vec::with_capacity(free.len());
        for (i, &v) in free.iter().enumerate() {
            let mut from_fixed = 0.0;
            for (c, x) in stiffness.row(v as usize) {
                let l = local[c as usize];
                if l == u32::MAX {
                    from_fixed += x * boundary_values[c as usize];
                } else {
                    if c == v {
                        diagonal_index[i] = cols.len();
                    }
                    cols.push(l);
                    stiffness_values.push(x);
                }
            }
            if diagonal_index[i] == usize::MAX {
                // A free vertex with no stiffness entry of its own: keep its mass.
                diagonal_index[i] = cols.len();
                cols.push(i as u32);
                stiffness_values.push(0.0);
            }
            boundary_stiffness.push(from_fixed);
            row_start.push(cols.len());
        }
        let n = free.len();
        let mass = free.iter().map(|&v| mass[v as usize]).collect();
        let mut solver = HeatSolver {
            free,
            stiffness: SparseMatrix {
                n,
                row_start,
                cols,
                vals: stiffness_values,
            },
            diagonal_index,
            boundary_stiffness,
            tau: 0.0,
            inverse_diagonal: Vec::new(),
            mass,
            boundary: Vec::new(),
            options,
            history: Vec::new(),
            multigrid: None,
        };
        if options.preconditioner.multigrid_for(n) {
            solver.multigrid = Hierarchy::new(
                &solver.stiffness,
                &solver.stiffness.vals,
                &solver.diagonal_index,
                &solver.mass,
            );
        }
        solver.set_tau(tau);
        solver
    }

    /// The multigrid levels' sizes, when the solve uses multigrid.
    pub fn multigrid(&self) -> Option<&HierarchyInfo> {
        self.multigrid.as_ref().map(Hierarchy::info)
    }

    /// The time step `τ` of the next steps.
    pub fn tau(&self) -> f64 {
        self.tau
    }

    /// Change the time step: the diagonal of `(M + τL)_ff` and `τ L_fd F_d` are rebuilt
    /// from the stored parts (no assembly), and so are the multigrid levels' matrices.
    /// The stored solutions need nothing: their products with the new matrix are
    /// `M_f x + τ L_ff x`.
    pub fn set_tau(&mut self, tau: f64) {
        if tau == self.tau && !self.inverse_diagonal.is_empty() {
            return;
        }
        self.tau = tau;
        let stiffness = &self.stiffness.vals;
        self.inverse_diagonal = (self.diagonal_index.iter().zip(&self.mass))
            .map(|(&d, m)| 1.0 / (tau * stiffness[d] + m))
            .collect();
        self.boundary = self.boundary_stiffness.iter().map(|x| tau * x).collect();
        if let Some(multigrid) = &mut self.multigrid {
            multigrid.set_tau(tau);
        }
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.free.len()
    }

    /// `(M + τL)_ff` at the current `τ`.
    fn operator(&self) -> HeatMatrix<'_> {
        HeatMatrix {
            stiffness: &self.stiffness,
            mass: &self.mass,
            tau: self.tau,
        }
    }

    /// One step: `field` (every vertex) → the new field (fixed vertices unchanged).
    /// The initial guess is the best combination (in the energy norm) of the current
    /// field and the last few solutions: along a heat flow they span most of the next
    /// one, which saves iterations.
    pub fn step(&mut self, field: &[f64]) -> (Vec<f64>, StepReport) {
        let f: Vec<f64> = self.free.iter().map(|&v| field[v as usize]).collect();
        let b: Vec<f64> = (0..f.len())
            .map(|i| self.mass[i] * f[i] - self.boundary[i])
            .collect();
        let guess = self.initial_guess(&b, f);
        let (x, report) = self.solve(&b, guess);
        let mut out = field.to_vec();
        for (&v, &value) in self.free.iter().zip(&x) {
            out[v as usize] = value;
        }
        let kept = self.options.history.unwrap_or(HISTORY).max(1);
        while self.history.len() >= kept {
            self.history.remove(0);
        }
        // `L_ff x` once, in the matrix's pattern: every later `τ` reuses it.
        let mut stiffness_x = vec![0.0; x.len()];
        self.stiffness.mul_vec_into(&x, &mut stiffness_x);
        self.history.push((x, stiffness_x));
        (out, report)
    }

    /// Galerkin projection of `A x = b` onto the span of the stored solutions, with
    /// `A x_i = M_f x_i + τ L_ff x_i` from their stored stiffness products; `fallback`
    /// when there is no history or the small system is singular.
    fn initial_guess(&self, b: &[f64], fallback: Vec<f64>) -> Vec<f64> {
        let k = self.history.len();
        if k == 0 {
            return fallback;
        }
        // G_ij = x_i · A x_j (symmetrised), r_i = x_i · b.
        let (mass, tau) = (&self.mass, self.tau);
        let products = DMatrix::from_fn(k, k, |i, j| {
            let ((xi, _), (xj, lxj)) = (&self.history[i], &self.history[j]);
            energy_dot(xi, xj, lxj, mass, tau)
        });
        let g = DMatrix::from_fn(k, k, |i, j| 0.5 * (products[(i, j)] + products[(j, i)]));
        let r = DVector::from_fn(k, |i, _| dot(&self.history[i].0, b));
        let scale = g.diagonal().amax();
        let Some(y) = g
            .lu()
            .solve(&r)
            .filter(|y| y.iter().all(|v| v.is_finite()) && scale > 0.0)
        else {
            return fallback;
        };
        let mut x = vec![0.0; b.len()];
        for (i, (xi, _)) in self.history.iter().enumerate() {
            x.par_iter_mut().zip(xi).for_each(|(x, xi)| *x += y[i] * xi);
        }
        x
    }

    /// Preconditioned CG from `x`: Jacobi, or one multigrid V-cycle per iteration when
    /// there is a hierarchy. With Jacobi each iteration makes three passes over the
    /// vectors: `q = A p` with `p · q`; the updates of `x`, `r`, `z` with `r · z` and
    /// `r · r`; and `p = z + β p`. Sums are taken over fixed chunks in a fixed order.
    fn solve(&self, b: &[f64], mut x: Vec<f64>) -> (Vec<f64>, StepReport) {
        let n = b.len();
        let tolerance = self.options.tolerance;
        let mut q = vec![0.0; n];
        self.operator().apply_into(&x, &mut q);
        let mut r: Vec<f64> = (0..n).map(|i| b[i] - q[i]).collect();
        let b_norm = dot(b, b).sqrt().max(f64::MIN_POSITIVE);
        let mut work = Workspace::default();
        let mut z = vec![0.0; n];
        self.precondition(&r, &mut z, &mut work);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        let mut report = StepReport {
            iterations: 0,
            residual: dot(&r, &r).sqrt() / b_norm,
            converged: false,
        };
        while report.residual > tolerance && report.iterations < self.options.max_iterations {
            let pq = self.mul_vec_dot(&p, &mut q);
            if pq <= 0.0 || !pq.is_finite() {
                break;
            }
            let alpha = rz / pq;
            let (rz_next, rr) = match &self.multigrid {
                None => self.jacobi_update(&mut x, &mut r, &mut z, &p, &q, alpha),
                Some(multigrid) => {
                    let rr = update(&mut x, &mut r, &p, &q, alpha);
                    if rr.sqrt() / b_norm <= tolerance {
                        // Converged: no cycle for a direction that is not taken.
                        (rz, rr)
                    } else {
                        multigrid.apply(
                            &self.operator(),
                            &self.inverse_diagonal,
                            &r,
                            &mut z,
                            &mut work,
                        );
                        (dot(&r, &z), rr)
                    }
                }
            };
            report.iterations += 1;
            report.residual = rr.sqrt() / b_norm;
            if report.residual <= tolerance || !(rz_next > 0.0 && rz_next.is_finite()) {
                break;
            }
            let beta = rz_next / rz;
            rz = rz_next;
            p.par_chunks_mut(CHUNK)
                .zip(z.par_chunks(CHUNK))
                .for_each(|(p, z)| {
                    for (p, z) in p.iter_mut().zip(z) {
                        *p = z + beta * *p;
                    }
                });
        }
        report.converged = report.residual <= tolerance;
        (x, report)
    }

    /// `z = B r`: the V-cycle, or the diagonal.
    fn precondition(&self, r: &[f64], z: &mut [f64], work: &mut Workspace) {
        let d = &self.inverse_diagonal;
        match &self.multigrid {
            Some(multigrid) => multigrid.apply(&self.operator(), d, r, z, work),
            None => z
                .par_iter_mut()
                .zip(r)
                .zip(d)
                .for_each(|((z, r), d)| *z = r * d),
        }
    }

    /// Jacobi's fused pass: `x += α p`, `r −= α q`, `z = D⁻¹ r`; returns `(r · z, r · r)`.
    fn jacobi_update(
        &self,
        x: &mut [f64],
        r: &mut [f64],
        z: &mut [f64],
        p: &[f64],
        q: &[f64],
        alpha: f64,
    ) -> (f64, f64) {
        let d = &self.inverse_diagonal;
        let sums: Vec<(f64, f64)> = x
            .par_chunks_mut(CHUNK)
            .zip(r.par_chunks_mut(CHUNK))
            .zip(z.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((xc, rc), zc))| {
                let start = c * CHUNK;
                let (mut rz, mut rr) = (0.0, 0.0);
                for k in 0..xc.len() {
                    let i = start + k;
                    xc[k] += alpha * p[i];
                    rc[k] -= alpha * q[i];
                    zc[k] = rc[k] * d[i];
                    rz += rc[k] * zc[k];
                    rr += rc[k] * rc[k];
                }
                (rz, rr)
            })
            .collect();
        (
            sums.iter().map(|s| s.0).sum(),
            sums.iter().map(|s| s.1).sum(),
        )
    }

    /// `q = A p = M_f p + τ L_ff p`, returning `p · q` (chunked, fixed order).
    fn mul_vec_dot(&self, p: &[f64], q: &mut [f64]) -> f64 {
        let (m, mass, tau) = (&self.stiffness, &self.mass, self.tau);
        let partial: Vec<f64> = q
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, qc)| {
                let start = c * CHUNK;
                let mut sum = 0.0;
                for (k, qi) in qc.iter_mut().enumerate() {
                    let i = start + k;
                    let range = m.row_start[i]..m.row_start[i + 1];
                    let lp: f64 = m.cols[range.clone()]
                        .iter()
                        .zip(&m.vals[range])
                        .map(|(&c, &v)| v * p[c as usize])
                        .sum();
                    *qi = tau * lp + mass[i] * p[i];
                    sum += p[i] * *qi;
                }
                sum
            })
            .collect();
        partial.iter().sum()
    }
}

/// `(M + τL)_ff` applied as `M_f x + τ (L_ff x)` from the solver's parts.
struct HeatMatrix<'a> {
    stiffness: &'a SparseMatrix,
    mass: &'a [f64],
    tau: f64,
}

impl LinearOperator for HeatMatrix<'_> {
    fn size(&self) -> usize {
        self.stiffness.n
    }

    fn apply_into(&self, x: &[f64], y: &mut [f64]) {
        let m = self.stiffness;
        row_products(&m.row_start, &m.cols, &m.vals, x, y, |i, yi, lx| {
            *yi = self.tau * lx + self.mass[i] * x[i]
        });
    }
}

/// `x += α p`, `r −= α q`; returns `r · r` (chunked, fixed order).
fn update(x: &mut [f64], r: &mut [f64], p: &[f64], q: &[f64], alpha: f64) -> f64 {
    let sums: Vec<f64> = x
        .par_chunks_mut(CHUNK)
        .zip(r.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (xc, rc))| {
            let start = c * CHUNK;
            let mut rr = 0.0;
            for k in 0..xc.len() {
                let i = start + k;
                xc[k] += alpha * p[i];
                rc[k] -= alpha * q[i];
                rr += rc[k] * rc[k];
            }
            rr
        })
        .collect();
    sums.iter().sum()
}

/// One implicit Euler step of the heat equation: returns the new field (fixed vertices
/// unchanged) and the solver's report. `stiffness` is `L` (positive semidefinite),
/// `mass` the lumped mass, `fixed[v]` marks Dirichlet vertices (values from `field`).
/// For many steps on one mesh, build a [`HeatSolver`] once.
pub fn implicit_step(
    stiffness: &SparseMatrix,
    mass: &[f64],
    fixed: &[bool],
    field: &[f64],
    tau: f64,
    options: &SolverOptions,
) -> (Vec<f64>, StepReport) {
    HeatSolver::new(stiffness, mass, fixed, field, tau, *options).step(field)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Laplacian of a path of `n` vertices (unit weights) and a mass that varies.
    fn path(n: usize) -> (SparseMatrix, Vec<f64>) {
        let mut triplets = Vec::new();
        for i in 0..n - 1 {
            let (a, b) = (i as u32, i as u32 + 1);
            triplets.extend([(a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)]);
        }
        let mass = (0..n).map(|i| 1.0 + 0.5 * (i as f64 * 0.7).sin()).collect();
        (SparseMatrix::from_triplets(n, triplets), mass)
    }

    #[test]
    fn the_warm_start_is_the_galerkin_projection_with_the_new_matrix() {
        let n = 60;
        let (stiffness, mass) = path(n);
        let fixed: Vec<bool> = (0..n).map(|i| i == 0 || i == n - 1).collect();
        let field: Vec<f64> = (0..n).map(|i| (i as f64 * 0.31).cos().abs()).collect();
        let mut solver = HeatSolver::new(
            &stiffness,
            &mass,
            &fixed,
            &field,
            0.3,
            SolverOptions::default(),
        );
        let mut f = field;
        for tau in [0.3, 0.7, 1.6, 2.9] {
            solver.set_tau(tau);
            f = solver.step(&f).0;
        }
        solver.set_tau(5.0);
        // Each stored stiffness product is L_ff x.
        let l_ff = |x: &[f64]| solver.stiffness.mul_vec(x);
        for (x, lx) in &solver.history {
            assert_eq!(&l_ff(x), lx);
        }
        // The guess is the projection computed with products by the new matrix itself.
        let free = solver.unknowns();
        let b: Vec<f64> = (0..free)
            .map(|i| solver.mass[i] * f[solver.free[i] as usize])
            .collect();
        let guess = solver.initial_guess(&b, vec![0.0; free]);
        let k = solver.history.len();
        // (M + 5 L)_ff assembled here from the path's own matrix (free: 1..n-1).
        let a_ff = DMatrix::from_fn(free, free, |i, j| {
            5.0 * stiffness.get(i + 1, j + 1) + if i == j { mass[i + 1] } else { 0.0 }
        });
        let ax: Vec<Vec<f64>> = solver
            .history
            .iter()
            .map(|(x, _)| (&a_ff * DVector::from_column_slice(x)).as_slice().to_vec())
            .collect();
        let g = DMatrix::from_fn(k, k, |i, j| dot(&solver.history[i].0, &ax[j]));
        let r = DVector::from_fn(k, |i, _| dot(&solver.history[i].0, &b));
        let y = g.lu().solve(&r).unwrap();
        let scale = guess.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (row, value) in guess.iter().enumerate() {
            let expected: f64 = (0..k).map(|i| y[i] * solver.history[i].0[row]).sum();
            assert!(
                (value - expected).abs() <= 1e-9 * scale,
                "{row}: {value} {expected}"
            );
        }
    }
}
