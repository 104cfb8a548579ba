//! Small fixed-size vector helpers shared by all modules (plain `[f64; 3]` arithmetic).
//! Not a stage: it holds no algorithm of the method, only the arithmetic every stage uses.
//!
//! Besides the arithmetic: closest points on a triangle or a segment, bounds, and
//! [`illinois_root`], the crate's one 1-D root finder (the tightening's anchor search, the
//! mesher's cut points).

/// `a − b`.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a + b`.
#[inline]
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `s · a`.
#[inline]
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean length.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Linear interpolation `a + t (b − a)`.
#[inline]
pub fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
    ]
}

/// An orthonormal basis `(u, v)` of the plane with unit normal `n`.
pub fn plane_basis(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if n[0].abs() < 0.6 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = cross(n, helper);
    let u = scale(u, 1.0 / norm(u));
    (u, cross(n, u))
}

/// Closest point to `p` on the triangle `abc`, by its Voronoi regions (Ericson,
/// *Real-Time Collision Detection*, 5.1.5). An interior closest point is the projection
/// onto the plane; a zero-area triangle, or rounding that contradicts the regions, falls
/// back to the closest point on the three edges, so the result is always on the triangle.
#[inline]
pub fn closest_on_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let den = d1 - d3;
        if den > 0.0 {
            return add(a, scale(ab, d1 / den));
        }
        return closest_on_edges(p, a, b, c);
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let den = d2 - d6;
        if den > 0.0 {
            return add(a, scale(ac, d2 / den));
        }
        return closest_on_edges(p, a, b, c);
    }
    let va = d3 * d6 - d5 * d4;
    let e1 = d4 - d3;
    let e2 = d5 - d6;
    if va <= 0.0 && e1 >= 0.0 && e2 >= 0.0 {
        let den = e1 + e2;
        if den > 0.0 {
            return add(b, scale(sub(c, b), e1 / den));
        }
        return closest_on_edges(p, a, b, c);
    }
    if va > 0.0 && vb > 0.0 && vc > 0.0 {
        let n = cross(ab, ac);
        let nn = dot(n, n);
        if nn > 0.0 && nn.is_finite() {
            return sub(p, scale(n, dot(n, ap) / nn));
        }
    }
    closest_on_edges(p, a, b, c)
}

/// Closest point to `p` on the boundary of triangle `abc` (all of a degenerate one).
fn closest_on_edges(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let mut best = a;
    let mut best_d2 = f64::INFINITY;
    for (u, v) in [(a, b), (b, c), (c, a)] {
        let q = closest_on_segment(p, u, v);
        let d = sub(p, q);
        let d2 = dot(d, d);
        if d2 < best_d2 {
            best_d2 = d2;
            best = q;
        }
    }
    best
}

/// Closest point to `p` on the segment `uv` (`u` for a zero-length one).
#[inline]
pub fn closest_on_segment(p: [f64; 3], u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    let e = sub(v, u);
    let ee = dot(e, e);
    if ee.is_nan() || ee <= 0.0 {
        return u;
    }
    let t = (dot(sub(p, u), e) / ee).clamp(0.0, 1.0);
    add(u, scale(e, t))
}

/// The root of `f` on `[0, 1]`, where `f(0) = f0` and `f(1) = f1` have opposite signs:
/// regula falsi with the Illinois rule (the value kept at a bracket end twice in a row is
/// halved, so the bracket shrinks from both sides). Stops when `|f(t)| <= tol`, when the
/// bracket is narrower than `width`, or after `steps` evaluations; returns the last `t`
/// evaluated (0.5 if none).
pub fn illinois_root(
    mut f: impl FnMut(f64) -> f64,
    f0: f64,
    f1: f64,
    tol: f64,
    width: f64,
    steps: usize,
) -> f64 {
    let (mut lo, mut hi, mut flo, mut fhi) = (0.0f64, 1.0f64, f0, f1);
    let mut side = 0i8;
    let mut t = 0.5;
    for _ in 0..steps {
        t = (lo * fhi - hi * flo) / (fhi - flo);
        if !(t > lo && t < hi) {
            t = 0.5 * (lo + hi);
        }
        let ft = f(t);
        if ft.abs() <= tol {
            break;
        }
        if (ft < 0.0) == (flo < 0.0) {
            lo = t;
            flo = ft;
            if side == -1 {
                fhi *= 0.5;
            }
            side = -1;
        } else {
            hi = t;
            fhi = ft;
            if side == 1 {
                flo *= 0.5;
            }
            side = 1;
        }
        if hi - lo < width {
            break;
        }
    }
    t
}

/// Axis-aligned bounds `(min, max)` of some points (NaN coordinates are ignored by
/// `min`/`max`; no points give infinite bounds, min above max).
pub fn bounds(points: impl IntoIterator<Item = [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// The regular icosahedron: its 12 corners (cyclic permutations of (±1, ±φ, 0), at
/// distance √(1 + φ²) from the origin) and its 20 faces, counter-clockwise seen from
/// outside.
pub fn icosahedron() -> ([[f64; 3]; 12], [[u32; 3]; 20]) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    (
        [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ],
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ],
    )
}
