//! Linked loops: the classes of a side that bound no disk there, so that no neck gives
//! them. A knotted tube is the example. Its tunnel loop runs once along the tube (the
//! knot's Seifert longitude): it bounds a surface outside but no disk, so no plane
//! through an outside saddle cuts it, yet it is null-homologous outside and essential
//! inside, as a tunnel loop is.
//!
//! A closed curve `c` on the surface is null-homologous on this side exactly when its
//! linking number with each cycle `k_i` of a basis of the *other* side's first homology
//! is 0 (Alexander duality: the other side's classes, up to a multiple, are what a
//! curve here can link); and such a class is non-zero exactly when `c` crosses some loop
//! `m` of the other side an odd number of times (the other side's loops span the
//! classes that bound there, and the intersection pairing between the two is perfect).
//! So, for a side whose loops span fewer classes than the genus, given the other side's
//! loops and cycles (the Morse stage's `cycles`):
//! 1. *links*: per surface edge, its signed crossings with a fan of triangles spanning
//!    each `k_i` (from the cycle's centroid); summed round a closed path of edges, with
//!    the sign of the way each is walked, that is the path's linking number with `k_i`;
//! 2. *search*, for each loop `m` of the other side, shortest first, until the classes
//!    reach the genus: the shortest closed path of surface edges whose linking numbers
//!    are all 0 and which crosses `m` an odd number of times. Dijkstra over states
//!    (vertex, linking counts so far within ±reach, parity of `m`'s crossings) from
//!    [`SOURCES`] vertices of the edges `m` crosses (the path passes one of those
//!    edges), with the reach 2, then 4, then [`MAX_REACH`] until a path is found;
//! 3. *strip*: the path moved off its vertices onto the faces on its left (the same
//!    class), tightened like every loop, measured, and kept where its class is new.
//!
//! Units are those of the surface; the surface must be closed and consistently
//! oriented. A search over more than [`MAX_STATES`] states or more than
//! [`MAX_LINK_TESTS`] edge–triangle tests is not run, and says so (the Menger sponge's
//! 1409 cycles are far over). Sequential, in a fixed order: the result does not depend
//! on the thread count. Entry point: [`linked_loops`].

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::cut::Crossing;
use super::selection::neck_loop;
use super::tighten::tighten;
use super::{
    best_fit_normal, centroid, classes, tightened, Initial, LoopOptions, LoopSurface, NeckLoop,
    Seed,
};
use crate::geom::{bounds, cross, dot, norm, sub};
use crate::mesh::{Side, SurfaceMesh, Topology, Z2Basis};

/// Most states a search may have: the surface's vertices times `2 (2 reach + 1)^cycles`.
pub const MAX_STATES: usize = 1 << 25;

/// Most edge–triangle tests the linking counts may take: the surface's edges times the
/// other side's cycles' total length.
pub const MAX_LINK_TESTS: usize = 1 << 31;

/// What [`linked_loops`] found.
#[derive(Debug, Clone, Default)]
pub struct Linked {
    /// The loops kept, each of a class new to the side.
    pub loops: Vec<NeckLoop>,
    /// Why the classes stayed short of the genus, one line each (empty when reached).
    pub shortfalls: Vec<String>,
}

/// Loops of `kind` for the classes of this side that its loops `found` miss, on
/// `surface` (with its `loop_surface`), from the `other` side's loops and its `cycles`
/// (a basis of the other side's H₁; see the module doc). `first_seed` numbers the new
/// loops' `seed` (they have no saddle: one past the side's saddles).
#[allow(clippy::too_many_arguments)]
pub fn linked_loops(
    surface: &SurfaceMesh,
    loop_surface: &LoopSurface,
    kind: Side,
    found: &[NeckLoop],
    other: &[NeckLoop],
    cycles: &[Vec<[f64; 3]>],
    genus: usize,
    first_seed: usize,
    options: &LoopOptions,
) -> Linked {
    let mut result = Linked::default();
    let topology = &loop_surface.topology;
    let mut basis = Z2Basis::default();
    for l in found {
        basis.insert(&l.class());
    }
    if basis.rank() >= genus {
        return result;
    }
    // 1. Preconditions: the other side's classes complete, and the search within bounds.
    let shortfall = |rank: usize, why: String| {
        vec![format!(
            "{}: {why}, so {} of the genus's {genus} classes have no {} loop",
            kind.name(),
            genus - rank,
            kind.neck_name()
        )]
    };
    let other_kind = match kind {
        Side::Inside => Side::Outside,
        Side::Outside => Side::Inside,
    };
    let other_rank = crate::mesh::z2_rank(&other.iter().map(NeckLoop::class).collect::<Vec<_>>());
    if other_rank < genus || cycles.len() < genus {
        result.shortfalls = shortfall(basis.rank(), format!(
            "the linked search needs the other side's loops and cycles to span the genus (they span {other_rank} and {} classes)",
            cycles.len()
        ));
        return result;
    }
    let widest = match Layers::fitting(cycles.len(), surface.num_vertices(), MAX_STATES, MAX_REACH)
    {
        Some(layers) if cycles.len() <= 64 => layers,
        _ => {
            result.shortfalls = shortfall(basis.rank(), format!(
                "the linked search over {} vertices and {} cycles would need more than its bound of {MAX_STATES} states",
                surface.num_vertices(),
                cycles.len()
            ));
            return result;
        }
    };
    let tests = topology.num_edges() * cycles.iter().map(Vec::len).sum::<usize>();
    if tests > MAX_LINK_TESTS {
        result.shortfalls = shortfall(basis.rank(), format!(
            "the linking counts would take {tests} edge-triangle tests, over their bound of {MAX_LINK_TESTS}"
        ));
        return result;
    }
    if let Some(e) = (0..topology.num_edges()).find(|&e| topology.edge_faces(e).len() != 2) {
        result.shortfalls = shortfall(
            basis.rank(),
            format!(
                "the linked search needs a closed surface (edge {e} has {} faces)",
                topology.edge_faces(e).len()
            ),
        );
        return result;
    }
    // 2. Each edge's linking counts with the cycles.
    let links = link_counts(surface, topology, cycles);
    let geometry = loop_surface.geometry(surface);
    let measures = loop_surface.measures(surface, options);
    let mut order: Vec<usize> = (0..other.len()).collect();
    order.sort_by(|&a, &b| other[a].length.total_cmp(&other[b].length).then(a.cmp(&b)));
    let mut failures = Vec::new();
    for j in order {
        if basis.rank() >= genus {
            break;
        }
        // 3. The shortest closed path of linking number 0 with every cycle that crosses
        //    loop `m` an odd number of times.
        let m = &other[j];
        let mut crosses = vec![false; topology.num_edges()];
        for e in classes::crossings(surface, topology, &m.surface_points) {
            crosses[e] = !crosses[e];
        }
        // The narrowest reach first: a path that keeps its counts near 0 is found in
        // fewer states.
        let path = [2, 4, MAX_REACH]
            .into_iter()
            .filter(|&r| r < widest.reach)
            .chain([widest.reach])
            .find_map(|reach| {
                let layers =
                    Layers::fitting(cycles.len(), surface.num_vertices(), MAX_STATES, reach)?;
                shortest_cycle(surface, topology, &links, &crosses, layers)
            });
        let Some(path) = path else {
            failures.push(format!(
                "no closed path crosses the {} loop of length {:.6} an odd number of times and links none of its cycles",
                other_kind.neck_name(),
                m.length
            ));
            continue;
        };
        // 4. Onto the faces on its left, tightened, measured.
        let Some((crossings, faces)) = left_strip(surface, topology, &path) else {
            failures.push(format!(
                "the path across the {} loop of length {:.6} has no strip on its left",
                other_kind.neck_name(),
                m.length
            ));
            continue;
        };
        let t = match tightened(tighten(&geometry, &crossings, &faces, &options.tighten)) {
            Ok(t) => t,
            Err(reason) => {
                failures.push(format!(
                    "the path across the {} loop of length {:.6} was not kept: {reason}",
                    other_kind.neck_name(),
                    m.length
                ));
                continue;
            }
        };
        let candidate = measures.candidate(t, 0.0, Initial::Linked, true);
        if candidate.areas.is_some() || !basis.insert(&candidate.class) {
            failures.push(format!(
                "the path across the {} loop of length {:.6} tightened into a class the side has",
                other_kind.neck_name(),
                m.length
            ));
            continue;
        }
        let center = centroid(&candidate.tightened.points);
        let seed = Seed {
            position: center,
            normal: best_fit_normal(&candidate.tightened.points, center),
            persistence: 0,
            role: None,
            scales: (0.0, None),
            bulge: None,
            lobe: None,
            needs_opening: false,
            disk_only: false,
        };
        let index = first_seed + result.loops.len();
        let mut l = neck_loop(
            kind,
            &seed,
            index,
            candidate,
            options,
            loop_surface.basis.len(),
        );
        l.membrane = SurfaceMesh::default();
        l.reason = format!(
            "completes the genus: a class that bounds on this side but no disk (a knotted part); a shortest closed path of surface edges of linking number 0 with each of the {} side's {} cycles that crosses its {} loop of length {:.6} an odd number of times, tightened from {:.6} to {:.6}",
            other_kind.name(),
            cycles.len(),
            other_kind.neck_name(),
            other[j].length,
            l.initial_length,
            l.length
        );
        result.loops.push(l);
    }
    if basis.rank() < genus {
        let why = if failures.is_empty() {
            "the linked search ran out of the other side's loops".to_string()
        } else {
            failures.join("; ")
        };
        result.shortfalls = shortfall(basis.rank(), why);
    }
    result
}

/// Per edge of `topology` and cycle `i` (`g` numbers per edge, edge-major): the signed
/// number of times the edge, from its first stored vertex to its second, crosses the fan
/// of triangles from `cycles[i]`'s centroid (+1 along the fan's normal; any apex spans
/// the cycle). Summed round a closed path of edges, each with the sign of the way it is
/// walked, that is the path's linking number with the cycle.
fn link_counts(surface: &SurfaceMesh, topology: &Topology, cycles: &[Vec<[f64; 3]>]) -> Vec<i32> {
    let g = cycles.len();
    let mut counts = vec![0i32; topology.num_edges() * g];
    for (i, cycle) in cycles.iter().enumerate() {
        let n = cycle.len();
        if n < 2 {
            continue;
        }
        let c = centroid(cycle);
        let fan: Vec<[[f64; 3]; 3]> = (0..n).map(|k| [c, cycle[k], cycle[(k + 1) % n]]).collect();
        let boxes: Vec<([f64; 3], [f64; 3])> = fan.iter().map(|t| bounds(*t)).collect();
        let all = bounds(fan.iter().flatten().copied());
        for (e, &[a, b]) in topology.edges().iter().enumerate() {
            let (p, q) = (surface.positions[a as usize], surface.positions[b as usize]);
            let edge_box = bounds([p, q]);
            if !overlap(edge_box, all) {
                continue;
            }
            counts[e * g + i] = fan
                .iter()
                .zip(&boxes)
                .filter(|(_, &b)| overlap(edge_box, b))
                .map(|(t, _)| crossing_sign(p, q, t))
                .sum();
        }
    }
    counts
}

fn overlap(a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3])) -> bool {
    (0..3).all(|k| a.0[k] <= b.1[k] && b.0[k] <= a.1[k])
}

/// +1 or −1 where the segment `p q` passes through the triangle `t` along or against
/// its normal, else 0: its ends on opposite sides of the triangle's plane (a point on
/// the plane counts as below), and the line through them on the same side of the
/// triangle's three edges.
fn crossing_sign(p: [f64; 3], q: [f64; 3], t: &[[f64; 3]; 3]) -> i32 {
    let [a, b, c] = *t;
    let normal = cross(sub(b, a), sub(c, a));
    let above = |x: [f64; 3]| dot(normal, sub(x, a)) > 0.0;
    if above(p) == above(q) {
        return 0;
    }
    let d = sub(q, p);
    let side = |u: [f64; 3], v: [f64; 3]| dot(d, cross(sub(u, p), sub(v, p))) > 0.0;
    let s = side(a, b);
    if s != side(b, c) || s != side(c, a) {
        return 0;
    }
    if above(q) {
        1
    } else {
        -1
    }
}

/// The states of the search: per vertex, each cycle's linking count so far in
/// `[−reach, reach]` and the parity of the other side's loop's crossings.
#[derive(Debug, Clone, Copy)]
struct Layers {
    /// Cycles.
    cycles: usize,
    /// Largest linking count a path may hold on its way.
    reach: i32,
    /// States per vertex: `2 (2 reach + 1)^cycles`.
    per_vertex: usize,
}

impl Layers {
    /// The widest reach up to `max_reach` whose states fit in `max_states` over
    /// `vertices`; `None` under a reach of 1.
    fn fitting(
        cycles: usize,
        vertices: usize,
        max_states: usize,
        max_reach: i32,
    ) -> Option<Layers> {
        (1..=max_reach).rev().find_map(|reach| {
            let width = 2 * reach as usize + 1;
            let per_vertex = (0..cycles).try_fold(2usize, |n, _| n.checked_mul(width))?;
            (per_vertex.checked_mul(vertices)? <= max_states).then_some(Layers {
                cycles,
                reach,
                per_vertex,
            })
        })
    }

    /// The state index of `counts` and `parity`.
    fn code(&self, counts: &[i32], parity: bool) -> usize {
        let width = 2 * self.reach as usize + 1;
        counts
            .iter()
            .rev()
            .fold(0, |code, &c| code * width + (c + self.reach) as usize)
            * 2
            + usize::from(parity)
    }

    /// The counts and parity of a state index (`counts` has one slot per cycle).
    fn decode(&self, mut code: usize, counts: &mut [i32]) -> bool {
        let width = 2 * self.reach as usize + 1;
        let parity = code % 2 == 1;
        code /= 2;
        for c in counts.iter_mut() {
            *c = (code % width) as i32 - self.reach;
            code /= width;
        }
        parity
    }
}

/// Largest linking count a search path may hold on its way round.
pub const MAX_REACH: i32 = 8;

/// Vertices of the other side's loop that searches start from. A closed path that
/// crosses the loop passes one of its crossed edges; starting at a few of them, the
/// path found may be longer than the shortest, and tightening shortens it.
pub const SOURCES: usize = 4;

/// The shortest closed path of edges whose linking counts with every cycle sum to 0
/// and which crosses the marked edges `crosses` an odd number of times: Dijkstra over
/// the states of `layers` from each vertex of a cover of the marked edges (the path uses
/// one of them), in vertex order, each search stopped at the best length so far. The
/// path's vertices, the first not repeated at the end.
fn shortest_cycle(
    surface: &SurfaceMesh,
    topology: &Topology,
    links: &[i32],
    crosses: &[bool],
    layers: Layers,
) -> Option<Vec<u32>> {
    let edges = topology.edges();
    let (g, per) = (layers.cycles, layers.per_vertex);
    let nv = surface.num_vertices();
    // A cover of the marked edges (the lower end unless the upper is taken already),
    // and [`SOURCES`] of its vertices spread over it in index order.
    let mut cover = vec![false; nv];
    for (e, &[a, b]) in edges.iter().enumerate() {
        if crosses[e] && !cover[a as usize] && !cover[b as usize] {
            cover[a.min(b) as usize] = true;
        }
    }
    let cover: Vec<usize> = (0..nv).filter(|&v| cover[v]).collect();
    let mut sources: Vec<usize> = (0..SOURCES)
        .map(|k| cover[k * cover.len() / SOURCES])
        .collect();
    sources.dedup();
    let length = |e: usize| {
        let [a, b] = edges[e];
        norm(sub(
            surface.positions[a as usize],
            surface.positions[b as usize],
        ))
    };
    let zero = vec![0i32; g];
    let (start_code, goal_code) = (layers.code(&zero, false), layers.code(&zero, true));
    let mut distance = vec![f64::INFINITY; nv * per];
    let mut parent = vec![u32::MAX; nv * per];
    let mut touched = Vec::new();
    let mut counts = vec![0i32; g];
    let mut best: Option<(f64, Vec<u32>)> = None;
    if cover.is_empty() {
        return None;
    }
    for s in sources {
        for &state in &touched {
            distance[state] = f64::INFINITY;
            parent[state] = u32::MAX;
        }
        touched.clear();
        let bound = best.as_ref().map_or(f64::INFINITY, |b| b.0);
        let (origin, goal) = (s * per + start_code, s * per + goal_code);
        distance[origin] = 0.0;
        touched.push(origin);
        // Non-negative floats order like their bit patterns.
        let mut heap = BinaryHeap::from([Reverse((0u64, origin))]);
        while let Some(Reverse((d, state))) = heap.pop() {
            let d = f64::from_bits(d);
            if d > distance[state] {
                continue;
            }
            if d >= bound || state == goal {
                break;
            }
            let v = state / per;
            let parity = layers.decode(state % per, &mut counts);
            'edges: for &e in topology.vertex_edges(v) {
                let e = e as usize;
                let [a, b] = edges[e];
                let (w, sign) = if a as usize == v { (b, 1) } else { (a, -1) };
                let mut next_counts = [0i32; 64];
                for i in 0..g {
                    let c = counts[i] + sign * links[e * g + i];
                    if c.abs() > layers.reach {
                        continue 'edges;
                    }
                    next_counts[i] = c;
                }
                let next = w as usize * per + layers.code(&next_counts[..g], parity ^ crosses[e]);
                let dn = d + length(e);
                if dn < distance[next] {
                    if distance[next].is_infinite() {
                        touched.push(next);
                    }
                    distance[next] = dn;
                    parent[next] = state as u32;
                    heap.push(Reverse((dn.to_bits(), next)));
                }
            }
        }
        if distance[goal] < bound {
            let mut path = Vec::new();
            let mut state = goal;
            while state != origin {
                path.push((state / per) as u32);
                state = parent[state] as usize;
            }
            path.reverse();
            best = Some((distance[goal], path));
        }
    }
    best.map(|(_, path)| path)
}

/// The closed vertex path moved onto the faces on its left: at each vertex, the faces
/// turned through from the edge it came in by to the edge it leaves by, the edges
/// between them crossed near the vertex. In the form [`tighten`] takes (crossings, and
/// the face after each); `None` where the surface is not oriented along the path or the
/// path turns through no edge at all.
fn left_strip(
    surface: &SurfaceMesh,
    topology: &Topology,
    path: &[u32],
) -> Option<(Vec<Crossing>, Vec<u32>)> {
    let n = path.len();
    if n < 3 {
        return None;
    }
    let tri = |f: u32| surface.triangles[f as usize];
    // The face holding the directed side u → v.
    let left_of = |u: u32, v: u32| {
        topology
            .vertex_faces(u as usize)
            .iter()
            .copied()
            .find(|&f| {
                let t = tri(f);
                (0..3).any(|i| t[i] == u && t[(i + 1) % 3] == v)
            })
    };
    let mut crossings = Vec::new();
    let mut faces = Vec::new();
    for i in 0..n {
        let (u, v, w) = (path[(i + n - 1) % n], path[i], path[(i + 1) % n]);
        let mut face = left_of(u, v)?;
        for _ in 0..=topology.vertex_faces(v as usize).len() {
            let t = tri(face);
            let at = (0..3).find(|&k| t[k] == v)?;
            let q = t[(at + 1) % 3];
            if q == w {
                break;
            }
            // Cross the side v q into the face that holds q → v.
            let e = (0..3)
                .filter_map(|k| topology.face_edge(face as usize, k))
                .find(|&e| {
                    let [a, b] = topology.edges()[e];
                    (a == v && b == q) || (a == q && b == v)
                })?;
            let [a, _] = topology.edges()[e];
            crossings.push(Crossing {
                edge: e as u32,
                t: if a == v { 0.25 } else { 0.75 },
            });
            face = left_of(q, v)?;
            faces.push(face);
        }
        if tri(face)
            .iter()
            .position(|&x| x == v)
            .map(|at| tri(face)[(at + 1) % 3])
            != Some(w)
        {
            return None;
        }
    }
    (!crossings.is_empty()).then_some((crossings, faces))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_through_a_triangle_crosses_it_with_the_sign_of_its_normal() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let (below, above) = ([0.2, 0.2, -1.0], [0.2, 0.2, 1.0]);
        assert_eq!(crossing_sign(below, above, &t), 1);
        assert_eq!(crossing_sign(above, below, &t), -1);
        // Beside the triangle, or not reaching its plane.
        assert_eq!(crossing_sign([0.8, 0.8, -1.0], [0.8, 0.8, 1.0], &t), 0);
        assert_eq!(crossing_sign([0.2, 0.2, 0.5], [0.2, 0.2, 1.0], &t), 0);
    }

    #[test]
    fn layer_codes_round_trip_and_fit_their_bound() {
        let layers = Layers::fitting(2, 10, 10 * 2 * 25, MAX_REACH).unwrap();
        assert_eq!((layers.reach, layers.per_vertex), (2, 50));
        let mut counts = [0i32; 2];
        for code in 0..layers.per_vertex {
            let parity = layers.decode(code, &mut counts);
            assert!(counts.iter().all(|c| c.abs() <= 2));
            assert_eq!(layers.code(&counts, parity), code);
        }
        assert!(Layers::fitting(3, 10, 10 * 2 * 26, MAX_REACH).is_none());
    }

    #[test]
    fn a_path_round_a_segment_links_it_once_and_a_path_beside_it_never() {
        // An octahedron's equator round the z axis, and the axis as a thin closed cycle
        // (up the axis, back down beside it): the equator's four edges link it once,
        // a meridian (through both poles) not at all.
        let positions = vec![
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let mut triangles = Vec::new();
        for i in 0..4u32 {
            let j = (i + 1) % 4;
            triangles.push([i, j, 4]);
            triangles.push([j, i, 5]);
        }
        let surface = SurfaceMesh::new(positions, triangles).unwrap();
        let topology = Topology::new(&surface);
        let cycle = vec![
            [0.01, 0.02, -0.5],
            [0.01, 0.02, 0.5],
            [5.0, 0.02, 0.5],
            [5.0, 0.02, -0.5],
        ];
        let links = link_counts(&surface, &topology, &[cycle]);
        let walk = |path: &[u32]| -> i32 {
            let n = path.len();
            (0..n)
                .map(|k| {
                    let (a, b) = (path[k], path[(k + 1) % n]);
                    let e = topology
                        .edges()
                        .iter()
                        .position(|&[x, y]| (x, y) == (a, b) || (x, y) == (b, a))
                        .unwrap();
                    let sign = if topology.edges()[e][0] == a { 1 } else { -1 };
                    sign * links[e]
                })
                .sum()
        };
        assert_eq!(walk(&[0, 1, 2, 3]).abs(), 1);
        assert_eq!(walk(&[0, 4, 2, 5]), 0);
        assert_eq!(walk(&[1, 4, 3, 5]), 0);
    }
}
