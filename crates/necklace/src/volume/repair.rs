//! Pinch repair: make the boundary of a stuffed tet mesh a 2-manifold.
//!
//! Stuffing decides from the signs at lattice vertices alone. Where the surface has a
//! feature below the lattice spacing (a sharp reflex crease, a slit), the inside can
//! touch itself along an edge or at a vertex whose neighbourhood is partly outside:
//! several fans of tets around one edge, or several groups of tets around one vertex
//! connected only through it, or a tunnel of the outside pinched to a single vertex.
//! Each edge or vertex pinch keeps its group of largest volume and drops the other
//! tets; a pinched tunnel loses the star of its vertex (the tunnel opens). Rounds repeat
//! until no pinch is left (a few at most). Interior vertices
//! that a dropped tet leaves on the boundary become boundary vertices; both counts are
//! reported.

use rustc_hash::FxHashMap as HashMap;

use crate::geom::{cross, dot, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// What the repair changed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Repair {
    /// Tets dropped.
    pub removed_tets: usize,
    /// Interior vertices left on the boundary.
    pub exposed: Vec<u32>,
}

const MAX_ROUNDS: usize = 20;

/// Remove tets until no edge or vertex of the boundary is pinched; `interior[v]` says
/// which vertices were strictly inside before.
pub(crate) fn repair_pinches(
    positions: &[[f64; 3]],
    tets: &mut Vec<[u32; 4]>,
    interior: &[bool],
) -> Repair {
    let mut repair = Repair::default();
    for _ in 0..MAX_ROUNDS {
        let drop = pinched_tets(positions, tets);
        if drop.is_empty() {
            break;
        }
        repair.removed_tets += drop.len();
        let mut keep = vec![true; tets.len()];
        for t in drop {
            keep[t] = false;
        }
        let mut i = 0;
        tets.retain(|_| {
            i += 1;
            keep[i - 1]
        });
    }
    if repair.removed_tets > 0 {
        for f in boundary_faces(tets) {
            repair
                .exposed
                .extend(f.into_iter().filter(|&v| interior[v as usize]));
        }
        repair.exposed.sort_unstable();
        repair.exposed.dedup();
    }
    repair
}

fn volume(positions: &[[f64; 3]], t: &[u32; 4]) -> f64 {
    let [a, b, c, d] = t.map(|v| positions[v as usize]);
    dot(sub(b, a), cross(sub(c, a), sub(d, a))) / 6.0
}

/// Faces with one tet (sorted vertex triples, in sorted order).
fn boundary_faces(tets: &[[u32; 4]]) -> Vec<[u32; 3]> {
    let mut faces: Vec<[u32; 3]> = tets.iter().flat_map(faces_of).collect();
    faces.sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j] == faces[i] {
            j += 1;
        }
        if j - i == 1 {
            out.push(faces[i]);
        }
        i = j;
    }
    out
}

/// The four faces of a tet, each with sorted vertices.
fn faces_of(t: &[u32; 4]) -> [[u32; 3]; 4] {
    let mut s = *t;
    s.sort_unstable();
    [
        [s[1], s[2], s[3]],
        [s[0], s[2], s[3]],
        [s[0], s[1], s[3]],
        [s[0], s[1], s[2]],
    ]
}

/// The tets to drop this round: at every pinched edge and vertex, all groups but the
/// one of largest volume.
fn pinched_tets(positions: &[[f64; 3]], tets: &[[u32; 4]]) -> Vec<usize> {
    let boundary = boundary_faces(tets);
    // Candidate vertices and edges: those on the boundary.
    let mut boundary_edges: HashMap<[u32; 2], u32> = HashMap::default();
    let mut on_boundary: HashMap<u32, ()> = HashMap::default();
    for f in &boundary {
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            *boundary_edges.entry([f[i], f[j]]).or_default() += 1;
        }
        for &v in f {
            on_boundary.insert(v, ());
        }
    }
    // Tets around each boundary vertex.
    let mut around: HashMap<u32, Vec<usize>> = HashMap::default();
    for (t, tet) in tets.iter().enumerate() {
        for &v in tet {
            if on_boundary.contains_key(&v) {
                around.entry(v).or_default().push(t);
            }
        }
    }
    let mut drop: Vec<usize> = Vec::new();
    let mut dropped = vec![false; tets.len()];
    let mark = |group: &[usize], dropped: &mut Vec<bool>, drop: &mut Vec<usize>| {
        for &t in group {
            if !dropped[t] {
                dropped[t] = true;
                drop.push(t);
            }
        }
    };
    // Pinched edges: more than two boundary faces.
    let mut pinched_edges: Vec<[u32; 2]> = boundary_edges
        .iter()
        .filter(|(_, n)| **n > 2)
        .map(|(e, _)| *e)
        .collect();
    pinched_edges.sort_unstable();
    for [a, b] in pinched_edges {
        let star: Vec<usize> = around[&a]
            .iter()
            .copied()
            .filter(|&t| tets[t].contains(&b))
            .collect();
        let groups = face_connected_groups(tets, &star, &[a, b]);
        for g in minority(positions, tets, &groups) {
            mark(g, &mut dropped, &mut drop);
        }
    }
    // Pinched vertices: tets around the vertex fall into several face-connected groups
    // (drop all but the largest), or form one group whose boundary faces make several
    // fans, a tunnel pinched to a point (drop the whole star: this opens the tunnel).
    let surface = SurfaceMesh {
        positions: positions.to_vec(),
        triangles: boundary.clone(),
    };
    let mut fanned: Vec<u32> = Topology::new(&surface)
        .non_manifold_vertices(&surface)
        .into_iter()
        .map(|v| v as u32)
        .collect();
    fanned.sort_unstable();
    let mut vertices: Vec<u32> = around.keys().copied().collect();
    vertices.sort_unstable();
    for v in vertices {
        let star = &around[&v];
        let groups = face_connected_groups(tets, star, &[v]);
        if groups.len() > 1 {
            for g in minority(positions, tets, &groups) {
                mark(g, &mut dropped, &mut drop);
            }
        } else if fanned.binary_search(&v).is_ok() {
            mark(star, &mut dropped, &mut drop);
        }
    }
    drop.sort_unstable();
    drop
}

/// Groups of `star` connected through faces that contain all of `through`.
fn face_connected_groups(tets: &[[u32; 4]], star: &[usize], through: &[u32]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..star.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut by_face: HashMap<[u32; 3], usize> = HashMap::default();
    for (i, &t) in star.iter().enumerate() {
        for f in faces_of(&tets[t]) {
            if through.iter().all(|v| f.contains(v)) {
                if let Some(&j) = by_face.get(&f) {
                    let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                    parent[ri.max(rj)] = ri.min(rj);
                } else {
                    by_face.insert(f, i);
                }
            }
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::default();
    for (i, &t) in star.iter().enumerate() {
        let r = find(&mut parent, i);
        groups.entry(r).or_default().push(t);
    }
    let mut out: Vec<Vec<usize>> = groups.into_values().collect();
    out.sort_unstable();
    out
}

/// All groups but the one of largest volume (ties: the first).
fn minority<'a>(
    positions: &[[f64; 3]],
    tets: &[[u32; 4]],
    groups: &'a [Vec<usize>],
) -> Vec<&'a Vec<usize>> {
    if groups.len() < 2 {
        return Vec::new();
    }
    let volumes: Vec<f64> = groups
        .iter()
        .map(|g| g.iter().map(|&t| volume(positions, &tets[t])).sum())
        .collect();
    let best = (0..groups.len())
        .max_by(|&i, &j| volumes[i].total_cmp(&volumes[j]).then(j.cmp(&i)))
        .unwrap_or(0);
    groups
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != best)
        .map(|(_, g)| g)
        .collect()
}
