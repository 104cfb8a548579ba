//! The Delaunay tetrahedralization of a point set (Bowyer–Watson).
//!
//! Computes the tets of the Delaunay tetrahedralization of `points`: every tet's
//! circumsphere holds no point strictly inside. It is the first step of a mesher whose
//! size follows the surface (`sampled`): the tets are later kept or dropped by the
//! domain, so the set need not be convex.
//!
//! Algorithm (Bowyer 1981, Watson 1981): the points are inserted one at a time, in the
//! order of a Morton curve over their bounding box so that each lands near the last,
//! into the tetrahedralization of four far points that enclose them all. A point is
//! located by a visibility walk from the last tet made; the tets whose circumsphere
//! holds it strictly (the cavity, found by a search over neighbours from the tet that
//! holds it) are removed, and each face of the cavity's boundary is joined to the point.
//!
//! Robustness: the orientation and in-sphere tests are Shewchuk's exact adaptive
//! predicates (the `robust` crate, named here and in `distance::crossing` alone). With a strict
//! in-sphere test the cavity is star-shaped from the point even where five points are
//! cospherical (a lattice, the corners of a rectangle on the surface): a boundary face
//! coplanar with the point would put the point strictly inside the circumcircle of the
//! face and so inside the neighbour's circumsphere too, which the strict test excludes.
//! So no flat tet is ever made, whatever the input's degeneracies; cospherical points
//! get one of their Delaunay tetrahedralizations. Points at the same position as an
//! earlier one are not inserted (reported in [`Delaunay::duplicates`]).
//!
//! The four far points sit at 1000 times the points' extent; tets that use one are
//! dropped at the end. Near the convex hull a few tets may then be missing where a far
//! point still sees a hull face (the hull is not recovered exactly); the mesher that
//! uses this module keeps tets by the domain, well inside the hull.
//!
//! Conventions: output tets are positively oriented as in [`crate::tet`]
//! (`(b − a) · ((c − a) × (d − a)) > 0`); the result does not depend on the thread count
//! (the insertion is sequential). Entry point: [`Tetrahedralization`] (points added in
//! batches, as the sampled mesher recovers its boundary).

use robust::{insphere, orient3d, Coord3D};

use super::repair::faces_of;
use rustc_hash::FxHashMap as HashMap;

/// No neighbour (a face on the outside of the far points).
pub(super) const NONE: u32 = u32::MAX;

/// The far points' distance from the centre, in units of the points' extent.
const FAR: f64 = 1000.0;

/// The Delaunay tetrahedralization of a point set (all at once: the tests' entry).
#[cfg(test)]
#[derive(Debug, Clone, Default)]
pub struct Delaunay {
    /// Tets as indices into the points, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// Points not inserted because an earlier point has the same position: (point,
    /// the earlier point).
    pub duplicates: Vec<(u32, u32)>,
}

/// The Delaunay tetrahedralization of `points` (finite coordinates). Fewer than four
/// points, or points all on one plane, give no tets.
#[cfg(test)]
pub fn delaunay(points: &[[f64; 3]]) -> Delaunay {
    if points.len() < 4 {
        return Delaunay::default();
    }
    let mut t = Tetrahedralization::new(crate::geom::bounds(points.iter().copied()));
    let duplicates = t.insert(points);
    Delaunay {
        tets: t.tets(),
        duplicates,
    }
}

/// A Delaunay tetrahedralization that points can be added to, in batches. Points are
/// numbered in the order of the batches.
pub struct Tetrahedralization {
    t: Triangulation,
}

impl Tetrahedralization {
    /// An empty one, for points within the box `(lo, hi)`.
    pub fn new((lo, hi): ([f64; 3], [f64; 3])) -> Self {
        Tetrahedralization {
            t: Triangulation::new(lo, hi),
        }
    }

    /// Add `points` (within the box), in Morton order. Returns the points not inserted
    /// because an earlier point has the same position: (point, the earlier point).
    pub fn insert(&mut self, points: &[[f64; 3]]) -> Vec<(u32, u32)> {
        let first = self.t.points.len() as u32;
        self.t.points.extend(points);
        let (lo, hi) = crate::geom::bounds(points.iter().copied());
        let mut duplicates = Vec::new();
        for i in morton_order(points, lo, hi) {
            if let Some(earlier) = self.t.insert(first + i) {
                duplicates.push((first + i - FAR_POINTS as u32, earlier - FAR_POINTS as u32));
            }
        }
        duplicates.sort_unstable();
        duplicates
    }

    /// The tets without a far point, positively oriented, sorted.
    pub fn tets(&self) -> Vec<[u32; 4]> {
        self.t.finish()
    }

    /// The faces of the tets without a far point, each as its sorted corners.
    pub fn face_set(&self) -> rustc_hash::FxHashSet<[u32; 3]> {
        self.t.finish().iter().flat_map(faces_of).collect()
    }
}

/// The far points come first in the triangulation's numbering.
pub(super) const FAR_POINTS: usize = 4;

/// The points' indices along a Morton (Z-order) curve over their bounding box, ties by
/// index.
pub(super) fn morton_order(points: &[[f64; 3]], lo: [f64; 3], hi: [f64; 3]) -> Vec<u32> {
    let extent = (0..3)
        .map(|k| hi[k] - lo[k])
        .fold(0.0, f64::max)
        .max(1e-300);
    let spread = |x: u64| {
        // 21 bits spread to every third bit.
        let mut x = x & 0x1f_ffff;
        x = (x | x << 32) & 0x1f00000000ffff;
        x = (x | x << 16) & 0x1f0000ff0000ff;
        x = (x | x << 8) & 0x100f00f00f00f00f;
        x = (x | x << 4) & 0x10c30c30c30c30c3;
        (x | x << 2) & 0x1249249249249249
    };
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let q = |k: usize| (((p[k] - lo[k]) / extent) * 2_097_151.0) as u64;
            (
                spread(q(0)) | spread(q(1)) << 1 | spread(q(2)) << 2,
                i as u32,
            )
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The tets a point's insertion removes, and the faces of their union's boundary.
pub(super) struct Cavity {
    /// The tets whose circumsphere holds the point strictly (connected).
    pub(super) tets: Vec<u32>,
    /// Each face of the cavity's boundary: a cavity tet and its corner opposite the face.
    pub(super) boundary: Vec<(u32, usize)>,
}

/// Tets under construction: vertices (the four far points, then the points), and per
/// tet the neighbour across the face opposite each corner. Refinement (`refined`) works
/// on it directly.
pub(super) struct Triangulation {
    /// The points, then the four far points.
    pub(super) points: Vec<[f64; 3]>,
    /// Tets with `orient3d(a, b, c, d) > 0` (Shewchuk's sign: `d` below `abc`).
    pub(super) tets: Vec<[u32; 4]>,
    /// `neighbours[t][i]`: the tet across the face opposite corner `i`.
    pub(super) neighbours: Vec<[u32; 4]>,
    /// Removed tets, whose slots are reused.
    free: Vec<u32>,
    pub(super) alive: Vec<bool>,
    /// The tet the next walk starts from.
    last: u32,
    /// Per tet, the insertion that last visited it (the cavity search's marks).
    visited: Vec<u32>,
    stamp: u32,
    /// The walk's random face order (a fixed sequence).
    rng: u64,
}

fn coord(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

impl Triangulation {
    pub(super) fn new(lo: [f64; 3], hi: [f64; 3]) -> Self {
        let centre = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let extent = (0..3)
            .map(|k| hi[k] - lo[k])
            .fold(0.0, f64::max)
            .max(1e-300);
        let r = FAR * extent;
        // A regular tetrahedron's corners around the centre.
        let far = [[r, r, r], [r, -r, -r], [-r, r, -r], [-r, -r, r]]
            .map(|d| [0, 1, 2].map(|k| centre[k] + d[k]));
        let mut tet = [0, 1, 2, 3];
        if orient3d(coord(far[0]), coord(far[1]), coord(far[2]), coord(far[3])) < 0.0 {
            tet.swap(0, 1);
        }
        Triangulation {
            points: far.to_vec(),
            tets: vec![tet],
            neighbours: vec![[NONE; 4]],
            free: Vec::new(),
            alive: vec![true],
            last: 0,
            visited: vec![0],
            stamp: 0,
            rng: 0x9e37_79b9_7f4a_7c15,
        }
    }

    fn orient(&self, t: [u32; 4]) -> f64 {
        let p = |i: usize| coord(self.points[t[i] as usize]);
        orient3d(p(0), p(1), p(2), p(3))
    }

    /// Whether point `v` is strictly inside tet `t`'s circumsphere.
    fn in_sphere(&self, t: u32, v: u32) -> bool {
        let c = self.tets[t as usize];
        let p = |i: u32| coord(self.points[i as usize]);
        insphere(p(c[0]), p(c[1]), p(c[2]), p(c[3]), p(v)) > 0.0
    }

    fn next_random(&mut self) -> u64 {
        // xorshift64: a fixed sequence, so the result is the same on every run.
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        self.rng
    }

    /// The tet that holds point `v` (closed), by a visibility walk from the last tet.
    fn locate(&mut self, v: u32) -> u32 {
        let mut t = self.last;
        'walk: loop {
            let start = (self.next_random() % 4) as usize;
            for k in 0..4 {
                let i = (start + k) % 4;
                let mut moved = self.tets[t as usize];
                moved[i] = v;
                if self.orient(moved) < 0.0 {
                    let next = self.neighbours[t as usize][i];
                    if next != NONE {
                        t = next;
                        continue 'walk;
                    }
                }
            }
            return t;
        }
    }

    /// Insert point `v`; returns the earlier point at the same position instead, if any.
    fn insert(&mut self, v: u32) -> Option<u32> {
        match self.cavity(v) {
            Ok(cavity) => {
                self.fill(v, &cavity);
                None
            }
            Err(same) => Some(same),
        }
    }

    /// The cavity of point `v` (not yet inserted): the tets whose circumsphere holds it
    /// strictly, connected to the one that holds it, and the faces of its boundary (tet,
    /// corner opposite). Nothing changes. Returns the earlier point at the same position
    /// instead, if any.
    pub(super) fn cavity(&mut self, v: u32) -> std::result::Result<Cavity, u32> {
        let start = self.locate(v);
        let position = self.points[v as usize];
        if let Some(&same) = self.tets[start as usize]
            .iter()
            .find(|&&c| self.points[c as usize] == position)
        {
            return Err(same);
        }
        self.stamp += 1;
        let stamp = self.stamp;
        let mut tets = vec![start];
        self.visited[start as usize] = stamp;
        let mut boundary: Vec<(u32, usize)> = Vec::new();
        let mut head = 0;
        while head < tets.len() {
            let t = tets[head];
            head += 1;
            for i in 0..4 {
                let next = self.neighbours[t as usize][i];
                if next != NONE && self.visited[next as usize] == stamp {
                    continue;
                }
                if next != NONE && self.in_sphere(next, v) {
                    self.visited[next as usize] = stamp;
                    tets.push(next);
                } else {
                    boundary.push((t, i));
                }
            }
        }
        Ok(Cavity { tets, boundary })
    }

    /// Replace `cavity` (of point `v`, just found by [`Self::cavity`]) by the tets that
    /// join each face of its boundary to `v`. Returns the new tets' slots (the cavity's
    /// slots are reused first).
    pub(super) fn fill(&mut self, v: u32, cavity: &Cavity) -> Vec<u32> {
        // Each boundary face joined to the point: tet `t` with corner `i` replaced. The
        // faces through the point are shared by two new tets, matched by their edge.
        let boundary = &cavity.boundary;
        let mut made = Vec::with_capacity(boundary.len());
        let mut edges: HashMap<(u32, u32), (u32, usize)> = HashMap::default();
        let mut new_tets = Vec::with_capacity(boundary.len());
        for &(t, i) in boundary {
            let mut tet = self.tets[t as usize];
            tet[i] = v;
            let outside = self.neighbours[t as usize][i];
            // Where the outside tet points back (found before any slot is reused).
            let back = if outside == NONE {
                0
            } else {
                self.neighbours[outside as usize]
                    .iter()
                    .position(|&n| n == t)
                    .expect("the outside tet faces the cavity")
            };
            new_tets.push((tet, outside, back));
        }
        for t in &cavity.tets {
            self.alive[*t as usize] = false;
            self.free.push(*t);
        }
        for (tet, outside, back) in new_tets {
            let slot = match self.free.pop() {
                Some(s) => {
                    self.tets[s as usize] = tet;
                    self.neighbours[s as usize] = [NONE; 4];
                    self.alive[s as usize] = true;
                    s
                }
                None => {
                    self.tets.push(tet);
                    self.neighbours.push([NONE; 4]);
                    self.alive.push(true);
                    self.visited.push(0);
                    (self.tets.len() - 1) as u32
                }
            };
            let i = tet
                .iter()
                .position(|&c| c == v)
                .expect("the point is a corner");
            self.neighbours[slot as usize][i] = outside;
            if outside != NONE {
                self.neighbours[outside as usize][back] = slot;
            }
            for j in 0..4 {
                if j == i {
                    continue;
                }
                let mut e = [0u32; 2];
                let mut k = 0;
                for (m, &c) in tet.iter().enumerate() {
                    if m != i && m != j {
                        e[k] = c;
                        k += 1;
                    }
                }
                let key = (e[0].min(e[1]), e[0].max(e[1]));
                match edges.remove(&key) {
                    Some((other, oj)) => {
                        self.neighbours[slot as usize][j] = other;
                        self.neighbours[other as usize][oj] = slot;
                    }
                    None => {
                        edges.insert(key, (slot, j));
                    }
                }
            }
            made.push(slot);
        }
        debug_assert!(edges.is_empty(), "the cavity's boundary is closed");
        self.last = made[0];
        made
    }

    /// The live tets without a far point, numbered without the far points, in our
    /// orientation, sorted.
    fn finish(&self) -> Vec<[u32; 4]> {
        let far = FAR_POINTS as u32;
        let mut out: Vec<[u32; 4]> = self
            .tets
            .iter()
            .zip(&self.alive)
            .filter(|(t, &alive)| alive && t.iter().all(|&c| c >= far))
            .map(|(t, _)| {
                // Shewchuk's positive orientation is our negative one.
                [t[1] - far, t[0] - far, t[2] - far, t[3] - far]
            })
            .collect();
        out.sort_unstable();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{cross, dot, sub};

    fn volume(p: [[f64; 3]; 4]) -> f64 {
        dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0]))) / 6.0
    }

    fn random_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    fn corners() -> Vec<[f64; 3]> {
        let mut c = Vec::new();
        for i in 0..8 {
            c.push([(i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64]);
        }
        c
    }

    fn check_empty_spheres(points: &[[f64; 3]], tets: &[[u32; 4]]) {
        for t in tets {
            let p = t.map(|i| coord(points[i as usize]));
            // Ours positive is Shewchuk's negative: swap two for insphere.
            for (k, q) in points.iter().enumerate() {
                if t.contains(&(k as u32)) {
                    continue;
                }
                let s = insphere(p[1], p[0], p[2], p[3], coord(*q));
                assert!(s <= 0.0, "point {k} inside the circumsphere of {t:?}");
            }
        }
    }

    #[test]
    fn random_points_in_a_cube_fill_it_with_empty_circumspheres_and_no_flat_tet() {
        let mut points = corners();
        points.extend(random_points(300, 7));
        let d = delaunay(&points);
        assert!(d.duplicates.is_empty());
        let total: f64 = d
            .tets
            .iter()
            .map(|t| {
                let v = volume(t.map(|i| points[i as usize]));
                assert!(v > 0.0, "{t:?} is not positive: {v}");
                v
            })
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        check_empty_spheres(&points, &d.tets);
        // A ball: V − E + F − T = 1, every point used.
        let topology = crate::tet::TetMesh::new(
            points.clone(),
            d.tets.clone(),
            vec![crate::tet::VertexKind::Interior; points.len()],
        )
        .expect("a valid mesh")
        .euler_characteristic();
        assert_eq!(topology, 1);
    }

    #[test]
    fn a_cubic_lattice_all_cospherical_gets_positive_tets_that_fill_it() {
        // Every cube of the lattice has eight cospherical corners.
        let n = 6;
        let mut points = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    points.push([i as f64, j as f64, k as f64]);
                }
            }
        }
        // The same points again: reported, not inserted.
        points.push([2.0, 3.0, 4.0]);
        let d = delaunay(&points);
        assert_eq!(d.duplicates, vec![(216, (2 * n * n + 3 * n + 4) as u32)]);
        let mut total = 0.0;
        for t in &d.tets {
            let v = volume(t.map(|i| points[i as usize]));
            assert!(v > 1e-12, "{t:?} is flat: {v}");
            total += v;
        }
        let side = (n - 1) as f64;
        assert!((total - side * side * side).abs() < 1e-9, "{total}");
        check_empty_spheres(&points, &d.tets);
    }

    #[test]
    fn coplanar_or_too_few_points_give_no_tets() {
        assert!(delaunay(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .tets
            .is_empty());
        let flat: Vec<[f64; 3]> = (0..20)
            .map(|i| [(i % 5) as f64, (i / 5) as f64, 0.0])
            .collect();
        assert!(delaunay(&flat).tets.is_empty());
    }
}
