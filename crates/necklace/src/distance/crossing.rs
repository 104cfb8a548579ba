//! The winding number of a closed chain of triangles by counting crossings, exactly.
//!
//! Where every edge is used as often in one direction as in the other (a closed
//! chain, [`SurfaceDistance::use_pseudonormal_sign`](super::SurfaceDistance::use_pseudonormal_sign)
//! finds it), the winding number is an integer off the surface that changes by one
//! across a triangle. It is 0 outside the tree's box, so at `p` it is the signed count
//! of the triangles a segment from `p` to a point `q` beyond the box passes through:
//! +1 for a triangle `p` lies behind (entering the solid, seen from `q`), −1 for one it
//! lies in front of. On an input whose parts overlap or cross, the fast winding number
//! sums exact solid angles over every triangle near the query, hundreds at a lattice
//! point near the crossings; the count visits the leaves along one segment.
//!
//! The tests are Shewchuk's exact orientation predicates (the `robust` crate):
//! `orient3d(a, b, c, p)` for the side of `p`, and the three orientations of the
//! segment with the triangle's sides for whether it passes through the triangle. A
//! segment through a side or a corner of a triangle, or from a point on its plane
//! inside it, is *degenerate*: the count is not taken along it. The segment heads out
//! of the box by its nearest face, tilted off the axis so that faces and edges aligned
//! with the axes (CAD parts, lattices) are never parallel to it; a degenerate segment
//! is replaced by the one through the next nearest face, and after three
//! [`winding_by_crossings`] gives up (`None`: the caller takes the fast winding
//! number). Triangles whose corners lie on a line add nothing (no solid angle) and are
//! skipped, and so are triangles in whose plane the whole segment lies: where such a
//! segment leaves the plane it passes along a side of a neighbour, which is degenerate.
//!
//! Entry point: [`winding_by_crossings`].

use robust::{orient3d, Coord3D};

use super::bvh::{Bvh, STACK};

/// The tilt of the segments off their axis, in the other two coordinates (fixed
/// values no CAD model aligns with).
const TILT: [f64; 2] = [0.123_456_7, 0.076_543_2];

/// How many directions are tried before giving up on a query.
const ATTEMPTS: usize = 3;

/// The winding number at `p` of the closed chain of triangles in `bvh`, by the signed
/// count of crossings along a segment out of the tree's box; `None` where every
/// segment tried is degenerate (through a side or a corner, or `p` on a triangle) or
/// `p` is not finite. Exact: the same answer from any of the segments.
pub(super) fn winding_by_crossings(bvh: &Bvh, p: [f64; 3]) -> Option<i32> {
    if !p.iter().all(|c| c.is_finite()) {
        return None;
    }
    let Some(root) = bvh.nodes.first() else {
        return Some(0);
    };
    // The six ways out (axis, sense), nearest face first; ties by index.
    let mut exits: [(f64, usize); 6] = std::array::from_fn(|i| {
        let (axis, up) = (i / 2, i % 2 == 0);
        let gap = if up {
            root.hi[axis] - p[axis]
        } else {
            p[axis] - root.lo[axis]
        };
        (gap, i)
    });
    exits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let extent = (0..3).map(|k| root.hi[k] - root.lo[k]).fold(0.0, f64::max);
    let margin = 0.01 * extent + 1e-9 * p.iter().fold(1.0f64, |m, c| m.max(c.abs()));
    exits.iter().take(ATTEMPTS).find_map(|&(gap, i)| {
        let (axis, sign) = (i / 2, if i % 2 == 0 { 1.0 } else { -1.0 });
        // Along the axis the segment leaves the box; the tilt keeps it off the axis.
        let length = gap.max(0.0) + margin;
        let mut q = p;
        q[axis] += sign * length;
        q[(axis + 1) % 3] += TILT[0] * length;
        q[(axis + 2) % 3] += TILT[1] * length;
        count_along(bvh, p, q)
    })
}

/// The signed count of the triangles the segment `pq` passes through, `q` outside the
/// tree's box; `None` if the segment is degenerate for one of them.
fn count_along(bvh: &Bvh, p: [f64; 3], q: [f64; 3]) -> Option<i32> {
    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
    let mut count = 0;
    let mut stack = [0u32; STACK];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let node = &bvh.nodes[stack[sp] as usize];
        if node.ray_interval(p, inv, 1.0).is_none() {
            continue;
        }
        if node.is_leaf() {
            for tri in &bvh.tris[node.start as usize..node.end as usize] {
                count += crossing(p, q, tri)?;
            }
        } else {
            stack[sp] = node.left;
            stack[sp + 1] = node.left + 1;
            sp += 2;
        }
    }
    Some(count)
}

/// What the segment `pq` adds crossing triangle `tri`: +1 through it with `p` behind
/// it (the side opposite its normal `(b − a) × (c − a)`), −1 with `p` in front, 0 when
/// it misses it (or lies in its plane, or the triangle is a segment); `None` where it
/// passes through a side or a corner, or `p` or `q` lies on the triangle.
fn crossing(p: [f64; 3], q: [f64; 3], tri: &[[f64; 3]; 3]) -> Option<i32> {
    let point = |x: [f64; 3]| Coord3D {
        x: x[0],
        y: x[1],
        z: x[2],
    };
    let [a, b, c] = tri.map(point);
    let (pp, qq) = (point(p), point(q));
    // `robust` orients so that a point below the plane in which `a, b, c` turn
    // counter-clockwise, i.e. behind the triangle, gives a positive value.
    let side_p = orient3d(a, b, c, pp);
    let side_q = orient3d(a, b, c, qq);
    if side_p == 0.0 && side_q == 0.0 {
        // A triangle whose corners lie on a line, or a segment in the triangle's plane.
        return Some(0);
    }
    if side_p * side_q > 0.0 {
        return Some(0);
    }
    // The line pq against the three sides: all of one sign, it passes inside.
    let sides = [
        orient3d(pp, qq, a, b),
        orient3d(pp, qq, b, c),
        orient3d(pp, qq, c, a),
    ];
    let positive = sides.iter().any(|&s| s > 0.0);
    let negative = sides.iter().any(|&s| s < 0.0);
    if positive && negative {
        return Some(0);
    }
    if sides.contains(&0.0) || side_p == 0.0 || side_q == 0.0 {
        // Through a side or a corner, or from a point of the triangle's plane inside it.
        return None;
    }
    Some(if side_p > 0.0 { 1 } else { -1 })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 12 triangles of the box `lo..hi`, outward (counter-clockwise seen from
    /// outside), optionally reversed.
    fn cube(lo: [f64; 3], hi: [f64; 3], reversed: bool) -> Vec<[[f64; 3]; 3]> {
        let v = |i: usize| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        };
        let quads = [
            [0, 2, 3, 1], // z = lo
            [4, 5, 7, 6], // z = hi
            [0, 1, 5, 4], // y = lo
            [2, 6, 7, 3], // y = hi
            [0, 4, 6, 2], // x = lo
            [1, 3, 7, 5], // x = hi
        ];
        quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .map(|t| {
                let t = if reversed { [t[0], t[2], t[1]] } else { t };
                t.map(v)
            })
            .collect()
    }

    fn tree(tris: Vec<[[f64; 3]; 3]>) -> Bvh {
        let faces = (0..tris.len() as u32).collect();
        Bvh::build(tris, faces)
    }

    /// A fixed scatter of points in `lo..hi` (a linear congruential generator).
    fn scatter(n: usize, lo: f64, hi: f64) -> Vec<[f64; 3]> {
        let mut s: u64 = 12345;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    #[test]
    fn the_count_is_the_winding_number_of_overlapping_and_reversed_boxes() {
        // Two boxes that overlap (2 in the overlap) and a reversed one apart (−1).
        let mut tris = cube([0.0; 3], [2.0; 3], false);
        tris.extend(cube([1.0; 3], [3.0; 3], false));
        tris.extend(cube([4.0, 0.0, 0.0], [5.0, 1.0, 1.0], true));
        let bvh = tree(tris);
        let inside = |p: [f64; 3], lo: f64, hi: f64| (0..3).all(|k| p[k] > lo && p[k] < hi);
        for p in scatter(2000, -0.5, 5.5) {
            let expected = i32::from(inside(p, 0.0, 2.0)) + i32::from(inside(p, 1.0, 3.0))
                - i32::from(p[0] > 4.0 && p[0] < 5.0 && (1..3).all(|k| p[k] > 0.0 && p[k] < 1.0));
            assert_eq!(winding_by_crossings(&bvh, p), Some(expected), "at {p:?}");
        }
    }

    #[test]
    fn lattice_points_on_the_planes_of_axis_aligned_faces_are_counted() {
        // Points on the planes of the faces (outside the faces) and on the lines of
        // the edges: a segment along an axis would lie in those planes.
        let bvh = tree(cube([0.0; 3], [1.0; 3], false));
        for &x in &[-1.0, -0.5, 0.0, 0.5, 1.0, 1.5] {
            for &y in &[-0.5, 0.0, 0.25, 1.0, 1.5] {
                for &z in &[-0.5, 0.0, 0.75, 1.0, 1.5] {
                    let p = [x, y, z];
                    let on_box = (0..3).all(|k| (0.0..=1.0).contains(&p[k]))
                        && (0..3).any(|k| p[k] == 0.0 || p[k] == 1.0);
                    let got = winding_by_crossings(&bvh, p);
                    if on_box {
                        // On the surface the winding number is not defined.
                        continue;
                    }
                    let inside = (0..3).all(|k| p[k] > 0.0 && p[k] < 1.0);
                    assert_eq!(got, Some(i32::from(inside)), "at {p:?}");
                }
            }
        }
    }

    #[test]
    fn a_segment_through_a_corner_is_degenerate() {
        // A segment through a corner of the box passes through the corners of several
        // triangles: it is not counted along.
        let bvh = tree(cube([0.0; 3], [1.0; 3], false));
        let p = [0.5, 0.5, 0.5];
        let q = [-1.0, -1.0, -1.0]; // through (0, 0, 0): a corner.
        assert_eq!(count_along(&bvh, p, q), None);
        // And the entry point still answers, by another segment.
        assert_eq!(winding_by_crossings(&bvh, p), Some(1));
    }

    #[test]
    fn zero_area_triangles_and_no_triangles_add_nothing() {
        let mut tris = cube([0.0; 3], [1.0; 3], false);
        tris.push([[0.2, 0.2, 0.2], [0.4, 0.4, 0.4], [0.8, 0.8, 0.8]]);
        let bvh = tree(tris);
        assert_eq!(winding_by_crossings(&bvh, [0.3, 0.6, 0.4]), Some(1));
        assert_eq!(winding_by_crossings(&bvh, [1.3, 0.6, 0.4]), Some(0));
        assert_eq!(winding_by_crossings(&Bvh::default(), [0.0; 3]), Some(0));
        assert_eq!(winding_by_crossings(&bvh, [f64::NAN, 0.0, 0.0]), None);
    }
}
