//! Compressed sparse rows: for each of `n` keys, the items listed for it, in order.
//! The one adjacency list of the crate: vertex–face and vertex–edge lists of
//! [`Topology`](super::Topology), vertex–tet lists of `TetMesh`, and the mesher's stars.

/// Compressed lists: for each of `n` keys, the items pushed for it (in push order).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Csr {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Csr {
    /// The lists of `n` keys from `(key, item)` pairs (iterated twice: count, fill).
    pub fn new(n: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Csr {
        let mut start = vec![0u32; n + 1];
        for (k, _) in pairs.clone() {
            start[k as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[n] as usize];
        for (k, item) in pairs {
            items[fill[k as usize] as usize] = item;
            fill[k as usize] += 1;
        }
        Csr { start, items }
    }

    /// The items of key `k`.
    pub fn get(&self, k: usize) -> &[u32] {
        &self.items[self.start[k] as usize..self.start[k + 1] as usize]
    }
}
