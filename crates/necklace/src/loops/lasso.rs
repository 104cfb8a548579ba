//! The lasso of a loop: the circle that fits it best, for a grasp planner.
//!
//! A neck loop is a closed geodesic on the surface; a gripper or a rope that lassoes the
//! neck is a circle. [`fit_lasso`] fits one: the least-squares plane of the polyline
//! (the loop's `normal`), then in that plane the circle that minimizes the squared
//! distances of the points to it (a geometric fit: Kåsa's algebraic circle as the start,
//! then Gauss–Newton steps on the centre and radius), every point weighted by the
//! length of polyline it stands for, so a densely sampled stretch does not pull the
//! circle. It reports how far the loop strays from the circle: the largest and the
//! root-mean-square 3D distance from the polyline (its points and its segments'
//! midpoints) to the circle, out-of-plane offsets included.
//!
//! Conventions: lengths in the surface's units; the normal is a unit vector oriented
//! like the loop (it turns counter-clockwise around it), as [`NeckLoop::normal`](super::NeckLoop::normal).

use serde::{Deserialize, Serialize};

use crate::geom::{add, dot, norm, plane_basis, scale, sub};

/// The best-fit circle of a loop and how far the loop strays from it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Lasso {
    /// The circle's centre.
    pub center: [f64; 3],
    /// Unit normal of the circle's plane, oriented like the loop.
    pub normal: [f64; 3],
    /// The circle's radius.
    pub radius: f64,
    /// Largest distance from the loop to the circle.
    pub max_deviation: f64,
    /// Root-mean-square distance from the loop to the circle (weighted by length).
    pub rms_deviation: f64,
}

/// Gauss–Newton steps of the geometric circle fit at most; each is one pass over the
/// points, and it converges in a handful on a loop that is near a circle.
const MAX_STEPS: usize = 50;

/// The fit stops when a step moves the centre and radius by less than this fraction
/// of the radius.
const STEP_TOLERANCE: f64 = 1e-13;

/// The best-fit circle of the closed polyline `points` (first point not repeated),
/// given its least-squares plane through `center` with unit `normal` (see the module
/// doc). A polyline with fewer than three points, one whose points are all on a line,
/// or a `normal` that is not a unit vector gets the circle of its own length around
/// `center`.
pub fn fit_lasso(points: &[[f64; 3]], center: [f64; 3], normal: [f64; 3]) -> Lasso {
    let n = points.len();
    let length: f64 = (0..n)
        .map(|i| norm(sub(points[(i + 1) % n], points[i])))
        .sum();
    let fallback = ([0.0, 0.0], length / (2.0 * std::f64::consts::PI));
    let unit = (norm(normal) - 1.0).abs() < 1e-9;
    let (u, v) = if unit {
        plane_basis(normal)
    } else {
        ([0.0; 3], [0.0; 3])
    };
    // Each point stands for half of each segment at it.
    let weights: Vec<f64> = (0..n)
        .map(|i| {
            0.5 * (norm(sub(points[(i + 1) % n], points[i]))
                + norm(sub(points[i], points[(i + n - 1) % n])))
        })
        .collect();
    let planar: Vec<[f64; 2]> = points
        .iter()
        .map(|&p| {
            let d = sub(p, center);
            [dot(d, u), dot(d, v)]
        })
        .collect();
    let (c, radius) = Some(())
        .filter(|_| unit && n >= 3)
        .and_then(|_| algebraic_circle(&planar, &weights))
        .map(|start| geometric_circle(&planar, &weights, start))
        .filter(|(c, r)| r.is_finite() && *r > 0.0 && c.iter().all(|x| x.is_finite()))
        .unwrap_or(fallback);
    let circle_center = add(center, add(scale(u, c[0]), scale(v, c[1])));
    let distance = |p: [f64; 3]| circle_distance(p, circle_center, normal, radius);
    let at_points: Vec<f64> = points.iter().map(|&p| distance(p)).collect();
    let mut max_deviation: f64 = 0.0;
    let mut sum = 0.0;
    let mut total = 0.0;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        let (da, db) = (at_points[i], at_points[(i + 1) % n]);
        let dm = distance(scale(add(a, b), 0.5));
        max_deviation = max_deviation.max(da).max(dm);
        // Simpson's rule along the segment: ends and middle.
        let w = norm(sub(b, a));
        sum += w * (da * da + 4.0 * dm * dm + db * db) / 6.0;
        total += w;
    }
    Lasso {
        center: circle_center,
        normal,
        radius,
        max_deviation,
        rms_deviation: if total > 0.0 {
            (sum / total).sqrt()
        } else {
            0.0
        },
    }
}

/// Distance from `p` to the circle of `center`, unit `normal` and `radius`.
pub fn circle_distance(p: [f64; 3], center: [f64; 3], normal: [f64; 3], radius: f64) -> f64 {
    let d = sub(p, center);
    let height = dot(d, normal);
    let across = norm(sub(d, scale(normal, height)));
    ((across - radius).powi(2) + height * height).sqrt()
}

/// Kåsa's fit: the circle `x² + y² + D x + E y + F = 0` minimizing the weighted squared
/// algebraic residuals (a 3 × 3 linear solve); `None` when the points are collinear.
fn algebraic_circle(points: &[[f64; 2]], weights: &[f64]) -> Option<([f64; 2], f64)> {
    let mut normal_matrix = nalgebra::Matrix3::<f64>::zeros();
    let mut rhs = nalgebra::Vector3::<f64>::zeros();
    for (q, &w) in points.iter().zip(weights) {
        let row = nalgebra::Vector3::new(q[0], q[1], 1.0);
        let z = q[0] * q[0] + q[1] * q[1];
        normal_matrix += w * row * row.transpose();
        rhs -= w * z * row;
    }
    let solution = normal_matrix.cholesky()?.solve(&rhs);
    let c = [-0.5 * solution[0], -0.5 * solution[1]];
    let r2 = c[0] * c[0] + c[1] * c[1] - solution[2];
    (r2 > 0.0 && r2.is_finite()).then(|| (c, r2.sqrt()))
}

/// Gauss–Newton on `Σ w (|q − c| − r)²` from `start`: each step solves the 3 × 3 normal
/// equations for the change of the centre and the radius.
fn geometric_circle(
    points: &[[f64; 2]],
    weights: &[f64],
    start: ([f64; 2], f64),
) -> ([f64; 2], f64) {
    let (mut c, mut r) = start;
    for _ in 0..MAX_STEPS {
        // Residual ρ_i − r with Jacobian rows (−e_i, −1), e_i the unit vector from c.
        let mut jtj = nalgebra::Matrix3::<f64>::zeros();
        let mut jtr = nalgebra::Vector3::<f64>::zeros();
        for (q, &w) in points.iter().zip(weights) {
            let d = [q[0] - c[0], q[1] - c[1]];
            let rho = (d[0] * d[0] + d[1] * d[1]).sqrt();
            if rho == 0.0 {
                continue;
            }
            let row = nalgebra::Vector3::new(-d[0] / rho, -d[1] / rho, -1.0);
            jtj += w * row * row.transpose();
            jtr += w * (rho - r) * row;
        }
        let Some(step) = jtj.cholesky().map(|f| f.solve(&(-jtr))) else {
            break;
        };
        c = [c[0] + step[0], c[1] + step[1]];
        r += step[2];
        if step.norm() <= STEP_TOLERANCE * r.abs().max(f64::MIN_POSITIVE) {
            break;
        }
    }
    (c, r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::cross;
    use crate::loops::{best_fit_normal, centroid};

    fn fit(points: &[[f64; 3]]) -> Lasso {
        let c = centroid(points);
        fit_lasso(points, c, best_fit_normal(points, c))
    }

    /// A circle of `radius` around `center` in the plane spanned by `u`, `v` (unit,
    /// orthogonal), sampled at the given angles.
    fn circle(
        center: [f64; 3],
        u: [f64; 3],
        v: [f64; 3],
        radius: f64,
        angles: &[f64],
    ) -> Vec<[f64; 3]> {
        angles
            .iter()
            .map(|&a| {
                add(
                    center,
                    add(scale(u, radius * a.cos()), scale(v, radius * a.sin())),
                )
            })
            .collect()
    }

    #[test]
    fn a_tilted_unevenly_sampled_circle_is_found_exactly() {
        // Dense on one side, sparse on the other: the centroid is off-centre, the
        // circle is not.
        let angles: Vec<f64> = (0..60)
            .map(|i| {
                let t = i as f64 / 60.0;
                2.0 * std::f64::consts::PI * t * t
            })
            .collect();
        let s = 1.0 / 3f64.sqrt();
        let u = [s, s, s];
        let v = scale([1.0, -1.0, 0.0], 1.0 / 2f64.sqrt());
        let center = [10.0, -4.0, 2.5];
        let points = circle(center, u, v, 0.75, &angles);
        let lasso = fit(&points);
        assert!(norm(sub(lasso.center, center)) < 1e-9, "{:?}", lasso);
        assert!((lasso.radius - 0.75).abs() < 1e-9, "{:?}", lasso);
        assert!((dot(lasso.normal, cross(u, v)).abs() - 1.0).abs() < 1e-9);
        // The points are on the circle; the chords' midpoints fall inside it by the
        // sagitta of the longest chord.
        let longest = (0..points.len())
            .map(|i| norm(sub(points[(i + 1) % points.len()], points[i])))
            .fold(0.0, f64::max);
        let sagitta = 0.75 - (0.75f64.powi(2) - (0.5 * longest).powi(2)).sqrt();
        assert!(
            (lasso.max_deviation - sagitta).abs() < 1e-9,
            "{} {}",
            lasso.max_deviation,
            sagitta
        );
        assert!(lasso.rms_deviation <= lasso.max_deviation);
    }

    #[test]
    fn a_square_gets_its_mean_distance_circle() {
        // A square of side 2 sampled finely: by symmetry the centre is the square's;
        // the geometric fit's radius is the mean distance from it over the perimeter,
        // (1/1) ∫₀¹ √(1 + t²) dt = (√2 + asinh 1) / 2, and the loop strays most at
        // the corners: √2 − r.
        let k = 2000;
        let mut points = Vec::new();
        for side in 0..4 {
            for i in 0..k {
                let t = -1.0 + 2.0 * i as f64 / k as f64;
                let p = match side {
                    0 => [t, -1.0, 0.0],
                    1 => [1.0, t, 0.0],
                    2 => [-t, 1.0, 0.0],
                    _ => [-1.0, -t, 0.0],
                };
                points.push(p);
            }
        }
        let lasso = fit(&points);
        let r = (2f64.sqrt() + 1f64.asinh()) / 2.0;
        assert!(norm(lasso.center) < 1e-9, "{:?}", lasso);
        assert!((lasso.radius - r).abs() < 1e-5, "{} {}", lasso.radius, r);
        assert!((lasso.max_deviation - (2f64.sqrt() - r)).abs() < 1e-5);
        assert!(norm(sub(lasso.normal, [0.0, 0.0, 1.0])) < 1e-12);
    }

    #[test]
    fn a_saddle_shaped_loop_strays_out_of_its_plane_by_its_height() {
        // The circle of radius 1 lifted by z = h cos 2θ (a loop round a saddle-shaped
        // neck): the best plane is z = 0, the circle radius 1, and the largest
        // deviation is h, at θ = 0, π/2, ….
        let h = 0.1;
        let points: Vec<[f64; 3]> = (0..400)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * i as f64 / 400.0;
                [a.cos(), a.sin(), h * (2.0 * a).cos()]
            })
            .collect();
        let lasso = fit(&points);
        assert!((lasso.radius - 1.0).abs() < 1e-4, "{:?}", lasso);
        assert!((lasso.max_deviation - h).abs() < 1e-4, "{:?}", lasso);
        assert!(
            (lasso.rms_deviation - h / 2f64.sqrt()).abs() < 1e-3,
            "{:?}",
            lasso
        );
    }

    #[test]
    fn degenerate_loops_get_the_circle_of_their_length() {
        let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let lasso = fit(&points);
        assert!((lasso.radius - 2.0 / (2.0 * std::f64::consts::PI)).abs() < 1e-12);
        assert!(lasso.max_deviation.is_finite());
    }
}
