//! Mesh file reading and writing through the public API: round trips, every accepted
//! quirk of each reader on tiny hand-made files, malformed inputs (each with its error
//! kind and location), and every truncation of valid files (never a panic).

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use necklace::io::{read_mesh, read_mesh_bytes, write_mesh, write_mesh_bytes, Format};
use necklace::{Error, ErrorKind, Location, SurfaceMesh};

// ---------------------------------------------------------------------------------------
// Helpers

fn read(data: impl AsRef<[u8]>, format: Format) -> SurfaceMesh {
    match read_mesh_bytes(data.as_ref(), format) {
        Ok(mesh) => mesh,
        Err(e) => panic!("expected a mesh, got error: {e}"),
    }
}

/// Read malformed data: it must fail with `kind`.
fn fails(data: impl AsRef<[u8]>, format: Format, kind: ErrorKind) -> Error {
    match read_mesh_bytes(data.as_ref(), format) {
        Ok(mesh) => panic!("expected a {kind:?} error, got a mesh: {mesh:?}"),
        Err(e) => {
            assert_eq!(e.kind(), kind, "wrong kind for error: {e}");
            assert!(!e.to_string().contains('\n'), "multi-line message: {e:?}");
            e
        }
    }
}

fn at_line(e: &Error, line: usize) {
    assert_eq!(e.location(), Some(Location::Line(line)), "error: {e}");
}

fn at_byte(e: &Error, byte: u64) {
    assert_eq!(e.location(), Some(Location::Byte(byte)), "error: {e}");
}

fn mentions(e: &Error, words: &[&str]) {
    for word in words {
        assert!(e.message().contains(word), "'{word}' not in: {e}");
    }
}

/// A unique path in the temp dir (removed by the caller).
fn temp_path(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("necklace-io-{}-{n}-{name}", std::process::id()))
}

fn bits(mesh: &SurfaceMesh) -> Vec<[u64; 3]> {
    mesh.positions.iter().map(|p| p.map(f64::to_bits)).collect()
}

fn assert_same(a: &SurfaceMesh, b: &SurfaceMesh) {
    assert_eq!(bits(a), bits(b), "positions differ (bitwise)");
    assert_eq!(a.triangles, b.triangles);
}

/// The unit tetrahedron, outward-oriented.
fn tetrahedron() -> SurfaceMesh {
    SurfaceMesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

/// A mesh whose coordinates are hard to print and parse exactly.
fn awkward_mesh() -> SurfaceMesh {
    SurfaceMesh {
        positions: vec![
            [0.1, -1e-300, 1e300],
            [1.0 / 3.0, -0.0, 2.5e-8],
            [-7.0, 123456.789, f64::MIN_POSITIVE],
            [5e-324, f64::MAX, -f64::EPSILON],
            [std::f64::consts::PI, -1.0 / 7.0, 0.0],
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3], [1, 3, 2], [0, 3, 1], [4, 0, 1]],
    }
}

// ---------------------------------------------------------------------------------------
// Round trips

#[test]
fn round_trip_in_memory() {
    let mesh = awkward_mesh();
    for format in [Format::Obj, Format::Off, Format::Ply] {
        let bytes = write_mesh_bytes(&mesh, format).unwrap();
        let back = read(&bytes, format);
        assert_same(&mesh, &back);
        // -0.0 survives as -0.0.
        assert_eq!(back.positions[1][1].to_bits(), (-0.0f64).to_bits());
    }
}

#[test]
fn round_trip_through_files() {
    let mesh = awkward_mesh();
    for ext in ["obj", "off", "ply", "OBJ"] {
        let path = temp_path(&format!("round-trip.{ext}"));
        write_mesh(&path, &mesh).unwrap();
        let back = read_mesh(&path);
        std::fs::remove_file(&path).unwrap();
        assert_same(&mesh, &back.unwrap());
    }
}

#[test]
fn writers_produce_the_documented_text() {
    let mesh = tetrahedron();
    let obj = String::from_utf8(write_mesh_bytes(&mesh, Format::Obj).unwrap()).unwrap();
    assert!(obj.starts_with('#'));
    assert!(obj.contains("\nv 1 0 0\n"));
    assert!(obj.ends_with("\nf 2 3 4\n"));
    let off = String::from_utf8(write_mesh_bytes(&mesh, Format::Off).unwrap()).unwrap();
    assert!(off.starts_with("OFF\n4 4 0\n0 0 0\n"));
    assert!(off.ends_with("\n3 1 2 3\n"));
    let ply = write_mesh_bytes(&mesh, Format::Ply).unwrap();
    let header = "ply\nformat binary_little_endian 1.0\ncomment written by necklace\n\
                  element vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
                  element face 4\nproperty list uchar uint vertex_indices\nend_header\n";
    assert!(ply.starts_with(header.as_bytes()));
    assert_eq!(ply.len(), header.len() + 4 * 24 + 4 * 13);
}

#[test]
fn stl_cannot_be_written() {
    let e = write_mesh_bytes(&tetrahedron(), Format::Stl).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Unsupported);
}

// ---------------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_slash_forms() {
    let data = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n\
                f 1 3 2\nf 1/1 2/1 4/1\nf 1//1 4//1 3//1\nf 2/1/1 3/1/1 4/1/1\n";
    assert_same(&read(data, Format::Obj), &tetrahedron());
}

#[test]
fn a_large_polygon_becomes_a_valid_triangulation_with_no_high_valence_corner() {
    // A convex 1000-gon: n − 2 triangles that tile it (their areas sum to the
    // polygon's, each one positively oriented), no corner in more than 2 log2(n) + 2.
    let n = 1000usize;
    let mut data = String::new();
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        data += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    data += "f";
    for i in 1..=n {
        data += &format!(" {i}");
    }
    let mesh = read(&data, Format::Obj);
    assert_eq!(mesh.triangles.len(), n - 2);
    let mut area = 0.0;
    let mut valence = vec![0usize; n];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let twice = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(twice > 0.0, "{t:?} is not counter-clockwise");
        area += 0.5 * twice;
        for &v in t {
            valence[v as usize] += 1;
        }
    }
    let polygon = 0.5 * n as f64 * (std::f64::consts::TAU / n as f64).sin();
    assert!((area - polygon).abs() < 1e-9, "{area} vs {polygon}");
    assert!(
        valence.iter().all(|&k| k <= 2 * 10 + 2),
        "{:?}",
        valence.iter().max()
    );
}

#[test]
fn obj_negative_indices_are_relative() {
    let data =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -1 -2\nv 0 0 1\nf -4 -3 -1\nf 1 -1 -2\nf -3 -2 -1\n";
    assert_same(&read(data, Format::Obj), &tetrahedron());
}

#[test]
fn obj_quads_are_fan_split_and_larger_polygons_halved() {
    let data = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf 1 2 3 4\nf 1 4 5 2/1 3//2\n";
    let mesh = read(data, Format::Obj);
    assert_eq!(mesh.positions.len(), 5);
    // The pentagon (0 3 4 1 2): the triangle on its first, middle and last corners,
    // then each half's arc.
    assert_eq!(
        mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 4, 2], [0, 3, 4], [4, 1, 2]]
    );
}

#[test]
fn obj_ignores_other_statements_crlf_tabs_and_continuations() {
    let data = "# a comment\r\nmtllib a.mtl\r\no thing\r\ng group\r\ns 1\r\nusemtl red\r\n\
                v\t0 0 0\r\n  v 1 0 0 1.0\r\nv 0 \\\r\n 1 \\\r\n 0\r\nvt 0.5 0.5\r\nvn 0 0 1\r\n\
                vp 0.1\r\n\r\nv 0 0 1 # trailing comment\r\nl 1 2\r\np 3\r\n\
                f 1 3 2\r\nf\t1 2 4\r\nf 1 4 \\\r\n3\r\nf 2 3 4";
    assert_same(&read(data, Format::Obj), &tetrahedron());
}

#[test]
fn obj_faces_may_refer_to_later_vertices() {
    let data = "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
    assert_same(&read(data, Format::Obj), &tetrahedron());
}

#[test]
fn obj_malformed() {
    use ErrorKind::*;
    let obj = Format::Obj;
    fails("", obj, Empty);
    fails(" \n\t\r\n", obj, Empty);
    let e = fails("# only a comment\ng nothing\n", obj, Empty);
    mentions(&e, &["no vertices"]);
    let e = fails("v 0 0 0\nv 1 0 0\nv 0 1 0\n", obj, Empty);
    mentions(&e, &["no faces"]);

    let e = fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", obj, IndexOutOfRange);
    at_line(&e, 4);
    mentions(&e, &["0"]);
    // Out of range is detected at the end, but names the face's line.
    let e = fails(
        "v 0 0 0\nv 1 0 0\nf 1 2 7\nv 0 1 0\nf 1 2 3\n",
        obj,
        IndexOutOfRange,
    );
    at_line(&e, 3);
    mentions(&e, &["7", "3 vertices"]);
    let e = fails(
        "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n",
        obj,
        IndexOutOfRange,
    );
    at_line(&e, 3);
    mentions(&e, &["-3", "2 vertices"]);
    let e = fails("f 1 2 3\n", obj, IndexOutOfRange);
    mentions(&e, &["0 vertices"]);
    fails(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n",
        obj,
        IndexOutOfRange,
    );

    let e = fails("v 0 0 0\nv 1 nan 0\n", obj, NonFinite);
    at_line(&e, 2);
    let e = fails("v 0 0 0\nv 1 0 -inf\n", obj, NonFinite);
    at_line(&e, 2);
    fails("v 1e400 0 0\n", obj, NonFinite);
    let e = fails("v 0 0 0\n\nv 1 2\n", obj, Syntax);
    at_line(&e, 3);
    let e = fails("v 0 0 0\nv 1 0 0\nf 1 2\n", obj, Syntax);
    at_line(&e, 3);
    mentions(&e, &["2 vertices"]);
    let e = fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n", obj, Syntax);
    at_line(&e, 4);
    mentions(&e, &["'x'"]);
    fails("v 0 0 zero\n", obj, Syntax);
    fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 /2 3\n", obj, Syntax);
    fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2.5 3\n", obj, Syntax);
    fails(b"v 0 0 \xff\xfe\n".as_slice(), obj, Syntax);
}

// ---------------------------------------------------------------------------------------
// OFF

const TETRA_OFF_FACES: &str = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

#[test]
fn off_comments_and_blank_lines_anywhere() {
    let data = "# leading comment\n\nOFF # the header\n# between\n\n4 4 6 # counts\n\
                0 0 0 # a vertex\n\n1 0 0\n# comment line\n0 1 0\n0 0 1\n\n\
                3 0 2 1 # a face\n3 0 1 3\n\n# another\n3 0 3 2\n3 1 2 3\n\n# the end\n";
    assert_same(&read(data, Format::Off), &tetrahedron());
}

#[test]
fn off_counts_on_header_line_and_missing_edge_count() {
    let vertices = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
    for head in ["OFF 4 4 6\n", "OFF 4 4\n", "OFF\n4 4\n", "OFF\t4\t4\t0\n"] {
        let data = format!("{head}{vertices}{TETRA_OFF_FACES}");
        assert_same(&read(data, Format::Off), &tetrahedron());
    }
}

#[test]
fn off_last_line_without_newline_crlf_and_extra_lines() {
    let data = "OFF\r\n4 4 6\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n0 0 1\r\n\
                3 0 2 1\r\n3 0 1 3\r\n3 0 3 2\r\n3 1 2 3";
    assert_same(&read(data, Format::Off), &tetrahedron());
    let data = format!("OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n{TETRA_OFF_FACES}1 2 3\nextra\n");
    assert_same(&read(data, Format::Off), &tetrahedron());
}

#[test]
fn off_variants_with_extra_columns() {
    // COFF: colours after vertices and faces; NOFF: normals; CNOFF: both.
    let data = "COFF\n4 4 6\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n\
                0 0 1 9 9 9 9\n3 0 2 1 255 0 0\n3 0 1 3 0.5 0.5 0.5 1\n3 0 3 2\n3 1 2 3 1 1 1\n";
    assert_same(&read(data, Format::Off), &tetrahedron());
    for keyword in ["NOFF", "CNOFF", "STOFF"] {
        let data = format!(
            "{keyword}\n4 4 0\n0 0 0 0 0 1 0.1 0.2 0.3\n1 0 0 1 0 0\n0 1 0 0 1 0\n0 0 1 0 0 1\n\
             {TETRA_OFF_FACES}"
        );
        assert_same(&read(data, Format::Off), &tetrahedron());
    }
}

#[test]
fn off_quads_are_fan_split_and_larger_polygons_halved() {
    let data = "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n-1 0.5 0\n4 0 1 2 3\n5 0 3 4 1 2\n";
    let mesh = read(data, Format::Off);
    assert_eq!(
        mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 4, 2], [0, 3, 4], [4, 1, 2]]
    );
    assert_eq!(mesh.positions[4], [-1.0, 0.5, 0.0]);
}

#[test]
fn off_malformed() {
    use ErrorKind::*;
    let off = Format::Off;
    fails("", off, Empty);
    fails("\n  \n", off, Empty);

    let e = fails("OFF\n4 4 6\n0 0 0\n1 0 0\n", off, Truncated);
    mentions(&e, &["expected 4 vertices, found 2"]);
    at_line(&e, 4);
    let e = fails(
        "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n# comment\n",
        off,
        Truncated,
    );
    mentions(&e, &["expected 4 faces, found 1"]);
    at_line(&e, 8);
    fails("OFF\n", off, Truncated);
    let e = fails("OFF\nfour 4 6\n", off, Syntax);
    at_line(&e, 2);
    mentions(&e, &["'four'"]);
    let e = fails("OFF\n-4 4 6\n", off, CountMismatch);
    at_line(&e, 2);
    fails("OFF 4 -1\n", off, CountMismatch);
    fails("OFF\n4\n", off, Syntax);
    let e = fails(
        "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 4\n",
        off,
        IndexOutOfRange,
    );
    at_line(&e, 8);
    mentions(&e, &["4", "4 vertices"]);
    fails(
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
        off,
        IndexOutOfRange,
    );
    let e = fails(
        format!("OFF\n4 4 6\n0 0 0\n1 inf 0\n0 1 0\n0 0 1\n{TETRA_OFF_FACES}"),
        off,
        NonFinite,
    );
    at_line(&e, 4);
    fails(
        format!("OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 NaN\n0 0 1\n{TETRA_OFF_FACES}"),
        off,
        NonFinite,
    );
    let e = fails("4 4 6\n0 0 0\n", off, Syntax);
    mentions(&e, &["missing OFF header"]);
    at_line(&e, 1);
    fails("PFF\n3 1 0\n", off, Syntax);
    let e = fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", off, Syntax);
    at_line(&e, 6);
    fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", off, Syntax);
    fails("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", off, Syntax);
    fails("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", off, Empty);
    fails("OFF BINARY\n", off, Unsupported);
    fails("4OFF\n3 1\n", off, Unsupported);
}

// ---------------------------------------------------------------------------------------
// PLY

/// One PLY value: its type name and its value.
type Value = (&'static str, f64);

/// A PLY file from its element/property header lines and its records (one per line in
/// ascii; packed in binary).
fn ply_file(format: &str, elements: &str, records: &[Vec<Value>]) -> Vec<u8> {
    let mut out = format!("ply\nformat {format} 1.0\n{elements}end_header\n").into_bytes();
    let big_endian = format == "binary_big_endian";
    for record in records {
        if format == "ascii" {
            let line: Vec<String> = record.iter().map(|(_, v)| v.to_string()).collect();
            out.extend_from_slice(line.join(" ").as_bytes());
            out.push(b'\n');
        } else {
            for &(ty, v) in record {
                let mut bytes = match ty {
                    "char" | "int8" => (v as i8).to_le_bytes().to_vec(),
                    "uchar" | "uint8" => (v as u8).to_le_bytes().to_vec(),
                    "short" | "int16" => (v as i16).to_le_bytes().to_vec(),
                    "ushort" | "uint16" => (v as u16).to_le_bytes().to_vec(),
                    "int" | "int32" => (v as i32).to_le_bytes().to_vec(),
                    "uint" | "uint32" => (v as u32).to_le_bytes().to_vec(),
                    "float" | "float32" => (v as f32).to_le_bytes().to_vec(),
                    "double" | "float64" => v.to_le_bytes().to_vec(),
                    _ => panic!("bad type {ty}"),
                };
                if big_endian {
                    bytes.reverse();
                }
                out.extend_from_slice(&bytes);
            }
        }
    }
    out
}

const PLY_FORMATS: [&str; 3] = ["ascii", "binary_little_endian", "binary_big_endian"];

/// Tetrahedron records with x/y/z as `ty` and faces as `list uchar int`.
fn simple_ply(format: &str, ty: &'static str) -> Vec<u8> {
    let elements = format!(
        "element vertex 4\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\n\
         element face 4\nproperty list uchar int vertex_indices\n"
    );
    let mesh = tetrahedron();
    let mut records: Vec<Vec<Value>> = mesh
        .positions
        .iter()
        .map(|p| p.iter().map(|&c| (ty, c)).collect())
        .collect();
    for t in &mesh.triangles {
        let mut record = vec![("uchar", 3.0)];
        record.extend(t.iter().map(|&i| ("int", f64::from(i))));
        records.push(record);
    }
    ply_file(format, &elements, &records)
}

#[test]
fn ply_ascii_and_binary_with_any_coordinate_type() {
    for format in PLY_FORMATS {
        for ty in [
            "float", "double", "uchar", "int", "short", "int8", "uint16", "uint",
        ] {
            let mesh = read(simple_ply(format, ty), Format::Ply);
            assert_same(&mesh, &tetrahedron());
        }
    }
}

#[test]
fn ply_skips_extra_properties_and_elements() {
    let elements = "comment an extra element comes first\n\
                    obj_info made by hand\n\
                    element material 2\n\
                    property uchar red\n\
                    property list int float weights\n\
                    element vertex 4\n\
                    property short tag\n\
                    property double x\n\
                    property list uchar int neighbours\n\
                    property float y\n\
                    property int8 flag\n\
                    property float z\n\
                    property ushort id\n\
                    element face 4\n\
                    property uchar flags\n\
                    property list ushort int vertex_index\n\
                    property list uint float texcoord\n\
                    property double quality\n\
                    element edge 1\n\
                    property int vertex1\n\
                    property list short uchar more\n";
    let mut records: Vec<Vec<Value>> = vec![
        vec![
            ("uchar", 200.0),
            ("int", 2.0),
            ("float", 0.5),
            ("float", -1.5),
        ],
        vec![("uchar", 1.0), ("int", 0.0)],
    ];
    let mesh = tetrahedron();
    for (i, p) in mesh.positions.iter().enumerate() {
        let mut record = vec![("short", -7.0), ("double", p[0]), ("uchar", i as f64)];
        record.extend((0..i).map(|k| ("int", k as f64)));
        record.extend([
            ("float", p[1]),
            ("int8", -1.0),
            ("float", p[2]),
            ("ushort", 65535.0),
        ]);
        records.push(record);
    }
    for t in &mesh.triangles {
        let mut record = vec![("uchar", 9.0), ("ushort", 3.0)];
        record.extend(t.iter().map(|&i| ("int", f64::from(i))));
        record.extend([("uint", 2.0), ("float", 0.25), ("float", 0.75)]);
        record.push(("double", 1e10));
        records.push(record);
    }
    records.push(vec![("int", 5.0), ("short", 1.0), ("uchar", 8.0)]);
    for format in PLY_FORMATS {
        let mesh = read(ply_file(format, elements, &records), Format::Ply);
        assert_same(&mesh, &tetrahedron());
    }
}

#[test]
fn ply_list_count_types_and_fan_split() {
    for count in [
        "uchar", "ushort", "uint", "int", "char", "short", "uint8", "int32",
    ] {
        for item in ["int", "uint", "ushort", "uchar", "int16"] {
            let elements = format!(
                "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
                 element face 2\nproperty list {count} {item} vertex_indices\n"
            );
            let mut records: Vec<Vec<Value>> = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
                .iter()
                .chain(&[[0.0, 1.0, 0.0], [-1.0, 0.5, 0.0]])
                .map(|p| p.iter().map(|&c| ("float", c)).collect())
                .collect();
            records.push(vec![
                (count, 4.0),
                (item, 0.0),
                (item, 1.0),
                (item, 2.0),
                (item, 3.0),
            ]);
            records.push(vec![(count, 3.0), (item, 4.0), (item, 0.0), (item, 3.0)]);
            for format in PLY_FORMATS {
                let mesh = read(ply_file(format, &elements, &records), Format::Ply);
                assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [4, 0, 3]]);
                assert_eq!(mesh.positions[4], [-1.0, 0.5, 0.0]);
            }
        }
    }
}

#[test]
fn ply_face_element_before_vertex_element() {
    let elements = "element face 1\nproperty list uchar uint vertex_indices\n\
                    element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    let records: Vec<Vec<Value>> = vec![
        vec![("uchar", 3.0), ("uint", 2.0), ("uint", 1.0), ("uint", 0.0)],
        vec![("float", 0.0), ("float", 0.0), ("float", 0.0)],
        vec![("float", 1.0), ("float", 0.0), ("float", 0.0)],
        vec![("float", 0.0), ("float", 1.0), ("float", 0.0)],
    ];
    for format in PLY_FORMATS {
        let mesh = read(ply_file(format, elements, &records), Format::Ply);
        assert_eq!(mesh.triangles, vec![[2, 1, 0]]);
        assert_eq!(mesh.positions[2], [0.0, 1.0, 0.0]);
    }
}

#[test]
fn ply_crlf_header() {
    for format in PLY_FORMATS {
        let data = simple_ply(format, "float");
        let end = b"end_header\n";
        let split = data.windows(end.len()).position(|w| w == end).unwrap() + end.len();
        let header = String::from_utf8(data[..split].to_vec()).unwrap();
        let mut crlf = header.replace('\n', "\r\n").into_bytes();
        if format == "ascii" {
            // Ascii data lines may end in CRLF too; binary data follows the "\n" at once.
            let body = String::from_utf8(data[split..].to_vec()).unwrap();
            crlf.extend_from_slice(body.replace('\n', "\r\n").as_bytes());
        } else {
            crlf.extend_from_slice(&data[split..]);
        }
        assert_same(&read(crlf, Format::Ply), &tetrahedron());
    }
}

fn vertex3() -> Vec<Vec<Value>> {
    vec![
        vec![("float", 0.0), ("float", 0.0), ("float", 0.0)],
        vec![("float", 1.0), ("float", 0.0), ("float", 0.0)],
        vec![("float", 0.0), ("float", 1.0), ("float", 0.0)],
    ]
}

const TRIANGLE_HEADER: &str = "element vertex 3\nproperty float x\nproperty float y\n\
                               property float z\nelement face 1\n\
                               property list uchar int vertex_indices\n";

fn triangle_ply(format: &str, face: Vec<Value>) -> Vec<u8> {
    let mut records = vertex3();
    records.push(face);
    ply_file(format, TRIANGLE_HEADER, &records)
}

#[test]
fn ply_malformed_header() {
    use ErrorKind::*;
    let ply = Format::Ply;
    let good = simple_ply("ascii", "float");
    assert_same(&read(&good, ply), &tetrahedron());
    let text = String::from_utf8(good).unwrap();

    let e = fails(text.replace("end_header\n", ""), ply, Syntax);
    mentions(&e, &["end_header"]);
    let e = fails(text.replace("ascii", "binary_middle_endian"), ply, Syntax);
    at_line(&e, 2);
    mentions(&e, &["binary_middle_endian"]);
    let e = fails(
        text.replace("property float y", "property float3 y"),
        ply,
        Syntax,
    );
    at_line(&e, 5);
    mentions(&e, &["float3"]);
    fails(
        text.replace("list uchar int", "list float int"),
        ply,
        Syntax,
    );
    fails(text.replace("list uchar int", "list uchar"), ply, Syntax);
    let e = fails(text.replace("ply\n", "plx\n"), ply, Syntax);
    at_line(&e, 1);
    fails(text.replace("format ascii 1.0\n", ""), ply, Syntax);
    fails(
        text.replace("element vertex 4", "element vertex -4"),
        ply,
        Syntax,
    );
    fails(
        text.replace("element vertex 4", "element vertex four"),
        ply,
        Syntax,
    );
    let e = fails(
        text.replace("element vertex", "bogus line\nelement vertex"),
        ply,
        Syntax,
    );
    at_line(&e, 3);
    fails(text.replace("element vertex 4\n", ""), ply, Syntax);

    let e = fails(text.replace("element vertex", "element point"), ply, Syntax);
    mentions(&e, &["vertex"]);
    let e = fails(
        text.replace("element face 4", "element polygon 4"),
        ply,
        Syntax,
    );
    mentions(&e, &["face"]);
    let e = fails(text.replace("float z", "float w"), ply, Syntax);
    mentions(&e, &["'z'"]);
    at_line(&e, 3);
    let e = fails(text.replace("vertex_indices", "corners"), ply, Syntax);
    mentions(&e, &["vertex_indices"]);
    fails(
        text.replace("list uchar int", "list uchar float"),
        ply,
        Syntax,
    );
    fails(text.replace("float x", "list uchar float x"), ply, Syntax);
}

#[test]
fn ply_malformed_data() {
    use ErrorKind::*;
    let ply = Format::Ply;
    let le = "binary_little_endian";
    // Header length of the triangle files, to check byte offsets.
    let header_len = triangle_ply(
        le,
        vec![("uchar", 3.0), ("int", 0.0), ("int", 1.0), ("int", 2.0)],
    )
    .len()
        - 3 * 12
        - 13;

    // Binary truncated in the middle of a vertex.
    let good = simple_ply(le, "float");
    let e = fails(&good[..good.len() - 40], ply, Truncated);
    assert!(matches!(e.location(), Some(Location::Byte(_))), "{e}");

    // Face list count 2.
    let e = fails(
        triangle_ply(le, vec![("uchar", 2.0), ("int", 0.0), ("int", 1.0)]),
        ply,
        Syntax,
    );
    at_byte(&e, header_len as u64 + 36);
    let e = fails(
        triangle_ply("ascii", vec![("uchar", 2.0), ("int", 0.0), ("int", 1.0)]),
        ply,
        Syntax,
    );
    at_line(&e, 13);
    // Negative list count and negative index.
    let negative_count = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                          element face 1\nproperty list int int vertex_indices\n";
    let mut records = vertex3();
    records.push(vec![
        ("int", -3.0),
        ("int", 0.0),
        ("int", 1.0),
        ("int", 2.0),
    ]);
    fails(ply_file(le, negative_count, &records), ply, Syntax);
    fails(ply_file("ascii", negative_count, &records), ply, Syntax);
    let e = fails(
        triangle_ply(
            le,
            vec![("uchar", 3.0), ("int", 0.0), ("int", -1.0), ("int", 2.0)],
        ),
        ply,
        IndexOutOfRange,
    );
    at_byte(&e, header_len as u64 + 36 + 5);
    let e = fails(
        triangle_ply(
            "ascii",
            vec![("uchar", 3.0), ("int", 0.0), ("int", 3.0), ("int", 2.0)],
        ),
        ply,
        IndexOutOfRange,
    );
    at_line(&e, 13);
    mentions(&e, &["3", "3 vertices"]);

    // Non-finite coordinates.
    let mut records = vertex3();
    records[1][2] = ("float", f64::NAN);
    records.push(vec![
        ("uchar", 3.0),
        ("int", 0.0),
        ("int", 1.0),
        ("int", 2.0),
    ]);
    let e = fails(ply_file(le, TRIANGLE_HEADER, &records), ply, NonFinite);
    at_byte(&e, header_len as u64 + 12 + 8);
    let e = fails(ply_file("ascii", TRIANGLE_HEADER, &records), ply, NonFinite);
    at_line(&e, 11);

    // Ascii records with too few or too many values, or bad numbers.
    let text = String::from_utf8(simple_ply("ascii", "float")).unwrap();
    let e = fails(text.replacen("\n1 0 0\n", "\n1 0\n", 1), ply, Syntax);
    at_line(&e, 11);
    fails(text.replacen("\n1 0 0\n", "\n1 0 0 0\n", 1), ply, Syntax);
    fails(text.replacen("\n1 0 0\n", "\n1 zero 0\n", 1), ply, Syntax);
    fails(text.replacen("3 0 2 1", "3 0 2.5 1", 1), ply, Syntax);
    fails(text.replacen("3 0 2 1", "300 0 2 1", 1), ply, Syntax);
    let e = fails(text.replacen("3 1 2 3\n", "", 1), ply, Truncated);
    mentions(&e, &["expected 4 'face' records, found 3"]);

    // No faces.
    let elements = TRIANGLE_HEADER.replace("face 1", "face 0");
    fails(ply_file(le, &elements, &vertex3()), ply, Empty);
}

#[test]
fn ply_hostile_counts_fail_fast() {
    use ErrorKind::*;
    let ply = Format::Ply;
    let le = "binary_little_endian";
    // A reader that trusted these counts would reserve tens of gigabytes and abort.
    let huge_faces = TRIANGLE_HEADER.replace("face 1", "face 4000000000");
    let mut records = vertex3();
    records.push(vec![
        ("uchar", 3.0),
        ("int", 0.0),
        ("int", 1.0),
        ("int", 2.0),
    ]);
    let e = fails(ply_file(le, &huge_faces, &records), ply, Truncated);
    assert!(matches!(e.location(), Some(Location::Byte(_))), "{e}");
    mentions(&e, &["4000000000"]);
    let huge_vertices = TRIANGLE_HEADER.replace("vertex 3", "vertex 4000000000");
    fails(ply_file(le, &huge_vertices, &records), ply, Truncated);
    let huge_other =
        format!("element junk 18446744073709551615\nproperty double a\n{TRIANGLE_HEADER}");
    fails(ply_file(le, &huge_other, &records), ply, Truncated);
    // A list count of 4 billion, in the face list and in a skipped list.
    let mut records = vertex3();
    records.push(vec![
        ("uint", 4e9),
        ("int", 0.0),
        ("int", 1.0),
        ("int", 2.0),
    ]);
    let elements = TRIANGLE_HEADER.replace("list uchar", "list uint");
    fails(ply_file(le, &elements, &records), ply, Truncated);
    let elements = format!("{TRIANGLE_HEADER}property list uint double junk\n");
    let mut records = vertex3();
    records.push(vec![
        ("uchar", 3.0),
        ("int", 0.0),
        ("int", 1.0),
        ("int", 2.0),
        ("uint", 4e9),
    ]);
    fails(ply_file(le, &elements, &records), ply, Truncated);
    // Ascii, too.
    let mut records = vertex3();
    records.push(vec![
        ("uchar", 3.0),
        ("int", 0.0),
        ("int", 1.0),
        ("int", 2.0),
    ]);
    fails(ply_file("ascii", &huge_faces, &records), ply, Truncated);
}

// ---------------------------------------------------------------------------------------
// STL

/// The tetrahedron's facets as corner triples.
fn tetra_facets() -> Vec<[[f32; 3]; 3]> {
    let mesh = tetrahedron();
    mesh.triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize].map(|c| c as f32)))
        .collect()
}

fn binary_stl(header: &[u8], facets: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut out = header.to_vec();
    out.resize(80, b' ');
    out.extend_from_slice(&(facets.len() as u32).to_le_bytes());
    for facet in facets {
        out.extend_from_slice(&[0; 12]); // normal
        for corner in facet {
            for c in corner {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]); // attribute
    }
    out
}

fn ascii_stl(facets: &[[[f32; 3]; 3]]) -> String {
    let mut out = String::from("solid tetra\n");
    for facet in facets {
        out.push_str("  facet normal 0 0 0\n    outer loop\n");
        for [x, y, z] in facet {
            out.push_str(&format!("      vertex {x:e} {y:e} {z:e}\n"));
        }
        out.push_str("    endloop\n  endfacet\n");
    }
    out.push_str("endsolid tetra\n");
    out
}

#[test]
fn stl_ascii_welds_corners() {
    let mesh = read(ascii_stl(&tetra_facets()), Format::Stl);
    // First appearance order: facet 0 is (0, 2, 1) of the tetrahedron.
    assert_eq!(
        mesh.positions,
        vec![
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0]
        ]
    );
    assert_eq!(
        mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [2, 1, 3]]
    );
}

#[test]
fn stl_ascii_quirks() {
    // Any case and whitespace, CRLF, no names, -0 welded with 0, two solids.
    let data = "SOLID\r\nFacet Normal 0 0 -1\r\n\tOuter Loop\r\n vertex 0 0 0\r\nvertex 0 1 0\r\n\
                VERTEX 1 0 0\r\n endLoop\r\nENDFACET\r\nfacet normal nan nan nan outer loop \
                vertex -0 0 -0.0 vertex 1 0 0 vertex 0 0 1 endloop endfacet\r\n\
                endsolid\r\n  solid second one\n facet normal 0 0 0\n outer loop\n\
                vertex 0e0 0 0\nvertex 0 0 1e0\nvertex 0 1 0\nendloop\nendfacet\n\
                facet normal 0 0 0 outer loop vertex 1 0 0 vertex 0.0 1 0 vertex 0 0 1 \
                endloop endfacet endsolid second one";
    let mesh = read(data, Format::Stl);
    assert_eq!(mesh.positions.len(), 4);
    assert_eq!(mesh.triangles.len(), 4);
    assert_eq!(
        mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [2, 1, 3]]
    );
    assert_eq!(mesh.positions[0][0].to_bits(), 0.0f64.to_bits());
}

#[test]
fn stl_binary_welds_corners() {
    let facets = tetra_facets();
    let ascii = read(ascii_stl(&facets), Format::Stl);
    for header in [
        &b"binary tetrahedron"[..],
        b"solid tetra (a binary file)",
        b"",
    ] {
        let data = binary_stl(header, &facets);
        let mesh = read(&data, Format::Stl);
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.triangles.len(), 4);
        assert_same(&mesh, &ascii);
    }
}

#[test]
fn stl_binary_keeps_f32_values_exactly() {
    let facets = vec![[
        [0.1f32, -0.0, 3e38],
        [1.0 / 3.0, 2.0, 1e-40],
        [0.1, 0.0, 3e38],
    ]];
    let mesh = read(binary_stl(b"", &facets), Format::Stl);
    assert_eq!(mesh.positions.len(), 2);
    assert_eq!(mesh.triangles, vec![[0, 1, 0]]);
    assert_eq!(
        mesh.positions[0],
        [f64::from(0.1f32), 0.0, f64::from(3e38f32)]
    );
    assert_eq!(mesh.positions[1][2], f64::from(1e-40f32));
}

#[test]
fn stl_malformed() {
    use ErrorKind::*;
    let stl = Format::Stl;
    let facets = tetra_facets();

    // Binary with a count that disagrees with the size.
    let mut data = binary_stl(b"binary", &facets);
    data[80] = 5;
    let e = fails(&data, stl, Truncated);
    mentions(&e, &["5 triangles", "284 bytes"]);
    let mut data = binary_stl(b"solid but binary", &facets);
    data.truncate(data.len() - 10);
    let e = fails(&data, stl, Truncated);
    mentions(&e, &["4 triangles", "274 bytes"]);
    fails(b"\x00\x01\x02".as_slice(), stl, Truncated);
    let mut data = binary_stl(b"", &facets);
    data[84 + 50 + 12 + 4..84 + 50 + 12 + 8].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let e = fails(&data, stl, NonFinite);
    at_byte(&e, 84 + 50 + 16);
    fails(binary_stl(b"", &[]), stl, Empty);

    let text = ascii_stl(&facets);
    // A facet with two vertices (lines 1-7 are the first facet).
    let e = fails(
        text.replacen("      vertex 0e0 1e0 0e0\n", "", 1),
        stl,
        Syntax,
    );
    mentions(&e, &["2 vertices"]);
    at_line(&e, 6);
    let e = fails(
        text.replacen("vertex 0e0 1e0 0e0", "vertex 0e0 one 0e0", 1),
        stl,
        Syntax,
    );
    at_line(&e, 5);
    mentions(&e, &["'one'"]);
    let e = fails(
        text.replacen("vertex 0e0 1e0 0e0", "vertex 0e0 NaN 0e0", 1),
        stl,
        NonFinite,
    );
    at_line(&e, 5);
    let e = fails(text.replacen("outer loop", "outer space", 1), stl, Syntax);
    at_line(&e, 3);
    fails(text.replacen("endfacet", "endfacets", 1), stl, Syntax);
    fails(
        text.replacen("facet normal 0 0 0", "facet 0 0 0", 1),
        stl,
        Syntax,
    );
    fails(text.replace("endsolid tetra\n", ""), stl, Truncated);
    fails(&text[..text.len() / 2], stl, Truncated);
    fails(format!("{text}garbage\n"), stl, Syntax);
    fails("solid empty\nendsolid empty\n", stl, Empty);
    fails(
        "not an stl file at all, but long enough to be more than 84 bytes long, oh yes it is",
        stl,
        Truncated,
    );
}

// ---------------------------------------------------------------------------------------
// Files and formats

#[test]
fn unknown_format_and_missing_file() {
    let path = temp_path("noise.xyz");
    let noise: Vec<u8> = (0..200u32)
        .map(|i| (i.wrapping_mul(37) % 128) as u8 | 0x80)
        .collect();
    std::fs::write(&path, noise).unwrap();
    let result = read_mesh(&path);
    std::fs::remove_file(&path).unwrap();
    let e = result.unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownFormat, "{e}");
    assert!(e.to_string().contains("noise.xyz"), "{e}");

    let path = temp_path("does-not-exist.obj");
    let e = read_mesh(&path).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io, "{e}");
    assert!(e.to_string().contains("does-not-exist.obj"), "{e}");
}

#[test]
fn errors_from_files_name_the_file_and_line() {
    let path = temp_path("bad.off");
    std::fs::write(&path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n").unwrap();
    let e = read_mesh(&path).unwrap_err();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(e.kind(), ErrorKind::IndexOutOfRange);
    let shown = e.to_string();
    assert!(shown.contains("bad.off: line 6: "), "{shown}");
}

#[test]
fn content_sniffing_without_extension() {
    let mesh = tetrahedron();
    for format in [Format::Obj, Format::Off, Format::Ply] {
        let path = temp_path(&format!("sniffed-{}", format.name()));
        std::fs::write(&path, write_mesh_bytes(&mesh, format).unwrap()).unwrap();
        let back = read_mesh(&path);
        std::fs::remove_file(&path).unwrap();
        assert_same(&back.unwrap(), &mesh);
    }
}

// ---------------------------------------------------------------------------------------
// Robustness: every truncation and every single-byte corruption returns, never panics.

fn samples() -> Vec<(&'static str, Format, Vec<u8>)> {
    let mesh = awkward_mesh();
    let mut mixed = simple_ply("binary_big_endian", "double");
    mixed.extend_from_slice(b"trailing bytes are ignored");
    vec![
        (
            "obj",
            Format::Obj,
            write_mesh_bytes(&mesh, Format::Obj).unwrap(),
        ),
        (
            "off",
            Format::Off,
            write_mesh_bytes(&mesh, Format::Off).unwrap(),
        ),
        (
            "ply",
            Format::Ply,
            write_mesh_bytes(&mesh, Format::Ply).unwrap(),
        ),
        ("ply ascii", Format::Ply, simple_ply("ascii", "float")),
        ("ply be", Format::Ply, mixed),
        ("stl", Format::Stl, binary_stl(b"solid x", &tetra_facets())),
        (
            "stl ascii",
            Format::Stl,
            ascii_stl(&tetra_facets()).into_bytes(),
        ),
        (
            "obj quirks",
            Format::Obj,
            b"v 0 0 0\r\nv 1 0 \\\n0\nv 0 1 0\nv 0 0 1\nf 1/2/3 -1//2 3\nf 1 2 3 4\n".to_vec(),
        ),
    ]
}

#[test]
fn every_prefix_returns_without_panic() {
    for (name, format, data) in samples() {
        assert!(read_mesh_bytes(&data, format).is_ok(), "{name}: full file");
        for len in 0..data.len() {
            let result = read_mesh_bytes(&data[..len], format);
            if name == "ply" || name == "stl" {
                // Binary files need all their bytes.
                assert!(result.is_err(), "{name}: prefix {len} read");
            }
        }
    }
}

#[test]
fn every_byte_corruption_returns_without_panic() {
    for (_, format, data) in samples() {
        for i in 0..data.len() {
            for value in [0x00, 0x20, 0x2d, 0x0a, 0x39, 0x7f, 0xff] {
                let mut bad = data.clone();
                bad[i] = value;
                let _ = read_mesh_bytes(&bad, format);
            }
        }
    }
}

#[test]
fn a_labelled_mesh_reads_back_and_a_label_count_mismatch_is_an_error() {
    let mesh = SurfaceMesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.5],
        ],
        triangles: vec![[0, 1, 2], [1, 3, 2]],
    };
    let path = temp_path("labelled.ply");
    necklace::io::write_labelled_mesh_ply(&path, &mesh, "loop", &[0, 7]).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header = String::from_utf8_lossy(&bytes[..300]);
    assert!(header.contains("property int loop"), "{header}");
    // The labels follow each face's indices: 1 + 3·4 + 4 bytes per face.
    let faces = &bytes[bytes.len() - 2 * 17..];
    assert_eq!(i32::from_le_bytes(faces[30..34].try_into().unwrap()), 7);
    let back = read_mesh(&path).unwrap();
    assert_eq!(back, mesh);
    let e = necklace::io::write_labelled_mesh_ply(&path, &mesh, "loop", &[0]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    let e = necklace::io::write_labelled_mesh_ply(temp_path("x.obj"), &mesh, "loop", &[0, 1])
        .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownFormat);
    std::fs::remove_file(&path).unwrap();
}
