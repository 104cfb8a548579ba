//! The topological role of each 2-saddle: does it join two lobes or close a cycle?
//! (the paper's "distance to nearby loops" rule done by topology).
//!
//! Sweep the superlevel sets `{f ≥ c}` from the top down (in the classification's vertex
//! order: outer-sphere vertices first, then interior vertices by decreasing `(f, index)`;
//! surface vertices are the bottom and never added) with a union–find over the
//! vertices. Outer-sphere vertices form one component from the start, older than any
//! maximum. When a 2-saddle `v` is added, its two upper link components are already in
//! the superlevel set (every upper link vertex is above `v`):
//! - if they lie in different components, `v` is *separating*: it joins two lobes, and
//!   by the elder rule the lobe with the lower maximum (the *younger* one) dies there;
//!   its *bulge ratio* is how much fatter the lobe is than the neck: the largest
//!   unsmoothed distance (inscribed radius) over the younger lobe's vertices, over the
//!   largest over `v` and its neighbours (a lattice vertex next to a neck's core sees
//!   less than the core's radius; the smoothed field's own ratio grows without bound
//!   with the scale, as heat drains from thin parts first);
//! - if they lie in the same component, `v` is *cycle-closing*: it closes a 1-cycle of
//!   the superlevel set, a handle (inside) or a tunnel (outside) of the genus, or noise
//!   that a 1-saddle fills again lower down.
//!
//! Noise cycles are told apart locally: if the two upper link components are joined
//! inside the superlevel set within [`LOCAL_HOPS`] edges of `v` (without `v`), the cycle
//! `v` closes lies in that small ball, far below the size of any handle or hole the
//! lattice resolves. A lattice splits one smooth saddle into such clusters: at a
//! satellite's neck, one vertex joins the two lobes and its neighbour closes a tiny
//! cycle around it. Such a `v` takes the role of the nearest separating 2-saddle of the
//! ball (same lobe, same bulge: the same neck), or is a *local cycle* when the ball has
//! none.
//!
//! Which cycles are essential: every vertex carries, beside its union–find parent, the
//! value (over the cocycle basis of [`cycles`](super::cycles)) of a path from it to its
//! component's root. Where a saddle's upper neighbours lie in one component, each path
//! through two of them closes a cycle whose class is the sum of their values; a class
//! independent of those closed above it is new, the saddle's cycle is *essential*
//! (the elder rule: a noise cycle, or a second copy of one, is filled lower down).
//! At the bottom the essential cycles are as many as the genus: [`Roles`] reports
//! their count.
//!
//! Entry points: [`Sweep::new`] once per mesh (vertex adjacency, cocycle basis), then
//! [`Sweep::roles`] per field. Sequential and sorted: the result does not depend on the
//! thread count.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::critical::{Classification, VertexType};
use super::cycles::Cocycles;
use crate::mesh::Z2Basis;
use crate::tet::{TetMesh, VertexKind};

/// What a 2-saddle does to the superlevel sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SaddleRole {
    /// Joins two lobes (two components of the superlevel set).
    Separating,
    /// Closes a cycle of one component: a handle (inside) or tunnel (outside).
    CycleClosing,
    /// Closes a cycle that lies within [`LOCAL_HOPS`] edges of it, with no separating
    /// 2-saddle there: lattice noise, never a neck.
    LocalCycle,
}

/// Radius, in edges, of the ball in which a closed cycle counts as lattice noise.
pub const LOCAL_HOPS: usize = 3;

/// The role of one 2-saddle at one level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RoleAt {
    /// The 2-saddle's vertex.
    pub vertex: u32,
    /// Separating or cycle-closing.
    pub role: SaddleRole,
    /// Separating: the maximum of the lobe that dies here (the lower of the two).
    pub younger_max: Option<u32>,
    /// Separating: the bulge ratio: the largest unsmoothed distance `d` over the
    /// younger lobe, over the largest `d` over the saddle and its neighbours (infinite
    /// when that is 0).
    pub bulge: Option<f64>,
    /// Separating: `f(younger_max) / f(vertex)` on the smoothed field of this level.
    pub field_ratio: Option<f64>,
    /// Cycle-closing: the class of its cycle is independent of the cycles closed above
    /// it, so the cycle lives for ever (false: a 1-saddle lower down fills it).
    pub essential: bool,
}

/// The roles of one field's 2-saddles, and the count of essential cycles.
#[derive(Debug, Clone, PartialEq)]
pub struct Roles {
    /// One per 2-saddle, in vertex order.
    pub roles: Vec<RoleAt>,
    /// Cycles closed in the sweep whose classes are independent: the dimension of
    /// H₁(X; Z2) when the sweep is consistent (every class is born at a saddle).
    pub essential_cycles: usize,
    /// The vertex that closes each essential cycle, in sweep order: a 2-saddle, or a
    /// degenerate saddle (whose upper link has three or more components).
    pub closers: Vec<Closer>,
}

/// A vertex that closes an essential cycle, and the two upper neighbours through
/// which it closes it (in two components of its upper link that are one component
/// of the superlevel set above it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Closer {
    /// The vertex.
    pub vertex: u32,
    /// The two upper neighbours.
    pub through: [u32; 2],
}

/// Vertex adjacency of a mesh, built once; see the module doc.
#[derive(Debug, Clone)]
pub struct Sweep {
    kinds: Vec<VertexKind>,
    start: Vec<usize>,
    neighbours: Vec<u32>,
    cocycles: Cocycles,
}

/// Scratch space of [`Sweep::cycle_through`]: which side reached each vertex and from
/// where, reset after each search along the vertices it touched (one allocation per
/// parallel task, not one per search: on meshes of millions of vertices, clearing a
/// whole array per search cost more than the searches; `docs/decisions.md`, Morse).
#[derive(Debug, Clone, Default)]
pub struct CycleSearch {
    mark: Vec<u8>,
    parent: Vec<u32>,
    touched: Vec<u32>,
}

const UNSEEN: u8 = 0;
const FROM: u8 = 1;
const TO: u8 = 2;

impl CycleSearch {
    /// Ready for a search over `n` vertices: every vertex unseen.
    fn start(&mut self, n: usize) {
        for &u in &self.touched {
            self.mark[u as usize] = UNSEEN;
        }
        self.touched.clear();
        if self.mark.len() != n {
            self.mark = vec![UNSEEN; n];
            self.parent = vec![0; n];
        }
    }

    fn reach(&mut self, u: u32, side: u8, parent: u32) {
        self.mark[u as usize] = side;
        self.parent[u as usize] = parent;
        self.touched.push(u);
    }
}

/// The outer sphere's component has no maximum vertex.
const OUTER: u32 = u32::MAX;

/// How many vertices ahead in its order the sweep asks for a vertex's neighbours.
const PREFETCH_AHEAD: usize = 8;

/// Ask the processor to bring the cache line at `p` in (no effect on any result).
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint: it reads nothing and faults on no address.
    unsafe {
        std::arch::x86_64::_mm_prefetch(p.cast::<i8>(), std::arch::x86_64::_MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

impl Sweep {
    /// Build the vertex adjacency (the edges of the tets) and the cocycle basis.
    pub fn new(mesh: &TetMesh) -> Sweep {
        let (start, neighbours) = adjacency(mesh);
        let cocycles = Cocycles::new(mesh, &start, &neighbours);
        Sweep {
            kinds: mesh.kinds.clone(),
            start,
            neighbours,
            cocycles,
        }
    }

    /// The cycle that `closer` closes, as a path of vertices: `closer.vertex`, then the
    /// fewest edges from one of its upper neighbours to the other through vertices above
    /// it (the superlevel set it closes a cycle of: outer-sphere vertices, and interior
    /// ones above in `(f, index)`). `None` when no such path is found within `limit`
    /// vertices visited. `search` is scratch space, reusable across calls.
    ///
    /// Breadth first from both ends at once, a whole layer at a time from the side whose
    /// layer is smaller, neighbours in index order: the same path on every run. Two balls
    /// of half the cycle's length hold about a quarter of the vertices of one ball of the
    /// whole length (figures in `docs/decisions.md`, Morse). The first edge found between the two sides closes a shortest
    /// path: a vertex one side reached has every neighbour reached by the time that side
    /// expands it, so the first edge between the sides is found from the newest layer of
    /// one side to the newest of the other.
    pub fn cycle_through(
        &self,
        closer: Closer,
        f: &[f64],
        limit: usize,
        search: &mut CycleSearch,
    ) -> Option<Vec<u32>> {
        let v = closer.vertex;
        let is_above = |u: u32| match self.kinds[u as usize] {
            VertexKind::Outer => true,
            VertexKind::Surface => false,
            VertexKind::Interior => f[u as usize]
                .total_cmp(&f[v as usize])
                .then(u.cmp(&v))
                .is_gt(),
        };
        let [from, to] = closer.through;
        if !is_above(from) || !is_above(to) {
            return None;
        }
        if from == to {
            return Some(vec![v, to]);
        }
        search.start(self.kinds.len());
        search.reach(from, FROM, from);
        search.reach(to, TO, to);
        let mut layers = [vec![from], vec![to]];
        let mut next = Vec::new();
        let meeting = 'search: loop {
            // Expand the smaller layer (the one from `from` on a tie).
            let side = usize::from(layers[1].len() < layers[0].len());
            let (own, other) = ([FROM, TO][side], [TO, FROM][side]);
            if layers[side].is_empty() {
                break None;
            }
            next.clear();
            for &u in &layers[side] {
                let ui = u as usize;
                for &w in &self.neighbours[self.start[ui]..self.start[ui + 1]] {
                    if w == v || !is_above(w) {
                        continue;
                    }
                    let mark = search.mark[w as usize];
                    if mark == other {
                        // `u` on this side, `w` on the other: as (from side, to side).
                        break 'search Some(if own == FROM { (u, w) } else { (w, u) });
                    }
                    if mark == UNSEEN {
                        search.reach(w, own, u);
                        next.push(w);
                    }
                }
                if search.touched.len() > limit {
                    break 'search None;
                }
            }
            std::mem::swap(&mut layers[side], &mut next);
        };
        let (a, b) = meeting?;
        // v, then `to` … b, then a … `from`.
        let mut to_side = vec![b];
        let mut x = b;
        while x != to {
            x = search.parent[x as usize];
            to_side.push(x);
        }
        let mut path = vec![v];
        path.extend(to_side.iter().rev());
        let mut x = a;
        path.push(x);
        while x != from {
            x = search.parent[x as usize];
            path.push(x);
        }
        Some(path)
    }

    /// The dimension of H₁(X; Z2) of the swept complex (see [`cycles`](super::cycles)):
    /// the genus, when the volume mesh kept the surface's topology.
    pub fn cycle_rank(&self) -> usize {
        self.cocycles.rank()
    }

    /// The role of every 2-saddle of `classification` (a classification of `f`), in
    /// vertex order, and the essential cycles; `distance` is the unsmoothed field (for
    /// the bulge ratios).
    pub fn roles(&self, f: &[f64], classification: &Classification, distance: &[f64]) -> Roles {
        let n = self.kinds.len();
        // Sorted by decreasing (f, index), the keys beside the indices (no indirection).
        let mut interior: Vec<(f64, u32)> = (0..n as u32)
            .filter(|&v| self.kinds[v as usize] == VertexKind::Interior)
            .map(|v| (f[v as usize], v))
            .collect();
        interior.par_sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)));
        // What the sweep reads of each vertex beside its neighbours, in the sweep's
        // order (its class's kind and upper link components, at most 65 535 as its link
        // vertices are): read at the vertex's own place, every step waited on a cache
        // miss. The unsmoothed distance takes the place of the key, no longer needed.
        let mut read: Vec<(VertexType, u16)> = Vec::with_capacity(interior.len());
        for (key, v) in &mut interior {
            let vi = *v as usize;
            *key = distance[vi];
            let class = &classification.classes[vi];
            read.push((class.kind, u16::try_from(class.upper).unwrap_or(u16::MAX)));
        }
        let outer = (0..n as u32).filter(|&v| self.kinds[v as usize] == VertexKind::Outer);

        let mut forest = Forest::new(n, self.potential_words());
        let w = forest.words;
        let mut added = vec![false; n];
        // Per root: the highest vertex of its component (OUTER for the sphere's).
        let mut top = vec![OUTER; n];
        // Per root: the largest unsmoothed distance in its component.
        let mut fattest = vec![0.0f64; n];
        let mut first_outer = None;
        for v in outer {
            added[v as usize] = true;
            match first_outer {
                None => first_outer = Some(v),
                Some(o) => forest.join(v, o),
            }
        }
        let mut roles = Vec::new();
        // Per vertex: its index in `roles` once it has one.
        let mut role_of_vertex = vec![u32::MAX; n];
        let mut ball = Ball::new(n);
        let mut essential = Z2Basis::default();
        // The components above v, and v's path value into each (w words per root).
        let mut roots: Vec<u32> = Vec::new();
        let mut into: Vec<u64> = Vec::new();
        // Per upper neighbour: its component's root, v's path value into it, itself.
        let mut through: Vec<(u32, Vec<u64>, u32)> = Vec::new();
        let mut closers = Vec::new();
        let mut value = vec![0u64; w];
        let mut root_into = vec![0u64; w];
        for (i, (&(d, v), &(kind, upper_components))) in interior.iter().zip(&read).enumerate() {
            // The neighbours of a vertex a few steps on, asked for now: the sweep's own
            // chain of reads would otherwise wait on them.
            if let Some(&(_, ahead)) = interior.get(i + PREFETCH_AHEAD) {
                prefetch(
                    self.neighbours
                        .as_ptr()
                        .wrapping_add(self.start[ahead as usize]),
                );
            }
            let vi = v as usize;
            added[vi] = true;
            top[vi] = v;
            fattest[vi] = d;
            roots.clear();
            into.clear();
            // Slots of v's edges to vertices above it.
            let mut upper = (self.start[vi]..self.start[vi + 1])
                .filter(|&s| added[self.neighbours[s] as usize]);
            let mut new_cycles = 0;
            if matches!(kind, VertexType::Saddle2 | VertexType::Degenerate) {
                through.clear();
                for slot in upper {
                    let root = self.path_into(&mut forest, slot, &mut value);
                    through.push((root, value.clone(), self.neighbours[slot]));
                }
                through.sort_by_key(|&(root, _, _)| root);
                for (i, (root, path, _)) in through.iter().enumerate() {
                    if through.iter().position(|(r, _, _)| r == root) == Some(i) {
                        roots.push(*root);
                        into.extend_from_slice(path);
                    }
                }
                // Each upper link component beyond one per root can close a cycle; look
                // for that many new classes among the ways down from one component.
                let can_close = usize::from(upper_components);
                let mut open = can_close.saturating_sub(roots.len());
                if w == 0 {
                    open = 0;
                }
                for (i, (root, path, last)) in through.iter().enumerate() {
                    if open == 0 {
                        break;
                    }
                    let first = through.iter().position(|(r, _, _)| r == root).unwrap_or(i);
                    if first == i || *path == through[first].1 {
                        continue;
                    }
                    // Two ways down to v from one component: a cycle.
                    let mut sum: Vec<u64> = path
                        .iter()
                        .zip(&through[first].1)
                        .map(|(a, b)| a ^ b)
                        .collect();
                    if essential.insert(&self.cocycles.class(&mut sum)) {
                        new_cycles += 1;
                        open -= 1;
                        closers.push(Closer {
                            vertex: v,
                            through: [through[first].2, *last],
                        });
                    }
                }
            } else if let Some(slot) = upper.next() {
                // One upper link component (regular, 1-saddle, minimum): its vertices
                // are joined through the link's edges already, so one root is all.
                roots.push(self.path_into(&mut forest, slot, &mut value));
                into.extend_from_slice(&value);
            }
            if kind == VertexType::Saddle2 {
                let mut role = self.role_of(v, f, distance, &roots, &top, &fattest);
                role.essential = role.role == SaddleRole::CycleClosing && new_cycles > 0;
                if role.role == SaddleRole::CycleClosing && ball.local_cycle(self, v, &added) {
                    role = ball
                        .nearest(self, |u| {
                            let i = role_of_vertex[u as usize];
                            (i != u32::MAX)
                                .then(|| roles[i as usize])
                                .filter(|r: &RoleAt| r.role == SaddleRole::Separating)
                        })
                        .map_or(
                            RoleAt {
                                role: SaddleRole::LocalCycle,
                                ..role
                            },
                            |r| RoleAt {
                                vertex: v,
                                essential: false,
                                ..r
                            },
                        );
                }
                role_of_vertex[vi] = roles.len() as u32;
                roles.push(role);
            }
            // Union: the component with the highest top survives as the root; a root
            // that joins another takes the difference of v's path values into the two.
            let mut root = v;
            root_into.fill(0);
            for (i, &r) in roots.iter().enumerate() {
                let r_into = &into[i * w..(i + 1) * w];
                // Every component already swept lies above v, so v joins the first.
                let (keep, lose) = if root == v || above(f, top[r as usize], top[root as usize]) {
                    (r, root)
                } else {
                    (root, r)
                };
                forest.join(lose, keep);
                for (k, d) in forest.offset_mut(lose).iter_mut().enumerate() {
                    *d = root_into[k] ^ r_into[k];
                }
                fattest[keep as usize] = fattest[keep as usize].max(fattest[lose as usize]);
                if keep == r {
                    root_into.copy_from_slice(r_into);
                }
                root = keep;
            }
        }
        roles.sort_by_key(|r| r.vertex);
        Roles {
            roles,
            essential_cycles: essential.rank(),
            closers,
        }
    }

    /// Words of the path values kept during the sweep (0 when there is no class).
    fn potential_words(&self) -> usize {
        if self.cocycles.rank() == 0 {
            0
        } else {
            self.cocycles.words()
        }
    }

    /// For the edge at adjacency `slot` (from `v` up to `u`): the root of `u`'s
    /// component, and in `value` the value of the path from that root down to `u` and
    /// on to `v`.
    fn path_into(&self, forest: &mut Forest, slot: usize, value: &mut [u64]) -> u32 {
        let root = forest.find(self.neighbours[slot], value);
        for (x, e) in value.iter_mut().zip(self.cocycles.value(slot)) {
            *x ^= e;
        }
        root
    }

    /// The largest of `distance` over `v` and its neighbours.
    fn ring_max(&self, v: u32, distance: &[f64]) -> f64 {
        let v = v as usize;
        self.neighbours[self.start[v]..self.start[v + 1]]
            .iter()
            .map(|&u| distance[u as usize])
            .fold(distance[v], f64::max)
    }

    fn role_of(
        &self,
        v: u32,
        f: &[f64],
        distance: &[f64],
        roots: &[u32],
        top: &[u32],
        fattest: &[f64],
    ) -> RoleAt {
        if roots.len() < 2 {
            return RoleAt {
                vertex: v,
                role: SaddleRole::CycleClosing,
                younger_max: None,
                bulge: None,
                field_ratio: None,
                essential: false,
            };
        }
        // The younger of the joined lobes: the lowest top among them.
        let younger_root = roots
            .iter()
            .copied()
            .min_by(|&a, &b| {
                if above(f, top[a as usize], top[b as usize]) {
                    std::cmp::Ordering::Greater
                } else {
                    std::cmp::Ordering::Less
                }
            })
            .unwrap_or(roots[0]);
        let younger = top[younger_root as usize];
        let neck = self.ring_max(v, distance);
        let bulge = if younger == OUTER {
            None
        } else if neck > 0.0 {
            Some(fattest[younger_root as usize] / neck)
        } else {
            Some(f64::INFINITY)
        };
        RoleAt {
            vertex: v,
            role: SaddleRole::Separating,
            younger_max: (younger != OUTER).then_some(younger),
            bulge,
            field_ratio: (younger != OUTER && f[v as usize] > 0.0)
                .then(|| f[younger as usize] / f[v as usize]),
            essential: false,
        }
    }
}

/// Scratch space for the local-cycle test, reused across saddles (stamped marks).
///
/// The ball is grown a layer at a time, only as far as the test needs: a flood that
/// joins the upper neighbours within fewer hops joins them within [`LOCAL_HOPS`] (a
/// larger ball holds every path of a smaller one), and the breadth-first order of the
/// smaller ball is the start of the larger one's. Most lattice-noise cycles close within
/// two hops, and a ball of three is several times the vertices of one of two.
struct Ball {
    stamp: u32,
    in_ball: Vec<u32>,
    /// Flood marks, stamped per flood (a ball may be flooded twice).
    reached: Vec<u32>,
    flood_stamp: u32,
    order: Vec<u32>,
    /// `order[head..]` is the last layer, not yet expanded; `hops` layers are in.
    head: usize,
    hops: usize,
    queue: Vec<u32>,
    upper: Vec<u32>,
}

/// The ball's first radius, in edges (then [`LOCAL_HOPS`]).
const FIRST_HOPS: usize = 2;

impl Ball {
    fn new(n: usize) -> Ball {
        Ball {
            stamp: 0,
            in_ball: vec![0; n],
            reached: vec![0; n],
            flood_stamp: 0,
            order: Vec::new(),
            head: 0,
            hops: 0,
            queue: Vec::new(),
            upper: Vec::new(),
        }
    }

    /// Add the next layer of the breadth-first ball round `order[0]`.
    fn grow(&mut self, sweep: &Sweep) {
        let stamp = self.stamp;
        let end = self.order.len();
        // The layer's neighbour lists are asked for at once: each is a cache miss of
        // its own, which the walk below would otherwise wait on one by one.
        for &u in &self.order[self.head..end] {
            prefetch(
                sweep
                    .neighbours
                    .as_ptr()
                    .wrapping_add(sweep.start[u as usize]),
            );
        }
        while self.head < end {
            let u = self.order[self.head] as usize;
            self.head += 1;
            for &w in &sweep.neighbours[sweep.start[u]..sweep.start[u + 1]] {
                if self.in_ball[w as usize] != stamp {
                    self.in_ball[w as usize] = stamp;
                    self.order.push(w);
                    prefetch(sweep.start.as_ptr().wrapping_add(w as usize));
                }
            }
        }
        self.hops += 1;
    }

    /// Whether the ball's superlevel vertices other than `v` join all of `upper`.
    fn floods(&mut self, sweep: &Sweep, v: u32, added: &[bool]) -> bool {
        let Some(&first) = self.upper.first() else {
            return false;
        };
        self.flood_stamp += 1;
        let (stamp, flood) = (self.stamp, self.flood_stamp);
        self.queue.clear();
        self.queue.push(first);
        self.reached[first as usize] = flood;
        // Upper neighbours not reached yet: the flood stops once it has them all.
        let mut missing = self.upper.len() - 1;
        while let Some(u) = self.queue.pop() {
            if missing == 0 {
                break;
            }
            let u = u as usize;
            for &w in &sweep.neighbours[sweep.start[u]..sweep.start[u + 1]] {
                let wi = w as usize;
                if w != v && added[wi] && self.in_ball[wi] == stamp && self.reached[wi] != flood {
                    self.reached[wi] = flood;
                    self.queue.push(w);
                    missing -= usize::from(self.upper.contains(&w));
                }
            }
        }
        missing == 0
    }

    /// If the superlevel set minus `v` joins all of `v`'s added neighbours within
    /// [`LOCAL_HOPS`] edges of `v` (the cycle `v` closes lies in that ball): true, and
    /// the ball is ready for [`Ball::nearest`]. Otherwise false: the cycle leaves it.
    fn local_cycle(&mut self, sweep: &Sweep, v: u32, added: &[bool]) -> bool {
        self.stamp += 1;
        self.order.clear();
        self.order.push(v);
        self.in_ball[v as usize] = self.stamp;
        self.head = 0;
        self.hops = 0;
        let vi = v as usize;
        self.upper.clear();
        self.upper.extend(
            sweep.neighbours[sweep.start[vi]..sweep.start[vi + 1]]
                .iter()
                .copied()
                .filter(|&u| added[u as usize]),
        );
        while self.hops < FIRST_HOPS.min(LOCAL_HOPS) {
            self.grow(sweep);
        }
        if self.floods(sweep, v, added) {
            return true;
        }
        if self.hops == LOCAL_HOPS {
            return false;
        }
        while self.hops < LOCAL_HOPS {
            self.grow(sweep);
        }
        self.floods(sweep, v, added)
    }

    /// The first of the ball's vertices other than its centre, nearest first (the
    /// breadth-first order of the whole ball of [`LOCAL_HOPS`]), for which `pick` gives
    /// a value; the ball grows to its whole radius only when the part built has none.
    fn nearest<T>(&mut self, sweep: &Sweep, mut pick: impl FnMut(u32) -> Option<T>) -> Option<T> {
        let mut from = 1;
        loop {
            if let Some(found) = self.order[from..].iter().find_map(|&u| pick(u)) {
                return Some(found);
            }
            if self.hops == LOCAL_HOPS {
                return None;
            }
            from = self.order.len();
            self.grow(sweep);
        }
    }
}

/// Whether component top `a` is above `b` (the outer sphere is above everything).
fn above(f: &[f64], a: u32, b: u32) -> bool {
    match (a == OUTER, b == OUTER) {
        (true, _) => b != OUTER,
        (false, true) => false,
        _ => f[a as usize]
            .total_cmp(&f[b as usize])
            .then(a.cmp(&b))
            .is_gt(),
    }
}

/// The vertex adjacency of a tet mesh (its edges): per vertex `v`, its neighbours
/// `neighbours[start[v]..start[v + 1]]`, sorted.
pub(super) fn adjacency(mesh: &TetMesh) -> (Vec<usize>, Vec<u32>) {
    let lists: Vec<Vec<u32>> = (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| {
            let mut around: Vec<u32> = mesh
                .vertex_tets(v)
                .iter()
                .flat_map(|&t| mesh.tets[t as usize])
                .filter(|&u| u as usize != v)
                .collect();
            around.sort_unstable();
            around.dedup();
            around
        })
        .collect();
    let mut start = Vec::with_capacity(lists.len() + 1);
    start.push(0);
    for n in &lists {
        start.push(start.last().copied().unwrap_or(0) + n.len());
    }
    (start, lists.concat())
}

/// Union–find over the vertices; beside each vertex's parent, the value of the path
/// from the parent down to it (`words` words; none when there is no class). Both sit
/// in one record per vertex, `1 + words` words, so a step up the tree reads one place.
struct Forest {
    words: usize,
    records: Vec<u64>,
}

impl Forest {
    fn new(n: usize, words: usize) -> Forest {
        let mut records = vec![0u64; n * (1 + words)];
        for x in 0..n {
            records[x * (1 + words)] = x as u64;
        }
        Forest { words, records }
    }

    fn parent(&self, x: u32) -> u32 {
        self.records[x as usize * (1 + self.words)] as u32
    }

    /// Make `root` (a root) a child of `parent`; its value is set with `offset_mut`.
    fn join(&mut self, root: u32, parent: u32) {
        self.records[root as usize * (1 + self.words)] = u64::from(parent);
    }

    fn offset_mut(&mut self, x: u32) -> &mut [u64] {
        let at = x as usize * (1 + self.words) + 1;
        &mut self.records[at..at + self.words]
    }

    /// The root of `x`, with the path value from the root down to `x` in `value`;
    /// halves the path (each vertex on it skips to its grandparent, its value
    /// summed with its parent's).
    fn find(&mut self, mut x: u32, value: &mut [u64]) -> u32 {
        value.fill(0);
        let stride = 1 + self.words;
        loop {
            let p = self.parent(x);
            if p == x {
                return x;
            }
            let up = self.parent(p);
            let (xi, pi) = (x as usize * stride, p as usize * stride);
            for k in 1..stride {
                self.records[xi + k] ^= self.records[pi + k];
                value[k - 1] ^= self.records[xi + k];
            }
            self.records[xi] = u64::from(up);
            x = up;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of `n`³ unit cubes, each split into six tets round its diagonal; the
    /// grid's outer vertices are surface vertices, the rest interior.
    fn cube_grid(n: usize) -> TetMesh {
        let side = n + 1;
        let id = |x: usize, y: usize, z: usize| (x + side * (y + side * z)) as u32;
        let mut positions = Vec::new();
        let mut kinds = Vec::new();
        for z in 0..side {
            for y in 0..side {
                for x in 0..side {
                    positions.push([x as f64, y as f64, z as f64]);
                    let outer = [x, y, z].iter().any(|&c| c == 0 || c == n);
                    kinds.push(if outer {
                        VertexKind::Surface
                    } else {
                        VertexKind::Interior
                    });
                }
            }
        }
        let mut tets = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let corner = |b: [usize; 3]| id(x + b[0], y + b[1], z + b[2]);
                    for axes in [
                        [0, 1, 2],
                        [0, 2, 1],
                        [1, 0, 2],
                        [1, 2, 0],
                        [2, 0, 1],
                        [2, 1, 0],
                    ] {
                        let mut at = [0usize; 3];
                        let mut tet = [corner(at); 4];
                        for (k, &a) in axes.iter().enumerate() {
                            at[a] = 1;
                            tet[k + 1] = corner(at);
                        }
                        tets.push(tet);
                    }
                }
            }
        }
        TetMesh::new(positions, tets, kinds).unwrap()
    }

    /// The local-cycle test read directly: the whole ball of [`LOCAL_HOPS`] round `v` in
    /// breadth-first order, and whether its superlevel vertices other than `v` join all
    /// of `v`'s added neighbours.
    fn whole_ball(sweep: &Sweep, v: u32, added: &[bool]) -> (bool, Vec<u32>) {
        let around =
            |u: u32| &sweep.neighbours[sweep.start[u as usize]..sweep.start[u as usize + 1]];
        let mut order = vec![v];
        let mut hops = vec![0usize];
        let mut head = 0;
        while head < order.len() {
            let (u, h) = (order[head], hops[head]);
            head += 1;
            if h == LOCAL_HOPS {
                continue;
            }
            for &w in around(u) {
                if !order.contains(&w) {
                    order.push(w);
                    hops.push(h + 1);
                }
            }
        }
        let upper: Vec<u32> = around(v)
            .iter()
            .copied()
            .filter(|&u| added[u as usize])
            .collect();
        let Some(&first) = upper.first() else {
            return (false, order);
        };
        let mut reached = vec![first];
        let mut stack = vec![first];
        while let Some(u) = stack.pop() {
            for &w in around(u) {
                if w != v && added[w as usize] && order.contains(&w) && !reached.contains(&w) {
                    reached.push(w);
                    stack.push(w);
                }
            }
        }
        (upper.iter().all(|u| reached.contains(u)), order)
    }

    #[test]
    fn the_ball_grown_as_needed_decides_and_orders_as_the_whole_ball() {
        let mesh = cube_grid(7);
        let sweep = Sweep::new(&mesh);
        let n = mesh.num_vertices();
        // A rough field (a fixed pseudo-random sequence): many small cycles, some not.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let f: Vec<f64> = (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64
            })
            .collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&a, &b| f[b as usize].total_cmp(&f[a as usize]));
        let mut added = vec![false; n];
        let mut ball = Ball::new(n);
        let (mut local, mut wide, mut grown_to_find) = (0, 0, 0);
        for &v in &order {
            let (expected, whole) = whole_ball(&sweep, v, &added);
            assert_eq!(ball.local_cycle(&sweep, v, &added), expected, "vertex {v}");
            if expected {
                local += 1;
                wide += usize::from(ball.hops == LOCAL_HOPS);
                // Sparse enough that some are found only in the outer layer.
                let pick = |u: u32| (added[u as usize] && u % 23 == 2).then_some(u);
                let before = ball.hops;
                let found = ball.nearest(&sweep, pick);
                assert_eq!(
                    found,
                    whole[1..].iter().find_map(|&u| pick(u)),
                    "vertex {v}"
                );
                grown_to_find += usize::from(found.is_some() && before < ball.hops);
            }
            added[v as usize] = true;
        }
        // Both ways out of the test were taken, and balls grown to their whole radius,
        // by the test itself and by the search for the nearest vertex.
        assert!(local > 0 && local < n, "{local} of {n}");
        assert!(wide > 0 && grown_to_find > 0, "{wide} {grown_to_find}");
    }
}
