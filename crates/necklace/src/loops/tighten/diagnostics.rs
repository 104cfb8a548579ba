//! The tightened loop as the caller gets it, with the diagnostics that say how close it
//! is to a closed geodesic ([`finish`]): the largest turn across an edge crossed in its
//! interior (0 when straight in the unfolding), the smallest angle on either side at a
//! vertex it passes (≥ π for a geodesic), and whether it is simple (no vertex twice, no
//! two segments crossing inside a face).

use std::f64::consts::PI;

use super::strip::vertex_runs;
use super::unfold::cross2;
use super::{
    angle, closed_length, Strip, StripPath, SurfaceGeometry, SurfacePoint, TightenStatus, Tightened,
};
use crate::geom::{cross, dot, norm, sub};

/// Crossings closer than this to their neighbours or to the edge's end are left out of
/// the edge-turn measure (no direction to measure).
const MIN_SEGMENT: f64 = 1e-14;

/// Two segments in a face cross only where each one's ends lie more than this fraction
/// of the face's size on either side of the other (touching is not crossing).
const CROSS_TOLERANCE: f64 = 1e-12;

/// Build the output: surface points, 3D points and the geodesic diagnostics.
pub(super) fn finish(
    geometry: &SurfaceGeometry,
    strip: &Strip,
    path: &StripPath,
    initial_length: f64,
    rounds: usize,
    updates: usize,
    status: TightenStatus,
) -> Tightened {
    let n = strip.portals.len();
    let cs = &path.crossings;

    // Straightness across edges crossed in their interior: the angle at the crossing
    // between the previous and next points, measured through the two faces, is π.
    let mut max_edge_turn: f64 = 0.0;
    for i in 0..n {
        if cs[i].vertex.is_some() {
            continue;
        }
        let (prev, next) = (cs[(i + n - 1) % n].point, cs[(i + 1) % n].point);
        let c = cs[i].point;
        let [a, _] = geometry.edge(strip.portals[i]);
        let pa = geometry.pos(a);
        let (dp, dn, da) = (sub(prev, c), sub(next, c), sub(pa, c));
        if norm(dp) <= MIN_SEGMENT || norm(dn) <= MIN_SEGMENT || norm(da) <= MIN_SEGMENT {
            continue;
        }
        let total = angle(dp, da) + angle(da, dn);
        max_edge_turn = max_edge_turn.max((PI - total).abs());
    }
    let runs = vertex_runs(geometry, strip, path);
    let min_vertex_angle = runs
        .iter()
        .map(|r| r.strip_angle.min(r.other_angle))
        .fold(PI, f64::min);

    // Points: one per portal, consecutive crossings at the same vertex merged.
    let mut surface_points = Vec::with_capacity(n);
    let mut points = Vec::with_capacity(n);
    for (i, c) in cs.iter().enumerate() {
        match c.vertex {
            Some(v) => {
                let prev = cs[(i + n - 1) % n].vertex;
                if prev == Some(v) && n > 1 {
                    continue;
                }
                surface_points.push(SurfacePoint::Vertex { vertex: v });
            }
            None => surface_points.push(SurfacePoint::Edge {
                edge: geometry.edge(strip.portals[i]),
                t: c.t,
            }),
        }
        points.push(c.point);
    }
    // Fewer than three points is a segment walked there and back, not a loop.
    let simple = points.len() >= 3 && is_simple(geometry, strip, path, &surface_points);
    Tightened {
        length: closed_length(&points),
        surface_points,
        points,
        initial_length,
        rounds,
        updates,
        status,
        max_edge_turn,
        min_vertex_angle,
        simple,
    }
}

/// No vertex visited twice, and no two segments in the same face crossing.
fn is_simple(
    geometry: &SurfaceGeometry,
    strip: &Strip,
    path: &StripPath,
    surface_points: &[SurfacePoint],
) -> bool {
    let mut vertices: Vec<u32> = surface_points
        .iter()
        .filter_map(|p| match p {
            SurfacePoint::Vertex { vertex } => Some(*vertex),
            SurfacePoint::Edge { .. } => None,
        })
        .collect();
    vertices.sort_unstable();
    if vertices.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    let n = strip.portals.len();
    let mut by_face: Vec<(u32, usize)> = (0..n).map(|i| (strip.faces[i], i)).collect();
    by_face.sort_unstable();
    for group in by_face.chunk_by(|a, b| a.0 == b.0) {
        for (x, &(f, i)) in group.iter().enumerate() {
            for &(_, j) in &group[x + 1..] {
                let seg = |k: usize| (path.crossings[k].point, path.crossings[(k + 1) % n].point);
                if segments_cross(geometry, f, seg(i), seg(j)) {
                    return false;
                }
            }
        }
    }
    true
}

/// Whether two segments in the plane of face `f` cross at a point interior to both.
fn segments_cross(
    geometry: &SurfaceGeometry,
    f: u32,
    (a, b): ([f64; 3], [f64; 3]),
    (c, d): ([f64; 3], [f64; 3]),
) -> bool {
    let [p0, p1, p2] = geometry.mesh.corners(f as usize);
    let u = sub(p1, p0);
    let nrm = cross(u, sub(p2, p0));
    let v = cross(nrm, u);
    let (lu, lv) = (norm(u), norm(v));
    if lu == 0.0 || lv == 0.0 {
        return false;
    }
    let to2 = |p: [f64; 3]| {
        let d = sub(p, p0);
        [dot(d, u) / lu, dot(d, v) / lv]
    };
    let (a, b, c, d) = (to2(a), to2(b), to2(c), to2(d));
    let eps = CROSS_TOLERANCE * (lu + lv);
    let o1 = cross2(a, b, c);
    let o2 = cross2(a, b, d);
    let o3 = cross2(c, d, a);
    let o4 = cross2(c, d, b);
    (o1 > eps && o2 < -eps || o1 < -eps && o2 > eps)
        && (o3 > eps && o4 < -eps || o3 < -eps && o4 > eps)
}
