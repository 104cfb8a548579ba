//! Bounding volume hierarchy over triangles, in flat arrays, with the exact
//! point–triangle distance, the nearest-triangle query and the nearest ray hit.
//!
//! The tree is built top-down. Each node's triangles are split where the surface-area
//! heuristic is lowest, the candidates being the boundaries of 16 bins of the centroids
//! along each axis: the split minimises `area(left box) · count(left) + area(right box) ·
//! count(right)`. On CAD models, whose long thin triangles have boxes much larger than
//! their centroids' spread, a split at the median made children whose boxes overlap,
//! and queries visited both. Where all centroids fall in one bin, and from depth
//! [`SAH_DEPTH`] on, the split is at the median of the centroids along the longest
//! axis, which halves the count; so the depth is below [`SAH_DEPTH`] + ⌈log₂(n /
//! LEAF_SIZE)⌉ + 1 (< 64 for any `u32` count), which bounds the fixed-size traversal
//! stacks below. Nodes split until they hold at most [`LEAF_SIZE`] triangles.
//! Triangles are stored reordered so that every node, leaf or not, owns a contiguous
//! range of them.

use crate::geom::{bounds, closest_on_triangle, cross, dot, norm, sub};

/// A node splits when it holds more triangles than this (leaves hold 4 to 8).
pub(super) const LEAF_SIZE: usize = 8;

/// Room for any traversal stack: depth + 1 entries are enough, and the depth is below
/// [`SAH_DEPTH`] + 31 for at most 2³² triangles.
pub(super) const STACK: usize = 64;

/// Levels split by the surface-area heuristic; deeper nodes split at the median.
const SAH_DEPTH: usize = 32;

/// Bins of the centroids per axis for the surface-area heuristic.
const SAH_BINS: usize = 16;

/// One node: its box, its triangle range, and its children if any.
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    /// Box minimum corner.
    pub lo: [f64; 3],
    /// Box maximum corner.
    pub hi: [f64; 3],
    /// Index of the first child (the second is `left + 1`); 0 for a leaf (the root is
    /// never a child, so 0 is free).
    pub left: u32,
    /// First triangle (in the reordered arrays).
    pub start: u32,
    /// One past the last triangle.
    pub end: u32,
}

impl Node {
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.left == 0
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    fn dist2(&self, p: [f64; 3]) -> f64 {
        let mut d2 = 0.0;
        for ((lo, hi), x) in self.lo.iter().zip(self.hi).zip(p) {
            let d = (lo - x).max(x - hi).max(0.0);
            d2 += d * d;
        }
        d2
    }

    /// Parameter interval `[t0, t1]` where the ray `o + t d` is in the box, clipped to
    /// `[0, t_max]`; `None` when empty. `inv` is `1 / d` componentwise (±∞ for 0).
    #[inline]
    pub(super) fn ray_interval(&self, o: [f64; 3], inv: [f64; 3], t_max: f64) -> Option<f64> {
        let mut t0 = 0.0f64;
        let mut t1 = t_max;
        for k in 0..3 {
            if inv[k].is_infinite() {
                // Parallel to the slab: always in it, or never. (The product below would
                // be 0 · ∞ = NaN for an origin on the slab's face, as on a grid of CAD
                // vertices, and lose the box.)
                if o[k] < self.lo[k] || o[k] > self.hi[k] {
                    return None;
                }
                continue;
            }
            let a = (self.lo[k] - o[k]) * inv[k];
            let b = (self.hi[k] - o[k]) * inv[k];
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        // Widen by a few ulps so that rounding never loses a hit on a box face.
        (t0 <= t1 * (1.0 + 4.0 * f64::EPSILON)).then_some(t0)
    }
}

/// The hierarchy and the triangles it holds, reordered.
#[derive(Debug, Clone, Default)]
pub(super) struct Bvh {
    /// Nodes; the root is node 0 (no nodes for no triangles).
    pub nodes: Vec<Node>,
    /// Triangle corners, in tree order.
    pub tris: Vec<[[f64; 3]; 3]>,
    /// The mesh face index of each triangle in tree order.
    pub faces: Vec<u32>,
}

impl Bvh {
    /// The diagonal of the root's box (0 for no triangles).
    pub fn diagonal(&self) -> f64 {
        self.nodes.first().map_or(0.0, |n| norm(sub(n.hi, n.lo)))
    }

    /// Build over `tris` (corners) with their mesh face indices `faces`. The top of the
    /// tree, where a node holds more than [`PARALLEL_SPLIT`] triangles, builds its two
    /// halves at the same time; the tree is the same whatever the thread count.
    pub fn build(tris: Vec<[[f64; 3]; 3]>, faces: Vec<u32>) -> Bvh {
        use rayon::prelude::*;
        let n = tris.len();
        if n == 0 {
            return Bvh::default();
        }
        // Each triangle's corners and face side by side: the splits move these and
        // read nothing else, so the build streams through memory.
        let mut items: Vec<Item> = tris
            .into_par_iter()
            .zip(faces)
            .map(|(corners, face)| Item { corners, face })
            .collect();
        let nodes = subtree(&mut items, 0, 0);
        let (tris_sorted, faces_sorted) = items
            .into_par_iter()
            .map(|it| (it.corners, it.face))
            .unzip();
        Bvh {
            nodes,
            tris: tris_sorted,
            faces: faces_sorted,
        }
    }

    /// The triangle (tree-order index) nearest to `p`, the closest point on it and the
    /// squared distance; `None` when there is no triangle or nothing is finitely near.
    pub fn nearest(&self, p: [f64; 3]) -> Option<(usize, [f64; 3], f64)> {
        self.nearest_within(p, f64::INFINITY)
    }

    /// Like [`Bvh::nearest`], but only triangles closer than `sqrt(limit2)` count; far
    /// queries then prune almost the whole tree.
    pub fn nearest_within(&self, p: [f64; 3], limit2: f64) -> Option<(usize, [f64; 3], f64)> {
        let root = self.nodes.first()?;
        let mut best = limit2;
        let mut found: Option<(usize, [f64; 3])> = None;
        let mut stack = [(0u32, 0.0f64); STACK];
        stack[0] = (0, root.dist2(p));
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (ni, bound) = stack[sp];
            if bound >= best {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.is_leaf() {
                for t in node.start as usize..node.end as usize {
                    let [a, b, c] = self.tris[t];
                    let q = closest_on_triangle(p, a, b, c);
                    let d = sub(p, q);
                    let d2 = dot(d, d);
                    if d2 < best {
                        best = d2;
                        found = Some((t, q));
                    }
                }
            } else {
                let l = node.left;
                let r = l + 1;
                let dl = self.nodes[l as usize].dist2(p);
                let dr = self.nodes[r as usize].dist2(p);
                // Push the farther child first so that the nearer one is visited first.
                let pairs = if dl <= dr {
                    [(r, dr), (l, dl)]
                } else {
                    [(l, dl), (r, dr)]
                };
                for (c, d) in pairs {
                    if d < best {
                        stack[sp] = (c, d);
                        sp += 1;
                    }
                }
            }
        }
        found.map(|(t, q)| (t, q, best))
    }

    /// The tree-order indices of the triangles whose bounding boxes meet the box
    /// `[lo, hi]` (a superset of the triangles that meet the box), appended to `out`.
    pub fn overlapping(&self, lo: [f64; 3], hi: [f64; 3], out: &mut Vec<usize>) {
        let Some(root) = self.nodes.first() else {
            return;
        };
        let meets = |n: &Node| (0..3).all(|k| n.lo[k] <= hi[k] && lo[k] <= n.hi[k]);
        if !meets(root) {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if node.is_leaf() {
                for t in node.start as usize..node.end as usize {
                    let (tlo, thi) = bounds(self.tris[t]);
                    if (0..3).all(|k| tlo[k] <= hi[k] && lo[k] <= thi[k]) {
                        out.push(t);
                    }
                }
            } else {
                for c in [node.left, node.left + 1] {
                    if meets(&self.nodes[c as usize]) {
                        stack[sp] = c;
                        sp += 1;
                    }
                }
            }
        }
    }

    /// Nearest hit `t` in `(t_min, t_max]` of the ray `o + t d`, with its tree-order
    /// triangle index.
    pub fn ray(&self, o: [f64; 3], d: [f64; 3], t_min: f64, t_max: f64) -> Option<(f64, usize)> {
        let root = self.nodes.first()?;
        let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
        let mut best = t_max;
        let mut hit = None;
        let mut stack = [(0u32, 0.0f64); STACK];
        stack[0] = (0, root.ray_interval(o, inv, best)?);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (ni, t_enter) = stack[sp];
            if t_enter > best {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.is_leaf() {
                for t in node.start as usize..node.end as usize {
                    let [a, b, c] = self.tris[t];
                    if let Some(th) = ray_triangle(o, d, a, b, c) {
                        if th > t_min && th <= best && (hit.is_none() || th < best) {
                            best = th;
                            hit = Some((th, t));
                        }
                    }
                }
            } else {
                let l = node.left;
                let r = l + 1;
                let tl = self.nodes[l as usize].ray_interval(o, inv, best);
                let tr = self.nodes[r as usize].ray_interval(o, inv, best);
                let pairs = match (tl, tr) {
                    (Some(a), Some(b)) if a <= b => [Some((r, b)), Some((l, a))],
                    (Some(a), Some(b)) => [Some((l, a)), Some((r, b))],
                    (a, b) => [a.map(|a| (l, a)), b.map(|b| (r, b))],
                };
                for (c, t) in pairs.into_iter().flatten() {
                    stack[sp] = (c, t);
                    sp += 1;
                }
            }
        }
        hit
    }
}

/// A node holding more triangles than this builds its two halves at the same time.
const PARALLEL_SPLIT: usize = 1 << 15;

/// A triangle while the tree is built: its corners and its mesh face.
#[derive(Clone, Copy)]
struct Item {
    corners: [[f64; 3]; 3],
    face: u32,
}

impl Item {
    fn centroid(&self) -> [f64; 3] {
        [0, 1, 2].map(|axis| self.centroid_on(axis))
    }

    /// One coordinate of the centroid (as `scale(add(add(a, b), c), 1 / 3)` computes it).
    fn centroid_on(&self, axis: usize) -> f64 {
        let [a, b, c] = self.corners;
        (a[axis] + b[axis] + c[axis]) * (1.0 / 3.0)
    }
}

/// The bounds of some items' corners.
fn item_bounds(items: &[Item]) -> ([f64; 3], [f64; 3]) {
    bounds(items.iter().flat_map(|it| it.corners))
}

/// The nodes of the subtree over `items` (the first is number `offset` in tree order),
/// with its root at index 0 and children indexed within the returned nodes. `items` is
/// left in tree order.
fn subtree(items: &mut [Item], offset: usize, depth: usize) -> Vec<Node> {
    let n = items.len();
    if n <= PARALLEL_SPLIT {
        return sequential_subtree(items, offset, depth);
    }
    let (lo, hi) = item_bounds(items);
    let mid = split(items, depth);
    let (first, second) = items.split_at_mut(mid);
    let (left, right) = rayon::join(
        || subtree(first, offset, depth + 1),
        || subtree(second, offset + mid, depth + 1),
    );
    // The root, its two children, the rest of the left subtree, the rest of the right.
    let (nl, nr) = (left.len(), right.len());
    let mut nodes = Vec::with_capacity(1 + nl + nr);
    nodes.push(Node {
        lo,
        hi,
        left: 1,
        start: offset as u32,
        end: (offset + n) as u32,
    });
    // A child's index j > 0 in its own subtree moves to j + 2 (left) or j + nl + 1
    // (right); its root moves to 1 (left) or 2 (right).
    let moved = |node: &Node, shift: usize| Node {
        left: if node.is_leaf() {
            0
        } else {
            node.left + shift as u32
        },
        ..*node
    };
    nodes.push(moved(&left[0], 2));
    nodes.push(moved(&right[0], nl + 1));
    nodes.extend(left[1..].iter().map(|node| moved(node, 2)));
    nodes.extend(right[1..].iter().map(|node| moved(node, nl + 1)));
    nodes
}

/// [`subtree`] on one thread: nodes in the order they are split (depth first).
fn sequential_subtree(items: &mut [Item], offset: usize, depth: usize) -> Vec<Node> {
    let mut nodes = vec![Node {
        lo: [0.0; 3],
        hi: [0.0; 3],
        left: 0,
        start: 0,
        end: items.len() as u32,
    }];
    let mut todo = vec![(0usize, depth)];
    while let Some((ni, depth)) = todo.pop() {
        let (s, e) = (nodes[ni].start as usize, nodes[ni].end as usize);
        let (lo, hi) = item_bounds(&items[s..e]);
        nodes[ni].lo = lo;
        nodes[ni].hi = hi;
        if e - s <= LEAF_SIZE {
            continue;
        }
        let mid = s + split(&mut items[s..e], depth);
        let left = nodes.len();
        for (start, end) in [(s, mid), (mid, e)] {
            nodes.push(Node {
                lo: [0.0; 3],
                hi: [0.0; 3],
                left: 0,
                start: start as u32,
                end: end as u32,
            });
        }
        nodes[ni].left = left as u32;
        todo.push((left, depth + 1));
        todo.push((left + 1, depth + 1));
    }
    for node in &mut nodes {
        node.start += offset as u32;
        node.end += offset as u32;
    }
    nodes
}

/// Split `items` (a node's triangles, more than one) at `depth` in the tree: where the
/// surface-area heuristic is lowest, else at the median (see the module doc). Returns
/// the first index of the second part; both parts are non-empty.
fn split(items: &mut [Item], depth: usize) -> usize {
    let (clo, chi) = bounds(items.iter().map(Item::centroid));
    let ext = sub(chi, clo);
    if depth < SAH_DEPTH {
        if let Some((axis, last)) = sah_split(items, clo, ext) {
            let bin = |it: &Item| bin_of(it.centroid_on(axis), clo[axis], ext[axis]);
            // Two-pointer partition: bins up to `last` first.
            let (mut i, mut j) = (0, items.len());
            while i < j {
                if bin(&items[i]) <= last {
                    i += 1;
                } else {
                    j -= 1;
                    items.swap(i, j);
                }
            }
            return i;
        }
    }
    let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] {
        0
    } else if ext[1] >= ext[2] {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    // Ties (and equal centroids) split by position, which still halves.
    items.select_nth_unstable_by(mid, |a, b| {
        a.centroid_on(axis).total_cmp(&b.centroid_on(axis))
    });
    mid
}

/// The bin of a centroid coordinate `c` along an axis whose centroids span `[lo, lo +
/// ext]` (`ext > 0`).
#[inline]
fn bin_of(c: f64, lo: f64, ext: f64) -> usize {
    (((c - lo) / ext * SAH_BINS as f64) as usize).min(SAH_BINS - 1)
}

/// Half the surface area of a box.
fn half_area(lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let d = sub(hi, lo);
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// The axis and the last bin of the first part of the cheapest split by the
/// surface-area heuristic over [`SAH_BINS`] bins of the centroids per axis; `None`
/// where no axis has two non-empty parts.
fn sah_split(items: &[Item], clo: [f64; 3], ext: [f64; 3]) -> Option<(usize, usize)> {
    let usable = ext.map(|e| e > 0.0 && e.is_finite());
    let empty = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    // Every axis's bins in one pass: each triangle's box is taken once.
    let mut count = [[0usize; SAH_BINS]; 3];
    let mut boxes = [[empty; SAH_BINS]; 3];
    for it in items {
        let (lo, hi) = bounds(it.corners);
        for axis in 0..3 {
            if !usable[axis] {
                continue;
            }
            let b = bin_of(it.centroid_on(axis), clo[axis], ext[axis]);
            count[axis][b] += 1;
            let (blo, bhi) = &mut boxes[axis][b];
            for k in 0..3 {
                blo[k] = blo[k].min(lo[k]);
                bhi[k] = bhi[k].max(hi[k]);
            }
        }
    }
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if !usable[axis] {
            continue;
        }
        let (count, boxes) = (&count[axis], &boxes[axis]);
        // Cost of the parts left of each boundary, then of those right of it.
        let join = |a: ([f64; 3], [f64; 3]), b: &([f64; 3], [f64; 3])| {
            (
                [0, 1, 2].map(|k| a.0[k].min(b.0[k])),
                [0, 1, 2].map(|k| a.1[k].max(b.1[k])),
            )
        };
        let mut left_cost = [0.0; SAH_BINS];
        let mut left_count = [0usize; SAH_BINS];
        let (mut acc, mut n) = (empty, 0);
        for b in 0..SAH_BINS {
            acc = join(acc, &boxes[b]);
            n += count[b];
            left_count[b] = n;
            left_cost[b] = if n > 0 {
                half_area(acc.0, acc.1) * n as f64
            } else {
                0.0
            };
        }
        let (mut acc, mut n) = (empty, 0);
        for last in (0..SAH_BINS - 1).rev() {
            acc = join(acc, &boxes[last + 1]);
            n += count[last + 1];
            if n == 0 || left_count[last] == 0 {
                continue;
            }
            let cost = left_cost[last] + half_area(acc.0, acc.1) * n as f64;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, last));
            }
        }
    }
    best.map(|(_, axis, last)| (axis, last))
}

/// Whether two triangles cross: an edge of one passes through the interior of the
/// other, away from its ends and the other's sides by a relative margin (so triangles
/// that only touch, at a shared position or along a side, do not count). Coplanar
/// triangles never cross by this test.
pub(super) fn triangles_cross(t: &[[f64; 3]; 3], u: &[[f64; 3]; 3]) -> bool {
    let edge_through = |a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]| {
        (0..3).any(|i| segment_through(a[i], a[(i + 1) % 3], b))
    };
    edge_through(t, u) || edge_through(u, t)
}

/// Whether the segment `pq` passes through the inside of triangle `b` (Möller–Trumbore;
/// its ends, `b`'s edges and a segment in `b`'s plane do not count, with a margin of
/// 1e-9 on the parameters).
pub(super) fn segment_through(p: [f64; 3], q: [f64; 3], b: &[[f64; 3]; 3]) -> bool {
    const MARGIN: f64 = 1e-9;
    let d = sub(q, p);
    let (e1, e2) = (sub(b[1], b[0]), sub(b[2], b[0]));
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det == 0.0 || !det.is_finite() {
        return false;
    }
    let inv = 1.0 / det;
    let tv = sub(p, b[0]);
    let bu = dot(tv, pv) * inv;
    let qv = cross(tv, e1);
    let bv = dot(d, qv) * inv;
    let s = dot(e2, qv) * inv;
    bu > MARGIN && bv > MARGIN && bu + bv < 1.0 - MARGIN && s > MARGIN && s < 1.0 - MARGIN
}

/// Relative tolerance on the barycentric coordinates of a ray hit, so that a ray through
/// a shared edge or vertex is not lost between two triangles by rounding.
const BARY_TOL: f64 = 1e-10;

/// Ray–triangle intersection (Möller–Trumbore): the parameter `t` of the hit of
/// `o + t d` with the plane of `abc` when the hit lies in the triangle (up to
/// [`BARY_TOL`]); `None` for a parallel ray or a zero-area triangle.
#[inline]
fn ray_triangle(o: [f64; 3], d: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<f64> {
    let e1 = sub(b, a);
    let e2 = sub(c, a);
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = sub(o, a);
    let u = dot(tv, pv) * inv;
    if !(-BARY_TOL..=1.0 + BARY_TOL).contains(&u) {
        return None;
    }
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    if v < -BARY_TOL || u + v > 1.0 + BARY_TOL {
        return None;
    }
    let t = dot(e2, qv) * inv;
    t.is_finite().then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{add, scale};

    /// Small triangles scattered through a box by a fixed sequence (a linear
    /// congruential generator), more than one parallel split's worth.
    fn scattered(n: usize) -> Vec<[[f64; 3]; 3]> {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let p = [next(), 2.0 * next(), 0.5 * next()];
                [
                    p,
                    add(p, [0.01 * next(), 0.0, 0.0]),
                    add(p, [0.0, 0.01, 0.01]),
                ]
            })
            .collect()
    }

    /// The subtree at `a` of one layout equals the subtree at `b` of the other: the same
    /// boxes and triangle ranges, node by node.
    fn same_tree(x: &[Node], a: usize, y: &[Node], b: usize) {
        let (p, q) = (x[a], y[b]);
        assert_eq!((p.lo, p.hi, p.start, p.end), (q.lo, q.hi, q.start, q.end));
        assert_eq!(p.is_leaf(), q.is_leaf());
        if !p.is_leaf() {
            for k in 0..2 {
                same_tree(x, p.left as usize + k, y, q.left as usize + k);
            }
        }
    }

    /// The depth of the subtree at `a` (a leaf has depth 0).
    fn depth(nodes: &[Node], a: usize) -> usize {
        let n = nodes[a];
        if n.is_leaf() {
            0
        } else {
            1 + depth(nodes, n.left as usize).max(depth(nodes, n.left as usize + 1))
        }
    }

    #[test]
    fn geometric_spacing_keeps_the_tree_shallow_and_the_nearest_exact() {
        // Centroids at 2^-i: most of them in the first bin of every split, so the
        // surface-area heuristic cuts off a few at a time until the median takes over.
        let tris: Vec<[[f64; 3]; 3]> = (0..3000)
            .map(|i| {
                let x = (-(i as f64) / 40.0).exp2();
                [[x, 0.0, 0.0], [x, 1e-3 * x, 0.0], [x, 0.0, 1e-3 * x]]
            })
            .collect();
        let faces: Vec<u32> = (0..tris.len() as u32).collect();
        let bvh = Bvh::build(tris.clone(), faces);
        let d = depth(&bvh.nodes, 0);
        assert!(d < SAH_DEPTH + 12, "depth {d}");
        for q in [
            [0.5, 0.1, 0.0],
            [1e-6, 0.0, 1e-9],
            [-1.0, 0.0, 0.0],
            [0.03, -0.2, 0.1],
        ] {
            let (_, _, d2) = bvh.nearest(q).unwrap();
            let brute = tris
                .iter()
                .map(|&[a, b, c]| {
                    let e = sub(q, closest_on_triangle(q, a, b, c));
                    dot(e, e)
                })
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d2, brute);
        }
    }

    #[test]
    fn the_parallel_build_is_the_one_thread_tree() {
        let tris = scattered(3 * PARALLEL_SPLIT);
        let faces: Vec<u32> = (0..tris.len() as u32).collect();
        let bvh = Bvh::build(tris.clone(), faces);
        // The one-thread build of the whole: what `build` did before its top split.
        let mut items: Vec<Item> = tris
            .iter()
            .enumerate()
            .map(|(f, &corners)| Item {
                corners,
                face: f as u32,
            })
            .collect();
        let one_thread = sequential_subtree(&mut items, 0, 0);
        let order: Vec<u32> = items.iter().map(|it| it.face).collect();
        assert_eq!(bvh.faces, order);
        // The split compares centroids as the mesh code computes them.
        for it in &items {
            let [a, b, c] = it.corners;
            assert_eq!(it.centroid(), scale(add(add(a, b), c), 1.0 / 3.0));
        }
        assert_eq!(bvh.nodes.len(), one_thread.len());
        same_tree(&bvh.nodes, 0, &one_thread, 0);
        // Every node's box holds its triangles, and its children split its range.
        for node in &bvh.nodes {
            for t in &bvh.tris[node.start as usize..node.end as usize] {
                for c in t {
                    assert!((0..3).all(|k| node.lo[k] <= c[k] && c[k] <= node.hi[k]));
                }
            }
            if node.is_leaf() {
                assert!((node.end - node.start) as usize <= LEAF_SIZE);
            } else {
                let (l, r) = (
                    bvh.nodes[node.left as usize],
                    bvh.nodes[node.left as usize + 1],
                );
                assert_eq!((l.start, l.end, r.end), (node.start, r.start, node.end));
            }
        }
    }
}
