//! A mutation fuzzer for every reader: valid files of each format (OBJ, OFF, PLY ascii
//! and binary in both byte orders, STL ascii and binary, Medit, Gmsh 2.2 and 4.1, VTU,
//! TetGen) are mutated (bit flips, hostile tokens, deleted, repeated and spliced ranges,
//! truncation) and read back. Whatever the bytes, a reader must return a mesh whose
//! indices are in range and whose coordinates are finite, or an error whose message is
//! one printable line; never panic.
//!
//! `cargo test --release --test suite fuzz::` runs a few thousand executions per format;
//! `NECKLACE_FUZZ_EXECS=1000000 cargo test --release --test suite fuzz:: -- --nocapture` runs
//! that many in total and prints the count (a seeded generator: the same run each time;
//! `NECKLACE_FUZZ_SEED` picks another).

use std::panic::{catch_unwind, AssertUnwindSafe};

use necklace::io::{self, Format, TetFormat};
use necklace::{MeshReport, SurfaceMesh, TetMesh, VertexKind};

/// xorshift64*: small, fast, and the same sequence on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens that have broken readers elsewhere: signs, huge and odd numbers, separators.
const TOKENS: &[&[u8]] = &[
    b"-1",
    b"0",
    b"4294967295",
    b"4294967296",
    b"18446744073709551616",
    b"99999999999999999999",
    b"1e308",
    b"1e309",
    b"-1e-320",
    b"nan",
    b"inf",
    b" ",
    b"\n",
    b"\r",
    b"\t",
    b"#",
    b"/",
    b"//",
    b"\\",
    b"\x00",
    b"\x1b[2J",
    b"\xef\xbb\xbf",
    b"\xff\xfe",
    b"end_header\n",
    b"element face 4000000000\n",
    b"property list uchar int vertex_indices\n",
    b"facet normal 0 0 0\n",
    b"$Nodes\n",
    b"Vertices\n",
    b"<DataArray",
    b"\"",
    b">",
];

fn mutate(rng: &mut Rng, seed: &[u8], other: &[u8]) -> Vec<u8> {
    let mut data = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let len = data.len();
        let at = rng.below(len + 1);
        match rng.below(8) {
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = [0u8, 0xff, b'-', b'9', b'\n', b'\r', b' ', 0x1b][rng.below(8)];
            }
            2 | 3 => {
                let token = TOKENS[rng.below(TOKENS.len())];
                data.splice(at..at, token.iter().copied());
            }
            4 if len > 0 => {
                let end = (at + 1 + rng.below(16)).min(len);
                data.drain(at.min(end)..end);
            }
            5 if len > 0 => {
                let end = (at + 1 + rng.below(64)).min(len);
                let piece = data[at.min(end)..end].to_vec();
                data.splice(at..at, piece);
            }
            6 => data.truncate(at),
            _ if !other.is_empty() => {
                let from = rng.below(other.len());
                let end = (from + 1 + rng.below(64)).min(other.len());
                data.splice(at..at, other[from..end].iter().copied());
            }
            _ => {}
        }
    }
    data
}

/// A small closed mesh with a polygon: an octahedron plus a square pyramid's worth of
/// faces would do; a coarse torus exercises more of each reader.
fn torus() -> SurfaceMesh {
    let (n, m) = (8u32, 5u32);
    let mut positions = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (
                std::f64::consts::TAU * f64::from(i) / f64::from(n),
                std::f64::consts::TAU * f64::from(j) / f64::from(m),
            );
            let r = 1.0 + 0.3 * v.cos();
            positions.push([r * u.cos(), r * u.sin(), 0.3 * v.sin()]);
        }
    }
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let a = i * m + j;
            let b = ((i + 1) % n) * m + j;
            let c = ((i + 1) % n) * m + (j + 1) % m;
            let d = i * m + (j + 1) % m;
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    SurfaceMesh::new(positions, triangles).unwrap()
}

fn tet_mesh() -> TetMesh {
    let positions = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
    ];
    let tets = vec![[0, 1, 2, 3], [1, 2, 3, 4]];
    let kinds = vec![VertexKind::Surface; 5];
    TetMesh::new(positions, tets, kinds).unwrap()
}

/// The seed files: (name, bytes, what reads them).
fn seeds() -> Vec<(&'static str, Vec<u8>, Reader)> {
    let mesh = torus();
    let ascii_ply = {
        let mut t = format!(
            "ply\nformat ascii 1.0\ncomment c\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            mesh.positions.len(),
            mesh.triangles.len()
        );
        for p in &mesh.positions {
            t += &format!("{} {} {}\n", p[0], p[1], p[2]);
        }
        for f in &mesh.triangles {
            t += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
        }
        t.into_bytes()
    };
    let big_endian_ply = {
        let mut b = format!(
            "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            mesh.positions.len(),
            mesh.triangles.len()
        )
        .into_bytes();
        for p in &mesh.positions {
            for c in p {
                b.extend(c.to_be_bytes());
            }
        }
        for f in &mesh.triangles {
            b.push(3);
            for v in f {
                b.extend(v.to_be_bytes());
            }
        }
        b
    };
    let stl_ascii = {
        let mut t = String::from("solid s\n");
        for f in 0..mesh.num_triangles() {
            t += "facet normal 0 0 1\nouter loop\n";
            for p in mesh.corners(f) {
                t += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            t += "endloop\nendfacet\n";
        }
        (t + "endsolid s\n").into_bytes()
    };
    let stl_binary = {
        let mut b = vec![0u8; 80];
        b.extend((mesh.num_triangles() as u32).to_le_bytes());
        for f in 0..mesh.num_triangles() {
            b.extend([0u8; 12]);
            for p in mesh.corners(f) {
                for c in p {
                    b.extend((c as f32).to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        b
    };
    let obj_polygons =
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nvt 0 0\nvn 0 0 1\nf 4/1/1 3/1/1 2/1/1 1/1/1\nf 1//1 2//1 5//1\nf -4 -3 -1\nf 3 4 5 \\\n\nf 4 1 5\n"
            .to_vec();
    let tets = tet_mesh();
    let tet = |f: TetFormat| io::write_tet_mesh_bytes(&tets, f, &[]).unwrap();
    let (node, ele) = io::write_tetgen_bytes(&tets).unwrap();
    let gmsh22 = b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n".to_vec();
    vec![
        (
            "obj",
            io::write_mesh_bytes(&mesh, Format::Obj).unwrap(),
            Reader::Surface(Format::Obj),
        ),
        ("obj polygons", obj_polygons, Reader::Surface(Format::Obj)),
        (
            "off",
            io::write_mesh_bytes(&mesh, Format::Off).unwrap(),
            Reader::Surface(Format::Off),
        ),
        (
            "ply le",
            io::write_mesh_bytes(&mesh, Format::Ply).unwrap(),
            Reader::Surface(Format::Ply),
        ),
        ("ply be", big_endian_ply, Reader::Surface(Format::Ply)),
        ("ply ascii", ascii_ply, Reader::Surface(Format::Ply)),
        ("stl ascii", stl_ascii, Reader::Surface(Format::Stl)),
        ("stl binary", stl_binary, Reader::Surface(Format::Stl)),
        (
            "medit",
            tet(TetFormat::Medit),
            Reader::Tet(TetFormat::Medit),
        ),
        (
            "gmsh 4.1",
            tet(TetFormat::Gmsh),
            Reader::Tet(TetFormat::Gmsh),
        ),
        ("gmsh 2.2", gmsh22, Reader::Tet(TetFormat::Gmsh)),
        ("vtu", tet(TetFormat::Vtu), Reader::Tet(TetFormat::Vtu)),
        ("tetgen node", node, Reader::TetGenNode(ele.clone())),
        (
            "tetgen ele",
            ele,
            Reader::TetGenEle(io::write_tetgen_bytes(&tets).unwrap().0),
        ),
    ]
}

#[derive(Clone)]
enum Reader {
    Surface(Format),
    Tet(TetFormat),
    /// Mutate the `.node` file; the `.ele` is this one.
    TetGenNode(Vec<u8>),
    /// Mutate the `.ele` file; the `.node` is this one.
    TetGenEle(Vec<u8>),
}

/// Read `data`: `Ok(true)` for a mesh, `Ok(false)` for a clean error; `Err(text)`
/// describes a broken promise.
fn check(reader: &Reader, data: &[u8]) -> Result<bool, String> {
    let outcome = catch_unwind(AssertUnwindSafe(|| match reader {
        Reader::Surface(format) => {
            let _ = Format::sniff(data);
            let _ = Format::signature(data);
            io::read_mesh_bytes(data, *format).map(|mesh| {
                let _ = MeshReport::new(&mesh);
                (
                    mesh.positions,
                    mesh.triangles
                        .iter()
                        .map(|t| t.to_vec())
                        .collect::<Vec<_>>(),
                )
            })
        }
        Reader::Tet(format) => io::read_tet_mesh_bytes(data, *format)
            .map(|m| (m.positions, m.tets.iter().map(|t| t.to_vec()).collect())),
        Reader::TetGenNode(ele) => io::read_tetgen_bytes(data, ele)
            .map(|m| (m.positions, m.tets.iter().map(|t| t.to_vec()).collect())),
        Reader::TetGenEle(node) => io::read_tetgen_bytes(node, data)
            .map(|m| (m.positions, m.tets.iter().map(|t| t.to_vec()).collect())),
    }));
    match outcome {
        Err(_) => Err("panicked".into()),
        Ok(Err(e)) => {
            let text = e.to_string();
            if text.chars().any(char::is_control) {
                Err(format!("error message with a control character: {text:?}"))
            } else {
                Ok(false)
            }
        }
        Ok(Ok((positions, cells))) => {
            if positions.iter().flatten().any(|c| !c.is_finite()) {
                return Err("a non-finite coordinate was accepted".into());
            }
            let n = positions.len();
            match cells.iter().flatten().find(|&&v| v as usize >= n) {
                Some(v) => Err(format!("index {v} out of range ({n} vertices) accepted")),
                None => Ok(true),
            }
        }
    }
}

#[test]
fn mutated_files_of_every_format_never_panic_nor_pass_bad_data() {
    let total: usize = std::env::var("NECKLACE_FUZZ_EXECS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40_000);
    let seed: u64 = std::env::var("NECKLACE_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x9e37_79b9_7f4a_7c15);
    let seeds = seeds();
    // Every seed must read as it is, or the fuzzer mutates garbage.
    for (name, data, reader) in &seeds {
        let ok = match reader {
            Reader::Surface(f) => io::read_mesh_bytes(data, *f).is_ok(),
            Reader::Tet(f) => io::read_tet_mesh_bytes(data, *f).is_ok(),
            Reader::TetGenNode(ele) => io::read_tetgen_bytes(data, ele).is_ok(),
            Reader::TetGenEle(node) => io::read_tetgen_bytes(node, data).is_ok(),
        };
        assert!(ok, "seed {name} does not read");
    }
    // Panics are caught and reported below; keep their messages off the output.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut rng = Rng(seed | 1);
    let mut failures = Vec::new();
    let mut meshes = 0usize;
    let mut errors = 0usize;
    for run in 0..total {
        let (name, data, reader) = &seeds[run % seeds.len()];
        let other = &seeds[rng.below(seeds.len())].1;
        let input = mutate(&mut rng, data, other);
        match check(reader, &input) {
            Ok(true) => meshes += 1,
            Ok(false) => errors += 1,
            Err(why) if failures.len() < 5 => failures.push(format!(
                "{name} run {run}: {why}; input {:?}",
                String::from_utf8_lossy(&input[..input.len().min(300)])
            )),
            Err(_) => {}
        }
    }
    std::panic::set_hook(hook);
    println!(
        "{total} executions over {} seed files: {meshes} read as meshes, {errors} clean errors, {} broken promises",
        seeds.len(),
        total - meshes - errors
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
