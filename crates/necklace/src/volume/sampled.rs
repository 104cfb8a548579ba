//! A mesher whose size follows the boundary: the Delaunay tetrahedralization of points
//! sampled on the boundary and graded inside, carved by the domain.
//!
//! Isosurface stuffing needs lattice cells of half a part's thickness everywhere along a
//! thin part, in all three directions, so a plate costs its area over the thickness
//! squared. Here the points follow the boundary instead: the surface is sampled at the
//! local spacing (the thickness and gaps where they are thin, `h` elsewhere), and the
//! inside is filled with points whose spacing grows with the distance to the boundary.
//! The Delaunay tetrahedralization of all of them (`delaunay`) is carved by the domain:
//! a tet is kept when its centroid is inside. A tet across a thin gap has its centroid in
//! the gap and is dropped, whatever the spacing; a plate gets tets from face to face.
//! This replaces the paper's TetGen step (sec. 4) like stuffing does; unlike TetGen's
//! constrained tetrahedralization, the boundary is made of faces of the Delaunay
//! tetrahedralization itself by bisecting the triangles that are not (a conforming
//! Delaunay tetrahedralization), so the boundary vertices are all samples.
//!
//! Steps:
//! 1. The boundary: the surface's triangles bisected at their longest edge until no edge
//!    is longer than the spacing at the piece ([`bisect_triangles`]; the spacing from
//!    the thickness sampled over the triangles, growing by [`GRADING`] away from thin
//!    places, at most `h`), pieces split where a neighbour's point lies on their edge so
//!    that they conform; for the shell, the sphere too ([`sphere_mesh`]).
//! 2. The interior points: an octree over the domain's bounds, cells split while larger
//!    than the spacing at their centre ([`SpacingField`]: the samples' spacing near
//!    them, growing by [`GRADING`] with the distance); the centre of each leaf deeper
//!    than [`MIN_DEPTH`] of its spacing inside is a point, unless it lies in a boundary
//!    triangle's diametral ball.
//! 3. Delaunay tetrahedralization of all of them (`delaunay`), and the boundary
//!    recovered: triangles that are not faces of it are flipped where it took the other
//!    diagonal of a flat pair, else bisected (in every triangle that shares the edge)
//!    and the midpoints inserted, for at most [`RECOVERY_ROUNDS`] rounds while the
//!    number missing falls ([`SampledStats::missing_triangles`] says what is left).
//! 4. Carving: tets whose centroid's domain value is negative are kept. Where every
//!    boundary triangle is a face, the kept tets are bounded by the bisected surface.
//! 5. Vertex kinds from the carved mesh's boundary ([`Domain::boundary_kind`] there).
//! 6. `chords`: edges between two boundary vertices across the inside are split, so a
//!    thin part keeps a layer of interior vertices.
//! 7. `quality`: interior vertices move to raise the smallest dihedral angles (the
//!    samples stay), unless more than [`MAX_MISSING_FOR_QUALITY`] of the boundary was
//!    left unrecovered.
//!
//! **Status: experimental** (`--mesher sampled`). On surfaces drawn with well-shaped
//! triangles (the shared torus, fertility, ps_cube_with_hole) every boundary triangle
//! is recovered and the mesh has the surface's topology and volume. On surfaces with
//! long thin triangles (marching-tetrahedra shapes, CAD plates such as
//! ps_mk3_bed.stl) the bisected triangles are not Delaunay on the surface, most are
//! not faces of the tetrahedralization, and bisecting them does not converge: the
//! rounds stop, a warning counts what is missing, and the topology check says the
//! rest. The next step is a surface triangulation that is Delaunay before the
//! recovery (edge flips on the bisected surface), and a criterion that asks whether an
//! edge crosses a triangle rather than whether the triangle is a face. The samples are
//! isotropic, so a plate costs its area over its thickness squared here too: the 39
//! plates of mf_Offset1.obj (about 2 thick, 1.7 M in area) ask for 3.6 M boundary
//! points, and the run is refused over budget (`necklace volume
//! ../shared/data/realworld/mf_Offset1.obj --mesher sampled`).
//!
//! Conventions: lengths in the domain's units; output tets positively oriented. Entry
//! point: [`mesh_sampled`]. Sequential where the order matters (insertion, chords,
//! quality's visit order): the result does not depend on the thread count.

use std::time::Instant;

use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;
use serde::{Deserialize, Serialize};

use super::chords::split_chords;
use super::delaunay::Tetrahedralization;
use super::domains::Domain;
use super::quality::{improve, Mobility, QualityStats};
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, cross, dot, norm, scale, sub};
use crate::tet::{renumber_used, TetMesh, VertexKind};

/// The spacing grows by this much per unit of distance from the boundary samples.
pub const GRADING: f64 = 0.5;

/// An octree leaf's centre is an interior point when it is at least this fraction of its
/// spacing inside: nearer, it would make flat tets with the boundary samples.
pub const MIN_DEPTH: f64 = 0.25;

/// A point on the boundary and the spacing wanted there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The point, on the domain's boundary.
    pub position: [f64; 3],
    /// The spacing of the samples around it.
    pub spacing: f64,
}

/// Options of [`mesh_sampled`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledOptions {
    /// The coarsest spacing of interior points (default: unbounded).
    pub max_spacing: f64,
    /// Most tets (the memory budget): a point set estimated over it is refused.
    pub max_tets: usize,
    /// The quality step's target smallest dihedral angle, degrees (default 10; 0: off).
    pub min_dihedral_deg: f64,
}

impl Default for SampledOptions {
    fn default() -> Self {
        SampledOptions {
            max_spacing: f64::INFINITY,
            max_tets: usize::MAX,
            min_dihedral_deg: 10.0,
        }
    }
}

/// The quality step runs when at most this fraction of the boundary triangles is left
/// unrecovered.
pub const MAX_MISSING_FOR_QUALITY: f64 = 0.01;

/// What a run of the sampled mesher (`volume::sampled`, `--mesher sampled`) did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SampledStats {
    /// Samples on the boundary.
    pub boundary_points: usize,
    /// Boundary triangles (bisected to the spacing, then until they are faces of the
    /// tetrahedralization).
    pub boundary_triangles: usize,
    /// Boundary triangles still not faces of the tetrahedralization after
    /// the recovery rounds (at most 12).
    pub missing_triangles: usize,
    /// Rounds of bisection the recovery took.
    pub recovery_rounds: usize,
    /// Points inside (octree leaf centres).
    pub interior_points: usize,
    /// Interior points dropped for lying in a boundary triangle's diametral ball.
    pub encroaching_points: usize,
    /// Points not inserted: the same position as an earlier one.
    pub duplicates: usize,
    /// Tets of the Delaunay tetrahedralization.
    pub delaunay_tets: usize,
    /// Tets kept by the carving.
    pub kept_tets: usize,
    /// Interior points the carving left on the boundary.
    pub exposed_points: usize,
    /// Chords split (see `chords`).
    pub chords_split: usize,
    /// What the quality step did.
    pub quality: QualityStats,
    /// Seconds: interior points, Delaunay, carving and kinds, chords and quality.
    pub seconds: [f64; 4],
}

/// The wanted spacing at any point: the boundary samples' spacing, growing by
/// [`GRADING`] with the distance from them, bounded by the coarsest (`coarse`):
/// `min(coarse, minᵢ sᵢ + GRADING·|p − qᵢ|)`. An additively weighted nearest-sample
/// query, answered exactly by branch and bound over a tree of the samples finer than
/// `coarse`: a node is skipped when its finest spacing plus the graded distance to its
/// box cannot beat the best found. A bucket grid scanned every sample in reach, which
/// on a thin plate (fine samples by the hundred thousand within `coarse / GRADING`)
/// made each query cost as much as the mesh.
pub struct SpacingField {
    samples: Vec<Sample>,
    /// Nodes in depth-first order; node 0 is the root (none without fine samples).
    nodes: Vec<SpacingNode>,
    /// The coarsest sample spacing (the value away from finer samples).
    coarse: f64,
}

/// A node of [`SpacingField`]'s tree: the box and finest spacing of `samples[range]`;
/// an inner node's children are the next node and `second`.
#[derive(Debug, Clone, Copy)]
struct SpacingNode {
    lo: [f64; 3],
    hi: [f64; 3],
    finest: f64,
    range: (u32, u32),
    /// The second child (0 for a leaf: node 0 is the root, never a child).
    second: u32,
}

/// Most samples in a leaf of [`SpacingField`]'s tree.
const LEAF_SAMPLES: usize = 8;

impl SpacingField {
    /// The field of `samples` (whose spacings are at most `coarse`).
    pub fn new(samples: &[Sample], coarse: f64) -> SpacingField {
        let mut fine: Vec<Sample> = samples
            .iter()
            .filter(|s| s.spacing < coarse)
            .copied()
            .collect();
        let mut nodes = Vec::new();
        if !fine.is_empty() {
            build_spacing_tree(&mut fine, 0, &mut nodes);
        }
        SpacingField {
            samples: fine,
            nodes,
            coarse,
        }
    }

    /// The spacing wanted at `p`.
    pub fn at(&self, p: [f64; 3]) -> f64 {
        let mut best = self.coarse;
        if self.nodes.is_empty() {
            return best;
        }
        let bound = |n: &SpacingNode| {
            let d2: f64 = (0..3)
                .map(|k| (n.lo[k] - p[k]).max(p[k] - n.hi[k]).max(0.0).powi(2))
                .sum();
            n.finest + GRADING * d2.sqrt()
        };
        let mut stack = vec![(bound(&self.nodes[0]), 0usize)];
        while let Some((lower, i)) = stack.pop() {
            // (With room for rounding: a box's distance and a sample's are computed
            // apart, and the answer must be the exact minimum.)
            if lower > best * (1.0 + 1e-12) {
                continue;
            }
            let node = &self.nodes[i];
            if node.second == 0 {
                for q in &self.samples[node.range.0 as usize..node.range.1 as usize] {
                    best = best.min(q.spacing + GRADING * norm(sub(p, q.position)));
                }
                continue;
            }
            let (a, b) = (i + 1, node.second as usize);
            let (la, lb) = (bound(&self.nodes[a]), bound(&self.nodes[b]));
            // The nearer child last, so that it is taken first.
            if la <= lb {
                stack.push((lb, b));
                stack.push((la, a));
            } else {
                stack.push((la, a));
                stack.push((lb, b));
            }
        }
        best
    }
}

/// Append the node of `samples` (which start at index `offset` of the field's samples)
/// and its subtree to `nodes`, reordering `samples` by a median split along the box's
/// longest side.
fn build_spacing_tree(samples: &mut [Sample], offset: usize, nodes: &mut Vec<SpacingNode>) {
    let (lo, hi) = crate::geom::bounds(samples.iter().map(|s| s.position));
    let finest = samples
        .iter()
        .map(|s| s.spacing)
        .fold(f64::INFINITY, f64::min);
    let me = nodes.len();
    nodes.push(SpacingNode {
        lo,
        hi,
        finest,
        range: (offset as u32, (offset + samples.len()) as u32),
        second: 0,
    });
    if samples.len() <= LEAF_SAMPLES {
        return;
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mid = samples.len() / 2;
    samples.select_nth_unstable_by(mid, |a, b| a.position[axis].total_cmp(&b.position[axis]));
    let (left, right) = samples.split_at_mut(mid);
    build_spacing_tree(left, offset, nodes);
    nodes[me].second = nodes.len() as u32;
    build_spacing_tree(right, offset + mid, nodes);
}

/// The kinds of a carved mesh's vertices: interior, or the domain's kind of boundary.
pub(super) fn vertex_kinds(
    domain: &dyn Domain,
    positions: &[[f64; 3]],
    interior: &[bool],
) -> Vec<VertexKind> {
    positions
        .iter()
        .zip(interior)
        .map(|(p, &inside)| {
            if inside {
                VertexKind::Interior
            } else {
                domain.boundary_kind(*p)
            }
        })
        .collect()
}

/// Mesh `domain` by the Delaunay tetrahedralization of `samples` (points on its
/// boundary, with their spacing) and interior points graded from them; `field` gives
/// the spacing near the boundary (built from the samples).
pub fn mesh_sampled(
    domain: &dyn Domain,
    boundary: &BoundaryMesh,
    samples: &[Sample],
    field: &SpacingField,
    options: &SampledOptions,
) -> Result<(TetMesh, SampledStats)> {
    if samples.len() < 4 {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!("{} boundary samples cannot bound a volume", samples.len()),
        ));
    }
    let mut stats = SampledStats {
        boundary_points: samples.len(),
        ..SampledStats::default()
    };
    let clock = Instant::now();

    // 1. Interior points.
    let interior = interior_points(domain, field, options)?;
    let before = interior.len();
    let coarsest = samples.iter().map(|s| s.spacing).fold(0.0, f64::max);
    let interior = outside_diametral_balls(interior, boundary, coarsest);
    stats.interior_points = interior.len();
    stats.encroaching_points = before - interior.len();
    // About 6.5 tets per point in a Delaunay tetrahedralization, fewer after carving.
    let estimate = 7 * (samples.len() + interior.len());
    if estimate > options.max_tets {
        return Err(Error::new(
            ErrorKind::OverBudget,
            format!(
                "the sampled volume mesh needs about {estimate} tets ({} boundary and {} interior points), over the budget of {}",
                samples.len(),
                interior.len(),
                options.max_tets
            ),
        ));
    }
    stats.seconds[0] = clock.elapsed().as_secs_f64();

    // 2. Delaunay, and the boundary's triangles recovered as its faces.
    let clock = Instant::now();
    let mut boundary = boundary.clone();
    let nb = boundary.positions.len();
    let mut dt = Tetrahedralization::new(domain.bounds());
    stats.duplicates = dt.insert(&boundary.positions).len();
    stats.duplicates += dt.insert(&interior).len();
    // Points of the boundary mesh from here on are numbered after the interior ones.
    let mut positions: Vec<[f64; 3]> = boundary.positions.clone();
    positions.extend(&interior);
    let (added, missing, rounds) = recover_boundary(&mut boundary, &mut positions, &mut dt, nb);
    stats.boundary_points += added;
    stats.missing_triangles = missing;
    stats.recovery_rounds = rounds;
    stats.boundary_triangles = boundary.triangles.len();
    let all = dt.tets();
    stats.delaunay_tets = all.len();
    stats.seconds[1] = clock.elapsed().as_secs_f64();

    // 3. Carving by the centroid's sign.
    let clock = Instant::now();
    let centroids: Vec<[f64; 3]> = all
        .par_iter()
        .map(|t| {
            let p = t.map(|v| positions[v as usize]);
            scale(add(add(p[0], p[1]), add(p[2], p[3])), 0.25)
        })
        .collect();
    let values = domain.values(&centroids);
    let kept: Vec<[u32; 4]> = all
        .iter()
        .zip(&values)
        .filter(|(_, v)| **v < 0.0)
        .map(|(t, _)| *t)
        .collect();
    stats.kept_tets = kept.len();
    let (new_of_old, old_of_new) = renumber_used(positions.len(), &kept);
    let mut tets: Vec<[u32; 4]> = kept
        .iter()
        .map(|t| t.map(|v| new_of_old[v as usize]))
        .collect();
    let mut positions: Vec<[f64; 3]> = old_of_new.iter().map(|&v| positions[v as usize]).collect();
    let is_sample: Vec<bool> = old_of_new
        .iter()
        .map(|&v| (v as usize) < nb || v as usize >= nb + interior.len())
        .collect();

    // 4. Kinds: on the carved boundary or not.
    let mut on_boundary = vec![false; positions.len()];
    for f in crate::tet::boundary_faces_of(tets.iter().copied()) {
        for v in f {
            on_boundary[v as usize] = true;
        }
    }
    stats.exposed_points = (0..positions.len())
        .filter(|&v| on_boundary[v] && !is_sample[v])
        .count();
    stats.seconds[2] = clock.elapsed().as_secs_f64();

    // 5. Chords, 6. quality.
    let clock = Instant::now();
    let mut interior_flags: Vec<bool> = on_boundary.iter().map(|b| !b).collect();
    stats.chords_split = split_chords(&mut positions, &mut tets, &mut interior_flags);
    let mobility: Vec<Mobility> = (0..positions.len())
        .map(|v| {
            // The samples stay where they are: a tet of four samples is not in any
            // interior vertex's row of the Laplacian, and moving along the boundary
            // costs a projection per trial.
            if interior_flags[v] {
                Mobility::Free
            } else {
                Mobility::Fixed
            }
        })
        .collect();
    // Where much of the boundary was not recovered the carved tets cross it in flat
    // slivers that no interior move mends: the step would spend its rounds on them
    // (minutes on a plate drawn with long triangles), so it is left out above
    // [`MAX_MISSING_FOR_QUALITY`] of the triangles.
    let few_missing =
        stats.missing_triangles as f64 <= MAX_MISSING_FOR_QUALITY * stats.boundary_triangles as f64;
    if options.min_dihedral_deg > 0.0 && few_missing {
        stats.quality = improve(
            &mut positions,
            &tets,
            &mobility,
            &|p| domain.project(p),
            options.min_dihedral_deg,
        );
    }
    let kinds = vertex_kinds(domain, &positions, &interior_flags);
    stats.seconds[3] = clock.elapsed().as_secs_f64();
    let mesh = TetMesh::new(positions, tets, kinds)?;
    Ok((mesh, stats))
}

/// The interior points: centres of the leaves of an octree over the domain's bounds,
/// split while larger than the spacing at their centre, at least [`MIN_DEPTH`] of that
/// spacing inside. Sorted by position, so the set does not depend on the thread count.
fn interior_points(
    domain: &dyn Domain,
    field: &SpacingField,
    options: &SampledOptions,
) -> Result<Vec<[f64; 3]>> {
    let (lo, hi) = domain.bounds();
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let centre = scale(add(lo, hi), 0.5);
    let mut cells = vec![(centre, size)];
    let mut points = Vec::new();
    while !cells.is_empty() {
        let centres: Vec<[f64; 3]> = cells.iter().map(|c| c.0).collect();
        let values = domain.values(&centres);
        let wanted: Vec<f64> = centres
            .par_iter()
            .zip(&values)
            .map(|(&c, &v)| field.at(c).max(GRADING * v.abs()).min(options.max_spacing))
            .collect();
        let mut next = Vec::new();
        for (i, &(c, a)) in cells.iter().enumerate() {
            let v = values[i];
            // Wholly outside: nothing of the domain in the cell.
            if v > 0.5 * 3f64.sqrt() * a {
                continue;
            }
            if a > wanted[i] {
                let q = 0.25 * a;
                for corner in 0..8 {
                    let d = [corner & 1, corner >> 1 & 1, corner >> 2 & 1].map(|b| {
                        if b == 1 {
                            q
                        } else {
                            -q
                        }
                    });
                    next.push((add(c, d), 0.5 * a));
                }
            } else if v < -MIN_DEPTH * wanted[i] {
                points.push(c);
            }
        }
        if next.len() + points.len() > options.max_tets / 6 {
            return Err(Error::new(
                ErrorKind::OverBudget,
                format!(
                    "the sampled volume mesh's interior needs more than {} points, over the budget of {} tets",
                    next.len() + points.len(),
                    options.max_tets
                ),
            ));
        }
        cells = next;
    }
    points.sort_unstable_by(|a, b| a.partial_cmp(b).expect("finite"));
    Ok(points)
}

/// The boundary as triangles (the surface's, bisected to the spacing; the sphere's),
/// whose corners are the samples.
#[derive(Debug, Clone, Default)]
pub struct BoundaryMesh {
    /// The samples' positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles over them.
    pub triangles: Vec<[u32; 3]>,
}

impl BoundaryMesh {
    /// Index of `p`, added if new (points are matched bit for bit: a midpoint made from
    /// the same two ends is the same point).
    fn point(&mut self, index: &mut HashMap<[u64; 3], u32>, p: [f64; 3]) -> u32 {
        *index.entry(p.map(f64::to_bits)).or_insert_with(|| {
            self.positions.push(p);
            (self.positions.len() - 1) as u32
        })
    }

    /// Append `other`'s triangles (its points renumbered after ours).
    pub fn extend(&mut self, other: &BoundaryMesh) {
        let n = self.positions.len() as u32;
        self.positions.extend(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + n)));
    }

    /// The samples: every point with the field's spacing there.
    pub fn samples(&self, field: &SpacingField) -> Vec<Sample> {
        self.positions
            .iter()
            .map(|&p| Sample {
                position: p,
                spacing: field.at(p),
            })
            .collect()
    }
}

/// The triangles (`positions`, `triangles`) bisected at their longest edge until no
/// edge is longer than the field's spacing at the piece's centroid.
pub fn bisect_triangles(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    field: &SpacingField,
) -> BoundaryMesh {
    let pieces: Vec<Vec<[[f64; 3]; 3]>> = triangles
        .par_iter()
        .map(|t| {
            let mut out = Vec::new();
            let mut stack = vec![t.map(|v| positions[v as usize])];
            while let Some(p) = stack.pop() {
                let split = longest_edge(p);
                let centroid = scale(add(add(p[0], p[1]), p[2]), 1.0 / 3.0);
                if split.1 > field.at(centroid) && out.len() + stack.len() < MAX_PIECES {
                    stack.extend(bisect(p, split.0));
                } else {
                    out.push(p);
                }
            }
            out
        })
        .collect();
    let mut mesh = BoundaryMesh::default();
    let mut index = HashMap::default();
    for p in positions {
        mesh.point(&mut index, *p);
    }
    for p in pieces.iter().flatten() {
        for q in p {
            mesh.point(&mut index, *q);
        }
    }
    // Pieces of two triangles split their shared edge to different depths: a piece
    // with another's point on its edge (that edge's midpoint, bit for bit) is split
    // there too, so the pieces form one conforming triangulation.
    for p in pieces.into_iter().flatten() {
        let t = p.map(|q| index[&q.map(f64::to_bits)]);
        split_at_hanging(t, &mesh.positions, &index, &mut mesh.triangles);
    }
    mesh
}

/// Bisect `t` at an edge whose midpoint is a point of `index`, and its halves likewise.
fn split_at_hanging(
    t: [u32; 3],
    positions: &[[f64; 3]],
    index: &HashMap<[u64; 3], u32>,
    out: &mut Vec<[u32; 3]>,
) {
    for k in 0..3 {
        let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
        let m = scale(add(positions[a as usize], positions[b as usize]), 0.5);
        if let Some(&id) = index.get(&m.map(f64::to_bits)) {
            if id == a || id == b {
                continue;
            }
            let mut first = t;
            first[(k + 2) % 3] = id;
            let mut second = t;
            second[(k + 1) % 3] = id;
            split_at_hanging(first, positions, index, out);
            split_at_hanging(second, positions, index, out);
            return;
        }
    }
    out.push(t);
}

/// Most pieces one triangle is bisected into (a bound on a runaway field).
const MAX_PIECES: usize = 1 << 16;

/// The longest edge of a triangle, by the corner opposite it, and its length.
fn longest_edge(p: [[f64; 3]; 3]) -> (usize, f64) {
    (0..3)
        .map(|k| (k, norm(sub(p[(k + 1) % 3], p[(k + 2) % 3]))))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("three edges")
}

/// The two halves of a triangle bisected at the edge opposite corner `k`.
fn bisect(p: [[f64; 3]; 3], k: usize) -> [[[f64; 3]; 3]; 2] {
    let m = scale(add(p[(k + 1) % 3], p[(k + 2) % 3]), 0.5);
    let mut first = p;
    first[(k + 2) % 3] = m;
    let mut second = p;
    second[(k + 1) % 3] = m;
    [first, second]
}

/// The smallest sphere through a triangle's corners: its circumcentre and radius.
fn diametral_ball(p: [[f64; 3]; 3]) -> ([f64; 3], f64) {
    let a = sub(p[1], p[0]);
    let b = sub(p[2], p[0]);
    let n = cross(a, b);
    let nn = dot(n, n);
    if nn <= 0.0 {
        let (k, l) = longest_edge(p);
        return (scale(add(p[(k + 1) % 3], p[(k + 2) % 3]), 0.5), 0.5 * l);
    }
    let c = scale(
        add(scale(cross(n, a), dot(b, b)), scale(cross(b, n), dot(a, a))),
        0.5 / nn,
    );
    (add(p[0], c), norm(c))
}

/// Points in a grid of buckets, for "is any point inside this ball".
struct PointGrid {
    buckets: HashMap<[i64; 3], Vec<u32>>,
}

impl PointGrid {
    fn new(points: &[[f64; 3]], cell: f64) -> PointGrid {
        let mut buckets: HashMap<[i64; 3], Vec<u32>> = HashMap::default();
        for (i, p) in points.iter().enumerate() {
            buckets
                .entry(p.map(|x| (x / cell).floor() as i64))
                .or_default()
                .push(i as u32);
        }
        PointGrid { buckets }
    }
}

/// A triangle whose diametral ball's radius is over this many times its longest edge
/// (an obtuse sliver) keeps the points in its ball: it would take most of a thin part's.
const MAX_BALL: f64 = 2.0;

/// Most rounds of [`recover_boundary`].
pub const RECOVERY_ROUNDS: usize = 12;

/// Drop the points inside a boundary triangle's diametral ball (they would keep it
/// from being a Delaunay face). Returns the points kept.
pub fn outside_diametral_balls(
    points: Vec<[f64; 3]>,
    mesh: &BoundaryMesh,
    cell: f64,
) -> Vec<[f64; 3]> {
    let grid = PointGrid::new(&points, cell);
    let mut inside = vec![false; points.len()];
    let hits: Vec<Vec<u32>> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let p = t.map(|v| mesh.positions[v as usize]);
            let (c, r) = diametral_ball(p);
            if r > MAX_BALL * longest_edge(p).1 {
                return Vec::new();
            }
            let lo = c.map(|x| ((x - r) / cell).floor() as i64);
            let hi = c.map(|x| ((x + r) / cell).floor() as i64);
            let mut out = Vec::new();
            for i in lo[0]..=hi[0] {
                for j in lo[1]..=hi[1] {
                    for k in lo[2]..=hi[2] {
                        for &q in grid.buckets.get(&[i, j, k]).map_or(&[][..], |v| &v[..]) {
                            if norm(sub(points[q as usize], c)) < r {
                                out.push(q);
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    for q in hits.into_iter().flatten() {
        inside[q as usize] = true;
    }
    points
        .into_iter()
        .zip(inside)
        .filter(|(_, i)| !i)
        .map(|(p, _)| p)
        .collect()
}

/// The sphere of `radius` about `centre` as triangles about `spacing` long: an
/// icosahedron's faces split in `k × k` and pushed onto the sphere.
pub fn sphere_mesh(centre: [f64; 3], radius: f64, spacing: f64) -> BoundaryMesh {
    let (ico, faces) = crate::geom::icosahedron();
    // The icosahedron's edge is 1.05 radii.
    let k = ((1.05 * radius / spacing).ceil() as usize).clamp(1, 256);
    let mut seen: HashMap<[i64; 3], u32> = HashMap::default();
    let mut mesh = BoundaryMesh::default();
    for f in faces {
        let [a, b, c] = f.map(|i| ico[i as usize]);
        let mut id = |i: usize, j: usize, mesh: &mut BoundaryMesh| {
            let (u, v) = (i as f64 / k as f64, j as f64 / k as f64);
            let p = add(add(scale(a, 1.0 - u - v), scale(b, u)), scale(c, v));
            let q = add(centre, scale(p, radius / norm(p)));
            // Shared edges give the same point up to rounding.
            let key = q.map(|x| (x / (1e-6 * radius)).round() as i64);
            *seen.entry(key).or_insert_with(|| {
                mesh.positions.push(q);
                (mesh.positions.len() - 1) as u32
            })
        };
        for i in 0..k {
            for j in 0..(k - i) {
                let p = id(i, j, &mut mesh);
                let q = id(i + 1, j, &mut mesh);
                let r = id(i, j + 1, &mut mesh);
                mesh.triangles.push([p, q, r]);
                if j + 1 < k - i {
                    let s = id(i + 1, j + 1, &mut mesh);
                    mesh.triangles.push([q, s, r]);
                }
            }
        }
    }
    mesh
}

/// Bisect the boundary triangles that are not faces of the tetrahedralization, and
/// insert the midpoints, until all are (at most [`RECOVERY_ROUNDS`] rounds). The
/// longest edge of each missing triangle is split in every triangle that has it, so
/// the boundary stays a conforming triangulation. `positions` are the
/// tetrahedralization's points, of which the boundary's first `nb` are the first;
/// midpoints are appended to both. A round that does not lower the number missing ends
/// the rounds. Returns the points added, the triangles still missing and the rounds.
fn recover_boundary(
    boundary: &mut BoundaryMesh,
    positions: &mut Vec<[f64; 3]>,
    dt: &mut Tetrahedralization,
    nb: usize,
) -> (usize, usize, usize) {
    // The boundary mesh numbers its points as the tetrahedralization does.
    let n_interior = positions.len() - nb;
    boundary.triangles = boundary
        .triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                if (v as usize) < nb {
                    v
                } else {
                    v + n_interior as u32
                }
            })
        })
        .collect();
    boundary.positions = positions.clone();
    let mut added = 0;
    let mut missing = 0;
    let mut previous = usize::MAX;
    let mut rounds = 0;
    while rounds < RECOVERY_ROUNDS {
        let faces = dt.face_set();
        let is_face = |t: [u32; 3]| {
            let mut f = t;
            f.sort_unstable();
            faces.contains(&f)
        };
        flip_to_faces(&mut boundary.triangles, positions, &is_face);
        let mut split: rustc_hash::FxHashSet<[u32; 2]> = rustc_hash::FxHashSet::default();
        missing = 0;
        for t in &boundary.triangles {
            if is_face(*t) {
                continue;
            }
            missing += 1;
            let (k, _) = longest_edge(t.map(|v| positions[v as usize]));
            let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            split.insert([a.min(b), a.max(b)]);
        }
        rounds += 1;
        // A round that does not lower the count (coplanar, cocircular samples: the
        // tetrahedralization triangulates the plane with the other diagonal) ends them.
        if missing == 0 || missing >= previous {
            break;
        }
        previous = missing;
        let mut index: HashMap<[u64; 3], u32> = HashMap::default();
        let first = positions.len();
        let old = std::mem::take(&mut boundary.triangles);
        for t in old {
            split_marked(t, &split, positions, &mut index, &mut boundary.triangles);
        }
        let new_points: Vec<[f64; 3]> = positions[first..].to_vec();
        added += new_points.len();
        dt.insert(&new_points);
    }
    boundary.positions = positions.clone();
    (added, missing, rounds)
}

/// Bisect triangle `t` at its longest marked edge, and its halves likewise, until no
/// marked edge is left; midpoints are appended to `positions` (once each, by `index`).
fn split_marked(
    t: [u32; 3],
    marked: &rustc_hash::FxHashSet<[u32; 2]>,
    positions: &mut Vec<[f64; 3]>,
    index: &mut HashMap<[u64; 3], u32>,
    out: &mut Vec<[u32; 3]>,
) {
    let edge = |k: usize| {
        let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
        [a.min(b), a.max(b)]
    };
    let longest = (0..3)
        .filter(|&k| marked.contains(&edge(k)))
        .max_by(|&i, &j| {
            let len = |k: usize| {
                let e = edge(k);
                norm(sub(positions[e[0] as usize], positions[e[1] as usize]))
            };
            len(i).total_cmp(&len(j)).then(j.cmp(&i))
        });
    let Some(k) = longest else {
        out.push(t);
        return;
    };
    let e = edge(k);
    let m = scale(add(positions[e[0] as usize], positions[e[1] as usize]), 0.5);
    let id = *index.entry(m.map(f64::to_bits)).or_insert_with(|| {
        positions.push(m);
        (positions.len() - 1) as u32
    });
    let mut first = t;
    first[(k + 2) % 3] = id;
    let mut second = t;
    second[(k + 1) % 3] = id;
    split_marked(first, marked, positions, index, out);
    split_marked(second, marked, positions, index, out);
}

/// Two boundary triangles that are not faces of the tetrahedralization, share an edge
/// and lie in one plane (up to [`FLAT_TURN`]) while the other diagonal of their
/// quadrilateral gives two that are: the tetrahedralization triangulated the four
/// (cocircular) points the other way, which leaves the boundary where it was. Such
/// pairs are flipped to that diagonal.
fn flip_to_faces(
    triangles: &mut [[u32; 3]],
    positions: &[[f64; 3]],
    is_face: &dyn Fn([u32; 3]) -> bool,
) {
    let mut by_edge: HashMap<[u32; 2], Vec<u32>> = HashMap::default();
    for (i, t) in triangles.iter().enumerate() {
        if is_face(*t) {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            by_edge
                .entry([a.min(b), a.max(b)])
                .or_default()
                .push(i as u32);
        }
    }
    let mut edges: Vec<([u32; 2], Vec<u32>)> = by_edge.into_iter().collect();
    edges.sort_unstable();
    let mut flipped = vec![false; triangles.len()];
    let normal = |t: [u32; 3]| {
        let p = t.map(|v| positions[v as usize]);
        let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        scale(n, 1.0 / norm(n).max(f64::MIN_POSITIVE))
    };
    for (e, pair) in edges {
        let &[i, j] = &pair[..] else { continue };
        if flipped[i as usize] || flipped[j as usize] {
            continue;
        }
        let (t, u) = (triangles[i as usize], triangles[j as usize]);
        // t = (a, b, c) and u = (b, a, d) around their shared edge a–b.
        let k = (0..3)
            .find(|&k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])] == e)
            .expect("t has the edge");
        let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let Some(&d) = u.iter().find(|&&v| v != a && v != b) else {
            continue;
        };
        if dot(normal(t), normal(u)) < FLAT_TURN.cos() {
            continue;
        }
        let (x, y) = ([a, d, c], [d, b, c]);
        if is_face(x) && is_face(y) && dot(normal(x), normal(t)) > 0.0 {
            triangles[i as usize] = x;
            triangles[j as usize] = y;
            flipped[i as usize] = true;
            flipped[j as usize] = true;
        }
    }
}

/// Two triangles turning by less than this (radians) count as one plane for a flip.
const FLAT_TURN: f64 = 1e-6;

#[cfg(test)]
mod tests {
    use super::*;

    /// The tree's answer is the definition's, `min(coarse, minᵢ sᵢ + GRADING·|p − qᵢ|)`
    /// over every sample, on samples clustered on a thin plate (fine) and scattered
    /// (coarse), at points near and far.
    #[test]
    fn the_spacing_is_the_graded_minimum_over_all_samples() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let coarse = 4.0;
        let mut samples = Vec::new();
        for i in 0..3000 {
            let plate = i % 3 != 0;
            let position = if plate {
                [20.0 * next(), 20.0 * next(), 0.01 * next()]
            } else {
                [
                    40.0 * next() - 10.0,
                    40.0 * next() - 10.0,
                    40.0 * next() - 10.0,
                ]
            };
            let spacing = if plate {
                0.05 + 0.2 * next()
            } else {
                6.0 * next()
            };
            samples.push(Sample { position, spacing });
        }
        let field = SpacingField::new(&samples, coarse);
        for _ in 0..500 {
            let p = [
                60.0 * next() - 20.0,
                60.0 * next() - 20.0,
                30.0 * next() - 15.0,
            ];
            let brute = samples
                .iter()
                .map(|q| q.spacing + GRADING * norm(sub(p, q.position)))
                .fold(coarse, f64::min);
            assert_eq!(field.at(p), brute, "at {p:?}");
        }
        assert_eq!(SpacingField::new(&[], coarse).at([1.0, 2.0, 3.0]), coarse);
    }
}
