//! Which cycles of the superlevel sweep are essential: the first cohomology over Z2 of
//! the complex the sweep covers, so that the noise cycles are paired away.
//!
//! The sweep ([`roles`](super::roles)) adds the interior vertices from the top down, the
//! outer sphere's vertices joined as one from the start; the surface's vertices are
//! never added. So it covers `X`: the full subcomplex on the interior vertices, with
//! the outer sphere coned off. `X` is the solid (inside) or the space around it
//! (outside) up to a collar, and its first Betti number is the surface's total genus.
//!
//! A cycle-closing saddle closes a cycle of the superlevel set. By the elder rule that
//! cycle lives for ever (is *essential*) exactly when its class in H₁(X; Z2) is
//! independent of the classes of the cycles closed before it; otherwise a 1-saddle
//! lower down fills it (it was noise, or a second copy of a cycle). The classes come
//! from a basis of 1-cocycles (edge values whose sum round every triangle of `X` is 0),
//! built once per mesh:
//! 1. a spanning forest of `X`'s edges, grown breadth-first from the outer sphere (then
//!    from the first unreached vertex of each other component), is set to 0, and so
//!    are the outer sphere's own edges (the cone);
//! 2. a triangle with one edge left unknown fixes it (the sum of its other two);
//!    where no triangle does, the lowest unknown edge becomes a free *parameter*
//!    (its value is a unit vector of Z2^P);
//! 3. every triangle's sum is then a linear relation among the parameters; the
//!    cocycles are the parameter values that satisfy them all.
//!
//! An edge's value is a vector of Z2^P; a cycle's is the sum over its edges, and its
//! class is that sum reduced modulo the relations (echelon form), read on the
//! parameters that lead no relation: [`Cocycles::rank`] coordinates, the dimension of
//! H¹(X; Z2). Entry point: [`Cocycles::new`]. Sequential and ordered by index: the
//! result does not depend on the thread count.

use std::collections::{HashMap, VecDeque};

use rayon::prelude::*;

use crate::mesh::Z2Basis;
use crate::tet::{TetMesh, VertexKind};

/// Edge values of a cocycle basis of `X` (see the module doc).
#[derive(Debug, Clone)]
pub struct Cocycles {
    /// Words per edge value (parameters ≤ 64 × words).
    words: usize,
    /// The distinct values of the edges of `X`, `words` words each, the zero value
    /// first (also the value of the slots whose edge is not in `X`).
    values: Vec<u64>,
    /// Per slot of the adjacency (`start`/`neighbours` of the sweep, both directions):
    /// the index of its edge's value in `values`. (Distinct values, not one per edge
    /// or per slot: the genus-1409 sponge's inside has 1.53 M edges of 23 words but
    /// 4897 distinct values, 81 % of the edges at zero; one per edge, they were most
    /// of the Morse stage's memory.)
    value_of_slot: Vec<u32>,
    /// The relations among the parameters, in echelon form.
    relations: Z2Basis,
    /// Parameters that lead no relation: the class coordinates.
    free: Vec<usize>,
    /// Free parameters taken where no triangle fixed an edge.
    pub parameters: usize,
}

/// How an edge's value was found.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// A free parameter (its index).
    Parameter(u32),
    /// The sum of the other two edges of this triangle.
    Triangle(u32),
}

/// Tets whose faces [`Cocycles::new`] writes in one piece of work.
const FACE_RUN: usize = 16_384;

/// Every edge's value (a parameter's unit vector, or the sum of the other two edges of
/// its triangle, in `order`; the gauge's edges 0) as the index of that value among the
/// distinct ones, and those values, `words` words each, the zero value first. Built a
/// word at a time, each edge's index refined by the pair (index so far, this word): the
/// values of all edges at once would take `edges × words` words (what this saves).
fn distinct_values(
    order: &[(u32, Source)],
    triangles: &[[u32; 3]],
    edges: usize,
    words: usize,
) -> (Vec<u64>, Vec<u32>) {
    let mut index = vec![0u32; edges];
    // Per word, the distinct pairs (index over the words before, this word); entry 0 is
    // the zero value's.
    let mut levels: Vec<Vec<(u32, u64)>> = Vec::with_capacity(words);
    let mut word = vec![0u64; edges];
    for w in 0..words {
        word.fill(0);
        for &(e, source) in order {
            let e = e as usize;
            match source {
                Source::Parameter(p) => {
                    if p as usize / 64 == w {
                        word[e] |= 1 << (p % 64);
                    }
                }
                Source::Triangle(t) => {
                    for &other in &triangles[t as usize] {
                        if other as usize != e {
                            word[e] ^= word[other as usize];
                        }
                    }
                }
            }
        }
        let mut level = vec![(0u32, 0u64)];
        let mut seen: HashMap<(u32, u64), u32> = HashMap::new();
        for (i, &x) in index.iter_mut().zip(&word) {
            let key = (*i, x);
            if key != (0, 0) {
                *i = *seen.entry(key).or_insert_with(|| {
                    level.push(key);
                    (level.len() - 1) as u32
                });
            }
        }
        levels.push(level);
    }
    // Each distinct value's words, read back along its pairs.
    let count = levels.last().map_or(1, Vec::len);
    let mut values = vec![0u64; count * words];
    for v in 0..count {
        let mut at = v as u32;
        for w in (0..words).rev() {
            let (before, x) = levels[w][at as usize];
            values[v * words + w] = x;
            at = before;
        }
    }
    (values, index)
}

impl Cocycles {
    /// The cocycle basis of `X` for `mesh`, whose vertex adjacency is `start` /
    /// `neighbours` (per vertex, its neighbours sorted).
    pub fn new(mesh: &TetMesh, start: &[usize], neighbours: &[u32]) -> Cocycles {
        let n = mesh.num_vertices();
        let in_x: Vec<bool> = mesh
            .kinds
            .iter()
            .map(|&k| k != VertexKind::Surface)
            .collect();
        let outer: Vec<bool> = mesh.kinds.iter().map(|&k| k == VertexKind::Outer).collect();

        // Edges of X, each once (from its lower end), numbered in slot order.
        let mut edge_of_slot = vec![u32::MAX; neighbours.len()];
        let mut ends: Vec<[u32; 2]> = Vec::new();
        for v in 0..n {
            if !in_x[v] {
                continue;
            }
            for s in start[v]..start[v + 1] {
                let u = neighbours[s] as usize;
                if u > v && in_x[u] {
                    edge_of_slot[s] = ends.len() as u32;
                    ends.push([v as u32, u as u32]);
                }
            }
        }
        let edge = |a: u32, b: u32| -> u32 {
            let (a, b) = (a.min(b) as usize, a.max(b));
            let list = &neighbours[start[a]..start[a + 1]];
            list.binary_search(&b)
                .map_or(u32::MAX, |i| edge_of_slot[start[a] + i])
        };

        // Triangles of X (faces of tets with three vertices in X), each once, as their
        // three edges: counted, written into one array of that length, sorted, shrunk
        // once the duplicates are gone and rewritten in place. (A parallel collect and
        // a second array held them several times over, the peak of a side's Morse
        // stage.)
        let faces_of = |t: &[u32; 4]| {
            [
                [t[0], t[1], t[2]],
                [t[0], t[1], t[3]],
                [t[0], t[2], t[3]],
                [t[1], t[2], t[3]],
            ]
            .into_iter()
            .filter(|f| f.iter().all(|&v| in_x[v as usize]))
            .map(|mut f| {
                f.sort_unstable();
                f
            })
        };
        let runs: Vec<&[[u32; 4]]> = mesh.tets.chunks(FACE_RUN).collect();
        let counts: Vec<usize> = runs
            .par_iter()
            .map(|run| run.iter().map(|t| faces_of(t).count()).sum())
            .collect();
        let mut triangles = vec![[0u32; 3]; counts.iter().sum()];
        let mut parts = Vec::with_capacity(runs.len());
        let mut rest = &mut triangles[..];
        for &count in &counts {
            let (part, tail) = rest.split_at_mut(count);
            parts.push(part);
            rest = tail;
        }
        parts.into_par_iter().zip(&runs).for_each(|(part, run)| {
            for (slot, f) in part.iter_mut().zip(run.iter().flat_map(faces_of)) {
                *slot = f;
            }
        });
        triangles.par_sort_unstable();
        triangles.dedup();
        triangles.shrink_to_fit();
        triangles
            .par_iter_mut()
            .for_each(|f| *f = [edge(f[0], f[1]), edge(f[0], f[2]), edge(f[1], f[2])]);

        // 1. The gauge: a spanning forest and the cone's edges are 0.
        let mut known = vec![false; ends.len()];
        for (e, &[a, b]) in ends.iter().enumerate() {
            known[e] = outer[a as usize] && outer[b as usize];
        }
        let mut reached = outer.clone();
        let mut queue: VecDeque<usize> = (0..n).filter(|&v| outer[v]).collect();
        let mut next_root = 0;
        loop {
            while let Some(v) = queue.pop_front() {
                for &u in &neighbours[start[v]..start[v + 1]] {
                    let u = u as usize;
                    if in_x[u] && !reached[u] {
                        reached[u] = true;
                        known[edge(v as u32, u as u32) as usize] = true;
                        queue.push_back(u);
                    }
                }
            }
            while next_root < n && (!in_x[next_root] || reached[next_root]) {
                next_root += 1;
            }
            if next_root == n {
                break;
            }
            reached[next_root] = true;
            queue.push_back(next_root);
        }

        // 2. Fix edges triangle by triangle; a parameter where none can.
        let mut incident_start = vec![0usize; ends.len() + 1];
        for t in &triangles {
            for &e in t {
                incident_start[e as usize + 1] += 1;
            }
        }
        for e in 0..ends.len() {
            incident_start[e + 1] += incident_start[e];
        }
        let mut incident = vec![0u32; incident_start[ends.len()]];
        let mut fill = incident_start.clone();
        for (i, t) in triangles.iter().enumerate() {
            for &e in t {
                incident[fill[e as usize]] = i as u32;
                fill[e as usize] += 1;
            }
        }
        drop(fill);
        let mut unknown: Vec<u8> = triangles
            .iter()
            .map(|t| t.iter().filter(|&&e| !known[e as usize]).count() as u8)
            .collect();
        let mut ready: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&t| unknown[t as usize] == 1)
            .collect();
        let mut order: Vec<(u32, Source)> = Vec::new();
        let mut parameters = 0u32;
        let mut next_free = 0;
        let mut settle = |e: u32,
                          source: Source,
                          known: &mut [bool],
                          unknown: &mut [u8],
                          ready: &mut Vec<u32>| {
            known[e as usize] = true;
            order.push((e, source));
            for &t in &incident[incident_start[e as usize]..incident_start[e as usize + 1]] {
                unknown[t as usize] -= 1;
                if unknown[t as usize] == 1 {
                    ready.push(t);
                }
            }
        };
        loop {
            while let Some(t) = ready.pop() {
                if unknown[t as usize] != 1 {
                    continue;
                }
                let Some(&e) = triangles[t as usize].iter().find(|&&e| !known[e as usize]) else {
                    continue;
                };
                settle(e, Source::Triangle(t), &mut known, &mut unknown, &mut ready);
            }
            while next_free < ends.len() && known[next_free] {
                next_free += 1;
            }
            if next_free == ends.len() {
                break;
            }
            settle(
                next_free as u32,
                Source::Parameter(parameters),
                &mut known,
                &mut unknown,
                &mut ready,
            );
            parameters += 1;
        }

        // The values, in the order they were found, each edge holding the index of its
        // value among the distinct ones.
        let words = (parameters as usize).div_ceil(64);
        let (values, value_of_edge) = distinct_values(&order, &triangles, ends.len(), words);

        // Per slot, from both ends: its edge's value, or the zero value (index 0).
        let mut value_of_slot = vec![0; if words > 0 { neighbours.len() } else { 0 }];
        if words > 0 {
            for v in 0..n {
                for s in start[v]..start[v + 1] {
                    let e = edge(v as u32, neighbours[s]);
                    if e != u32::MAX {
                        value_of_slot[s] = value_of_edge[e as usize];
                    }
                }
            }
        }

        // 3. Every triangle's sum is a relation among the parameters.
        let mut relations = Z2Basis::default();
        if words > 0 {
            let mut sum = vec![0u64; words];
            for t in &triangles {
                sum.fill(0);
                for &e in t {
                    let v = value_of_edge[e as usize] as usize;
                    for (x, v) in sum.iter_mut().zip(&values[v * words..]) {
                        *x ^= v;
                    }
                }
                if sum.iter().any(|&x| x != 0) {
                    relations.insert(&sum);
                }
            }
        }
        let mut leads = vec![false; parameters as usize];
        for lead in relations.leads() {
            leads[lead] = true;
        }
        let free = (0..parameters as usize).filter(|&p| !leads[p]).collect();
        Cocycles {
            words,
            values,
            value_of_slot,
            relations,
            free,
            parameters: parameters as usize,
        }
    }

    /// The dimension of H¹(X; Z2): the number of class coordinates.
    pub fn rank(&self) -> usize {
        self.free.len()
    }

    /// Words of an edge value (and of a cycle's sum).
    pub fn words(&self) -> usize {
        self.words
    }

    /// The value of the edge at adjacency slot `slot` (either end's slot).
    pub fn value(&self, slot: usize) -> &[u64] {
        if self.words == 0 {
            return &[];
        }
        let e = self.value_of_slot[slot] as usize;
        &self.values[e * self.words..(e + 1) * self.words]
    }

    /// The class in H₁(X; Z2) of a cycle whose edge values sum to `sum` (consumed):
    /// [`Cocycles::rank`] bits, packed in words.
    pub fn class(&self, sum: &mut [u64]) -> Vec<u64> {
        self.relations.reduce(sum);
        let mut class = vec![0u64; self.rank().div_ceil(64)];
        for (i, &p) in self.free.iter().enumerate() {
            if sum[p / 64] >> (p % 64) & 1 == 1 {
                class[i / 64] |= 1 << (i % 64);
            }
        }
        class
    }
}

#[cfg(test)]
mod tests {
    use super::super::roles::adjacency;
    use super::*;

    /// A solid torus: a ring of `k` triangular prisms (each split into 3 tets), all
    /// vertices interior, so that `X` is the whole mesh.
    fn solid_ring(k: usize) -> TetMesh {
        let mut positions = Vec::new();
        for i in 0..k {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            for j in 0..3 {
                let b = std::f64::consts::TAU * j as f64 / 3.0;
                let r = 2.0 + 0.5 * b.cos();
                positions.push([r * a.cos(), r * a.sin(), 0.5 * b.sin()]);
            }
        }
        let id = |i: usize, j: usize| (3 * (i % k) + j) as u32;
        let mut tets = Vec::new();
        for i in 0..k {
            let (a0, a1, a2) = (id(i, 0), id(i, 1), id(i, 2));
            let (b0, b1, b2) = (id(i + 1, 0), id(i + 1, 1), id(i + 1, 2));
            tets.push([a0, a1, a2, b0]);
            tets.push([a1, a2, b0, b1]);
            tets.push([a2, b0, b1, b2]);
        }
        let kinds = vec![VertexKind::Interior; positions.len()];
        TetMesh::new(positions, tets, kinds).unwrap()
    }

    /// The sum of the edge values round a closed vertex path.
    fn cycle_sum(c: &Cocycles, start: &[usize], nb: &[u32], path: &[u32]) -> Vec<u64> {
        let mut sum = vec![0u64; c.words()];
        for i in 0..path.len() {
            let (a, b) = (path[i] as usize, path[(i + 1) % path.len()]);
            let slot = start[a] + nb[start[a]..start[a + 1]].binary_search(&b).unwrap();
            let v = c.value(slot);
            for (x, y) in sum.iter_mut().zip(v) {
                *x ^= y;
            }
        }
        sum
    }

    #[test]
    fn a_solid_ring_has_one_class_and_its_core_carries_it() {
        let mesh = solid_ring(8);
        let (start, nb) = adjacency(&mesh);
        let c = Cocycles::new(&mesh, &start, &nb);
        assert_eq!(c.rank(), 1);
        // Round the ring once: the class; round a triangle of a prism: nothing.
        let core: Vec<u32> = (0..8).map(|i| 3 * i).collect();
        assert_eq!(c.class(&mut cycle_sum(&c, &start, &nb, &core)), vec![1]);
        assert_eq!(
            c.class(&mut cycle_sum(&c, &start, &nb, &[0, 1, 2])),
            vec![0]
        );
        // Two ways round the ring differ by a boundary.
        let other: Vec<u32> = (0..8).map(|i| 3 * i + 2).collect();
        assert_eq!(c.class(&mut cycle_sum(&c, &start, &nb, &other)), vec![1]);
    }

    #[test]
    fn an_edge_out_of_x_reads_zero_and_edges_share_their_values() {
        // Vertex 0 on the surface: the ring still closes through the other two
        // vertices of its section.
        let ring = solid_ring(8);
        let mut kinds = ring.kinds.clone();
        kinds[0] = VertexKind::Surface;
        let mesh = TetMesh::new(ring.positions.clone(), ring.tets.clone(), kinds).unwrap();
        let (start, nb) = adjacency(&mesh);
        let c = Cocycles::new(&mesh, &start, &nb);
        assert_eq!(c.rank(), 1);
        let slot = start[1] + nb[start[1]..start[2]].binary_search(&0).unwrap();
        assert!(c.value(slot).iter().all(|&x| x == 0));
        let other: Vec<u32> = (0..8).map(|i| 3 * i + 2).collect();
        assert_eq!(c.class(&mut cycle_sum(&c, &start, &nb, &other)), vec![1]);
        // One parameter: at most the zero value and the parameter's.
        assert_eq!(c.parameters, 1);
        assert!(c.values.len() <= 2 * c.words());
    }

    #[test]
    fn distinct_values_over_several_words_are_the_values_summed_in_full() {
        // 130 parameters (three words) on edges 0..130, then 70 edges each the sum of
        // two earlier ones (every tenth an edge with itself: zero), against the values summed
        // with all their words at once.
        let (parameters, edges) = (130usize, 200usize);
        let words = parameters.div_ceil(64);
        let mut order: Vec<(u32, Source)> = (0..parameters as u32)
            .map(|p| (p, Source::Parameter(p)))
            .collect();
        let mut triangles = Vec::new();
        let mut seed = 12345u64;
        for e in parameters..edges {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let a = (seed >> 33) as usize % e;
            let b = if e % 10 == 0 {
                a
            } else {
                (seed >> 13) as usize % e
            };
            triangles.push([e as u32, a as u32, b as u32]);
            order.push((e as u32, Source::Triangle(triangles.len() as u32 - 1)));
        }
        let mut full = vec![0u64; edges * words];
        for &(e, source) in &order {
            let e = e as usize;
            match source {
                Source::Parameter(p) => full[e * words + p as usize / 64] |= 1 << (p % 64),
                Source::Triangle(t) => {
                    for &other in &triangles[t as usize] {
                        let other = other as usize;
                        if other != e {
                            for w in 0..words {
                                full[e * words + w] ^= full[other * words + w];
                            }
                        }
                    }
                }
            }
        }
        let (values, index) = distinct_values(&order, &triangles, edges, words);
        assert!(values[..words].iter().all(|&x| x == 0));
        for e in 0..edges {
            let i = index[e] as usize;
            assert_eq!(
                &values[i * words..(i + 1) * words],
                &full[e * words..(e + 1) * words]
            );
        }
        let distinct: std::collections::HashSet<&[u64]> = full.chunks(words).collect();
        let zero = usize::from(!distinct.contains(&[0u64; 3][..]));
        assert_eq!(values.len() / words, distinct.len() + zero);
    }

    #[test]
    fn a_ball_has_no_class() {
        // One prism of the ring: a ball.
        let ring = solid_ring(8);
        let tets: Vec<[u32; 4]> = ring.tets[..3].to_vec();
        let mesh = TetMesh::new(ring.positions.clone(), tets, ring.kinds.clone()).unwrap();
        let (start, nb) = adjacency(&mesh);
        let c = Cocycles::new(&mesh, &start, &nb);
        assert_eq!(c.rank(), 0);
    }
}
