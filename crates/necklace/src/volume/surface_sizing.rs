//! What the volume stage measures on a surface for the mesher: at every vertex the
//! thickness of the solid and the width of the gap in front of it ([`thickness_along`]: a ray
//! along the normal, then the inscribed ball touching there), and at the middle of
//! every face that turns away from its corners' normals (a hole's wall drawn with its
//! rim's vertices alone: [`measure_surface`]), more points where those do not tell
//! ([`sample_thickness`]), the sizing features that ask for finer cells where either is
//! below `2h` ([`thin_part_sizing`]; two cells across, one across a thin part of the
//! solid, at most `h / 2`, for the shell's mesh, and none finer than `h / 4` across a gap
//! for the solid's mesh, nor than a quarter of a thin solid beside it), and the creases
//! and corners to snap onto
//! ([`sharp_features`]). Folds of the surface and places where it crosses itself are
//! not parts, and are skipped.
//!
//! Conventions: lengths in the surface's units; thickness `[solid, gap]` per vertex,
//! infinite where not thin.

use super::{SharpFeatures, SizingFeature};
use crate::distance::SurfaceDistance;
use crate::geom::{add, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Parts and gaps thinner than this many `h` get finer cells (at `h`, two cells across).
pub(super) const THIN_FACTOR: f64 = 2.0;

/// Cells across a thin part or gap on the side a mesh covers (a plate, for the mesh of
/// the solid). Warping moves a vertex by at most 0.36 of a cell, so two cells across
/// leave a core of more than a cell whose lattice vertices stay inside and connect
/// along the part. (Where that is not enough, the topology check finds it and refines.)
pub(super) const CELLS_ACROSS: f64 = 2.0;

/// Cells across a thin part of the solid for the mesh of the gap around it (the
/// shell): that mesh needs no interior vertex in the part, only a lattice vertex inside
/// it between its walls so that its edges do not bridge them, and one cell across puts
/// one there on most of the part. (Where it does not, the topology check finds the
/// bridge and refines.) The cells stay at most `h / 2` there, one level below the
/// lattice's: at `h`, the buckyball's shell (sticks 0.2 thick, h 0.145) lost one
/// window's loop, its saddle's plane cutting no curve round it. (A part thicker than
/// `h` keeps its two cells across, at least `h / 2` each: no finer than in the solid's
/// mesh.) The mesh of the solid
/// keeps [`CELLS_ACROSS`] across gaps (down to [`GAP_FLOOR_OF_H`]): at one,
/// os_cow-low-resolution lost its handle class, the junction where its tail meets its
/// leg being sized by the gap beside it.
pub(super) const CELLS_ACROSS_BEYOND: f64 = 1.0;

/// The finest cells a gap asks for in the mesh of the solid, as a fraction of `h`
/// (bounded by [`GAP_FLOOR_OF_SOLID`]).
/// That mesh holds no field in the gap: it needs a lattice vertex between the gap's
/// walls so that its edges do not bridge them, and the cells of the solid beside a
/// junction (the cow's tail meets its leg beside a gap). Below both bounds a gap keeps
/// [`CELLS_ACROSS`], above them the floor (one cell across a gap narrower than it). On
/// os_cow-low-resolution.obj, whose inside spent 62 % of its unknowns on cells of `h / 4`
/// and finer, most of them along gaps of `h / 8` to `h / 4`, the floor takes the inside
/// from 82 459 unknowns to 57 710 with the same loops; the same loops on the 21 shared
/// models. Without the bound by the solid's thickness, the boot's eyelet (a ring about
/// `0.6 h` thick beside a gap) lost its saddle; at `h / 2`, the scorpion gained three
/// handle loops (docs/decisions.md, "a gap asks the solid's mesh for cells no finer than
/// h/4", has the commands and the other models).
pub(super) const GAP_FLOOR_OF_H: f64 = 0.25;

/// Where the solid behind a gap's wall is thin, the floor of [`GAP_FLOOR_OF_H`] is at
/// most this fraction of its thickness (one level finer than its own two cells across).
pub(super) const GAP_FLOOR_OF_SOLID: f64 = 0.25;

/// A contact of the inscribed ball counts as the opposite wall (not the surface curving
/// next to the vertex) when it is at least this angle round the ball from the vertex.
const MIN_SEPARATION_DEG: f64 = 120.0;

/// A part or gap thinner than 1/`FOLD_RATIO` of the shortest edge at a vertex, whose
/// other wall is a triangle beside the vertex's own (it has a corner on their ring), is
/// taken for a fold of the surface there, not refined for: a real thin part is drawn
/// with edges not much longer than its thickness somewhere around it (a plate's rim, a
/// wire's section). A wall farther along the surface, or on another part, is a part
/// or a gap however long the edges (two plates drawn with a few big triangles each).
const FOLD_RATIO: f64 = 20.0;

/// An edge whose two faces' normals differ by more than this is a crease.
const CREASE_DEG: f64 = 40.0;

/// A ray across a part meets the other wall within this angle of the wall's normal; one
/// that meets it more obliquely skims along the surface (see [`faces_ray`]).
const MAX_INCIDENCE_DEG: f64 = 80.0;

/// Most shrinking steps of the inscribed ball at a vertex (each a closest-point query);
/// a ball still shrinking after them is taken as not thin.
const MEDIAL_STEPS: usize = 8;

/// [`thickness_along`] the vertex normals.
#[cfg(test)]
fn thickness(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    skip: &[bool],
    limit: f64,
) -> Vec<[f64; 2]> {
    let (normals, shortest) = (vertex_normals(surface), shortest_edges(surface));
    thickness_along(
        surface, topology, distance, skip, limit, &normals, &shortest,
    )
}

/// For each surface vertex (but those marked `skip`), the thickness of the solid and the
/// width of the gap in front of it, each when below `limit` (else infinity), by
/// [`measure`] along the vertex normal (`normals`: from [`vertex_normals`]). A contact
/// or hit on a triangle at the vertex does not count, nor a thickness below
/// 1/[`FOLD_RATIO`] of the vertex's shortest edge (`shortest`: from [`shortest_edges`])
/// across to a triangle beside the vertex's own (a fold, not a part).
fn thickness_along(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    skip: &[bool],
    limit: f64,
    normals: &[[f64; 3]],
    shortest: &[f64],
) -> Vec<[f64; 2]> {
    use rayon::prelude::*;
    (0..surface.num_vertices())
        .into_par_iter()
        .map(|v| {
            if topology.vertex_faces(v).is_empty() || skip[v] || normals[v] == [0.0; 3] {
                return [f64::INFINITY; 2];
            }
            let corner = [v as u32];
            let at = Home::on(&corner, shortest);
            let p = surface.positions[v];
            measure(surface, topology, distance, p, normals[v], limit, &at)
        })
        .collect()
}

/// A face turns away from each of its corners' normals by more than this: its corners
/// look across elsewhere, and its middle is measured along its own normal.
const OBLIQUE_DEG: f64 = 30.0;

/// The thickness at vertices and at the middles of the faces their normals do not see
/// ([`thickness_along`], then [`oblique_faces`] measured along their own normals): a hole
/// through a plate drawn with its rim's vertices alone has corners whose normals lean
/// halfway between the plate's face and the hole's wall, and rays along them leave
/// through the hole's openings, so no vertex measures the hole's width. The middles
/// are points on no triangle (sized on their own where thin); the triangles are the
/// surface's.
pub(super) fn measure_surface(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    skip: &[bool],
    limit: f64,
) -> ThicknessSamples {
    use rayon::prelude::*;
    let (normals, shortest) = (vertex_normals(surface), shortest_edges(surface));
    let thickness = thickness_along(
        surface, topology, distance, skip, limit, &normals, &shortest,
    );
    let oblique = oblique_faces(surface, &normals, skip);
    let mut samples = ThicknessSamples {
        positions: surface.positions.clone(),
        normals,
        thickness,
        triangles: surface.triangles.clone(),
        bound: false,
    };
    let measured: Vec<([f64; 3], [f64; 3], [f64; 2])> = oblique
        .par_iter()
        .map(|&f| {
            let corners = surface.triangles[f as usize];
            let p = surface.corners(f as usize);
            let middle = scale(add(add(p[0], p[1]), p[2]), 1.0 / 3.0);
            let normal = unit(surface.face_normal_scaled(f as usize));
            let at = Home::on(&corners, &shortest);
            let t = measure(surface, topology, distance, middle, normal, limit, &at);
            (middle, normal, t)
        })
        .collect();
    for (middle, normal, t) in measured {
        samples.positions.push(middle);
        samples.normals.push(normal);
        samples.thickness.push(t);
    }
    samples
}

/// The faces (in order) that turn away from each of their corners' `normals` by more
/// than [`OBLIQUE_DEG`], but those with a `skip` corner.
fn oblique_faces(surface: &SurfaceMesh, normals: &[[f64; 3]], skip: &[bool]) -> Vec<u32> {
    let min_cos = OBLIQUE_DEG.to_radians().cos();
    (0..surface.num_triangles())
        .filter(|&f| {
            let n = unit(surface.face_normal_scaled(f));
            let corners = surface.triangles[f];
            n != [0.0; 3]
                && corners
                    .iter()
                    .all(|&v| !skip[v as usize] && dot(n, normals[v as usize]) < min_cos)
        })
        .map(|f| f as u32)
        .collect()
}

/// Where a point measured lies: on the surface's triangles round `corners` (a vertex,
/// or the corners of the triangle a point lies on), whose shortest edge is `shortest`.
struct Home<'a> {
    corners: &'a [u32],
    shortest: f64,
}

impl<'a> Home<'a> {
    /// At `corners`, with the shortest of their edges (`shortest_edge`: per vertex, from
    /// [`shortest_edges`]).
    fn on(corners: &'a [u32], shortest_edge: &[f64]) -> Home<'a> {
        let shortest = corners
            .iter()
            .map(|&v| shortest_edge[v as usize])
            .fold(f64::INFINITY, f64::min);
        Home { corners, shortest }
    }

    /// Whether `face` is not at the point: it has none of the corners (a contact or
    /// hit on the point's own triangles does not count).
    fn far(&self, surface: &SurfaceMesh, face: u32) -> bool {
        surface
            .triangles
            .get(face as usize)
            .is_some_and(|t| !t.iter().any(|v| self.corners.contains(v)))
    }

    /// Whether `face` lies beside the point's own triangles: one of its corners shares
    /// a triangle with one of the point's corners. A wall there closer than
    /// 1/[`FOLD_RATIO`] of the shortest edge is a fold.
    fn beside(&self, surface: &SurfaceMesh, topology: &Topology, face: u32) -> bool {
        surface.triangles.get(face as usize).is_some_and(|t| {
            t.iter().any(|&c| {
                topology.vertex_faces(c as usize).iter().any(|&g| {
                    surface.triangles[g as usize]
                        .iter()
                        .any(|v| self.corners.contains(v))
                })
            })
        })
    }
}

/// The shortest edge at each vertex (infinite at a vertex on no triangle): a wall much
/// closer than it is a fold of the surface there (a crease folded flat, a scanning
/// defect), not a part.
fn shortest_edges(surface: &SurfaceMesh) -> Vec<f64> {
    let mut shortest = vec![f64::INFINITY; surface.num_vertices()];
    for t in &surface.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let l = norm(sub(surface.positions[a], surface.positions[b]));
            shortest[a] = shortest[a].min(l);
            shortest[b] = shortest[b].min(l);
        }
    }
    shortest
}

/// The thickness of the solid behind the surface point `p` and the width of the gap in
/// front of it (`normal`: the unit outward normal there), each when below `limit`, else
/// infinity. On each side a ray along the normal looks for the other wall within
/// `limit`; where it finds one on a triangle far from `p` (`at`: [`Home::far`]) that
/// faces it ([`faces_ray`]), the thickness is the
/// diameter of the largest ball touching the surface at `p` whose other contact lies
/// across the part (shrinking-ball medial distance, started from the ray's chord), or
/// the chord where no ball tells. A thickness below 1/[`FOLD_RATIO`] of the shortest
/// edge at `p` across to a triangle beside `p`'s own ([`Home::beside`]) is a fold of
/// the surface, not a part (infinity).
fn measure(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    p: [f64; 3],
    normal: [f64; 3],
    limit: f64,
    at: &Home,
) -> [f64; 2] {
    let far = |face: u32| at.far(surface, face);
    [-1.0, 1.0].map(|direction| {
        let d = scale(normal, direction);
        // A ray that meets no other wall within the limit leaves room for a ball of
        // the limit's diameter: not thin on this side.
        let Some((hit, face)) = distance.ray_hit(p, d, limit) else {
            return f64::INFINITY;
        };
        if !far(face) || !faces_ray(surface, face, d, direction) {
            return f64::INFINITY;
        }
        // The ball's diameter is the thickness across a plate or a wire whatever the
        // normal (the ray's chord is only a bound on it).
        let ball = 2.0 * medial_radius(distance, p, d, 0.5 * hit, &far);
        let t = if ball.is_finite() { ball } else { hit };
        let fold = t * FOLD_RATIO < at.shortest && at.beside(surface, topology, face);
        if t < limit && !fold {
            t
        } else {
            f64::INFINITY
        }
    })
}

/// Whether a ray along the unit `d` that set out into the solid (`direction` −1) or into
/// the gap (+1) meets `face` as the other wall of a part: it leaves the solid through the
/// face's back (into the solid) or enters it through its front (into the gap), within
/// [`MAX_INCIDENCE_DEG`] of the face's normal. A ray that meets a face the other way, or
/// grazing it, crossed no part: the vertex normal at a crease drawn with sliver
/// triangles can point nearly along one of its sheets, and the ray skims along that
/// sheet, meeting it again a hair's breadth away where it bends.
fn faces_ray(surface: &SurfaceMesh, face: u32, d: [f64; 3], direction: f64) -> bool {
    let normal = surface.face_normal_scaled(face as usize);
    let length = norm(normal);
    length > 0.0 && -direction * dot(d, normal) >= MAX_INCIDENCE_DEG.to_radians().cos() * length
}

/// Unit vertex normals (area-weighted face normals summed; zero where they cancel).
fn vertex_normals(surface: &SurfaceMesh) -> Vec<[f64; 3]> {
    let mut normals = vec![[0.0; 3]; surface.num_vertices()];
    for f in 0..surface.num_triangles() {
        let n = surface.face_normal_scaled(f);
        for &v in &surface.triangles[f] {
            normals[v as usize] = add(normals[v as usize], n);
        }
    }
    normals.iter().map(|&n| unit(n)).collect()
}

/// `n` scaled to length one, or zero when it has no direction.
fn unit(n: [f64; 3]) -> [f64; 3] {
    let l = norm(n);
    if l > 0.0 && l.is_finite() {
        scale(n, 1.0 / l)
    } else {
        [0.0; 3]
    }
}

/// The thickness sampled over the surface: its vertices, and points added on triangles
/// where the vertices alone do not tell ([`sample_thickness`]). Triangles lie on the
/// surface's triangles, the first points are its vertices.
#[derive(Debug, Clone)]
pub(super) struct ThicknessSamples {
    /// The points: the surface's vertices, then the added ones.
    pub positions: Vec<[f64; 3]>,
    /// Unit outward normal at each point (the vertex normal; the face's on a face).
    pub normals: Vec<[f64; 3]>,
    /// `[solid, gap]` at each point, infinite where not thin.
    pub thickness: Vec<[f64; 2]>,
    /// Triangles over the points, covering the surface's triangles (pieces of one
    /// surface triangle need not share their edges' points with the next one's); a
    /// point may lie on none (a face's middle, see [`measure_surface`]).
    pub triangles: Vec<[u32; 3]>,
    /// Whether [`MAX_SAMPLES`] stopped the splitting (pieces left that asked for more).
    pub bound: bool,
}

impl ThicknessSamples {
    /// The thickness at the surface's vertices alone (`thickness`: from `thickness`),
    /// over its triangles.
    #[cfg(test)]
    pub fn at_vertices(surface: &SurfaceMesh, thickness: &[[f64; 2]]) -> ThicknessSamples {
        ThicknessSamples {
            positions: surface.positions.clone(),
            normals: vertex_normals(surface),
            thickness: thickness.to_vec(),
            triangles: surface.triangles.clone(),
            bound: false,
        }
    }
}

/// Most points [`sample_thickness`] adds (about 10 µs each on one core): past it, the
/// pieces left are sized by their corners, and the bound is reported.
pub(super) const MAX_SAMPLES: usize = 2_000_000;

/// Pieces whose longest edge is at most this fraction of the thickness limit (`2h`)
/// are not split: the thickness is sampled every `h/8` at the finest. (The pipeline
/// samples only where the vertices' sizing gave another topology: finely sampled,
/// thin contacts between parts drawn with long triangles ask for fine cells over their
/// whole area.)
pub(super) const FINEST_SAMPLE: f64 = 1.0 / 16.0;

/// Sample the thickness over the surface where the points measured so far (`start`:
/// from [`measure_surface`]) do not tell it: a triangle
/// (or piece) is split in four, and the thickness measured at its edges' midpoints,
/// while its longest edge exceeds `limit` (a thin part may pass between vertices that
/// far apart), or while on either side its corners disagree (thin at one and not at
/// another, or thinner by more than √2) and its longest edge exceeds the thinnest
/// corner's thickness (the change lies inside it at a scale the cells see), down to
/// pieces of [`FINEST_SAMPLE`] `× limit`. A plate's thin rim drawn with long triangles
/// reaching into the plate would otherwise ask for the rim's cells over those
/// triangles' whole area. Triangles with a `skip` corner (crossings) are not split. A
/// point added is a fold (not thin) where its thickness is below 1/[`FOLD_RATIO`] of
/// the shortest edge at any corner of its surface triangle across to a triangle beside
/// it ([`Home::beside`]), as a vertex is against its own.
/// At most [`MAX_SAMPLES`] points are added (`bound` says when that stopped it).
pub(super) fn sample_thickness(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    start: &ThicknessSamples,
    skip: &[bool],
    limit: f64,
) -> ThicknessSamples {
    use rayon::prelude::*;
    use rustc_hash::FxHashMap;
    let shortest_edge = shortest_edges(surface);
    let mut samples = ThicknessSamples {
        triangles: Vec::new(),
        bound: false,
        ..start.clone()
    };
    let crossing = |t: &[u32; 3]| t.iter().any(|&v| skip[v as usize]);
    // Pieces still to decide: corners and the surface triangle they lie on.
    let mut pieces: Vec<([u32; 3], u32)> = surface
        .triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| !crossing(t))
        .map(|(f, &t)| (t, f as u32))
        .collect();
    samples
        .triangles
        .extend(surface.triangles.iter().filter(|t| crossing(t)));
    while !pieces.is_empty() {
        let split: Vec<bool> = pieces
            .par_iter()
            .map(|&(t, _)| wants_split(&samples, t, limit))
            .collect();
        // Each split adds at most three points.
        let added = 3 * split.iter().filter(|&&s| s).count();
        if samples.positions.len() - surface.num_vertices() + added > MAX_SAMPLES {
            samples.bound = true;
            samples.triangles.extend(pieces.iter().map(|&(t, _)| t));
            break;
        }
        // The midpoints, one per edge (shared by the pieces on both sides of it), in
        // the pieces' order; then measured all at once.
        let first_new = samples.positions.len();
        let mut midpoint: FxHashMap<[u32; 2], u32> = FxHashMap::default();
        // Per new point: its surface triangle.
        let mut homes: Vec<u32> = Vec::new();
        let mut next = Vec::new();
        for (&(t, f), &s) in pieces.iter().zip(&split) {
            if !s {
                samples.triangles.push(t);
                continue;
            }
            let mut m = [0u32; 3];
            for (i, mi) in m.iter_mut().enumerate() {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let key = [a.min(b), a.max(b)];
                *mi = *midpoint.entry(key).or_insert_with(|| {
                    let id = samples.positions.len() as u32;
                    let (pa, pb) = (samples.positions[a as usize], samples.positions[b as usize]);
                    samples.positions.push(scale(add(pa, pb), 0.5));
                    samples
                        .normals
                        .push(unit(surface.face_normal_scaled(f as usize)));
                    homes.push(f);
                    id
                });
            }
            // Corners a, b, c with midpoints ab, bc, ca.
            let [a, b, c] = t;
            let [ab, bc, ca] = m;
            next.extend([
                ([a, ab, ca], f),
                ([ab, b, bc], f),
                ([ca, bc, c], f),
                ([ab, bc, ca], f),
            ]);
        }
        let measured: Vec<[f64; 2]> = (first_new..samples.positions.len())
            .into_par_iter()
            .map(|i| {
                let corners = surface.triangles[homes[i - first_new] as usize];
                let at = Home::on(&corners, &shortest_edge);
                let (p, n) = (samples.positions[i], samples.normals[i]);
                measure(surface, topology, distance, p, n, limit, &at)
            })
            .collect();
        samples.thickness.extend(measured);
        pieces = next;
    }
    samples
}

/// The longest edge of a triangle.
fn longest_edge(p: [[f64; 3]; 3]) -> f64 {
    (0..3)
        .map(|k| norm(sub(p[k], p[(k + 1) % 3])))
        .fold(0.0, f64::max)
}

/// Whether a piece needs the thickness at its edges' midpoints (see
/// [`sample_thickness`]).
fn wants_split(samples: &ThicknessSamples, t: [u32; 3], limit: f64) -> bool {
    let longest = longest_edge(t.map(|v| samples.positions[v as usize]));
    if longest.is_nan() || longest <= FINEST_SAMPLE * limit {
        return false;
    }
    if longest > limit {
        return true;
    }
    (0..2).any(|side| {
        let th = t.map(|v| samples.thickness[v as usize][side]);
        let thinnest = th.iter().copied().fold(f64::INFINITY, f64::min);
        let thickest = th.iter().copied().fold(0.0, f64::max);
        thinnest.is_finite() && thickest > thinnest * std::f64::consts::SQRT_2 && longest > thinnest
    })
}

/// The radius of the largest ball (up to `r_max`) touching the surface at `q` with its
/// centre along the unit direction `d`, by shrinking (Ma, Bae & Ponchio 2012): start at
/// `r_max`; while the ball holds a surface point `x`, shrink it to the ball through `q`
/// and `x`. A contact counts as across the part when it is at least
/// [`MIN_SEPARATION_DEG`] round the ball from `q` and on a triangle `far` from `q`;
/// the radius of the last such shrink is returned (infinity for none), and shrinking
/// stops at the first contact that does not count after one that did.
fn medial_radius(
    distance: &SurfaceDistance,
    q: [f64; 3],
    d: [f64; 3],
    r_max: f64,
    far: &dyn Fn(u32) -> bool,
) -> f64 {
    let min_cos = MIN_SEPARATION_DEG.to_radians().cos();
    let mut r = r_max;
    let mut across = f64::INFINITY;
    for _ in 0..MEDIAL_STEPS {
        let c = add(q, scale(d, r));
        // Only a surface point inside the ball shrinks it.
        let x = distance.closest_point_within(c, r);
        if x.distance.is_nan() || x.distance >= r * (1.0 - 1e-9) {
            break;
        }
        let (cq, cx) = (sub(q, c), sub(x.point, c));
        let separation = dot(cq, cx) / (norm(cq) * norm(cx));
        let qx = sub(x.point, q);
        let den = 2.0 * dot(d, qx);
        if den.is_nan() || den <= 0.0 {
            break;
        }
        let next = dot(qx, qx) / den;
        if next.is_nan() || next >= r {
            break;
        }
        if separation <= min_cos && far(x.face) {
            across = next;
        } else if across.is_finite() {
            break;
        }
        r = next;
    }
    across
}

/// Sizing features where the surface is thin, for each side (the solid behind it, the
/// gap in front), from the thickness sampled over it: over each sampled triangle whose
/// three corners are thin on that side (a plate, a wire, the walls of a slit), cells of
/// 1/[`CELLS_ACROSS`] of its middle corner's thickness, so the part is resolved between
/// its points too; at a thin point that no such triangle sizes as finely (on the rim of
/// a thin region, alone, or thinner than its neighbours), a point with its own. Each
/// faces its side and reaches half the thickness and one cell more: to the middle of the
/// part or gap (the other wall's features reach the rest), and one cell out the other
/// way. The octree's 2:1 balance grades the cells around them. A part or gap gets
/// [`CELLS_ACROSS`] cells across, but a thin part of the solid for the mesh of the gap
/// (`covered`: 0 for the mesh of the solid, 1 of the gap) [`CELLS_ACROSS_BEYOND`], no
/// coarser than `h / 2` and no finer than at [`CELLS_ACROSS`] (see there), and, with
/// `gap_floor`, a gap for the mesh of the solid no finer than [`GAP_FLOOR_OF_H`] and
/// [`GAP_FLOOR_OF_SOLID`] allow (for a mesh whose topology is checked: a gap bridged at
/// one cell across is found and refined).
pub(super) fn thin_part_sizing(
    samples: &ThicknessSamples,
    covered: usize,
    h: f64,
    gap_floor: bool,
) -> Vec<SizingFeature> {
    let ThicknessSamples {
        positions,
        normals,
        thickness,
        triangles,
        ..
    } = samples;
    let mut out = Vec::new();
    // Side 0 is the solid (against the outward normal), side 1 the gap.
    for (side, sign) in [(0, -1.0), (1, 1.0)] {
        let beyond = side == 0 && covered == 1;
        let gap_in_solid = side == 1 && covered == 0;
        // `solid`: the thickness of the solid behind the wall (infinite where thick).
        let feature = |corners: [[f64; 3]; 3], t: f64, reach: f64, toward: [f64; 3], solid: f64| {
            let spacing = if beyond {
                (t / CELLS_ACROSS_BEYOND).min(0.5 * h).max(t / CELLS_ACROSS)
            } else if gap_in_solid && gap_floor {
                let floor = (GAP_FLOOR_OF_H * h).min(GAP_FLOOR_OF_SOLID * solid).min(t);
                (t / CELLS_ACROSS).max(floor)
            } else {
                t / CELLS_ACROSS
            };
            SizingFeature {
                corners,
                spacing,
                reach: 0.5 * reach + spacing,
                toward,
            }
        };
        // Per point: the coarsest thickness a triangle over it was sized for (infinite
        // when some triangle at it is not all thin, or none is).
        let mut covered_by = vec![None::<f64>; thickness.len()];
        for tri in triangles {
            let mut t = tri.map(|v| thickness[v as usize][side]);
            let all_thin = t.iter().all(|x| x.is_finite());
            t.sort_unstable_by(f64::total_cmp);
            // The middle corner: one outlier corner neither coarsens nor refines it.
            let sized = if all_thin { t[1] } else { f64::INFINITY };
            for &v in tri {
                let c = &mut covered_by[v as usize];
                *c = Some(c.map_or(sized, |c| c.max(sized)));
            }
            if all_thin {
                let mut solid = tri.map(|v| thickness[v as usize][0]);
                solid.sort_unstable_by(f64::total_cmp);
                let corners = tri.map(|v| positions[v as usize]);
                let normal = unit(crate::geom::cross(
                    sub(corners[1], corners[0]),
                    sub(corners[2], corners[0]),
                ));
                out.push(feature(corners, t[1], t[2], scale(normal, sign), solid[1]));
            }
        }
        for (v, t) in thickness.iter().enumerate() {
            let (solid, t) = (t[0], t[side]);
            let covered = covered_by[v].unwrap_or(f64::INFINITY);
            if t.is_finite() && t * std::f64::consts::SQRT_2 < covered {
                let toward = scale(normals[v], sign);
                out.push(feature([positions[v]; 3], t, t, toward, solid));
            }
        }
    }
    out
}

/// The surface's creases (edges whose two faces turn by more than [`CREASE_DEG`]) and
/// corners (vertices where other than two creases meet: a crease's end, or three and
/// more), for the mesher to snap its boundary onto.
pub(super) fn sharp_features(surface: &SurfaceMesh, topology: &Topology) -> SharpFeatures {
    let min_cos = CREASE_DEG.to_radians().cos();
    let normals: Vec<[f64; 3]> = (0..surface.num_triangles())
        .map(|f| {
            let n = surface.face_normal_scaled(f);
            let l = norm(n);
            if l > 0.0 {
                scale(n, 1.0 / l)
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let mut creases_at = vec![0u32; surface.num_vertices()];
    let mut features = SharpFeatures::default();
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        let faces = topology.edge_faces(e);
        if faces.len() != 2 {
            continue;
        }
        let (n0, n1) = (normals[faces[0] as usize], normals[faces[1] as usize]);
        if n0 == [0.0; 3] || n1 == [0.0; 3] || dot(n0, n1) >= min_cos {
            continue;
        }
        features
            .edges
            .push([surface.positions[a as usize], surface.positions[b as usize]]);
        creases_at[a as usize] += 1;
        creases_at[b as usize] += 1;
    }
    for (v, &n) in creases_at.iter().enumerate() {
        if n == 1 || n >= 3 {
            features.corners.push(surface.positions[v]);
        }
    }
    features
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::closest_on_triangle;

    /// A slab 40 × 40 × 1.5 with a flange 10 × 40 × 0.5 along one side (the L-shaped
    /// profile (0,0) (50,0) (50,0.5) (40,0.5) (40,1.5) (0,1.5) in x–z, extruded 40
    /// along y), drawn with as few triangles as it takes: the bottom is two triangles
    /// from the slab's edge to the flange's, as a CAD export draws it.
    fn stepped_plate() -> SurfaceMesh {
        let profile = [
            [0.0, 0.0],
            [50.0, 0.0],
            [50.0, 0.5],
            [40.0, 0.5],
            [40.0, 1.5],
            [0.0, 1.5],
        ];
        prism(&profile, &[0.0, 40.0])
    }

    /// The closed prism of a profile in x–z (star-shaped from its first corner)
    /// extruded along y through `rows`, its caps fans from that corner, oriented
    /// outward.
    fn prism(profile: &[[f64; 2]], rows: &[f64]) -> SurfaceMesh {
        let n = profile.len() as u32;
        let mut positions = Vec::new();
        for &y in rows {
            positions.extend(profile.iter().map(|&[x, z]| [x, y, z]));
        }
        let mut triangles = Vec::new();
        for row in 0..rows.len() as u32 - 1 {
            let (a, b) = (row * n, (row + 1) * n);
            for i in 0..n {
                let j = (i + 1) % n;
                triangles.push([a + i, a + j, b + j]);
                triangles.push([a + i, b + j, b + i]);
            }
        }
        let last = (rows.len() as u32 - 1) * n;
        for k in 1..n - 1 {
            triangles.push([0, k + 1, k]);
            triangles.push([last, last + k, last + k + 1]);
        }
        let mut mesh = SurfaceMesh::new(positions, triangles).unwrap();
        if mesh.signed_volume() < 0.0 {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
        mesh
    }

    #[test]
    fn a_flange_drawn_with_long_triangles_is_sized_over_the_flange_only() {
        let plate = stepped_plate();
        assert!((plate.signed_volume() - (40.0 * 40.0 * 1.5 + 10.0 * 40.0 * 0.5)).abs() < 1e-9);
        let topology = Topology::new(&plate);
        let distance = SurfaceDistance::new(&plate);
        let skip = vec![false; plate.num_vertices()];
        // Both the slab (1.5) and the flange (0.5) are thin below this limit.
        let limit = 2.0;
        let at_vertices = thickness(&plate, &topology, &distance, &skip, limit);
        let start = ThicknessSamples::at_vertices(&plate, &at_vertices);
        let samples = sample_thickness(&plate, &topology, &distance, &start, &skip, limit);
        assert!(samples.positions.len() > plate.num_vertices() && !samples.bound);
        // Every point measured on the flange's bottom or top, away from its edges,
        // has the solid 0.5 thick behind it; on the slab's bottom, 1.5.
        let (mut on_flange, mut on_slab) = (0, 0);
        for (p, t) in samples.positions.iter().zip(&samples.thickness) {
            let inner_y = p[1] > 0.5 && p[1] < 39.5;
            let flat = p[2] == 0.0 || p[2] == 0.5;
            if inner_y && flat && p[0] > 40.5 && p[0] < 49.5 {
                assert!((t[0] - 0.5).abs() < 1e-6, "{p:?}: {t:?}");
                on_flange += 1;
            }
            if inner_y && p[2] == 0.0 && p[0] > 0.5 && p[0] < 38.0 {
                assert!((t[0] - 1.5).abs() < 1e-6, "{p:?}: {t:?}");
                on_slab += 1;
            }
        }
        assert!(on_flange > 20 && on_slab > 20, "{on_flange} {on_slab}");
        {
            let features = thin_part_sizing(&samples, 0, 0.5 * limit, true);
            let flange = |f: &&SizingFeature| f.spacing * CELLS_ACROSS < 1.0;
            // The flange's cells stay on the flange: no feature that fine reaches
            // more than a sample's spacing (limit / 2) into the slab ...
            for f in features.iter().filter(flange) {
                for c in f.corners {
                    assert!(c[0] >= 40.0 - 0.5 * limit, "{f:?}");
                }
                assert!(f.spacing * CELLS_ACROSS > 0.99 * 0.5, "{f:?}");
            }
            // ... and they cover the flange's bottom.
            for i in 0..19 {
                for j in 0..79 {
                    let p = [40.5 + 0.5 * i as f64, 0.5 + 0.5 * j as f64, 0.0];
                    let covered = features.iter().filter(flange).any(|f| {
                        let [a, b, c] = f.corners;
                        norm(sub(closest_on_triangle(p, a, b, c), p)) < 1e-9
                    });
                    assert!(covered, "{p:?} is not sized");
                }
            }
        }
        // Sized by its corners alone, a bottom triangle with two corners on the
        // flange asks for the flange's cells over the slab too.
        let spread = thin_part_sizing(&start, 0, 0.5 * limit, true)
            .iter()
            .filter(|f| f.spacing * CELLS_ACROSS < 1.0)
            .flat_map(|f| f.corners)
            .map(|c| c[0])
            .fold(f64::INFINITY, f64::min);
        assert!(spread < 1.0, "{spread}");
    }

    #[test]
    fn a_gap_asks_the_solid_for_cells_no_finer_than_its_floor() {
        // One triangle facing a gap `gap` wide with the solid `solid` thick behind it,
        // at h = 1: the spacing each mesh's features ask for.
        let spacing_with = |gap: f64, solid: f64, covered: usize, gap_floor: bool| {
            let samples = ThicknessSamples {
                positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                normals: vec![[0.0, 0.0, 1.0]; 3],
                thickness: vec![[solid, gap]; 3],
                triangles: vec![[0, 1, 2]],
                bound: false,
            };
            let features = thin_part_sizing(&samples, covered, 1.0, gap_floor);
            // Side 1 faces the gap: along the outward normal.
            let toward_gap: Vec<f64> = features
                .iter()
                .filter(|f| f.toward[2] > 0.0)
                .map(|f| f.spacing)
                .collect();
            assert_eq!(toward_gap.len(), 1, "{features:?}");
            toward_gap[0]
        };
        let spacing =
            |gap: f64, solid: f64, covered: usize| spacing_with(gap, solid, covered, true);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // The shell's mesh (the gap is its region) keeps two cells across.
        assert!(close(spacing(0.2, f64::INFINITY, 1), 0.1));
        // The solid's mesh: two across a gap down to h / 4 ...
        assert!(close(spacing(1.0, f64::INFINITY, 0), 0.5));
        // ... then h / 4, one cell across where the gap is narrower ...
        assert!(close(spacing(0.3, f64::INFINITY, 0), 0.25));
        assert!(close(spacing(0.1, f64::INFINITY, 0), 0.1));
        // ... and no coarser than a quarter of a thin solid behind the wall.
        assert!(close(spacing(0.3, 0.6, 0), 0.15));
        assert!(close(spacing(0.2, 0.2, 0), 0.1));
        // Without the floor (a mesh whose topology is not checked), two across.
        assert!(close(spacing_with(0.3, f64::INFINITY, 0, false), 0.15));
    }

    /// A block 10 × 10 × 10 (the profile in x–z extruded along y, rows at y = 0, 5, 10)
    /// whose side x = 10 is drawn, just below the top edge, with a strip of sliver
    /// triangles that zigzag by 10⁻⁴ (the profile (10, 10) → (10.0001, 9.995) →
    /// (9.9999, 9.99) → (10, 0)), as a CAD export draws a fillet's end.
    fn block_with_a_zigzag_under_its_edge() -> SurfaceMesh {
        let profile = [
            [0.0, 0.0],
            [10.0, 0.0],
            [9.9999, 9.99],
            [10.0001, 9.995],
            [10.0, 10.0],
            [0.0, 10.0],
        ];
        prism(&profile, &[0.0, 5.0, 10.0])
    }

    #[test]
    fn a_ray_that_skims_along_a_crease_measures_no_part() {
        let block = block_with_a_zigzag_under_its_edge();
        assert!((block.signed_volume() - 1000.0).abs() < 1e-2);
        let topology = Topology::new(&block);
        let distance = SurfaceDistance::new(&block);
        let skip = vec![false; block.num_vertices()];
        let limit = 2.0;
        // Rays into the solid from the top edge's corners and the zigzag's run down
        // the side and leave it through the zigzag a hundredth below, nearly along
        // its plane (without the incidence test: "thicknesses" of 0.011 and 0.017).
        // The block is 10 thick: nothing on it is thinner than the limit.
        let t = thickness(&block, &topology, &distance, &skip, limit);
        assert!(t.iter().flatten().all(|x| x.is_infinite()), "{t:?}");
        // A ray that meets a wall head-on crosses a part; one along it does not.
        let top = (0..block.num_triangles())
            .find(|&f| block.corners(f).iter().all(|c| c[2] == 10.0))
            .unwrap() as u32;
        assert!(faces_ray(&block, top, [0.0, 0.0, 1.0], -1.0));
        assert!(!faces_ray(&block, top, [0.0, 0.0, -1.0], -1.0));
        assert!(faces_ray(&block, top, [0.0, 0.0, -1.0], 1.0));
        assert!(!faces_ray(&block, top, [1.0, 0.0, 0.01], -1.0));
    }

    /// A square plate 20 × 20 × 3.2 with an octagonal hole of circumradius 1.9 through
    /// its middle, drawn with the hole's rim vertices alone (each wall of the hole two
    /// triangles from top to bottom, the top and bottom rings of quads out to eight
    /// points on the plate's edge), as a CAD export draws a drilled hole.
    fn plate_with_a_drilled_hole() -> SurfaceMesh {
        let (n, r, half, t) = (8usize, 1.9, 10.0, 3.2);
        let mut positions = Vec::new();
        // Per angle k: the rim's bottom and top, the edge's bottom and top.
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            let (c, s) = (a.cos(), a.sin());
            let edge = half / c.abs().max(s.abs());
            for (radius, z) in [(r, 0.0), (r, t), (edge, 0.0), (edge, t)] {
                positions.push([radius * c, radius * s, z]);
            }
        }
        let at = |k: usize, which: u32| (4 * (k % n)) as u32 + which;
        // Quads, each with the direction its outward normal should point along.
        let mut quads = Vec::new();
        for k in 0..n {
            let [ib, it, ob, ot] = [0, 1, 2, 3];
            let middle = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
            let radial = [middle.cos(), middle.sin(), 0.0];
            quads.push((
                [at(k, it), at(k + 1, it), at(k + 1, ot), at(k, ot)],
                [0.0, 0.0, 1.0],
            ));
            quads.push((
                [at(k, ib), at(k + 1, ib), at(k + 1, ob), at(k, ob)],
                [0.0, 0.0, -1.0],
            ));
            quads.push((
                [at(k, ib), at(k + 1, ib), at(k + 1, it), at(k, it)],
                scale(radial, -1.0),
            ));
            quads.push(([at(k, ob), at(k + 1, ob), at(k + 1, ot), at(k, ot)], radial));
        }
        let mut triangles = Vec::new();
        for ([a, b, c, d], toward) in quads {
            for mut tri in [[a, b, c], [a, c, d]] {
                let p = tri.map(|v| positions[v as usize]);
                let normal = crate::geom::cross(sub(p[1], p[0]), sub(p[2], p[0]));
                if dot(normal, toward) < 0.0 {
                    tri.swap(1, 2);
                }
                triangles.push(tri);
            }
        }
        SurfaceMesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn a_hole_drawn_with_its_rim_alone_is_measured_on_its_walls() {
        let plate = plate_with_a_drilled_hole();
        let (r, t) = (1.9, 3.2);
        let apothem = r * (std::f64::consts::PI / 8.0).cos();
        let octagon = 0.5 * 8.0 * r * r * (std::f64::consts::TAU / 8.0).sin();
        assert!((plate.signed_volume() - (400.0 - octagon) * t).abs() < 1e-9);
        let topology = Topology::new(&plate);
        let distance = SurfaceDistance::new(&plate);
        let skip = vec![false; plate.num_vertices()];
        let limit = 10.0;
        let samples = measure_surface(&plate, &topology, &distance, &skip, limit);
        // The rim's vertex normals lean halfway out of the hole: no vertex sees it.
        let on_rim = |p: [f64; 3]| (norm([p[0], p[1], 0.0]) - r).abs() < 1e-9;
        for (p, th) in samples.positions.iter().zip(&samples.thickness) {
            if on_rim(*p) {
                assert!(th[1].is_infinite(), "{p:?}: {th:?}");
            }
        }
        // The middle of every wall of the hole measures the width across it.
        let n = plate.num_vertices();
        let mut walls = 0;
        for (p, th) in samples.positions[n..].iter().zip(&samples.thickness[n..]) {
            if norm([p[0], p[1], 0.0]) < r {
                assert!((th[1] - 2.0 * apothem).abs() < 1e-9, "{p:?}: {th:?}");
                walls += 1;
            }
        }
        assert_eq!(walls, 16);
        // The middles lie on no triangle: the triangles are the surface's.
        assert_eq!(samples.triangles, plate.triangles);
        // The gap's mesh and the solid's get cells of half the width in the hole.
        for covered in [0, 1] {
            let hole = thin_part_sizing(&samples, covered, 0.5 * limit, true)
                .into_iter()
                // Facing the hole's axis: into the gap.
                .filter(|f| f.toward[2] == 0.0 && dot(f.toward, f.corners[0]) < 0.0)
                .filter(|f| f.corners.iter().all(|c| norm([c[0], c[1], 0.0]) < r + 1e-9))
                .map(|f| f.spacing)
                .fold(f64::INFINITY, f64::min);
            assert!((hole - apothem).abs() < 1e-9, "{hole}");
        }
        // The gap's mesh takes the plate at one cell across, the solid's at two; the
        // features are made in the same order for both.
        let h = 0.5 * limit;
        let solid = thin_part_sizing(&samples, 0, h, true);
        let gap = thin_part_sizing(&samples, 1, h, true);
        assert_eq!(solid.len(), gap.len());
        let coarser = CELLS_ACROSS / CELLS_ACROSS_BEYOND;
        let (mut same, mut coarse) = (0, 0);
        for (g, s) in gap.iter().zip(&solid) {
            if g.spacing == s.spacing {
                same += 1;
            } else {
                let bounded = (coarser * s.spacing).min(0.5 * h).max(s.spacing);
                assert_eq!(g.spacing, bounded, "{g:?} {s:?}");
                coarse += 1;
            }
        }
        assert!(same > 0 && coarse > 0, "{same} {coarse}");
    }
}
