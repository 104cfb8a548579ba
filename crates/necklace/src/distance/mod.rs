//! Distance queries on a triangle mesh: exact unsigned distance and closest point,
//! inside/outside by the generalized winding number, signed distance and ray hits.
//!
//! Entry point: [`SurfaceDistance::new`] builds, once, a bounding volume hierarchy over
//! the triangles (median splits, leaves of 4 to 8 triangles, flat arrays) and the
//! far-field expansions of the fast winding number on the same tree; the result is
//! read-only and `Send + Sync`, so one instance serves any number of threads.
//!
//! [`SurfaceDistance::of_surface`] is a run's one structure, shared by the input checks,
//! both volume meshes (the mesher's domain and its feature snapping), the distance field
//! and the loops: its crossings found once, and the sign taken from the closest point's
//! angle-weighted pseudonormal wherever that decides it
//! ([`SurfaceDistance::use_pseudonormal_sign`]: everywhere on a closed manifold that does
//! not cross itself; where it crosses itself or has non-manifold vertices, on each
//! triangle away from them whose side winding numbers, read once at four points, agree;
//! where it has holes, on each triangle far enough from them for a bound on the winding
//! number's change). Where the pseudonormals do not decide, the winding number is the
//! exact count of signed crossings along a segment from the nearest of a lattice of
//! anchors whose counts were taken once (or, where that segment is degenerate, out of
//! the tree's box; `crossing`), less, on a surface with holes, the winding number of
//! the cones that close them: it visits the leaves along one short segment, where the
//! fast winding number sums the solid angles of every triangle near the query,
//! hundreds where parts overlap or cross.
//! A dense input the pipeline simplifies is built [`SurfaceDistance::without_winding`] (no
//! winding expansions, no pseudonormals: the stages that ask signs work on the copy;
//! [`SurfaceDistance::add_winding`] adds the expansions); [`SurfaceDistance::recording`]
//! records crossings without the pseudonormal sign.
//!
//! Crossings: [`SurfaceDistance::self_intersections`] (pairs of faces meeting along a
//! segment longer than [`CROSSING_TOLERANCE`] of the diagonal, [`crossing_segment`], which
//! takes triangles coplanar up to rounding, [`COPLANAR_TOLERANCE`], as coplanar) and
//! [`crossings_among`] (those of some faces, after an edit). [`nesting`]: which component
//! encloses which, by winding numbers (the input step's orientation, the volume stage's
//! topology prediction).
//!
//! Conventions:
//! - Distances are Euclidean, in the units of the mesh positions, to the triangles
//!   themselves (not to the vertices); they are exact up to rounding.
//! - Signed distance is *negative inside* and positive outside. Inside means a
//!   winding number of at least 0.5, which reads a mesh with small holes, or one made
//!   of overlapping closed components (winding number 2 in the overlap), as a solid.
//! - Orientation: triangles counter-clockwise seen from outside (the crate's convention)
//!   give winding number 1 inside and 0 outside; a reversed mesh gives −1 inside.
//! - Degenerate input never panics: triangles with an out-of-range index or a
//!   non-finite corner are ignored, zero-area triangles are handled as segments or
//!   points, and a mesh without (usable) triangles has distance +∞ and winding number 0
//!   everywhere. A query with a NaN coordinate gets NaN.
//!
//! Batch queries ([`SurfaceDistance::distances`], [`SurfaceDistance::signed_distances`])
//! run in parallel with rayon, each point independently, so their results are the
//! per-point results bit for bit whatever the number of threads.

mod bvh;
mod crossing;
mod nesting;
mod pseudonormal;
mod winding;

pub use nesting::nesting;
pub use winding::BETA;

use rayon::prelude::*;

use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::mesh::SurfaceMesh;

use bvh::Bvh;
use pseudonormal::Pseudonormals;
use winding::Expansion;

/// Smallest ray parameter counted as a hit, relative to the mesh size: a hit must be
/// farther than `RAY_EPSILON` × (bounding-box diagonal) from the ray origin.
pub const RAY_EPSILON: f64 = 1e-12;

/// A closest point on the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// The closest point (on triangle `face`).
    pub point: [f64; 3],
    /// Its distance to the query.
    pub distance: f64,
    /// The mesh triangle it lies on ([`Closest::NO_FACE`] when there is none).
    pub face: u32,
}

impl Closest {
    /// The `face` of a query without answer (no usable triangle, or a NaN query).
    pub const NO_FACE: u32 = u32::MAX;
}

/// Distance, closest-point, winding-number and ray queries on one triangle mesh.
///
/// ```
/// # use necklace::{SurfaceMesh, distance::SurfaceDistance};
/// // A tetrahedron, outward oriented.
/// let mesh = SurfaceMesh {
///     positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
///     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
/// };
/// let sd = SurfaceDistance::new(&mesh);
/// assert!(sd.is_inside([0.1, 0.1, 0.1]));
/// assert!((sd.signed_distance([0.1, 0.1, 0.1]) + 0.1).abs() < 1e-12);
/// assert!((sd.distance([0.0, 0.0, -2.0]) - 2.0).abs() < 1e-12);
/// ```
#[derive(Clone)]
pub struct SurfaceDistance {
    bvh: Bvh,
    /// The fast winding number's far-field expansions (`None`: built without them,
    /// [`SurfaceDistance::without_winding`]; winding numbers are then exact).
    expansions: Option<Vec<Expansion>>,
    /// The sign from the closest point, when enabled (see
    /// [`SurfaceDistance::use_pseudonormal_sign`]).
    pseudonormals: Option<std::sync::Arc<Pseudonormals>>,
    /// Bounding-box diagonal of the usable triangles (the length scale of tolerances).
    scale: f64,
    /// The triangles that close the chain (none where the triangles already form a
    /// closed chain, `closed_chain`; cones over the unbalanced edges
    /// of one with holes), as found by [`SurfaceDistance::use_pseudonormal_sign`]: the
    /// winding number is then counted by crossings (`crossing`). `None` until then, or
    /// with more than [`crossing::MAX_CLOSURE`] unbalanced edges or triangles left out
    /// of the tree.
    closing: Option<std::sync::Arc<crossing::Closure>>,
    /// The crossing pairs of the mesh, when found once for all
    /// ([`SurfaceDistance::of_surface`], [`SurfaceDistance::with_crossings`]).
    crossings: Option<std::sync::Arc<Vec<[u32; 2]>>>,
}

impl std::fmt::Debug for SurfaceDistance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfaceDistance")
            .field("triangles", &self.bvh.tris.len())
            .field("nodes", &self.bvh.nodes.len())
            .field("scale", &self.scale)
            .finish()
    }
}

impl SurfaceDistance {
    /// Build the BVH over the triangles of `mesh` and the winding-number expansions.
    /// Triangles with an out-of-range index or a non-finite corner are left out.
    pub fn new(mesh: &SurfaceMesh) -> Self {
        let mut distance = SurfaceDistance::without_winding(mesh);
        distance.add_winding();
        distance
    }

    /// [`SurfaceDistance::new`] without the winding number's expansions: distances,
    /// closest points, rays and crossings for the cost of the tree alone, for a surface
    /// whose inside is asked about elsewhere (a dense surface the pipeline simplifies:
    /// the stages that need signs work on the copy). Winding numbers and signs are
    /// exact, `O(triangles)` per query, until [`add_winding`](Self::add_winding).
    pub fn without_winding(mesh: &SurfaceMesh) -> Self {
        let n = mesh.positions.len();
        let mut tris = Vec::with_capacity(mesh.triangles.len());
        let mut faces = Vec::with_capacity(mesh.triangles.len());
        for (f, t) in mesh.triangles.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= n) {
                continue;
            }
            let corners = t.map(|v| mesh.positions[v as usize]);
            if corners.iter().flatten().all(|c| c.is_finite()) {
                tris.push(corners);
                faces.push(f as u32);
            }
        }
        let bvh = Bvh::build(tris, faces);
        let scale = bvh
            .nodes
            .first()
            .map_or(0.0, |root| norm(sub(root.hi, root.lo)));
        SurfaceDistance {
            bvh,
            expansions: None,
            pseudonormals: None,
            scale,
            closing: None,
            crossings: None,
        }
    }

    /// Build the fast winding number's expansions, where they are missing.
    pub fn add_winding(&mut self) {
        if self.expansions.is_none() {
            self.expansions = Some(winding::expansions(&self.bvh));
        }
    }

    /// The distance structure of a surface the method runs on, built once per run and
    /// shared by every stage that asks about the surface (the input checks, both
    /// volume meshes, the distance field, the loops): [`SurfaceDistance::new`], its
    /// crossing pairs found once ([`SurfaceDistance::crossings`]) and the sign from the
    /// pseudonormals wherever they decide it ([`SurfaceDistance::use_pseudonormal_sign`]).
    pub fn of_surface(mesh: &SurfaceMesh) -> Self {
        let distance = SurfaceDistance::new(mesh);
        let crossings = distance.self_intersections(&mesh.triangles);
        distance.with_crossings(mesh, crossings)
    }

    /// Record `crossings`, the [`SurfaceDistance::self_intersections`] of `mesh` (the
    /// mesh this was built from), and take the sign from the pseudonormals wherever
    /// they decide it, as [`SurfaceDistance::of_surface`] does.
    pub fn with_crossings(self, mesh: &SurfaceMesh, crossings: Vec<[u32; 2]>) -> Self {
        let mut distance = self.recording(crossings);
        distance.use_pseudonormal_sign(mesh);
        distance
    }

    /// Record `crossings`, the [`SurfaceDistance::self_intersections`] of the mesh this
    /// was built from, without changing how signs are taken.
    pub fn recording(mut self, crossings: Vec<[u32; 2]>) -> Self {
        self.crossings = Some(std::sync::Arc::new(crossings));
        self
    }

    /// The crossing pairs of triangles recorded by [`SurfaceDistance::of_surface`] or
    /// [`SurfaceDistance::with_crossings`] (`None` when they were not looked for).
    pub fn crossings(&self) -> Option<&[[u32; 2]]> {
        self.crossings.as_deref().map(Vec::as_slice)
    }

    /// Take the sign of signed distances from the closest point's angle-weighted
    /// pseudonormal instead of the winding number: exact, and far cheaper near the
    /// surface. `mesh` must be the mesh this was built from. Without crossings recorded
    /// ([`SurfaceDistance::recording`]) the caller vouches that it does not cross itself,
    /// and the mesh qualifies when it is closed, manifold and consistently oriented.
    /// With crossings recorded (or a few non-manifold vertices, or holes) and the
    /// winding number's expansions built, every triangle away from them that its
    /// winding number confirms decides locally (near holes, only within a bound on the
    /// winding number's change), and the others leave the sign to the winding number
    /// (`pseudonormal`). Returns whether any triangle decides by its
    /// pseudonormal (the sign stays on the winding number otherwise).
    pub fn use_pseudonormal_sign(&mut self, mesh: &SurfaceMesh) -> bool {
        let complete = self.bvh.faces.len() == mesh.triangles.len();
        let unbalanced = unbalanced_sides(&mesh.triangles);
        self.closing = (complete && unbalanced.len() <= crossing::MAX_CLOSURE)
            .then(|| std::sync::Arc::new(crossing::Closure::new(&mesh.positions, &unbalanced)));
        let pseudonormals = match (&self.crossings, &self.expansions) {
            (Some(crossings), Some(expansions)) => {
                let winding = |p: [f64; 3]| self.winding_of_chain(expansions, p);
                let local = pseudonormal::Local {
                    crossings,
                    winding: &winding,
                };
                Pseudonormals::new(mesh, &self.bvh, Some(local))
            }
            _ => Pseudonormals::new(mesh, &self.bvh, None),
        };
        self.pseudonormals = pseudonormals.map(std::sync::Arc::new);
        self.pseudonormals.is_some()
    }

    /// The sign at `p` whose closest point on tree triangle `t` is `q`: from the
    /// pseudonormals when enabled and decisive, else from the winding number.
    fn sign_at(&self, p: [f64; 3], nearest: Option<(usize, [f64; 3])>) -> f64 {
        if let (Some(pn), Some((t, q))) = (&self.pseudonormals, nearest) {
            if let Some(s) = pn.sign(t, &self.bvh.tris[t], q, p) {
                return s;
            }
        }
        if self.is_inside(p) {
            -1.0
        } else {
            1.0
        }
    }

    /// Number of triangles used (those of the mesh less the unusable ones).
    pub fn num_triangles(&self) -> usize {
        self.bvh.tris.len()
    }

    /// Bounding-box diagonal of the triangles used (0 for none).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Exact unsigned distance from `p` to the nearest triangle (+∞ without triangles).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.closest_point(p).distance
    }

    /// The closest point on the surface to `p`, its distance and its triangle. Without
    /// triangles: distance +∞, point NaN, face [`Closest::NO_FACE`]; for a NaN query the
    /// distance is NaN too.
    pub fn closest_point(&self, p: [f64; 3]) -> Closest {
        self.closest_point_within(p, f64::INFINITY)
    }

    /// [`closest_point`](Self::closest_point) among the triangles closer than `limit`
    /// (the same answer when the closest is closer; otherwise distance +∞, point NaN,
    /// face [`Closest::NO_FACE`]), pruning everything farther.
    pub fn closest_point_within(&self, p: [f64; 3], limit: f64) -> Closest {
        let none = |distance| Closest {
            point: [f64::NAN; 3],
            distance,
            face: Closest::NO_FACE,
        };
        if p.iter().any(|c| c.is_nan()) || limit.is_nan() {
            return none(f64::NAN);
        }
        match self.bvh.nearest_within(p, limit * limit) {
            Some((t, point, d2)) => Closest {
                point,
                distance: d2.sqrt(),
                face: self.bvh.faces[t],
            },
            None => none(f64::INFINITY),
        }
    }

    /// Generalized winding number at `p` by the fast hierarchical approximation
    /// (Barill et al. 2018, third-order expansions, β = [`BETA`]): typically within a few
    /// 10⁻³ of [`winding_number_exact`](Self::winding_number_exact) away from the surface
    /// (exact on it: near triangles are always summed exactly); exact throughout when
    /// built [`without_winding`](Self::without_winding).
    /// 0 for an infinite query, NaN for a NaN one.
    pub fn winding_number(&self, p: [f64; 3]) -> f64 {
        match check_query(p) {
            Some(w) => w,
            None => match &self.expansions {
                Some(expansions) => winding::fast(&self.bvh, expansions, p),
                None => winding::exact(&self.bvh, p),
            },
        }
    }

    /// Generalized winding number at `p`: the sum of the signed solid angles of all
    /// triangles (Van Oosterom–Strackee) over 4π. Exactly an integer (up to rounding)
    /// for a closed mesh off its surface; O(number of triangles) per query.
    pub fn winding_number_exact(&self, p: [f64; 3]) -> f64 {
        match check_query(p) {
            Some(w) => w,
            None => winding::exact(&self.bvh, p),
        }
    }

    /// Whether `p` is inside: winding number at least 0.5. Once
    /// [`use_pseudonormal_sign`](Self::use_pseudonormal_sign) has closed the chain
    /// (nothing to add, or cones over its holes), it is the exact count of signed
    /// crossings along a segment from the nearest anchor (or out of the tree's box),
    /// less the cones' winding number (`crossing`); else (and where every segment
    /// tried passes through a side or a corner) the fast winding number.
    pub fn is_inside(&self, p: [f64; 3]) -> bool {
        if let Some(w) = self.counted_winding(p) {
            return w >= 0.5;
        }
        self.winding_number(p) >= 0.5
    }

    /// Whether the triangles form a closed chain (every edge used as often in each
    /// direction, no triangle left out), as found by
    /// [`use_pseudonormal_sign`](Self::use_pseudonormal_sign): the winding number is then
    /// an integer off the surface and its sign changes only across the surface. False
    /// until then.
    fn closed_chain(&self) -> bool {
        self.closing
            .as_deref()
            .is_some_and(crossing::Closure::is_empty)
    }

    /// The winding number at `p` counted by crossings, where the chain is closed
    /// ([`SurfaceDistance::closing`]) and a segment was not degenerate.
    fn counted_winding(&self, p: [f64; 3]) -> Option<f64> {
        let closure = self.closing.as_deref()?;
        crossing::winding_by_crossings(&self.bvh, closure, p)
    }

    /// The winding number at `p` for the pseudonormals' samples: counted where it can
    /// be, else the fast one.
    fn winding_of_chain(&self, expansions: &[Expansion], p: [f64; 3]) -> f64 {
        self.counted_winding(p)
            .unwrap_or_else(|| winding::fast(&self.bvh, expansions, p))
    }

    /// Distance to the surface, negative inside ([`is_inside`](Self::is_inside), or the
    /// closest point's pseudonormal once [`use_pseudonormal_sign`](Self::use_pseudonormal_sign)
    /// is on). Exactly 0 on the surface; +∞ without triangles.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        if p.iter().any(|c| c.is_nan()) {
            return f64::NAN;
        }
        match self.bvh.nearest(p) {
            Some((t, q, d2)) if d2 > 0.0 => d2.sqrt() * self.sign_at(p, Some((t, q))),
            Some(_) => 0.0,
            None => f64::INFINITY,
        }
    }

    /// `min(distance(p), limit)`, pruning everything farther than `limit`.
    pub fn distance_within(&self, p: [f64; 3], limit: f64) -> f64 {
        match self.bvh.nearest_within(p, limit * limit) {
            Some((_, _, d2)) => d2.sqrt(),
            None => limit,
        }
    }

    /// [`signed_distance`](Self::signed_distance) where the distance is below `band`;
    /// beyond it, `±band` with the right sign (much cheaper far from the surface).
    pub fn signed_distance_within(&self, p: [f64; 3], band: f64) -> f64 {
        let (d, nearest) = match self.bvh.nearest_within(p, band * band) {
            Some((t, q, d2)) => (d2.sqrt(), Some((t, q))),
            None => (band, None),
        };
        if d > 0.0 && d.is_finite() {
            d * self.sign_at(p, nearest)
        } else {
            d
        }
    }

    /// [`signed_distance_within`](Self::signed_distance_within) of every point, in
    /// parallel.
    pub fn signed_distances_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        points
            .par_iter()
            .map(|&p| self.signed_distance_within(p, band))
            .collect()
    }

    /// [`signed_distances_within`](Self::signed_distances_within) where `signs[i]`,
    /// when not 0, is the sign the caller vouches for at `points[i]` (no surface
    /// between it and a point of that sign nearer than its distance): taken instead of
    /// the pseudonormal's or the winding number's, which far from a surface that
    /// crosses itself is most of a signed distance's cost. Only on triangles that form
    /// a closed chain (found by [`use_pseudonormal_sign`](Self::use_pseudonormal_sign)):
    /// across the hole of an open surface the winding number passes ½ away from the
    /// surface, so there the signs are ignored. In parallel.
    pub fn signed_distances_within_known(
        &self,
        points: &[[f64; 3]],
        band: f64,
        signs: &[i8],
    ) -> Vec<f64> {
        points
            .par_iter()
            .enumerate()
            .map(|(i, &p)| match signs.get(i) {
                Some(&s) if s != 0 && self.closed_chain() => {
                    let d = self.distance_within(p, band);
                    if d > 0.0 && d.is_finite() {
                        d * f64::from(s.signum())
                    } else {
                        d
                    }
                }
                _ => self.signed_distance_within(p, band),
            })
            .collect()
    }

    /// [`distance`](Self::distance) of every point, in parallel.
    pub fn distances(&self, points: &[[f64; 3]]) -> Vec<f64> {
        points.par_iter().map(|&p| self.distance(p)).collect()
    }

    /// [`signed_distance`](Self::signed_distance) of every point, in parallel.
    pub fn signed_distances(&self, points: &[[f64; 3]]) -> Vec<f64> {
        points
            .par_iter()
            .map(|&p| self.signed_distance(p))
            .collect()
    }

    /// Nearest hit of the ray `origin + t · dir` with `t` in `(t_min, t_max]`, where
    /// `t_min` makes the hit farther than [`RAY_EPSILON`] × [`scale`](Self::scale) from
    /// the origin (so a ray leaving a surface point does not hit its own triangle).
    /// `dir` need not be unit: `t` is in units of `dir`. Returns `t` and the mesh face;
    /// `None` for no hit, a zero or non-finite `dir`, or a non-finite origin. Rays
    /// through a shared edge or vertex hit (up to a 10⁻¹⁰ barycentric tolerance).
    pub fn ray_hit(&self, origin: [f64; 3], dir: [f64; 3], t_max: f64) -> Option<(f64, u32)> {
        let len = norm(dir);
        if len == 0.0 || !len.is_finite() || origin.iter().any(|c| !c.is_finite()) || t_max.is_nan()
        {
            return None;
        }
        let t_min = RAY_EPSILON * self.scale / len;
        if t_max <= t_min {
            return None;
        }
        self.bvh
            .ray(origin, dir, t_min, t_max)
            .map(|(t, i)| (t, self.bvh.faces[i]))
    }
}

/// The directed sides to add to `triangles` so that every edge is used as often in one
/// direction as in the other, each as often as its edge is unbalanced (none: the
/// triangles close; degenerate sides, from a vertex to itself, are no edges). Sorted.
fn unbalanced_sides(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    // Each side as (edge, ±1), sorted by edge: the edge's uses sum to 0 in each run
    // where it is balanced.
    let mut sides: Vec<([u32; 2], i32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .filter(|(a, b)| a != b)
        .map(|(a, b)| ([a.min(b), a.max(b)], if a < b { 1 } else { -1 }))
        .collect();
    sides.sort_unstable();
    let mut missing = Vec::new();
    for run in sides.chunk_by(|x, y| x.0 == y.0) {
        let [a, b] = run[0].0;
        let excess: i32 = run.iter().map(|s| s.1).sum();
        // More uses a → b than b → a: the closure goes b → a, as often as the excess.
        let side = if excess > 0 { [b, a] } else { [a, b] };
        missing.extend(std::iter::repeat_n(side, excess.unsigned_abs() as usize));
    }
    missing
}

impl SurfaceDistance {
    /// Pairs of mesh faces that cross each other: faces with no common vertex (of
    /// `triangles`, the mesh's faces) where an edge of one passes through the other,
    /// meeting along a segment ([`crossing_segment`]) longer than
    /// [`CROSSING_TOLERANCE`] × the mesh's bounding-box diagonal (nearly coplanar
    /// neighbours of a finely split mesh touch within rounding; they do not cross).
    /// Sorted, each pair `[lower, higher]`. A closed surface without such pairs bounds
    /// a solid whose topology its genus predicts; one with them does not. Runs in
    /// parallel; the result does not depend on the thread count.
    pub fn self_intersections(&self, triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
        let bvh = &self.bvh;
        let tolerance = CROSSING_TOLERANCE * bvh.diagonal();
        let mut pairs: Vec<[u32; 2]> = (0..bvh.tris.len())
            .into_par_iter()
            .map_init(Vec::new, |candidates, i| {
                let tri = bvh.tris[i];
                let (lo, hi) = bounds(&tri);
                candidates.clear();
                bvh.overlapping(lo, hi, candidates);
                let fi = bvh.faces[i];
                let vi = triangles.get(fi as usize).copied().unwrap_or([u32::MAX; 3]);
                candidates
                    .iter()
                    .filter(|&&j| bvh.faces[j] > fi)
                    .filter(|&&j| {
                        triangles
                            .get(bvh.faces[j] as usize)
                            .is_some_and(|&vj| faces_cross(&tri, vi, &bvh.tris[j], vj, tolerance))
                    })
                    .map(|&j| [fi, bvh.faces[j]])
                    .collect::<Vec<_>>()
            })
            .flatten()
            .collect();
        pairs.sort_unstable();
        pairs
    }
}

/// The crossing pairs of `mesh`'s faces (as [`SurfaceDistance::self_intersections`]
/// counts them, the same tolerance of the whole mesh's diagonal) that involve a face of
/// `among`: the check after an edit that added only those faces to a surface that did
/// not cross itself, for the cost of a tree over them and one pass over the rest.
/// Sorted, each pair `[lower, higher]`; the result does not depend on the thread count.
pub fn crossings_among(mesh: &SurfaceMesh, among: &[u32]) -> Vec<[u32; 2]> {
    let n = mesh.positions.len();
    let corners = |f: u32| -> Option<[[f64; 3]; 3]> {
        let t = mesh.triangles.get(f as usize)?;
        let c = t.map(|v| mesh.positions.get(v as usize).copied());
        let c = [c[0]?, c[1]?, c[2]?];
        c.iter().flatten().all(|x| x.is_finite()).then_some(c)
    };
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in mesh
        .positions
        .iter()
        .filter(|p| p.iter().all(|x| x.is_finite()))
    {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let tolerance = CROSSING_TOLERANCE * if n == 0 { 0.0 } else { norm(sub(hi, lo)) };
    let mut chosen = vec![false; mesh.triangles.len()];
    let (mut tris, mut faces) = (Vec::new(), Vec::new());
    for &f in among {
        if let (Some(c), Some(slot)) = (corners(f), chosen.get_mut(f as usize)) {
            if !*slot {
                *slot = true;
                tris.push(c);
                faces.push(f);
            }
        }
    }
    let tree = Bvh::build(tris, faces);
    let Some(root) = tree.nodes.first() else {
        return Vec::new();
    };
    let (root_lo, root_hi) = (root.lo, root.hi);
    let mut pairs: Vec<[u32; 2]> = (0..mesh.triangles.len() as u32)
        .into_par_iter()
        .map_init(Vec::new, |candidates, f| {
            let Some(tri) = corners(f) else {
                return Vec::new();
            };
            let (a, b) = bounds(&tri);
            if (0..3).any(|k| b[k] < root_lo[k] || a[k] > root_hi[k]) {
                return Vec::new();
            }
            candidates.clear();
            tree.overlapping(a, b, candidates);
            let vf = mesh.triangles[f as usize];
            candidates
                .iter()
                .map(|&j| (j, tree.faces[j]))
                // A pair of two chosen faces is seen from both: kept from the lower.
                .filter(|&(_, g)| g != f && !(chosen[f as usize] && g < f))
                .filter(|&(j, g)| {
                    faces_cross(
                        &tri,
                        vf,
                        &tree.tris[j],
                        mesh.triangles[g as usize],
                        tolerance,
                    )
                })
                .map(|(_, g)| [f.min(g), f.max(g)])
                .collect::<Vec<_>>()
        })
        .flatten()
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// A triangle's bounding box.
fn bounds(tri: &[[f64; 3]; 3]) -> ([f64; 3], [f64; 3]) {
    let (mut lo, mut hi) = (tri[0], tri[0]);
    for p in tri {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Two faces (corners `a`, `b`; vertices `va`, `vb`) cross: they share no vertex, an
/// edge of one passes through the other, and they meet along a segment longer than
/// `tolerance` (the test of [`SurfaceDistance::self_intersections`]).
fn faces_cross(
    a: &[[f64; 3]; 3],
    va: [u32; 3],
    b: &[[f64; 3]; 3],
    vb: [u32; 3],
    tolerance: f64,
) -> bool {
    !vb.iter().any(|v| va.contains(v))
        && bvh::triangles_cross(a, b)
        && crossing_segment(*a, *b).is_some_and(|[p, q]| norm(sub(p, q)) > tolerance)
}

/// Two triangles cross (see [`SurfaceDistance::self_intersections`]) when they meet
/// along a segment longer than this fraction of the bounding-box diagonal.
pub const CROSSING_TOLERANCE: f64 = 1e-9;

/// Triangles whose corners lie within this fraction of their size of each other's
/// planes are coplanar for [`crossing_segment`].
pub const COPLANAR_TOLERANCE: f64 = 1e-9;

/// The segment where two crossing triangles meet: each one's part in the other's plane,
/// overlapped along the planes' common line. `None` for separate triangles and for
/// coplanar ones, also where they are coplanar only up to rounding (each one's corners
/// within [`COPLANAR_TOLERANCE`] × the pair's extent of the other's plane, plus the
/// rounding of their coordinates): there the planes' common line is noise, and the
/// pieces of one triangle split at its edge midpoints would be seen crossing.
pub fn crossing_segment(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> Option<[[f64; 3]; 2]> {
    let normal = |t: &[[f64; 3]; 3]| cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let (na, nb) = (normal(&a), normal(&b));
    let longest = a
        .iter()
        .chain(&b)
        .flat_map(|p| a.iter().chain(&b).map(move |q| norm(sub(*p, *q))))
        .fold(0.0, f64::max);
    let magnitude = a
        .iter()
        .chain(&b)
        .flatten()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    let slab = COPLANAR_TOLERANCE * longest + 1e-14 * magnitude;
    let within = |t: &[[f64; 3]; 3], n: [f64; 3], origin: [f64; 3]| {
        let length = norm(n);
        length > 0.0
            && t.iter()
                .all(|p| dot(n, sub(*p, origin)).abs() <= slab * length)
    };
    if within(&a, nb, b[0]) && within(&b, na, a[0]) {
        return None;
    }
    // The part of triangle t in the plane through `origin` with normal n.
    let in_plane = |t: &[[f64; 3]; 3], n: [f64; 3], origin: [f64; 3]| {
        let d = t.map(|p| dot(n, sub(p, origin)));
        if d.iter().all(|&x| x == 0.0) {
            return None;
        }
        let mut points = Vec::with_capacity(3);
        for i in 0..3 {
            let j = (i + 1) % 3;
            if d[i] == 0.0 {
                points.push(t[i]);
            } else if (d[i] < 0.0) != (d[j] < 0.0) && d[j] != 0.0 {
                let s = d[i] / (d[i] - d[j]);
                points.push(add(t[i], scale(sub(t[j], t[i]), s)));
            }
        }
        (points.len() >= 2).then(|| [points[0], points[1]])
    };
    let sa = in_plane(&a, nb, b[0])?;
    let sb = in_plane(&b, na, a[0])?;
    let line = cross(na, nb);
    let along = |p: [f64; 3]| dot(line, p);
    let (a0, a1) = (along(sa[0]), along(sa[1]));
    let (b0, b1) = (along(sb[0]), along(sb[1]));
    let lo = a0.min(a1).max(b0.min(b1));
    let hi = a0.max(a1).min(b0.max(b1));
    if lo >= hi || lo.is_nan() || hi.is_nan() || a0 == a1 {
        return None;
    }
    let at = |t: f64| add(sa[0], scale(sub(sa[1], sa[0]), (t - a0) / (a1 - a0)));
    Some([at(lo), at(hi)])
}

/// The winding number of a non-finite query (NaN for NaN, 0 far away), else `None`.
fn check_query(p: [f64; 3]) -> Option<f64> {
    if p.iter().any(|c| c.is_nan()) {
        Some(f64::NAN)
    } else if p.iter().any(|c| c.is_infinite()) {
        Some(0.0)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::bvh::LEAF_SIZE;
    use super::*;
    use crate::geom::closest_on_triangle;

    fn tetra() -> SurfaceMesh {
        SurfaceMesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    /// The pieces of one thin triangle (the fertility's face 6185) split three times at
    /// its edge midpoints lie in its plane only up to rounding; none crosses another.
    #[test]
    fn the_pieces_of_one_triangle_do_not_cross() {
        let mut pieces = vec![[
            [-4.19335, -64.8618, 26.9076],
            [-11.7365, -67.5856, 26.271],
            [-13.4595, -68.1812, 22.5577],
        ]];
        let mid = |p: [f64; 3], q: [f64; 3]| scale(add(p, q), 0.5);
        for _ in 0..3 {
            pieces = pieces
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        for (i, p) in pieces.iter().enumerate() {
            for q in &pieces[i + 1..] {
                assert_eq!(crossing_segment(*p, *q), None, "{p:?} {q:?}");
            }
        }
        // A real crossing is still one.
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let b = [[0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.9, 0.9, 0.0]];
        assert!(crossing_segment(a, b).is_some());
    }

    /// A sign the caller vouches for is taken where the triangles close (even a wrong
    /// one: the caller answers for it; the magnitude stays the distance), and ignored
    /// where they do not (across a hole the winding number passes ½ off the surface).
    #[test]
    fn vouched_signs_are_taken_only_where_the_triangles_close() {
        let points = [[0.1, 0.1, 0.1], [5.0, 5.0, 5.0], [0.2, 0.2, -0.5]];
        let closed = tetra();
        let mut distance = SurfaceDistance::new(&closed);
        distance.use_pseudonormal_sign(&closed);
        for band in [0.01, 10.0] {
            let plain = distance.signed_distances_within_known(&points, band, &[0; 3]);
            assert!(
                plain[0] < 0.0 && plain[1] > 0.0 && plain[2] > 0.0,
                "{plain:?}"
            );
            let vouched = distance.signed_distances_within_known(&points, band, &[1, -1, 0]);
            assert_eq!(vouched, [-plain[0], -plain[1], plain[2]], "band {band}");
        }
        let mut open = tetra();
        open.triangles.pop();
        let mut distance = SurfaceDistance::new(&open);
        distance.use_pseudonormal_sign(&open);
        for band in [0.01, 10.0] {
            let plain = distance.signed_distances_within_known(&points, band, &[0; 3]);
            let vouched = distance.signed_distances_within_known(&points, band, &[1, -1, 1]);
            assert_eq!(vouched, plain, "band {band}");
        }
    }

    /// Two tetrahedra, the second moved half into the first: the crossings that involve
    /// a set of faces are those of the whole surface's crossings with a face in it.
    #[test]
    fn crossings_among_faces_are_the_surfaces_crossings_that_involve_them() {
        let mut mesh = tetra();
        let moved = tetra();
        mesh.positions
            .extend(moved.positions.iter().map(|p| add(*p, [0.3, 0.25, 0.2])));
        mesh.triangles
            .extend(moved.triangles.iter().map(|t| t.map(|v| v + 4)));
        let all = SurfaceDistance::without_winding(&mesh).self_intersections(&mesh.triangles);
        assert!(!all.is_empty());
        for among in [
            vec![0, 1, 2, 3, 4, 5, 6, 7],
            vec![4, 5, 6, 7],
            vec![1],
            vec![6, 6, 2],
        ] {
            let expected: Vec<[u32; 2]> = all
                .iter()
                .filter(|p| p.iter().any(|f| among.contains(f)))
                .copied()
                .collect();
            assert_eq!(crossings_among(&mesh, &among), expected, "{among:?}");
        }
        // Apart, nothing crosses.
        for p in &mut mesh.positions[4..] {
            p[0] += 5.0;
        }
        assert!(crossings_among(&mesh, &[0, 1, 2, 3, 4, 5, 6, 7]).is_empty());
        assert!(crossings_among(&mesh, &[]).is_empty());
    }

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        // Interior, each vertex, each edge.
        assert_eq!(
            closest_on_triangle([0.2, 0.2, 3.0], a, b, c),
            [0.2, 0.2, 0.0]
        );
        assert_eq!(closest_on_triangle([-1.0, -1.0, 0.5], a, b, c), a);
        assert_eq!(closest_on_triangle([2.0, -0.5, 0.0], a, b, c), b);
        assert_eq!(closest_on_triangle([-0.5, 2.0, 0.0], a, b, c), c);
        assert_eq!(
            closest_on_triangle([0.5, -1.0, 1.0], a, b, c),
            [0.5, 0.0, 0.0]
        );
        assert_eq!(
            closest_on_triangle([-1.0, 0.5, 1.0], a, b, c),
            [0.0, 0.5, 0.0]
        );
        assert_eq!(
            closest_on_triangle([1.0, 1.0, 0.0], a, b, c),
            [0.5, 0.5, 0.0]
        );
    }

    #[test]
    fn degenerate_triangles_are_segments_and_points() {
        let p = [0.5, 1.0, 0.0];
        // Collinear (c between a and b), repeated corner, and a single point.
        let q = closest_on_triangle(p, [0.0; 3], [1.0, 0.0, 0.0], [0.25, 0.0, 0.0]);
        assert!(norm(sub(q, [0.5, 0.0, 0.0])) < 1e-15);
        let q = closest_on_triangle(p, [0.0; 3], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        assert!(norm(sub(q, [0.5, 0.0, 0.0])) < 1e-15);
        let q = closest_on_triangle(p, [2.0; 3], [2.0; 3], [2.0; 3]);
        assert_eq!(q, [2.0; 3]);
    }

    #[test]
    fn empty_and_broken_meshes_do_not_panic() {
        let empty = SurfaceDistance::new(&SurfaceMesh::default());
        assert_eq!(empty.distance([0.0; 3]), f64::INFINITY);
        assert_eq!(empty.signed_distance([0.0; 3]), f64::INFINITY);
        assert_eq!(empty.winding_number([0.0; 3]), 0.0);
        assert_eq!(empty.winding_number_exact([0.0; 3]), 0.0);
        assert_eq!(empty.closest_point([0.0; 3]).face, Closest::NO_FACE);
        assert_eq!(
            empty.ray_hit([0.0; 3], [1.0, 0.0, 0.0], f64::INFINITY),
            None
        );
        assert!(empty
            .distances(&[[1.0; 3]; 3])
            .iter()
            .all(|d| d.is_infinite()));

        let broken = SurfaceMesh {
            positions: vec![
                [0.0; 3],
                [1.0, 0.0, 0.0],
                [f64::NAN, 0.0, 0.0],
                [1.0, 0.0, 0.0],
            ],
            triangles: vec![[0, 1, 7], [0, 1, 2], [0, 1, 3], [0, 0, 0]],
        };
        let sd = SurfaceDistance::new(&broken);
        assert_eq!(sd.num_triangles(), 2);
        assert!((sd.distance([0.5, 2.0, 0.0]) - 2.0).abs() < 1e-15);
        assert_eq!(sd.winding_number([0.5, 2.0, 0.0]), 0.0);
        assert!(sd.distance([f64::NAN, 0.0, 0.0]).is_nan());
        assert_eq!(sd.ray_hit([0.0; 3], [0.0; 3], 1.0), None);
    }

    #[test]
    fn tree_shape_and_leaf_sizes() {
        let mut mesh = tetra();
        // Many copies, shifted, to get a deep tree.
        let base = mesh.clone();
        for k in 1..200 {
            let off = mesh.positions.len() as u32;
            mesh.positions.extend(
                base.positions
                    .iter()
                    .map(|p| [p[0] + 2.0 * k as f64, p[1], p[2]]),
            );
            mesh.triangles
                .extend(base.triangles.iter().map(|t| t.map(|v| v + off)));
        }
        let sd = SurfaceDistance::new(&mesh);
        let nodes = &sd.bvh.nodes;
        for node in nodes {
            if node.is_leaf() {
                let n = (node.end - node.start) as usize;
                assert!((1..=LEAF_SIZE).contains(&n));
            } else {
                let (l, r) = (&nodes[node.left as usize], &nodes[node.left as usize + 1]);
                assert_eq!((l.start, l.end, r.end), (node.start, r.start, node.end));
                for k in 0..3 {
                    assert!(node.lo[k] <= l.lo[k].min(r.lo[k]));
                    assert!(node.hi[k] >= l.hi[k].max(r.hi[k]));
                }
            }
        }
        // Point inside the 100th copy.
        assert!(sd.is_inside([200.1, 0.1, 0.1]));
        assert!(sd.winding_number([201.0, 1.0, 1.0]).abs() < 1e-3);
        assert!(sd.winding_number_exact([201.0, 1.0, 1.0]).abs() < 1e-12);
    }

    #[test]
    fn tetrahedron_queries() {
        let sd = SurfaceDistance::new(&tetra());
        let inside = [0.1, 0.2, 0.3];
        assert!((sd.winding_number_exact(inside) - 1.0).abs() < 1e-12);
        assert!((sd.winding_number(inside) - 1.0).abs() < 1e-12);
        assert!((sd.signed_distance(inside) + 0.1).abs() < 1e-12);
        let hit = sd.ray_hit(inside, [0.0, 0.0, -2.0], f64::INFINITY).unwrap();
        assert!((hit.0 - 0.15).abs() < 1e-12);
        assert_eq!(hit.1, 0);
        assert_eq!(sd.ray_hit(inside, [0.0, 0.0, -2.0], 0.1), None);
        // From a surface point, the own triangle is not hit again.
        let on = [0.2, 0.2, 0.0];
        assert_eq!(sd.ray_hit(on, [0.0, 0.0, -1.0], f64::INFINITY), None);
        assert_eq!(sd.signed_distance(on), 0.0);
    }
}
