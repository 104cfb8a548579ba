//! The surface near a loop refined until its edges there are short against the loop
//! ([`refine_near`]), so that a band a small fraction of the loop's radius wide can be
//! cut on a coarse mesh (a boot's eyelet is crossed by a handful of edges).

use std::collections::{BTreeMap, HashMap};

use super::band::{common_face, OnSurface, SNAP};
use crate::error::Result;
use crate::geom::{add, closest_on_segment, cross, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// A surface refined near a curve, and the curve on it.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The surface: the input's vertices first, with their indices, then the edges'
    /// midpoints; each triangle split in place (the same plane, the same orientation).
    pub mesh: SurfaceMesh,
    /// The curve on `mesh`: the input curve's points and its crossings with the new
    /// edges, consecutive points on a common triangle.
    pub curve: Vec<OnSurface>,
    /// Edges split.
    pub splits: usize,
}

/// Most rounds of splitting: each halves the edges it splits.
const MAX_ROUNDS: usize = 10;

/// Split every edge of `surface` longer than `max_edge` that comes within `reach` of
/// the closed curve `curve` (consecutive points on a common triangle), in rounds until
/// none is left (at most 10 rounds, each halving the edges).
///
/// 1. A round marks the edges to split and splits each triangle by how many of its
///    edges are marked: in 2 (one marked), 3 (two) or 4 (three, the midpoint
///    triangle), so the mesh stays conforming.
/// 2. The curve is carried over: its points onto the halves of their split edges, and
///    each of its segments crosses the new edges inside the triangle that held it;
///    those crossings are inserted in order.
pub fn refine_near(
    surface: &SurfaceMesh,
    topology: &Topology,
    curve: &[OnSurface],
    max_edge: f64,
    reach: f64,
) -> Result<Refined> {
    let points: Vec<[f64; 3]> = curve.iter().map(|p| p.position(surface)).collect();
    let holders: Vec<u32> = (0..curve.len())
        .map(|k| common_face(topology, &curve[k], &curve[(k + 1) % curve.len()], k))
        .collect::<Result<_>>()?;
    // Only edges in the curve's box, grown by `reach`, can come near it.
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in &points {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i] - reach);
            hi[i] = hi[i].max(p[i] + reach);
        }
    }
    let near = |a: [f64; 3], b: [f64; 3]| {
        let in_box = (0..3).all(|i| a[i].max(b[i]) >= lo[i] && a[i].min(b[i]) <= hi[i]);
        in_box && polyline_distance(&points, a, b) <= reach
    };

    let mut positions = surface.positions.clone();
    let mut triangles = surface.triangles.clone();
    let mut parent: Vec<u32> = (0..triangles.len() as u32).collect();
    let mut midpoint: HashMap<[u32; 2], u32> = HashMap::new();
    for _ in 0..MAX_ROUNDS {
        // 1. The edges to split this round.
        let mut marked: BTreeMap<[u32; 2], u32> = BTreeMap::new();
        for t in &triangles {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let (pa, pb) = (positions[a as usize], positions[b as usize]);
                if norm(sub(pa, pb)) > max_edge && near(pa, pb) {
                    marked.insert([a.min(b), a.max(b)], u32::MAX);
                }
            }
        }
        if marked.is_empty() {
            break;
        }
        for (edge, mid) in marked.iter_mut() {
            *mid = positions.len() as u32;
            let (pa, pb) = (positions[edge[0] as usize], positions[edge[1] as usize]);
            positions.push(scale(add(pa, pb), 0.5));
            midpoint.insert(*edge, *mid);
        }
        let mut split = Vec::with_capacity(triangles.len());
        let mut split_parent = Vec::with_capacity(triangles.len());
        for (t, &p) in triangles.iter().zip(&parent) {
            for child in split_triangle(*t, &marked) {
                split.push(child);
                split_parent.push(p);
            }
        }
        triangles = split;
        parent = split_parent;
    }
    let splits = midpoint.len();
    let mesh = SurfaceMesh {
        positions,
        triangles,
    };
    if splits == 0 {
        return Ok(Refined {
            mesh,
            curve: curve.to_vec(),
            splits,
        });
    }

    // 2. The curve on the refined mesh.
    let mut edges_of: HashMap<u32, Vec<[u32; 2]>> = HashMap::new();
    for (t, &p) in mesh.triangles.iter().zip(&parent) {
        if surface.triangles[p as usize] != *t {
            let list = edges_of.entry(p).or_default();
            for i in 0..3 {
                let e = [t[i].min(t[(i + 1) % 3]), t[i].max(t[(i + 1) % 3])];
                if !list.contains(&e) {
                    list.push(e);
                }
            }
        }
    }
    let mut out: Vec<OnSurface> = Vec::new();
    let n = curve.len();
    for k in 0..n {
        push(&mut out, carried(curve[k], &midpoint));
        let Some(edges) = edges_of.get(&holders[k]) else {
            continue;
        };
        let corners = surface.corners(holders[k] as usize);
        let normal = cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]));
        let (p, q) = (points[k], points[(k + 1) % n]);
        let mut crossings: Vec<(f64, OnSurface)> = edges
            .iter()
            .filter_map(|&[a, b]| {
                let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                let (s, t) = intersection(p, q, pa, pb, normal)?;
                let point = if t < SNAP {
                    OnSurface::Vertex(a)
                } else if t > 1.0 - SNAP {
                    OnSurface::Vertex(b)
                } else {
                    OnSurface::Edge { edge: [a, b], t }
                };
                Some((s, point))
            })
            .collect();
        crossings.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (_, point) in crossings {
            push(&mut out, point);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    Ok(Refined {
        mesh,
        curve: out,
        splits,
    })
}

/// `point` unless it repeats the last one.
fn push(out: &mut Vec<OnSurface>, point: OnSurface) {
    if out.last() != Some(&point) {
        out.push(point);
    }
}

/// A point of the input on the refined mesh: on the half of each split edge it lies in.
fn carried(point: OnSurface, midpoint: &HashMap<[u32; 2], u32>) -> OnSurface {
    let OnSurface::Edge {
        edge: [mut a, mut b],
        mut t,
    } = point
    else {
        return point;
    };
    while let Some(&m) = midpoint.get(&[a.min(b), a.max(b)]) {
        if t <= 0.5 {
            (b, t) = (m, 2.0 * t);
        } else {
            (a, t) = (m, 2.0 * t - 1.0);
        }
    }
    if t < SNAP {
        OnSurface::Vertex(a)
    } else if t > 1.0 - SNAP {
        OnSurface::Vertex(b)
    } else {
        OnSurface::Edge { edge: [a, b], t }
    }
}

/// Where the segment `p`–`q` crosses the segment `a`–`b` in the plane with normal
/// `normal`: the parameters along each, strictly inside `p`–`q` and within `a`–`b`.
fn intersection(
    p: [f64; 3],
    q: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    normal: [f64; 3],
) -> Option<(f64, f64)> {
    let (d, e, w) = (sub(q, p), sub(b, a), sub(a, p));
    let denominator = dot(cross(d, e), normal);
    if denominator.abs() <= 1e-12 * norm(d) * norm(e) * norm(normal) {
        return None;
    }
    let s = dot(cross(w, e), normal) / denominator;
    let t = dot(cross(w, d), normal) / denominator;
    (s > 1e-9 && s < 1.0 - 1e-9 && (-1e-9..=1.0 + 1e-9).contains(&t))
        .then_some((s, t.clamp(0.0, 1.0)))
}

/// The triangle `t` split at the midpoints of its marked edges (same orientation).
fn split_triangle(t: [u32; 3], marked: &BTreeMap<[u32; 2], u32>) -> Vec<[u32; 3]> {
    let mid = |i: usize| {
        let (a, b) = (t[i], t[(i + 1) % 3]);
        marked.get(&[a.min(b), a.max(b)]).copied()
    };
    let m = [mid(0), mid(1), mid(2)];
    match m.iter().filter(|x| x.is_some()).count() {
        0 => vec![t],
        1 => {
            // Rotate so that the split edge is t[r]–t[r + 1].
            let r = (0..3).find(|&i| m[i].is_some()).unwrap_or(0);
            let (a, b, c) = (t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
            let x = m[r].unwrap_or(a);
            vec![[a, x, c], [x, b, c]]
        }
        2 => {
            // Rotate so that the unsplit edge is t[r + 2]–t[r].
            let r = (0..3).find(|&i| m[(i + 2) % 3].is_none()).unwrap_or(0);
            let (a, b, c) = (t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
            let (x, y) = (m[r].unwrap_or(a), m[(r + 1) % 3].unwrap_or(b));
            vec![[x, b, y], [a, x, y], [a, y, c]]
        }
        _ => {
            let (x, y, z) = (
                m[0].unwrap_or(t[0]),
                m[1].unwrap_or(t[1]),
                m[2].unwrap_or(t[2]),
            );
            vec![[t[0], x, z], [x, t[1], y], [z, y, t[2]], [x, y, z]]
        }
    }
}

/// The distance between the segment `a`–`b` and the closed polyline (sampled at the
/// segment's ends and midpoint, against every polyline segment: enough for edges no
/// longer than a few times `reach`, as the rounds' are).
fn polyline_distance(points: &[[f64; 3]], a: [f64; 3], b: [f64; 3]) -> f64 {
    let n = points.len();
    let mid = scale(add(a, b), 0.5);
    let half = 0.5 * norm(sub(b, a));
    (0..n)
        .map(|k| {
            let (p, q) = (points[k], points[(k + 1) % n]);
            let d = [a, mid, b]
                .iter()
                .map(|&x| norm(sub(x, closest_on_segment(x, p, q))))
                .fold(f64::MAX, f64::min);
            // Between samples the segment may come closer, by at most half its length.
            (d - half).max(0.0)
        })
        .fold(f64::MAX, f64::min)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::mesh::MeshReport;

    /// A closed torus, `nu` × `nv` quads split in two, faces outward.
    fn torus(nu: usize, nv: usize) -> SurfaceMesh {
        let (big, small) = (1.0, 0.3);
        let mut positions = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let (u, v) = (
                    2.0 * PI * i as f64 / nu as f64,
                    2.0 * PI * j as f64 / nv as f64,
                );
                let ring = big + small * v.cos();
                positions.push([ring * u.cos(), ring * u.sin(), small * v.sin()]);
            }
        }
        let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
        let mut triangles = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        SurfaceMesh {
            positions,
            triangles,
        }
    }

    #[test]
    fn a_coarse_meridian_gets_short_edges_and_stays_a_curve_on_the_same_surface() {
        let (nu, nv) = (12, 6);
        let mesh = torus(nu, nv);
        let topology = Topology::new(&mesh);
        // Between meridians 0 and 1: the midpoints of the edges (i, j)–(i + 1, j) and of
        // the diagonals (i, j)–(i + 1, j + 1), alternately.
        let curve: Vec<OnSurface> = (0..nv)
            .flat_map(|j| {
                let v = |i: usize, j: usize| (i * nv + j % nv) as u32;
                [
                    OnSurface::Edge {
                        edge: [v(0, j), v(1, j)],
                        t: 0.5,
                    },
                    OnSurface::Edge {
                        edge: [v(0, j), v(1, j + 1)],
                        t: 0.5,
                    },
                ]
            })
            .collect();
        let length = |mesh: &SurfaceMesh, c: &[OnSurface]| {
            (0..c.len())
                .map(|k| {
                    norm(sub(
                        c[(k + 1) % c.len()].position(mesh),
                        c[k].position(mesh),
                    ))
                })
                .sum::<f64>()
        };
        let before = length(&mesh, &curve);
        let max_edge = 0.05;
        let refined = refine_near(&mesh, &topology, &curve, max_edge, 0.1).unwrap();
        assert!(refined.splits > 0);
        // The same closed surface: valid, same area and volume, the input's vertices
        // kept in place.
        let (a, b) = (MeshReport::new(&mesh), MeshReport::new(&refined.mesh));
        assert!(b.is_valid_solid(), "{:?}", b.problems());
        assert_eq!(b.genus, a.genus);
        assert!((refined.mesh.area() / mesh.area() - 1.0).abs() < 1e-12);
        assert!((refined.mesh.signed_volume() / mesh.signed_volume() - 1.0).abs() < 1e-12);
        assert_eq!(
            refined.mesh.positions[..mesh.positions.len()],
            mesh.positions[..]
        );
        // The curve: the same polyline (its length), consecutive points on a common
        // triangle of the refined mesh, whose edges near it are short.
        assert!((length(&refined.mesh, &refined.curve) / before - 1.0).abs() < 1e-9);
        let refined_topology = Topology::new(&refined.mesh);
        let n = refined.curve.len();
        for k in 0..n {
            common_face(
                &refined_topology,
                &refined.curve[k],
                &refined.curve[(k + 1) % n],
                k,
            )
            .unwrap();
        }
        for p in &refined.curve {
            if let OnSurface::Edge { edge: [a, b], .. } = *p {
                let l = norm(sub(
                    refined.mesh.positions[a as usize],
                    refined.mesh.positions[b as usize],
                ));
                assert!(l <= max_edge, "{l}");
            }
        }
    }
}
