//! Medit `.mesh` files (ascii, as written by Medit, MMG, TetGen and Gmsh).
//!
//! Reading: the file is a stream of whitespace-separated tokens (line breaks do not
//! matter), `#` comments run to the end of a line, and keywords match in any case.
//! Sections:
//! - `MeshVersionFormatted v` (ignored) and `Dimension 3` (any other dimension is
//!   [`ErrorKind::Unsupported`]);
//! - `Vertices n` then `n` records `x y z ref`;
//! - `Tetrahedra n` then `n` records `v1 v2 v3 v4 ref` (1-based), and `TetrahedraP2 n`
//!   with 10 vertices per record, of which the first 4 (the corners) are kept;
//! - `End` stops reading (it may be missing).
//!
//! Other known sections (`Edges`, `Triangles`, `Quadrilaterals`, `Prisms`, `Hexahedra`,
//! their P2/Q2 variants, `Corners`, `Ridges`, `Required*`, `Normals`, `Tangents`,
//! `NormalAtVertices`, ...) are skipped by their record size; an unknown section is
//! [`ErrorKind::Unsupported`], since its record size is unknown.
//!
//! Vertex kinds: when the line after the `Dimension` section is the comment
//! `# necklace kinds` (our writer's mark), the vertex refs are the kind codes 0 interior,
//! 1 surface, 2 outer, and restore the kinds; otherwise refs are ignored and kinds are
//! classified from the boundary.
//!
//! Errors carry the line: a bad token is [`ErrorKind::Syntax`], a negative count or a
//! section keyword before the declared records are read [`ErrorKind::CountMismatch`],
//! the file ending inside a section [`ErrorKind::Truncated`], a NaN or infinite coordinate
//! [`ErrorKind::NonFinite`], a tet naming a missing vertex [`ErrorKind::IndexOutOfRange`]
//! (`Vertices` must come before the tets), and no tets [`ErrorKind::Empty`].
//!
//! Writing: `MeshVersionFormatted 2`, `Dimension 3`, the kinds mark, `Vertices` with the
//! kind code as ref, `Tetrahedra` with ref 0, `Triangles` (the boundary faces, outward)
//! with ref 2 when all three corners are outer and 1 otherwise, and `End`.

use std::io::Write;

use super::text;
use crate::error::{Error, ErrorKind, Result};
use crate::tet::{TetMesh, VertexKind};

/// The comment line that marks vertex refs as our kind codes.
const KINDS_MARK: &[u8] = b"# necklace kinds";

/// Sections that are skipped, with their number of tokens per record (dimension 3).
const SKIPPED: &[(&str, u64)] = &[
    ("edges", 3),
    ("triangles", 4),
    ("quadrilaterals", 5),
    ("pyramids", 6),
    ("prisms", 7),
    ("hexahedra", 9),
    ("edgesp2", 4),
    ("trianglesp2", 7),
    ("quadrilateralsq2", 10),
    ("hexahedraq2", 28),
    ("corners", 1),
    ("ridges", 1),
    ("requiredvertices", 1),
    ("requirededges", 1),
    ("requiredtriangles", 1),
    ("requiredquadrilaterals", 1),
    ("requiredtetrahedra", 1),
    ("requiredhexahedra", 1),
    ("normals", 3),
    ("tangents", 3),
    ("normalatvertices", 2),
    ("normalattrianglevertices", 3),
    ("normalatquadrilateralvertices", 3),
    ("tangentatvertices", 2),
    ("tangentatedgevertices", 3),
];

/// Read a Medit file.
pub(crate) fn read(data: &[u8]) -> Result<TetMesh> {
    let end = text::last_line(data);
    let tokens = text::content_lines(data)
        .flat_map(|(line, content)| text::tokens(content).map(move |token| (line, token)));
    let mut stream = Stream { tokens, end };

    let mut positions = Vec::new();
    let mut kinds = Vec::new();
    let mut marked = false;
    let mut tets = Vec::new();
    while let Some((line, keyword)) = stream.tokens.next() {
        let key = keyword.to_ascii_lowercase();
        match key.as_slice() {
            b"end" => break,
            b"meshversionformatted" => {
                stream.int_after(line, "version")?;
            }
            b"dimension" => {
                let (line, dimension) = stream.int_after(line, "dimension")?;
                if dimension != 3 {
                    return Err(Error::new(
                        ErrorKind::Unsupported,
                        format!("dimension {dimension} is not supported (3 expected)"),
                    )
                    .at_line(line));
                }
                marked = positions.is_empty() && has_kinds_mark(data, line);
            }
            b"vertices" => {
                let count = stream.count(line)?;
                for found in 0..count {
                    let mut position = [0.0; 3];
                    for coordinate in &mut position {
                        let (line, token) = stream.field(count, "vertices", found)?;
                        *coordinate = text::parse_coordinate(token, line)?;
                    }
                    let (line, token) = stream.field(count, "vertices", found)?;
                    let reference = text::parse_int(token, "vertex ref", line)?;
                    if marked {
                        kinds.push(super::kind_from_code(reference).ok_or_else(|| {
                            Error::new(
                                ErrorKind::Syntax,
                                format!("vertex ref {reference} is not a kind code (0, 1 or 2)"),
                            )
                            .at_line(line)
                        })?);
                    }
                    positions.push(position);
                }
            }
            b"tetrahedra" => read_tets(&mut stream, line, 4, positions.len(), &mut tets)?,
            b"tetrahedrap2" => read_tets(&mut stream, line, 10, positions.len(), &mut tets)?,
            _ => {
                let Some(&(_, size)) = SKIPPED.iter().find(|(name, _)| name.as_bytes() == key)
                else {
                    return Err(Error::new(
                        ErrorKind::Unsupported,
                        format!("unknown section {}", text::shown(keyword)),
                    )
                    .at_line(line));
                };
                let count = stream.count(line)?;
                let what = String::from_utf8_lossy(keyword);
                for found in 0..count {
                    for _ in 0..size {
                        stream.field(count, &what, found)?;
                    }
                }
            }
        }
    }
    if tets.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "no tetrahedra").at_line(end));
    }
    super::build_tet_mesh(positions, tets, marked.then_some(kinds))
}

/// Read `count` records of `size` vertex indices and a ref; keep the first 4 indices.
fn read_tets<'a>(
    stream: &mut Stream<impl Iterator<Item = (usize, &'a [u8])>>,
    line: usize,
    size: usize,
    vertex_count: usize,
    tets: &mut Vec<[u32; 4]>,
) -> Result<()> {
    let count = stream.count(line)?;
    for found in 0..count {
        let mut vertices = [0u32; 10];
        for slot in vertices.iter_mut().take(size) {
            let (line, token) = stream.field(count, "tetrahedra", found)?;
            let index = text::parse_int(token, "vertex index", line)?;
            let vertex = usize::try_from(index)
                .ok()
                .filter(|&i| (1..=vertex_count).contains(&i))
                .and_then(|i| u32::try_from(i - 1).ok())
                .ok_or_else(|| {
                    Error::new(
                        ErrorKind::IndexOutOfRange,
                        format!("vertex index {index} out of range ({vertex_count} vertices)"),
                    )
                    .at_line(line)
                })?;
            *slot = vertex;
        }
        let (line, token) = stream.field(count, "tetrahedra", found)?;
        text::parse_int(token, "tet ref", line)?;
        tets.push([vertices[0], vertices[1], vertices[2], vertices[3]]);
    }
    Ok(())
}

/// Whether `token` is a section keyword we know (any case).
fn is_keyword(token: &[u8]) -> bool {
    const READ: &[&str] = &[
        "end",
        "meshversionformatted",
        "dimension",
        "vertices",
        "tetrahedra",
        "tetrahedrap2",
    ];
    let mut names = READ.iter().chain(SKIPPED.iter().map(|(name, _)| name));
    token.first().is_some_and(u8::is_ascii_alphabetic)
        && names.any(|name| name.as_bytes().eq_ignore_ascii_case(token))
}

/// Whether the first non-blank line after `line` is our kinds mark.
fn has_kinds_mark(data: &[u8], line: usize) -> bool {
    text::raw_lines(data)
        .skip(line)
        .map(|(_, content)| content.trim_ascii())
        .find(|content| !content.is_empty())
        == Some(KINDS_MARK)
}

/// The token stream with the line where the file ends.
struct Stream<I> {
    tokens: I,
    end: usize,
}

impl<'a, I: Iterator<Item = (usize, &'a [u8])>> Stream<I> {
    /// The integer `what` after a keyword, with its line.
    fn int_after(&mut self, keyword_line: usize, what: &str) -> Result<(usize, i64)> {
        let (line, token) = self.tokens.next().ok_or_else(|| {
            Error::new(ErrorKind::Truncated, format!("file ends before the {what}"))
                .at_line(keyword_line.max(self.end))
        })?;
        Ok((line, text::parse_int(token, what, line)?))
    }

    /// The record count after a section keyword.
    fn count(&mut self, keyword_line: usize) -> Result<u64> {
        let (line, value) = self.int_after(keyword_line, "count")?;
        u64::try_from(value).map_err(|_| {
            Error::new(ErrorKind::CountMismatch, format!("negative count {value}")).at_line(line)
        })
    }

    /// The next token of record `found` of `expected` `what`: the file must not end,
    /// and a section keyword means the section has fewer records than declared.
    fn field(&mut self, expected: u64, what: &str, found: u64) -> Result<(usize, &'a [u8])> {
        let message = || format!("expected {expected} {what}, found {found}");
        let (line, token) = self
            .tokens
            .next()
            .ok_or_else(|| Error::new(ErrorKind::Truncated, message()).at_line(self.end))?;
        if is_keyword(token) {
            return Err(Error::new(
                ErrorKind::CountMismatch,
                format!("{} before {}", message(), text::shown(token)),
            )
            .at_line(line));
        }
        Ok((line, token))
    }
}

/// Write a mesh as Medit ascii.
pub(crate) fn write(mesh: &TetMesh, out: &mut Vec<u8>) {
    // Writing into a Vec<u8> cannot fail, so the io::Results below are always Ok.
    let _ = writeln!(out, "MeshVersionFormatted 2");
    let _ = writeln!(out, "Dimension 3");
    let _ = out.write_all(KINDS_MARK);
    let _ = writeln!(out, "\n\nVertices\n{}", mesh.positions.len());
    for ([x, y, z], &kind) in mesh.positions.iter().zip(&mesh.kinds) {
        let _ = writeln!(out, "{x} {y} {z} {}", super::kind_code(kind));
    }
    let _ = writeln!(out, "\nTetrahedra\n{}", mesh.tets.len());
    for tet in &mesh.tets {
        let [a, b, c, d] = tet.map(|v| v + 1);
        let _ = writeln!(out, "{a} {b} {c} {d} 0");
    }
    let faces = mesh.boundary_faces();
    let _ = writeln!(out, "\nTriangles\n{}", faces.len());
    for face in &faces {
        let outer = face
            .iter()
            .all(|&v| mesh.kinds[v as usize] == VertexKind::Outer);
        let [a, b, c] = face.map(|v| v + 1);
        let _ = writeln!(out, "{a} {b} {c} {}", if outer { 2 } else { 1 });
    }
    let _ = writeln!(out, "\nEnd");
}
