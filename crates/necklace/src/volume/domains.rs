//! The [`Domain`] the mesher meshes (a region given by a 1-Lipschitz function), and
//! domains built from other things: [`SurfaceInside`], the solid a closed surface
//! bounds (through the `distance` service), and [`Shell`], the space between any solid
//! domain and a sphere around it — the two regions the method meshes (handles inside,
//! tunnels in the shell). The tests mesh the shell of analytic shapes with the same
//! [`Shell`].
//!
//! Conventions: values negative inside the region, 1-Lipschitz (signed distances, and
//! the max of two for the shell); lengths in the surface's units.

use super::{SharpFeatures, SizingFeature};
use crate::distance::SurfaceDistance;
use crate::geom::{add, dot, norm, scale, sub};
use crate::tet::VertexKind;

/// A region to mesh, given implicitly.
pub trait Domain: Sync {
    /// Negative inside, zero on the boundary, positive outside; 1-Lipschitz.
    fn value(&self, p: [f64; 3]) -> f64;

    /// [`Domain::value`] at many points (implementations may parallelise; the result
    /// must not depend on the thread count).
    fn values(&self, points: &[[f64; 3]]) -> Vec<f64> {
        points.iter().map(|&p| self.value(p)).collect()
    }

    /// Like [`Domain::values`], but only values of magnitude below `band` must be exact;
    /// beyond it any value of the right sign and magnitude ≥ `band` will do (lets an
    /// implementation skip exact distances far from the boundary).
    fn values_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        let _ = band;
        self.values(points)
    }

    /// [`Domain::values_within`] where the caller knows some signs: `signs[i]`, when
    /// not 0, is the sign of the value at `points[i]` (the caller saw a value of that
    /// sign at a point nearer to it than that value's magnitude, so no boundary lies
    /// between). An implementation may take the sign from it instead of finding it
    /// (far from a surface that crosses itself, a signed distance costs a winding
    /// number); the default ignores it.
    fn values_within_signed(&self, points: &[[f64; 3]], band: f64, signs: &[i8]) -> Vec<f64> {
        let _ = signs;
        self.values_within(points, band)
    }

    /// Where the segment `a`–`b` (whose ends have opposite signs) crosses the boundary,
    /// as a parameter in (0, 1), if the domain can say directly (e.g. by a ray cast);
    /// `None` lets the mesher search for the root of [`Domain::value`].
    fn crossing(&self, a: [f64; 3], b: [f64; 3]) -> Option<f64> {
        let _ = (a, b);
        None
    }

    /// The point of the boundary nearest to `p` (used to keep boundary vertices on the
    /// boundary when the quality step moves them). The default takes Newton steps on
    /// [`Domain::value`] with a central-difference gradient, which is exact in one step
    /// for a signed distance.
    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let mut q = p;
        for _ in 0..4 {
            let f = self.value(q);
            if f == 0.0 {
                break;
            }
            let step = 1e-6 * (1.0 + norm(q));
            let g: [f64; 3] = std::array::from_fn(|k| {
                let mut a = q;
                let mut b = q;
                a[k] -= step;
                b[k] += step;
                (self.value(b) - self.value(a)) / (2.0 * step)
            });
            let gg = dot(g, g);
            if !(gg > 0.0 && gg.is_finite()) {
                break;
            }
            q = sub(q, scale(g, f / gg));
        }
        q
    }

    /// Which boundary a point on the zero set lies on.
    fn boundary_kind(&self, p: [f64; 3]) -> VertexKind;

    /// The distance from `p` to the boundary where it is below `limit`; beyond it, any
    /// value of at least `limit` (lets an implementation prune the search). The default
    /// is `|value(p)|`, exact for a signed distance.
    fn distance_within(&self, p: [f64; 3], limit: f64) -> f64 {
        let _ = limit;
        self.value(p).abs()
    }

    /// Corners and creases of the boundary that boundary vertices should be snapped
    /// onto (none by default).
    fn sharp_features(&self) -> SharpFeatures {
        SharpFeatures::default()
    }

    /// A box `(min, max)` that contains the whole region.
    fn bounds(&self) -> ([f64; 3], [f64; 3]);

    /// Where the lattice must be finer than `h` (thin parts and gaps, and whatever a
    /// caller learned from an earlier mesh); see [`SizingFeature`].
    fn sizing(&self) -> Vec<SizingFeature> {
        Vec::new()
    }

    /// The spacing wanted where the boundary passes near `p`, given the requested `h`:
    /// `h` by default; a shell returns more near its outer sphere, which needs no detail.
    fn spacing_near(&self, _p: [f64; 3], h: f64) -> f64 {
        h
    }

    /// The largest value [`Domain::spacing_near`] returns for this `h`.
    fn coarsest_spacing(&self, h: f64) -> f64 {
        h
    }
}

/// The solid bounded by a surface: the signed distance to it (negative inside), with
/// its own sizing features (thin parts) and sharp features (creases, corners) for the
/// mesher.
#[derive(Debug, Clone)]
pub struct SurfaceInside<'a> {
    /// The surface's distance structure (its sign says inside).
    pub distance: &'a SurfaceDistance,
    /// The surface's bounding box.
    pub bounds: ([f64; 3], [f64; 3]),
    /// Where to mesh finer than `h` (see [`SizingFeature`]).
    pub sizing: Vec<SizingFeature>,
    /// Creases and corners to snap the boundary onto.
    pub features: SharpFeatures,
}

impl Domain for SurfaceInside<'_> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.distance.signed_distance(p)
    }

    fn values(&self, points: &[[f64; 3]]) -> Vec<f64> {
        self.distance.signed_distances(points)
    }

    fn values_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        self.distance.signed_distances_within(points, band)
    }

    fn values_within_signed(&self, points: &[[f64; 3]], band: f64, signs: &[i8]) -> Vec<f64> {
        self.distance
            .signed_distances_within_known(points, band, signs)
    }

    fn distance_within(&self, p: [f64; 3], limit: f64) -> f64 {
        self.distance.distance_within(p, limit)
    }

    fn crossing(&self, a: [f64; 3], b: [f64; 3]) -> Option<f64> {
        // The first hit of the segment. A segment through a hole of an open mesh hits
        // nothing; the mesher then searches the winding-number jump.
        self.distance.ray_hit(a, sub(b, a), 1.0).map(|(t, _)| t)
    }

    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let closest = self.distance.closest_point(p);
        if closest.point.iter().all(|c| c.is_finite()) {
            closest.point
        } else {
            p
        }
    }

    fn boundary_kind(&self, _p: [f64; 3]) -> VertexKind {
        VertexKind::Surface
    }

    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.bounds
    }

    fn sizing(&self) -> Vec<SizingFeature> {
        self.sizing.clone()
    }

    fn sharp_features(&self) -> SharpFeatures {
        self.features.clone()
    }
}

/// The space between a solid and a sphere around it: `max(−solid, |p − centre| − radius)`.
/// Its boundary is the solid's (vertex kind from the solid) and the sphere's
/// ([`VertexKind::Outer`]); the sphere is only a container, meshed at a quarter of its
/// radius.
#[derive(Debug, Clone)]
pub struct Shell<D> {
    /// The solid the shell surrounds.
    pub solid: D,
    /// The sphere's centre.
    pub centre: [f64; 3],
    /// The sphere's radius (it must enclose the solid).
    pub radius: f64,
}

impl<D: Domain> Shell<D> {
    /// The shell between `solid` and the sphere of `radius` about `centre`.
    pub fn new(solid: D, centre: [f64; 3], radius: f64) -> Self {
        Shell {
            solid,
            centre,
            radius,
        }
    }

    fn sphere_value(&self, p: [f64; 3]) -> f64 {
        norm(sub(p, self.centre)) - self.radius
    }

    /// Whether `p` is nearer the sphere than the solid's boundary.
    fn nearer_the_sphere(&self, p: [f64; 3]) -> bool {
        let to_sphere = self.sphere_value(p).abs();
        let limit = to_sphere + 1e-12 * self.radius;
        self.solid.distance_within(p, limit) > to_sphere
    }

    fn combine(&self, p: [f64; 3], solid: f64) -> f64 {
        (-solid).max(self.sphere_value(p))
    }

    /// The sphere's spacing: a quarter of its radius, never finer than `h`. (The sphere
    /// only closes the shell: tunnels lie at the surface. An eighth gave the kitten's
    /// shell 17 % more unknowns and the same loops.)
    fn sphere_spacing(&self, h: f64) -> f64 {
        (self.radius / 4.0).max(h)
    }
}

impl<D: Domain> Domain for Shell<D> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.combine(p, self.solid.value(p))
    }

    fn values(&self, points: &[[f64; 3]]) -> Vec<f64> {
        let solid = self.solid.values(points);
        points
            .iter()
            .zip(solid)
            .map(|(&p, s)| self.combine(p, s))
            .collect()
    }

    fn values_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        let solid = self.solid.values_within(points, band);
        points
            .iter()
            .zip(solid)
            .map(|(&p, s)| self.combine(p, s))
            .collect()
    }

    fn values_within_signed(&self, points: &[[f64; 3]], band: f64, signs: &[i8]) -> Vec<f64> {
        // Inside the sphere the shell's value and the solid's have opposite signs (in
        // the shell: outside the solid; else inside it); outside it the solid's sign is
        // not told.
        let solid_signs: Vec<i8> = points
            .iter()
            .zip(signs)
            .map(|(&p, &s)| if self.sphere_value(p) < 0.0 { -s } else { 0 })
            .collect();
        let solid = self.solid.values_within_signed(points, band, &solid_signs);
        points
            .iter()
            .zip(solid)
            .map(|(&p, s)| self.combine(p, s))
            .collect()
    }

    fn distance_within(&self, p: [f64; 3], limit: f64) -> f64 {
        self.solid
            .distance_within(p, limit)
            .min(self.sphere_value(p).abs())
    }

    fn crossing(&self, a: [f64; 3], b: [f64; 3]) -> Option<f64> {
        let (sa, sb) = (self.sphere_value(a), self.sphere_value(b));
        if (sa < 0.0) == (sb < 0.0) {
            return self.solid.crossing(a, b);
        }
        // The sphere: solve |a + t (b − a) − c| = R.
        let d = sub(b, a);
        let m = sub(a, self.centre);
        let (qa, qb, qc) = (
            dot(d, d),
            2.0 * dot(m, d),
            dot(m, m) - self.radius * self.radius,
        );
        let disc = qb * qb - 4.0 * qa * qc;
        if qa <= 0.0 || disc < 0.0 {
            return None;
        }
        let roots = [
            (-qb - disc.sqrt()) / (2.0 * qa),
            (-qb + disc.sqrt()) / (2.0 * qa),
        ];
        roots.into_iter().find(|t| *t > 0.0 && *t < 1.0)
    }

    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        if self.nearer_the_sphere(p) {
            let r = sub(p, self.centre);
            let len = norm(r);
            if len > 0.0 {
                return add(self.centre, scale(r, self.radius / len));
            }
        }
        self.solid.project(p)
    }

    fn boundary_kind(&self, p: [f64; 3]) -> VertexKind {
        if self.nearer_the_sphere(p) {
            VertexKind::Outer
        } else {
            self.solid.boundary_kind(p)
        }
    }

    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (
            self.centre.map(|c| c - self.radius),
            self.centre.map(|c| c + self.radius),
        )
    }

    fn sizing(&self) -> Vec<SizingFeature> {
        self.solid.sizing()
    }

    fn sharp_features(&self) -> SharpFeatures {
        self.solid.sharp_features()
    }

    fn coarsest_spacing(&self, h: f64) -> f64 {
        self.sphere_spacing(h)
    }

    fn spacing_near(&self, p: [f64; 3], h: f64) -> f64 {
        if self.nearer_the_sphere(p) {
            self.sphere_spacing(h)
        } else {
            self.solid.spacing_near(p, h)
        }
    }
}
