//! Critical points of a piecewise-linear function on a tet mesh from vertex links
//! (paper sec. 4.1).
//!
//! Order: surface vertices come below every interior vertex, outer-sphere vertices
//! above, and otherwise `(f, index)` decides (so ties are broken and the
//! classification is exact). For an interior vertex `v`, its link is the triangles
//! opposite `v` in its tets; the *upper* (*lower*) link is the part of the link above
//! (below) `v`, and its components are counted using only link edges whose two ends are
//! on the same side. Types: regular (1 up, 1 low), maximum (0, 1), minimum (1, 0),
//! 1-saddle (1, 2), 2-saddle (2, 1), anything else degenerate (a monkey saddle; its
//! counts are kept).
//!
//! Morse check: adding `v` to the lower-star filtration changes χ by `1 − χ(lower link)`
//! (= (−1)^index for a non-degenerate critical point, 0 for a regular one). Since the
//! surface comes first and the outer sphere last, the sum over interior vertices is
//! χ(K_{S∪I}) − χ(K_S) ([`expected_morse_sum`]): for a connected genus-g surface, g − 1
//! inside and g outside. Where the link is a triangulated 2-sphere (checked once per
//! link), χ(lower link) = lower − upper + 1: the lower and the upper link are full
//! subcomplexes on complementary vertices, so the sphere less the lower link retracts
//! onto the upper one, and Alexander duality gives b1(lower) = b0(upper) − 1 (an empty
//! side gives 0 or 2 by the same formula). Elsewhere the lower link's vertices, edges
//! and triangles are counted. Entry points: [`Links::new`] once per mesh, then
//! [`Links::classify`] per field ([`classify`] does both), or
//! [`Links::classify_again`] for a sequence of fields (the smoothing levels): a vertex
//! whose link vertices all lie on the same sides of it as at the previous field keeps
//! its class, since the class depends on nothing else.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, norm, scale, sub};
use crate::tet::{TetMesh, VertexKind};

/// The type of a vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VertexType {
    /// Not interior (surface or outer sphere): not classified.
    Boundary,
    /// One upper and one lower link component.
    Regular,
    /// No upper link.
    Maximum,
    /// No lower link.
    Minimum,
    /// One upper, two lower components.
    Saddle1,
    /// Two upper, one lower component.
    Saddle2,
    /// Any other counts.
    Degenerate,
}

/// The classification of one vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct VertexClass {
    /// Its type.
    pub kind: VertexType,
    /// Components of the upper link.
    pub upper: u32,
    /// Components of the lower link.
    pub lower: u32,
    /// `1 − χ(lower link)`: its contribution to the Morse sum.
    pub euler_term: i32,
}

/// Every vertex's class, and the Morse sum over interior vertices.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    /// One entry per mesh vertex.
    pub classes: Vec<VertexClass>,
    /// Σ over interior vertices of `1 − χ(lower link)`.
    pub morse_sum: i64,
}

impl Classification {
    /// How many vertices have this type.
    pub fn count(&self, kind: VertexType) -> usize {
        self.classes.iter().filter(|c| c.kind == kind).count()
    }
}

/// Classify every interior vertex of `mesh` for the field `f` (one value per vertex).
/// Builds the [`Links`] first; to classify many fields on one mesh, build them once.
pub fn classify(mesh: &TetMesh, f: &[f64]) -> Result<Classification> {
    Ok(Links::new(mesh)?.classify(f))
}

/// The Morse sum that the mesh's topology forces, from the lower-star filtration in
/// our vertex order: Σ over interior vertices of `1 − χ(lower link)` =
/// χ(K_{S∪I}) − χ(K_S), with `K_X` the full subcomplex on the vertices of kinds `X`
/// (S surface, I interior).
///
/// For a 3-manifold mesh `T` whose boundary is the surface (and the outer sphere),
/// χ(T) = χ(∂T)/2, so when `K_S` is exactly the surface and `K_{S∪I}` has the topology
/// of `T`, the sum is `Σ_i (g_i − 1)` inside and `1 + Σ_i (g_i − 1)` outside over the
/// surface components `i` of genus `g_i` (g − 1 and g for one component). `K_S` is more
/// than the surface where a tet, face or edge spans surface vertices only (a thin part
/// with no interior vertex); then the two differ, and the mesh's value is the one the
/// classification must meet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct MorseExpectation {
    /// χ(K_S): the full subcomplex on the surface vertices.
    pub surface_part_euler: i64,
    /// χ(K_{S∪I}): everything but the outer-sphere vertices' stars.
    pub inner_part_euler: i64,
    /// χ(K_{S∪I}) − χ(K_S).
    pub sum: i64,
}

/// See [`MorseExpectation`].
pub fn expected_morse_sum(mesh: &TetMesh) -> MorseExpectation {
    let surface: Vec<bool> = mesh
        .kinds
        .iter()
        .map(|&k| k == VertexKind::Surface)
        .collect();
    let not_outer: Vec<bool> = mesh.kinds.iter().map(|&k| k != VertexKind::Outer).collect();
    let surface_part_euler = mesh.euler_characteristic_where(&surface);
    let inner_part_euler = mesh.euler_characteristic_where(&not_outer);
    MorseExpectation {
        surface_part_euler,
        inner_part_euler,
        sum: inner_part_euler - surface_part_euler,
    }
}

/// The links of a mesh's interior vertices in local indices, built once per mesh so
/// that classifying a field (every smoothing step) only compares values and joins
/// small union-find sets: no sorting, no allocation per vertex.
///
/// A link's triangles are not kept (they were 40 % of the links' bytes,
/// `docs/decisions.md`, Morse). Where the link is a triangulated 2-sphere, as at every
/// interior vertex of a 3-manifold mesh, χ(lower link) follows from the components
/// (see the module doc); where it is not, its triangles are read from the mesh: its
/// vertex's tets less the vertex.
#[derive(Debug, Clone)]
pub struct Links<'m> {
    mesh: &'m TetMesh,
    /// Per vertex: its range in `vertices` (empty unless interior); `n + 1` entries.
    vertex_start: Vec<usize>,
    /// Link vertices (global ids), sorted within each link.
    vertices: Vec<u32>,
    edge_start: Vec<usize>,
    /// Link edges in local indices.
    edges: Vec<[u16; 2]>,
    /// The interior vertices whose links are not 2-spheres, in order (none on a
    /// 3-manifold mesh).
    not_spheres: Vec<u32>,
}

/// Which link vertices lay below each vertex at the last field
/// [`Links::classify_again`] saw, and the classes it gave (empty before the first).
/// Keep one per [`Links`]: sides taken from another mesh give wrong classes.
#[derive(Debug, Clone, Default)]
pub struct LinkSides {
    words: Vec<u64>,
    classes: Vec<VertexClass>,
}

/// The side word of a link too long for one (bit 63 is never a vertex's).
const UNTRACKED: u64 = 1 << 63;

/// The class of a vertex that is not interior.
const BOUNDARY: VertexClass = VertexClass {
    kind: VertexType::Boundary,
    upper: 0,
    lower: 0,
    euler_term: 0,
};

/// Vertices whose links [`Links::new`] builds in one piece of work.
const LINK_RUN: usize = 4096;

/// The links of a run of vertices, one after the other, and where each vertex's ends
/// in the two arrays.
#[derive(Default)]
struct LinkRun {
    vertices: Vec<u32>,
    edges: Vec<[u16; 2]>,
    ends: Vec<[usize; 2]>,
    not_spheres: Vec<u32>,
}

/// One vertex's link in local indices, and the buffers that build it: one per
/// thread, reused from vertex to vertex.
#[derive(Default)]
struct Link {
    vertices: Vec<u32>,
    /// Its edges, sorted, each once.
    edges: Vec<[u16; 2]>,
    /// Whether it is a triangulated 2-sphere ([`is_sphere`]).
    sphere: bool,
    /// Its triangles as global corners, then as local ones.
    global: Vec<[u32; 3]>,
    triangles: Vec<[u16; 3]>,
    /// Union–find forest of [`is_sphere`].
    parent: Vec<u32>,
}

impl<'m> Links<'m> {
    /// Build the link of every interior vertex. Fails only when a vertex has more than
    /// 65535 link vertices.
    pub fn new(mesh: &'m TetMesh) -> Result<Links<'m>> {
        // Built in runs of vertices, each into flat arrays of its own, then copied into
        // arrays reserved at their final length: a vector per link, at its capacity
        // before duplicates were removed, held several times the links' size (and
        // arrays grown by doubling up to three times theirs), the analysis's peak.
        let n = mesh.num_vertices();
        let runs: Vec<LinkRun> = (0..n.div_ceil(LINK_RUN))
            .into_par_iter()
            .map(|r| {
                let mut run = LinkRun::default();
                let mut link = Link::default();
                for v in r * LINK_RUN..n.min((r + 1) * LINK_RUN) {
                    if mesh.kinds[v] == VertexKind::Interior {
                        link_of(mesh, v as u32, &mut link)?;
                        run.vertices.extend(&link.vertices);
                        run.edges.extend(&link.edges);
                        if !link.sphere {
                            run.not_spheres.push(v as u32);
                        }
                    }
                    run.ends.push([run.vertices.len(), run.edges.len()]);
                }
                Ok(run)
            })
            .collect::<Result<_>>()?;
        let total = |size: fn(&LinkRun) -> usize| runs.iter().map(size).sum();
        let starts = || {
            let mut start = Vec::with_capacity(n + 1);
            start.push(0);
            start
        };
        let mut links = Links {
            mesh,
            vertex_start: starts(),
            vertices: Vec::with_capacity(total(|r| r.vertices.len())),
            edge_start: starts(),
            edges: Vec::with_capacity(total(|r| r.edges.len())),
            not_spheres: Vec::new(),
        };
        for run in runs {
            let offsets = [links.vertices.len(), links.edges.len()];
            for end in &run.ends {
                links.vertex_start.push(offsets[0] + end[0]);
                links.edge_start.push(offsets[1] + end[1]);
            }
            links.vertices.extend(run.vertices);
            links.edges.extend(run.edges);
            links.not_spheres.extend(run.not_spheres);
        }
        Ok(links)
    }

    /// Number of mesh vertices.
    pub fn num_vertices(&self) -> usize {
        self.mesh.num_vertices()
    }

    /// Classify every interior vertex for the field `f` (one value per vertex), in
    /// parallel; the result does not depend on the thread count.
    pub fn classify(&self, f: &[f64]) -> Classification {
        let classes: Vec<VertexClass> = (0..self.num_vertices())
            .into_par_iter()
            .map_init(Scratch::default, |s, v| {
                if self.mesh.kinds[v] == VertexKind::Interior {
                    self.classify_vertex(v, f, s)
                } else {
                    BOUNDARY
                }
            })
            .collect();
        let morse_sum = classes.iter().map(|c| i64::from(c.euler_term)).sum();
        Classification { classes, morse_sum }
    }

    /// Whether `a` comes below `b`: surface first, outer sphere last, else `(f, index)`.
    #[inline]
    fn below(&self, f: &[f64], a: usize, b: usize) -> bool {
        let rank = |v: usize| match self.mesh.kinds[v] {
            VertexKind::Surface => 0u8,
            VertexKind::Interior => 1,
            VertexKind::Outer => 2,
        };
        let (ra, rb) = (rank(a), rank(b));
        if ra != rb {
            return ra < rb;
        }
        match f[a].total_cmp(&f[b]) {
            std::cmp::Ordering::Less => true,
            std::cmp::Ordering::Greater => false,
            std::cmp::Ordering::Equal => a < b,
        }
    }

    /// [`classify`](Self::classify) for the next field of a sequence: `sides` holds
    /// which link vertices were below each vertex at the previous call (empty at the
    /// first), and a vertex whose sides did not change keeps its class from there
    /// without joining its link again. The result is exactly that of
    /// [`classify`](Self::classify); `sides` is updated for the next call.
    pub fn classify_again(&self, f: &[f64], sides: &mut LinkSides) -> Classification {
        let n = self.num_vertices();
        let fresh = sides.words.len() != n;
        let previous = std::mem::take(sides);
        let (words, classes): (Vec<u64>, Vec<VertexClass>) = (0..n)
            .into_par_iter()
            .map_init(Scratch::default, |s, v| {
                if self.mesh.kinds[v] != VertexKind::Interior {
                    return (0, BOUNDARY);
                }
                let word = self.side_word(v, f);
                let same = !fresh && word != UNTRACKED && previous.words[v] == word;
                if same {
                    (word, previous.classes[v])
                } else {
                    (word, self.classify_vertex(v, f, s))
                }
            })
            .unzip();
        let morse_sum = classes.iter().map(|c| i64::from(c.euler_term)).sum();
        *sides = LinkSides {
            words,
            classes: classes.clone(),
        };
        Classification { classes, morse_sum }
    }

    /// Bit `i` set when link vertex `i` of `v` is below it; [`UNTRACKED`] for a link
    /// of more than 63 vertices.
    fn side_word(&self, v: usize, f: &[f64]) -> u64 {
        let vertices = &self.vertices[self.vertex_start[v]..self.vertex_start[v + 1]];
        if vertices.len() > 63 {
            return UNTRACKED;
        }
        vertices.iter().enumerate().fold(0u64, |word, (i, &u)| {
            word | (u64::from(self.below(f, u as usize, v)) << i)
        })
    }

    /// The axis between two components of a vertex's upper link, those of its link
    /// vertices `through`: the sum of the unit vectors from `v` to each vertex of a
    /// component, the second's less the first's, made unit. Along it
    /// the field rises on both sides: for a 2-saddle, the direction its Hessian's
    /// positive eigenvector estimates, read from the link instead of a quadratic fit.
    /// `None` when `v` is not interior, either is not an upper link vertex, both lie in
    /// one component, or the two directions agree.
    pub fn upper_axis(
        &self,
        v: usize,
        f: &[f64],
        positions: &[[f64; 3]],
        through: [u32; 2],
    ) -> Option<[f64; 3]> {
        if self.mesh.kinds.get(v) != Some(&VertexKind::Interior) {
            return None;
        }
        let vertices = &self.vertices[self.vertex_start[v]..self.vertex_start[v + 1]];
        let edges = &self.edges[self.edge_start[v]..self.edge_start[v + 1]];
        let upper: Vec<bool> = vertices
            .iter()
            .map(|&u| !self.below(f, u as usize, v))
            .collect();
        let mut parent: Vec<u16> = (0..vertices.len() as u16).collect();
        for &[a, b] in edges {
            if upper[usize::from(a)] && upper[usize::from(b)] {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[usize::from(ra.max(rb))] = ra.min(rb);
            }
        }
        let local = |u: u32| {
            let i = vertices.binary_search(&u).ok()?;
            upper[i].then_some(i as u16)
        };
        let (a, b) = (local(through[0])?, local(through[1])?);
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra == rb {
            return None;
        }
        let centre = positions[v];
        let direction = |parent: &mut [u16], r: u16| {
            let mut sum = [0.0; 3];
            for i in 0..vertices.len() {
                if upper[i] && root(parent, i as u16) == r {
                    let u = vertices[i] as usize;
                    let d = sub(positions[u], centre);
                    let length = norm(d);
                    if length > 0.0 {
                        sum = add(sum, scale(d, 1.0 / length));
                    }
                }
            }
            sum
        };
        let axis = sub(direction(&mut parent, rb), direction(&mut parent, ra));
        let length = norm(axis);
        (length > 0.0 && length.is_finite()).then(|| scale(axis, 1.0 / length))
    }

    fn classify_vertex(&self, v: usize, f: &[f64], s: &mut Scratch) -> VertexClass {
        let vertices = &self.vertices[self.vertex_start[v]..self.vertex_start[v + 1]];
        let edges = &self.edges[self.edge_start[v]..self.edge_start[v + 1]];
        s.is_lower.clear();
        s.is_lower
            .extend(vertices.iter().map(|&u| self.below(f, u as usize, v)));
        s.parent.clear();
        s.parent.extend(0..vertices.len() as u16);

        // Components of each side, through same-side link edges.
        let mut lower_edges = 0i32;
        for &[a, b] in edges {
            let (i, j) = (usize::from(a), usize::from(b));
            if s.is_lower[i] == s.is_lower[j] {
                let (ri, rj) = (root(&mut s.parent, a), root(&mut s.parent, b));
                s.parent[usize::from(ri.max(rj))] = ri.min(rj);
                lower_edges += i32::from(s.is_lower[i]);
            }
        }
        let (mut upper, mut lower) = (0u32, 0u32);
        for i in 0..vertices.len() {
            if usize::from(s.parent[i]) == i {
                if s.is_lower[i] {
                    lower += 1;
                } else {
                    upper += 1;
                }
            }
        }
        let euler_lower = if self.not_spheres.binary_search(&(v as u32)).is_err() {
            // A full subcomplex of a 2-sphere and the one on the other vertices:
            // b1(lower) = upper − 1 by Alexander duality (see the module doc).
            lower as i32 - upper as i32 + 1
        } else {
            // Counted: the link's triangles are the faces of v's tets opposite v.
            let lower_vertices = s.is_lower.iter().filter(|&&l| l).count() as i32;
            let lower_triangles = self
                .mesh
                .vertex_tets(v)
                .iter()
                .filter(|&&t| {
                    self.mesh.tets[t as usize]
                        .iter()
                        .all(|&u| u as usize == v || self.below(f, u as usize, v))
                })
                .count() as i32;
            lower_vertices - lower_edges + lower_triangles
        };
        let kind = match (upper, lower) {
            (1, 1) => VertexType::Regular,
            (0, 1) => VertexType::Maximum,
            (1, 0) => VertexType::Minimum,
            (1, 2) => VertexType::Saddle1,
            (2, 1) => VertexType::Saddle2,
            _ => VertexType::Degenerate,
        };
        VertexClass {
            kind,
            upper,
            lower,
            euler_term: 1 - euler_lower,
        }
    }
}

/// The link of interior vertex `v`, the faces opposite `v` in its tets, into `link`.
fn link_of(mesh: &TetMesh, v: u32, link: &mut Link) -> Result<()> {
    link.global.clear();
    link.global
        .extend(mesh.vertex_tets(v as usize).iter().map(|&t| {
            let mut tri = [0u32; 3];
            let mut k = 0;
            for &u in &mesh.tets[t as usize] {
                if u != v && k < 3 {
                    tri[k] = u;
                    k += 1;
                }
            }
            tri.sort_unstable();
            tri
        }));
    let vertices = &mut link.vertices;
    vertices.clear();
    vertices.extend(link.global.iter().flatten());
    vertices.sort_unstable();
    vertices.dedup();
    if vertices.len() > usize::from(u16::MAX) {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "vertex {v} has {} link vertices (at most 65535)",
                vertices.len()
            ),
        ));
    }
    // Local indices keep the global order, so each triangle's corners stay sorted.
    let local = |u: u32| vertices.binary_search(&u).unwrap_or(0) as u16;
    link.triangles.clear();
    link.triangles
        .extend(link.global.iter().map(|t| t.map(local)));
    sorted_edges_into(&link.triangles, &mut link.edges);
    link.sphere = is_sphere(
        vertices.len(),
        &link.triangles,
        &link.edges,
        &mut link.parent,
    );
    link.edges.dedup();
    Ok(())
}

/// Every triangle's three edges (the triangle's corners sorted), each low end first,
/// sorted, repeats kept.
fn sorted_edges_into(triangles: &[[u16; 3]], edges: &mut Vec<[u16; 2]>) {
    edges.clear();
    edges.extend(
        triangles
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [a, c], [b, c]]),
    );
    edges.sort_unstable();
}

/// Whether a link is a triangulated 2-sphere: every edge in exactly two triangles (it
/// is closed), the triangles round every vertex one cycle (a surface, no pinch),
/// connected, and χ = 2. Each triangle's corners are sorted; `edges` holds every
/// triangle's three edges, sorted, repeats kept; `parent` is a buffer.
///
/// Round a vertex, its triangles are joined across the edges they share at it. With
/// every edge in two triangles, the triangles round each vertex form disjoint cycles,
/// one union–find set each over the vertex's ends of its edges (edge `e`'s low end is
/// element `2e`, its high end `2e + 1`). The link is a surface when there are as many
/// sets as vertices.
fn is_sphere(
    vertices: usize,
    triangles: &[[u16; 3]],
    edges: &[[u16; 2]],
    parent: &mut Vec<u32>,
) -> bool {
    let closed = edges.len().is_multiple_of(2)
        && edges.chunks(2).all(|pair| pair[0] == pair[1])
        && edges.windows(3).all(|w| w[0] != w[2]);
    let distinct = edges.len() / 2;
    if !closed || vertices as i64 - distinct as i64 + triangles.len() as i64 != 2 {
        return false;
    }
    // Edges come in pairs, so the first copy's position halved numbers the edge.
    let index = |a: u16, b: u16| (edges.partition_point(|e| *e < [a, b]) / 2) as u32;
    parent.clear();
    parent.extend(0..2 * distinct as u32);
    let mut sets = 2 * distinct;
    for &[a, b, c] in triangles {
        let (ab, ac, bc) = (index(a, b), index(a, c), index(b, c));
        for (x, y) in [
            (2 * ab, 2 * ac),
            (2 * ab + 1, 2 * bc),
            (2 * ac + 1, 2 * bc + 1),
        ] {
            sets -= usize::from(union(parent, x, y));
        }
    }
    if sets != vertices {
        return false;
    }
    // Connected: the edges join the vertices into one set.
    parent.clear();
    parent.extend(0..vertices as u32);
    let mut sets = vertices;
    for pair in edges.chunks(2) {
        let [a, b] = pair[0];
        sets -= usize::from(union(parent, u32::from(a), u32::from(b)));
    }
    sets == 1
}

/// Join the sets of `x` and `y` (the lower root becomes the root); whether they were
/// apart.
fn union(parent: &mut [u32], x: u32, y: u32) -> bool {
    let find = |parent: &mut [u32], mut x: u32| {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    };
    let (rx, ry) = (find(parent, x), find(parent, y));
    parent[rx.max(ry) as usize] = rx.min(ry);
    rx != ry
}

/// Per-thread buffers, reused from vertex to vertex.
#[derive(Default)]
struct Scratch {
    parent: Vec<u16>,
    is_lower: Vec<bool>,
}

fn root(p: &mut [u16], mut x: u16) -> u16 {
    while p[usize::from(x)] != x {
        p[usize::from(x)] = p[usize::from(p[usize::from(x)])];
        x = p[usize::from(x)];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `is_sphere` on triangles given by their corners, edges as `link_of` gives them.
    fn sphere(vertices: usize, triangles: &[[u16; 3]]) -> bool {
        let triangles: Vec<[u16; 3]> = triangles
            .iter()
            .map(|t| {
                let mut t = *t;
                t.sort_unstable();
                t
            })
            .collect();
        let mut edges = Vec::new();
        sorted_edges_into(&triangles, &mut edges);
        is_sphere(vertices, &triangles, &edges, &mut Vec::new())
    }

    /// The octahedron on `[+x, −x, +y, −y, +z, −z]`.
    fn octahedron(v: [u16; 6]) -> Vec<[u16; 3]> {
        let mut triangles = Vec::new();
        for x in [v[0], v[1]] {
            for y in [v[2], v[3]] {
                for z in [v[4], v[5]] {
                    triangles.push([x, y, z]);
                }
            }
        }
        triangles
    }

    #[test]
    fn spheres_are_told_from_pinched_open_and_other_closed_links() {
        assert!(sphere(6, &octahedron([0, 1, 2, 3, 4, 5])));
        assert!(sphere(4, &[[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]));
        // Two octahedra sharing two opposite corners: closed, connected, χ = 2, but
        // pinched at both corners.
        let mut pinched = octahedron([0, 1, 2, 3, 4, 5]);
        pinched.extend(octahedron([0, 1, 6, 7, 8, 9]));
        assert!(!sphere(10, &pinched));
        // Two spheres apart (χ = 4), a torus (χ = 0), a disk (open).
        let mut apart = octahedron([0, 1, 2, 3, 4, 5]);
        apart.extend(octahedron([6, 7, 8, 9, 10, 11]));
        assert!(!sphere(12, &apart));
        let at = |i: u16, j: u16| (i % 3) * 3 + j % 3;
        let torus: Vec<[u16; 3]> = (0..3)
            .flat_map(|i| {
                (0..3).flat_map(move |j| {
                    [
                        [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                        [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                    ]
                })
            })
            .collect();
        assert!(!sphere(9, &torus));
        // A sphere and a torus apart: closed, no pinch, χ = 2, but not connected.
        let mut sphere_and_torus = octahedron([0, 1, 2, 3, 4, 5]);
        sphere_and_torus.extend(torus.iter().map(|t| t.map(|i| i + 6)));
        assert!(!sphere(15, &sphere_and_torus));
        assert!(!sphere(3, &[[0, 1, 2]]));
    }
}
