//! Cotangent stiffness and lumped mass matrices of a tetrahedral mesh.
//!
//! For a tet with volume `V` and barycentric functions `φ_i`, the local stiffness is
//! `K_ij = V ∇φ_i · ∇φ_j`, with `∇φ_i = −A_i n_i / (3V)` (`A_i`, `n_i`: area and outward
//! unit normal of the face opposite vertex `i`); this is the classic cotangent formula
//! `K_ij = −l_kl cot θ_kl / 6` written without angles. Summed over tets it gives the
//! symmetric positive semidefinite `L` with `L·1 = 0` and `fᵀ L f = ∫ |∇f|²` for the
//! piecewise-linear `f`. Local matrices are computed in parallel and summed in a fixed
//! order, so the result does not depend on the thread count.

use rayon::prelude::*;

use crate::geom::{cross, dot, scale, sub};
use crate::tet::TetMesh;

/// A square sparse matrix in compressed rows, columns sorted within each row.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseMatrix {
    /// Number of rows (and columns).
    pub n: usize,
    /// Start of each row in `cols` / `vals`; `n + 1` entries.
    pub row_start: Vec<usize>,
    /// Column of each stored entry.
    pub cols: Vec<u32>,
    /// Value of each stored entry.
    pub vals: Vec<f64>,
}

impl SparseMatrix {
    /// Sum duplicate `(row, col, value)` triplets into a matrix (order-independent of
    /// how the triplets were produced, as long as their order is fixed).
    pub fn from_triplets(n: usize, mut triplets: Vec<(u32, u32, f64)>) -> SparseMatrix {
        // Stable: equal (row, col) keep their production order, so sums are reproducible.
        triplets.sort_by_key(|t| (t.0, t.1));
        let mut row_start = vec![0usize; n + 1];
        let mut cols = Vec::new();
        let mut vals: Vec<f64> = Vec::new();
        let mut last: Option<(u32, u32)> = None;
        for (r, c, v) in triplets {
            if last == Some((r, c)) {
                if let Some(x) = vals.last_mut() {
                    *x += v;
                }
            } else {
                cols.push(c);
                vals.push(v);
                row_start[r as usize + 1] += 1;
                last = Some((r, c));
            }
        }
        for i in 0..n {
            row_start[i + 1] += row_start[i];
        }
        SparseMatrix {
            n,
            row_start,
            cols,
            vals,
        }
    }

    /// The stored entries of row `i` as `(column, value)`.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let range = self.row_start[i]..self.row_start[i + 1];
        self.cols[range.clone()]
            .iter()
            .copied()
            .zip(self.vals[range].iter().copied())
    }

    /// The entry at `(i, j)` (0 when not stored).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.row(i)
            .find(|&(c, _)| c as usize == j)
            .map_or(0.0, |(_, v)| v)
    }

    /// `y = A x`, rows in parallel.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        self.mul_vec_into(x, &mut y);
        y
    }

    /// `y = A x` into a buffer of `n` entries, rows in parallel.
    pub fn mul_vec_into(&self, x: &[f64], y: &mut [f64]) {
        row_products(&self.row_start, &self.cols, &self.vals, x, y, |_, yi, s| {
            *yi = s
        });
    }
}

/// A square linear operator applied row by row in parallel, each row summed in a fixed
/// order (so the result does not depend on the thread count): a stored matrix, or one
/// applied without being assembled.
pub trait LinearOperator: Sync {
    /// Number of rows (and columns).
    fn size(&self) -> usize;
    /// `y = A x` into a buffer of [`LinearOperator::size`] entries.
    fn apply_into(&self, x: &[f64], y: &mut [f64]);
}

impl LinearOperator for SparseMatrix {
    fn size(&self) -> usize {
        self.n
    }

    fn apply_into(&self, x: &[f64], y: &mut [f64]) {
        self.mul_vec_into(x, y);
    }
}

/// Each row's product with `x` of the compressed-row matrix `(row_start, cols, vals)`
/// (any shape), stored into `y` by `store(row, y_row, sum)`. Rows run in parallel,
/// each summed in its stored order, so the result does not depend on the thread count.
pub(crate) fn row_products<V: Copy + Into<f64> + Sync>(
    row_start: &[usize],
    cols: &[u32],
    vals: &[V],
    x: &[f64],
    y: &mut [f64],
    store: impl Fn(usize, &mut f64, f64) + Sync,
) {
    y.par_chunks_mut(ROWS_PER_TASK)
        .enumerate()
        .for_each(|(chunk, ys)| {
            let first = chunk * ROWS_PER_TASK;
            for (k, yi) in ys.iter_mut().enumerate() {
                let range = row_start[first + k]..row_start[first + k + 1];
                let s: f64 = cols[range.clone()]
                    .iter()
                    .zip(&vals[range])
                    .map(|(&c, &v)| v.into() * x[c as usize])
                    .sum();
                store(first + k, yi, s);
            }
        });
}

/// Vector length of one unit of parallel work in [`chunked_dot`].
pub(crate) const CHUNK: usize = 4096;

/// Dot product summed over fixed chunks in a fixed order (thread-count independent).
pub(crate) fn chunked_dot(a: &[f64], b: &[f64]) -> f64 {
    let partial: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x * y).sum())
        .collect();
    partial.iter().sum()
}

/// Rows per unit of parallel work in the products (each row is summed on its own, so
/// the split does not change the result).
const ROWS_PER_TASK: usize = 2048;

/// Gradients of the four barycentric functions of a tet and its (signed) volume.
fn gradients(p: [[f64; 3]; 4]) -> ([[f64; 3]; 4], f64) {
    let volume6 = dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0])));
    if volume6 == 0.0 {
        return ([[0.0; 3]; 4], 0.0);
    }
    // ∇φ_i is the area vector of the face opposite i, oriented towards i, over 3V;
    // with (j, k, l) an even permutation after i, that is (p_k − p_j) × (p_l − p_j) / 6V
    // up to the sign fixed by the orientation.
    let mut g = [[0.0; 3]; 4];
    for (i, gi) in g.iter_mut().enumerate() {
        let (j, k, l) = ((i + 1) % 4, (i + 2) % 4, (i + 3) % 4);
        let n = cross(sub(p[k], p[j]), sub(p[l], p[j]));
        // Point n towards vertex i.
        let towards = if dot(n, sub(p[i], p[j])) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        *gi = scale(n, towards / volume6.abs());
    }
    (g, volume6 / 6.0)
}

/// The cotangent stiffness matrix `L` (positive semidefinite, `l = −Δf`). Rows are
/// assembled in parallel, each from its vertex's tets in increasing tet order, so entry
/// `(i, j)` sums the same terms in the same order as `(j, i)`: `L` is exactly symmetric
/// and independent of the thread count.
pub fn cotangent_stiffness(mesh: &TetMesh) -> SparseMatrix {
    let rows: Vec<Vec<(u32, f64)>> = (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| {
            let mut entries: Vec<(u32, f64)> = Vec::with_capacity(4 * mesh.vertex_tets(v).len());
            for &t in mesh.vertex_tets(v) {
                let tet = mesh.tets[t as usize];
                let (g, volume) = gradients(mesh.corners(t as usize));
                let volume = volume.abs();
                if let Some(i) = tet.iter().position(|&u| u as usize == v) {
                    for (j, &u) in tet.iter().enumerate() {
                        entries.push((u, volume * dot(g[i], g[j])));
                    }
                }
            }
            // Stable: equal columns keep tet order.
            entries.sort_by_key(|e| e.0);
            let mut row: Vec<(u32, f64)> = Vec::with_capacity(entries.len() / 3);
            for (c, x) in entries {
                match row.last_mut() {
                    Some(last) if last.0 == c => last.1 += x,
                    _ => row.push((c, x)),
                }
            }
            row
        })
        .collect();
    // Reserved at their final length: grown by doubling, the two arrays could hold
    // twice the entries for as long as the matrix lives.
    let entries = rows.iter().map(Vec::len).sum();
    let mut row_start = Vec::with_capacity(rows.len() + 1);
    row_start.push(0);
    let mut cols = Vec::with_capacity(entries);
    let mut vals = Vec::with_capacity(entries);
    for row in rows {
        for (c, x) in row {
            cols.push(c);
            vals.push(x);
        }
        row_start.push(cols.len());
    }
    SparseMatrix {
        n: mesh.num_vertices(),
        row_start,
        cols,
        vals,
    }
}

/// The lumped mass: a quarter of each tet's volume to each of its vertices.
pub fn lumped_mass(mesh: &TetMesh) -> Vec<f64> {
    let mut mass = vec![0.0; mesh.num_vertices()];
    for t in 0..mesh.num_tets() {
        let quarter = mesh.tet_volume(t).abs() / 4.0;
        for &v in &mesh.tets[t] {
            mass[v as usize] += quarter;
        }
    }
    mass
}
