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

/// Ellipsoid with semi-axes `r` along x, y, z around the origin. The zero set is exact;
/// the value is the scaled-sphere bound (|p/r| − 1)·min(r), a close approximation.
pub(crate) fn ellipsoid(p: [f64; 3], r: [f64; 3]) -> f64 {
    let q = [p[0] / r[0], p[1] / r[1], p[2] / r[2]];
    (norm(q) - 1.0) * r[0].min(r[1]).min(r[2])
}

/// Round cone: the convex hull of the balls (`a`, `ra`) and (`b`, `rb`), `|ra − rb| < |b − a|`.
///
/// In the half-plane through the axis, with u along `a → b` and v ≥ 0 away from it, the
/// lateral line touches both circles; its outward normal is n = (sin α, cos α) with
/// sin α = (ra − rb)/L. A point whose coordinate along the line's direction
/// (cos α, −sin α) falls before the tangent point on `a` (at 0) is nearest to ball `a`,
/// one past the tangent point on `b` (at L cos α) to ball `b`, and any other to the line.
pub(crate) fn round_cone(p: [f64; 3], a: [f64; 3], b: [f64; 3], ra: f64, rb: f64) -> f64 {
    let axis = sub(b, a);
    let length = norm(axis);
    let d = sub(p, a);
    let u = dot(d, axis) / length;
    let v = (dot(d, d) - u * u).max(0.0).sqrt();
    let sin = (ra - rb) / length;
    let cos = (1.0 - sin * sin).sqrt();
    let along = u * cos - v * sin;
    if along < 0.0 {
        (u * u + v * v).sqrt() - ra
    } else if along > length * cos {
        ((u - length) * (u - length) + v * v).sqrt() - rb
    } else {
        u * sin + v * cos - ra
    }
}

/// Distance from `p` to the closed curve `core(t)`, t in [0, 2π): the nearest of 64
/// samples, then golden-section search on the two sample intervals beside it. Exact for
/// a smooth curve whose samples are dense compared with its curvature radius.
pub(crate) fn distance_to_closed_curve(p: [f64; 3], core: impl Fn(f64) -> [f64; 3]) -> f64 {
    const SAMPLES: usize = 64;
    let step = std::f64::consts::TAU / SAMPLES as f64;
    let d = |t: f64| norm(sub(p, core(t)));
    let best = (0..SAMPLES)
        .map(|i| i as f64 * step)
        .min_by(|a, b| d(*a).total_cmp(&d(*b)))
        .expect("samples");
    let (mut a, mut b) = (best - step, best + step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (d(x1), d(x2));
    for _ in 0..40 {
        if f1 < f2 {
            b = x2;
            (x2, f2) = (x1, f1);
            x1 = b - g * (b - a);
            f1 = d(x1);
        } else {
            a = x1;
            (x1, f1) = (x2, f2);
            x2 = a + g * (b - a);
            f2 = d(x2);
        }
    }
    f1.min(f2).min(d(best))
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
        assert!((ellipsoid([0.0, 0.0, 0.5], [2.0, 1.0, 0.5])).abs() < 1e-15);
        assert!((ellipsoid([2.0, 0.0, 0.0], [2.0, 1.0, 0.5])).abs() < 1e-15);
        // A round cone from (0, r 1) to (4, r 0.5): the ends are balls, the side a line.
        let (a, b) = ([0.0; 3], [4.0, 0.0, 0.0]);
        assert!((round_cone([-3.0, 0.0, 0.0], a, b, 1.0, 0.5) - 2.0).abs() < 1e-15);
        assert!((round_cone([6.0, 0.0, 0.0], a, b, 1.0, 0.5) - 1.5).abs() < 1e-15);
        assert!((round_cone([2.0, 0.0, 0.0], a, b, 1.0, 0.5) + 0.75).abs() < 1e-12);
        // Equal radii: a capsule.
        for q in [[1.0, 0.7, 0.2], [-0.5, 0.1, 0.0], [5.0, -1.0, 2.0]] {
            assert!((round_cone(q, a, b, 0.3, 0.3) - capsule(q, a, b, 0.3)).abs() < 1e-12);
        }
        assert!(smooth_union(0.0, 0.0, 0.1) < 0.0);
        // A circle of radius 2: the distance from its axis, and from a point beside it.
        let circle = |t: f64| [2.0 * t.cos(), 2.0 * t.sin(), 0.0];
        assert!((distance_to_closed_curve([0.0, 0.0, 1.5], circle) - 2.5).abs() < 1e-12);
        let q = [3.0 * 0.7f64.cos(), 3.0 * 0.7f64.sin(), 1.0];
        assert!((distance_to_closed_curve(q, circle) - 2f64.sqrt()).abs() < 1e-9);
    }
}
