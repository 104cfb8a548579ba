//! What the integration tests share: the shared real meshes, and analytic domains (the
//! inside of a generated shape, and the shell between it and a sphere of a given
//! radius at the origin, through `volume::Shell`). Each test binary compiles this module and uses only part of it.

use std::path::PathBuf;

use necklace::shapes::{Shape, ShapeKind};
use necklace::volume::{Domain, Shell};
use necklace::{SurfaceMesh, VertexKind};

/// The folder of shared real meshes: `$NECKLACE_MESHES`, else `../shared/data/meshes`
/// beside the repository.
pub fn meshes_dir() -> PathBuf {
    match std::env::var_os("NECKLACE_MESHES") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes"),
    }
}

/// The folder of shared real-world models (printable parts, CAD exports, soups):
/// `$NECKLACE_REALWORLD`, else `../shared/data/realworld` beside the repository.
pub fn realworld_dir() -> PathBuf {
    match std::env::var_os("NECKLACE_REALWORLD") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/realworld"),
    }
}

/// A real-world model read as the pipeline reads it; `None` (after printing SKIPPED)
/// when the file is absent.
pub fn realworld_surface(name: &str) -> Option<necklace::pipeline::PreparedSurface> {
    let path = realworld_dir().join(name);
    if !path.is_file() {
        println!("SKIPPED: no {}", path.display());
        return None;
    }
    Some(necklace::pipeline::load_surface(&path).expect("a shared real-world model reads"))
}

/// The 21 shared mesh files, sorted; `None` (after printing SKIPPED) when the folder is
/// absent.
pub fn shared_meshes() -> Option<Vec<PathBuf>> {
    let dir = meshes_dir();
    let Ok(files) = necklace::io::mesh_files(&dir) else {
        println!("SKIPPED: no mesh folder at {}", dir.display());
        return None;
    };
    assert_eq!(files.len(), 21, "shared meshes in {}", dir.display());
    Some(files)
}

/// The inside of an analytic shape.
pub struct Inside(pub Shape);

impl Domain for Inside {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.0.sdf(p)
    }
    fn boundary_kind(&self, _p: [f64; 3]) -> VertexKind {
        VertexKind::Surface
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.0.bounds()
    }
}

/// The shell between an analytic shape and a sphere of radius `radius` at the origin
/// (the library's own shell combinator around [`Inside`]).
pub fn shell(shape: Shape, radius: f64) -> Shell<Inside> {
    Shell::new(Inside(shape), [0.0; 3], radius)
}

/// The same surface with every triangle split in four at its edge midpoints (the same
/// shape, four times the triangles).
pub fn split_in_four(mesh: &necklace::SurfaceMesh) -> necklace::SurfaceMesh {
    let mut positions = mesh.positions.clone();
    let mut midpoints = std::collections::HashMap::new();
    let mut midpoint = |a: u32, b: u32| {
        *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            positions.push([0, 1, 2].map(|i| 0.5 * (p[i] + q[i])));
            (positions.len() - 1) as u32
        })
    };
    let mut triangles = Vec::with_capacity(4 * mesh.triangles.len());
    for &[a, b, c] in &mesh.triangles {
        let (ab, bc, ca) = (midpoint(a, b), midpoint(b, c), midpoint(c, a));
        triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    necklace::SurfaceMesh::new(positions, triangles).unwrap()
}

/// The generated unit sphere (`res` its resolution) scaled to `radius` about `centre`.
pub fn sphere(radius: f64, centre: [f64; 3], res: f64) -> SurfaceMesh {
    let mut m = Shape::new(ShapeKind::Sphere)
        .with("res", res)
        .unwrap()
        .mesh()
        .unwrap();
    for p in &mut m.positions {
        for k in 0..3 {
            p[k] = centre[k] + radius * p[k];
        }
    }
    m
}

/// One surface made of `parts` (vertices renumbered, nothing merged).
pub fn union(parts: &[SurfaceMesh]) -> SurfaceMesh {
    let mut out = SurfaceMesh {
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    for part in parts {
        let n = out.positions.len() as u32;
        out.positions.extend_from_slice(&part.positions);
        out.triangles
            .extend(part.triangles.iter().map(|t| t.map(|v| v + n)));
    }
    out
}
