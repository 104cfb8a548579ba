//! Repairs of careless input that keep the shape: corners that are the same point up to
//! a tolerance are welded into one vertex, vertices no face uses are removed, and the
//! faces of each component are turned to agree with their neighbours.
//!
//! None changes a position; welding removes only the triangles it collapses (two
//! corners welded together), and the others keep the set of triangles (only the order of
//! two corners of some), so the surface stays the same point set up to the tolerance;
//! each returns what it changed, for the caller to report. [`weld`] matters because STL
//! stores every triangle's corners apart, CAD exporters write `6e-17` where they mean
//! `0`, and OBJ and PLY files duplicate positions along texture seams: unwelded, a closed
//! solid reads as open sheets. [`remove_unreferenced`] matters because the bounding box sets
//! the method's scales: one stray vertex far away would make the lattice coarser than
//! the shape. [`orient_consistently`] is libigl's `bfs_orient`: a breadth-first walk over
//! the faces of each component through its manifold edges, turning a face whenever it
//! uses the edge it shares with the face it was reached from in the same direction.
//! Which of the two orientations a component ends with is the one most of its faces
//! already had; whether that points outward is for the caller to decide (it needs the
//! nesting of the components, see `pipeline::prepare_input`).

use std::collections::{HashMap, VecDeque};

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

/// What [`weld`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Welding {
    /// The distance below which two vertices were taken for one point (the mesh's
    /// units).
    pub tolerance: f64,
    /// Boundary vertices merged into another: the triangles now use its
    /// representative, the first boundary vertex in index order within the tolerance.
    pub merged: usize,
    /// Triangles removed because two of their corners were merged (a sliver thinner
    /// than the tolerance).
    pub collapsed_faces: usize,
}

/// `mesh` with every vertex on its boundary (an edge of one triangle) that is closer
/// than `tolerance` to an earlier such vertex (in index order) merged into the first
/// such vertex: removed, its triangles using that one instead, and the triangles that
/// lose a corner that way removed. Only boundary vertices are welded: a crack closes,
/// but where the surface is already closed, coincident vertices are parts that touch,
/// which welding would make non-manifold. The other vertices keep their positions and
/// order (a vertex no triangle uses stays, for [`remove_unreferenced`] to report).
/// Returns the mesh, for each of its vertices its index in `mesh`, and the counts.
/// Equal positions merge at any tolerance (−0 and +0 alike); `tolerance` 0 merges only
/// those. Deterministic: the same mesh gives the same result. A vertex is compared with
/// the representatives found before it, so a chain of points each within the tolerance
/// of the next is not merged end to end.
pub fn weld(mesh: &SurfaceMesh, tolerance: f64) -> (SurfaceMesh, Vec<u32>, Welding) {
    let tolerance = if tolerance.is_finite() {
        tolerance.max(0.0)
    } else {
        0.0
    };
    let n = mesh.positions.len();
    let lo = mesh
        .positions
        .iter()
        .fold([f64::INFINITY; 3], |m, p| [0, 1, 2].map(|k| m[k].min(p[k])));
    // Cells of the tolerance's size, counted from the box's low corner (so the keys
    // stay small wherever the mesh is); with tolerance 0, exact positions.
    let cell = |p: &[f64; 3]| -> [i64; 3] {
        if tolerance > 0.0 {
            [0, 1, 2].map(|k| ((p[k] - lo[k]) / tolerance).floor() as i64)
        } else {
            p.map(|c| if c == 0.0 { 0 } else { c.to_bits() as i64 })
        }
    };
    let reach: i64 = if tolerance > 0.0 { 1 } else { 0 };
    // The vertices on an edge that only one triangle has.
    let topology = Topology::new(mesh);
    let mut on_boundary = vec![false; n];
    for e in topology.boundary_edges() {
        for v in topology.edges()[e] {
            on_boundary[v as usize] = true;
        }
    }
    let mut representatives: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(n);
    let mut into: Vec<u32> = (0..n as u32).collect();
    let mut merged = 0;
    for (v, p) in mesh.positions.iter().enumerate() {
        if !on_boundary[v] || p.iter().any(|c| !c.is_finite()) {
            continue;
        }
        let key = cell(p);
        let mut found: Option<u32> = None;
        for dx in -reach..=reach {
            for dy in -reach..=reach {
                for dz in -reach..=reach {
                    let near = [key[0] + dx, key[1] + dy, key[2] + dz];
                    for &r in representatives.get(&near).into_iter().flatten() {
                        let q = mesh.positions[r as usize];
                        let d2: f64 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum();
                        let same = *p == q || (tolerance > 0.0 && d2 <= tolerance * tolerance);
                        if same && found.is_none_or(|f| r < f) {
                            found = Some(r);
                        }
                    }
                }
            }
        }
        match found {
            Some(r) => {
                into[v] = r;
                merged += 1;
            }
            None => representatives.entry(key).or_default().push(v as u32),
        }
    }
    // The vertices kept (all but the merged ones), renumbered in their order.
    let kept: Vec<u32> = (0..n as u32).filter(|&v| into[v as usize] == v).collect();
    let mut new_index = vec![u32::MAX; n];
    for (i, &v) in kept.iter().enumerate() {
        new_index[v as usize] = i as u32;
    }
    let before = mesh.triangles.len();
    let triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| into.get(v as usize).map_or(v, |&r| new_index[r as usize])))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    let welding = Welding {
        tolerance,
        merged,
        collapsed_faces: before - triangles.len(),
    };
    let positions = kept.iter().map(|&v| mesh.positions[v as usize]).collect();
    (
        SurfaceMesh {
            positions,
            triangles,
        },
        kept,
        welding,
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

    /// The octahedron as STL stores it: every triangle with corners of its own, moved by
    /// `jitter` (a different amount per copy, as a CAD exporter's rounding does).
    fn triangle_soup(jitter: f64) -> SurfaceMesh {
        let mesh = octahedron();
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (f, t) in mesh.triangles.iter().enumerate() {
            let base = positions.len() as u32;
            for (i, &v) in t.iter().enumerate() {
                let wobble = jitter * ((f * 3 + i) % 5) as f64 / 5.0;
                positions.push(mesh.positions[v as usize].map(|c| c + wobble));
            }
            triangles.push([base, base + 1, base + 2]);
        }
        SurfaceMesh {
            positions,
            triangles,
        }
    }

    #[test]
    fn separate_corners_within_the_tolerance_weld_into_a_closed_surface() {
        // Corners 1e-12 apart (a CAD exporter's 6e-17 for 0, or float rounding).
        let soup = triangle_soup(1e-12);
        assert!(!MeshReport::new(&soup).watertight);
        let (welded, kept, what) = weld(&soup, 1e-9);
        assert_eq!(what.merged, 24 - 6);
        assert_eq!(what.collapsed_faces, 0);
        assert_eq!(welded.positions.len(), 6);
        // Each kept vertex is the first corner at its point.
        for (i, &v) in kept.iter().enumerate() {
            assert_eq!(welded.positions[i], soup.positions[v as usize]);
        }
        let report = MeshReport::new(&welded);
        assert!(report.watertight && report.manifold && report.oriented);
        assert_eq!(report.genus, vec![Some(0)]);
        // Below the jitter nothing but exact copies merge (the first corner of each
        // triangle is not moved: those six meet at two or more triangles each).
        let (_, _, exact) = weld(&soup, 0.0);
        assert!(exact.merged < 24 - 6);
        // The result does not depend on anything but the mesh.
        assert_eq!(weld(&soup, 1e-9), (welded, kept, what));
    }

    #[test]
    fn a_sliver_below_the_tolerance_collapses_and_is_counted() {
        let mut mesh = octahedron();
        // A seventh vertex 1e-10 from vertex 0, used by an extra sliver triangle.
        let p = mesh.positions[0];
        mesh.positions.push([p[0], p[1] + 1e-10, p[2]]);
        mesh.triangles.push([0, 6, 1]);
        let (welded, kept, what) = weld(&mesh, 1e-8);
        assert_eq!((what.merged, what.collapsed_faces), (1, 1));
        assert_eq!(welded, octahedron());
        assert_eq!(kept, (0..6).collect::<Vec<u32>>());
        // Far apart: nothing to do; a vertex no face uses stays.
        let mut spare = octahedron();
        spare.positions.push(spare.positions[0]);
        let (same, _, none) = weld(&spare, 1e-3);
        assert_eq!((same, none.merged, none.collapsed_faces), (spare, 0, 0));
    }

    #[test]
    fn welding_is_the_same_far_from_the_origin() {
        let shift = |m: &SurfaceMesh| SurfaceMesh {
            positions: m.positions.iter().map(|p| p.map(|c| c + 1e6)).collect(),
            triangles: m.triangles.clone(),
        };
        let soup = triangle_soup(1e-7);
        let (near, _, a) = weld(&soup, 1e-6);
        let (far, _, b) = weld(&shift(&soup), 1e-6);
        assert_eq!((a.merged, near.triangles), (b.merged, far.triangles));
    }

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
