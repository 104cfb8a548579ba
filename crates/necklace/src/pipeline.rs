//! The pipeline: the one module that composes the others.
//!
//! The method (see `ARCHITECTURE.md`) runs: input surface → volume mesh → distance field
//! and smoothing → critical points → neck loops. Each stage is a module that takes plain
//! data and returns plain data; only this module calls one stage with another's output.
//! Today it holds the first step, shared by every later one: [`prepare_surface`] checks
//! that a mesh is a closed, manifold, consistently oriented surface (what the volume
//! stages need) and turns an inward-oriented one outward, saying so.

use std::path::Path;

use crate::error::{Error, ErrorKind, Result};
use crate::io;
use crate::mesh::{MeshReport, SurfaceMesh};

/// A surface accepted as input to the method, with the report it was checked against.
#[derive(Debug, Clone)]
pub struct PreparedSurface {
    /// The mesh, outward-oriented.
    pub mesh: SurfaceMesh,
    /// The validity report of the mesh as given.
    pub report: MeshReport,
    /// Whether the faces were flipped because the input was oriented inward.
    pub flipped: bool,
}

/// Check that `mesh` is a closed, manifold, consistently oriented surface, and orient
/// it outward. Several components are allowed; each must be closed. An error names
/// every problem found.
pub fn prepare_surface(mut mesh: SurfaceMesh) -> Result<PreparedSurface> {
    let report = MeshReport::new(&mesh);
    let fatal = !(report.watertight && report.manifold && report.oriented);
    if mesh.triangles.is_empty() || fatal {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "not a closed manifold oriented surface: {}",
                report.problems().join("; ")
            ),
        ));
    }
    let flipped = report.outward == Some(false);
    if flipped {
        mesh.flip_orientation();
    }
    Ok(PreparedSurface {
        mesh,
        report,
        flipped,
    })
}

/// Read a mesh file and [`prepare_surface`] it; errors name the file.
pub fn load_surface(path: impl AsRef<Path>) -> Result<PreparedSurface> {
    let path = path.as_ref();
    let mesh = io::read_mesh(path)?;
    prepare_surface(mesh).map_err(|e| e.in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> SurfaceMesh {
        SurfaceMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn an_inward_surface_is_flipped_and_says_so() {
        let mut mesh = tetrahedron();
        let ok = prepare_surface(mesh.clone()).unwrap();
        assert!(!ok.flipped);
        mesh.flip_orientation();
        let fixed = prepare_surface(mesh).unwrap();
        assert!(fixed.flipped);
        assert!(fixed.mesh.signed_volume() > 0.0);
    }

    #[test]
    fn an_open_surface_is_refused_with_its_problems() {
        let mut mesh = tetrahedron();
        mesh.triangles.pop();
        let err = prepare_surface(mesh).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidMesh);
        assert!(err.to_string().contains("3 boundary edges"), "{err}");
    }
}
