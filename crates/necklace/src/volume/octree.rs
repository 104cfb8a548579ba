//! A balanced octree of cubes on an integer grid: the grading of the background lattice.
//!
//! Coordinates are integers in *units* of half the smallest allowed cell, so cell
//! corners, centres and face centres of every cell are integer points. A cell is
//! `(origin, size)` with `size` a power of two ≥ 2 units. The tree is refined top-down by
//! a caller-supplied rule and then balanced: cells that touch (by a face, an edge or a
//! corner) differ in size by at most a factor of two.

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};

/// An integer point in units.
pub(crate) type Key = [i64; 3];

/// A cube of the octree: lowest corner and side length, in units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct Cell {
    pub origin: Key,
    pub size: i64,
}

impl Cell {
    pub fn center(&self) -> Key {
        let h = self.size / 2;
        [self.origin[0] + h, self.origin[1] + h, self.origin[2] + h]
    }

    pub fn children(&self) -> [Cell; 8] {
        let h = self.size / 2;
        std::array::from_fn(|c| Cell {
            origin: [
                self.origin[0] + h * (c as i64 & 1),
                self.origin[1] + h * ((c as i64 >> 1) & 1),
                self.origin[2] + h * ((c as i64 >> 2) & 1),
            ],
            size: h,
        })
    }

    pub fn corner(&self, c: usize) -> Key {
        [
            self.origin[0] + self.size * (c as i64 & 1),
            self.origin[1] + self.size * ((c as i64 >> 1) & 1),
            self.origin[2] + self.size * ((c as i64 >> 2) & 1),
        ]
    }
}

/// The leaves of a balanced octree over a root cube.
pub(crate) struct Octree {
    pub root: Cell,
    leaves: HashSet<Cell>,
}

impl Octree {
    /// Refine from `root`, level by level: `refine` gets the cells of one level and says
    /// which to split (cells of size 2, the smallest, are never split). Then balance.
    pub fn build(root: Cell, mut refine: impl FnMut(&[Cell]) -> Vec<bool>) -> Octree {
        let mut leaves = HashSet::default();
        let mut level = vec![root];
        while !level.is_empty() {
            let split = refine(&level);
            let mut next = Vec::new();
            for (cell, split) in level.into_iter().zip(split) {
                if split && cell.size > 2 {
                    next.extend(cell.children());
                } else {
                    leaves.insert(cell);
                }
            }
            level = next;
        }
        let mut tree = Octree { root, leaves };
        tree.balance();
        tree
    }

    /// The leaves, sorted (deterministic order).
    pub fn leaves(&self) -> Vec<Cell> {
        let mut v: Vec<Cell> = self.leaves.iter().copied().collect();
        v.sort_unstable();
        v
    }

    /// Whether an integer point lies in the root cube (closed on the low side, open on
    /// the high side).
    pub fn contains(&self, p: Key) -> bool {
        (0..3).all(|k| p[k] >= self.root.origin[k] && p[k] < self.root.origin[k] + self.root.size)
    }

    /// The leaf whose half-open cube contains `p`, if `p` is in the root.
    pub fn leaf_containing(&self, p: Key) -> Option<Cell> {
        self.leaf_containing_from(p, 2)
    }

    /// [`Octree::leaf_containing`] when the leaf is known to be at least `min_size`
    /// (fewer lookups: balanced neighbours are at least half a cell's size).
    pub fn leaf_containing_from(&self, p: Key, min_size: i64) -> Option<Cell> {
        if !self.contains(p) {
            return None;
        }
        let mut size = min_size.max(2);
        while size <= self.root.size {
            let origin = [0, 1, 2].map(|k| {
                let rel = p[k] - self.root.origin[k];
                self.root.origin[k] + rel.div_euclid(size) * size
            });
            let cell = Cell { origin, size };
            if self.leaves.contains(&cell) {
                return Some(cell);
            }
            size *= 2;
        }
        None
    }

    /// Split leaves until neighbours (across faces, edges and corners) differ in size by
    /// at most a factor of two.
    fn balance(&mut self) {
        let mut queue: Vec<Cell> = self.leaves();
        while let Some(cell) = queue.pop() {
            if !self.leaves.contains(&cell) {
                continue;
            }
            for probe in neighbour_probes(cell) {
                // Only a neighbour larger than twice this cell matters.
                let Some(n) = self.leaf_containing_from(probe, 4 * cell.size) else {
                    continue;
                };
                if n.size > 2 * cell.size {
                    self.leaves.remove(&n);
                    for child in n.children() {
                        self.leaves.insert(child);
                        queue.push(child);
                    }
                    // The split may leave `cell` still too small next to a child; check again.
                    queue.push(cell);
                }
            }
        }
    }
}

/// One integer point just outside each of the 26 faces, edges and corners of a cell.
fn neighbour_probes(cell: Cell) -> impl Iterator<Item = Key> {
    let c = cell.center();
    let reach = cell.size / 2 + 1;
    (0..27).filter(|&i| i != 13).map(move |i| {
        let d = [i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1];
        [
            c[0] + d[0] * reach,
            c[1] + d[1] * reach,
            c[2] + d[2] * reach,
        ]
    })
}

/// Record the smallest required cell size at each cell that contains a sizing point, at
/// every level, so refinement can look it up per cell.
pub(crate) fn sizing_table(root: Cell, points: &[(Key, i64)]) -> HashMap<Cell, i64> {
    let mut table: HashMap<Cell, i64> = HashMap::default();
    for &(p, required) in points {
        let mut size = root.size;
        while size >= 2 {
            let origin = [0, 1, 2].map(|k| {
                let rel = p[k] - root.origin[k];
                root.origin[k] + rel.div_euclid(size) * size
            });
            let e = table.entry(Cell { origin, size }).or_insert(i64::MAX);
            *e = (*e).min(required);
            if size <= required {
                break;
            }
            size /= 2;
        }
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refining_one_corner_gives_a_balanced_tree() {
        let root = Cell {
            origin: [0, 0, 0],
            size: 64,
        };
        // Refine every cell that contains the origin corner, down to size 2.
        let tree = Octree::build(root, |cells| {
            cells.iter().map(|c| c.origin == [0, 0, 0]).collect()
        });
        let leaves = tree.leaves();
        let volume: i64 = leaves.iter().map(|c| c.size.pow(3)).sum();
        assert_eq!(volume, 64i64.pow(3), "leaves tile the root");
        for cell in &leaves {
            for probe in neighbour_probes(*cell) {
                if let Some(n) = tree.leaf_containing(probe) {
                    assert!(n.size <= 2 * cell.size && cell.size <= 2 * n.size);
                }
            }
        }
        assert_eq!(tree.leaf_containing([0, 0, 0]).unwrap().size, 2);
        assert_eq!(tree.leaf_containing([63, 63, 63]).unwrap().size, 32);
    }
}
