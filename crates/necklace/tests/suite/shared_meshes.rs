//! Every real mesh in `../shared/data/meshes` reads with the counts, genus and validity
//! flags its MANIFEST.tsv lists (computed independently with trimesh). Skips, saying
//! so, when the folder is absent; CI always has it.

use necklace::{io, MeshReport};

use crate::common::meshes_dir;

#[test]
fn shared_meshes_match_the_manifest() {
    let dir = meshes_dir();
    let Ok(manifest) = std::fs::read_to_string(dir.join("MANIFEST.tsv")) else {
        println!("SKIPPED: no mesh folder at {}", dir.display());
        return;
    };
    let mut lines = manifest.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let mut checked = 0;
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let row: Vec<&str> = line.split('\t').collect();
        let get = |name: &str| row[col(name)];
        let num = |name: &str| get(name).parse::<i64>().unwrap();
        let flag = |name: &str| get(name) == "true";
        let file = get("file");
        let mesh = io::read_mesh(dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        let r = MeshReport::new(&mesh);
        assert_eq!(r.vertices as i64, num("vertices"), "{file} vertices");
        assert_eq!(r.faces as i64, num("faces"), "{file} faces");
        assert_eq!(r.edges as i64, num("edges"), "{file} edges");
        assert_eq!(r.euler, num("euler_characteristic"), "{file} euler");
        assert_eq!(r.components as i64, num("components"), "{file} components");
        assert_eq!(r.genus, vec![Some(num("genus"))], "{file} genus");
        assert_eq!(r.watertight, flag("is_watertight"), "{file} watertight");
        assert_eq!(r.manifold, flag("is_manifold"), "{file} manifold");
        assert_eq!(r.oriented, flag("is_oriented"), "{file} oriented");
        let outward = get("normals") == "outward";
        assert_eq!(r.outward, Some(outward), "{file} orientation");
        assert_eq!(
            r.unreferenced_vertices as i64,
            num("unreferenced_vertices"),
            "{file} unreferenced"
        );
        assert_eq!(
            r.duplicate_vertices as i64,
            num("duplicate_vertex_positions"),
            "{file} duplicates"
        );
        assert_eq!(
            r.zero_area_faces as i64,
            num("zero_area_faces"),
            "{file} zero-area"
        );
        let diag: f64 = get("bbox_diagonal").parse().unwrap();
        assert!(
            (r.bbox_diagonal - diag).abs() <= 1e-3 * diag,
            "{file} diagonal"
        );
        checked += 1;
    }
    assert_eq!(checked, 21, "the manifest lists 21 meshes");

    // The one inward-oriented model is reported as such.
    let horse = io::read_mesh(dir.join("horse.ply")).unwrap();
    let report = MeshReport::new(&horse);
    assert_eq!(report.outward, Some(false));
    assert!(report.problems().iter().any(|p| p.contains("inward")));
}
