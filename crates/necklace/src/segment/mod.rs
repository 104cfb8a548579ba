//! Segmentation of a surface along closed curves on it: what the neck loops are for
//! (the paper's sec. 1 names segmentation as their first use).
//!
//! Input: a surface and closed curves given as [`CurvePoint`]s — mesh vertices or points
//! on mesh edges, each consecutive pair on a common triangle (or a common edge), as the
//! loop stage's tightened loops are (`pipeline::segment_along_loops` passes the loops'
//! surface points). [`segment`] then:
//! 1. checks the curves against the mesh;
//! 2. inserts the curves as edges (submodule `arrangement`): every edge a curve crosses is split
//!    there (on both of its triangles), and every triangle a curve passes through is cut
//!    along its pieces — where curves cross inside a triangle, at their crossing — into
//!    convex regions, each triangulated round a point inside it;
//! 3. groups the refined triangles into segments: connected across every edge that is
//!    not on a curve;
//! 4. measures each segment *cut open* along the curves (a curve with the same segment
//!    on both sides, a handle's loop, is two boundaries of it): area, χ = V − E + F with
//!    the vertices on a cut counted once per side, boundary count, genus, the curves
//!    that bound it, and the volume of the solid it encloses once each boundary is
//!    closed by a fan from its centroid (divergence theorem; where a boundary cannot be
//!    traced as one cycle, `None`).
//!
//! The result, a [`Segmentation`]: the refined mesh, each face's segment, and each
//! [`Segment`] with its measures.
//!
//! Separating loops split the surface into parts; cycle-closing loops cut a handle open:
//! a torus cut along its handle loop is one segment, a cylinder (χ = 0, two boundaries).
//!
//! Conventions: the refined mesh keeps the input's vertices first (same indices) and
//! the orientation of each input triangle; volumes are positive for an outward-oriented
//! surface (if the whole surface's signed volume is negative, every volume is negated).
//! Segments are numbered by their first triangle in the refined mesh's order.

mod arrangement;

use std::collections::{BTreeSet, HashMap, HashSet};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geom::{add, cross, dot, scale, sub};
use crate::mesh::SurfaceMesh;
use arrangement::{refine, Refined};

/// A point of a curve on the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CurvePoint {
    /// At a mesh vertex.
    Vertex(u32),
    /// On the mesh edge `edge` at `(1 − t)·edge[0] + t·edge[1]`.
    Edge {
        /// The edge's vertices.
        edge: [u32; 2],
        /// Parameter from `edge[0]`, in `[0, 1]`.
        t: f64,
    },
}

/// One part of the segmented surface.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Its number (the `segment` of its triangles).
    pub id: usize,
    /// Triangles of the refined mesh in it.
    pub triangles: usize,
    /// Its area.
    pub area: f64,
    /// The volume it encloses with each boundary closed by a fan (see the module doc);
    /// the whole solid's for a segment that is the solid cut open.
    pub volume: Option<f64>,
    /// Euler characteristic of the segment cut open along the curves.
    pub euler: i64,
    /// Boundary curves of the segment cut open (a curve with the segment on both sides
    /// counts twice).
    pub boundaries: usize,
    /// Genus, `(2 − χ − b) / 2`.
    pub genus: i64,
    /// The curves (their indices in the input) on its boundary.
    pub loops: Vec<usize>,
}

/// The surface with the curves inserted as edges, and its segments.
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// The refined surface: the input's vertices first, then the points on edges, then
    /// crossings and the points inside the cut triangles.
    pub mesh: SurfaceMesh,
    /// Segment of each triangle of `mesh`.
    pub segment_of: Vec<u32>,
    /// The input triangle each triangle of `mesh` lies in.
    pub parent: Vec<u32>,
    /// The segments, by `id`.
    pub segments: Vec<Segment>,
}

/// Cut `surface` along `curves` (closed; first point not repeated) and measure the parts
/// (see the module doc). Errors name the first curve point that is not on the mesh or
/// not on a triangle with the next one.
pub fn segment(surface: &SurfaceMesh, curves: &[Vec<CurvePoint>]) -> Result<Segmentation> {
    let input_edges = EdgeFaces::new(surface);
    let curves = check_curves(surface, &input_edges, curves)?;
    let Refined {
        mesh,
        parent,
        cut_edges,
    } = refine(surface, &input_edges, &curves)?;
    let edges = EdgeFaces::new(&mesh);
    let segment_of = group(&mesh, &edges, &cut_edges);
    let outward = surface.signed_volume() >= 0.0;
    let segments = measure(&mesh, &edges, &segment_of, &cut_edges, outward);
    Ok(Segmentation {
        mesh,
        segment_of,
        parent,
        segments,
    })
}

/// Each curve point as a vertex, or an edge point strictly inside its edge with the
/// edge's smaller vertex first; an error for a point off the mesh.
fn check_curves(
    surface: &SurfaceMesh,
    edges: &EdgeFaces,
    curves: &[Vec<CurvePoint>],
) -> Result<Vec<Vec<CurvePoint>>> {
    let n = surface.num_vertices() as u32;
    curves
        .iter()
        .enumerate()
        .map(|(i, curve)| {
            if curve.len() < 2 {
                return Err(Error::invalid_argument(format!(
                    "loop {i} has {} points: a closed curve needs at least 2",
                    curve.len()
                )));
            }
            curve
                .iter()
                .enumerate()
                .map(|(k, &p)| match p {
                    CurvePoint::Vertex(v) if v < n => Ok(p),
                    CurvePoint::Vertex(v) => Err(Error::invalid_argument(format!(
                        "loop {i}, point {k}: vertex {v} is not in the mesh ({n} vertices): are these the loops of another mesh?"
                    ))),
                    CurvePoint::Edge { edge, t } => {
                        if !edges.contains(sorted(edge)) {
                            return Err(Error::invalid_argument(format!(
                                "loop {i}, point {k}: {}–{} is not an edge of the mesh: are these the loops of another mesh?",
                                edge[0], edge[1]
                            )));
                        }
                        if !(0.0..=1.0).contains(&t) {
                            return Err(Error::invalid_argument(format!(
                                "loop {i}, point {k}: edge parameter {t} is not in [0, 1]"
                            )));
                        }
                        Ok(if t == 0.0 {
                            CurvePoint::Vertex(edge[0])
                        } else if t == 1.0 {
                            CurvePoint::Vertex(edge[1])
                        } else if edge[0] < edge[1] {
                            p
                        } else {
                            CurvePoint::Edge {
                                edge: [edge[1], edge[0]],
                                t: 1.0 - t,
                            }
                        })
                    }
                })
                .collect()
        })
        .collect()
}

fn sorted([a, b]: [u32; 2]) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// Segment of each triangle: components across edges that are not cut, numbered by
/// their first triangle.
fn group(
    mesh: &SurfaceMesh,
    edges: &EdgeFaces,
    cut_edges: &HashMap<[u32; 2], Vec<usize>>,
) -> Vec<u32> {
    let mut parent: Vec<usize> = (0..mesh.num_triangles()).collect();
    for (e, faces) in edges.runs() {
        if cut_edges.contains_key(&e) {
            continue;
        }
        for w in faces.windows(2) {
            crate::mesh::union(&mut parent, w[0].1 as usize, w[1].1 as usize);
        }
    }
    let mut id = HashMap::new();
    (0..mesh.num_triangles())
        .map(|f| {
            let root = crate::mesh::find(&mut parent, f);
            let next = id.len() as u32;
            *id.entry(root).or_insert(next)
        })
        .collect()
}

/// The triangles at each edge: every (edge, triangle) pair sorted by edge then triangle,
/// edges as sorted vertex pairs packed in a `u64`. One sort instead of a map of lists
/// (a dense surface has millions of edges).
pub(crate) struct EdgeFaces {
    pairs: Vec<(u64, u32)>,
}

impl EdgeFaces {
    pub(crate) fn new(mesh: &SurfaceMesh) -> EdgeFaces {
        use rayon::prelude::*;
        let mut pairs: Vec<(u64, u32)> = mesh
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| (0..3).map(move |k| (key(sorted([t[k], t[(k + 1) % 3]])), f as u32)))
            .collect();
        pairs.par_sort_unstable();
        EdgeFaces { pairs }
    }

    /// The triangles at `edge` (sorted), in triangle order; empty if it is no edge.
    pub(crate) fn faces(&self, edge: [u32; 2]) -> impl Iterator<Item = u32> + '_ {
        let k = key(edge);
        let start = self.pairs.partition_point(|p| p.0 < k);
        self.pairs[start..]
            .iter()
            .take_while(move |p| p.0 == k)
            .map(|p| p.1)
    }

    /// Whether `edge` (sorted) is an edge.
    pub(crate) fn contains(&self, edge: [u32; 2]) -> bool {
        self.faces(edge).next().is_some()
    }

    /// Each edge with its triangles, in edge order.
    fn runs(&self) -> impl Iterator<Item = ([u32; 2], &[(u64, u32)])> + '_ {
        self.pairs
            .chunk_by(|a, b| a.0 == b.0)
            .map(|run| ([(run[0].0 >> 32) as u32, run[0].0 as u32], run))
    }
}

fn key([a, b]: [u32; 2]) -> u64 {
    (u64::from(a) << 32) | u64::from(b)
}

/// Area, χ and boundaries of each segment cut open along the cut edges, its curves, and
/// its capped volume.
fn measure(
    mesh: &SurfaceMesh,
    edges: &EdgeFaces,
    segment_of: &[u32],
    cut_edges: &HashMap<[u32; 2], Vec<usize>>,
    outward: bool,
) -> Vec<Segment> {
    let count = segment_of
        .iter()
        .map(|&s| s as usize + 1)
        .max()
        .unwrap_or(0);
    // Corners (3f + k) joined across uncut edges within a segment: the vertex copies
    // of the segment cut open.
    let mut corner: Vec<usize> = (0..3 * mesh.num_triangles()).collect();
    let corner_of = |f: u32, v: u32| -> usize {
        let k = mesh.triangles[f as usize]
            .iter()
            .position(|&x| x == v)
            .unwrap_or(0);
        3 * f as usize + k
    };
    for (e, faces) in edges.runs() {
        if cut_edges.contains_key(&e) {
            continue;
        }
        for w in faces.windows(2) {
            let (f, g) = (w[0].1, w[1].1);
            if segment_of[f as usize] == segment_of[g as usize] {
                for v in e {
                    crate::mesh::union(&mut corner, corner_of(f, v), corner_of(g, v));
                }
            }
        }
    }
    let roots: Vec<u32> = (0..corner.len())
        .map(|c| crate::mesh::find(&mut corner, c) as u32)
        .collect();

    let mut segments: Vec<Segment> = (0..count)
        .map(|id| Segment {
            id,
            triangles: 0,
            area: 0.0,
            volume: Some(0.0),
            euler: 0,
            boundaries: 0,
            genus: 0,
            loops: Vec::new(),
        })
        .collect();
    // Edges with one triangle (an open input's boundary).
    let open_edges: HashSet<[u32; 2]> = edges
        .runs()
        .filter(|(_, faces)| faces.len() == 1)
        .map(|(e, _)| e)
        .collect();
    // Vertex copies: one per class of corners, counted at its root.
    let mut copies = vec![0i64; count];
    let mut half_edges = vec![0i64; count];
    let mut boundary_half_edges = vec![0i64; count];
    // Boundary half-edges (a → b in triangle f) by the vertex copy they start from.
    let mut boundary_from: Vec<HashMap<u32, (u32, u32)>> = vec![HashMap::new(); count];
    let mut traceable = vec![true; count];
    // Volumes are taken about a point of the mesh, not the origin: a closed surface's is
    // the same about any point, and far from the origin the products would cancel.
    let origin = mesh.positions.first().copied().unwrap_or([0.0; 3]);
    for (f, t) in mesh.triangles.iter().enumerate() {
        let s = segment_of[f] as usize;
        let seg = &mut segments[s];
        seg.triangles += 1;
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        seg.area += 0.5 * crate::geom::norm(cross(sub(b, a), sub(c, a)));
        if let Some(v) = &mut seg.volume {
            let (a, b, c) = (sub(a, origin), sub(b, origin), sub(c, origin));
            *v += dot(a, cross(b, c)) / 6.0;
        }
        for k in 0..3 {
            if roots[3 * f + k] as usize == 3 * f + k {
                copies[s] += 1;
            }
            half_edges[s] += 1;
            let (from, to) = (t[k], t[(k + 1) % 3]);
            let e = sorted([from, to]);
            let cut = cut_edges.get(&e);
            let open = open_edges.contains(&e);
            if cut.is_some() || open {
                boundary_half_edges[s] += 1;
                if let Some(curves) = cut {
                    seg.loops.extend(curves.iter().copied());
                }
                let start = roots[3 * f + k];
                let end = roots[corner_of(f as u32, to)];
                if boundary_from[s].insert(start, (to, end)).is_some() {
                    traceable[s] = false;
                }
            }
        }
    }
    for (s, seg) in segments.iter_mut().enumerate() {
        seg.loops.sort_unstable();
        seg.loops.dedup();
        // Uncut edges are shared by two half-edges of the segment, cut ones are not.
        let edge_count = (half_edges[s] - boundary_half_edges[s]) / 2 + boundary_half_edges[s];
        seg.euler = copies[s] - edge_count + seg.triangles as i64;
        let (cycles, caps) = trace_boundaries(mesh, origin, &boundary_from[s]);
        seg.boundaries = cycles;
        seg.genus = (2 - seg.euler - cycles as i64) / 2;
        seg.volume = match (seg.volume, caps) {
            (Some(v), Some(caps)) if traceable[s] => {
                let v = v + caps;
                Some(if outward { v } else { -v })
            }
            _ => None,
        };
    }
    segments
}

/// The boundary cycles of a segment from its boundary half-edges (keyed by the vertex
/// copy they start from, giving the vertex and copy they end at): how many, and the
/// volume their centroid fans add about `origin` (`None` where a cycle does not close).
fn trace_boundaries(
    mesh: &SurfaceMesh,
    origin: [f64; 3],
    from: &HashMap<u32, (u32, u32)>,
) -> (usize, Option<f64>) {
    let mut starts: Vec<u32> = from.keys().copied().collect();
    starts.sort_unstable();
    let mut done: BTreeSet<u32> = BTreeSet::new();
    let mut cycles = 0;
    let mut caps = Some(0.0);
    for &start in &starts {
        if done.contains(&start) {
            continue;
        }
        // Walk the cycle, collecting its vertices in half-edge order.
        let mut vertices = Vec::new();
        let mut at = start;
        let closed = loop {
            if !done.insert(at) {
                break at == start;
            }
            let Some(&(to, end)) = from.get(&at) else {
                break false;
            };
            vertices.push(to);
            at = end;
        };
        cycles += 1;
        if !closed {
            caps = None;
            continue;
        }
        // Fan from the centroid, against the cycle's direction (the segment's faces
        // run along it): triangles (c, next, this).
        let points: Vec<[f64; 3]> = vertices
            .iter()
            .map(|&v| mesh.positions[v as usize])
            .collect();
        let centroid = scale(
            points.iter().fold([0.0; 3], |acc, &p| add(acc, p)),
            1.0 / points.len().max(1) as f64,
        );
        if let Some(total) = &mut caps {
            for i in 0..points.len() {
                let (p, q) = (points[i], points[(i + 1) % points.len()]);
                let (c, p, q) = (sub(centroid, origin), sub(p, origin), sub(q, origin));
                *total += dot(c, cross(q, p)) / 6.0;
            }
        }
    }
    (cycles, caps)
}

#[cfg(test)]
mod tests;
