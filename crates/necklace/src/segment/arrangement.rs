//! The surface with curves inserted as edges (step 2 of [`segment`](super::segment)).
//!
//! A curve runs from point to point, each a mesh vertex or a point on a mesh edge. Two
//! consecutive points on one edge make a piece *along* that edge; otherwise the two lie
//! on a common triangle and the piece is a *chord* of it. Every point on an edge splits
//! that edge in both of its triangles, so the refined mesh stays conforming. Each
//! triangle with points on its sides or chords is cut along its chords — at their
//! crossings where two curves cross inside it — into regions; as chords are straight
//! lines across a triangle, every region is convex, and it is triangulated as a fan
//! round the mean of its corners (a fan from a corner would make flat triangles along a
//! side with points on it).
//!
//! Conventions: each triangle is worked in 2D coordinates of its own plane with its
//! first corner at the origin and its second on the +x axis, so counter-clockwise there
//! is the input triangle's orientation, and the refined triangles keep it. New vertices
//! are numbered after the input's: points on edges in the order the curves reach them,
//! then per triangle, in triangle order, crossings and fan centres.

use std::collections::{BTreeMap, HashMap};

use crate::error::{Error, Result};
use crate::geom::{add, cross, dot, lerp, norm, scale, sub};
use crate::mesh::SurfaceMesh;

use super::{sorted, CurvePoint, EdgeFaces};
use crate::mesh::Csr;

/// What [`refine`] returns.
pub(super) struct Refined {
    /// The surface with the curves as edges.
    pub mesh: SurfaceMesh,
    /// The input triangle of each triangle.
    pub parent: Vec<u32>,
    /// The edges on curves (sorted vertex pairs) and which curves run along each.
    pub cut_edges: HashMap<[u32; 2], Vec<usize>>,
}

/// A piece of a curve inside one triangle, between two points on its boundary.
struct Chord {
    ends: [u32; 2],
    curve: usize,
}

/// Insert the (checked) curves into `surface` (see the module doc).
pub(super) fn refine(
    surface: &SurfaceMesh,
    edges: &EdgeFaces,
    curves: &[Vec<CurvePoint>],
) -> Result<Refined> {
    let mut positions = surface.positions.clone();
    let faces_at_vertex = Csr::new(
        surface.num_vertices(),
        surface
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| t.iter().map(move |&v| (v, f as u32))),
    );

    // Points on edges: one vertex per (edge, t), in the order the curves reach them.
    let mut on_edge: BTreeMap<[u32; 2], Vec<(f64, u32)>> = BTreeMap::new();
    let mut edge_point: HashMap<([u32; 2], u64), u32> = HashMap::new();
    let mut vertex_of = |p: CurvePoint, positions: &mut Vec<[f64; 3]>| -> u32 {
        match p {
            CurvePoint::Vertex(v) => v,
            CurvePoint::Edge { edge, t } => {
                *edge_point.entry((edge, t.to_bits())).or_insert_with(|| {
                    let id = positions.len() as u32;
                    positions.push(lerp(
                        positions[edge[0] as usize],
                        positions[edge[1] as usize],
                        t,
                    ));
                    on_edge.entry(edge).or_default().push((t, id));
                    id
                })
            }
        }
    };
    let ids: Vec<Vec<u32>> = curves
        .iter()
        .map(|c| c.iter().map(|&p| vertex_of(p, &mut positions)).collect())
        .collect();
    for points in on_edge.values_mut() {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }

    // Pieces: along an edge (from t0 to t1 on it), or a chord of a triangle.
    let mut chords: BTreeMap<u32, Vec<Chord>> = BTreeMap::new();
    let mut cut_edges: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    for (i, curve) in curves.iter().enumerate() {
        let n = curve.len();
        for k in 0..n {
            let (p, q) = (curve[k], curve[(k + 1) % n]);
            let (a, b) = (ids[i][k], ids[i][(k + 1) % n]);
            if a == b {
                continue;
            }
            if let Some(edge) = common_edge(p, q, edges) {
                let (t0, t1) = (param_on(p, edge), param_on(q, edge));
                for piece in pieces_between(edge, &on_edge, t0.min(t1), t0.max(t1)) {
                    cut_edges.entry(piece).or_default().push(i);
                }
                continue;
            }
            let faces = |p: CurvePoint| -> Vec<u32> {
                match p {
                    CurvePoint::Vertex(v) => faces_at_vertex.get(v as usize).to_vec(),
                    CurvePoint::Edge { edge, .. } => edges.faces(edge).collect(),
                }
            };
            let (fp, fq) = (faces(p), faces(q));
            let Some(&f) = fp.iter().filter(|f| fq.contains(f)).min() else {
                return Err(Error::invalid_argument(format!(
                    "loop {i}: points {k} and {} are on no common triangle: a loop must cross the mesh from triangle to neighbouring triangle",
                    (k + 1) % n
                )));
            };
            chords.entry(f).or_default().push(Chord {
                ends: [a, b],
                curve: i,
            });
        }
    }

    // Cut every triangle with points on its sides or chords.
    let mut triangles = Vec::with_capacity(surface.num_triangles());
    let mut parent = Vec::with_capacity(surface.num_triangles());
    for (f, t) in surface.triangles.iter().enumerate() {
        let side_points = |k: usize| -> Vec<u32> {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            let edge = sorted([u, v]);
            let mut points: Vec<u32> = on_edge
                .get(&edge)
                .map(|ps| ps.iter().map(|&(_, id)| id).collect())
                .unwrap_or_default();
            if u != edge[0] {
                points.reverse();
            }
            points
        };
        let sides = [side_points(0), side_points(1), side_points(2)];
        let face_chords = chords.get(&(f as u32));
        if sides.iter().all(Vec::is_empty) && face_chords.is_none() {
            triangles.push(*t);
            parent.push(f as u32);
            continue;
        }
        let regions = cut_triangle(
            *t,
            &sides,
            face_chords.map_or(&[][..], Vec::as_slice),
            &mut positions,
            &mut cut_edges,
        );
        for tri in regions {
            triangles.push(tri);
            parent.push(f as u32);
        }
    }
    for curves in cut_edges.values_mut() {
        curves.sort_unstable();
        curves.dedup();
    }
    Ok(Refined {
        mesh: SurfaceMesh {
            positions,
            triangles,
        },
        parent,
        cut_edges,
    })
}

/// The mesh edge both points lie on (a vertex lies on the edges at it), if any.
fn common_edge(p: CurvePoint, q: CurvePoint, edges: &EdgeFaces) -> Option<[u32; 2]> {
    match (p, q) {
        (CurvePoint::Edge { edge: e, .. }, CurvePoint::Edge { edge, .. }) => {
            (e == edge).then_some(e)
        }
        (CurvePoint::Vertex(v), CurvePoint::Edge { edge, .. })
        | (CurvePoint::Edge { edge, .. }, CurvePoint::Vertex(v)) => {
            edge.contains(&v).then_some(edge)
        }
        (CurvePoint::Vertex(u), CurvePoint::Vertex(v)) => {
            let e = sorted([u, v]);
            edges.contains(e).then_some(e)
        }
    }
}

/// The parameter of a point on `edge` (sorted) from its first vertex.
fn param_on(p: CurvePoint, edge: [u32; 2]) -> f64 {
    match p {
        CurvePoint::Edge { t, .. } => t,
        CurvePoint::Vertex(v) if v == edge[0] => 0.0,
        CurvePoint::Vertex(_) => 1.0,
    }
}

/// The pieces of `edge`, split at its points, that lie between parameters `lo` and `hi`.
fn pieces_between(
    edge: [u32; 2],
    on_edge: &BTreeMap<[u32; 2], Vec<(f64, u32)>>,
    lo: f64,
    hi: f64,
) -> Vec<[u32; 2]> {
    let mut chain = vec![(0.0, edge[0])];
    chain.extend(on_edge.get(&edge).into_iter().flatten().copied());
    chain.push((1.0, edge[1]));
    chain
        .windows(2)
        .filter(|w| w[0].0 >= lo && w[1].0 <= hi)
        .map(|w| sorted([w[0].1, w[1].1]))
        .collect()
}

/// Triangles of triangle `t` cut along `chords`, with `sides[k]` the points on its side
/// from corner `k` to corner `k + 1` in that order. New vertices are appended to
/// `positions`; the chords' pieces are recorded in `cut_edges`.
fn cut_triangle(
    t: [u32; 3],
    sides: &[Vec<u32>; 3],
    chords: &[Chord],
    positions: &mut Vec<[f64; 3]>,
    cut_edges: &mut HashMap<[u32; 2], Vec<usize>>,
) -> Vec<[u32; 3]> {
    // The plane's frame: first corner at the origin, second on +x.
    let [p0, p1, p2] = t.map(|v| positions[v as usize]);
    let x_axis = sub(p1, p0);
    let length = norm(x_axis);
    let normal = cross(x_axis, sub(p2, p0));
    let y_axis = cross(normal, x_axis);
    let y_length = norm(y_axis);
    if !(length > 0.0 && y_length > 0.0) {
        // A flat triangle (no area to cut): a fan from its first corner over its sides'
        // points keeps the mesh conforming.
        let ring: Vec<u32> = (0..3)
            .flat_map(|k| std::iter::once(t[k]).chain(sides[k].iter().copied()))
            .collect();
        return (1..ring.len() - 1)
            .map(|i| [ring[0], ring[i], ring[i + 1]])
            .collect();
    }
    let to_2d = |p: [f64; 3]| -> [f64; 2] {
        let d = sub(p, p0);
        [dot(d, x_axis) / length, dot(d, y_axis) / y_length]
    };

    // Local vertices: the boundary in counter-clockwise order, then crossings.
    let mut global: Vec<u32> = Vec::new();
    for k in 0..3 {
        global.push(t[k]);
        global.extend(&sides[k]);
    }
    let boundary = global.len();
    let mut plane: Vec<[f64; 2]> = global
        .iter()
        .map(|&v| to_2d(positions[v as usize]))
        .collect();
    let local_of = |v: u32, global: &[u32]| global.iter().position(|&g| g == v);
    let mut edges: Vec<([usize; 2], Option<usize>)> = (0..boundary)
        .map(|i| ([i, (i + 1) % boundary], None))
        .collect();

    // Chords as local pairs, each with the crossings along it (parameter, vertex).
    let lines: Vec<([usize; 2], usize)> = chords
        .iter()
        .filter_map(|c| {
            let a = local_of(c.ends[0], &global)?;
            let b = local_of(c.ends[1], &global)?;
            Some(([a, b], c.curve))
        })
        .collect();
    let mut along: Vec<Vec<(f64, usize)>> = vec![Vec::new(); lines.len()];
    for i in 0..lines.len() {
        for j in i + 1..lines.len() {
            let ([a, b], _) = lines[i];
            let ([c, d], _) = lines[j];
            if a == c || a == d || b == c || b == d {
                continue;
            }
            let Some((s, u)) = crossing(plane[a], plane[b], plane[c], plane[d]) else {
                continue;
            };
            let id = global.len();
            let at = lerp(
                positions[global[a] as usize],
                positions[global[b] as usize],
                s,
            );
            global.push(positions.len() as u32);
            positions.push(at);
            plane.push(to_2d(at));
            along[i].push((s, id));
            along[j].push((u, id));
        }
    }
    for (i, &([a, b], curve)) in lines.iter().enumerate() {
        let mut chain = vec![(0.0, a)];
        along[i].sort_by(|x, y| x.0.total_cmp(&y.0));
        chain.extend(&along[i]);
        chain.push((1.0, b));
        for w in chain.windows(2) {
            edges.push(([w[0].1, w[1].1], Some(curve)));
            let key = sorted([global[w[0].1], global[w[1].1]]);
            cut_edges.entry(key).or_default().push(curve);
        }
    }

    // Regions: walk each directed edge with the region on its left, turning at every
    // vertex to the next edge clockwise from the one arrived by.
    let count = global.len();
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); count];
    for &([a, b], _) in &edges {
        if a != b && !around[a].contains(&b) {
            around[a].push(b);
            around[b].push(a);
        }
    }
    for (v, list) in around.iter_mut().enumerate() {
        let o = plane[v];
        list.sort_by(|&x, &y| angle(o, plane[x]).total_cmp(&angle(o, plane[y])));
    }
    let mut used: HashMap<(usize, usize), ()> = HashMap::new();
    let mut triangles = Vec::new();
    for start in 0..count {
        for &first in &around[start].clone() {
            if used.contains_key(&(start, first)) {
                continue;
            }
            let mut polygon = vec![start];
            let (mut u, mut v) = (start, first);
            used.insert((u, v), ());
            while v != start {
                polygon.push(v);
                let list = &around[v];
                let back = list.iter().position(|&w| w == u).unwrap_or(0);
                let w = list[(back + list.len() - 1) % list.len()];
                (u, v) = (v, w);
                if used.insert((u, v), ()).is_some() || polygon.len() > count {
                    break;
                }
            }
            if v != start || signed_area(&polygon, &plane) <= 0.0 {
                continue;
            }
            fan(&polygon, &mut global, positions, &mut triangles);
        }
    }
    triangles
}

/// Triangles of a convex region: itself if a triangle, else a fan round the mean of its
/// corners (appended as a new vertex).
fn fan(
    polygon: &[usize],
    global: &mut Vec<u32>,
    positions: &mut Vec<[f64; 3]>,
    out: &mut Vec<[u32; 3]>,
) {
    let ids: Vec<u32> = polygon.iter().map(|&l| global[l]).collect();
    if ids.len() == 3 {
        out.push([ids[0], ids[1], ids[2]]);
        return;
    }
    let sum = ids
        .iter()
        .fold([0.0; 3], |acc, &v| add(acc, positions[v as usize]));
    let centre = positions.len() as u32;
    positions.push(scale(sum, 1.0 / ids.len() as f64));
    global.push(centre);
    for i in 0..ids.len() {
        out.push([centre, ids[i], ids[(i + 1) % ids.len()]]);
    }
}

/// Where segments `a`–`b` and `c`–`d` cross strictly inside both, as the parameters
/// along each; `None` when they do not (or are parallel).
fn crossing(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<(f64, f64)> {
    let r = [b[0] - a[0], b[1] - a[1]];
    let s = [d[0] - c[0], d[1] - c[1]];
    let denom = r[0] * s[1] - r[1] * s[0];
    if denom == 0.0 {
        return None;
    }
    let q = [c[0] - a[0], c[1] - a[1]];
    let t = (q[0] * s[1] - q[1] * s[0]) / denom;
    let u = (q[0] * r[1] - q[1] * r[0]) / denom;
    const INSIDE: f64 = 1e-12;
    (t > INSIDE && t < 1.0 - INSIDE && u > INSIDE && u < 1.0 - INSIDE).then_some((t, u))
}

fn angle(o: [f64; 2], p: [f64; 2]) -> f64 {
    (p[1] - o[1]).atan2(p[0] - o[0])
}

fn signed_area(polygon: &[usize], plane: &[[f64; 2]]) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| {
            let (p, q) = (plane[polygon[i]], plane[polygon[(i + 1) % n]]);
            p[0] * q[1] - p[1] * q[0]
        })
        .sum::<f64>()
        * 0.5
}
