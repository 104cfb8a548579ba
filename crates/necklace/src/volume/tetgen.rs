//! Tet meshing with TetGen (optional, cargo feature `tetgen`).
//!
//! Meshes the volume inside a closed, outward-oriented [`SurfaceMesh`], or the shell
//! between it and a sphere, with TetGen through the `tritet` crate, using the switches of
//! "Fast Computation of Neck-like Features": the surface is a piecewise linear complex
//! (`p`) and tets are refined to a radius-edge ratio of at most 1.2 (`q1.2`).
//!
//! **License:** TetGen is AGPL-3.0; enabling this feature links it in and makes the
//! resulting build AGPL-3.0. Without the feature nothing of TetGen is compiled.
//!
//! ## Entry points
//! - [`mesh_inside`]: the solid bounded by the surface (cavities, i.e. components nested
//!   inside another one, are left empty through hole points).
//! - [`mesh_shell`]: the region between the surface and a sphere (the sphere is an
//!   icosphere of [`SPHERE_TRIANGLES`] triangles inscribed in it), with one hole point
//!   just inside each component of the surface. Vertices of the sphere (and the Steiner
//!   points TetGen puts on it) are [`VertexKind::Outer`].
//!
//! Both return a [`TetMesh`] with positively oriented tets and vertex kinds from
//! [`TetMesh::classify_boundary`] (boundary vertices `Surface`, except the sphere's).
//!
//! ## Switches
//! `tritet::Tetgen::generate_mesh(false, false, None, Some(1.2))` runs TetGen with
//! `pzAfQaq1.2`: `p` PLC input, `q1.2` radius-edge bound (tritet calls the argument a
//! minimum angle, but writes it as the first `q` value, which TetGen reads as the
//! radius-edge ratio), plus tritet's fixed `z` (zero-based numbering), `A`/`a` (region
//! attributes and volumes; no regions are given, so no effect), `f` (face output) and
//! `Q` (quiet). `q` also refines the input surface: on marching-tetrahedra surfaces (many
//! skinny triangles) expect about 40–60 times the input vertex count, e.g. a 7k-triangle
//! sphere gives ~670k tets in a few seconds.
//!
//! ## Failures
//! Every failure is an [`Error`] with a one-line message: bad input found before
//! meshing (open or inward surface, a surface not strictly inside the sphere), errors
//! reported by tritet, and TetGen runs that stop early. TetGen is built by tritet as a
//! library (`TETLIBRARY`), so it never calls `exit()`: it throws, and tritet catches the
//! throw, prints `status = N` on stdout and reports success with an empty or partial
//! mesh; this module therefore checks the output (tets present, indices in range, no
//! degenerate tet, total volume within 1e-4 of what the PLC encloses) and turns a
//! mismatch into an error. What cannot be caught: TetGen's internal `assert`s (tritet
//! compiles without `NDEBUG`, so a failed one aborts the process), crashes inside the
//! C++ code, and the `status = N` line on stdout. TetGen keeps process-wide state, so
//! calls are serialised by a lock in this module.

use std::collections::{HashMap, HashSet};
use std::sync::Mutex;

use tritet::Tetgen;

use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::mesh::{find, union, SurfaceMesh, Topology};
use crate::tet::{TetMesh, VertexKind};

/// Radius-edge ratio bound of the quality switch (`q1.2`).
pub const RADIUS_EDGE_RATIO: f64 = 1.2;

/// Icosahedron subdivisions of the outer sphere of [`mesh_shell`].
const SPHERE_SUBDIVISIONS: usize = 3;

/// Triangles of the outer sphere of [`mesh_shell`] (20 · 4³).
pub const SPHERE_TRIANGLES: usize = 20 << (2 * SPHERE_SUBDIVISIONS);

/// TetGen is not thread-safe (process-wide predicate state): one run at a time.
static TETGEN_LOCK: Mutex<()> = Mutex::new(());

/// Tet mesh of the solid bounded by `surface` (closed, outward oriented), with TetGen
/// switches `pq1.2`. All boundary vertices are [`VertexKind::Surface`].
pub fn mesh_inside(surface: &SurfaceMesh) -> Result<TetMesh> {
    let plc = Plc::new(surface)?;
    // Cavities: a point just outside a component that is still enclosed by another one.
    let mut holes = Vec::new();
    for c in 0..plc.num_components {
        let p = plc.probe(c, 1.0).ok_or_else(|| {
            invalid(format!(
                "cannot place a point just outside surface component {c}"
            ))
        })?;
        let w = plc.windings(p);
        if (0..plc.num_components).any(|k| k != c && w[k] != 0) {
            holes.push(p);
        }
    }
    let volume = plc.volume;
    let mut mesh = run_tetgen(&plc.positions, &plc.triangles, &holes, volume)?;
    for k in &mut mesh.kinds {
        if *k == VertexKind::Outer {
            *k = VertexKind::Surface;
        }
    }
    Ok(mesh)
}

/// Tet mesh of the shell between `surface` (closed, outward oriented, strictly inside
/// the sphere) and the sphere of `radius` around `centre`, with TetGen switches `pq1.2`.
///
/// The sphere is an icosphere of [`SPHERE_TRIANGLES`] triangles with its vertices on the
/// sphere; the surface must lie strictly inside that polyhedron. One hole point just
/// inside each component of the surface removes the solid. Vertices on the sphere are
/// [`VertexKind::Outer`], those on the surface [`VertexKind::Surface`].
pub fn mesh_shell(surface: &SurfaceMesh, centre: [f64; 3], radius: f64) -> Result<TetMesh> {
    if !radius.is_finite() || radius <= 0.0 || centre.iter().any(|c| !c.is_finite()) {
        return Err(Error::invalid_argument(format!(
            "sphere centre {centre:?} and radius {radius} must be finite, radius > 0"
        )));
    }
    let plc = Plc::new(surface)?;
    let (sphere_pos, sphere_tris) = icosphere(SPHERE_SUBDIVISIONS, centre, radius);

    // The surface must lie strictly inside the convex polyhedron.
    let planes: Vec<([f64; 3], f64)> = sphere_tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| sphere_pos[v as usize]);
            let n = cross(sub(b, a), sub(c, a));
            let n = scale(n, 1.0 / norm(n));
            (n, dot(n, a))
        })
        .collect();
    let inradius = planes
        .iter()
        .map(|&(n, d)| d - dot(n, centre))
        .fold(f64::INFINITY, f64::min);
    let margin = 1e-9 * radius;
    for (i, &p) in plc.positions.iter().enumerate() {
        let outside = norm(sub(p, centre)) >= inradius - margin
            && planes.iter().any(|&(n, d)| dot(n, p) >= d - margin);
        if outside {
            return Err(Error::invalid_argument(format!(
                "surface vertex {} at {p:?} is not strictly inside the sphere (centre {centre:?}, radius {radius}; the polyhedron of {} triangles has inradius {inradius})",
                plc.original[i], SPHERE_TRIANGLES
            )));
        }
    }

    // One hole point just inside each component, verified by winding number.
    let mut holes = Vec::with_capacity(plc.num_components);
    for c in 0..plc.num_components {
        holes.push(plc.probe(c, -1.0).ok_or_else(|| {
            invalid(format!(
                "cannot place a hole point just inside surface component {c}"
            ))
        })?);
    }

    let offset = plc.positions.len() as u32;
    let mut positions = plc.positions.clone();
    positions.extend_from_slice(&sphere_pos);
    let mut triangles = plc.triangles.clone();
    triangles.extend(sphere_tris.iter().map(|t| t.map(|v| v + offset)));
    let sphere_volume: f64 = sphere_tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| sub(sphere_pos[v as usize], centre));
            dot(a, cross(b, c)) / 6.0
        })
        .sum();
    let mut mesh = run_tetgen(&positions, &triangles, &holes, sphere_volume - plc.volume)?;

    // Boundary components holding a sphere vertex are Outer, the others Surface.
    let sphere_keys: HashSet<[u64; 3]> = sphere_pos.iter().map(|p| p.map(f64::to_bits)).collect();
    let n = mesh.num_vertices();
    let mut parent: Vec<usize> = (0..n).collect();
    for f in mesh.boundary_faces() {
        union(&mut parent, f[0] as usize, f[1] as usize);
        union(&mut parent, f[0] as usize, f[2] as usize);
    }
    let mut outer_roots = HashSet::new();
    let mut found = 0;
    for v in 0..n {
        if sphere_keys.contains(&mesh.positions[v].map(f64::to_bits)) {
            found += 1;
            outer_roots.insert(find(&mut parent, v));
        }
    }
    if found != sphere_pos.len() {
        return Err(tetgen_failed(format!(
            "only {found} of the {} sphere vertices are in TetGen's mesh",
            sphere_pos.len()
        )));
    }
    for v in 0..n {
        if mesh.kinds[v] != VertexKind::Interior {
            mesh.kinds[v] = if outer_roots.contains(&find(&mut parent, v)) {
                VertexKind::Outer
            } else {
                VertexKind::Surface
            };
        }
    }
    Ok(mesh)
}

/// The surface as TetGen input: referenced vertices only, components, enclosed volume.
struct Plc {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// Input index of each compacted vertex.
    original: Vec<u32>,
    /// Component of each triangle.
    face_component: Vec<usize>,
    num_components: usize,
    volume: f64,
}

impl Plc {
    fn new(surface: &SurfaceMesh) -> Result<Plc> {
        let n = surface.positions.len();
        if surface.triangles.len() < 4 {
            return Err(invalid(format!(
                "a closed surface needs at least 4 triangles, this one has {}",
                surface.triangles.len()
            )));
        }
        let mut new_index = vec![u32::MAX; n];
        let mut original = Vec::new();
        let mut triangles = Vec::with_capacity(surface.triangles.len());
        for (f, t) in surface.triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
                return Err(Error::new(
                    ErrorKind::IndexOutOfRange,
                    format!("triangle {f} uses vertex {v}, but there are {n} vertices"),
                ));
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(invalid(format!("triangle {f} repeats a vertex: {t:?}")));
            }
            triangles.push(t.map(|v| {
                let v = v as usize;
                if new_index[v] == u32::MAX {
                    new_index[v] = original.len() as u32;
                    original.push(v as u32);
                }
                new_index[v]
            }));
        }
        let positions: Vec<[f64; 3]> = original
            .iter()
            .map(|&v| surface.positions[v as usize])
            .collect();
        if let Some(i) = positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(Error::new(
                ErrorKind::NonFinite,
                format!("vertex {} has a non-finite coordinate", original[i]),
            ));
        }
        // TetGen indexes with i32; leave room for the sphere.
        if positions.len() + triangles.len() > (i32::MAX as usize) / 4 {
            return Err(invalid(format!(
                "{} vertices and {} triangles are too many for TetGen",
                positions.len(),
                triangles.len()
            )));
        }
        let compact = SurfaceMesh {
            positions,
            triangles,
        };
        let topology = Topology::new(&compact);
        if !topology.boundary_edges().is_empty() || !topology.non_manifold_edges().is_empty() {
            return Err(invalid(format!(
                "the surface is not closed: {} boundary and {} non-manifold edges",
                topology.boundary_edges().len(),
                topology.non_manifold_edges().len()
            )));
        }
        let volume = compact.signed_volume();
        if volume.is_nan() || volume <= 0.0 {
            return Err(invalid(format!(
                "the surface encloses volume {volume}; it must be closed and outward oriented"
            )));
        }
        let (ids, num_components) = topology.components(&compact);
        let face_component = compact
            .triangles
            .iter()
            .map(|t| ids[t[0] as usize].unwrap_or(0) as usize)
            .collect();
        let SurfaceMesh {
            positions,
            triangles,
        } = compact;
        Ok(Plc {
            positions,
            triangles,
            original,
            face_component,
            num_components,
            volume,
        })
    }

    /// Winding number of every component around `p` (rounded; `i64::MIN` when `p` is
    /// too close to the surface for the rounding to be trusted).
    fn windings(&self, p: [f64; 3]) -> Vec<i64> {
        let mut sum = vec![0.0; self.num_components];
        for (t, &c) in self.triangles.iter().zip(&self.face_component) {
            let [a, b, d] = t.map(|v| sub(self.positions[v as usize], p));
            let (la, lb, ld) = (norm(a), norm(b), norm(d));
            let num = dot(a, cross(b, d));
            let den = la * lb * ld + dot(a, b) * ld + dot(b, d) * la + dot(d, a) * lb;
            sum[c] += 2.0 * num.atan2(den);
        }
        sum.iter()
            .map(|s| {
                let w = s / (4.0 * std::f64::consts::PI);
                if (w - w.round()).abs() < 0.25 {
                    w.round() as i64
                } else {
                    i64::MIN
                }
            })
            .collect()
    }

    /// A point just off component `c`: a face centroid moved along the outward normal
    /// by `side` · (a tenth of the face's shortest edge). Verified: inside the solid
    /// (total winding 1) for `side < 0`, outside it (total winding 0) for `side > 0`.
    /// Tries the component's largest faces first.
    fn probe(&self, c: usize, side: f64) -> Option<[f64; 3]> {
        let mut faces: Vec<(f64, usize)> = (0..self.triangles.len())
            .filter(|&f| self.face_component[f] == c)
            .map(|f| {
                let [a, b, d] = self.triangles[f].map(|v| self.positions[v as usize]);
                (norm(cross(sub(b, a), sub(d, a))), f)
            })
            .collect();
        faces.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let want = if side < 0.0 { 1 } else { 0 };
        faces.iter().take(32).find_map(|&(area2, f)| {
            let [a, b, d] = self.triangles[f].map(|v| self.positions[v as usize]);
            let h = norm(sub(b, a)).min(norm(sub(d, b))).min(norm(sub(a, d)));
            if area2 <= 0.0 || h <= 0.0 {
                return None;
            }
            let normal = scale(cross(sub(b, a), sub(d, a)), 1.0 / area2);
            let centroid = scale(add(add(a, b), d), 1.0 / 3.0);
            let p = add(centroid, scale(normal, side * 0.1 * h));
            let w = self.windings(p);
            (w.iter().all(|&x| x != i64::MIN) && w.iter().sum::<i64>() == want).then_some(p)
        })
    }
}

/// Run TetGen (`pq1.2`) on the PLC and read its mesh back, checking that the tets fill
/// `expected_volume`.
fn run_tetgen(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    holes: &[[f64; 3]],
    expected_volume: f64,
) -> Result<TetMesh> {
    let (points, tets) = {
        let _guard = TETGEN_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let nhole = (!holes.is_empty()).then_some(holes.len());
        let mut tg = Tetgen::new(positions.len(), Some(vec![3; triangles.len()]), None, nhole)
            .map_err(tritet_error)?;
        for (i, p) in positions.iter().enumerate() {
            tg.set_point(i, 0, p[0], p[1], p[2]).map_err(tritet_error)?;
        }
        for (f, t) in triangles.iter().enumerate() {
            for (m, &v) in t.iter().enumerate() {
                tg.set_facet_point(f, m, v as usize).map_err(tritet_error)?;
            }
        }
        for (i, h) in holes.iter().enumerate() {
            tg.set_hole(i, h[0], h[1], h[2]).map_err(tritet_error)?;
        }
        tg.generate_mesh(false, false, None, Some(RADIUS_EDGE_RATIO))
            .map_err(tritet_error)?;
        let (npoint, ncell) = (tg.out_npoint(), tg.out_ncell());
        if ncell == 0 {
            return Err(tetgen_failed(
                "no tetrahedra; it stopped on bad input (stdout shows `status = N`: 3 self-intersection, 4 tiny feature, 5 facets too close, 10 input error)".to_string(),
            ));
        }
        if tg.out_cell_npoint() != 4 {
            return Err(tetgen_broke(format!(
                "{} nodes per tetrahedron, expected 4",
                tg.out_cell_npoint()
            )));
        }
        let points: Vec<[f64; 3]> = (0..npoint)
            .map(|i| [tg.out_point(i, 0), tg.out_point(i, 1), tg.out_point(i, 2)])
            .collect();
        let mut tets = Vec::with_capacity(ncell);
        for c in 0..ncell {
            let mut tet = [0u32; 4];
            for (m, slot) in tet.iter_mut().enumerate() {
                let v = tg.out_cell_point(c, m);
                if v >= npoint {
                    return Err(tetgen_broke(format!(
                        "tetrahedron {c} uses point {v} of {npoint}"
                    )));
                }
                *slot = v as u32;
            }
            tets.push(tet);
        }
        (points, tets)
    };

    let mut tets = tets;
    let mut total = 0.0;
    for (c, tet) in tets.iter_mut().enumerate() {
        let [a, b, d, e] = tet.map(|v| points[v as usize]);
        let vol = dot(sub(b, a), cross(sub(d, a), sub(e, a))) / 6.0;
        if vol == 0.0 || !vol.is_finite() {
            return Err(tetgen_failed(format!("tetrahedron {c} is degenerate")));
        }
        if vol < 0.0 {
            tet.swap(2, 3);
        }
        total += vol.abs();
    }
    if (total - expected_volume).abs() > 1e-4 * expected_volume.abs() {
        return Err(tetgen_failed(format!(
            "its tets have volume {total}, but the input encloses {expected_volume} (self-intersecting input, or holes not carved)"
        )));
    }
    let kinds = TetMesh::classify_boundary(&points, &tets);
    TetMesh::new(points, tets, kinds)
}

/// The icosahedron subdivided `levels` times, projected on the sphere, outward oriented.
fn icosphere(levels: usize, centre: [f64; 3], radius: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let unit = |p: [f64; 3]| scale(p, 1.0 / norm(p));
    let (corners, faces) = crate::geom::icosahedron();
    let mut pos: Vec<[f64; 3]> = corners.into_iter().map(unit).collect();
    let mut tris: Vec<[u32; 3]> = faces.to_vec();
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(4 * tris.len());
        for &[a, b, c] in &tris {
            let mut m = |i: u32, j: u32| {
                *mid.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    let p = unit(add(pos[i as usize], pos[j as usize]));
                    pos.push(p);
                    (pos.len() - 1) as u32
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    for t in &mut tris {
        let [a, b, c] = t.map(|v| pos[v as usize]);
        if dot(cross(sub(b, a), sub(c, a)), add(add(a, b), c)) < 0.0 {
            t.swap(1, 2);
        }
    }
    let pos = pos
        .into_iter()
        .map(|p| add(centre, scale(p, radius)))
        .collect();
    (pos, tris)
}

fn invalid(message: String) -> Error {
    Error::new(ErrorKind::InvalidMesh, message)
}

fn tritet_error(message: &'static str) -> Error {
    Error::new(
        ErrorKind::InvalidMesh,
        format!("TetGen (tritet): {message}"),
    )
}

fn tetgen_failed(message: String) -> Error {
    Error::new(ErrorKind::InvalidMesh, format!("TetGen failed: {message}"))
}

/// TetGen's output is inconsistent: not the input's fault.
fn tetgen_broke(message: String) -> Error {
    Error::new(
        ErrorKind::Internal,
        format!("TetGen returned a broken mesh: {message}"),
    )
}
