//! Repairs of careless input that keep the shape: vertices no face uses are removed,
//! and the faces of each component are turned to agree with their neighbours.
//!
//! Neither changes a position or the set of triangles (only the order of two corners of
//! some), so the surface stays the same point set; both return what they changed, for
//! the caller to report. [`remove_unreferenced`] matters because the bounding box sets
//! the method's scales: one stray vertex far away would make the lattice coarser than
//! the shape. [`orient_consistently`] is libigl's `bfs_orient`: a breadth-first walk over
//! the faces of each component through its manifold edges, turning a face whenever it
//! uses the edge it shares with the face it was reached from in the same direction.
//! Which of the two orientations a component ends with is the one most of its faces
//! already had; whether that points outward is for the caller to decide (it needs the
//! nesting of the components, see `pipeline::prepare_input`).

use std::collections::VecDeque;

use super::{SurfaceMesh, Topology};

/// `mesh` without the vertices no triangle uses, and for each vertex kept its index in
/// `mesh` (the kept vertices keep their order; `mesh.positions.len() - kept.len()` were
/// removed).
pub fn remove_unreferenced(mesh: &SurfaceMesh) -> (SurfaceMesh, Vec<u32>) {
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let kept: Vec<u32> = (0..mesh.positions.len() as u32)
        .filter(|&v| used[v as usize])
        .collect();
    if kept.len() == mesh.positions.len() {
        return (mesh.clone(), kept);
    }
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    for (i, &v) in kept.iter().enumerate() {
        new_index[v as usize] = i as u32;
    }
    let positions = kept.iter().map(|&v| mesh.positions[v as usize]).collect();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    (
        SurfaceMesh {
            positions,
            triangles,
        },
        kept,
    )
}

/// What [`orient_consistently`] changed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Reorientation {
    /// Faces turned round.
    pub flipped_faces: usize,
    /// Components that had at least one face turned round.
    pub components: usize,
    /// Components that cannot be oriented (a Möbius band or a Klein bottle): some edge
    /// stays used twice in one direction whichever way their faces are turned. They are
    /// left as the walk found them.
    pub non_orientable: usize,
}

/// Turn faces so that every manifold edge (two faces) is used in opposite directions,
/// component by component (see the module doc); returns the new mesh and what changed.
pub fn orient_consistently(mesh: &SurfaceMesh) -> (SurfaceMesh, Reorientation) {
    let topology = Topology::new(mesh);
    let nf = mesh.triangles.len();
    // Whether face f is turned relative to the file, per walk; `None` until reached.
    let mut turned: Vec<Option<bool>> = vec![None; nf];
    let mut result = Reorientation::default();
    let mut flip = vec![false; nf];
    let mut queue = VecDeque::new();
    let mut members = Vec::new();
    for seed in 0..nf {
        if turned[seed].is_some() {
            continue;
        }
        turned[seed] = Some(false);
        queue.push_back(seed);
        members.clear();
        let mut orientable = true;
        while let Some(f) = queue.pop_front() {
            members.push(f);
            let f_turned = turned[f] == Some(true);
            for side in 0..3 {
                let Some((g, _)) = topology.across(f, side) else {
                    continue;
                };
                if g == f {
                    continue;
                }
                // g must use the shared edge against f's direction once both are
                // turned as decided.
                let t = mesh.triangles[f];
                let (a, b) = (t[side], t[(side + 1) % 3]);
                let g_same = uses_directed(mesh.triangles[g], a, b);
                let g_turned = f_turned ^ g_same;
                match turned[g] {
                    None => {
                        turned[g] = Some(g_turned);
                        queue.push_back(g);
                    }
                    Some(decided) if decided != g_turned => orientable = false,
                    Some(_) => {}
                }
            }
        }
        if !orientable {
            result.non_orientable += 1;
            continue;
        }
        // Keep the orientation most faces of the component already have.
        let turned_count = members.iter().filter(|&&f| turned[f] == Some(true)).count();
        let keep_majority = 2 * turned_count > members.len();
        let mut changed = 0;
        for &f in &members {
            let turn = (turned[f] == Some(true)) ^ keep_majority;
            flip[f] = turn;
            changed += usize::from(turn);
        }
        if changed > 0 {
            result.components += 1;
            result.flipped_faces += changed;
        }
    }
    let mut out = mesh.clone();
    for (t, &turn) in out.triangles.iter_mut().zip(&flip) {
        if turn {
            t.swap(1, 2);
        }
    }
    (out, result)
}

/// Whether triangle `t` runs from `a` to `b` along one of its sides.
fn uses_directed(t: [u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|i| t[i] == a && t[(i + 1) % 3] == b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::octahedron;
    use crate::mesh::MeshReport;

    #[test]
    fn unreferenced_vertices_go_and_faces_follow() {
        let mut mesh = octahedron();
        mesh.positions.insert(0, [1e9, 0.0, 0.0]);
        for t in &mut mesh.triangles {
            *t = t.map(|v| v + 1);
        }
        mesh.positions.push([-5.0, 5.0, 5.0]);
        let (clean, kept) = remove_unreferenced(&mesh);
        let removed = mesh.positions.len() - kept.len();
        assert_eq!(removed, 2);
        assert_eq!(kept, (1..=6).collect::<Vec<u32>>());
        assert_eq!(clean, octahedron());
    }

    #[test]
    fn a_minority_of_turned_faces_is_turned_back() {
        let mut mesh = octahedron();
        mesh.triangles[1].swap(1, 2);
        mesh.triangles[6].swap(1, 2);
        assert!(!MeshReport::new(&mesh).oriented);
        let (fixed, what) = orient_consistently(&mesh);
        assert_eq!(fixed, octahedron());
        assert_eq!(
            what,
            Reorientation {
                flipped_faces: 2,
                components: 1,
                non_orientable: 0
            }
        );
        let (same, nothing) = orient_consistently(&octahedron());
        assert_eq!(same, octahedron());
        assert_eq!(nothing, Reorientation::default());
    }

    #[test]
    fn a_moebius_band_is_reported_and_left_alone() {
        // A strip of 2n triangles whose ends are glued with a half twist.
        let n = 6u32;
        let mut positions = Vec::new();
        for i in 0..n {
            let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
            let w = 0.3 * (0.5 * a).cos();
            let z = 0.3 * (0.5 * a).sin();
            positions.push([(1.0 + w) * a.cos(), (1.0 + w) * a.sin(), z]);
            positions.push([(1.0 - w) * a.cos(), (1.0 - w) * a.sin(), -z]);
        }
        let mut triangles = Vec::new();
        for i in 0..n {
            let (a, b) = (2 * i, 2 * i + 1);
            let (c, d) = if i + 1 < n {
                (2 * i + 2, 2 * i + 3)
            } else {
                (1, 0) // the half twist
            };
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
        let mesh = SurfaceMesh::new(positions, triangles).unwrap();
        let (same, what) = orient_consistently(&mesh);
        assert_eq!(what.non_orientable, 1);
        assert_eq!(same, mesh);
    }
}
