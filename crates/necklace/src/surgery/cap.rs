//! The disk spanning a closed boundary polygon ([`cap`]).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::mesh::SurfaceMesh;

/// How a cap is faired after it is built on the cone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Fairing {
    /// A harmonic solve, then minimal-area steps (the default): the least area.
    #[default]
    MinimalArea,
    /// The harmonic solve only (uniform weights, no fold).
    Harmonic,
    /// None: the cone from the apex as built.
    Cone,
}

/// Options of [`cap`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CapOptions {
    /// How the disk is faired (default [`Fairing::MinimalArea`]).
    pub fairing: Fairing,
    /// Target edge length inside the disk, in the surface's units (default 0: the
    /// boundary's mean edge length).
    pub edge: f64,
    /// Most minimal-area steps after the harmonic solve (default 3).
    pub minimal_steps: usize,
    /// A solve stops when no vertex's Jacobi correction (its residual over its weight)
    /// exceeds this fraction of the edge length (default 1e-9).
    pub tolerance: f64,
    /// Most conjugate-gradient iterations per solve (default 5000).
    pub max_iterations: usize,
}

impl Default for CapOptions {
    fn default() -> Self {
        CapOptions {
            fairing: Fairing::MinimalArea,
            edge: 0.0,
            minimal_steps: 3,
            tolerance: 1e-9,
            max_iterations: 5000,
        }
    }
}

/// A disk spanning a boundary polygon, and how its fairing went.
#[derive(Debug, Clone, PartialEq)]
pub struct Cap {
    /// The disk: the boundary's points first, in the order given, then the rings
    /// inwards, then the centre.
    pub mesh: SurfaceMesh,
    /// Its area.
    pub area: f64,
    /// The area of the cone it started from.
    pub cone_area: f64,
    /// Conjugate-gradient iterations over all solves.
    pub iterations: usize,
    /// Whether every solve met the tolerance within `max_iterations`.
    pub converged: bool,
    /// Minimal-area steps kept (a step that does not lower the area is undone and ends
    /// them).
    pub minimal_steps: usize,
}

/// The disk spanning the closed polygon `boundary` (at least 3 points, not repeating
/// the first at the end).
///
/// 1. Rings: with ρ the boundary's length over 2π, `K = round(ρ / edge)` rings (at
///    least 1); ring `j` holds about `2πρ(1 − j/K) / edge` points (at least 3) at equal
///    parameter steps, each on the segment from `apex` to the boundary point at that
///    fraction of its length, `1 − j/K` of the way out: the cone from `apex`.
/// 2. Consecutive rings are zipped by parameter, the last one fanned to the centre
///    (`apex`): a disk by construction.
/// 3. Fairing with the boundary fixed (as `options.fairing` says): a harmonic solve with uniform weights (no fold,
///    Tutte), then minimal-area steps (Pinkall–Polthier: cotangent weights of the
///    current shape, clamped to stay positive, and a Laplace solve), each kept only if
///    it lowers the area.
pub fn cap(boundary: &[[f64; 3]], apex: [f64; 3], options: &CapOptions) -> Result<Cap> {
    check(boundary, apex, options)?;
    let length = perimeter(boundary);
    let edge = if options.edge > 0.0 {
        options.edge
    } else {
        length / boundary.len() as f64
    };
    let mut mesh = rings(boundary, apex, length, edge);
    let cone_area = area(&mesh);
    let neighbours = neighbours(&mesh);
    let fixed = boundary.len();
    let mut iterations = 0;
    let mut converged = true;
    let uniform: Vec<Vec<(u32, f64)>> = neighbours
        .iter()
        .map(|n| n.iter().map(|&v| (v, 1.0)).collect())
        .collect();
    if options.fairing != Fairing::Cone {
        let (s, c) = solve(&mut mesh.positions, &uniform, fixed, edge, options);
        iterations += s;
        converged &= c;
    }
    let mut current = area(&mesh);
    let mut kept = 0;
    let steps = match options.fairing {
        Fairing::MinimalArea => options.minimal_steps,
        Fairing::Harmonic | Fairing::Cone => 0,
    };
    for _ in 0..steps {
        let weights = cotangent_weights(&mesh, &neighbours);
        let before = mesh.positions.clone();
        let (s, c) = solve(&mut mesh.positions, &weights, fixed, edge, options);
        iterations += s;
        let after = area(&mesh);
        if after >= current {
            mesh.positions = before;
            break;
        }
        converged &= c;
        current = after;
        kept += 1;
    }
    Ok(Cap {
        mesh,
        area: current,
        cone_area,
        iterations,
        converged,
        minimal_steps: kept,
    })
}

fn check(boundary: &[[f64; 3]], apex: [f64; 3], options: &CapOptions) -> Result<()> {
    if boundary.len() < 3 {
        return Err(Error::invalid_argument(format!(
            "a cap needs a boundary of at least 3 points, not {}",
            boundary.len()
        )));
    }
    if boundary
        .iter()
        .chain([&apex])
        .flatten()
        .any(|x| !x.is_finite())
    {
        return Err(Error::invalid_argument(
            "a cap's boundary and apex must be finite points",
        ));
    }
    let tolerance_ok = options.tolerance > 0.0 && options.tolerance.is_finite();
    if !(options.edge >= 0.0 && options.edge.is_finite() && tolerance_ok) {
        return Err(Error::invalid_argument(format!(
            "cap options: edge {} must be 0 or positive, tolerance {} positive",
            options.edge, options.tolerance
        )));
    }
    if perimeter(boundary) <= 0.0 {
        return Err(Error::invalid_argument("a cap's boundary has zero length"));
    }
    Ok(())
}

fn perimeter(boundary: &[[f64; 3]]) -> f64 {
    (0..boundary.len())
        .map(|i| norm(sub(boundary[(i + 1) % boundary.len()], boundary[i])))
        .sum()
}

/// The boundary point at fraction `t` of its length (`at`: each point's fraction).
fn along(boundary: &[[f64; 3]], at: &[f64], t: f64) -> [f64; 3] {
    let n = boundary.len();
    let i = at.partition_point(|&s| s <= t).saturating_sub(1);
    let (s0, s1) = (at[i], if i + 1 < n { at[i + 1] } else { 1.0 });
    let u = if s1 > s0 { (t - s0) / (s1 - s0) } else { 0.0 };
    let (a, b) = (boundary[i], boundary[(i + 1) % n]);
    add(a, scale(sub(b, a), u))
}

/// Steps 1 and 2: the rings on the cone from `apex`, zipped into a disk.
fn rings(boundary: &[[f64; 3]], apex: [f64; 3], length: f64, edge: f64) -> SurfaceMesh {
    let n = boundary.len();
    // Each boundary point's fraction of the length.
    let mut at = Vec::with_capacity(n);
    let mut s = 0.0;
    for i in 0..n {
        at.push(s / length);
        s += norm(sub(boundary[(i + 1) % n], boundary[i]));
    }
    let rho = length / (2.0 * std::f64::consts::PI);
    let k = ((rho / edge).round() as usize).max(1);
    let mut positions: Vec<[f64; 3]> = boundary.to_vec();
    let mut triangles = Vec::new();
    // The outer ring: its vertices' indices and parameters.
    let mut outer: Vec<(u32, f64)> = (0..n).map(|i| (i as u32, at[i])).collect();
    for j in 1..k {
        let r = 1.0 - j as f64 / k as f64;
        let count = ((2.0 * std::f64::consts::PI * rho * r / edge).round() as usize).max(3);
        let first = positions.len() as u32;
        let inner: Vec<(u32, f64)> = (0..count)
            .map(|i| {
                let t = i as f64 / count as f64;
                let on = along(boundary, &at, t);
                positions.push(add(apex, scale(sub(on, apex), r)));
                (first + i as u32, t)
            })
            .collect();
        zip(&outer, &inner, &mut triangles);
        outer = inner;
    }
    let centre = positions.len() as u32;
    positions.push(apex);
    for i in 0..outer.len() {
        triangles.push([outer[i].0, outer[(i + 1) % outer.len()].0, centre]);
    }
    SurfaceMesh {
        positions,
        triangles,
    }
}

/// Triangles between an outer ring (run forwards) and an inner one, advancing on the
/// ring whose next point comes first by parameter.
fn zip(outer: &[(u32, f64)], inner: &[(u32, f64)], triangles: &mut Vec<[u32; 3]>) {
    let (m, q) = (outer.len(), inner.len());
    let next = |ring: &[(u32, f64)], i: usize| {
        if i + 1 < ring.len() {
            ring[i + 1].1
        } else {
            1.0
        }
    };
    let (mut i, mut k) = (0, 0);
    while i < m || k < q {
        let step_outer = k == q || (i < m && next(outer, i) <= next(inner, k));
        let (o, c) = (outer[i % m].0, inner[k % q].0);
        if step_outer {
            triangles.push([o, outer[(i + 1) % m].0, c]);
            i += 1;
        } else {
            triangles.push([o, inner[(k + 1) % q].0, c]);
            k += 1;
        }
    }
}

fn area(mesh: &SurfaceMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            0.5 * norm(cross(sub(b, a), sub(c, a)))
        })
        .sum()
}

/// Each vertex's neighbours, sorted.
fn neighbours(mesh: &SurfaceMesh) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            out[a as usize].push(b);
            out[b as usize].push(a);
        }
    }
    for n in &mut out {
        n.sort_unstable();
        n.dedup();
    }
    out
}

/// Cotangent weights of the current shape, per vertex and neighbour, clamped below at
/// 5 % of the mean so that every weight stays positive (an obtuse triangle's negative
/// cotangent would let the solve fold the disk).
fn cotangent_weights(mesh: &SurfaceMesh, neighbours: &[Vec<u32>]) -> Vec<Vec<(u32, f64)>> {
    let mut weight: std::collections::HashMap<(u32, u32), f64> = std::collections::HashMap::new();
    for t in &mesh.triangles {
        let p = t.map(|v| mesh.positions[v as usize]);
        for k in 0..3 {
            let (u, v) = (sub(p[(k + 1) % 3], p[k]), sub(p[(k + 2) % 3], p[k]));
            let cot = dot(u, v) / norm(cross(u, v)).max(f64::MIN_POSITIVE);
            let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            *weight.entry((a.min(b), a.max(b))).or_default() += 0.5 * cot;
        }
    }
    // Summed in the order of the edges, not the map's (the same input, the same cap).
    let mut positive: Vec<((u32, u32), f64)> = weight
        .iter()
        .filter(|(_, w)| **w > 0.0)
        .map(|(e, w)| (*e, *w))
        .collect();
    positive.sort_unstable_by_key(|(e, _)| *e);
    let mean = positive.iter().map(|(_, w)| w).sum::<f64>() / positive.len().max(1) as f64;
    let floor = 0.05 * mean.max(f64::MIN_POSITIVE);
    neighbours
        .iter()
        .enumerate()
        .map(|(a, n)| {
            let a = a as u32;
            n.iter()
                .map(|&b| (b, weight[&(a.min(b), a.max(b))].max(floor)))
                .collect()
        })
        .collect()
}

/// The weighted Laplace equation `Σ_u w_vu (x_v − x_u) = 0` at the vertices from
/// `fixed` on, the others fixed, by conjugate gradients with the Jacobi preconditioner
/// from the current positions (the weights are symmetric and positive: the matrix is
/// symmetric positive definite). Returns the iterations and whether it met the
/// tolerance.
fn solve(
    positions: &mut [[f64; 3]],
    weights: &[Vec<(u32, f64)>],
    fixed: usize,
    edge: f64,
    options: &CapOptions,
) -> (usize, bool) {
    let free = positions.len().saturating_sub(fixed);
    if free == 0 {
        return (0, true);
    }
    let diagonal: Vec<f64> = (fixed..positions.len())
        .map(|v| weights[v].iter().map(|(_, w)| w).sum())
        .collect();
    // The matrix on the free vertices times `x`.
    let apply = |x: &[[f64; 3]], out: &mut [[f64; 3]]| {
        for (i, o) in out.iter_mut().enumerate() {
            let mut sum = scale(x[i], diagonal[i]);
            for &(u, w) in &weights[fixed + i] {
                if u as usize >= fixed {
                    sum = sub(sum, scale(x[u as usize - fixed], w));
                }
            }
            *o = sum;
        }
    };
    let columns = |a: &[[f64; 3]], b: &[[f64; 3]]| {
        let mut d = [0.0; 3];
        for (p, q) in a.iter().zip(b) {
            for k in 0..3 {
                d[k] += p[k] * q[k];
            }
        }
        d
    };
    let mut x: Vec<[f64; 3]> = positions[fixed..].to_vec();
    let mut r = vec![[0.0; 3]; free];
    apply(&x, &mut r);
    for (i, ri) in r.iter_mut().enumerate() {
        let mut b = [0.0; 3];
        for &(u, w) in &weights[fixed + i] {
            if (u as usize) < fixed {
                b = add(b, scale(positions[u as usize], w));
            }
        }
        *ri = sub(b, *ri);
    }
    let precondition = |r: &[[f64; 3]]| -> Vec<[f64; 3]> {
        r.iter()
            .zip(&diagonal)
            .map(|(ri, d)| scale(*ri, 1.0 / d))
            .collect()
    };
    let small = |z: &[[f64; 3]]| z.iter().all(|zi| norm(*zi) <= options.tolerance * edge);
    let mut z = precondition(&r);
    let mut p = z.clone();
    let mut rz = columns(&r, &z);
    let mut q = vec![[0.0; 3]; free];
    let mut outcome = (options.max_iterations, false);
    for iteration in 0..=options.max_iterations {
        if small(&z) {
            outcome = (iteration, true);
            break;
        }
        if iteration == options.max_iterations {
            break;
        }
        apply(&p, &mut q);
        let pq = columns(&p, &q);
        let alpha: [f64; 3] =
            std::array::from_fn(|k| if pq[k] > 0.0 { rz[k] / pq[k] } else { 0.0 });
        for i in 0..free {
            for k in 0..3 {
                x[i][k] += alpha[k] * p[i][k];
                r[i][k] -= alpha[k] * q[i][k];
            }
        }
        z = precondition(&r);
        let next = columns(&r, &z);
        let beta: [f64; 3] =
            std::array::from_fn(|k| if rz[k] > 0.0 { next[k] / rz[k] } else { 0.0 });
        for i in 0..free {
            for k in 0..3 {
                p[i][k] = z[i][k] + beta[k] * p[i][k];
            }
        }
        rz = next;
    }
    positions[fixed..].copy_from_slice(&x);
    outcome
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;
    use std::f64::consts::PI;

    use super::*;

    fn circle(n: usize, z: impl Fn(f64) -> f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| {
                let t = 2.0 * PI * i as f64 / n as f64;
                [t.cos(), t.sin(), z(t)]
            })
            .collect()
    }

    /// χ = 1, one boundary cycle that is the given polygon in its order, every inner
    /// edge in two triangles with opposite directions.
    fn assert_disk(mesh: &SurfaceMesh, n: usize) {
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(
            directed.values().all(|&c| c == 1),
            "an edge twice in one direction"
        );
        let boundary: Vec<(u32, u32)> = directed
            .keys()
            .filter(|(a, b)| !directed.contains_key(&(*b, *a)))
            .copied()
            .collect();
        let mut expected: Vec<(u32, u32)> =
            (0..n).map(|i| (i as u32, ((i + 1) % n) as u32)).collect();
        let mut found = boundary.clone();
        expected.sort_unstable();
        found.sort_unstable();
        assert_eq!(found, expected);
        let edges = (directed.len() + boundary.len()) / 2;
        let euler = mesh.positions.len() as i64 - edges as i64 + mesh.triangles.len() as i64;
        assert_eq!(euler, 1);
    }

    #[test]
    fn a_cone_over_a_flat_circle_fairs_to_the_flat_disk() {
        let n = 64;
        let boundary = circle(n, |_| 0.0);
        let cap = cap(&boundary, [0.1, -0.2, 0.5], &CapOptions::default()).unwrap();
        assert_disk(&cap.mesh, n);
        assert!(cap.converged);
        let polygon = 0.5 * n as f64 * (2.0 * PI / n as f64).sin();
        assert!(
            (cap.area - polygon).abs() < 1e-6 * polygon,
            "{} vs {polygon}",
            cap.area
        );
        assert!(cap.cone_area > cap.area);
        assert!(cap.mesh.positions.iter().all(|p| p[2].abs() < 1e-6));
    }

    #[test]
    fn a_saddle_boundary_gets_the_minimal_surface_area() {
        // z = a r² cos 2θ is harmonic: the graph's area is π(1 + a²) to second order.
        let (n, a) = (96, 0.2);
        let boundary = circle(n, |t| a * (2.0 * t).cos());
        let cap = cap(&boundary, [0.0; 3], &CapOptions::default()).unwrap();
        assert_disk(&cap.mesh, n);
        let polygon = 0.5 * n as f64 * (2.0 * PI / n as f64).sin() / PI;
        let expected = PI * (1.0 + a * a) * polygon;
        assert!(
            (cap.area - expected).abs() < 0.005 * expected,
            "{} vs {expected}",
            cap.area
        );
        assert!(cap.area < cap.cone_area);
        // At the centre, the surface is flat (the saddle's value there is 0).
        let centre = cap.mesh.positions.last().unwrap();
        assert!(centre[2].abs() < 1e-3, "{centre:?}");
    }

    #[test]
    fn a_boundary_of_few_points_and_an_edge_longer_than_it_still_give_a_disk() {
        let triangle = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let options = CapOptions {
            edge: 10.0,
            ..CapOptions::default()
        };
        let cap = cap(&triangle, [0.3, 0.3, 0.0], &options).unwrap();
        assert_disk(&cap.mesh, 3);
        assert!((cap.area - 0.5).abs() < 1e-9, "{}", cap.area);
    }

    #[test]
    fn bad_boundaries_are_refused_in_one_line() {
        let o = CapOptions::default();
        assert!(cap(&[[0.0; 3], [1.0, 0.0, 0.0]], [0.0; 3], &o).is_err());
        assert!(cap(&[[0.0; 3]; 3], [0.0; 3], &o).is_err());
        let nan = [[f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(cap(&nan, [0.0; 3], &o).is_err());
    }
}
