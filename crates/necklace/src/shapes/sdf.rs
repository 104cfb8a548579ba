//! Signed distance primitives and their smooth union (negative inside).

use crate::geom::{dot, norm, sub};

/// Ball of radius `r` around `c`.
pub(crate) fn ball(p: [f64; 3], c: [f64; 3], r: f64) -> f64 {
    norm(sub(p, c)) - r
}

/// Capsule: points within `r` of the segment `a`–`b`.
pub(crate) fn capsule(p: [f64; 3], a: [f64; 3], b: [f64; 3], r: f64) -> f64 {
    let ab = sub(b, a);
    let t = (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0);
    let closest = [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]];
    norm(sub(p, closest)) - r
}

/// Torus around the z axis through `c`: core circle radius `big_r`, tube radius
/// `tube(θ)` where θ is the angle around the axis (θ = 0 on +x). Exact for a constant
/// tube; for a varying tube the zero set is exact and the value a close approximation.
pub(crate) fn torus(p: [f64; 3], c: [f64; 3], big_r: f64, tube: impl Fn(f64) -> f64) -> f64 {
    let d = sub(p, c);
    let rho = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let theta = d[1].atan2(d[0]);
    let q = [rho - big_r, d[2]];
    (q[0] * q[0] + q[1] * q[1]).sqrt() - tube(theta)
}

/// Polynomial smooth minimum with blend width `k` (plain `min` for `k = 0`). It differs
/// from `min(a, b)` only where `|a − b| < k`, by at most `k/4`.
pub(crate) fn smooth_union(a: f64, b: f64, k: f64) -> f64 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_have_known_values() {
        assert!((ball([2.0, 0.0, 0.0], [0.0; 3], 1.0) - 1.0).abs() < 1e-15);
        let a = [-1.0, 0.0, 0.0];
        let b = [1.0, 0.0, 0.0];
        assert!((capsule([0.0, 0.5, 0.0], a, b, 0.2) - 0.3).abs() < 1e-15);
        assert!((capsule([3.0, 0.0, 0.0], a, b, 0.2) - 1.8).abs() < 1e-15);
        assert!((torus([1.0, 0.0, 0.0], [0.0; 3], 1.0, |_| 0.3) + 0.3).abs() < 1e-15);
        assert!((torus([0.0, 0.0, 0.0], [0.0; 3], 1.0, |_| 0.3) - 0.7).abs() < 1e-15);
        assert_eq!(smooth_union(0.0, 5.0, 0.1), 0.0);
        assert!(smooth_union(0.0, 0.0, 0.1) < 0.0);
    }
}
