//! The two curves that bound the band a cut removes around a loop ([`offset_curves`]).

use std::collections::{BTreeMap, HashMap, VecDeque};

use crate::error::{Error, Result};
use crate::geom::{add, closest_on_segment, cross, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// A point on a surface: a vertex, or a point on an edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OnSurface {
    /// At a mesh vertex.
    Vertex(u32),
    /// On the edge `edge` at `(1 − t)·edge[0] + t·edge[1]`.
    Edge {
        /// The edge's vertices.
        edge: [u32; 2],
        /// Parameter from `edge[0]`, in `[0, 1]`.
        t: f64,
    },
}

impl OnSurface {
    /// The point's position on `surface`.
    pub fn position(&self, surface: &SurfaceMesh) -> [f64; 3] {
        match *self {
            OnSurface::Vertex(v) => surface.positions[v as usize],
            OnSurface::Edge { edge: [a, b], t } => {
                let (p, q) = (surface.positions[a as usize], surface.positions[b as usize]);
                add(p, scale(sub(q, p), t))
            }
        }
    }
}

/// A crossing parameter this close to an end of its edge is that end's vertex.
pub(super) const SNAP: f64 = 1e-6;

/// Faces reached from the curve's own faces are in the band's region while one of their
/// corners lies within this many `delta` of the curve.
const REACH: f64 = 1.5;

/// The curves at signed distance `+delta` and `−delta` from a closed curve on the
/// surface, and the faces searched for them.
#[derive(Debug, Clone, PartialEq)]
pub struct Offsets {
    /// `[+delta, −delta]`: each closed (its last point joins its first), consecutive
    /// points on a common face.
    pub curves: [Vec<OnSurface>; 2],
    /// Faces reached from the curve (the band lies in them).
    pub region: Vec<u32>,
    /// The distance.
    pub delta: f64,
}

/// The curves at distance `delta` on either side of the closed curve `curve` (points on
/// `surface`, consecutive ones on a common face), through the surface.
///
/// 1. Each segment of the curve gets the face holding both its ends; its *side*
///    direction is that face's normal × the segment's direction.
/// 2. Region: faces reached across edges from the faces at the curve's points while one of their
///    corners lies within 1.5 `delta` of the curve (so another sheet across a thin
///    gap is never reached).
/// 3. At each region vertex, the signed distance to the curve: the distance to its
///    closest point, signed by the side direction of the segment holding that point.
/// 4. Marching triangles at `+delta` and `−delta` over the region; the crossings are
///    chained across shared edges, and the longest closed chain of each sign is its
///    curve (small rings round bumps are dropped). A sign with no closed chain at least
///    half as long as the curve is an error: the region ends before the distance is
///    reached, or the band reaches round a thin part.
pub fn offset_curves(
    surface: &SurfaceMesh,
    topology: &Topology,
    curve: &[OnSurface],
    delta: f64,
) -> Result<Offsets> {
    if curve.len() < 3 || !(delta > 0.0 && delta.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "offset curves need a closed curve of at least 3 points and a positive distance (got {} points, {delta})",
            curve.len()
        )));
    }
    let curve = &snapped(curve);
    if curve.len() < 3 {
        return Err(Error::invalid_argument(format!(
            "offset curves need a closed curve of at least 3 distinct points (got {})",
            curve.len()
        )));
    }
    let points: Vec<[f64; 3]> = curve.iter().map(|p| p.position(surface)).collect();
    let segments = segment_sides(surface, topology, curve, &points)?;
    let seeds: Vec<u32> = curve.iter().flat_map(|p| faces_at(topology, p)).collect();
    let (region, signed) = region(surface, topology, &seeds, &points, &segments, delta);
    // A chain under half the curve's length is a ring round a bump, not the band's side.
    let n = points.len();
    let length: f64 = (0..n)
        .map(|k| norm(sub(points[(k + 1) % n], points[k])))
        .sum();
    let mut curves = [Vec::new(), Vec::new()];
    for (k, level) in [delta, -delta].into_iter().enumerate() {
        curves[k] = longest_isoline(surface, &region, &signed, level, 0.5 * length).ok_or_else(|| {
            Error::invalid_argument(format!(
                "no closed curve at distance {level:.3e} from the loop: the surface ends, or the loop's band reaches past a neighbouring part"
            ))
        })?;
    }
    Ok(Offsets {
        curves,
        region,
        delta,
    })
}

/// The faces a surface point lies on.
fn faces_at(topology: &Topology, p: &OnSurface) -> Vec<u32> {
    match *p {
        OnSurface::Vertex(v) => topology.vertex_faces(v as usize).to_vec(),
        OnSurface::Edge { edge: [a, b], .. } => topology
            .vertex_edges(a as usize)
            .iter()
            .find(|&&e| {
                let [x, y] = topology.edges()[e as usize];
                [x, y] == [a.min(b), a.max(b)]
            })
            .map_or_else(Vec::new, |&e| topology.edge_faces(e as usize).to_vec()),
    }
}

/// `curve` with each point within [`SNAP`] of an end of its edge on that vertex, and
/// repeated points merged (a loop tightened along a crease runs along its edges,
/// crossing each a hair from its ends).
fn snapped(curve: &[OnSurface]) -> Vec<OnSurface> {
    let mut out: Vec<OnSurface> = Vec::with_capacity(curve.len());
    for &p in curve {
        let p = match p {
            OnSurface::Edge { edge: [a, _], t } if t < SNAP => OnSurface::Vertex(a),
            OnSurface::Edge { edge: [_, b], t } if t > 1.0 - SNAP => OnSurface::Vertex(b),
            p => p,
        };
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

/// The mesh edge both points lie on, if any.
fn common_edge(topology: &Topology, p: &OnSurface, q: &OnSurface) -> Option<usize> {
    let edge = |a: u32, b: u32| {
        topology
            .vertex_edges(a as usize)
            .iter()
            .map(|&e| e as usize)
            .find(|&e| topology.edges()[e] == [a.min(b), a.max(b)])
    };
    match (*p, *q) {
        (OnSurface::Vertex(a), OnSurface::Vertex(b)) => edge(a, b),
        (OnSurface::Vertex(v), OnSurface::Edge { edge: [a, b], .. })
        | (OnSurface::Edge { edge: [a, b], .. }, OnSurface::Vertex(v))
            if v == a || v == b =>
        {
            edge(a, b)
        }
        (OnSurface::Edge { edge: e, .. }, OnSurface::Edge { edge: f, .. })
            if [e[0].min(e[1]), e[0].max(e[1])] == [f[0].min(f[1]), f[0].max(f[1])] =>
        {
            edge(e[0], e[1])
        }
        _ => None,
    }
}

/// Per segment `k` (point `k` to `k + 1`): its side direction (unit face normal ×
/// segment direction; for a segment along an edge, the sum of its faces' unit normals ×
/// the direction, which points into the left face and away from the right one even
/// where the edge is a crease), or an error when the two points share no face.
fn segment_sides(
    surface: &SurfaceMesh,
    topology: &Topology,
    curve: &[OnSurface],
    points: &[[f64; 3]],
) -> Result<Vec<[f64; 3]>> {
    let n = curve.len();
    (0..n)
        .map(|k| {
            let (p, q) = (&curve[k], &curve[(k + 1) % n]);
            let unit_normal = |f: u32| {
                let c = surface.corners(f as usize);
                let normal = cross(sub(c[1], c[0]), sub(c[2], c[0]));
                let length = norm(normal);
                if length > 0.0 {
                    scale(normal, 1.0 / length)
                } else {
                    [0.0; 3]
                }
            };
            let normal = match common_edge(topology, p, q) {
                Some(e) => topology
                    .edge_faces(e)
                    .iter()
                    .fold([0.0; 3], |sum, &f| add(sum, unit_normal(f))),
                None => unit_normal(common_face(topology, p, q, k)?),
            };
            let side = cross(normal, sub(points[(k + 1) % n], points[k]));
            let length = norm(side);
            Ok(if length > 0.0 {
                scale(side, 1.0 / length)
            } else {
                [0.0; 3]
            })
        })
        .collect()
}

/// A triangle holding both `p` and `q` (points `k` and `k + 1` of a loop), or an error.
pub(super) fn common_face(
    topology: &Topology,
    p: &OnSurface,
    q: &OnSurface,
    k: usize,
) -> Result<u32> {
    let next = faces_at(topology, q);
    faces_at(topology, p)
        .into_iter()
        .find(|f| next.contains(f))
        .ok_or_else(|| {
            Error::invalid_argument(format!(
                "point {k} of the loop and the next share no triangle"
            ))
        })
}

/// The closest point of the closed polyline to `p`: its distance and segment.
fn closest(points: &[[f64; 3]], p: [f64; 3]) -> (f64, usize, [f64; 3]) {
    let n = points.len();
    (0..n)
        .map(|k| {
            let q = closest_on_segment(p, points[k], points[(k + 1) % n]);
            (norm(sub(p, q)), k, q)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .expect("at least 3 points")
}

/// Steps 2 and 3: the region's faces (sorted) and the signed distance at its vertices.
fn region(
    surface: &SurfaceMesh,
    topology: &Topology,
    seeds: &[u32],
    points: &[[f64; 3]],
    sides: &[[f64; 3]],
    delta: f64,
) -> (Vec<u32>, HashMap<u32, f64>) {
    let mut signed: HashMap<u32, f64> = HashMap::new();
    let mut value = |v: u32| -> f64 {
        *signed.entry(v).or_insert_with(|| {
            let p = surface.positions[v as usize];
            let (d, k, q) = closest(points, p);
            let n = points.len();
            // At a corner of the polyline, both segments' sides count.
            let side = if norm(sub(q, points[(k + 1) % n])) == 0.0 {
                add(sides[k], sides[(k + 1) % n])
            } else if norm(sub(q, points[k])) == 0.0 {
                add(sides[k], sides[(k + n - 1) % n])
            } else {
                sides[k]
            };
            if dot(sub(p, q), side) < 0.0 {
                -d
            } else {
                d
            }
        })
    };
    let mut inside = vec![false; surface.triangles.len()];
    let mut queue: VecDeque<u32> = VecDeque::new();
    for &f in seeds {
        if !inside[f as usize] {
            inside[f as usize] = true;
            queue.push_back(f);
        }
    }
    while let Some(f) = queue.pop_front() {
        for side in 0..3 {
            let Some((g, _)) = topology.across(f as usize, side) else {
                continue;
            };
            if inside[g] {
                continue;
            }
            let near = surface.triangles[g]
                .iter()
                .any(|&v| value(v).abs() <= REACH * delta);
            if near {
                inside[g] = true;
                queue.push_back(g as u32);
            }
        }
    }
    let faces: Vec<u32> = (0..surface.triangles.len() as u32)
        .filter(|&f| inside[f as usize])
        .collect();
    for &f in &faces {
        for &v in &surface.triangles[f as usize] {
            value(v);
        }
    }
    (faces, signed)
}

/// Step 4: the longest closed isoline at `level` over the region's faces, if it is at
/// least `min_length` long.
fn longest_isoline(
    surface: &SurfaceMesh,
    region: &[u32],
    signed: &HashMap<u32, f64>,
    level: f64,
    min_length: f64,
) -> Option<Vec<OnSurface>> {
    // One crossing per edge, found from either of its faces alike.
    let mut crossing: BTreeMap<[u32; 2], usize> = BTreeMap::new();
    let mut points: Vec<([u32; 2], f64)> = Vec::new();
    let mut links: Vec<Vec<usize>> = Vec::new();
    for &f in region {
        let t = surface.triangles[f as usize];
        let above = t.map(|v| signed[&v] >= level);
        let mut ends = Vec::new();
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            if above[i] == above[(i + 1) % 3] {
                continue;
            }
            let edge = [a.min(b), a.max(b)];
            let id = *crossing.entry(edge).or_insert_with(|| {
                let (fa, fb) = (signed[&edge[0]], signed[&edge[1]]);
                points.push((edge, (level - fa) / (fb - fa)));
                links.push(Vec::new());
                points.len() - 1
            });
            ends.push(id);
        }
        if let [p, q] = ends[..] {
            links[p].push(q);
            links[q].push(p);
        }
    }
    // Chains: a closed one has every point linked twice.
    let mut seen = vec![false; points.len()];
    let mut best: Option<(f64, Vec<usize>)> = None;
    for start in 0..points.len() {
        if seen[start] {
            continue;
        }
        let mut chain = vec![start];
        seen[start] = true;
        let mut closed = links[start].len() == 2;
        let (mut previous, mut current) = (usize::MAX, start);
        loop {
            let next = links[current]
                .iter()
                .copied()
                .find(|&x| x != previous && !seen[x]);
            match next {
                Some(x) => {
                    closed &= links[x].len() == 2;
                    seen[x] = true;
                    chain.push(x);
                    previous = current;
                    current = x;
                }
                None => {
                    closed &= links[current].contains(&start) && chain.len() > 2;
                    break;
                }
            }
        }
        if !closed {
            continue;
        }
        let position = |i: usize| {
            let ([a, b], t) = points[i];
            let (p, q) = (surface.positions[a as usize], surface.positions[b as usize]);
            add(p, scale(sub(q, p), t))
        };
        let length: f64 = (0..chain.len())
            .map(|i| {
                norm(sub(
                    position(chain[(i + 1) % chain.len()]),
                    position(chain[i]),
                ))
            })
            .sum();
        if best.as_ref().is_none_or(|(l, _)| length > *l) {
            best = Some((length, chain));
        }
    }
    let (_, chain) = best.filter(|(length, _)| *length >= min_length)?;
    let mut out: Vec<OnSurface> = Vec::with_capacity(chain.len());
    for i in chain {
        let (edge, t) = points[i];
        let p = if t < SNAP {
            OnSurface::Vertex(edge[0])
        } else if t > 1.0 - SNAP {
            OnSurface::Vertex(edge[1])
        } else {
            OnSurface::Edge { edge, t }
        };
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    /// An open tube of radius 1 round z, `nt` vertices round, rows at `z[j]`, faces
    /// outward.
    fn tube(nt: usize, z: &[f64]) -> SurfaceMesh {
        let mut positions = Vec::new();
        for &h in z {
            for i in 0..nt {
                let a = 2.0 * PI * i as f64 / nt as f64;
                positions.push([a.cos(), a.sin(), h]);
            }
        }
        let id = |i: usize, j: usize| (j * nt + i % nt) as u32;
        let mut triangles = Vec::new();
        for j in 0..z.len() - 1 {
            for i in 0..nt {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        SurfaceMesh {
            positions,
            triangles,
        }
    }

    fn rows() -> Vec<f64> {
        (0..=40).map(|j| -2.0 + 0.1 * j as f64).collect()
    }

    #[test]
    fn a_ring_of_vertices_on_a_tube_has_rings_at_plus_and_minus_delta() {
        let nt = 48;
        let mesh = tube(nt, &rows());
        let topology = Topology::new(&mesh);
        // The row at z = 0 (row 20), counter-clockwise seen from +z.
        let curve: Vec<OnSurface> = (0..nt)
            .map(|i| OnSurface::Vertex((20 * nt + i) as u32))
            .collect();
        let offsets = offset_curves(&mesh, &topology, &curve, 0.25).unwrap();
        for (k, z) in [(0, 0.25), (1, -0.25)] {
            let c = &offsets.curves[k];
            assert!(c.len() >= nt, "{}", c.len());
            for p in c {
                let q = p.position(&mesh);
                assert!((q[2] - z).abs() < 1e-9, "{q:?} not at z = {z}");
                assert!(((q[0] * q[0] + q[1] * q[1]).sqrt() - 1.0).abs() < 0.01);
            }
        }
    }

    /// The tube above z = 0 meets a flat annulus at a right-angled crease along row 20;
    /// the curve runs along the crease's edges a hair from their ends, each vertex
    /// passed twice (as a loop tightened along a CAD part's rim does). Its sides are the
    /// tube (`+delta`, at z = delta) and the annulus (`−delta`, at radius 1 + delta).
    #[test]
    fn a_curve_along_a_crease_has_its_offsets_on_the_two_faces_of_the_crease() {
        let nt = 40;
        let mut mesh = tube(nt, &rows());
        for j in 0..20 {
            for i in 0..nt {
                let a = 2.0 * PI * i as f64 / nt as f64;
                let r = 1.0 + 0.1 * (20 - j) as f64;
                mesh.positions[j * nt + i] = [r * a.cos(), r * a.sin(), 0.0];
            }
        }
        let topology = Topology::new(&mesh);
        let v = |i: usize| (20 * nt + i % nt) as u32;
        let curve: Vec<OnSurface> = (0..nt)
            .flat_map(|i| {
                [
                    OnSurface::Edge {
                        edge: [v(i), v(i + 1)],
                        t: 1e-7,
                    },
                    OnSurface::Edge {
                        edge: [v(i), v(i + 1)],
                        t: 1.0 - 3e-7,
                    },
                ]
            })
            .collect();
        let offsets = offset_curves(&mesh, &topology, &curve, 0.25).unwrap();
        for p in &offsets.curves[0] {
            let q = p.position(&mesh);
            let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
            assert!(
                (q[2] - 0.25).abs() < 1e-9 && (r - 1.0).abs() < 0.01,
                "{q:?}"
            );
        }
        for p in &offsets.curves[1] {
            let q = p.position(&mesh);
            let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
            assert!(q[2].abs() < 1e-9 && (r - 1.25).abs() < 0.01, "{q:?}");
        }
    }

    #[test]
    fn a_ring_between_rows_is_offset_from_where_it_is() {
        let nt = 32;
        let mesh = tube(nt, &rows());
        let topology = Topology::new(&mesh);
        // At z = 0.05, between rows 20 (z = 0) and 21 (z = 0.1): the midpoints of the
        // vertical edges and of the diagonals between them (consecutive points must
        // share a triangle).
        let v = |i: usize, j: usize| (j * nt + i % nt) as u32;
        let curve: Vec<OnSurface> = (0..nt)
            .flat_map(|i| {
                [
                    OnSurface::Edge {
                        edge: [v(i, 20), v(i, 21)],
                        t: 0.5,
                    },
                    OnSurface::Edge {
                        edge: [v(i, 20), v(i + 1, 21)],
                        t: 0.5,
                    },
                ]
            })
            .collect();
        let offsets = offset_curves(&mesh, &topology, &curve, 0.3).unwrap();
        for (k, z) in [(0, 0.35), (1, -0.25)] {
            for p in &offsets.curves[k] {
                let q = p.position(&mesh);
                assert!((q[2] - z).abs() < 1e-9, "{q:?} not at z = {z}");
            }
        }
        // The region holds the band and stops about REACH × delta out.
        assert!(
            offsets.region.len() < 2 * nt * 12,
            "{}",
            offsets.region.len()
        );
    }

    #[test]
    fn a_distance_past_the_end_of_the_tube_is_an_error_in_one_line() {
        let nt = 24;
        let mesh = tube(nt, &rows());
        let topology = Topology::new(&mesh);
        let curve: Vec<OnSurface> = (0..nt)
            .map(|i| OnSurface::Vertex((20 * nt + i) as u32))
            .collect();
        let err = offset_curves(&mesh, &topology, &curve, 3.0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("no closed curve at distance"), "{err}");
        assert!(!err.contains('\n'));
        // Points that share no triangle.
        let apart = [
            OnSurface::Vertex(0),
            OnSurface::Vertex(500),
            OnSurface::Vertex(900),
        ];
        assert!(offset_curves(&mesh, &topology, &apart, 0.1).is_err());
    }
}
