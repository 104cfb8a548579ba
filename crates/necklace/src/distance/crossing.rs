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
//!
//! A surface with holes is closed by cones ([`Closure`]): the edges used more often one
//! way than the other, reversed, fall into connected groups (each a union of cycles:
//! every vertex has as many such edges in as out), and each group is joined to one
//! apex, the mean of its vertices. The cones and the surface form a closed chain, whose
//! count at `p` is exact; the surface's winding number is that count less the cones'
//! own (winding numbers add over triangles), their fast winding number on a tree of
//! their own: small caps over the holes, far from most queries, where a few far-field
//! terms give it. Beyond [`MAX_CLOSURE`] such edges the caller keeps the fast winding
//! number.
//!
//! Most queries need no segment out of the box. The first query counts, once, the
//! chain's winding number at the corners of a lattice of *anchors* over the box
//! (at most [`MAX_ANCHOR_CELLS`] cells along its longest side, offset from the
//! box by fixed fractions so that no CAD plane holds them). The winding number at
//! `p` is then the count at the anchor nearest to it plus the signed count along the
//! short segment between them: counts are integers, so any path gives the same
//! answer, and the short segment meets a few triangles where the segment out of the
//! box meets dozens (on a model whose parts cross, 8.5 M queries of 44 triangles each;
//! figures in `docs/decisions.md`). Where that segment is degenerate, or the anchor's own
//! count was, the segment out of the box is taken.
//!
//! Entry points: [`Closure::new`], then [`winding_by_crossings`].

use robust::{orient3d, Coord3D};

use super::bvh::{Bvh, STACK};
use super::winding::{self, Expansion};
use crate::geom::add;

/// The most unbalanced edges closed by cones.
pub(super) const MAX_CLOSURE: usize = 1 << 16;

/// The cones that close a chain, on a tree with the fast winding number's expansions
/// (no triangles for a chain that closes), and the chain's counts at the anchors,
/// taken at the first query (most surfaces take every sign from their pseudonormals and
/// never ask).
#[derive(Debug, Clone, Default)]
pub(super) struct Closure {
    bvh: Bvh,
    expansions: Vec<Expansion>,
    anchors: std::sync::OnceLock<Anchors>,
}

impl Closure {
    /// The cones over the directed sides `missing` that a chain lacks
    /// ([`unbalanced_sides`](super::unbalanced_sides)): per connected group of sides,
    /// one triangle `(apex, a, b)` per side `a → b`, the apex the mean of the group's
    /// vertices. No triangles for no sides.
    pub(super) fn new(positions: &[[f64; 3]], missing: &[[u32; 2]]) -> Closure {
        if missing.is_empty() {
            return Closure::default();
        }
        // Groups by union–find over the sides' vertices, numbered in order of the
        // sides (deterministic).
        let mut vertices: Vec<u32> = missing.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let index = |v: u32| vertices.binary_search(&v).expect("a side's vertex");
        let mut parent: Vec<usize> = (0..vertices.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for &[a, b] in missing {
            let (ra, rb) = (root(&mut parent, index(a)), root(&mut parent, index(b)));
            parent[ra.max(rb)] = ra.min(rb);
        }
        let mut sum = vec![([0.0f64; 3], 0usize); vertices.len()];
        for (i, &v) in vertices.iter().enumerate() {
            let r = root(&mut parent, i);
            let p = positions[v as usize];
            sum[r].0 = add(sum[r].0, p);
            sum[r].1 += 1;
        }
        let tris: Vec<[[f64; 3]; 3]> = missing
            .iter()
            .map(|&[a, b]| {
                let (s, n) = sum[root(&mut parent, index(a))];
                let apex = s.map(|c| c / n as f64);
                [apex, positions[a as usize], positions[b as usize]]
            })
            .collect();
        let faces = (0..tris.len() as u32).collect();
        let bvh = Bvh::build(tris, faces);
        let expansions = winding::expansions(&bvh);
        Closure {
            bvh,
            expansions,
            anchors: std::sync::OnceLock::new(),
        }
    }

    /// Whether there is nothing to close: the triangles form a closed chain.
    pub(super) fn is_empty(&self) -> bool {
        self.bvh.tris.is_empty()
    }
}

/// The tilt of the segments off their axis, in the other two coordinates (fixed
/// values no CAD model aligns with).
const TILT: [f64; 2] = [0.123_456_7, 0.076_543_2];

/// How many directions are tried before giving up on a query.
const ATTEMPTS: usize = 3;

/// The most anchor cells along the longest side of the box (fewer for few
/// triangles: twice the cube root of their number).
pub(super) const MAX_ANCHOR_CELLS: usize = 64;

/// Where the anchors sit within their cells, in fractions of a cell per axis (fixed
/// values no CAD model aligns with).
const ANCHOR_OFFSET: [f64; 3] = [0.313_579_1, 0.264_137_9, 0.152_864_3];

/// The chain's winding number at the corners of a lattice over the tree's box:
/// `counts[(k · n[1] + j) · n[0] + i]` at `lo + ((i, j, k) + ANCHOR_OFFSET) · cell`,
/// `None` where the segment out of the box was degenerate. Empty for no triangles.
#[derive(Debug, Clone, Default)]
struct Anchors {
    lo: [f64; 3],
    cell: f64,
    n: [usize; 3],
    counts: Vec<Option<i32>>,
}

impl Anchors {
    /// The lattice over the box of `surface`, one more anchor than cells along each
    /// side (cubic cells, [`MAX_ANCHOR_CELLS`] or fewer along the longest side), and
    /// the count of `surface` and `cones` at each, by segments out of the box. On the
    /// calling thread: it runs inside a query, which may be one of a parallel loop's,
    /// and a thread that stole another query while this waited on its workers would
    /// wait for itself (a few tenths of a second at 64³ anchors).
    fn new(surface: &Bvh, cones: &Bvh) -> Anchors {
        let Some(root) = surface.nodes.first() else {
            return Anchors::default();
        };
        let extent: [f64; 3] = std::array::from_fn(|k| root.hi[k] - root.lo[k]);
        let longest = extent.iter().fold(0.0f64, |m, &e| m.max(e));
        if !(longest > 0.0 && longest.is_finite()) {
            return Anchors::default();
        }
        let wanted = (2.0 * (surface.tris.len() as f64).cbrt()).round() as usize;
        let cells = wanted.clamp(1, MAX_ANCHOR_CELLS);
        let cell = longest / cells as f64;
        // Each side's cells cover it with the offset anchors on both sides.
        let n: [usize; 3] = std::array::from_fn(|k| (extent[k] / cell).ceil() as usize + 2);
        let lo: [f64; 3] = std::array::from_fn(|k| root.lo[k] - cell);
        let mut anchors = Anchors {
            lo,
            cell,
            n,
            counts: Vec::new(),
        };
        anchors.counts = (0..n[0] * n[1] * n[2])
            .map(|i| chain_count(surface, cones, anchors.position(i)))
            .collect();
        anchors
    }

    /// Where anchor `i` sits.
    fn position(&self, i: usize) -> [f64; 3] {
        let index = [
            i % self.n[0],
            i / self.n[0] % self.n[1],
            i / (self.n[0] * self.n[1]),
        ];
        std::array::from_fn(|k| self.lo[k] + (index[k] as f64 + ANCHOR_OFFSET[k]) * self.cell)
    }

    /// The anchor nearest `p` with a count, and the count: `None` outside the
    /// lattice, or where that anchor's count was not taken.
    fn nearest(&self, p: [f64; 3]) -> Option<([f64; 3], i32)> {
        if self.counts.is_empty() {
            return None;
        }
        let mut i = 0;
        for k in (0..3).rev() {
            let x = ((p[k] - self.lo[k]) / self.cell - ANCHOR_OFFSET[k]).round();
            if !(x >= 0.0 && x < self.n[k] as f64) {
                return None;
            }
            i = i * self.n[k] + x as usize;
        }
        Some((self.position(i), self.counts[i]?))
    }
}

/// The winding number at `p` of the triangles in `bvh`, closed by `closure` (built for
/// those triangles: its anchors are counted on `bvh` at the first call): the
/// chain's count at the nearest anchor plus the signed count along the segment from
/// it, or else by a segment out of the tree's box; less the closure's fast winding
/// number. `None` where every segment tried is degenerate (through a side or a
/// corner, or `p` on a triangle) or `p` is not finite. Exact for a chain that closes
/// (an integer, the same from any of the segments).
pub(super) fn winding_by_crossings(bvh: &Bvh, closure: &Closure, p: [f64; 3]) -> Option<f64> {
    if !p.iter().all(|c| c.is_finite()) {
        return None;
    }
    let anchors = closure
        .anchors
        .get_or_init(|| Anchors::new(bvh, &closure.bvh));
    let from_anchor = anchors.nearest(p).and_then(|(a, count)| {
        // w(p) = w(a) + the count along p → a (+1 for each triangle p lies behind).
        Some(count + count_along(bvh, p, a)? + count_along(&closure.bvh, p, a)?)
    });
    let count = match from_anchor {
        Some(count) => count,
        None => chain_count(bvh, &closure.bvh, p)?,
    };
    let cones = winding::fast(&closure.bvh, &closure.expansions, p);
    Some(f64::from(count) - cones)
}

/// The winding number at `p` of the chain of the triangles in `bvh` and `cones`, by
/// the signed count along a segment out of `bvh`'s box (by its nearest face, tilted;
/// [`ATTEMPTS`] faces tried); `None` where each was degenerate. 0 for no triangles.
fn chain_count(bvh: &Bvh, cones: &Bvh, p: [f64; 3]) -> Option<i32> {
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
        Some(count_along(bvh, p, q)? + count_along(cones, p, q)?)
    })
}

/// The signed count of the triangles the segment `pq` passes through (+1 for each
/// `p` lies behind); `None` if the segment is degenerate for one of them.
fn count_along(bvh: &Bvh, p: [f64; 3], q: [f64; 3]) -> Option<i32> {
    if bvh.nodes.is_empty() {
        return Some(0);
    }
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

    /// The corners and the 12 triangles of the box `lo..hi`, outward
    /// (counter-clockwise seen from outside); corner bit 1 is +x, 2 is +y, 4 is +z.
    fn box_mesh(lo: [f64; 3], hi: [f64; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let corners = (0..8u32)
            .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 0 { lo[k] } else { hi[k] }))
            .collect();
        let sides: [[u32; 4]; 6] = [
            [0, 2, 3, 1], // z = lo
            [4, 5, 7, 6], // z = hi
            [0, 1, 5, 4], // y = lo
            [2, 6, 7, 3], // y = hi
            [0, 4, 6, 2], // x = lo
            [1, 3, 7, 5], // x = hi
        ];
        let triangles = sides
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (corners, triangles)
    }

    /// The box's triangles as corners, optionally reversed.
    fn cube(lo: [f64; 3], hi: [f64; 3], reversed: bool) -> Vec<[[f64; 3]; 3]> {
        let (corners, triangles) = box_mesh(lo, hi);
        triangles
            .iter()
            .map(|&t| {
                let t = if reversed { [t[0], t[2], t[1]] } else { t };
                t.map(|v| corners[v as usize])
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
        let anchored = Closure::default();
        assert!(anchored.is_empty());
        let inside = |p: [f64; 3], lo: f64, hi: f64| (0..3).all(|k| p[k] > lo && p[k] < hi);
        let mut from_anchors = 0;
        for p in scatter(2000, -0.5, 5.5) {
            let expected = i32::from(inside(p, 0.0, 2.0)) + i32::from(inside(p, 1.0, 3.0))
                - i32::from(p[0] > 4.0 && p[0] < 5.0 && (1..3).all(|k| p[k] > 0.0 && p[k] < 1.0));
            // Out of the box, and from the nearest anchor.
            assert_eq!(chain_count(&bvh, &Bvh::default(), p), Some(expected));
            assert_eq!(
                winding_by_crossings(&bvh, &anchored, p),
                Some(f64::from(expected)),
                "at {p:?}"
            );
            // Within the tree's box (0..5, 0..3, 0..3) every point has an anchor.
            let in_box = p[0] > 0.0 && p[0] < 5.0 && (1..3).all(|k| p[k] > 0.0 && p[k] < 3.0);
            let anchor = anchored.anchors.get().expect("counted").nearest(p);
            assert!(anchor.is_some() || !in_box, "no anchor at {p:?}");
            from_anchors += usize::from(anchor.is_some());
        }
        // Every anchor's count was taken.
        let counts = &anchored.anchors.get().expect("counted").counts;
        assert!(counts.iter().all(Option::is_some));
        assert!(from_anchors > 1000, "{from_anchors} points from anchors");
    }

    #[test]
    fn the_anchors_hold_the_winding_number_at_their_positions() {
        // Two nested boxes, the inner one reversed: 1 between them, 0 inside the
        // inner one and outside the outer one.
        let mut tris = cube([0.0; 3], [4.0; 3], false);
        tris.extend(cube([1.0; 3], [3.0; 3], true));
        let bvh = tree(tris);
        let anchors = Anchors::new(&bvh, &Bvh::default());
        assert_eq!(anchors.counts.len(), anchors.n.iter().product::<usize>());
        for (i, count) in anchors.counts.iter().enumerate() {
            let a = anchors.position(i);
            let within = |lo: f64, hi: f64| (0..3).all(|k| a[k] > lo && a[k] < hi);
            let expected = i32::from(within(0.0, 4.0)) - i32::from(within(1.0, 3.0));
            assert_eq!(*count, Some(expected), "at anchor {a:?}");
            // The nearest anchor to an anchor is itself.
            assert_eq!(anchors.nearest(a), Some((a, expected)));
        }
        // Beyond the lattice there is no anchor.
        assert_eq!(anchors.nearest([-10.0, 2.0, 2.0]), None);
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
                    let got = winding_by_crossings(&bvh, &Closure::default(), p);
                    if on_box {
                        // On the surface the winding number is not defined.
                        continue;
                    }
                    let inside = (0..3).all(|k| p[k] > 0.0 && p[k] < 1.0);
                    assert_eq!(got, Some(f64::from(u8::from(inside))), "at {p:?}");
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
        assert_eq!(
            winding_by_crossings(&bvh, &Closure::default(), p),
            Some(1.0)
        );
    }

    #[test]
    fn zero_area_triangles_and_no_triangles_add_nothing() {
        let mut tris = cube([0.0; 3], [1.0; 3], false);
        tris.push([[0.2, 0.2, 0.2], [0.4, 0.4, 0.4], [0.8, 0.8, 0.8]]);
        let bvh = tree(tris);
        assert_eq!(
            winding_by_crossings(&bvh, &Closure::default(), [0.3, 0.6, 0.4]),
            Some(1.0)
        );
        assert_eq!(
            winding_by_crossings(&bvh, &Closure::default(), [1.3, 0.6, 0.4]),
            Some(0.0)
        );
        assert_eq!(
            winding_by_crossings(&Bvh::default(), &Closure::default(), [0.0; 3]),
            Some(0.0)
        );
        assert_eq!(
            winding_by_crossings(&bvh, &Closure::default(), [f64::NAN, 0.0, 0.0]),
            None
        );
    }

    #[test]
    fn a_surface_with_holes_closed_by_cones_has_its_winding_number() {
        // A unit box without its top, and a smaller box apart without one side
        // triangle: the count less the cones' winding number is the sum of all the
        // triangles' solid angles.
        let (mut positions, mut triangles) = box_mesh([0.0; 3], [1.0; 3]);
        triangles.drain(2..4); // the top, z = 1
        let (corners, second) = box_mesh([2.0; 3], [2.5; 3]);
        positions.extend(corners);
        triangles.extend(
            second
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != 7)
                .map(|(_, t)| t.map(|v| v + 8)),
        );
        let missing = super::super::unbalanced_sides(&triangles);
        assert_eq!(missing.len(), 4 + 3);
        let tris: Vec<[[f64; 3]; 3]> = triangles
            .iter()
            .map(|t| t.map(|v| positions[v as usize]))
            .collect();
        let bvh = tree(tris);
        let closure = Closure::new(&positions, &missing);
        assert_eq!(closure.bvh.tris.len(), 7);
        for p in scatter(500, -0.5, 3.0) {
            let exact = super::super::winding::exact(&bvh, p);
            let counted = winding_by_crossings(&bvh, &closure, p).expect("a generic point");
            // The cones' part is the fast winding number (Barill et al.: a few 1e-3).
            assert!(
                (counted - exact).abs() < 1e-2,
                "at {p:?}: {counted} against {exact}"
            );
        }
    }
}
