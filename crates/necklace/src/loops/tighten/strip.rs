//! Step 3 of the tightening: the strip update. Where the path passes a mesh vertex
//! ([`vertex_runs`]: the portals crossed there, the angle on the strip's side and on
//! the other), a loop whose other side is below π is shorter round that side
//! ([`vertex_updates`]); [`Strip::apply`] replaces the faces around the vertex on the
//! strip's side by those on the other ([`other_side`]).
//!
//! Conventions: angles in radians; a run's portals are `first..first + len`, cyclic.

use std::f64::consts::PI;

use super::{angle, Strip, StripPath, SurfaceGeometry};
use crate::geom::sub;

/// A maximal run of consecutive portals `first..=last` (cyclic, `first` may exceed
/// `last` when it wraps) crossed at one vertex.
#[derive(Debug, Clone, Copy)]
pub(super) struct VertexRun {
    pub vertex: u32,
    pub first: usize,
    pub len: usize,
    /// Angle on the strip side.
    pub strip_angle: f64,
    /// Angle on the other side.
    pub other_angle: f64,
}

/// Runs of portals crossed at a vertex, with their two angles.
pub(super) fn vertex_runs(
    geometry: &SurfaceGeometry,
    strip: &Strip,
    path: &StripPath,
) -> Vec<VertexRun> {
    let n = strip.portals.len();
    let cs = &path.crossings;
    // Start scanning just after a portal not crossed at a vertex (exists unless collapsed).
    let Some(free) = (0..n).find(|&i| cs[i].vertex.is_none()) else {
        return Vec::new();
    };
    let mut runs = Vec::new();
    let mut k = 1;
    while k < n {
        let i = (free + k) % n;
        let Some(v) = cs[i].vertex else {
            k += 1;
            continue;
        };
        let mut len = 1;
        while k + len < n && cs[(free + k + len) % n].vertex == Some(v) {
            len += 1;
        }
        let last = (i + len - 1) % n;
        let before = (i + n - 1) % n;
        let after = (last + 1) % n;
        let pv = geometry.pos(v);
        let other_end = |e: u32| {
            let [a, b] = geometry.edge(e);
            if a == v {
                b
            } else {
                a
            }
        };
        let part = |p: [f64; 3], w: u32| angle(sub(p, pv), sub(geometry.pos(w), pv));
        let mut strip_angle = part(cs[before].point, other_end(strip.portals[i]));
        for m in 0..len - 1 {
            strip_angle += geometry.face_angle(strip.faces[(i + m) % n], v);
        }
        strip_angle += part(cs[after].point, other_end(strip.portals[last]));
        runs.push(VertexRun {
            vertex: v,
            first: i,
            len,
            strip_angle,
            other_angle: geometry.total_angle[v as usize] - strip_angle,
        });
        k += len;
    }
    runs
}

/// The runs where the other side is shorter: angle below π − tolerance.
pub(super) fn vertex_updates(
    geometry: &SurfaceGeometry,
    strip: &Strip,
    path: &StripPath,
    tolerance: f64,
) -> Vec<VertexRun> {
    vertex_runs(geometry, strip, path)
        .into_iter()
        .filter(|r| r.other_angle < PI - tolerance)
        .collect()
}

impl Strip {
    /// Replace, for each run (non-overlapping ones only), the strip faces around its
    /// vertex by the faces on the other side. Returns the number of updates made.
    pub(super) fn apply(
        &mut self,
        geometry: &SurfaceGeometry,
        path: &StripPath,
        runs: &[VertexRun],
    ) -> Option<usize> {
        let n = self.portals.len();
        // Rotate so that index 0 is a portal crossed away from any vertex.
        let free = (0..n).find(|&i| path.crossings[i].vertex.is_none())?;
        self.portals.rotate_left(free);
        self.faces.rotate_left(free);
        self.hint.rotate_left(free);
        let mut runs: Vec<(usize, usize, u32)> = runs
            .iter()
            .map(|r| {
                let first = (r.first + n - free) % n;
                (first, first + r.len - 1, r.vertex)
            })
            .collect();
        runs.sort_unstable();

        let mut portals = Vec::with_capacity(n + 8);
        let mut faces = Vec::with_capacity(n + 8);
        let mut hint = Vec::with_capacity(n + 8);
        let mut next = 0; // next portal index to copy
        let mut done = 0;
        for &(first, last, v) in &runs {
            // A portal next to the run that ends at the vertex is the edge the loop
            // enters or leaves it along: the other side reaches up to that edge, so the
            // replaced stretch includes it.
            let at_v = |e: u32| geometry.edge(e).contains(&v);
            let mut first = first;
            while first >= 2 && at_v(self.portals[first - 1]) {
                first -= 1;
            }
            let mut last = last;
            while last + 1 < n && at_v(self.portals[last + 1]) {
                last += 1;
            }
            // Faces first-1 ..= last are touched; skip runs overlapping the previous one.
            if first == 0 || first <= next || last >= n {
                continue;
            }
            let start_face = self.faces[first - 1];
            let end_face = self.faces[last];
            if start_face == end_face {
                continue;
            }
            let Some((new_portals, new_faces)) =
                other_side(geometry, v, start_face, self.portals[first], end_face)
            else {
                continue;
            };
            // The loop runs along a portal edge into the vertex: no well-defined other
            // side from here; the neighbouring run's update resolves it.
            if new_portals.first() == Some(&self.portals[first - 1])
                || new_portals.last() == self.portals.get(last + 1)
            {
                continue;
            }
            for q in next..first {
                portals.push(self.portals[q]);
                faces.push(self.faces[q]);
                hint.push(self.hint[q]);
            }
            let m = new_faces.len();
            for (a, &e) in new_portals.iter().enumerate() {
                portals.push(e);
                faces.push(if a < m { new_faces[a] } else { end_face });
                hint.push(f64::NAN);
            }
            next = last + 1;
            done += 1;
        }
        for q in next..n {
            portals.push(self.portals[q]);
            faces.push(self.faces[q]);
            hint.push(self.hint[q]);
        }
        self.portals = portals;
        self.faces = faces;
        self.hint = hint;
        Some(done)
    }
}

/// Walk around `v` from `start_face` away from edge `entry` until `end_face`: the edges
/// crossed and the faces strictly between.
fn other_side(
    geometry: &SurfaceGeometry,
    v: u32,
    start_face: u32,
    entry: u32,
    end_face: u32,
) -> Option<(Vec<u32>, Vec<u32>)> {
    let degree = geometry.topology.vertex_faces(v as usize).len();
    let mut edges = Vec::new();
    let mut faces = Vec::new();
    let mut face = start_face;
    let mut edge = geometry.other_edge_at(face, v, entry)?;
    for _ in 0..degree {
        edges.push(edge);
        face = geometry.across(edge, face)?;
        if face == end_face {
            return Some((edges, faces));
        }
        faces.push(face);
        edge = geometry.other_edge_at(face, v, edge)?;
    }
    None
}
