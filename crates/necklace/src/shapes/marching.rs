//! Marching tetrahedra: the zero level set of a signed distance function as a closed,
//! manifold, outward-oriented triangle mesh.
//!
//! The box is covered by a regular lattice of cubes, each split into the six
//! tetrahedra of the Kuhn (Freudenthal) triangulation around its main diagonal. The
//! split is the same in every cube, so neighbouring tetrahedra share faces exactly and
//! the surface pieces glue into a 2-manifold: marching tetrahedra has no ambiguous case.
//! Lattice values are pushed at least `ZERO_GAP · h` away from zero (symbolic
//! perturbation), so no surface vertex sits on a lattice vertex and no triangle
//! degenerates. Surface vertices are shared through their lattice edge, then moved onto
//! the zero set by a few Newton steps along the numerical gradient.
//!
//! Convention: inside is `sdf < 0`; triangles are counter-clockwise seen from outside.

use std::collections::HashMap;

use crate::geom::{add, cross, dot, lerp, norm, scale, sub};
use crate::mesh::SurfaceMesh;

/// Lattice values closer to zero than this fraction of the spacing are pushed away.
const ZERO_GAP: f64 = 1e-3;
/// Newton steps when projecting vertices onto the level set.
const PROJECTION_STEPS: usize = 4;

/// The six tetrahedra of a cube (corner bit 1 = +x, 2 = +y, 4 = +z), each a monotone
/// path from corner 0 to corner 7.
const KUHN_TETS: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Mesh the zero set of `sdf` inside the box `[lo, hi]` (which must hold the whole
/// inside region strictly inside it) on a lattice of spacing `h`.
pub(crate) fn mesh_level_set(
    sdf: &dyn Fn([f64; 3]) -> f64,
    lo: [f64; 3],
    hi: [f64; 3],
    h: f64,
) -> SurfaceMesh {
    let extent = sub(hi, lo);
    let dims = extent.map(|e| (e / h).ceil() as usize + 1);
    let grid = Grid { lo, h, dims };

    let values = grid.sample(sdf);
    let mut builder = SurfaceBuilder::default();
    for k in 0..dims[2] - 1 {
        for j in 0..dims[1] - 1 {
            for i in 0..dims[0] - 1 {
                let corner = |c: usize| grid.index(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
                for tet in KUHN_TETS {
                    let ids = tet.map(corner);
                    builder.add_tet(&grid, &values, ids);
                }
            }
        }
    }
    let mut mesh = builder.mesh;
    for p in &mut mesh.positions {
        *p = project_to_zero_set(sdf, *p, h);
    }
    mesh
}

/// A regular lattice: origin, spacing and vertex counts per axis.
struct Grid {
    lo: [f64; 3],
    h: f64,
    dims: [usize; 3],
}

impl Grid {
    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    fn position(&self, id: usize) -> [f64; 3] {
        let i = id % self.dims[0];
        let j = (id / self.dims[0]) % self.dims[1];
        let k = id / (self.dims[0] * self.dims[1]);
        [
            self.lo[0] + i as f64 * self.h,
            self.lo[1] + j as f64 * self.h,
            self.lo[2] + k as f64 * self.h,
        ]
    }

    /// Sample the function at every lattice vertex, keeping values off zero.
    fn sample(&self, sdf: &dyn Fn([f64; 3]) -> f64) -> Vec<f64> {
        let gap = ZERO_GAP * self.h;
        (0..self.dims[0] * self.dims[1] * self.dims[2])
            .map(|id| {
                let v = sdf(self.position(id));
                if v >= 0.0 {
                    v.max(gap)
                } else {
                    v.min(-gap)
                }
            })
            .collect()
    }
}

/// Collects triangles, sharing each surface vertex through the lattice edge it lies on.
#[derive(Default)]
struct SurfaceBuilder {
    mesh: SurfaceMesh,
    vertex_on_edge: HashMap<(usize, usize), u32>,
}

impl SurfaceBuilder {
    /// Emit the surface piece inside one tetrahedron.
    fn add_tet(&mut self, grid: &Grid, values: &[f64], ids: [usize; 4]) {
        let mut inside = [0usize; 4];
        let mut outside = [0usize; 4];
        let (mut ni, mut no) = (0, 0);
        for id in ids {
            if values[id] < 0.0 {
                inside[ni] = id;
                ni += 1;
            } else {
                outside[no] = id;
                no += 1;
            }
        }
        let (inside, outside) = (&inside[..ni], &outside[..no]);
        // Direction from the inside corners towards the outside corners: the normal.
        let centroid = |s: &[usize]| {
            let mut c = [0.0; 3];
            for &id in s {
                let p = grid.position(id);
                c = [c[0] + p[0], c[1] + p[1], c[2] + p[2]];
            }
            scale(c, 1.0 / s.len().max(1) as f64)
        };
        match ni {
            1 | 3 => {
                // One corner is alone on its side: a triangle around it.
                let (lone, others) = if ni == 1 {
                    (inside[0], outside)
                } else {
                    (outside[0], inside)
                };
                let tri = [
                    self.crossing(grid, values, lone, others[0]),
                    self.crossing(grid, values, lone, others[1]),
                    self.crossing(grid, values, lone, others[2]),
                ];
                let outward = sub(centroid(outside), centroid(inside));
                self.push_oriented(tri, outward);
            }
            2 => {
                // A quad through the four edges joining the two sides, in cyclic order.
                let (a, b) = (inside[0], inside[1]);
                let (c, d) = (outside[0], outside[1]);
                let quad = [
                    self.crossing(grid, values, a, c),
                    self.crossing(grid, values, a, d),
                    self.crossing(grid, values, b, d),
                    self.crossing(grid, values, b, c),
                ];
                let outward = sub(centroid(outside), centroid(inside));
                let p = quad.map(|v| self.mesh.positions[v as usize]);
                let normal = add(
                    cross(sub(p[1], p[0]), sub(p[2], p[0])),
                    cross(sub(p[2], p[0]), sub(p[3], p[0])),
                );
                let quad = if dot(normal, outward) >= 0.0 {
                    quad
                } else {
                    [quad[0], quad[3], quad[2], quad[1]]
                };
                self.mesh.triangles.push([quad[0], quad[1], quad[2]]);
                self.mesh.triangles.push([quad[0], quad[2], quad[3]]);
            }
            _ => {}
        }
    }

    fn push_oriented(&mut self, tri: [u32; 3], outward: [f64; 3]) {
        let p = tri.map(|v| self.mesh.positions[v as usize]);
        let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        if dot(n, outward) >= 0.0 {
            self.mesh.triangles.push(tri);
        } else {
            self.mesh.triangles.push([tri[0], tri[2], tri[1]]);
        }
    }

    /// The surface vertex on lattice edge (a, b), created on first use.
    fn crossing(&mut self, grid: &Grid, values: &[f64], a: usize, b: usize) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&v) = self.vertex_on_edge.get(&key) {
            return v;
        }
        let (fa, fb) = (values[key.0], values[key.1]);
        let t = fa / (fa - fb);
        let p = lerp(grid.position(key.0), grid.position(key.1), t);
        let v = self.mesh.positions.len() as u32;
        self.mesh.positions.push(p);
        self.vertex_on_edge.insert(key, v);
        v
    }
}

/// Newton steps `p ← p − f ∇f / |∇f|²` (central differences), each at most `h/2` long.
fn project_to_zero_set(sdf: &dyn Fn([f64; 3]) -> f64, mut p: [f64; 3], h: f64) -> [f64; 3] {
    let eps = 1e-5 * h;
    for _ in 0..PROJECTION_STEPS {
        let f = sdf(p);
        if f.abs() <= 1e-12 * h {
            break;
        }
        let mut g = [0.0; 3];
        for (axis, gk) in g.iter_mut().enumerate() {
            let mut a = p;
            let mut b = p;
            a[axis] += eps;
            b[axis] -= eps;
            *gk = (sdf(a) - sdf(b)) / (2.0 * eps);
        }
        let g2 = dot(g, g);
        if g2 < 1e-12 {
            break;
        }
        let mut step = scale(g, f / g2);
        let len = norm(step);
        if len > 0.5 * h {
            step = scale(step, 0.5 * h / len);
        }
        p = sub(p, step);
    }
    p
}
