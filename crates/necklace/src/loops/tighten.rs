//! Geodesic tightening of a closed loop on a triangle mesh (sec. 4.3; the paper's
//! ref. \[25\], Xin & Wang 2007, "Efficiently determining a locally exact shortest path on
//! polyhedral surfaces").
//!
//! The loop is held as a *strip*: the cyclic sequence of edges it crosses (portals) and
//! the faces between them. One round:
//! 1. **Unfold** the strip into the plane, starting from an anchor portal; the anchor
//!    appears twice, at the start and (moved rigidly) at the end.
//! 2. **Shortest closed path in the strip**: for an anchor point at parameter `t`, the
//!    funnel algorithm gives the shortest path from the point to its image through the
//!    portals. Its length is convex in `t` (distance between two points moving along
//!    geodesics of a flat simply connected surface), so `t` is found by a safeguarded
//!    regula falsi on the derivative.
//! 3. **Strip update**: where the path touches a mesh vertex, compare the angle on the
//!    strip side with the angle on the other side (total angle − strip side). If the
//!    other side is below π − tolerance the loop is shorter there: the faces around the
//!    vertex on the other side replace those on the strip side.
//!
//! Rounds stop when no vertex needs an update (a closed geodesic: straight inside faces
//! and across edges, and at every vertex it passes both angles are ≥ π), when the length
//! decrease is below `rel_tolerance`, or at `max_rounds`. A loop whose length falls below
//! `min_length_ratio` of its start slid off a cap: it is reported as collapsed.
//!
//! Conventions: a strip is traversed forward; each portal has a *left* and a *right*
//! vertex seen in that direction. Angles are in radians; lengths in mesh units.
//! Entry point: [`tighten`].

use std::f64::consts::PI;

use serde::Serialize;

use super::cut::Crossing;
use crate::geom::{dot, illinois_root, lerp, norm, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// The anchor search stops when its bracket of the strip parameter is narrower than
/// this.
const SLOPE_BRACKET: f64 = 1e-13;

/// Most evaluations of the anchor search.
const SLOPE_STEPS: usize = 100;

/// Options of [`tighten`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TightenOptions {
    /// Most strip-update rounds. Default 2000.
    pub max_rounds: usize,
    /// Stop when a round shortens the loop by less than this fraction. Default 1e-10.
    pub rel_tolerance: f64,
    /// A loop shorter than this fraction of its initial length has collapsed. Default 0.2.
    pub min_length_ratio: f64,
    /// Angle slack (radians) in the "both sides ≥ π" test at vertices. Default 1e-6.
    pub angle_tolerance: f64,
}

impl Default for TightenOptions {
    fn default() -> Self {
        TightenOptions {
            max_rounds: 2000,
            rel_tolerance: 1e-10,
            min_length_ratio: 0.2,
            angle_tolerance: 1e-6,
        }
    }
}

/// A point of the surface the loop passes through.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfacePoint {
    /// On edge `[a, b]` at `(1 − t)·a + t·b`, `0 < t < 1`.
    Edge {
        /// The edge's vertices.
        edge: [u32; 2],
        /// Parameter from `edge[0]`.
        t: f64,
    },
    /// At a mesh vertex.
    Vertex {
        /// The vertex.
        vertex: u32,
    },
}

/// How tightening ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TightenStatus {
    /// A closed geodesic: no vertex needs an update.
    Converged,
    /// The last round shortened the loop by less than `rel_tolerance`, or no pending
    /// vertex update could be made; the diagnostics say how far from a geodesic it is.
    Stalled,
    /// Shorter than `min_length_ratio` of the start, or shrunk onto one vertex.
    Collapsed,
    /// `max_rounds` reached while still shortening.
    NotConverged,
    /// The strip could not be unfolded (it is not a strip of an oriented manifold).
    InvalidStrip,
}

/// A tightened loop with its diagnostics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tightened {
    /// Surface points in order, cyclic, first not repeated.
    pub surface_points: Vec<SurfacePoint>,
    /// Their 3D positions.
    pub points: Vec<[f64; 3]>,
    /// Length of the closed polyline.
    pub length: f64,
    /// Length of the loop given.
    pub initial_length: f64,
    /// Strip-update rounds done.
    pub rounds: usize,
    /// Vertex updates done (over all rounds).
    pub updates: usize,
    /// How it ended.
    pub status: TightenStatus,
    /// Largest turning angle (radians) across an edge crossed in its interior: 0 for a
    /// path that is straight in the unfolding.
    pub max_edge_turn: f64,
    /// Smallest of the two angles (radians) at a vertex the loop passes through: ≥ π for
    /// a geodesic; π when it passes through no vertex.
    pub min_vertex_angle: f64,
    /// Whether the loop is simple: it visits no vertex twice and no two of its segments
    /// cross inside a face.
    pub simple: bool,
}

/// Per-mesh data the tightening needs: adjacency and the total angle at each vertex.
#[derive(Debug, Clone)]
pub struct SurfaceGeometry<'a> {
    mesh: &'a SurfaceMesh,
    topology: &'a Topology,
    total_angle: Vec<f64>,
}

impl<'a> SurfaceGeometry<'a> {
    /// Precompute the total angle at every vertex. `O(F)`.
    pub fn new(mesh: &'a SurfaceMesh, topology: &'a Topology) -> Self {
        let mut total_angle = vec![0.0; mesh.num_vertices()];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (v, a, b) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let p = mesh.positions[v as usize];
                total_angle[v as usize] += angle(
                    sub(mesh.positions[a as usize], p),
                    sub(mesh.positions[b as usize], p),
                );
            }
        }
        SurfaceGeometry {
            mesh,
            topology,
            total_angle,
        }
    }

    /// The sum of the face angles at each vertex.
    pub fn total_angles(&self) -> &[f64] {
        &self.total_angle
    }

    fn pos(&self, v: u32) -> [f64; 3] {
        self.mesh.positions[v as usize]
    }

    fn edge(&self, e: u32) -> [u32; 2] {
        self.topology.edges()[e as usize]
    }

    /// Angle at `v` inside face `f`.
    fn face_angle(&self, f: u32, v: u32) -> f64 {
        let t = self.mesh.triangles[f as usize];
        let k = t.iter().position(|&x| x == v).unwrap_or(0);
        let p = self.pos(v);
        angle(
            sub(self.pos(t[(k + 1) % 3]), p),
            sub(self.pos(t[(k + 2) % 3]), p),
        )
    }

    /// The edge of face `f` at vertex `v` other than edge `e`.
    fn other_edge_at(&self, f: u32, v: u32, e: u32) -> Option<u32> {
        (0..3)
            .filter_map(|i| self.topology.face_edge(f as usize, i))
            .map(|g| g as u32)
            .find(|&g| g != e && self.edge(g).contains(&v))
    }

    /// The face across edge `e` from face `f`.
    fn across(&self, e: u32, f: u32) -> Option<u32> {
        let faces = self.topology.edge_faces(e as usize);
        if faces.len() != 2 {
            return None;
        }
        Some(if faces[0] == f { faces[1] } else { faces[0] })
    }
}

/// Angle between two vectors, in `[0, π]`.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = crate::geom::cross(a, b);
    norm(c).atan2(dot(a, b))
}

/// Tighten the closed loop given by its crossings (in order) and the faces between them
/// (`faces[i]` between `crossings[i]` and `crossings[i + 1]`, cyclically), as produced by
/// a plane cut.
pub fn tighten(
    geometry: &SurfaceGeometry,
    crossings: &[Crossing],
    faces: &[u32],
    options: &TightenOptions,
) -> Tightened {
    let mut strip = Strip {
        portals: crossings.iter().map(|c| c.edge).collect(),
        faces: faces.to_vec(),
        hint: crossings.iter().map(|c| c.t).collect(),
    };
    let initial_points: Vec<[f64; 3]> = crossings
        .iter()
        .map(|c| {
            let [a, b] = geometry.edge(c.edge);
            lerp(geometry.pos(a), geometry.pos(b), c.t)
        })
        .collect();
    let initial_length = super::cut::closed_length(&initial_points);

    let mut rounds = 0;
    let mut updates = 0;
    let mut status = TightenStatus::NotConverged;
    let mut path: Option<StripPath> = None;
    let mut previous: Option<Strip> = None;
    while rounds < options.max_rounds {
        rounds += 1;
        let Some(p) = shortest_closed_path(geometry, &mut strip) else {
            status = TightenStatus::InvalidStrip;
            break;
        };
        // Each update keeps the last path inside the strip, so the length cannot grow;
        // should rounding ever make it, keep the last loop rather than a longer one.
        if let (Some(last), Some(prev)) = (&path, &previous) {
            if p.length > last.length * (1.0 + 1e-12) {
                strip = prev.clone();
                status = TightenStatus::Stalled;
                break;
            }
        }
        let decrease = path.as_ref().map_or(f64::INFINITY, |l| l.length - p.length);
        let length = p.length;
        let shrunk_to_vertex = p.crossings.iter().all(|c| c.vertex.is_some())
            && p.crossings
                .iter()
                .all(|c| c.vertex == p.crossings[0].vertex);
        path = Some(p);
        if shrunk_to_vertex || length < options.min_length_ratio * initial_length {
            status = TightenStatus::Collapsed;
            break;
        }
        let p = path.as_ref().expect("set above");
        let wanted = vertex_updates(geometry, &strip, p, options.angle_tolerance);
        if wanted.is_empty() {
            status = TightenStatus::Converged;
            break;
        }
        // The strip goes all the way around a vertex that the loop wants to pass on
        // its other side: the loop contracts over that vertex.
        let n = strip.portals.len();
        if wanted
            .iter()
            .any(|r| strip.faces[(r.first + n - 1) % n] == strip.faces[(r.first + r.len - 1) % n])
        {
            status = TightenStatus::Collapsed;
            break;
        }
        if decrease <= options.rel_tolerance * length {
            status = TightenStatus::Stalled;
            break;
        }
        previous = Some(strip.clone());
        match strip.apply(geometry, p, &wanted) {
            Some(0) => {
                status = TightenStatus::Stalled;
                break;
            }
            Some(n) => updates += n,
            None => {
                // Keep the strip the last path lies in.
                if let Some(prev) = &previous {
                    strip = prev.clone();
                }
                status = TightenStatus::InvalidStrip;
                break;
            }
        }
        // A strip that keeps growing is sliding around the surface, not settling. The
        // last path lies in the strip before this round's update: report on that one.
        if strip.portals.len() > 20 * crossings.len() + 1000 {
            if let Some(prev) = &previous {
                strip = prev.clone();
            }
            status = TightenStatus::NotConverged;
            break;
        }
    }

    // The path must lie in the strip reported on (one crossing per portal).
    let path = path.filter(|p| p.crossings.len() == strip.portals.len());
    if path.is_none() && status != TightenStatus::NotConverged {
        status = TightenStatus::InvalidStrip;
    }
    let Some(path) = path else {
        return Tightened {
            surface_points: Vec::new(),
            points: initial_points,
            length: initial_length,
            initial_length,
            rounds,
            updates,
            status,
            max_edge_turn: f64::NAN,
            min_vertex_angle: f64::NAN,
            simple: false,
        };
    };
    finish(
        geometry,
        &strip,
        &path,
        initial_length,
        rounds,
        updates,
        status,
    )
}

/// The loop's strip: `faces[i]` lies between `portals[i]` and `portals[i + 1]`.
#[derive(Debug, Clone)]
struct Strip {
    portals: Vec<u32>,
    faces: Vec<u32>,
    /// Edge parameter of the previous path on each portal (NaN when unknown); used to
    /// choose an anchor away from vertices.
    hint: Vec<f64>,
}

/// Where the path crosses one portal.
#[derive(Debug, Clone, Copy)]
struct PortalCrossing {
    /// Parameter along the edge's stored vertex pair.
    t: f64,
    /// The vertex, when the path passes through an endpoint.
    vertex: Option<u32>,
    /// 3D point.
    point: [f64; 3],
}

#[derive(Debug, Clone)]
struct StripPath {
    crossings: Vec<PortalCrossing>,
    length: f64,
}

/// A portal in the unfolding.
#[derive(Debug, Clone, Copy)]
struct Portal2 {
    left: [f64; 2],
    right: [f64; 2],
    lv: u32,
    rv: u32,
}

fn cross2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn lerp2(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// Unfold the strip starting at portal `anchor`: `n + 1` portals, the last being the
/// anchor's image. `None` when consecutive portals do not share a face as stored.
fn unfold(geometry: &SurfaceGeometry, strip: &Strip, anchor: usize) -> Option<Vec<Portal2>> {
    let n = strip.portals.len();
    let [a, b] = geometry.edge(strip.portals[anchor]);
    let len = norm(sub(geometry.pos(a), geometry.pos(b)));
    let mut out = Vec::with_capacity(n + 1);
    // Right vertex at the origin, left above it: forward is +x.
    let mut cur = Portal2 {
        left: [0.0, len],
        right: [0.0, 0.0],
        lv: a,
        rv: b,
    };
    // The first face must lie forward; the orientation of (a, b) is arbitrary, so
    // nothing to check here: the third vertex is placed forward by construction.
    out.push(cur);
    for k in 0..n {
        let i = (anchor + k) % n;
        let f = strip.faces[i];
        let tri = geometry.mesh.triangles[f as usize];
        let w = *tri.iter().find(|&&x| x != cur.lv && x != cur.rv)?;
        if !(tri.contains(&cur.lv) && tri.contains(&cur.rv)) {
            return None;
        }
        let pw = geometry.pos(w);
        let da = norm(sub(pw, geometry.pos(cur.lv)));
        let db = norm(sub(pw, geometry.pos(cur.rv)));
        let d = dist2(cur.left, cur.right);
        if d <= 0.0 {
            return None;
        }
        let u = [
            (cur.left[0] - cur.right[0]) / d,
            (cur.left[1] - cur.right[1]) / d,
        ];
        let forward = [u[1], -u[0]];
        let x = (db * db - da * da + d * d) / (2.0 * d);
        let h = (db * db - x * x).max(0.0).sqrt();
        let w2 = [
            cur.right[0] + x * u[0] + h * forward[0],
            cur.right[1] + x * u[1] + h * forward[1],
        ];
        let [p, q] = geometry.edge(strip.portals[(i + 1) % n]);
        let next_has = |v: u32| p == v || q == v;
        cur = if next_has(w) && next_has(cur.rv) {
            Portal2 {
                left: w2,
                right: cur.right,
                lv: w,
                rv: cur.rv,
            }
        } else if next_has(w) && next_has(cur.lv) {
            Portal2 {
                left: cur.left,
                right: w2,
                lv: cur.lv,
                rv: w,
            }
        } else {
            return None;
        };
        out.push(cur);
    }
    // The anchor comes back with the same sides on an oriented surface.
    (out[n].lv == a && out[n].rv == b).then_some(out)
}

/// One vertex of the funnel path: its 2D position, its mesh vertex (None for the end
/// points) and the index of the portal where it was found.
#[derive(Debug, Clone, Copy)]
struct Apex {
    pos: [f64; 2],
    vertex: Option<u32>,
    index: usize,
}

/// Shortest path from `start` (on portal 0) to `goal` (on portal `n`) through portals
/// `1..n` (the funnel algorithm). Returns the bend points including both ends.
/// An end point that is a portal endpoint carries its vertex, so that the funnel sees it
/// as the same point as that vertex on the following portals.
fn funnel(
    start: [f64; 2],
    goal: [f64; 2],
    portals: &[Portal2],
    end_vertex: Option<u32>,
) -> Vec<Apex> {
    let n = portals.len() - 1;
    let mut path = vec![Apex {
        pos: start,
        vertex: end_vertex,
        index: 0,
    }];
    let mut apex = path[0];
    let (mut left, mut right) = (apex, apex);
    let same = |a: &Apex, b: &Apex| a.vertex == b.vertex && a.pos == b.pos;
    let mut i = 1;
    while i <= n {
        let (l, r) = if i < n {
            let p = portals[i];
            (
                Apex {
                    pos: p.left,
                    vertex: Some(p.lv),
                    index: i,
                },
                Apex {
                    pos: p.right,
                    vertex: Some(p.rv),
                    index: i,
                },
            )
        } else {
            let g = Apex {
                pos: goal,
                vertex: end_vertex,
                index: n,
            };
            (g, g)
        };
        // Right side: r narrows the funnel when it is left of (or on) apex→right.
        if same(&r, &apex) || same(&r, &right) {
            right = r;
        } else if cross2(apex.pos, right.pos, r.pos) >= 0.0 || same(&apex, &right) {
            if same(&apex, &right) || same(&apex, &left) || cross2(apex.pos, left.pos, r.pos) < 0.0
            {
                right = r;
            } else {
                // r passes over the left side: the path bends at the left point.
                path.push(left);
                apex = left;
                right = apex;
                i = apex.index + 1;
                continue;
            }
        }
        // Left side: l narrows the funnel when it is right of (or on) apex→left.
        if same(&l, &apex) || same(&l, &left) || same(&l, &right) {
            // (l == right only at the goal, where the portal is a single point.)
            left = l;
        } else if cross2(apex.pos, left.pos, l.pos) <= 0.0 || same(&apex, &left) {
            if same(&apex, &left) || same(&apex, &right) || cross2(apex.pos, right.pos, l.pos) > 0.0
            {
                left = l;
            } else {
                path.push(right);
                apex = right;
                left = apex;
                i = apex.index + 1;
                continue;
            }
        }
        i += 1;
    }
    path.push(Apex {
        pos: goal,
        vertex: end_vertex,
        index: n,
    });
    path
}

/// Length of a funnel path and its derivative with respect to the anchor parameter,
/// given how the start and goal move (`ds`, `dg` per unit parameter).
fn length_and_slope(path: &[Apex], ds: [f64; 2], dg: [f64; 2]) -> (f64, f64) {
    let length: f64 = path.windows(2).map(|w| dist2(w[0].pos, w[1].pos)).sum();
    let unit = |a: [f64; 2], b: [f64; 2]| {
        let d = dist2(a, b);
        if d > 0.0 {
            [(a[0] - b[0]) / d, (a[1] - b[1]) / d]
        } else {
            [0.0, 0.0]
        }
    };
    // Bend points at the same place as an end do not count.
    let (s, g) = (path[0].pos, path[path.len() - 1].pos);
    let inner: Vec<[f64; 2]> = path[1..path.len() - 1]
        .iter()
        .map(|a| a.pos)
        .filter(|&p| p != s && p != g)
        .collect();
    let k = inner.len() + 2;
    let slope = if k == 2 {
        let e = unit(g, s);
        e[0] * (dg[0] - ds[0]) + e[1] * (dg[1] - ds[1])
    } else {
        let a = unit(s, inner[0]);
        let b = unit(g, inner[k - 3]);
        a[0] * ds[0] + a[1] * ds[1] + b[0] * dg[0] + b[1] * dg[1]
    };
    (length, slope)
}

/// The shortest closed path homotopic to the strip's core, with its crossings.
fn shortest_closed_path(geometry: &SurfaceGeometry, strip: &mut Strip) -> Option<StripPath> {
    let n = strip.portals.len();
    if n < 2 {
        return None;
    }
    // Anchor: the portal whose previous crossing is farthest from both endpoints.
    let anchor = (0..n)
        .min_by(|&i, &j| {
            let score = |k: usize| {
                let t = strip.hint[k];
                if t.is_nan() {
                    1.0
                } else {
                    (t - 0.5).abs()
                }
            };
            score(i).total_cmp(&score(j)).then(i.cmp(&j))
        })
        .unwrap_or(0);
    let portals = unfold(geometry, strip, anchor)?;
    let (p0, pn) = (portals[0], portals[n]);
    let ds = [p0.right[0] - p0.left[0], p0.right[1] - p0.left[1]];
    let dg = [pn.right[0] - pn.left[0], pn.right[1] - pn.left[1]];
    let eval = |t: f64| {
        let (s, g, end_vertex) = if t == 0.0 {
            (p0.left, pn.left, Some(p0.lv))
        } else if t == 1.0 {
            (p0.right, pn.right, Some(p0.rv))
        } else {
            (
                lerp2(p0.left, p0.right, t),
                lerp2(pn.left, pn.right, t),
                None,
            )
        };
        let path = funnel(s, g, &portals, end_vertex);
        let (len, slope) = length_and_slope(&path, ds, dg);
        (path, len, slope)
    };

    // Minimise the convex length over t in [0, 1]: regula falsi (Illinois) on the slope.
    let (_, _, s0) = eval(0.0);
    let (_, _, s1) = eval(1.0);
    let t = if s0 >= 0.0 {
        0.0
    } else if s1 <= 0.0 {
        1.0
    } else {
        illinois_root(|t| eval(t).2, s0, s1, 0.0, SLOPE_BRACKET, SLOPE_STEPS)
    };
    let (path, length, _) = eval(t);
    // Crossings of every portal, anchor first (index k ↔ strip portal (anchor + k) % n).
    let mut by_k: Vec<Option<PortalCrossing>> = vec![None; n];
    let mk = |geometry: &SurfaceGeometry, k: usize, s: f64, vertex: Option<u32>| {
        let pt = portals[k];
        let e = strip.portals[(anchor + k) % n];
        let [a, b] = geometry.edge(e);
        // s runs from left to right.
        let t = if pt.lv == a { s } else { 1.0 - s };
        let point = match vertex {
            Some(v) => geometry.pos(v),
            None => lerp(geometry.pos(a), geometry.pos(b), t),
        };
        let t = match vertex {
            Some(v) if v == a => 0.0,
            Some(_) => 1.0,
            None => t,
        };
        PortalCrossing { t, vertex, point }
    };
    // Crossings within SNAP of an endpoint are at that vertex: rounding must not leave a
    // point a hair away from a vertex the path really passes through.
    const SNAP: f64 = 1e-9;
    let at_end = |s: f64, pt: Portal2| {
        if s <= SNAP {
            Some(pt.lv)
        } else if s >= 1.0 - SNAP {
            Some(pt.rv)
        } else {
            None
        }
    };
    by_k[0] = Some(mk(geometry, 0, t, at_end(t, p0)));
    for seg in path.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        for k in a.index.max(1)..=b.index.min(n - 1) {
            if by_k[k].is_some() {
                continue;
            }
            let pt = portals[k];
            let touches = |x: &Apex| {
                x.vertex.and_then(|v| {
                    if pt.lv == v && pt.left == x.pos {
                        Some((0.0, v))
                    } else if pt.rv == v && pt.right == x.pos {
                        Some((1.0, v))
                    } else {
                        None
                    }
                })
            };
            // A portal holding both bend points is the edge the path runs along: it
            // counts as crossed where that run ends, so each vertex's run starts with
            // the edge it is entered along.
            let hit = touches(&b).or_else(|| {
                let (s, v) = touches(&a)?;
                // From `a` along this very edge: the path passes its other end too.
                let (w, wv) = if s == 0.0 {
                    (pt.right, pt.rv)
                } else {
                    (pt.left, pt.lv)
                };
                let along = cross2(a.pos, b.pos, w).abs()
                    <= 1e-8 * dist2(a.pos, b.pos) * dist2(a.pos, w)
                    && dist2(a.pos, w) <= dist2(a.pos, b.pos);
                Some(if along { (1.0 - s, wv) } else { (s, v) })
            });
            let c = if let Some((s, v)) = hit {
                mk(geometry, k, s, Some(v))
            } else {
                let d = [b.pos[0] - a.pos[0], b.pos[1] - a.pos[1]];
                let e = [pt.right[0] - pt.left[0], pt.right[1] - pt.left[1]];
                let den = e[0] * d[1] - e[1] * d[0];
                let scale = dist2(a.pos, b.pos) * dist2(pt.left, pt.right);
                let s = if den.abs() > 1e-12 * scale {
                    let w = [a.pos[0] - pt.left[0], a.pos[1] - pt.left[1]];
                    ((w[0] * d[1] - w[1] * d[0]) / den).clamp(0.0, 1.0)
                } else if dist2(pt.left, b.pos) <= dist2(pt.right, b.pos) {
                    // The path runs along this edge: it passes its endpoint nearer
                    // the next bend point.
                    0.0
                } else {
                    1.0
                };
                mk(geometry, k, s, at_end(s, pt))
            };
            by_k[k] = Some(c);
        }
    }
    let mut crossings = vec![
        PortalCrossing {
            t: f64::NAN,
            vertex: None,
            point: [f64::NAN; 3]
        };
        n
    ];
    for (k, c) in by_k.into_iter().enumerate() {
        crossings[(anchor + k) % n] = c?;
    }
    for (i, c) in crossings.iter().enumerate() {
        strip.hint[i] = if c.vertex.is_some() { f64::NAN } else { c.t };
    }
    Some(StripPath { crossings, length })
}

/// A maximal run of consecutive portals `first..=last` (cyclic, `first` may exceed
/// `last` when it wraps) crossed at one vertex.
#[derive(Debug, Clone, Copy)]
struct VertexRun {
    vertex: u32,
    first: usize,
    len: usize,
    /// Angle on the strip side.
    strip_angle: f64,
    /// Angle on the other side.
    other_angle: f64,
}

/// Runs of portals crossed at a vertex, with their two angles.
fn vertex_runs(geometry: &SurfaceGeometry, strip: &Strip, path: &StripPath) -> Vec<VertexRun> {
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
fn vertex_updates(
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
    fn apply(
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

/// Build the output: surface points, 3D points and the geodesic diagnostics.
fn finish(
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
        if norm(dp) <= 1e-14 || norm(dn) <= 1e-14 || norm(da) <= 1e-14 {
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
        length: super::cut::closed_length(&points),
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
    let nrm = crate::geom::cross(u, sub(p2, p0));
    let v = crate::geom::cross(nrm, u);
    let (lu, lv) = (norm(u), norm(v));
    if lu == 0.0 || lv == 0.0 {
        return false;
    }
    let to2 = |p: [f64; 3]| {
        let d = sub(p, p0);
        [dot(d, u) / lu, dot(d, v) / lv]
    };
    let (a, b, c, d) = (to2(a), to2(b), to2(c), to2(d));
    let eps = 1e-12 * (lu + lv);
    let o1 = cross2(a, b, c);
    let o2 = cross2(a, b, d);
    let o3 = cross2(c, d, a);
    let o4 = cross2(c, d, b);
    (o1 > eps && o2 < -eps || o1 < -eps && o2 > eps)
        && (o3 > eps && o4 < -eps || o3 < -eps && o4 > eps)
}
