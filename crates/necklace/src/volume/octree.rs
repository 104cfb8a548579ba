//! A balanced octree of cubes on an integer grid: the grading of the background lattice.
//!
//! Coordinates are integers in *units* of half the smallest allowed cell, so cell
//! corners, centres and face centres of every cell are integer points. A cell is
//! `(origin, size)` with `size` a power of two ≥ 2 units. The tree is refined top-down by
//! a caller-supplied rule and then balanced: cells that touch (by a face, an edge or a
//! corner) differ in size by at most a factor of two.

use rustc_hash::FxHashSet as HashSet;

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
    #[cfg(test)]
    pub fn build(root: Cell, mut refine: impl FnMut(&[Cell]) -> Vec<bool>) -> Octree {
        Octree::build_unless(root, |cells| Some(refine(cells)))
            .expect("a refinement that never gives up builds a tree")
    }

    /// [`Octree::build`] where `refine` may give the tree up (`None`): then nothing is
    /// balanced and there is no tree.
    pub fn build_unless(
        root: Cell,
        mut refine: impl FnMut(&[Cell]) -> Option<Vec<bool>>,
    ) -> Option<Octree> {
        // The cells that are split; a cell is a leaf when its parent is split and it
        // is not.
        let mut split: HashSet<Cell> = HashSet::default();
        let mut level = vec![root];
        while !level.is_empty() {
            let decisions = refine(&level)?;
            let mut next = Vec::new();
            for (cell, decision) in level.into_iter().zip(decisions) {
                if decision && cell.size > 2 {
                    split.insert(cell);
                    next.extend(cell.children());
                }
            }
            level = next;
        }
        balance(root, &mut split);
        let mut leaves: HashSet<Cell> = HashSet::default();
        if split.contains(&root) {
            for cell in &split {
                for child in cell.children() {
                    if !split.contains(&child) {
                        leaves.insert(child);
                    }
                }
            }
        } else {
            leaves.insert(root);
        }
        Some(Octree { root, leaves })
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
        contains(self.root, p)
    }

    /// The leaf whose half-open cube contains `p`, if `p` is in the root.
    pub fn leaf_containing(&self, p: Key) -> Option<Cell> {
        self.leaf_containing_from(p, 2)
    }

    /// [`Octree::leaf_containing`] for a point next to a leaf of side `size`: the
    /// balanced tree's leaf there is most often as large, else half or twice as large,
    /// and those are looked up first.
    pub fn leaf_containing_near(&self, p: Key, size: i64) -> Option<Cell> {
        if !self.contains(p) {
            return None;
        }
        for s in [size, size / 2] {
            if s >= 2 && s <= self.root.size {
                let cell = cell_at(self.root, p, s);
                if self.leaves.contains(&cell) {
                    return Some(cell);
                }
            }
        }
        self.leaf_containing_from(p, 2 * size)
    }

    /// [`Octree::leaf_containing`] when the leaf is known to be at least `min_size`
    /// (fewer lookups: balanced neighbours are at least half a cell's size).
    pub fn leaf_containing_from(&self, p: Key, min_size: i64) -> Option<Cell> {
        if !self.contains(p) {
            return None;
        }
        let mut size = min_size.max(2);
        while size <= self.root.size {
            let cell = cell_at(self.root, p, size);
            if self.leaves.contains(&cell) {
                return Some(cell);
            }
            size *= 2;
        }
        None
    }
}

fn contains(root: Cell, p: Key) -> bool {
    (0..3).all(|k| p[k] >= root.origin[k] && p[k] < root.origin[k] + root.size)
}

/// The cell that `cell` is one of the eight children of (`None` for the root).
pub(crate) fn parent(root: Cell, cell: Cell) -> Option<Cell> {
    (cell.size < root.size).then(|| cell_at(root, cell.origin, 2 * cell.size))
}

/// The cell of side `size` (a power of two dividing the root's) that contains `p`.
fn cell_at(root: Cell, p: Key, size: i64) -> Cell {
    let origin = [0, 1, 2].map(|k| {
        let rel = p[k] - root.origin[k];
        root.origin[k] + rel.div_euclid(size) * size
    });
    Cell { origin, size }
}

/// Split cells until leaves that touch (across faces, edges and corners) differ in size
/// by at most a factor of two. Bottom-up by size: every leaf of side `s` needs the cells
/// of side `2s` around it to exist, i.e. their ancestors to be split. Splitting a cell
/// only makes leaves of side ≥ `2s`, which a later pass (a larger `s`) looks at, so one
/// sweep suffices, and each leaf costs a lookup per neighbour.
fn balance(root: Cell, split: &mut HashSet<Cell>) {
    if !split.contains(&root) {
        return;
    }
    // Parents of the leaves of side `s` have side `2s`; walk sizes upward.
    let mut size = 2;
    while size * 4 <= root.size {
        let mut parents: Vec<Cell> = split
            .iter()
            .filter(|c| c.size == 2 * size)
            .copied()
            .collect();
        parents.sort_unstable();
        let mut required: Vec<Cell> = Vec::new();
        for parent in parents {
            for leaf in parent.children() {
                if split.contains(&leaf) {
                    continue;
                }
                for probe in neighbour_probes(leaf) {
                    if !contains(root, probe) {
                        continue;
                    }
                    // The neighbour of side 2s must exist: its parent must be split.
                    let grand = cell_at(root, probe, 4 * size);
                    if !split.contains(&grand) {
                        required.push(grand);
                    }
                }
            }
        }
        required.sort_unstable();
        required.dedup();
        for cell in required {
            // Split the cell and its ancestors (which may be leaves themselves).
            let mut c = cell;
            while split.insert(c) && c.size < root.size {
                c = cell_at(root, c.origin, 2 * c.size);
            }
        }
        size *= 2;
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

    #[test]
    fn every_child_has_its_cell_for_parent() {
        let root = Cell {
            origin: [-8, 4, 0],
            size: 32,
        };
        assert_eq!(parent(root, root), None);
        let mut level = vec![root];
        while level[0].size > 2 {
            let next: Vec<Cell> = level.iter().flat_map(Cell::children).collect();
            for (i, child) in next.iter().enumerate() {
                assert_eq!(parent(root, *child), Some(level[i / 8]));
            }
            level = next;
        }
    }
}
