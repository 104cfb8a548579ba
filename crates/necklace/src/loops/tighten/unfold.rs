//! Step 1 and the core of step 2 of the tightening: the strip unfolded into the plane
//! ([`unfold`]: portals as 2D segments, left and right seen forward, the anchor portal at
//! both ends), and the shortest path from a point on the first portal to its image on
//! the last through the ones between ([`funnel`], Lee & Preparata's funnel), with its
//! length and derivative in the anchor parameter ([`length_and_slope`]).
//!
//! Conventions: the anchor's right vertex at the origin, its left vertex on +y, forward
//! is +x; `cross2(a, b, c) > 0` when `c` is left of `a → b`.

use super::{Strip, SurfaceGeometry};
use crate::geom::{norm, sub};

/// A portal in the unfolding.
#[derive(Debug, Clone, Copy)]
pub(super) struct Portal2 {
    /// The left end (seen forward) in the plane, and its mesh vertex.
    pub left: [f64; 2],
    /// The right end, and its mesh vertex.
    pub right: [f64; 2],
    pub lv: u32,
    pub rv: u32,
}

pub(super) fn cross2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

pub(super) fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

pub(super) fn lerp2(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// Unfold the strip starting at portal `anchor`: `n + 1` portals, the last being the
/// anchor's image. `None` when consecutive portals do not share a face as stored.
pub(super) fn unfold(
    geometry: &SurfaceGeometry,
    strip: &Strip,
    anchor: usize,
) -> Option<Vec<Portal2>> {
    let n = strip.portals.len();
    let [a, b] = geometry.edge(strip.portals[anchor]);
    let len = norm(sub(geometry.pos(a), geometry.pos(b)));
    let mut out = Vec::with_capacity(n + 1);
    // Right vertex at the origin, left above it: forward is +x.
    let mut cur = Portal2 {
        left: [0.0, len],
        right: [0.0, 0.0],
        lv: a,
        rv: b,
    };
    // The first face must lie forward; the orientation of (a, b) is arbitrary, so
    // nothing to check here: the third vertex is placed forward by construction.
    out.push(cur);
    for k in 0..n {
        let i = (anchor + k) % n;
        let f = strip.faces[i];
        let tri = geometry.mesh.triangles[f as usize];
        let w = *tri.iter().find(|&&x| x != cur.lv && x != cur.rv)?;
        if !(tri.contains(&cur.lv) && tri.contains(&cur.rv)) {
            return None;
        }
        let pw = geometry.pos(w);
        let da = norm(sub(pw, geometry.pos(cur.lv)));
        let db = norm(sub(pw, geometry.pos(cur.rv)));
        let d = dist2(cur.left, cur.right);
        if d <= 0.0 {
            return None;
        }
        let u = [
            (cur.left[0] - cur.right[0]) / d,
            (cur.left[1] - cur.right[1]) / d,
        ];
        let forward = [u[1], -u[0]];
        let x = (db * db - da * da + d * d) / (2.0 * d);
        let h = (db * db - x * x).max(0.0).sqrt();
        let w2 = [
            cur.right[0] + x * u[0] + h * forward[0],
            cur.right[1] + x * u[1] + h * forward[1],
        ];
        let [p, q] = geometry.edge(strip.portals[(i + 1) % n]);
        let next_has = |v: u32| p == v || q == v;
        cur = if next_has(w) && next_has(cur.rv) {
            Portal2 {
                left: w2,
                right: cur.right,
                lv: w,
                rv: cur.rv,
            }
        } else if next_has(w) && next_has(cur.lv) {
            Portal2 {
                left: cur.left,
                right: w2,
                lv: cur.lv,
                rv: w,
            }
        } else {
            return None;
        };
        out.push(cur);
    }
    // The anchor comes back with the same sides on an oriented surface.
    (out[n].lv == a && out[n].rv == b).then_some(out)
}

/// One vertex of the funnel path: its 2D position, its mesh vertex (None for the end
/// points) and the index of the portal where it was found.
#[derive(Debug, Clone, Copy)]
pub(super) struct Apex {
    pub pos: [f64; 2],
    pub vertex: Option<u32>,
    pub index: usize,
}

/// Shortest path from `start` (on portal 0) to `goal` (on portal `n`) through portals
/// `1..n` (the funnel algorithm). Returns the bend points including both ends.
/// An end point that is a portal endpoint carries its vertex, so that the funnel sees it
/// as the same point as that vertex on the following portals.
pub(super) fn funnel(
    start: [f64; 2],
    goal: [f64; 2],
    portals: &[Portal2],
    end_vertex: Option<u32>,
) -> Vec<Apex> {
    let n = portals.len() - 1;
    let mut path = vec![Apex {
        pos: start,
        vertex: end_vertex,
        index: 0,
    }];
    let mut apex = path[0];
    let (mut left, mut right) = (apex, apex);
    let same = |a: &Apex, b: &Apex| a.vertex == b.vertex && a.pos == b.pos;
    let mut i = 1;
    while i <= n {
        let (l, r) = if i < n {
            let p = portals[i];
            (
                Apex {
                    pos: p.left,
                    vertex: Some(p.lv),
                    index: i,
                },
                Apex {
                    pos: p.right,
                    vertex: Some(p.rv),
                    index: i,
                },
            )
        } else {
            let g = Apex {
                pos: goal,
                vertex: end_vertex,
                index: n,
            };
            (g, g)
        };
        // Right side: r narrows the funnel when it is left of (or on) apex→right.
        if same(&r, &apex) || same(&r, &right) {
            right = r;
        } else if cross2(apex.pos, right.pos, r.pos) >= 0.0 || same(&apex, &right) {
            if same(&apex, &right) || same(&apex, &left) || cross2(apex.pos, left.pos, r.pos) < 0.0
            {
                right = r;
            } else {
                // r passes over the left side: the path bends at the left point.
                path.push(left);
                apex = left;
                right = apex;
                i = apex.index + 1;
                continue;
            }
        }
        // Left side: l narrows the funnel when it is right of (or on) apex→left.
        if same(&l, &apex) || same(&l, &left) || same(&l, &right) {
            // (l == right only at the goal, where the portal is a single point.)
            left = l;
        } else if cross2(apex.pos, left.pos, l.pos) <= 0.0 || same(&apex, &left) {
            if same(&apex, &left) || same(&apex, &right) || cross2(apex.pos, right.pos, l.pos) > 0.0
            {
                left = l;
            } else {
                path.push(right);
                apex = right;
                left = apex;
                i = apex.index + 1;
                continue;
            }
        }
        i += 1;
    }
    path.push(Apex {
        pos: goal,
        vertex: end_vertex,
        index: n,
    });
    path
}

/// Length of a funnel path and its first and second derivatives with respect to the
/// anchor parameter, given how the start and goal move (`ds`, `dg` per unit parameter),
/// the path's bend points held still. A segment of length `d` whose end moves by `v`
/// turns, and its length's second derivative is `(|v|² − (e·v)²) / d` (`e` its unit
/// direction); the second derivative is 0 where an end segment has no length.
pub(super) fn length_and_slope(path: &[Apex], ds: [f64; 2], dg: [f64; 2]) -> (f64, f64, f64) {
    let length: f64 = path.windows(2).map(|w| dist2(w[0].pos, w[1].pos)).sum();
    let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
    // The unit vector from b to a, the length of that segment.
    let unit = |a: [f64; 2], b: [f64; 2]| {
        let d = dist2(a, b);
        if d > 0.0 {
            ([(a[0] - b[0]) / d, (a[1] - b[1]) / d], d)
        } else {
            ([0.0, 0.0], 0.0)
        }
    };
    // The second derivative of a segment's length whose end moves by `v`.
    let bend = |(e, d): ([f64; 2], f64), v: [f64; 2]| {
        if d > 0.0 {
            (dot(v, v) - dot(e, v) * dot(e, v)).max(0.0) / d
        } else {
            0.0
        }
    };
    // Bend points at the same place as an end do not count.
    let (s, g) = (path[0].pos, path[path.len() - 1].pos);
    let inner: Vec<[f64; 2]> = path[1..path.len() - 1]
        .iter()
        .map(|a| a.pos)
        .filter(|&p| p != s && p != g)
        .collect();
    let k = inner.len() + 2;
    let (slope, curvature) = if k == 2 {
        let e = unit(g, s);
        let w = [dg[0] - ds[0], dg[1] - ds[1]];
        (dot(e.0, w), bend(e, w))
    } else {
        let a = unit(s, inner[0]);
        let b = unit(g, inner[k - 3]);
        (dot(a.0, ds) + dot(b.0, dg), bend(a, ds) + bend(b, dg))
    };
    (length, slope, curvature)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn portal(left: [f64; 2], right: [f64; 2], lv: u32, rv: u32) -> Portal2 {
        Portal2 {
            left,
            right,
            lv,
            rv,
        }
    }

    /// A straight corridor: portals x = 0, 1, 2, 3 from y = 0 to y = 1.
    fn corridor() -> Vec<Portal2> {
        (0..4)
            .map(|i| {
                let x = f64::from(i);
                portal([x, 1.0], [x, 0.0], 2 * i as u32, 2 * i as u32 + 1)
            })
            .collect()
    }

    #[test]
    fn the_funnel_goes_straight_through_a_straight_corridor() {
        let portals = corridor();
        let path = funnel([0.0, 0.5], [3.0, 0.5], &portals, None);
        assert_eq!(path.len(), 2, "{path:?}");
        let (length, slope, _) = length_and_slope(&path, [0.0, -1.0], [0.0, -1.0]);
        assert!((length - 3.0).abs() < 1e-15);
        // Moving both ends the same way leaves the length unchanged.
        assert!(slope.abs() < 1e-15);
        // A diagonal from corner to corner stays straight too: √(3² + 1²).
        let path = funnel([0.0, 0.0], [3.0, 1.0], &portals, None);
        assert_eq!(path.len(), 2, "{path:?}");
        let (length, _, _) = length_and_slope(&path, [0.0, -1.0], [0.0, -1.0]);
        assert!((length - 10f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn the_funnel_bends_round_the_corner_of_a_dog_leg() {
        // The middle portal only opens above y = 1: the path from (0, 0) to (2, 0)
        // bends at its lower end (1, 1), the portal's right vertex 11.
        let portals = vec![
            portal([0.0, 1.0], [0.0, -1.0], 0, 1),
            portal([1.0, 2.0], [1.0, 1.0], 10, 11),
            portal([2.0, 1.0], [2.0, -1.0], 20, 21),
        ];
        let path = funnel([0.0, 0.0], [2.0, 0.0], &portals, None);
        let bends: Vec<Option<u32>> = path.iter().map(|a| a.vertex).collect();
        assert_eq!(bends, [None, Some(11), None]);
        assert_eq!(path[1].pos, [1.0, 1.0]);
        let (length, slope, curvature) = length_and_slope(&path, [0.0, -2.0], [0.0, -2.0]);
        assert!((length - 2.0 * 2f64.sqrt()).abs() < 1e-15);
        // Lowering both ends by 2t lengthens both legs, L(t) = 2 √(1 + (1 + 2t)²):
        // L'(0) = 2 · 2 · (1/√2) = 2√2, and L''(0) = 2 (4/√2 − 4/(2√2)) = 2√2.
        assert!((slope - 2.0 * 2f64.sqrt()).abs() < 1e-12, "{slope}");
        assert!((curvature - 2.0 * 2f64.sqrt()).abs() < 1e-12, "{curvature}");
    }

    #[test]
    fn a_strip_of_a_unit_square_cylinder_unfolds_flat_and_closes() {
        // A cube-shaped tube of four unit squares around the z axis (no caps), each
        // square split into two triangles; the strip goes once around at mid-height
        // through the four vertical edges and the four diagonals.
        let ring = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let mut positions = Vec::new();
        for z in [0.0, 1.0] {
            for p in ring {
                positions.push([p[0], p[1], z]);
            }
        }
        let mut triangles = Vec::new();
        for i in 0..4u32 {
            let j = (i + 1) % 4;
            triangles.push([i, j, j + 4]);
            triangles.push([i, j + 4, i + 4]);
        }
        let mesh = crate::mesh::SurfaceMesh::new(positions, triangles).unwrap();
        let topology = crate::mesh::Topology::new(&mesh);
        let geometry = SurfaceGeometry::new(&mesh, &topology);
        let edge = |a: u32, b: u32| {
            topology
                .edges()
                .iter()
                .position(|e| *e == [a.min(b), a.max(b)])
                .unwrap() as u32
        };
        let mut portals = Vec::new();
        let mut faces = Vec::new();
        for i in 0..4u32 {
            let j = (i + 1) % 4;
            portals.push(edge(i, i + 4));
            faces.push(2 * i + 1);
            portals.push(edge(i, j + 4));
            faces.push(2 * i);
        }
        let strip = Strip {
            hint: vec![f64::NAN; portals.len()],
            portals,
            faces,
        };
        let unfolded = unfold(&geometry, &strip, 0).expect("a strip of an oriented surface");
        assert_eq!(unfolded.len(), 9);
        // Flat: the vertical edges land one unit apart, upright and unit long.
        let (first, last) = (unfolded[0], unfolded[8]);
        for p in [first, last] {
            assert!((dist2(p.left, p.right) - 1.0).abs() < 1e-14);
        }
        assert!((dist2(first.right, last.right) - 4.0).abs() < 1e-12);
        assert!((dist2(first.left, last.left) - 4.0).abs() < 1e-12);
        assert_eq!((last.lv, last.rv), (first.lv, first.rv));
        // Straight across: the loop at any height is 4 long.
        let path = funnel(
            lerp2(first.left, first.right, 0.5),
            lerp2(last.left, last.right, 0.5),
            &unfolded,
            None,
        );
        let (length, _, _) = length_and_slope(&path, [0.0; 2], [0.0; 2]);
        assert!((length - 4.0).abs() < 1e-12, "{length}");
    }
}
