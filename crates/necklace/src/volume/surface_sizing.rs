//! What the volume stage measures on a surface for the mesher: at every vertex the
//! thickness of the solid and the width of the gap in front of it ([`thickness`]: a ray
//! along the normal, then the inscribed ball touching there), the sizing features that
//! ask for finer cells where either is below `2h` ([`thin_part_sizing`]), and the
//! creases and corners to snap onto ([`sharp_features`]). Folds of the surface and
//! places where it crosses itself are not parts, and are skipped.
//!
//! Conventions: lengths in the surface's units; thickness `[solid, gap]` per vertex,
//! infinite where not thin.

use super::{SharpFeatures, SizingFeature};
use crate::distance::SurfaceDistance;
use crate::geom::{add, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Parts and gaps thinner than this many `h` get finer cells (at `h`, two cells across).
pub(super) const THIN_FACTOR: f64 = 2.0;

/// Cells across a thin part or gap. Warping moves a vertex by at most 0.36 of a cell,
/// so two cells across leave a core of more than a cell whose lattice vertices stay
/// inside and connect along the part. (Where that is not enough, the topology check
/// finds it and refines.)
pub(super) const CELLS_ACROSS: f64 = 2.0;

/// A contact of the inscribed ball counts as the opposite wall (not the surface curving
/// next to the vertex) when it is at least this angle round the ball from the vertex.
const MIN_SEPARATION_DEG: f64 = 120.0;

/// A part or gap thinner than 1/`FOLD_RATIO` of the shortest edge at a vertex is taken
/// for a fold of the surface there, not refined for: a real thin part is drawn with
/// edges not much longer than its thickness somewhere around it (a plate's rim, a
/// wire's section).
const FOLD_RATIO: f64 = 20.0;

/// An edge whose two faces' normals differ by more than this is a crease.
const CREASE_DEG: f64 = 40.0;

/// Most shrinking steps of the inscribed ball at a vertex (each a closest-point query);
/// a ball still shrinking after them is taken as not thin.
const MEDIAL_STEPS: usize = 8;

/// For each surface vertex (but those marked `skip`), the thickness of the solid and the
/// width of the gap in front of it, each when below `limit` (else infinity). On each
/// side, a ray along the vertex normal looks for the other wall within `limit`;
/// where it finds one, the thickness is the diameter of the largest ball touching the
/// surface at the vertex whose other contact lies across the part (shrinking-ball
/// medial distance, started from the ray's chord), or the chord where no ball tells. A
/// contact or hit on a triangle at the vertex does not count, nor a thickness below
/// 1/[`FOLD_RATIO`] of the vertex's shortest edge (a fold, not a part).
pub(super) fn thickness(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    skip: &[bool],
    limit: f64,
) -> Vec<[f64; 2]> {
    use rayon::prelude::*;
    let mut normals = vec![[0.0; 3]; surface.num_vertices()];
    for f in 0..surface.num_triangles() {
        let n = surface.face_normal_scaled(f);
        for &v in &surface.triangles[f] {
            normals[v as usize] = add(normals[v as usize], n);
        }
    }
    (0..surface.num_vertices())
        .into_par_iter()
        .map(|v| {
            let len = norm(normals[v]);
            let faces = topology.vertex_faces(v);
            if faces.is_empty() || skip[v] || len.is_nan() || len <= 0.0 {
                return [f64::INFINITY; 2];
            }
            let p = surface.positions[v];
            // The shortest edge at v: a wall much closer than it is a fold of the
            // surface at v (a crease folded flat, a scanning defect), not a part.
            let shortest = faces
                .iter()
                .flat_map(|&f| surface.triangles[f as usize])
                .filter(|&u| u as usize != v)
                .map(|u| norm(sub(surface.positions[u as usize], p)))
                .fold(f64::INFINITY, f64::min);
            let v32 = v as u32;
            let far = |face: u32| {
                surface
                    .triangles
                    .get(face as usize)
                    .is_some_and(|t| !t.contains(&v32))
            };
            [-1.0, 1.0].map(|direction| {
                let d = scale(normals[v], direction / len);
                // A ray that meets no other wall within the limit leaves room for a ball
                // of the limit's diameter: not thin on this side.
                let Some((hit, face)) = distance.ray_hit(p, d, limit) else {
                    return f64::INFINITY;
                };
                if !far(face) {
                    return f64::INFINITY;
                }
                // The ball's diameter is the thickness across a plate or a wire whatever
                // the vertex normal (the ray's chord is only a bound on it).
                let ball = 2.0 * medial_radius(distance, p, d, 0.5 * hit, &far);
                let t = if ball.is_finite() { ball } else { hit };
                if t < limit && t * FOLD_RATIO >= shortest {
                    t
                } else {
                    f64::INFINITY
                }
            })
        })
        .collect()
}

/// The radius of the largest ball (up to `r_max`) touching the surface at `q` with its
/// centre along the unit direction `d`, by shrinking (Ma, Bae & Ponchio 2012): start at
/// `r_max`; while the ball holds a surface point `x`, shrink it to the ball through `q`
/// and `x`. A contact counts as across the part when it is at least
/// [`MIN_SEPARATION_DEG`] round the ball from `q` and on a triangle `far` from `q`;
/// the radius of the last such shrink is returned (infinity for none), and shrinking
/// stops at the first contact that does not count after one that did.
fn medial_radius(
    distance: &SurfaceDistance,
    q: [f64; 3],
    d: [f64; 3],
    r_max: f64,
    far: &dyn Fn(u32) -> bool,
) -> f64 {
    let min_cos = MIN_SEPARATION_DEG.to_radians().cos();
    let mut r = r_max;
    let mut across = f64::INFINITY;
    for _ in 0..MEDIAL_STEPS {
        let c = add(q, scale(d, r));
        // Only a surface point inside the ball shrinks it.
        let x = distance.closest_point_within(c, r);
        if x.distance.is_nan() || x.distance >= r * (1.0 - 1e-9) {
            break;
        }
        let (cq, cx) = (sub(q, c), sub(x.point, c));
        let separation = dot(cq, cx) / (norm(cq) * norm(cx));
        let qx = sub(x.point, q);
        let den = 2.0 * dot(d, qx);
        if den.is_nan() || den <= 0.0 {
            break;
        }
        let next = dot(qx, qx) / den;
        if next.is_nan() || next >= r {
            break;
        }
        if separation <= min_cos && far(x.face) {
            across = next;
        } else if across.is_finite() {
            break;
        }
        r = next;
    }
    across
}

/// Sizing features where the surface is thin, for each side (the solid behind it, the
/// gap in front): over each triangle whose three corners are thin on that side (a
/// plate, a wire, the walls of a slit), cells of 1/[`CELLS_ACROSS`] of its middle
/// corner's thickness, so the part is resolved between its vertices too; at a thin
/// vertex that no such triangle sizes as finely (on the rim of a thin region, alone, or
/// thinner than its neighbours), a point with its own. Each faces its side and reaches
/// half the thickness and one cell more: to the middle of the part or gap (the other
/// wall's features reach the rest), and one cell out the other way. The octree's 2:1
/// balance grades the cells around them.
pub(super) fn thin_part_sizing(
    surface: &SurfaceMesh,
    thickness: &[[f64; 2]],
) -> Vec<SizingFeature> {
    let unit = |n: [f64; 3], sign: f64| {
        let l = norm(n);
        if l > 0.0 && l.is_finite() {
            scale(n, sign / l)
        } else {
            [0.0; 3]
        }
    };
    let mut normals = vec![[0.0; 3]; surface.num_vertices()];
    for f in 0..surface.num_triangles() {
        let n = surface.face_normal_scaled(f);
        for &v in &surface.triangles[f] {
            normals[v as usize] = add(normals[v as usize], n);
        }
    }
    let mut out = Vec::new();
    // Side 0 is the solid (against the outward normal), side 1 the gap.
    for (side, sign) in [(0, -1.0), (1, 1.0)] {
        let feature = |corners: [[f64; 3]; 3], t: f64, reach: f64, toward: [f64; 3]| {
            let spacing = t / CELLS_ACROSS;
            SizingFeature {
                corners,
                spacing,
                reach: 0.5 * reach + spacing,
                toward,
            }
        };
        // Per vertex: the coarsest thickness a triangle over it was sized for (infinite
        // when some triangle at it is not all thin).
        let mut covered_by = vec![0.0f64; thickness.len()];
        for (f, tri) in surface.triangles.iter().enumerate() {
            let mut t = tri.map(|v| thickness[v as usize][side]);
            let all_thin = t.iter().all(|x| x.is_finite());
            t.sort_unstable_by(f64::total_cmp);
            // The middle corner: one outlier corner neither coarsens nor refines it.
            let sized = if all_thin { t[1] } else { f64::INFINITY };
            for &v in tri {
                covered_by[v as usize] = covered_by[v as usize].max(sized);
            }
            if all_thin {
                out.push(feature(
                    tri.map(|v| surface.positions[v as usize]),
                    t[1],
                    t[2],
                    unit(surface.face_normal_scaled(f), sign),
                ));
            }
        }
        for (v, t) in thickness.iter().enumerate() {
            let t = t[side];
            if t.is_finite() && t * std::f64::consts::SQRT_2 < covered_by[v] {
                out.push(feature(
                    [surface.positions[v]; 3],
                    t,
                    t,
                    unit(normals[v], sign),
                ));
            }
        }
    }
    out
}

/// The surface's creases (edges whose two faces turn by more than [`CREASE_DEG`]) and
/// corners (vertices where other than two creases meet: a crease's end, or three and
/// more), for the mesher to snap its boundary onto.
pub(super) fn sharp_features(surface: &SurfaceMesh, topology: &Topology) -> SharpFeatures {
    let min_cos = CREASE_DEG.to_radians().cos();
    let normals: Vec<[f64; 3]> = (0..surface.num_triangles())
        .map(|f| {
            let n = surface.face_normal_scaled(f);
            let l = norm(n);
            if l > 0.0 {
                scale(n, 1.0 / l)
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let mut creases_at = vec![0u32; surface.num_vertices()];
    let mut features = SharpFeatures::default();
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        let faces = topology.edge_faces(e);
        if faces.len() != 2 {
            continue;
        }
        let (n0, n1) = (normals[faces[0] as usize], normals[faces[1] as usize]);
        if n0 == [0.0; 3] || n1 == [0.0; 3] || dot(n0, n1) >= min_cos {
            continue;
        }
        features
            .edges
            .push([surface.positions[a as usize], surface.positions[b as usize]]);
        creases_at[a as usize] += 1;
        creases_at[b as usize] += 1;
    }
    for (v, &n) in creases_at.iter().enumerate() {
        if n == 1 || n >= 3 {
            features.corners.push(surface.positions[v]);
        }
    }
    features
}
