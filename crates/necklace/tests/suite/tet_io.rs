//! Tetrahedral-mesh files through the public API: round trips through every format,
//! the accepted quirks of each reader on tiny hand-written files, malformed inputs (each
//! with its error kind), and every prefix of valid files (never a panic).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use necklace::io::{
    read_tet_mesh, read_tet_mesh_bytes, read_tetgen_bytes, write_tet_mesh, write_tet_mesh_bytes,
    write_tetgen_bytes, TetFormat,
};
use necklace::{Error, ErrorKind, Location, TetMesh, VertexKind};

// ---------------------------------------------------------------------------------------
// Helpers

/// The single-file formats.
const SINGLE: [TetFormat; 3] = [TetFormat::Vtu, TetFormat::Medit, TetFormat::Gmsh];

fn read(data: &str, format: TetFormat) -> TetMesh {
    match read_tet_mesh_bytes(data.as_bytes(), format) {
        Ok(mesh) => mesh,
        Err(e) => panic!("expected a mesh, got error: {e}"),
    }
}

fn read_tetgen(node: &str, ele: &str) -> TetMesh {
    match read_tetgen_bytes(node.as_bytes(), ele.as_bytes()) {
        Ok(mesh) => mesh,
        Err(e) => panic!("expected a mesh, got error: {e}"),
    }
}

/// Check that a read failed with `kind` and a one-line message.
fn check_error(result: necklace::Result<TetMesh>, kind: ErrorKind) -> Error {
    match result {
        Ok(mesh) => panic!("expected a {kind:?} error, got a mesh: {mesh:?}"),
        Err(e) => {
            assert_eq!(e.kind(), kind, "wrong kind for error: {e}");
            assert!(!e.to_string().contains('\n'), "multi-line message: {e:?}");
            e
        }
    }
}

fn fails(data: &str, format: TetFormat, kind: ErrorKind) -> Error {
    check_error(read_tet_mesh_bytes(data.as_bytes(), format), kind)
}

fn tetgen_fails(node: &str, ele: &str, kind: ErrorKind) -> Error {
    check_error(read_tetgen_bytes(node.as_bytes(), ele.as_bytes()), kind)
}

fn at_line(e: &Error, line: usize) {
    assert_eq!(e.location(), Some(Location::Line(line)), "error: {e}");
}

/// A unique path in the temp dir (removed by the caller).
fn temp_path(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("necklace-tet-io-{}-{n}-{name}", std::process::id()))
}

fn remove(path: &Path) {
    let _ = std::fs::remove_file(path);
}

fn bits(mesh: &TetMesh) -> Vec<[u64; 3]> {
    mesh.positions.iter().map(|p| p.map(f64::to_bits)).collect()
}

/// Same positions (bitwise), tets and kinds.
fn assert_same(a: &TetMesh, b: &TetMesh) {
    assert_eq!(bits(a), bits(b), "positions differ (bitwise)");
    assert_eq!(a.tets, b.tets);
    assert_eq!(a.kinds, b.kinds);
}

/// A mesh with positively oriented tets and kinds from the boundary.
fn mesh(positions: Vec<[f64; 3]>, tets: Vec<[u32; 4]>) -> TetMesh {
    let kinds = TetMesh::classify_boundary(&positions, &tets);
    let mut mesh = TetMesh::new(positions, tets, kinds).unwrap();
    for t in 0..mesh.num_tets() {
        if mesh.tet_volume(t) < 0.0 {
            mesh.tets[t].swap(2, 3);
        }
    }
    mesh
}

/// An `n`³ grid of cubes, each split into 6 Kuhn tets (conforming across cubes), the
/// cells for which `skip` holds left out. Vertices are numbered in order of first use
/// and mapped through an awkward affine map, so printing must round-trip exactly.
fn grid(n: u32, skip: impl Fn([u32; 3]) -> bool) -> TetMesh {
    let mut index = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let mut tets = Vec::new();
    for cell in (0..n * n * n).map(|i| [i % n, (i / n) % n, i / (n * n)]) {
        if skip(cell) {
            continue;
        }
        // Corner bits x=1, y=2, z=4; each tet walks from corner 0 to corner 7.
        for path in [[1, 3], [1, 5], [2, 3], [2, 6], [4, 5], [4, 6]] {
            let tet = [0u32, path[0], path[1], 7].map(|corner| {
                let p = [0, 1, 2].map(|k| cell[k] + ((corner >> k) & 1));
                *index.entry(p).or_insert_with(|| {
                    let [x, y, z] = p.map(f64::from);
                    positions.push([
                        0.1 * x + 1.0 / 3.0,
                        -1.0 / 7.0 + y * 1e-7,
                        std::f64::consts::PI * z - 1e10,
                    ]);
                    positions.len() as u32 - 1
                })
            });
            tets.push(tet);
        }
    }
    mesh(positions, tets)
}

/// The unit cube as 6 tets (all vertices on the surface).
fn cube() -> TetMesh {
    grid(1, |_| false)
}

/// 2³ cubes: one interior vertex, the rest on the surface.
fn solid() -> TetMesh {
    grid(2, |_| false)
}

/// 3³ cubes without the centre one: an outer boundary (Outer) around a cavity (Surface).
fn shell() -> TetMesh {
    grid(3, |c| c == [1, 1, 1])
}

fn all_meshes() -> Vec<TetMesh> {
    vec![cube(), solid(), shell()]
}

/// Kinds that differ from the classified ones: only formats carrying kinds keep them.
fn with_custom_kinds(mut mesh: TetMesh) -> TetMesh {
    let cycle = [VertexKind::Outer, VertexKind::Interior, VertexKind::Surface];
    for (i, kind) in mesh.kinds.iter_mut().enumerate() {
        *kind = cycle[i % 3];
    }
    mesh
}

fn carries_kinds(format: TetFormat) -> bool {
    matches!(format, TetFormat::Vtu | TetFormat::Medit)
}

// ---------------------------------------------------------------------------------------
// Round trips

#[test]
fn test_meshes_are_what_they_claim() {
    assert_eq!(cube().kind_counts(), (0, 8, 0));
    assert_eq!(solid().kind_counts(), (1, 26, 0));
    assert_eq!(shell().kind_counts(), (0, 8, 56));
    for mesh in all_meshes() {
        assert!((0..mesh.num_tets()).all(|t| mesh.tet_volume(t) > 0.0));
    }
}

#[test]
fn round_trip_in_memory() {
    for original in all_meshes() {
        for format in SINGLE {
            let bytes = write_tet_mesh_bytes(&original, format, &[]).unwrap();
            let back = read_tet_mesh_bytes(&bytes, format).unwrap();
            assert_same(&original, &back);
        }
        let (node, ele) = write_tetgen_bytes(&original).unwrap();
        assert_same(&original, &read_tetgen_bytes(&node, &ele).unwrap());
    }
}

#[test]
fn kinds_survive_only_in_formats_that_carry_them() {
    let original = with_custom_kinds(shell());
    let classified = TetMesh::classify_boundary(&original.positions, &original.tets);
    assert_ne!(original.kinds, classified);
    for format in SINGLE {
        let bytes = write_tet_mesh_bytes(&original, format, &[]).unwrap();
        let back = read_tet_mesh_bytes(&bytes, format).unwrap();
        assert_eq!(bits(&back), bits(&original));
        assert_eq!(back.tets, original.tets);
        let expected = if carries_kinds(format) {
            &original.kinds
        } else {
            &classified
        };
        assert_eq!(&back.kinds, expected, "{format:?}");
    }
    let (node, ele) = write_tetgen_bytes(&original).unwrap();
    assert_eq!(read_tetgen_bytes(&node, &ele).unwrap().kinds, classified);
}

#[test]
fn round_trip_through_files() {
    let original = with_custom_kinds(shell());
    let classified = TetMesh::classify_boundary(&original.positions, &original.tets);
    for ext in ["vtu", "mesh", "msh", "node", "VTU"] {
        let path = temp_path(&format!("round-trip.{ext}"));
        write_tet_mesh(&path, &original, &[]).unwrap();
        let back = read_tet_mesh(&path);
        if ext == "node" {
            // Both files are written; either name reads the pair.
            let ele = path.with_extension("ele");
            let via_ele = read_tet_mesh(&ele).unwrap();
            remove(&ele);
            assert_same(back.as_ref().unwrap(), &via_ele);
        }
        remove(&path);
        let back = back.unwrap();
        assert_eq!(bits(&back), bits(&original), "{ext}");
        assert_eq!(back.tets, original.tets, "{ext}");
        let carries = matches!(ext, "vtu" | "VTU" | "mesh");
        let expected = if carries {
            &original.kinds
        } else {
            &classified
        };
        assert_eq!(&back.kinds, expected, "{ext}");
    }
}

#[test]
fn vtu_writes_fields_as_point_data() {
    let mesh = cube();
    let temperature: Vec<f64> = (0..8).map(|i| f64::from(i) / 3.0).collect();
    let weird: Vec<f64> = vec![-0.0; 8];
    let fields: [(&str, &[f64]); 2] = [("temperature", &temperature), ("a<&\"b", &weird)];
    let bytes = write_tet_mesh_bytes(&mesh, TetFormat::Vtu, &fields).unwrap();
    let text = String::from_utf8_lossy(&bytes).to_string();
    assert!(text.contains(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"
    ));
    assert!(text.contains("<DataArray type=\"Float64\" Name=\"temperature\" format=\"appended\""));
    assert!(text.contains("Name=\"a&lt;&amp;&quot;b\""));
    // (The values themselves are read back by meshio in the Python tests.)
    // The file still reads, fields and all.
    assert_same(&mesh, &read_tet_mesh_bytes(&bytes, TetFormat::Vtu).unwrap());

    // Fields through a file.
    let path = temp_path("fields.vtu");
    write_tet_mesh(&path, &mesh, &fields).unwrap();
    let written = std::fs::read(&path).unwrap();
    remove(&path);
    assert_eq!(written, bytes);
}

#[test]
fn fields_are_checked() {
    let mesh = cube();
    let short = [1.0; 7];
    let eight = [1.0; 8];
    for format in SINGLE {
        let e = write_tet_mesh_bytes(&mesh, format, &[("t", &short)]).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidArgument, "{e}");
    }
    let path = temp_path("short.node");
    let e = write_tet_mesh(&path, &mesh, &[("t", &short)]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    assert!(!path.exists());
    // Other formats ignore fields.
    let plain = write_tet_mesh_bytes(&mesh, TetFormat::Medit, &[]).unwrap();
    let with = write_tet_mesh_bytes(&mesh, TetFormat::Medit, &[("t", &eight)]).unwrap();
    assert_eq!(plain, with);
    let vtu = TetFormat::Vtu;
    let e = write_tet_mesh_bytes(&mesh, vtu, &[("kind", &eight)]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    let e = write_tet_mesh_bytes(&mesh, vtu, &[("t", &eight), ("t", &eight)]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    let mut nan = eight;
    nan[3] = f64::NAN;
    let e = write_tet_mesh_bytes(&mesh, vtu, &[("t", &nan)]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NonFinite);
}

#[test]
fn writers_produce_the_documented_text() {
    let mesh = cube();
    let text =
        |format| String::from_utf8(write_tet_mesh_bytes(&mesh, format, &[]).unwrap()).unwrap();

    let vtu = write_tet_mesh_bytes(&mesh, TetFormat::Vtu, &[]).unwrap();
    let vtu = String::from_utf8_lossy(&vtu);
    assert!(vtu.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
    assert!(vtu.contains("<Piece NumberOfPoints=\"8\" NumberOfCells=\"6\">"));
    assert!(vtu.contains("Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\""));
    assert!(vtu.contains("<DataArray type=\"Int64\" Name=\"connectivity\""));
    assert!(vtu.contains("<DataArray type=\"Int64\" Name=\"offsets\""));
    assert!(vtu.contains("<DataArray type=\"UInt8\" Name=\"types\""));
    assert!(
        vtu.contains("<DataArray type=\"Int32\" Name=\"kind\" format=\"appended\" offset=\"0\"/>")
    );
    assert!(vtu.contains("<AppendedData encoding=\"raw\">\n   _"));
    assert!(vtu.ends_with("</AppendedData>\n</VTKFile>\n"));

    let medit = text(TetFormat::Medit);
    assert!(medit.starts_with("MeshVersionFormatted 2\nDimension 3\n# necklace kinds\n"));
    assert!(medit.contains("\nVertices\n8\n"));
    let [a, b, c, d] = mesh.tets[0].map(|v| v + 1);
    assert!(medit.contains(&format!("\nTetrahedra\n6\n{a} {b} {c} {d} 0\n")));
    assert!(medit.contains("\nTriangles\n12\n"));
    assert!(medit.ends_with("\nEnd\n"));
    let shell_medit =
        String::from_utf8(write_tet_mesh_bytes(&shell(), TetFormat::Medit, &[]).unwrap()).unwrap();
    let triangles = shell_medit.split("Triangles\n").nth(1).unwrap();
    let refs: Vec<&str> = triangles
        .lines()
        .skip(1)
        .take_while(|l| !l.is_empty())
        .map(|l| l.rsplit(' ').next().unwrap())
        .collect();
    assert_eq!(refs.len(), shell().boundary_faces().len());
    assert_eq!(refs.iter().filter(|r| **r == "2").count(), 6 * 9 * 2);
    assert_eq!(refs.iter().filter(|r| **r == "1").count(), 6 * 2);

    let gmsh = text(TetFormat::Gmsh);
    assert!(gmsh.starts_with("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 8 1 8\n3 1 0 8\n1\n"));
    assert!(gmsh.contains(&format!("$Elements\n1 6 1 6\n3 1 4 6\n1 {a} {b} {c} {d}\n")));
    assert!(gmsh.ends_with("$EndElements\n"));

    let (node, ele) = write_tetgen_bytes(&mesh).unwrap();
    let (node, ele) = (
        String::from_utf8(node).unwrap(),
        String::from_utf8(ele).unwrap(),
    );
    assert!(node.contains("\n8 3 0 1\n0 "));
    assert!(node.lines().nth(2).unwrap().ends_with(" 1"));
    let [a, b, c, d] = mesh.tets[0];
    assert!(ele.contains(&format!("\n6 4 0\n0 {a} {b} {c} {d}\n")));
}

#[test]
fn tetgen_cannot_go_through_the_single_file_functions() {
    let e = write_tet_mesh_bytes(&cube(), TetFormat::TetGen, &[]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    fails("1 3 0 0\n", TetFormat::TetGen, ErrorKind::InvalidArgument);
}

#[test]
fn format_from_extension() {
    let f = |name: &str| TetFormat::from_extension(Path::new(name));
    assert_eq!(f("a.node"), Some(TetFormat::TetGen));
    assert_eq!(f("a.1.ELE"), Some(TetFormat::TetGen));
    assert_eq!(f("a.mesh"), Some(TetFormat::Medit));
    assert_eq!(f("a.msh"), Some(TetFormat::Gmsh));
    assert_eq!(f("a.vtu"), Some(TetFormat::Vtu));
    assert_eq!(f("a.vtk"), None);
    assert_eq!(f("mesh"), None);
}

// ---------------------------------------------------------------------------------------
// TetGen

/// The unit tetrahedron's corners and (1, 1, 1): two tets sharing a face.
const CORNERS: [[f64; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
];

#[test]
fn tetgen_one_based_with_comments_attributes_and_markers() {
    let node = "# two tets\n\n5 3 2 1  # nodes, dim, attributes, markers\n\
                1 0 0 0 0.5 7 1\n2 1 0 0 0.5 7 1\n  3\t0 1 0 0.5 7 1\r\n4 0 0 1 0.5 7 1 # 4\n\
                5 1 1 1 0.5 7 0\n";
    let ele = "# tets\n2 4 1\n1 1 2 3 4 10\n2 2 4 3 5 -1\n# trailing comment\n";
    let mesh = read_tetgen(node, ele);
    assert_eq!(mesh.positions, CORNERS.to_vec());
    // The second tet is negatively oriented in the file: two vertices get swapped.
    assert_eq!(mesh.tets, vec![[0, 1, 2, 3], [1, 3, 4, 2]]);
    assert_eq!(mesh.kinds, vec![VertexKind::Surface; 5]);
}

#[test]
fn tetgen_zero_based_and_second_order() {
    let node = "10 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n\
                4 .5 0 0\n5 .5 .5 0\n6 0 .5 0\n7 0 0 .5\n8 .5 0 .5\n9 0 .5 .5\n";
    let ele = "1 10 0\n0 0 1 2 3 5 6 4 7 8 9\n";
    let mesh = read_tetgen(node, ele);
    assert_eq!(mesh.positions.len(), 10);
    assert_eq!(mesh.tets, vec![[0, 1, 2, 3]]);
    // Mid-edge nodes are used by no tet.
    assert_eq!(mesh.kind_counts(), (6, 4, 0));
}

#[test]
fn tetgen_malformed() {
    use ErrorKind::*;
    let ele = "1 4 0\n1 1 2 3 4\n";
    let node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    tetgen_fails("", ele, Empty);
    tetgen_fails("# nothing\n", ele, Empty);
    tetgen_fails(node, "# nothing\n", Empty);
    tetgen_fails(node, "0 4 0\n", Empty);
    let e = tetgen_fails("4 2 0 0\n", ele, Unsupported);
    at_line(&e, 1);
    let e = tetgen_fails("4 3\n1 0 0 0\n2 1 0 0\n", ele, Truncated);
    at_line(&e, 3);
    assert_eq!(e.source_name(), Some(".node"));
    let e = tetgen_fails("2 3\n1 0 0 0\n2 1 nan 0\n", ele, NonFinite);
    at_line(&e, 3);
    let e = tetgen_fails("2 3\n1 0 0 0\n3 1 0 0\n", ele, Syntax);
    at_line(&e, 3);
    let e = tetgen_fails("2 3 1 1\n1 0 0 0 0 0\n2 1 0 0 0\n", ele, Syntax);
    at_line(&e, 3);
    tetgen_fails("-1 3\n", ele, CountMismatch);
    let e = tetgen_fails(node, "2 4 0\n1 1 2 3 4\n2 1 2 3 5\n", IndexOutOfRange);
    at_line(&e, 3);
    assert_eq!(e.source_name(), Some(".ele"));
    tetgen_fails(node, "1 4 0\n1 0 2 3 4\n", IndexOutOfRange);
    tetgen_fails(node, "2 4 0\n1 1 2 3 4\n", Truncated);
    tetgen_fails(node, "1 6 0\n1 1 2 3 4 1 1\n", Syntax);
    tetgen_fails(node, "1 4 0\n1 1 2 3\n", Syntax);
    tetgen_fails(node, "1 4 0\n1 1 2 x 4\n", Syntax);
}

// ---------------------------------------------------------------------------------------
// Medit

#[test]
fn medit_skips_other_sections_and_ignores_case() {
    let data = "MeshVersionFormatted 1\n# a comment\ndimension\n3\n\nVERTICES\n5\n\
                0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 0\n\
                Edges 1\n1 2 0\nCorners 2 1 2\nTriangles\n1\n1 2 3 5\n\
                Normals 1\n0 0 1\nNormalAtVertices 1\n1 1\n\
                tetrahedra 2\n2 4 3 5 0 # negatively oriented\n1 2 3 4 0\n\
                RequiredVertices 1 1\nEnd\nthis is ignored\n";
    let mesh = read(data, TetFormat::Medit);
    assert_eq!(mesh.positions, CORNERS.to_vec());
    assert_eq!(mesh.tets, vec![[1, 3, 4, 2], [0, 1, 2, 3]]);
    assert_eq!(mesh.kinds, vec![VertexKind::Surface; 5]);
}

#[test]
fn medit_free_format_second_order_and_missing_end() {
    let data = "MeshVersionFormatted 2 Dimension 3 Vertices 10 0 0 0 0 1 0 0 0 0 1 0 0 \
                0 0 1 0 .5 0 0 0 .5 .5 0 0 0 .5 0 0 0 0 .5 0 .5 0 .5 0 0 .5 .5 0\r\n\
                TetrahedraP2 1\r\n1 2 3 4 5 6 7 8 9 10 3";
    let mesh = read(data, TetFormat::Medit);
    assert_eq!(mesh.positions.len(), 10);
    assert_eq!(mesh.tets, vec![[0, 1, 2, 3]]);
}

#[test]
fn medit_kinds_only_with_our_mark() {
    let body = "Vertices\n4\n0 0 0 2\n1 0 0 0\n0 1 0 1\n0 0 1 2\nTetrahedra\n1\n1 2 3 4 0\nEnd\n";
    let marked = format!("MeshVersionFormatted 2\nDimension 3\n\n# necklace kinds\n{body}");
    let mesh = read(&marked, TetFormat::Medit);
    use VertexKind::*;
    assert_eq!(mesh.kinds, vec![Outer, Interior, Surface, Outer]);
    let unmarked = format!("MeshVersionFormatted 2\nDimension 3\n{body}");
    assert_eq!(read(&unmarked, TetFormat::Medit).kinds, vec![Surface; 4]);
    let elsewhere = format!("MeshVersionFormatted 2\nDimension 3\n{body}# necklace kinds\n");
    assert_eq!(read(&elsewhere, TetFormat::Medit).kinds, vec![Surface; 4]);
    let bad = marked.replace("1 0 0 0\n", "1 0 0 7\n");
    let e = fails(&bad, TetFormat::Medit, ErrorKind::Syntax);
    at_line(&e, 8);
}

#[test]
fn medit_malformed() {
    use ErrorKind::*;
    let m = TetFormat::Medit;
    let head = "MeshVersionFormatted 2\nDimension 3\n";
    let vertices = "Vertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n";
    fails("", m, Empty);
    fails("# only a comment\n", m, Empty);
    fails(&format!("{head}{vertices}End\n"), m, Empty);
    let e = fails("MeshVersionFormatted 2\nDimension 2\n", m, Unsupported);
    at_line(&e, 2);
    let e = fails(&format!("{head}Foo 3\n"), m, Unsupported);
    at_line(&e, 3);
    // Three of four vertices, then the next section.
    let short = "Vertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\nTetrahedra\n1\n1 2 3 4 0\n";
    let e = fails(&format!("{head}{short}"), m, CountMismatch);
    at_line(&e, 8);
    let e = fails(
        &format!("{head}{vertices}Tetrahedra\n1\n1 2 3 5 0\n"),
        m,
        IndexOutOfRange,
    );
    at_line(&e, 11);
    fails(
        &format!("{head}{vertices}Tetrahedra\n1\n0 2 3 4 0\n"),
        m,
        IndexOutOfRange,
    );
    let e = fails(
        &format!("{head}{vertices}Tetrahedra\n2\n1 2 3 4 0\n1 2"),
        m,
        Truncated,
    );
    at_line(&e, 12);
    let e = fails(&format!("{head}Vertices\n1\n0 inf 0 0\n"), m, NonFinite);
    at_line(&e, 5);
    fails(&format!("{head}Vertices\n1\n0 x 0 0\n"), m, Syntax);
    fails(&format!("{head}Vertices\n-1\n"), m, CountMismatch);
    fails(&format!("{head}Vertices\n"), m, Truncated);
    fails(&format!("{head}Triangles 2\n1 2 3 0\n"), m, Truncated);
    // Tets before vertices name vertices that do not exist (yet).
    fails(
        &format!("{head}Tetrahedra\n1\n1 2 3 4 0\n{vertices}"),
        m,
        IndexOutOfRange,
    );
}

// ---------------------------------------------------------------------------------------
// Gmsh

#[test]
fn gmsh_2_2_with_tags_and_other_elements() {
    let data = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n\
                $PhysicalNames\n1\n3 1 \"domain\"\n$EndPhysicalNames\n\
                $Nodes\n5\n10 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n50 1 1 1\n$EndNodes\n\
                $Elements\n6\n1 15 2 0 10 10\n2 1 2 0 1 10 20\n3 2 2 0 1 10 20 30\n\
                4 4 2 1 1 10 20 30 40\n5 4 0 20 30 40 50\n\
                6 11 3 1 1 0 10 30 20 40 20 20 20 20 20 20\n$EndElements\n\
                $NodeData\n1\n\"t\"\n$EndNodeData\n";
    let mesh = read(data, TetFormat::Gmsh);
    assert_eq!(mesh.positions.len(), 5);
    assert_eq!(mesh.positions[4], [1.0, 1.0, 1.0]);
    assert_eq!(mesh.tets, vec![[0, 1, 2, 3], [1, 2, 3, 4], [0, 2, 3, 1]]);
}

#[test]
fn gmsh_4_1_with_entities_blocks_and_sparse_tags() {
    let data = "$MeshFormat\r\n4.1 0 8\r\n$EndMeshFormat\r\n\
                $Comments\nanything $Nodes\n$EndComments\n\
                $Entities\n0 0 1 1\n1 0 0 0 1 1 0 0 0\n1 0 0 0 1 1 1 0 1 1\n$EndEntities\n\
                $Nodes\n2 5 3 70\n2 1 1 2\n3\n7\n0 0 0 0.1 0.2\n1 0 0 0.3 0.4\n\
                3 1 0 3\n70\n12\n5\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n\
                $Elements\n3 4 1 9\n2 1 2 1\n1 3 7 70\n\
                3 1 4 2\n5 3 7 70 12\n9 7 12 70 5\n0 1 15 1\n4 3\n$EndElements\n";
    let mesh = read(data, TetFormat::Gmsh);
    assert_eq!(
        mesh.positions,
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0]
        ]
    );
    assert_eq!(mesh.tets, vec![[0, 1, 2, 3], [1, 3, 4, 2]]);
    assert_eq!(mesh.kind_counts(), (0, 5, 0));
}

#[test]
fn gmsh_malformed() {
    use ErrorKind::*;
    let g = TetFormat::Gmsh;
    let v2 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
    let nodes = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
    fails("", g, Empty);
    let e = fails("$Nodes\n", g, Syntax);
    at_line(&e, 1);
    let e = fails("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", g, Unsupported);
    at_line(&e, 2);
    fails(
        "$MeshFormat\n4.1 1 8\n\u{1}\0\0\0\n$EndMeshFormat\n",
        g,
        Unsupported,
    );
    fails("$MeshFormat\n2.2 x 8\n$EndMeshFormat\n", g, Syntax);
    fails("$MeshFormat\n", g, Truncated);
    fails(&format!("{v2}{nodes}"), g, Empty);
    let only_triangles = "$Elements\n1\n1 2 0 1 2 3\n$EndElements\n";
    fails(&format!("{v2}{nodes}{only_triangles}"), g, Empty);
    let e = fails(
        &format!("{v2}{nodes}$Elements\n1\n1 4 0 1 2 3 9\n$EndElements\n"),
        g,
        IndexOutOfRange,
    );
    at_line(&e, 13);
    let e = fails(
        &format!("{v2}$Nodes\n2\n1 0 0 0\n1 1 0 0\n$EndNodes\n"),
        g,
        Syntax,
    );
    at_line(&e, 7);
    let e = fails(
        &format!("{v2}$Nodes\n3\n1 0 0 0\n2 1 0 0\n$EndNodes\n"),
        g,
        CountMismatch,
    );
    at_line(&e, 8);
    fails(
        &format!("{v2}$Nodes\n2\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"),
        g,
        Syntax,
    );
    let e = fails(
        &format!("{v2}$Nodes\n1\n1 0 NaN 0\n$EndNodes\n"),
        g,
        NonFinite,
    );
    at_line(&e, 6);
    let e = fails(
        &format!("{v2}{nodes}$Elements\n2\n1 4 0 1 2 3 4\n"),
        g,
        Truncated,
    );
    at_line(&e, 13);
    fails(
        &format!("{v2}{nodes}$Elements\n1\n1 4 0 1 2 3 4\n"),
        g,
        Truncated,
    );
    fails(
        &format!("{v2}{nodes}$Elements\n1\n1 4 0 1 2 3\n$EndElements\n"),
        g,
        Syntax,
    );
    fails(
        &format!("{v2}{nodes}$Elements\n1\n1 4 9 1 2 3 4\n$EndElements\n"),
        g,
        Syntax,
    );
    fails(&format!("{v2}$Nodes\n-2\n$EndNodes\n"), g, CountMismatch);
    fails(&format!("{v2}$PhysicalNames\n1\n"), g, Truncated);
    fails(&format!("{v2}stray text\n"), g, Syntax);
    let v4 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let e = fails(
        &format!("{v4}$Nodes\n1 3 1 2\n3 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n"),
        g,
        CountMismatch,
    );
    at_line(&e, 5);
    fails(
        &format!("{v4}$Nodes\n1 1 1 1\n3 1 0 1\n1\n$EndNodes\n"),
        g,
        CountMismatch,
    );
}

// ---------------------------------------------------------------------------------------
// VTU

/// A VTU file with the given points, cells and extra attributes/arrays.
fn vtu(points: &str, connectivity: &str, offsets: &str, types: &str, extra: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<!-- a comment -->\n\
         <VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"BigEndian\">\n\
         <UnstructuredGrid>\n<Piece NumberOfPoints='{}' NumberOfCells=\"{}\" >\n{extra}\
         <Points>\n<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n{points}\n</DataArray>\n</Points>\n\
         <Cells>\n\
         <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">{connectivity}</DataArray>\n\
         <DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">{offsets}</DataArray>\n\
         <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">{types}</DataArray>\n\
         </Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n",
        points.split_whitespace().count() / 3,
        types.split_whitespace().count(),
    )
}

const FIVE_POINTS: &str = "0 0 0  1 0 0  0 1 0\n0 0 1  1 1 1";

#[test]
fn vtu_other_writers_layout_and_cell_types() {
    // A vertex, a triangle, a negatively oriented tet and a quadratic tet.
    let data = vtu(
        FIVE_POINTS,
        "4 0 1 2 0 2 1 3 1 2 3 4 0 0 0 0 0 0",
        "1 4 8 18",
        "1 5 10 24",
        "<PointData><DataArray type=\"Float64\" Name=\"t\" format=\"ascii\">1 2 3 4 5</DataArray>\
         <DataArray Name=\"empty\" type=\"Float64\" format=\"ascii\"/></PointData>\n<CellData/>\n",
    );
    let mesh = read(&data, TetFormat::Vtu);
    assert_eq!(mesh.positions.len(), 5);
    assert_eq!(mesh.tets, vec![[0, 2, 3, 1], [1, 2, 3, 4]]);
    assert_eq!(mesh.kind_counts(), (0, 5, 0));
}

#[test]
fn vtu_malformed() {
    use ErrorKind::*;
    let v = TetFormat::Vtu;
    let good = vtu(FIVE_POINTS, "0 1 2 3", "4", "10", "");
    read(&good, v);
    fails("", v, Empty);
    fails("not xml at all", v, Syntax);
    fails(
        &good.replace("UnstructuredGrid\" version", "PolyData\" version"),
        v,
        Unsupported,
    );
    fails(
        &good.replace("format=\"ascii\"", "format=\"binary\""),
        v,
        Unsupported,
    );
    // Binary files: ours read back; damaged ones are errors, not panics.
    let cube_mesh = cube();
    let binary = write_tet_mesh_bytes(&cube_mesh, v, &[]).unwrap();
    assert_same(&cube_mesh, &read_tet_mesh_bytes(&binary, v).unwrap());
    let damaged = |from: &str, to: &str| {
        // Keep the binary section byte for byte: patch only the XML before it.
        let cut = binary.windows(4).position(|w| w == b"   _").unwrap();
        let xml = String::from_utf8_lossy(&binary[..cut]);
        assert!(xml.contains(from), "{from}");
        let mut bytes = xml.replacen(from, to, 1).into_bytes();
        bytes.extend_from_slice(&binary[cut..]);
        bytes
    };
    let check = |bytes: Vec<u8>, kind| {
        check_error(read_tet_mesh_bytes(&bytes, v), kind);
    };
    check(
        damaged("encoding=\"raw\"", "encoding=\"base64\""),
        Unsupported,
    );
    check(
        damaged("vtkZLibDataCompressor", "vtkLZMADataCompressor"),
        Unsupported,
    );
    check(
        damaged("header_type=\"UInt64\"", "header_type=\"UInt16\""),
        Unsupported,
    );
    check(
        damaged("Int64\" Name=\"connectivity", "Int77\" Name=\"connectivity"),
        Unsupported,
    );
    assert!(
        read_tet_mesh_bytes(&damaged("<AppendedData encoding=\"raw\">", "<Other>"), v).is_err()
    );
    check(damaged("offset=\"0\"", "offset=\"99999\""), Truncated);
    // Every shorter file fails cleanly.
    for cut in (1..binary.len()).step_by(7) {
        assert!(read_tet_mesh_bytes(&binary[..cut], v).is_err(), "{cut}");
    }
    // Flipped bytes in the compressed data: an error or a valid mesh, never a panic.
    let start = binary.windows(4).position(|w| w == b"   _").unwrap() + 4;
    for i in (start..binary.len() - 30).step_by(5) {
        let mut bytes = binary.clone();
        bytes[i] ^= 0x5a;
        let _ = read_tet_mesh_bytes(&bytes, v);
    }
    let e = fails(
        &vtu(FIVE_POINTS, "0 1 2 9", "4", "10", ""),
        v,
        IndexOutOfRange,
    );
    at_line(&e, 13);
    fails(
        &vtu(FIVE_POINTS, "0 1 2 3", "5", "10", ""),
        v,
        IndexOutOfRange,
    );
    fails(
        &vtu(FIVE_POINTS, "0 1 2 3", "4 2", "10 10", ""),
        v,
        IndexOutOfRange,
    );
    fails(
        &vtu(FIVE_POINTS, "0 1 2 3", "4", "10 10", ""),
        v,
        CountMismatch,
    );
    fails(&vtu(FIVE_POINTS, "0 1 2", "3", "10", ""), v, Syntax);
    fails(&vtu(FIVE_POINTS, "0 1 2", "3", "5", ""), v, Empty);
    let e = fails(
        &good.replace("NumberOfPoints='5'", "NumberOfPoints='6'"),
        v,
        CountMismatch,
    );
    at_line(&e, 5);
    fails(&good.replace("1 1 1", "1 1"), v, CountMismatch);
    let e = fails(
        &good.replace("0 0 1  1 1 1", "0 0 1  1 nan 1"),
        v,
        NonFinite,
    );
    at_line(&e, 9);
    fails(&good.replace("</VTKFile>", ""), v, Truncated);
    fails(&good.replace("</Points>", "</Cells>"), v, Syntax);
    fails(
        &good.replace("Name=\"offsets\"", "Name=\"offset\""),
        v,
        Syntax,
    );
    fails(&good.replace("0 1 2 3", "0 1 x 3"), v, Syntax);
    fails(
        &good.replace("NumberOfComponents=\"3\"", "NumberOfComponents=\"2\""),
        v,
        Syntax,
    );
    fails(&good.replace("<Piece", "<Piece a=b"), v, Syntax);
    fails(
        &good.replace("</Piece>", "</Piece><Piece></Piece>"),
        v,
        Unsupported,
    );
    let kind = "<PointData><DataArray type=\"Int32\" Name=\"kind\" format=\"ascii\">";
    let bad_kind = format!("{kind}0 1 2 3 0</DataArray></PointData>");
    fails(
        &vtu(FIVE_POINTS, "0 1 2 3", "4", "10", &bad_kind),
        v,
        Syntax,
    );
    let short_kind = format!("{kind}0 1 2</DataArray></PointData>");
    fails(
        &vtu(FIVE_POINTS, "0 1 2 3", "4", "10", &short_kind),
        v,
        CountMismatch,
    );
}

// ---------------------------------------------------------------------------------------
// Files

#[test]
fn file_errors_name_the_file() {
    let path = temp_path("mesh.tet");
    let e = read_tet_mesh(&path).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownFormat);
    let e = write_tet_mesh(&path, &cube(), &[]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownFormat);

    let path = temp_path("missing.msh");
    let e = read_tet_mesh(&path).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io);
    assert!(e.to_string().contains("missing.msh"), "{e}");

    let path = temp_path("binary.msh");
    std::fs::write(&path, "$MeshFormat\n4.1 1 8\n").unwrap();
    let e = read_tet_mesh(&path).unwrap_err();
    remove(&path);
    assert_eq!(e.kind(), ErrorKind::Unsupported);
    assert_eq!(e.source_name(), Some(path.display().to_string().as_str()));
    at_line(&e, 2);

    // TetGen: the missing or faulty part is named.
    let node = temp_path("pair.node");
    std::fs::write(&node, "4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n").unwrap();
    let e = read_tet_mesh(&node).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io);
    let ele = node.with_extension("ele");
    assert_eq!(e.source_name(), Some(ele.display().to_string().as_str()));
    std::fs::write(&ele, "1 4 0\n1 1 2 3 5\n").unwrap();
    let e = read_tet_mesh(&ele).unwrap_err();
    remove(&node);
    remove(&ele);
    assert_eq!(e.kind(), ErrorKind::IndexOutOfRange);
    assert_eq!(e.source_name(), Some(ele.display().to_string().as_str()));
    at_line(&e, 2);
}

// ---------------------------------------------------------------------------------------
// Robustness: every prefix, and single-byte corruptions, never panic.

/// Feed `data` to `reader` cut at every length and with each byte replaced by a few
/// troublesome ones: every outcome must be Ok or Err, never a panic.
fn never_panics(data: &[u8], reader: impl Fn(&[u8]) -> necklace::Result<TetMesh>) {
    for cut in 0..=data.len() {
        let _ = reader(&data[..cut]);
    }
    let mut copy = data.to_vec();
    for i in 0..data.len() {
        for byte in [
            b'0', b'9', b'-', b' ', b'\n', b'<', b'>', b'"', b'$', b'#', 0xff,
        ] {
            copy[i] = byte;
            let _ = reader(&copy);
        }
        copy[i] = data[i];
    }
}

#[test]
fn every_prefix_and_corruption_of_valid_files_is_handled() {
    let mesh = cube();
    for format in SINGLE {
        let bytes = write_tet_mesh_bytes(&mesh, format, &[("f", &[0.5; 8])]).unwrap();
        assert!(read_tet_mesh_bytes(&bytes, format).is_ok());
        never_panics(&bytes, |data| read_tet_mesh_bytes(data, format));
    }
    let (node, ele) = write_tetgen_bytes(&mesh).unwrap();
    never_panics(&node, |data| read_tetgen_bytes(data, &ele));
    never_panics(&ele, |data| read_tetgen_bytes(&node, data));
}

#[test]
fn every_prefix_of_the_hand_written_files_is_handled() {
    let vtu_file = vtu(FIVE_POINTS, "4 0 1 2 0 2 1 3", "1 4 8", "1 5 10", "");
    let gmsh_file = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n$EndEntities\n\
                     $Nodes\n1 4 1 4\n3 1 1 4\n1\n2\n3\n4\n0 0 0 9\n1 0 0 9\n0 1 0 9\n0 0 1 9\n$EndNodes\n\
                     $Elements\n2 2 1 2\n2 1 2 1\n1 1 2 3\n3 1 4 1\n2 1 2 3 4\n$EndElements\n";
    let medit_file = "MeshVersionFormatted 2\nDimension 3\n# necklace kinds\nVertices 4\n\
                      0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\nEdges 1 1 2 0\nTetrahedra 1\n1 2 3 4 0\nEnd\n";
    for (data, format) in [
        (vtu_file.as_str(), TetFormat::Vtu),
        (gmsh_file, TetFormat::Gmsh),
        (medit_file, TetFormat::Medit),
    ] {
        read(data, format);
        never_panics(data.as_bytes(), |d| read_tet_mesh_bytes(d, format));
    }
}
