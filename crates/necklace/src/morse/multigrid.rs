//! Smoothed-aggregation algebraic multigrid: the heat steps' preconditioner.
//!
//! The heat system `A(τ) = M + τL` (on the free vertices) grows worse conditioned with
//! `τ` and with the mesh's size, so Jacobi-preconditioned CG needs hundreds of iterations
//! on a million unknowns. One V-cycle of this hierarchy costs a few matrix passes, and the
//! iteration count it leaves does not grow with the mesh (Vaněk, Mandel and Brezina,
//! "Algebraic multigrid by smoothed aggregation", 1996; as in pyamg's
//! `smoothed_aggregation_solver`).
//!
//! **Setup** ([`Hierarchy::new`], once per mesh; nothing in it depends on `τ`):
//! 1. aggregate the unknowns along `L`'s graph, greedily in index order: a vertex whose
//!    neighbours are all free starts an aggregate with them; the rest join a neighbour's
//!    aggregate, or start their own;
//! 2. prolong by the tentative operator `T` (1 from a vertex's aggregate: constants are
//!    `L`'s near null space), smoothed once: `P = (I − ω D_L⁻¹ L) T` with
//!    `ω = 4 / (3 ρ(D_L⁻¹ L))`;
//! 3. keep the coarse operators `Pᵀ L P` and `Pᵀ M P` apart, on one pattern, so that the
//!    Galerkin coarse matrix of every `τ` is `Pᵀ M P + τ Pᵀ L P`;
//! 4. repeat on the coarse pair until at most [`COARSEST`] unknowns remain.
//!
//! **Per `τ`** ([`Hierarchy::set_tau`]): each coarse level's values and diagonal, and the
//! coarsest level's dense Cholesky factor. The Jacobi damping needs `ρ(D_A⁻¹ A)`; since
//! `xᵀ(M + τL)x / xᵀ(D_M + τD_L)x` lies between the two quotients, it is at most
//! `max(ρ(D_M⁻¹ M), ρ(D_L⁻¹ L))`, both estimated once at setup.
//!
//! **Apply** ([`Hierarchy::apply`]): one V-cycle from zero with [`SWEEPS`] damped Jacobi
//! sweeps before and after the coarse correction: a symmetric positive definite
//! preconditioner for CG. The finest level's operator is the caller's (not copied, and
//! not necessarily assembled: the heat solver applies `M + τL` from `L` and `M`).
//!
//! **Memory** (about 130 bytes an unknown on a million): the setup borrows the finest
//! level's pattern and `L`, and reads its lumped `M` on the diagonal; the transfers are
//! built in double precision and kept in single (`Transfer::rounded`); the finest
//! level keeps only a scratch vector for the cycle.
//!
//! Every product runs rows in parallel, each row summed in a fixed order, and every dot
//! product over fixed chunks: the result does not depend on the thread count.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::laplacian::{chunked_dot as dot, row_products, LinearOperator, SparseMatrix};

/// Levels stop coarsening at this many unknowns; the coarsest is solved exactly.
pub const COARSEST: usize = 400;

/// Damped Jacobi sweeps before and after each coarse correction.
pub const SWEEPS: usize = 1;

/// At most this many levels (the finest included).
const MAX_LEVELS: usize = 12;

/// Power iterations of the spectral-radius estimates.
const POWER_ITERATIONS: usize = 20;

/// The estimates are Rayleigh quotients (from below): widened by this factor.
const RADIUS_MARGIN: f64 = 1.1;

/// A coarse level whose size falls by less than this factor ends the hierarchy
/// (aggregation has stalled: the smoother alone does as well there).
const MIN_COARSENING: f64 = 1.5;

/// A rectangular sparse matrix in compressed rows (the transfers `P` and `Pᵀ`). The
/// setup builds them in double precision (the coarse operators are `Pᵀ X P` of
/// those); the hierarchy keeps them in single precision ([`Transfer::rounded`]): a
/// transfer only shapes the preconditioner, which stays symmetric (`Pᵀ` holds the
/// same rounded values as `P`), and the finest level's two transfers are the
/// hierarchy's largest arrays.
#[derive(Debug, Clone)]
struct Transfer<V = f32> {
    columns: usize,
    row_start: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<V>,
}

impl Transfer<f64> {
    /// The same matrix with its values rounded to single precision.
    fn rounded(self) -> Transfer {
        Transfer {
            columns: self.columns,
            row_start: self.row_start,
            cols: self.cols,
            vals: self.vals.iter().map(|&x| x as f32).collect(),
        }
    }
}

impl<V: Copy + Default + Into<f64> + Sync> Transfer<V> {
    fn rows(&self) -> usize {
        self.row_start.len() - 1
    }

    /// `y = self · x`, rows in parallel.
    fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        row_products(&self.row_start, &self.cols, &self.vals, x, y, |_, yi, s| {
            *yi = s
        });
    }

    /// `y += self · x`, rows in parallel.
    fn mul_add_into(&self, x: &[f64], y: &mut [f64]) {
        row_products(&self.row_start, &self.cols, &self.vals, x, y, |_, yi, s| {
            *yi += s
        });
    }

    /// The transpose, rows in increasing column order (deterministic).
    fn transpose(&self) -> Transfer<V> {
        let mut count = vec![0usize; self.columns + 1];
        for &c in &self.cols {
            count[c as usize + 1] += 1;
        }
        for i in 0..self.columns {
            count[i + 1] += count[i];
        }
        let row_start = count.clone();
        let mut next = count;
        let mut cols = vec![0u32; self.cols.len()];
        let mut vals = vec![V::default(); self.vals.len()];
        for i in 0..self.rows() {
            for k in self.row_start[i]..self.row_start[i + 1] {
                let c = self.cols[k] as usize;
                cols[next[c]] = i as u32;
                vals[next[c]] = self.vals[k];
                next[c] += 1;
            }
        }
        Transfer {
            columns: self.rows(),
            row_start,
            cols,
            vals,
        }
    }
}

/// A level's `L` and `M` on one pattern, borrowed: the finest level's from the
/// caller's reduced system (its lumped mass on the diagonal, so that the setup copies
/// none of the run's largest matrix), a coarse level's from its [`Operator`].
#[derive(Clone, Copy)]
struct Pair<'a> {
    n: usize,
    row_start: &'a [usize],
    cols: &'a [u32],
    stiffness: &'a [f64],
    mass: Mass<'a>,
    diagonal_index: &'a [usize],
}

/// The mass of a [`Pair`].
#[derive(Clone, Copy)]
enum Mass<'a> {
    /// One value per row, on the diagonal (the finest level's lumped mass).
    Lumped(&'a [f64]),
    /// One value per entry of the pattern (a coarse level's `Pᵀ M P`).
    Entries(&'a [f64]),
}

impl Pair<'_> {
    /// The mass at entry `k`, of row `row`.
    fn mass_at(&self, row: usize, k: usize) -> f64 {
        match self.mass {
            Mass::Lumped(mass) if k == self.diagonal_index[row] => mass[row],
            Mass::Lumped(_) => 0.0,
            Mass::Entries(mass) => mass[k],
        }
    }
}

/// A coarse level's operator pair on one pattern: `L` and `M` values, and `M + τL`
/// for the current `τ`.
#[derive(Debug, Clone)]
struct Operator {
    /// Pattern, with `M + τL` as its values.
    matrix: SparseMatrix,
    stiffness: Vec<f64>,
    mass: Vec<f64>,
    diagonal_index: Vec<usize>,
}

impl Operator {
    fn pair(&self) -> Pair<'_> {
        Pair {
            n: self.matrix.n,
            row_start: &self.matrix.row_start,
            cols: &self.matrix.cols,
            stiffness: &self.stiffness,
            mass: Mass::Entries(&self.mass),
            diagonal_index: &self.diagonal_index,
        }
    }

    fn set_tau(&mut self, tau: f64) -> Vec<f64> {
        self.matrix.vals = self
            .mass
            .iter()
            .zip(&self.stiffness)
            .map(|(m, l)| m + tau * l)
            .collect();
        self.diagonal_index
            .iter()
            .map(|&d| inverse(self.matrix.vals[d]))
            .collect()
    }
}

/// One coarse level: its operators, the Jacobi weight, and its transfer to the next.
#[derive(Debug, Clone)]
struct Level {
    operator: Operator,
    inverse_diagonal: Vec<f64>,
    /// `ω / ρ`: the damping of its Jacobi sweeps.
    weight: f64,
}

/// The transfers between level `k` and `k + 1`.
#[derive(Debug, Clone)]
struct Transfers {
    prolong: Transfer,
    restrict: Transfer,
}

/// What the setup built, for the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HierarchyInfo {
    /// Unknowns per level, finest first.
    pub sizes: Vec<usize>,
    /// Stored entries per level's matrix, finest first.
    pub entries: Vec<usize>,
    /// Stored entries of each prolongation, finest first.
    pub transfer_entries: Vec<usize>,
}

/// The multigrid hierarchy of one heat system (see the module doc).
#[derive(Debug, Clone)]
pub struct Hierarchy {
    /// Jacobi damping on the finest level.
    fine_weight: f64,
    /// `transfers[k]` goes between level `k` and `k + 1` (level 0 the finest).
    transfers: Vec<Transfers>,
    /// Levels 1, 2, …; the last is the coarsest.
    levels: Vec<Level>,
    /// The coarsest level's factor for the current `τ` (`None`: not positive definite
    /// in floating point; then Jacobi sweeps stand in).
    factor: Option<Cholesky<f64, Dyn>>,
    info: HierarchyInfo,
}

impl Hierarchy {
    /// Build the hierarchy of `M + τL` on `pattern` (the finest matrix's pattern, with a
    /// diagonal entry in every row), `stiffness` = `L`'s values in that pattern, `mass`
    /// = the lumped (diagonal) `M`. `None` when the system is already at most
    /// [`COARSEST`] unknowns or does not coarsen.
    pub fn new(
        pattern: &SparseMatrix,
        stiffness: &[f64],
        diagonal_index: &[usize],
        mass: &[f64],
    ) -> Option<Hierarchy> {
        let fine = Pair {
            n: pattern.n,
            row_start: &pattern.row_start,
            cols: &pattern.cols,
            stiffness,
            mass: Mass::Lumped(mass),
            diagonal_index,
        };
        let (fine_stiffness, fine_mass) = spectral_radii(fine);
        let fine_weight = smoothing_weight(fine_stiffness, fine_mass);
        let mut info = HierarchyInfo {
            sizes: vec![pattern.n],
            entries: vec![pattern.cols.len()],
            transfer_entries: Vec::new(),
        };
        let mut transfers = Vec::new();
        let mut levels: Vec<Level> = Vec::new();
        // `ρ(D_L⁻¹ L)` of the level being coarsened.
        let mut stiffness_radius = fine_stiffness;
        while levels.len() + 1 < MAX_LEVELS {
            let current = levels.last().map_or(fine, |level| level.operator.pair());
            if current.n <= COARSEST {
                break;
            }
            let aggregates = aggregate(current);
            let count = aggregates.iter().filter(|&&a| a != u32::MAX).max();
            let Some(&count) = count else { break };
            let count = count as usize + 1;
            if (count as f64) * MIN_COARSENING > current.n as f64 {
                break;
            }
            let prolong = smoothed_prolongator(current, &aggregates, count, stiffness_radius);
            let restrict = prolong.transpose();
            let coarse = galerkin(current, &prolong, &restrict);
            info.sizes.push(coarse.matrix.n);
            info.entries.push(coarse.matrix.cols.len());
            info.transfer_entries.push(prolong.cols.len());
            let (stiffness, mass) = spectral_radii(coarse.pair());
            stiffness_radius = stiffness;
            transfers.push(Transfers {
                prolong: prolong.rounded(),
                restrict: restrict.rounded(),
            });
            levels.push(Level {
                operator: coarse,
                inverse_diagonal: Vec::new(),
                weight: smoothing_weight(stiffness, mass),
            });
        }
        if levels.is_empty() {
            return None;
        }
        Some(Hierarchy {
            fine_weight,
            transfers,
            levels,
            factor: None,
            info,
        })
    }

    /// Sizes of the levels (for the report).
    pub fn info(&self) -> &HierarchyInfo {
        &self.info
    }

    /// Set the coarse levels' matrices to `M + τL` and factor the coarsest.
    pub fn set_tau(&mut self, tau: f64) {
        for level in &mut self.levels {
            level.inverse_diagonal = level.operator.set_tau(tau);
        }
        let last = self.levels.last().expect("at least one coarse level");
        let m = &last.operator.matrix;
        let mut dense = DMatrix::zeros(m.n, m.n);
        for i in 0..m.n {
            for (j, x) in m.row(i) {
                dense[(i, j as usize)] = x;
            }
        }
        self.factor = dense.cholesky();
    }

    /// `z = B r`: one V-cycle from zero. `fine` is the finest level's current operator
    /// and `fine_inverse_diagonal` its inverse diagonal; `work` holds the cycle's
    /// vectors between calls (no allocation per cycle).
    pub fn apply(
        &self,
        fine: &dyn LinearOperator,
        fine_inverse_diagonal: &[f64],
        r: &[f64],
        z: &mut [f64],
        work: &mut Workspace,
    ) {
        if work.levels.len() != self.levels.len() + 1 {
            // The finest level's right-hand side and solution are the caller's: only
            // its scratch vector is needed.
            work.levels = std::iter::once((Vec::new(), Vec::new(), vec![0.0; fine.size()]))
                .chain(self.levels.iter().map(|l| {
                    let n = l.operator.matrix.n;
                    (vec![0.0; n], vec![0.0; n], vec![0.0; n])
                }))
                .collect();
        }
        self.cycle(
            0,
            fine,
            fine_inverse_diagonal,
            self.fine_weight,
            r,
            z,
            &mut work.levels,
        );
    }

    /// One V-cycle on level `k` for `a z = r`; `work[0]` is this level's scratch,
    /// `work[1..]` the coarser levels' (right-hand side, solution, scratch).
    #[allow(clippy::too_many_arguments)]
    fn cycle(
        &self,
        k: usize,
        a: &dyn LinearOperator,
        inverse_diagonal: &[f64],
        weight: f64,
        r: &[f64],
        z: &mut [f64],
        work: &mut [(Vec<f64>, Vec<f64>, Vec<f64>)],
    ) {
        let (here, coarser) = work.split_first_mut().expect("a workspace per level");
        let scratch = &mut here.2;
        if k == self.levels.len() {
            match &self.factor {
                Some(factor) => {
                    let x = factor.solve(&DVector::from_column_slice(r));
                    z.copy_from_slice(x.as_slice());
                }
                None => {
                    jacobi_from_zero(inverse_diagonal, weight, r, z);
                    jacobi_sweeps(a, inverse_diagonal, weight, r, z, scratch, 2 * SWEEPS - 1);
                }
            }
            return;
        }
        // Pre-smoothing, from zero.
        jacobi_from_zero(inverse_diagonal, weight, r, z);
        jacobi_sweeps(a, inverse_diagonal, weight, r, z, scratch, SWEEPS - 1);
        // Coarse correction: restrict the residual, cycle, prolong.
        a.apply_into(z, scratch);
        scratch.par_iter_mut().zip(r).for_each(|(q, r)| *q = r - *q);
        let transfer = &self.transfers[k];
        let next = &self.levels[k];
        {
            let (coarse_r, coarse_z, _) = &mut coarser[0];
            transfer.restrict.mul_into(scratch, coarse_r);
            let coarse_r = std::mem::take(coarse_r);
            let mut coarse_z_owned = std::mem::take(coarse_z);
            self.cycle(
                k + 1,
                &next.operator.matrix,
                &next.inverse_diagonal,
                next.weight,
                &coarse_r,
                &mut coarse_z_owned,
                coarser,
            );
            transfer.prolong.mul_add_into(&coarse_z_owned, z);
            coarser[0].0 = coarse_r;
            coarser[0].1 = coarse_z_owned;
        }
        // Post-smoothing.
        jacobi_sweeps(a, inverse_diagonal, weight, r, z, scratch, SWEEPS);
    }
}

/// The vectors of a V-cycle, kept between cycles: per level a right-hand side, a
/// solution and a scratch vector.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    levels: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)>,
}

/// `1 / x`, or 0 where `x` is not positive (a row without coupling is left alone).
fn inverse(x: f64) -> f64 {
    if x > 0.0 {
        1.0 / x
    } else {
        0.0
    }
}

/// The first damped Jacobi sweep for `A z = r` from `z = 0`: `z = ω D⁻¹ r`.
fn jacobi_from_zero(inverse_diagonal: &[f64], weight: f64, r: &[f64], z: &mut [f64]) {
    z.par_iter_mut()
        .zip(r)
        .zip(inverse_diagonal)
        .for_each(|((z, r), d)| *z = weight * d * r);
}

/// `sweeps` damped Jacobi sweeps `z += ω D⁻¹ (r − A z)`.
fn jacobi_sweeps(
    a: &dyn LinearOperator,
    inverse_diagonal: &[f64],
    weight: f64,
    r: &[f64],
    z: &mut [f64],
    scratch: &mut [f64],
    sweeps: usize,
) {
    for _ in 0..sweeps {
        a.apply_into(z, scratch);
        z.par_iter_mut()
            .zip(scratch.par_iter())
            .zip(r)
            .zip(inverse_diagonal)
            .for_each(|(((z, az), r), d)| *z += weight * d * (r - az));
    }
}

/// `ρ(D_L⁻¹ L)` and `ρ(D_M⁻¹ M)` of a level (estimates, see [`spectral_radius`]).
fn spectral_radii(pair: Pair) -> (f64, f64) {
    (
        spectral_radius(pair, |_, k| pair.stiffness[k]),
        spectral_radius(pair, |row, k| pair.mass_at(row, k)),
    )
}

/// `4 / (3 ρ)` with `ρ` a bound of `ρ(D_A⁻¹ A)` for every `τ`: the larger of the two
/// radii (see the module doc), widened by the margin.
fn smoothing_weight(stiffness_radius: f64, mass_radius: f64) -> f64 {
    let rho = (stiffness_radius.max(mass_radius) * RADIUS_MARGIN).max(1.0);
    4.0 / (3.0 * rho)
}

/// Power-iteration estimate of `ρ(D⁻¹ X)` for `X` (symmetric, `value(row, k)` its entry
/// `k` of `pair`'s pattern), through the similar `D^{-1/2} X D^{-1/2}`; rows with no
/// positive diagonal count as 0.
fn spectral_radius(pair: Pair, value: impl Fn(usize, usize) -> f64 + Sync) -> f64 {
    let n = pair.n;
    let scale: Vec<f64> = pair
        .diagonal_index
        .iter()
        .enumerate()
        .map(|(i, &d)| inverse(value(i, d)).sqrt())
        .collect();
    if scale.iter().all(|&s| s == 0.0) {
        return 0.0;
    }
    // A fixed start that is not close to a constant (which is near L's null space).
    let mut v: Vec<f64> = (0..n)
        .map(|i| scale[i].min(1.0) * (1.0 + ((i * 7919) % 101) as f64 / 101.0))
        .collect();
    let mut w = vec![0.0; n];
    let mut estimate = 0.0;
    for _ in 0..POWER_ITERATIONS {
        let norm = dot(&v, &v).sqrt();
        if norm == 0.0 {
            break;
        }
        v.par_iter_mut().for_each(|x| *x /= norm);
        w.par_iter_mut().enumerate().for_each(|(i, wi)| {
            let range = pair.row_start[i]..pair.row_start[i + 1];
            let s: f64 = range
                .map(|k| {
                    let c = pair.cols[k] as usize;
                    value(i, k) * scale[c] * v[c]
                })
                .sum();
            *wi = scale[i] * s;
        });
        estimate = dot(&v, &w);
        std::mem::swap(&mut v, &mut w);
    }
    estimate.abs()
}

/// Greedy aggregation of the level's unknowns along `L`'s graph (see the module doc).
/// `u32::MAX` marks an unknown with no coupling at all (left to the smoother).
fn aggregate(pair: Pair) -> Vec<u32> {
    let (m, l) = (pair, pair.stiffness);
    let n = m.n;
    let neighbours = |i: usize| {
        let range = m.row_start[i]..m.row_start[i + 1];
        m.cols[range.clone()]
            .iter()
            .zip(&l[range])
            .filter(move |&(&c, &x)| c as usize != i && x != 0.0)
            .map(|(&c, _)| c as usize)
    };
    let mut owner = vec![u32::MAX; n];
    let mut count = 0u32;
    // 1. Roots: an unknown whose neighbours are all unaggregated takes them.
    for i in 0..n {
        if owner[i] != u32::MAX || neighbours(i).next().is_none() {
            continue;
        }
        if neighbours(i).all(|j| owner[j] == u32::MAX) {
            owner[i] = count;
            for j in neighbours(i) {
                owner[j] = count;
            }
            count += 1;
        }
    }
    // 2. The rest join the aggregate of their first aggregated neighbour (from pass 1).
    let first = owner.clone();
    for (i, o) in owner.iter_mut().enumerate() {
        if *o == u32::MAX {
            if let Some(j) = neighbours(i).find(|&j| first[j] != u32::MAX) {
                *o = first[j];
            }
        }
    }
    // 3. Any left (their neighbours all unaggregated after pass 2): new aggregates.
    for i in 0..n {
        if owner[i] != u32::MAX || neighbours(i).next().is_none() {
            continue;
        }
        owner[i] = count;
        for j in neighbours(i) {
            if owner[j] == u32::MAX {
                owner[j] = count;
            }
        }
        count += 1;
    }
    owner
}

/// `P = (I − ω D_L⁻¹ L) T`, `T` the aggregates' indicator, `ω = 4 / (3 ρ(D_L⁻¹ L))`.
fn smoothed_prolongator(
    pair: Pair,
    aggregates: &[u32],
    count: usize,
    stiffness_radius: f64,
) -> Transfer<f64> {
    let (m, l) = (pair, pair.stiffness);
    let rho = stiffness_radius * RADIUS_MARGIN;
    let omega = if rho > 0.0 { 4.0 / (3.0 * rho) } else { 0.0 };
    let rows: Vec<Vec<(u32, f64)>> = (0..m.n)
        .into_par_iter()
        .map(|i| {
            let factor = omega * inverse(l[pair.diagonal_index[i]]);
            let mut entries: Vec<(u32, f64)> = Vec::new();
            if aggregates[i] != u32::MAX {
                entries.push((aggregates[i], 1.0));
            }
            for k in m.row_start[i]..m.row_start[i + 1] {
                let a = aggregates[m.cols[k] as usize];
                if a != u32::MAX && l[k] != 0.0 {
                    entries.push((a, -factor * l[k]));
                }
            }
            merge_sorted(entries)
        })
        .collect();
    let (row_start, cols, vals) = flatten(rows);
    Transfer {
        columns: count,
        row_start,
        cols,
        vals,
    }
}

/// Sort by column (stably: equal columns keep their order) and sum equal columns.
fn merge_sorted(mut entries: Vec<(u32, f64)>) -> Vec<(u32, f64)> {
    entries.sort_by_key(|e| e.0);
    let mut row: Vec<(u32, f64)> = Vec::with_capacity(entries.len());
    for (c, x) in entries {
        match row.last_mut() {
            Some(last) if last.0 == c => last.1 += x,
            _ => row.push((c, x)),
        }
    }
    row
}

fn flatten(rows: Vec<Vec<(u32, f64)>>) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
    let mut row_start = Vec::with_capacity(rows.len() + 1);
    row_start.push(0);
    let total = rows.iter().map(Vec::len).sum();
    let mut cols = Vec::with_capacity(total);
    let mut vals = Vec::with_capacity(total);
    for row in rows {
        for (c, x) in row {
            cols.push(c);
            vals.push(x);
        }
        row_start.push(cols.len());
    }
    (row_start, cols, vals)
}

/// The coarse pair `(Pᵀ L P, Pᵀ M P)` on one pattern: `(X P)` row by row, then
/// `Pᵀ (X P)` row by row, each row accumulated densely in the order of its terms.
fn galerkin(fine: Pair, prolong: &Transfer<f64>, restrict: &Transfer<f64>) -> Operator {
    let m = fine;
    let coarse_n = prolong.columns;
    // Y = X P for both values (n × coarse_n).
    let y_rows: Vec<Vec<(u32, f64, f64)>> = (0..m.n)
        .into_par_iter()
        .map_init(
            || Accumulator::new(coarse_n),
            |acc, i| {
                for k in m.row_start[i]..m.row_start[i + 1] {
                    let (xl, xm) = (fine.stiffness[k], fine.mass_at(i, k));
                    let j = m.cols[k] as usize;
                    for q in prolong.row_start[j]..prolong.row_start[j + 1] {
                        let p = prolong.vals[q];
                        acc.add(prolong.cols[q], xl * p, xm * p);
                    }
                }
                acc.take()
            },
        )
        .collect();
    // C = Pᵀ Y.
    let c_rows: Vec<Vec<(u32, f64, f64)>> = (0..coarse_n)
        .into_par_iter()
        .map_init(
            || Accumulator::new(coarse_n),
            |acc, row| {
                for q in restrict.row_start[row]..restrict.row_start[row + 1] {
                    let r = restrict.vals[q];
                    for &(c, yl, ym) in &y_rows[restrict.cols[q] as usize] {
                        acc.add(c, r * yl, r * ym);
                    }
                }
                let mut entries = acc.take();
                if !entries.iter().any(|e| e.0 as usize == row) {
                    // Keep a diagonal entry in every row (an aggregate never empty: P
                    // has its 1s, so this only guards the pattern).
                    entries.push((row as u32, 0.0, 0.0));
                    entries.sort_by_key(|e| e.0);
                }
                entries
            },
        )
        .collect();
    drop(y_rows);
    let mut row_start = Vec::with_capacity(coarse_n + 1);
    row_start.push(0);
    let total = c_rows.iter().map(Vec::len).sum();
    let mut cols = Vec::with_capacity(total);
    let mut stiffness = Vec::with_capacity(total);
    let mut mass = Vec::with_capacity(total);
    let mut diagonal_index = Vec::with_capacity(coarse_n);
    for (row, entries) in c_rows.into_iter().enumerate() {
        for (c, l, m) in entries {
            if c as usize == row {
                diagonal_index.push(cols.len());
            }
            cols.push(c);
            stiffness.push(l);
            mass.push(m);
        }
        row_start.push(cols.len());
    }
    // Exact symmetry (the two triangles are summed in different orders).
    symmetrize(&row_start, &cols, &mut stiffness);
    symmetrize(&row_start, &cols, &mut mass);
    Operator {
        matrix: SparseMatrix {
            n: coarse_n,
            row_start,
            cols,
            vals: Vec::new(),
        },
        stiffness,
        mass,
        diagonal_index,
    }
}

/// Replace `(i, j)` and `(j, i)` by their mean (the pattern is symmetric).
fn symmetrize(row_start: &[usize], cols: &[u32], vals: &mut [f64]) {
    let n = row_start.len() - 1;
    for i in 0..n {
        for k in row_start[i]..row_start[i + 1] {
            let j = cols[k] as usize;
            if j <= i {
                continue;
            }
            let range = row_start[j]..row_start[j + 1];
            if let Ok(pos) = cols[range.clone()].binary_search(&(i as u32)) {
                let t = range.start + pos;
                let mean = 0.5 * (vals[k] + vals[t]);
                vals[k] = mean;
                vals[t] = mean;
            }
        }
    }
}

/// A dense row accumulator for two value arrays: values in the order they come, the
/// touched columns listed, sorted on `take`.
struct Accumulator {
    values: Vec<(f64, f64)>,
    seen: Vec<bool>,
    touched: Vec<u32>,
}

impl Accumulator {
    fn new(n: usize) -> Accumulator {
        Accumulator {
            values: vec![(0.0, 0.0); n],
            seen: vec![false; n],
            touched: Vec::new(),
        }
    }

    fn add(&mut self, c: u32, a: f64, b: f64) {
        let i = c as usize;
        if !self.seen[i] {
            self.seen[i] = true;
            self.touched.push(c);
        }
        self.values[i].0 += a;
        self.values[i].1 += b;
    }

    fn take(&mut self) -> Vec<(u32, f64, f64)> {
        self.touched.sort_unstable();
        let out = self
            .touched
            .iter()
            .map(|&c| {
                let i = c as usize;
                let (a, b) = self.values[i];
                self.values[i] = (0.0, 0.0);
                self.seen[i] = false;
                (c, a, b)
            })
            .collect();
        self.touched.clear();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 7-point Laplacian of an `m³` grid with Neumann sides (`L·1 = 0`), as a
    /// pattern with a diagonal in every row, and a varying diagonal mass.
    fn grid(m: usize) -> (SparseMatrix, Vec<f64>, Vec<usize>, Vec<f64>) {
        let index = |x: usize, y: usize, z: usize| (x * m + y) * m + z;
        let n = m * m * m;
        let mut triplets = Vec::new();
        for x in 0..m {
            for y in 0..m {
                for z in 0..m {
                    let i = index(x, y, z);
                    let mut neighbours = Vec::new();
                    if x > 0 {
                        neighbours.push(index(x - 1, y, z));
                    }
                    if x + 1 < m {
                        neighbours.push(index(x + 1, y, z));
                    }
                    if y > 0 {
                        neighbours.push(index(x, y - 1, z));
                    }
                    if y + 1 < m {
                        neighbours.push(index(x, y + 1, z));
                    }
                    if z > 0 {
                        neighbours.push(index(x, y, z - 1));
                    }
                    if z + 1 < m {
                        neighbours.push(index(x, y, z + 1));
                    }
                    triplets.push((i as u32, i as u32, neighbours.len() as f64));
                    for j in neighbours {
                        triplets.push((i as u32, j as u32, -1.0));
                    }
                }
            }
        }
        let l = SparseMatrix::from_triplets(n, triplets);
        let diagonal_index: Vec<usize> = (0..n)
            .map(|i| (l.row_start[i]..l.row_start[i + 1]).find(|&k| l.cols[k] as usize == i))
            .map(Option::unwrap)
            .collect();
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + (i % 5) as f64 / 10.0).collect();
        let values = l.vals.clone();
        (l, values, diagonal_index, mass)
    }

    fn fine_matrix(
        l: &SparseMatrix,
        values: &[f64],
        diagonal: &[usize],
        mass: &[f64],
        tau: f64,
    ) -> (SparseMatrix, Vec<f64>) {
        let mut a = l.clone();
        a.vals = values.iter().map(|x| tau * x).collect();
        for (i, &d) in diagonal.iter().enumerate() {
            a.vals[d] += mass[i];
        }
        let inverse = diagonal.iter().map(|&d| 1.0 / a.vals[d]).collect();
        (a, inverse)
    }

    #[test]
    fn coarse_operators_keep_constants_and_total_mass() {
        let (l, values, diagonal, mass) = grid(16);
        let h = Hierarchy::new(&l, &values, &diagonal, &mass).unwrap();
        assert!(h.info().sizes.len() >= 3, "{:?}", h.info());
        let sizes = &h.info().sizes;
        assert!(sizes.windows(2).all(|w| w[1] < w[0]), "{sizes:?}");
        let total: f64 = mass.iter().sum();
        for level in &h.levels {
            let op = &level.operator;
            // P·1 = 1 (T·1 = 1 and L·1 = 0), so Pᵀ L P has zero row sums and
            // 1ᵀ Pᵀ M P 1 = 1ᵀ M 1.
            for i in 0..op.matrix.n {
                let range = op.matrix.row_start[i]..op.matrix.row_start[i + 1];
                let sum: f64 = op.stiffness[range.clone()].iter().sum();
                let scale: f64 = op.stiffness[range].iter().map(|x| x.abs()).sum();
                assert!(sum.abs() <= 1e-12 * scale, "row {i}: {sum} of {scale}");
            }
            let coarse_total: f64 = op.mass.iter().sum();
            assert!((coarse_total - total).abs() < 1e-9 * total);
        }
    }

    #[test]
    fn a_v_cycle_is_a_symmetric_positive_definite_operator() {
        let (l, values, diagonal, mass) = grid(12);
        let mut h = Hierarchy::new(&l, &values, &diagonal, &mass).unwrap();
        for tau in [1e-3, 1.0, 1e3] {
            h.set_tau(tau);
            let (a, inverse) = fine_matrix(&l, &values, &diagonal, &mass, tau);
            let n = a.n;
            let apply = |x: &[f64]| {
                let mut z = vec![0.0; n];
                h.apply(&a, &inverse, x, &mut z, &mut Workspace::default());
                z
            };
            let x: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
            let y: Vec<f64> = (0..n).map(|i| ((i * 13) % 7) as f64 * 0.3 - 1.0).collect();
            let (bx, by) = (apply(&x), apply(&y));
            let (xby, ybx) = (dot(&x, &by), dot(&y, &bx));
            assert!(
                (xby - ybx).abs() <= 1e-10 * xby.abs().max(ybx.abs()),
                "τ = {tau}: {xby} against {ybx}"
            );
            assert!(dot(&x, &bx) > 0.0 && dot(&y, &by) > 0.0);
        }
    }

    #[test]
    fn a_v_cycle_reduces_the_error_by_a_fixed_factor() {
        // Stationary iteration x ← x + B(b − A x) on the stiffest τ: the error must
        // shrink by a fixed factor per cycle, which is what makes the iteration count
        // independent of the mesh.
        for m in [10, 20] {
            let (l, values, diagonal, mass) = grid(m);
            let mut h = Hierarchy::new(&l, &values, &diagonal, &mass).unwrap();
            let tau = 1e4;
            h.set_tau(tau);
            let (a, inverse) = fine_matrix(&l, &values, &diagonal, &mass, tau);
            let n = a.n;
            let exact: Vec<f64> = (0..n).map(|i| ((i * 31) % 17) as f64).collect();
            let b = a.mul_vec(&exact);
            let mut x = vec![0.0; n];
            let mut work = Workspace::default();
            let error = |x: &[f64]| {
                let e: Vec<f64> = x.iter().zip(&exact).map(|(a, b)| a - b).collect();
                dot(&e, &a.mul_vec(&e)).sqrt()
            };
            let first = error(&x);
            for _ in 0..8 {
                let ax = a.mul_vec(&x);
                let r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
                let mut z = vec![0.0; n];
                h.apply(&a, &inverse, &r, &mut z, &mut work);
                x.iter_mut().zip(&z).for_each(|(x, z)| *x += z);
            }
            let factor = (error(&x) / first).powf(1.0 / 8.0);
            assert!(factor < 0.6, "m = {m}: {factor} per cycle");
        }
    }
}
