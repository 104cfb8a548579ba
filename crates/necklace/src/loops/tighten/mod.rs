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
//! Entry point: [`tighten`]; [`tighten_resumable`] also hands back a loop that stopped
//! below its length ratio as a [`Tightening`], which [`Tightening::resume`] carries on
//! under a smaller ratio to what a fresh run with that ratio gives. Submodules, along
//! the steps: `unfold` (step 1, and the funnel of step 2), `path` (step 2), `strip`
//! (step 3), `diagnostics` (the result).

mod diagnostics;
mod path;
mod strip;
mod unfold;

use serde::{Deserialize, Serialize};

use super::cut::{closed_length, Crossing};
use crate::geom::{dot, lerp, norm, sub};
use crate::mesh::{SurfaceMesh, Topology};
use diagnostics::finish;
use path::shortest_closed_path;
use strip::vertex_updates;

/// A new path may be longer than the last by this fraction (rounding) before the
/// tightening stops and keeps the last one.
const GROWTH_TOLERANCE: f64 = 1e-12;

/// A strip that grows beyond this many times the loop's first crossings (plus
/// [`STRIP_GROWTH_SLACK`]) is sliding round the surface, not settling.
const MAX_STRIP_GROWTH: usize = 20;

/// See [`MAX_STRIP_GROWTH`].
const STRIP_GROWTH_SLACK: usize = 1000;

/// Options of [`tighten`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

    /// The same, with the total angles already computed (`total_angles` of an earlier
    /// one on the same mesh).
    pub fn with_angles(
        mesh: &'a SurfaceMesh,
        topology: &'a Topology,
        total_angle: Vec<f64>,
    ) -> Self {
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
    tighten_resumable(geometry, crossings, faces, options).0
}

/// [`tighten`], and where the loop stopped only because it fell below
/// [`TightenOptions::min_length_ratio`] of its start, the tightening at that point, which
/// [`Tightening::resume`] carries on under a smaller ratio (to the result a fresh
/// [`tighten`] with that ratio gives, bit for bit).
pub fn tighten_resumable(
    geometry: &SurfaceGeometry,
    crossings: &[Crossing],
    faces: &[u32],
    options: &TightenOptions,
) -> (Tightened, Option<Tightening>) {
    let initial_points: Vec<[f64; 3]> = crossings
        .iter()
        .map(|c| {
            let [a, b] = geometry.edge(c.edge);
            lerp(geometry.pos(a), geometry.pos(b), c.t)
        })
        .collect();
    let initial_length = closed_length(&initial_points);
    let tightening = Tightening {
        strip: Strip {
            portals: crossings.iter().map(|c| c.edge).collect(),
            faces: faces.to_vec(),
            hint: crossings.iter().map(|c| c.t).collect(),
        },
        path: None,
        previous: None,
        rounds: 0,
        updates: 0,
        decrease: f64::INFINITY,
        initial_points,
        initial_length,
        first_crossings: crossings.len(),
        below_ratio: None,
    };
    tightening.run(geometry, options, false)
}

/// A tightening in progress: the strip, the last path in it and the counts. Held between
/// [`tighten_resumable`] and [`Tightening::resume`] when the loop fell below the length
/// ratio asked for, at the point of that test.
#[derive(Debug, Clone)]
pub struct Tightening {
    strip: Strip,
    path: Option<StripPath>,
    /// The strip before the last update (the last path lies in it).
    previous: Option<Strip>,
    rounds: usize,
    updates: usize,
    /// The length the last round took off.
    decrease: f64,
    initial_points: Vec<[f64; 3]>,
    initial_length: f64,
    first_crossings: usize,
    /// The ratio the loop fell below, where it stopped for that.
    below_ratio: Option<f64>,
}

impl Tightening {
    /// Carry on a tightening that stopped below `min_length_ratio` of its start, under
    /// `options` (which must differ from the first ones in that ratio alone). The result
    /// is [`tighten`]'s with `options` where their ratio is below the one it stopped at;
    /// `None` where it is not (a fresh run may stop earlier).
    pub fn resume(
        mut self,
        geometry: &SurfaceGeometry,
        options: &TightenOptions,
    ) -> Option<(Tightened, Option<Tightening>)> {
        let stopped_at = self.below_ratio.take()?;
        (options.min_length_ratio < stopped_at).then(|| self.run(geometry, options, true))
    }

    /// The bytes it holds (its strips, path and start).
    pub fn bytes(&self) -> usize {
        let strip = |s: &Strip| {
            s.portals.len() * size_of::<u32>()
                + s.faces.len() * size_of::<u32>()
                + s.hint.len() * size_of::<f64>()
        };
        strip(&self.strip)
            + self.previous.as_ref().map_or(0, strip)
            + self
                .path
                .as_ref()
                .map_or(0, |p| p.crossings.len() * size_of::<PortalCrossing>())
            + self.initial_points.len() * size_of::<[f64; 3]>()
    }

    /// The strip the number of portals grows past when it slides round the surface.
    fn growth_limit(&self) -> usize {
        MAX_STRIP_GROWTH * self.first_crossings + STRIP_GROWTH_SLACK
    }

    /// Rounds until the loop ends, from the round's start, or (resuming) from just after
    /// the length ratio's test.
    fn run(
        mut self,
        geometry: &SurfaceGeometry,
        options: &TightenOptions,
        mut resuming: bool,
    ) -> (Tightened, Option<Tightening>) {
        let mut status = TightenStatus::NotConverged;
        loop {
            if !resuming {
                if self.rounds >= options.max_rounds {
                    break;
                }
                match self.measure(geometry, options) {
                    Measured::Continue => {}
                    Measured::End(s) => {
                        status = s;
                        break;
                    }
                    Measured::BelowRatio => {
                        self.below_ratio = Some(options.min_length_ratio);
                        let result = self.result(geometry, TightenStatus::Collapsed);
                        return (result, Some(self));
                    }
                }
            }
            resuming = false;
            if let Some(s) = self.update(geometry, options) {
                status = s;
                break;
            }
        }
        (self.result(geometry, status), None)
    }

    /// The first half of a round: the shortest path in the strip and the tests on its
    /// length.
    fn measure(&mut self, geometry: &SurfaceGeometry, options: &TightenOptions) -> Measured {
        self.rounds += 1;
        let Some(p) = shortest_closed_path(geometry, &mut self.strip) else {
            return Measured::End(TightenStatus::InvalidStrip);
        };
        // Each update keeps the last path inside the strip, so the length cannot grow;
        // should rounding ever make it, keep the last loop rather than a longer one.
        if let (Some(last), Some(prev)) = (&self.path, &self.previous) {
            if p.length > last.length * (1.0 + GROWTH_TOLERANCE) {
                self.strip = prev.clone();
                return Measured::End(TightenStatus::Stalled);
            }
        }
        self.decrease = self
            .path
            .as_ref()
            .map_or(f64::INFINITY, |l| l.length - p.length);
        let length = p.length;
        let shrunk_to_vertex = p.crossings.iter().all(|c| c.vertex.is_some())
            && p.crossings
                .iter()
                .all(|c| c.vertex == p.crossings[0].vertex);
        self.path = Some(p);
        if shrunk_to_vertex {
            return Measured::End(TightenStatus::Collapsed);
        }
        if length < options.min_length_ratio * self.initial_length {
            return Measured::BelowRatio;
        }
        Measured::Continue
    }

    /// The second half of a round: the strip update where the path wants the other side
    /// of a vertex; the status where the loop ends here.
    fn update(
        &mut self,
        geometry: &SurfaceGeometry,
        options: &TightenOptions,
    ) -> Option<TightenStatus> {
        let p = self.path.as_ref().expect("measured before the update");
        let length = p.length;
        let wanted = vertex_updates(geometry, &self.strip, p, options.angle_tolerance);
        if wanted.is_empty() {
            return Some(TightenStatus::Converged);
        }
        // The strip goes all the way around a vertex that the loop wants to pass on
        // its other side: the loop contracts over that vertex.
        let strip = &self.strip;
        let n = strip.portals.len();
        if wanted
            .iter()
            .any(|r| strip.faces[(r.first + n - 1) % n] == strip.faces[(r.first + r.len - 1) % n])
        {
            return Some(TightenStatus::Collapsed);
        }
        if self.decrease <= options.rel_tolerance * length {
            return Some(TightenStatus::Stalled);
        }
        self.previous = Some(self.strip.clone());
        match self.strip.apply(geometry, p, &wanted) {
            Some(0) => return Some(TightenStatus::Stalled),
            Some(n) => self.updates += n,
            None => {
                // Keep the strip the last path lies in.
                if let Some(prev) = &self.previous {
                    self.strip = prev.clone();
                }
                return Some(TightenStatus::InvalidStrip);
            }
        }
        // A strip that keeps growing is sliding around the surface, not settling. The
        // last path lies in the strip before this round's update: report on that one.
        if self.strip.portals.len() > self.growth_limit() {
            if let Some(prev) = &self.previous {
                self.strip = prev.clone();
            }
            return Some(TightenStatus::NotConverged);
        }
        None
    }

    /// The tightened loop as it stands, with `status`.
    fn result(&self, geometry: &SurfaceGeometry, status: TightenStatus) -> Tightened {
        // The path must lie in the strip reported on (one crossing per portal).
        let path = self
            .path
            .as_ref()
            .filter(|p| p.crossings.len() == self.strip.portals.len());
        let status = if path.is_none() && status != TightenStatus::NotConverged {
            TightenStatus::InvalidStrip
        } else {
            status
        };
        let Some(path) = path else {
            return Tightened {
                surface_points: Vec::new(),
                points: self.initial_points.clone(),
                length: self.initial_length,
                initial_length: self.initial_length,
                rounds: self.rounds,
                updates: self.updates,
                status,
                max_edge_turn: f64::NAN,
                min_vertex_angle: f64::NAN,
                simple: false,
            };
        };
        finish(
            geometry,
            &self.strip,
            path,
            self.initial_length,
            self.rounds,
            self.updates,
            status,
        )
    }
}

/// How the first half of a round ended.
enum Measured {
    Continue,
    End(TightenStatus),
    /// Shorter than the ratio asked for: collapsed, unless a smaller ratio carries on.
    BelowRatio,
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
