//! The validity report on hand-built meshes whose answers are known by construction.

use necklace::shapes::{Shape, ShapeKind};
use necklace::{MeshReport, SurfaceMesh};

fn tetrahedron(offset: [f64; 3]) -> SurfaceMesh {
    let p = |x: f64, y: f64, z: f64| [x + offset[0], y + offset[1], z + offset[2]];
    SurfaceMesh::new(
        vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(0.0, 0.0, 1.0),
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
    .unwrap()
}

/// Disjoint union of two meshes.
fn join(a: &SurfaceMesh, b: &SurfaceMesh) -> SurfaceMesh {
    let n = a.positions.len() as u32;
    let mut m = a.clone();
    m.positions.extend_from_slice(&b.positions);
    m.triangles
        .extend(b.triangles.iter().map(|t| t.map(|v| v + n)));
    m
}

#[test]
fn a_tetrahedron_is_a_valid_genus_0_solid() {
    let r = MeshReport::new(&tetrahedron([0.0; 3]));
    assert_eq!((r.vertices, r.edges, r.faces, r.euler), (4, 6, 4, 2));
    assert_eq!(r.genus, vec![Some(0)]);
    assert!(r.is_valid_solid());
    assert!((r.signed_volume - 1.0 / 6.0).abs() < 1e-15);
    // Three right isosceles faces (45°) and one equilateral face (60°).
    assert!((r.min_angle_deg - 45.0).abs() < 1e-9);
    let mean_edge = (3.0 + 3.0 * 2f64.sqrt()) / 6.0;
    assert!((r.mean_edge_length - mean_edge).abs() < 1e-15);
    assert_eq!(r.bbox_min, [0.0; 3]);
    assert_eq!(r.bbox_max, [1.0; 3]);
    assert!(r.problems().is_empty());
}

#[test]
fn an_open_mesh_reports_its_hole() {
    let mut m = tetrahedron([0.0; 3]);
    m.triangles.pop();
    let r = MeshReport::new(&m);
    assert!(!r.watertight);
    assert!(r.manifold && r.oriented);
    assert_eq!((r.boundary_edges, r.boundary_loops), (3, 1));
    // A disk: χ = 1 = 2 − 2g − b with b = 1 gives g = 0.
    assert_eq!(r.genus, vec![Some(0)]);
    assert_eq!(r.outward, None);
}

#[test]
fn an_inward_mesh_is_read_and_reported() {
    let mut m = tetrahedron([0.0; 3]);
    m.flip_orientation();
    let r = MeshReport::new(&m);
    assert!(r.watertight && r.manifold && r.oriented);
    assert_eq!(r.outward, Some(false));
    assert!(!r.is_valid_solid());
}

#[test]
fn one_flipped_face_breaks_orientation_on_its_three_edges() {
    let mut m = tetrahedron([0.0; 3]);
    m.triangles[0].swap(1, 2);
    let r = MeshReport::new(&m);
    assert!(r.watertight && r.manifold);
    assert!(!r.oriented);
    assert_eq!(r.inconsistent_edges, 3);
    assert_eq!(r.genus, vec![None]);
    assert_eq!(r.outward, None);
}

#[test]
fn three_faces_on_one_edge_make_it_non_manifold() {
    let mut m = tetrahedron([0.0; 3]);
    m.positions.push([0.5, 0.5, -1.0]);
    m.triangles.push([0, 1, 4]); // edge 0-1 now has three faces
    let r = MeshReport::new(&m);
    assert_eq!(r.non_manifold_edges, 1);
    assert!(!r.manifold && !r.watertight);
    assert_eq!(r.genus, vec![None]);
}

#[test]
fn two_solids_touching_at_a_vertex_make_it_non_manifold() {
    // The second tetrahedron's vertex 0 is the first's vertex 3 (0,0,1).
    let a = tetrahedron([0.0; 3]);
    let b = tetrahedron([0.0, 0.0, 1.0]);
    let mut m = join(&a, &b);
    for t in &mut m.triangles {
        for v in t.iter_mut() {
            if *v == 4 {
                *v = 3;
            }
        }
    }
    let r = MeshReport::new(&m);
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.non_manifold_edges, 0);
    assert!(r.watertight && !r.manifold);
    assert_eq!(r.components, 1);
    assert_eq!(r.unreferenced_vertices, 1);
    assert_eq!(
        r.duplicate_vertices, 1,
        "vertex 4 still sits at vertex 3's position"
    );
}

#[test]
fn components_get_their_own_genus() {
    let sphere = Shape::from_name("sphere", &[("res".into(), 12.0)])
        .unwrap()
        .mesh()
        .unwrap();
    let mut torus = Shape::new(ShapeKind::Torus)
        .with("res", 24.0)
        .unwrap()
        .mesh()
        .unwrap();
    for p in &mut torus.positions {
        p[0] += 5.0;
    }
    let r = MeshReport::new(&join(&sphere, &torus));
    assert_eq!(r.components, 2);
    assert_eq!(r.genus, vec![Some(0), Some(1)]);
    assert_eq!(r.euler, 2);
    assert!(r.is_valid_solid());
    assert!(r
        .problems()
        .iter()
        .any(|p| p.contains("2 connected components")));
}

#[test]
fn degenerate_and_zero_area_faces_are_counted() {
    let mut m = tetrahedron([0.0; 3]);
    m.positions.push([2.0, 0.0, 0.0]); // collinear with vertices 0 and 1
    m.triangles.push([0, 1, 4]);
    m.triangles.push([0, 0, 1]);
    let r = MeshReport::new(&m);
    assert_eq!(r.degenerate_faces, 1);
    assert_eq!(r.zero_area_faces, 2);
}

#[test]
fn an_empty_mesh_reports_without_failing() {
    let r = MeshReport::new(&SurfaceMesh::default());
    assert_eq!((r.vertices, r.faces, r.components), (0, 0, 0));
    assert!(!r.watertight);
    assert!(r.problems().iter().any(|p| p.contains("no triangles")));
}

#[test]
fn the_constructor_rejects_bad_indices_and_coordinates() {
    let e = SurfaceMesh::new(vec![[0.0; 3]], vec![[0, 0, 1]]).unwrap_err();
    assert_eq!(e.kind(), necklace::ErrorKind::IndexOutOfRange);
    let e = SurfaceMesh::new(vec![[f64::NAN, 0.0, 0.0]], vec![]).unwrap_err();
    assert_eq!(e.kind(), necklace::ErrorKind::NonFinite);
}
