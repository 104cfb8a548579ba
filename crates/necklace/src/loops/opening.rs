//! How the surface opens out on the two sides of a loop: the neck test for separating
//! saddles whose lobe is not much fatter than the neck.
//!
//! A neck is where the surface is saddle-shaped all round the loop: walking away from
//! the loop, on either side, the curves parallel to it get longer. On a side of a
//! geodesic loop of length `L₀`, let `L(δ)` be the length of the curve at geodesic
//! distance `δ`. Gauss–Bonnet on the band between the loop and that curve gives
//! `L'(δ) = −∫∫_band K dA`, so with the tent weight `φ(δ) = 1 − δ/W` on `[0, W]`
//!
//! ```text
//! opening = −(1/2π) ∫∫_side φ(δ) K dA = (L(W) − L₀) / (2π W),
//! ```
//!
//! the mean of `L'/2π` over the first `W` (for a surface of revolution: the mean sine of
//! the angle between its profile and the axis). With `W = L₀/2π` (the loop's radius),
//! `opening = L(W)/L₀ − 1`: how much longer the parallel curve one radius away is. A
//! cylinder gives 0 on both sides, a cone of half-angle α gives `+sin α` on its wide side
//! and `−sin α` on its narrow side, a side that closes within `W` (a cap) gives −1, and a
//! neck gives a positive value on both sides. Tube noise (a bump where tubes meet a few
//! radii away) stays near 0; the fertility's waist and baby's neck, whose inscribed radii
//! grow by only 10–35 % but whose girth grows fast on both sides, give 0.16 and 0.34.
//!
//! Discretely: `K dA` is the angle defect `2π − Σ angles` at each vertex (exact
//! Gauss–Bonnet on a polyhedral surface); `δ` is the edge-graph distance from the loop
//! (Dijkstra from the loop's crossing points, an upper bound of the geodesic distance),
//! up to `W`; the two sides are the vertices reached without crossing the loop or
//! passing through a vertex it passes from the corners on the left and on the right of
//! its segments. A vertex on the loop gives half its defect to each side.
//!
//! Entry points: [`Openings::new`] once per surface, [`Openings::of_loop`] per loop.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap, HashSet};

use crate::geom::{cross, dot, norm, sub};
use crate::mesh::{SurfaceMesh, Topology};

use super::classes::carrier;
use super::tighten::{SurfaceGeometry, SurfacePoint};

/// The angle defect of every vertex, and the length of every edge.
#[derive(Debug, Clone)]
pub struct Openings {
    /// `2π − Σ angles` (0 at a vertex on a boundary or non-manifold edge).
    defect: Vec<f64>,
    /// Per edge of the [`Topology`].
    length: Vec<f64>,
}

impl Openings {
    /// Angle defects and edge lengths, from the total angle at each vertex
    /// ([`SurfaceGeometry::total_angles`]). `O(V + E)`.
    pub fn new(surface: &SurfaceMesh, topology: &Topology, geometry: &SurfaceGeometry) -> Openings {
        let n = surface.num_vertices();
        let edges = topology.edges();
        let length = edges
            .iter()
            .map(|&[a, b]| {
                norm(sub(
                    surface.positions[a as usize],
                    surface.positions[b as usize],
                ))
            })
            .collect();
        let angle_sum = geometry.total_angles();
        let mut open = vec![false; n];
        for (e, &[a, b]) in edges.iter().enumerate() {
            if topology.edge_faces(e).len() != 2 {
                open[a as usize] = true;
                open[b as usize] = true;
            }
        }
        let defect = (0..n)
            .map(|v| {
                if open[v] {
                    0.0
                } else {
                    2.0 * std::f64::consts::PI - angle_sum[v]
                }
            })
            .collect();
        Openings { defect, length }
    }

    /// The opening of each side of the loop through `points` (at `positions`; it crosses
    /// the edges `crossed`, as [`classes::crossings`](super::classes::crossings) gives them),
    /// measured out to `reach` (`W`), smaller first. `None` when a side has no vertex
    /// within `reach` (edges longer than the loop's radius), or its two sides meet
    /// within `reach` (the band around it is not two-sided there: a short handle).
    pub fn of_loop(
        &self,
        surface: &SurfaceMesh,
        topology: &Topology,
        points: &[SurfacePoint],
        positions: &[[f64; 3]],
        crossed: &[usize],
        reach: f64,
    ) -> Option<[f64; 2]> {
        if !(reach > 0.0 && reach.is_finite()) {
            return None;
        }
        // Distances from the loop, out to `reach`.
        let mut on_loop = HashSet::new();
        let mut distance: HashMap<u32, f64> = HashMap::new();
        let mut heap = BinaryHeap::new();
        let mut seed = |v: u32, d: f64, heap: &mut BinaryHeap<Near>| {
            if distance.get(&v).is_none_or(|&old| d < old) {
                distance.insert(v, d);
                heap.push(Near(d, v));
            }
        };
        for p in points {
            match *p {
                SurfacePoint::Edge { edge: [a, b], t } => {
                    let length = norm(sub(
                        surface.positions[a as usize],
                        surface.positions[b as usize],
                    ));
                    seed(a, t * length, &mut heap);
                    seed(b, (1.0 - t) * length, &mut heap);
                }
                SurfacePoint::Vertex { vertex } => {
                    on_loop.insert(vertex);
                    seed(vertex, 0.0, &mut heap);
                }
            }
        }
        let mut settled: HashMap<u32, f64> = HashMap::new();
        while let Some(Near(d, v)) = heap.pop() {
            if d > reach || settled.contains_key(&v) {
                continue;
            }
            settled.insert(v, d);
            for (u, _, length) in self.slots(topology, v) {
                let du = d + length;
                if du <= reach && !settled.contains_key(&u) {
                    seed(u, du, &mut heap);
                }
            }
        }

        // The two sides: each face a segment of the loop lies in has its corners off the
        // loop on its left or right (the surface is oriented); floods from them through
        // the band, never across the loop, must not meet.
        let blocked: HashSet<u32> = crossed.iter().map(|&e| e as u32).collect();
        let mut side: HashMap<u32, u8> = HashMap::new();
        let mut stack = Vec::new();
        let n = points.len();
        for i in 0..n {
            let (a, b) = (positions[i], positions[(i + 1) % n]);
            // The faces the segment lies in: one, or the two of an edge it runs along.
            let ((p, pn), (q, qn)) = (carrier(points[i]), carrier(points[(i + 1) % n]));
            let carriers: Vec<u32> = p[..pn].iter().chain(&q[..qn]).copied().collect();
            let faces = topology
                .vertex_faces(carriers[0] as usize)
                .iter()
                .map(|&f| f as usize)
                .filter(|&f| carriers.iter().all(|v| surface.triangles[f].contains(v)));
            for f in faces {
                let normal = surface.face_normal_scaled(f);
                for v in surface.triangles[f] {
                    if on_loop.contains(&v) || !settled.contains_key(&v) {
                        continue;
                    }
                    let turn = dot(
                        cross(sub(b, a), sub(surface.positions[v as usize], a)),
                        normal,
                    );
                    if turn == 0.0 {
                        continue;
                    }
                    let label = u8::from(turn < 0.0);
                    match side.insert(v, label) {
                        None => stack.push(v),
                        Some(old) if old != label => return None,
                        Some(_) => {}
                    }
                }
            }
        }
        while let Some(v) = stack.pop() {
            let label = side[&v];
            for (u, e, _) in self.slots(topology, v) {
                if blocked.contains(&e) || on_loop.contains(&u) || !settled.contains_key(&u) {
                    continue;
                }
                match side.get(&u) {
                    None => {
                        side.insert(u, label);
                        stack.push(u);
                    }
                    Some(&l) if l == label => {}
                    Some(_) => return None,
                }
            }
        }

        // Summed in vertex order, so that the result does not depend on hashing.
        let mut members: Vec<(u32, u8)> = side.into_iter().collect();
        members.sort_unstable();
        let mut sums = [0.0f64; 2];
        let mut counts = [0usize; 2];
        for (v, label) in members {
            let weight = 1.0 - settled[&v] / reach;
            sums[label as usize] -= weight * self.defect[v as usize];
            counts[label as usize] += 1;
        }
        if counts.contains(&0) {
            return None;
        }
        // A vertex on the loop carries the curvature of the band around it: half to
        // each side.
        let mut on: Vec<u32> = on_loop.into_iter().collect();
        on.sort_unstable();
        for v in on {
            for sum in &mut sums {
                *sum -= 0.5 * self.defect[v as usize];
            }
        }
        let mut opening = sums.map(|s| s / (2.0 * std::f64::consts::PI));
        if opening[1] < opening[0] {
            opening.swap(0, 1);
        }
        Some(opening)
    }

    /// The neighbours of `v`, with the edge to each and its length.
    fn slots<'a>(
        &'a self,
        topology: &'a Topology,
        v: u32,
    ) -> impl Iterator<Item = (u32, u32, f64)> + 'a {
        topology.vertex_edges(v as usize).iter().map(move |&e| {
            let [a, b] = topology.edges()[e as usize];
            (if a == v { b } else { a }, e, self.length[e as usize])
        })
    }
}

/// A vertex and its distance, nearest first in a max-heap.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Near(f64, u32);

impl Eq for Near {}

impl PartialOrd for Near {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Near {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}
