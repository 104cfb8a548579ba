//! What the volume stage measures on a surface for the mesher: at every vertex the
//! thickness of the solid and the width of the gap in front of it ([`thickness`]: a ray
//! along the normal, then the inscribed ball touching there), the sizing features that
//! ask for finer cells where either is below `2h` ([`thin_part_sizing`]), and the
//! creases and corners to snap onto ([`sharp_features`]). Folds of the surface and
//! places where it crosses itself are not parts, and are skipped.
//!
//! Conventions: lengths in the surface's units; thickness `[solid, gap]` per vertex,
//! infinite where not thin.

use super::{SharpFeatures, SizingFeature};
use crate::distance::SurfaceDistance;
use crate::geom::{add, dot, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// Parts and gaps thinner than this many `h` get finer cells (at `h`, two cells across).
pub(super) const THIN_FACTOR: f64 = 2.0;

/// Cells across a thin part or gap. Warping moves a vertex by at most 0.36 of a cell,
/// so two cells across leave a core of more than a cell whose lattice vertices stay
/// inside and connect along the part. (Where that is not enough, the topology check
/// finds it and refines.)
pub(super) const CELLS_ACROSS: f64 = 2.0;

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

/// For each surface vertex (but those marked `skip`), the thickness of the solid and the
/// width of the gap in front of it, each when below `limit` (else infinity), by
/// [`measure`] along the vertex normal. A contact or hit on a triangle at the vertex
/// does not count, nor a thickness below 1/[`FOLD_RATIO`] of the vertex's shortest edge
/// across to a triangle beside the vertex's own (a fold, not a part).
pub(super) fn thickness(
    surface: &SurfaceMesh,
    topology: &Topology,
    distance: &SurfaceDistance,
    skip: &[bool],
    limit: f64,
) -> Vec<[f64; 2]> {
    use rayon::prelude::*;
    let normals = vertex_normals(surface);
    let shortest = shortest_edges(surface);
    (0..surface.num_vertices())
        .into_par_iter()
        .map(|v| {
            let faces = topology.vertex_faces(v);
            if faces.is_empty() || skip[v] || normals[v] == [0.0; 3] {
                return [f64::INFINITY; 2];
            }
            let p = surface.positions[v];
            let v32 = v as u32;
            let far = |face: u32| {
                surface
                    .triangles
                    .get(face as usize)
                    .is_some_and(|t| !t.contains(&v32))
            };
            let ring = ring_of(surface, faces.iter().copied());
            let beside = |face: u32| touches(surface, face, &ring);
            let walls = Walls {
                far: &far,
                beside: &beside,
            };
            measure(surface, distance, p, normals[v], shortest[v], limit, &walls)
        })
        .collect()
}

/// The corners of `faces`, sorted, without repeats (a vertex's ring with the vertex).
fn ring_of(surface: &SurfaceMesh, faces: impl Iterator<Item = u32>) -> Vec<u32> {
    let mut ring: Vec<u32> = faces
        .filter_map(|f| surface.triangles.get(f as usize))
        .flatten()
        .copied()
        .collect();
    ring.sort_unstable();
    ring.dedup();
    ring
}

/// Whether `face` has a corner in the sorted `ring`.
fn touches(surface: &SurfaceMesh, face: u32, ring: &[u32]) -> bool {
    surface
        .triangles
        .get(face as usize)
        .is_some_and(|t| t.iter().any(|v| ring.binary_search(v).is_ok()))
}

/// Which triangles can be the other wall of a part at a point, for [`measure`].
struct Walls<'a> {
    /// Not at the point (a contact or hit on the point's own triangles does not count).
    far: &'a dyn Fn(u32) -> bool,
    /// Beside the point's own triangles: a wall there closer than 1/[`FOLD_RATIO`] of
    /// the shortest edge is a fold.
    beside: &'a dyn Fn(u32) -> bool,
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
/// `limit`; where it finds one on a triangle far from `p` (`walls`) that faces it
/// ([`faces_ray`]), the thickness is the
/// diameter of the largest ball touching the surface at `p` whose other contact lies
/// across the part (shrinking-ball medial distance, started from the ray's chord), or
/// the chord where no ball tells. A thickness below 1/[`FOLD_RATIO`] of `shortest`
/// across to a triangle beside `p`'s own is a fold of the surface, not a part
/// (infinity).
fn measure(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    p: [f64; 3],
    normal: [f64; 3],
    shortest: f64,
    limit: f64,
    walls: &Walls,
) -> [f64; 2] {
    let far = walls.far;
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
        let ball = 2.0 * medial_radius(distance, p, d, 0.5 * hit, far);
        let t = if ball.is_finite() { ball } else { hit };
        let fold = t * FOLD_RATIO < shortest && (walls.beside)(face);
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
    /// surface triangle need not share their edges' points with the next one's).
    pub triangles: Vec<[u32; 3]>,
    /// Whether [`MAX_SAMPLES`] stopped the splitting (pieces left that asked for more).
    pub bound: bool,
}

impl ThicknessSamples {
    /// The thickness at the surface's vertices alone (`thickness`: from [`thickness`]),
    /// over its triangles.
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

/// Sample the thickness over the surface where its vertices do not tell it: a triangle
/// (or piece) is split in four, and the thickness measured at its edges' midpoints,
/// while its longest edge exceeds `limit` (a thin part may pass between vertices that
/// far apart), or while on either side its corners disagree (thin at one and not at
/// another, or thinner by more than √2) and its longest edge exceeds the thinnest
/// corner's thickness (the change lies inside it at a scale the cells see), down to
/// pieces of [`FINEST_SAMPLE`] `× limit`. A plate's thin rim drawn with long triangles
/// reaching into the plate would otherwise ask for the rim's cells over those
/// triangles' whole area. Triangles with a `skip` corner (crossings) are not split. A
/// point added is a fold (not thin) where its thickness is below 1/[`FOLD_RATIO`] of
/// the shortest edge at any corner of its triangle across to a triangle beside it (a
/// corner on the corners' rings), as a vertex is against its own.
/// At most [`MAX_SAMPLES`] points are added (`bound` says when that stopped it).
pub(super) fn sample_thickness(
    surface: &SurfaceMesh,
    distance: &SurfaceDistance,
    vertex_thickness: &[[f64; 2]],
    skip: &[bool],
    limit: f64,
) -> ThicknessSamples {
    use rayon::prelude::*;
    use rustc_hash::FxHashMap;
    let shortest_edge = shortest_edges(surface);
    let topology = Topology::new(surface);
    let mut samples = ThicknessSamples {
        positions: surface.positions.clone(),
        normals: vertex_normals(surface),
        thickness: vertex_thickness.to_vec(),
        triangles: Vec::new(),
        bound: false,
    };
    // Pieces still to decide: corners and the surface triangle they lie on.
    let mut pieces: Vec<([u32; 3], u32)> = surface
        .triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| !t.iter().any(|&v| skip[v as usize]))
        .map(|(f, &t)| (t, f as u32))
        .collect();
    samples.triangles.extend(
        surface
            .triangles
            .iter()
            .filter(|t| t.iter().any(|&v| skip[v as usize])),
    );
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
                let home = surface.triangles[homes[i - first_new] as usize];
                let shortest = home
                    .iter()
                    .map(|&v| shortest_edge[v as usize])
                    .fold(f64::INFINITY, f64::min);
                // A wall on a triangle sharing a corner with the home triangle is the
                // surface turning there, not the other side of a part.
                let far = |face: u32| {
                    surface
                        .triangles
                        .get(face as usize)
                        .is_some_and(|t| !t.iter().any(|v| home.contains(v)))
                };
                let ring = ring_of(
                    surface,
                    home.iter()
                        .flat_map(|&v| topology.vertex_faces(v as usize).iter().copied()),
                );
                let beside = |face: u32| touches(surface, face, &ring);
                let walls = Walls {
                    far: &far,
                    beside: &beside,
                };
                let (p, n) = (samples.positions[i], samples.normals[i]);
                measure(surface, distance, p, n, shortest, limit, &walls)
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
/// way. The octree's 2:1 balance grades the cells around them.
pub(super) fn thin_part_sizing(samples: &ThicknessSamples) -> Vec<SizingFeature> {
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
        let feature = |corners: [[f64; 3]; 3], t: f64, reach: f64, toward: [f64; 3]| {
            let spacing = t / CELLS_ACROSS;
            SizingFeature {
                corners,
                spacing,
                reach: 0.5 * reach + spacing,
                toward,
            }
        };
        // Per point: the coarsest thickness a triangle over it was sized for (infinite
        // when some triangle at it is not all thin).
        let mut covered_by = vec![0.0f64; thickness.len()];
        for tri in triangles {
            let mut t = tri.map(|v| thickness[v as usize][side]);
            let all_thin = t.iter().all(|x| x.is_finite());
            t.sort_unstable_by(f64::total_cmp);
            // The middle corner: one outlier corner neither coarsens nor refines it.
            let sized = if all_thin { t[1] } else { f64::INFINITY };
            for &v in tri {
                covered_by[v as usize] = covered_by[v as usize].max(sized);
            }
            if all_thin {
                let corners = tri.map(|v| positions[v as usize]);
                let normal = unit(crate::geom::cross(
                    sub(corners[1], corners[0]),
                    sub(corners[2], corners[0]),
                ));
                out.push(feature(corners, t[1], t[2], scale(normal, sign)));
            }
        }
        for (v, t) in thickness.iter().enumerate() {
            let t = t[side];
            if t.is_finite() && t * std::f64::consts::SQRT_2 < covered_by[v] {
                out.push(feature([positions[v]; 3], t, t, scale(normals[v], sign)));
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
        let samples = sample_thickness(&plate, &distance, &at_vertices, &skip, limit);
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
            let features = thin_part_sizing(&samples);
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
        let corners_only = ThicknessSamples::at_vertices(&plate, &at_vertices);
        let spread = thin_part_sizing(&corners_only)
            .iter()
            .filter(|f| f.spacing * CELLS_ACROSS < 1.0)
            .flat_map(|f| f.corners)
            .map(|c| c[0])
            .fold(f64::INFINITY, f64::min);
        assert!(spread < 1.0, "{spread}");
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
}
