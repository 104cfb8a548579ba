//! Generalized winding numbers: the exact sum of signed solid angles, and the fast
//! hierarchical approximation of Barill, Dickson, Schmidt, Levin and Jacobson, "Fast
//! Winding Numbers for Soups and Clouds" (SIGGRAPH 2018), on the distance BVH.
//!
//! The winding number of a query `q` is `w(q) = (1/4π) ∫ (x − q)·n(x) / |x − q|³ dA(x)`,
//! the signed solid angle the surface subtends at `q` over 4π. Each node of the tree
//! stores the Taylor expansion of its triangles' contribution about their area-weighted
//! centroid `c`, to third order as in the paper, from three moments integrated exactly
//! over the (flat) triangles:
//!
//! ```text
//! N      = ∫ n dA                   = Σ a_t n_t          (dipole: area-weighted normals)
//! H_ij   = ∫ n_i (x − c)_j dA       = Σ a_t n_ti (x̄_t − c)_j
//! C_ijk  = ∫ n_i (x − c)_j (x − c)_k dA
//!        = Σ a_t n_ti (Σ_v y_vj y_vk + s_j s_k) / 12    (y_v = corner − c, s = Σ_v y_v)
//! ```
//!
//! With `r = c − q`, `g(x) = (x − q)/|x − q|³`, and its derivatives at `c`,
//!
//! ```text
//! 4π w_node(q) ≈ r·N / |r|³                                           (first order)
//!              + tr H / |r|³ − 3 rᵀHr / |r|⁵                          (second order)
//!              + ½ [ −3 (2 Σ_ik C_iik r_k + Σ_i r_i tr C_i) / |r|⁵
//!                    + 15 Σ_ijk r_i r_j r_k C_ijk / |r|⁷ ]             (third order)
//! ```
//!
//! used when `|r| > β · radius`, the radius being the largest distance from `c` to a
//! corner of the node's triangles ([`BETA`] = 2). Nearer nodes are opened; leaves sum the
//! exact solid angles of their triangles. The third order matters: on curved patches the
//! second-order term alone is of the same size as the third (both O(θ⁴) for a cap of
//! angular radius θ) and makes the estimate worse, not better, while the third-order
//! expansion leaves O(θ⁶).

use std::f64::consts::PI;

use super::bvh::{Bvh, STACK};
use crate::geom::{add, cross, dot, norm, scale, sub};

/// Accuracy parameter β of the fast winding number: a node's expansion is used for
/// queries farther than β times its radius from its centre (Barill et al. use 2).
pub const BETA: f64 = 2.0;

/// The far-field expansion of one BVH node.
#[derive(Debug, Clone, Copy)]
pub(super) struct Expansion {
    /// Expansion centre: area-weighted centroid of the node's triangles.
    centre: [f64; 3],
    /// `(β · radius)²`: the expansion is used beyond this squared distance.
    far2: f64,
    /// Dipole moment `N = Σ a_t n_t`.
    dipole: [f64; 3],
    /// First moment `H[i][j]`.
    first: [[f64; 3]; 3],
    /// Second moment `C[i]`, a symmetric matrix in `(j, k)` stored as
    /// `[xx, yy, zz, xy, xz, yz]`.
    second: [[f64; 6]; 3],
}

/// The expansion of every node of `bvh`, indexed like `bvh.nodes`.
pub(super) fn expansions(bvh: &Bvh) -> Vec<Expansion> {
    use rayon::prelude::*;
    // Per-triangle area vector (a_t n_t) and centroid, in tree order.
    let area_vec: Vec<[f64; 3]> = bvh
        .tris
        .par_iter()
        .map(|[a, b, c]| scale(cross(sub(*b, *a), sub(*c, *a)), 0.5))
        .collect();
    let centroid: Vec<[f64; 3]> = bvh
        .tris
        .par_iter()
        .map(|[a, b, c]| scale(add(add(*a, *b), *c), 1.0 / 3.0))
        .collect();
    // Each node's sums over its own range, in triangle order: the same whatever the
    // thread count.
    bvh.nodes
        .par_iter()
        .map(|node| {
            let range = node.start as usize..node.end as usize;
            let mut dipole = [0.0; 3];
            let mut area = 0.0;
            let mut weighted = [0.0; 3];
            let mut plain = [0.0; 3];
            for t in range.clone() {
                dipole = add(dipole, area_vec[t]);
                let a = norm(area_vec[t]);
                area += a;
                weighted = add(weighted, scale(centroid[t], a));
                plain = add(plain, centroid[t]);
            }
            let centre = if area > 0.0 {
                scale(weighted, 1.0 / area)
            } else {
                scale(plain, 1.0 / range.len() as f64)
            };
            let mut first = [[0.0; 3]; 3];
            let mut second = [[0.0; 6]; 3];
            let mut radius2: f64 = 0.0;
            for t in range {
                let av = area_vec[t];
                let dx = sub(centroid[t], centre);
                let ys = bvh.tris[t].map(|corner| sub(corner, centre));
                let s = add(add(ys[0], ys[1]), ys[2]);
                // ∫ y yᵀ dA over the triangle, divided by its area, times 12.
                let mut m = [
                    s[0] * s[0],
                    s[1] * s[1],
                    s[2] * s[2],
                    s[0] * s[1],
                    s[0] * s[2],
                    s[1] * s[2],
                ];
                for y in ys {
                    radius2 = radius2.max(dot(y, y));
                    m[0] += y[0] * y[0];
                    m[1] += y[1] * y[1];
                    m[2] += y[2] * y[2];
                    m[3] += y[0] * y[1];
                    m[4] += y[0] * y[2];
                    m[5] += y[1] * y[2];
                }
                for i in 0..3 {
                    for j in 0..3 {
                        first[i][j] += av[i] * dx[j];
                    }
                    for (c, mk) in second[i].iter_mut().zip(m) {
                        *c += av[i] * mk / 12.0;
                    }
                }
            }
            Expansion {
                centre,
                far2: BETA * BETA * radius2,
                dipole,
                first,
                second,
            }
        })
        .collect()
}

/// Signed solid angle of triangle `abc` seen from `q` (Van Oosterom–Strackee):
/// positive when `q` is on the side opposite to the normal `(b − a) × (c − a)`.
#[inline]
pub(super) fn solid_angle(q: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let a = sub(a, q);
    let b = sub(b, q);
    let c = sub(c, q);
    let la = norm(a);
    let lb = norm(b);
    let lc = norm(c);
    let det = dot(a, cross(b, c));
    let den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    2.0 * det.atan2(den)
}

/// Exact winding number: the sum of all signed solid angles over 4π.
pub(super) fn exact(bvh: &Bvh, q: [f64; 3]) -> f64 {
    let sum: f64 = bvh
        .tris
        .iter()
        .map(|&[a, b, c]| solid_angle(q, a, b, c))
        .sum();
    sum / (4.0 * PI)
}

/// Fast winding number: expansions for far nodes, exact solid angles in near leaves.
pub(super) fn fast(bvh: &Bvh, exp: &[Expansion], q: [f64; 3]) -> f64 {
    if bvh.nodes.is_empty() {
        return 0.0;
    }
    let mut omega = 0.0; // exact solid angles, radians
    let mut far = 0.0; // expansions, already divided by 4π
    let mut stack = [0u32; STACK];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let ni = stack[sp] as usize;
        let e = &exp[ni];
        let r = sub(e.centre, q);
        let r2 = dot(r, r);
        if r2 > e.far2 {
            far += far_field(e, r, r2);
            continue;
        }
        let node = &bvh.nodes[ni];
        if node.is_leaf() {
            for &[a, b, c] in &bvh.tris[node.start as usize..node.end as usize] {
                omega += solid_angle(q, a, b, c);
            }
        } else {
            stack[sp] = node.left;
            stack[sp + 1] = node.left + 1;
            sp += 2;
        }
    }
    omega / (4.0 * PI) + far
}

/// Third-order far-field contribution of one node, for `r = centre − q`, `r2 = |r|²`.
#[inline]
fn far_field(e: &Expansion, r: [f64; 3], r2: f64) -> f64 {
    let inv_r = 1.0 / r2.sqrt();
    let inv_r3 = inv_r / r2;
    let inv_r5 = inv_r3 / r2;
    let inv_r7 = inv_r5 / r2;
    let h = &e.first;
    let order1 = dot(r, e.dipole) * inv_r3;
    let trace_h = h[0][0] + h[1][1] + h[2][2];
    let rhr = dot(r, [dot(h[0], r), dot(h[1], r), dot(h[2], r)]);
    let order2 = trace_h * inv_r3 - 3.0 * rhr * inv_r5;
    // Σ_ik C_iik r_k, Σ_i r_i tr C_i and Σ_i r_i rᵀ C_i r.
    let (mut contracted, mut traced, mut cubic) = (0.0, 0.0, 0.0);
    for (i, c) in e.second.iter().enumerate() {
        let [xx, yy, zz, xy, xz, yz] = *c;
        let row = match i {
            0 => [xx, xy, xz],
            1 => [xy, yy, yz],
            _ => [xz, yz, zz],
        };
        contracted += dot(row, r);
        traced += r[i] * (xx + yy + zz);
        let rcr = xx * r[0] * r[0]
            + yy * r[1] * r[1]
            + zz * r[2] * r[2]
            + 2.0 * (xy * r[0] * r[1] + xz * r[0] * r[2] + yz * r[1] * r[2]);
        cubic += r[i] * rcr;
    }
    let order3 = 0.5 * (-3.0 * (2.0 * contracted + traced) * inv_r5 + 15.0 * cubic * inv_r7);
    (order1 + order2 + order3) / (4.0 * PI)
}
