//! The background tetrahedralisation of a balanced octree: body-centred cubic (BCC)
//! tetrahedra where cells of equal size meet, and cones at transitions.
//!
//! Vertices are the octree's cell corners ("black" lattice points), cell centres ("red")
//! and, where needed, face centres. Where two leaves of the same size share a face, each
//! of the face's edges (split at a hanging midpoint when a smaller cell touches it) gives
//! one BCC tetrahedron joining the two centres to that edge (Labelle & Shewchuk, sec. 3;
//! bisected BCC tetrahedra at midpoints, sec. 5). Where the leaf across a face is larger,
//! smaller or missing (the root boundary), the cell is coned from its centre to the
//! face, fanned from the face centre (subdivided into four sub-faces when the other side
//! is finer), which both sides see identically, so the result is conforming.
//! Orientation is decided exactly on the integer coordinates.

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};

use super::octree::{Cell, Key, Octree};

/// Background tets over integer lattice points.
pub(crate) struct Background {
    /// Integer coordinates (units) of each vertex.
    pub keys: Vec<Key>,
    /// Positively oriented tets.
    pub tets: Vec<[u32; 4]>,
}

/// The four corners of face (`axis`, `side`) of a cell, in cyclic order.
fn face_corners(cell: &Cell, axis: usize, side: i64) -> [Key; 4] {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut base = cell.origin;
    if side > 0 {
        base[axis] += cell.size;
    }
    let at = |du: i64, dv: i64| {
        let mut p = base;
        p[u] += du * cell.size;
        p[v] += dv * cell.size;
        p
    };
    [at(0, 0), at(1, 0), at(1, 1), at(0, 1)]
}

fn midpoint(a: Key, b: Key) -> Key {
    [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2]
}

fn orient(p: [Key; 4]) -> i128 {
    let d = |a: Key, b: Key| {
        [
            (b[0] - a[0]) as i128,
            (b[1] - a[1]) as i128,
            (b[2] - a[2]) as i128,
        ]
    };
    let (u, v, w) = (d(p[0], p[1]), d(p[0], p[2]), d(p[0], p[3]));
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
}

/// A lattice point as the builder's tables hold it: [`Packed`] in one word where the
/// root is small enough, else the point itself.
trait PointKey: Copy + Eq + std::hash::Hash {
    fn of(k: Key) -> Self;
}

impl PointKey for Key {
    fn of(k: Key) -> Key {
        k
    }
}

/// A point of a root of less than [`PACKED_ROOT`] units a side, 21 bits an axis: a
/// third of a [`Key`]'s bytes in the corner and vertex tables, most of the lattice's
/// memory besides the tets.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Packed(u64);

/// Roots below this side (in units) have their points packed.
const PACKED_ROOT: i64 = 1 << 21;

impl PointKey for Packed {
    fn of(k: Key) -> Packed {
        debug_assert!(k.iter().all(|&c| (0..PACKED_ROOT).contains(&c)));
        Packed(k[0] as u64 | (k[1] as u64) << 21 | (k[2] as u64) << 42)
    }
}

struct Builder<'a, P> {
    tree: &'a Octree,
    dead: &'a dyn Fn(&Cell) -> bool,
    corners: HashSet<P>,
    index: HashMap<P, u32>,
    /// The vertices the current cell's tets have used, in front of `index`: a cell's
    /// tets (some eighteen, seventy tet corners) share about fifteen vertices, and the
    /// table is large.
    near: Vec<(P, u32)>,
    keys: Vec<Key>,
    tets: Vec<[u32; 4]>,
}

impl<P: PointKey> Builder<'_, P> {
    fn vertex(&mut self, k: Key) -> u32 {
        let p = P::of(k);
        if let Some(&(_, i)) = self.near.iter().find(|(q, _)| *q == p) {
            return i;
        }
        let i = match self.index.get(&p) {
            Some(&i) => i,
            None => {
                let i = self.keys.len() as u32;
                self.keys.push(k);
                self.index.insert(p, i);
                i
            }
        };
        self.near.push((p, i));
        i
    }

    fn tet(&mut self, mut p: [Key; 4]) {
        let o = orient(p);
        if o == 0 {
            return; // cannot happen for lattice tets; never emit a flat one
        }
        if o < 0 {
            p.swap(2, 3);
        }
        let t = p.map(|k| self.vertex(k));
        self.tets.push(t);
    }

    /// The points along edge a→b: the ends, and the midpoint if it is a cell corner
    /// (the points are the first `n` of the array).
    fn chain(&self, a: Key, b: Key) -> ([Key; 3], usize) {
        let m = midpoint(a, b);
        let even = (0..3).all(|k| (a[k] + b[k]) % 2 == 0);
        if even && m != a && self.corners.contains(&P::of(m)) {
            ([a, m, b], 3)
        } else {
            ([a, b, b], 2)
        }
    }

    /// Cone from `apex` to a square face (corners in cyclic order), fanned from its centre.
    fn cone(&mut self, apex: Key, quad: [Key; 4]) {
        let centre = midpoint(quad[0], quad[2]);
        for i in 0..4 {
            let (chain, n) = self.chain(quad[i], quad[(i + 1) % 4]);
            for w in chain[..n].windows(2) {
                self.tet([apex, centre, w[0], w[1]]);
            }
        }
    }

    fn cell(&mut self, cell: Cell) {
        self.near.clear();
        let c = cell.center();
        let dead = (self.dead)(&cell);
        for axis in 0..3 {
            for side in [-1i64, 1] {
                // A dead cell gives tets only towards a leaf of its size on its high
                // side (the leaf across gives those on its low side).
                if dead && side < 0 {
                    continue;
                }
                let quad = face_corners(&cell, axis, side);
                let mut probe = c;
                probe[axis] += side * (cell.size / 2 + 1);
                match self.tree.leaf_containing_near(probe, cell.size) {
                    Some(n) if n.size == cell.size => {
                        if side > 0 && !(dead && (self.dead)(&n)) {
                            let cn = n.center();
                            for i in 0..4 {
                                let (chain, k) = self.chain(quad[i], quad[(i + 1) % 4]);
                                for w in chain[..k].windows(2) {
                                    self.tet([c, cn, w[0], w[1]]);
                                }
                            }
                        }
                    }
                    _ if dead => {}
                    Some(n) if n.size < cell.size => {
                        // Finer cells across: cone to each of the four sub-faces.
                        let m = [0, 1, 2, 3].map(|i| midpoint(quad[i], quad[(i + 1) % 4]));
                        let centre = midpoint(quad[0], quad[2]);
                        for i in 0..4 {
                            let sub = [quad[i], m[i], centre, m[(i + 3) % 4]];
                            self.cone(c, sub);
                        }
                    }
                    _ => self.cone(c, quad),
                }
            }
        }
    }
}

/// What a balanced octree's leaves give, a little above the most measured (cow,
/// kitten, featuretype, bed, gears and Offset1, both sides): 1.05–1.31 distinct
/// corners per leaf, and per leaf not dead 2.9–3.7 vertices and 14.5–16.9 tets. The
/// tables are reserved for that many (more grow them).
const CORNERS_PER_THREE_LEAVES: usize = 4;
const VERTICES_PER_LIVE_LEAF: usize = 4;
const TETS_PER_LIVE_LEAF: usize = 18;

/// Tetrahedralise the leaves of a balanced octree, leaving out the tets that touch only
/// `dead` leaves (leaves known to lie wholly outside the region).
pub(crate) fn tetrahedralize(tree: &Octree, dead: &dyn Fn(&Cell) -> bool) -> Background {
    // The root's far corners are points too: they must stay below the packed range.
    let root = tree.root;
    if (0..3).all(|k| root.origin[k] >= 0 && root.origin[k] + root.size < PACKED_ROOT) {
        build::<Packed>(tree, dead)
    } else {
        build::<Key>(tree, dead)
    }
}

fn build<P: PointKey>(tree: &Octree, dead: &dyn Fn(&Cell) -> bool) -> Background {
    let leaves = tree.leaves();
    // Reserved for what the tree will hold, no more: a hash table's slots are touched
    // all over as it fills, so the slots reserved cost memory whether used or not.
    // Only the leaves not dead give vertices and tets.
    let live = leaves.iter().filter(|c| !dead(c)).count();
    let mut corners = HashSet::with_capacity_and_hasher(
        leaves.len() * CORNERS_PER_THREE_LEAVES / 3,
        Default::default(),
    );
    for cell in &leaves {
        for c in 0..8 {
            corners.insert(P::of(cell.corner(c)));
        }
    }
    let mut b = Builder {
        tree,
        dead,
        corners,
        index: HashMap::with_capacity_and_hasher(live * VERTICES_PER_LIVE_LEAF, Default::default()),
        near: Vec::new(),
        keys: Vec::new(),
        tets: Vec::with_capacity(live * TETS_PER_LIVE_LEAF),
    };
    for cell in leaves {
        b.cell(cell);
    }
    Background {
        keys: b.keys,
        tets: b.tets,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total_volume(b: &Background) -> i128 {
        b.tets
            .iter()
            .map(|t| orient(t.map(|v| b.keys[v as usize])))
            .sum()
    }

    /// Every interior face is shared by exactly two tets, boundary faces lie on the root.
    fn assert_conforming(b: &Background, root: Cell) {
        let mut faces: HashMap<[u32; 3], usize> = HashMap::default();
        for t in &b.tets {
            for skip in 0..4 {
                let mut f = [0u32; 3];
                let mut k = 0;
                for (i, &v) in t.iter().enumerate() {
                    if i != skip {
                        f[k] = v;
                        k += 1;
                    }
                }
                f.sort_unstable();
                *faces.entry(f).or_default() += 1;
            }
        }
        for (f, n) in faces {
            assert!(n <= 2, "face shared by {n} tets");
            if n == 1 {
                let on_root = (0..3).any(|k| {
                    let lo = root.origin[k];
                    let hi = root.origin[k] + root.size;
                    f.iter().all(|&v| b.keys[v as usize][k] == lo)
                        || f.iter().all(|&v| b.keys[v as usize][k] == hi)
                });
                assert!(on_root, "a hole inside the background mesh");
            }
        }
    }

    #[test]
    fn uniform_and_graded_trees_are_tiled_conformingly() {
        let root = Cell {
            origin: [0, 0, 0],
            size: 32,
        };
        for corner_refined in [false, true] {
            let tree = Octree::build(root, |cells| {
                cells
                    .iter()
                    .map(|c| {
                        if corner_refined {
                            c.origin == [0, 0, 0]
                        } else {
                            c.size > 8
                        }
                    })
                    .collect()
            });
            let b = tetrahedralize(&tree, &|_| false);
            assert_eq!(total_volume(&b), 6 * 32i128.pow(3), "volume of the root");
            assert_conforming(&b, root);
            // The tables' packed points give the very lattice the points themselves do.
            let dead = |c: &Cell| c.origin[0] >= 16;
            let (packed, plain) = (build::<Packed>(&tree, &dead), build::<Key>(&tree, &dead));
            assert!(packed.keys == plain.keys && packed.tets == plain.tets);
            assert!(!packed.tets.is_empty() && packed.tets.len() < b.tets.len());
        }
    }
}
