//! Small closed surfaces for the crate's unit tests.

use super::SurfaceMesh;

/// An octahedron with its vertices on the unit axes, faces outward.
pub(crate) fn octahedron() -> SurfaceMesh {
    let positions = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let triangles = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    SurfaceMesh::new(positions, triangles).unwrap()
}
