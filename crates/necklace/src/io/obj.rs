//! Wavefront OBJ: reads `v` and `f` statements, writes `v x y z` / `f a b c`.
//!
//! Reading:
//! - `v x y z [w ...]`: the position; `w` and any further values (vertex colours) are
//!   ignored.
//! - `f` with tokens `v`, `v/vt`, `v//vn` or `v/vt/vn`: only the vertex index is used.
//!   Indices are 1-based; negative indices are relative (-1 is the last vertex defined
//!   so far); 0 is an error. Positive indices may point to vertices defined later in
//!   the file: they are checked once the whole file is read, and an error still names
//!   the face's line. Polygons are split into triangles (fans up to quads).
//! - Every other statement (`vt`, `vn`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`, ...)
//!   is ignored, as are `#` comments, blank lines, CRLF endings and tabs. A line ending
//!   in `\` continues on the next line.
//!
//! Errors carry the 1-based line number (of the first line of a continued statement):
//! a short vertex or a face with fewer than 3 vertices or a token that is not a number
//! is [`ErrorKind::Syntax`], NaN or infinite coordinates [`ErrorKind::NonFinite`], index
//! 0 or an index beyond the vertices [`ErrorKind::IndexOutOfRange`]. A file without
//! vertices or without faces is [`ErrorKind::Empty`].
//!
//! Writing: a comment line, the vertices with Rust's shortest round-trip `{}` formatting
//! (so reading back gives the same bits), then the triangles as 1-based `f a b c`.

use std::io::Write;

use super::text;
use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;

/// Read an OBJ file.
pub(crate) fn read(data: &[u8]) -> Result<SurfaceMesh> {
    let mut reader = Reader::default();
    // A statement, joined from its continued lines, and the number of its first line.
    let mut statement: Vec<u8> = Vec::new();
    let mut first_line = None;
    for (number, line) in text::raw_lines(data) {
        let start = *first_line.get_or_insert(number);
        match line.trim_ascii_end().strip_suffix(b"\\") {
            Some(head) => {
                statement.extend_from_slice(head);
                statement.push(b' ');
            }
            None => {
                statement.extend_from_slice(line);
                reader.statement(&statement, start)?;
                statement.clear();
                first_line = None;
            }
        }
    }
    if let Some(start) = first_line {
        // The file ends with a continued line.
        reader.statement(&statement, start)?;
    }
    reader.finish()
}

#[derive(Default)]
struct Reader {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// Faces referring to vertices not defined yet: (line, largest 0-based index).
    forward: Vec<(usize, u32)>,
    /// The current face's vertex indices (reused).
    polygon: Vec<u32>,
}

impl Reader {
    fn statement(&mut self, statement: &[u8], line: usize) -> Result<()> {
        let mut tokens = text::tokens(text::strip_comment(statement));
        match tokens.next() {
            Some(b"v") => self.vertex(tokens, line),
            Some(b"f") => self.face(tokens, line),
            _ => Ok(()),
        }
    }

    fn vertex<'a>(&mut self, tokens: impl Iterator<Item = &'a [u8]>, line: usize) -> Result<()> {
        self.positions.push(text::parse_position(tokens, line)?);
        Ok(())
    }

    fn face<'a>(&mut self, tokens: impl Iterator<Item = &'a [u8]>, line: usize) -> Result<()> {
        self.polygon.clear();
        for token in tokens {
            let index = self.resolve(token, line)?;
            self.polygon.push(index);
        }
        if self.polygon.len() < 3 {
            return Err(text::too_few_corners("face", self.polygon.len()).at_line(line));
        }
        if let Some(&largest) = self.polygon.iter().max() {
            if largest as usize >= self.positions.len() {
                self.forward.push((line, largest));
            }
        }
        text::triangulate(&self.polygon, &mut self.triangles);
        Ok(())
    }

    /// The 0-based vertex index of a face token (`v`, `v/vt`, `v//vn` or `v/vt/vn`).
    fn resolve(&self, token: &[u8], line: usize) -> Result<u32> {
        let vertex = token.split(|&b| b == b'/').next().unwrap_or(token);
        let index = text::parse_int(vertex, "vertex index", line)?;
        let out_of_range =
            |message: String| Err(Error::new(ErrorKind::IndexOutOfRange, message).at_line(line));
        let defined = self.positions.len() as i64;
        let zero_based = match index {
            0 => return out_of_range("vertex index 0 (OBJ indices start at 1)".into()),
            i if i > 0 => i - 1,
            i => match defined.checked_add(i) {
                Some(j) if j >= 0 => j,
                _ => {
                    return out_of_range(format!(
                        "vertex index {i} out of range ({defined} vertices defined so far)"
                    ))
                }
            },
        };
        match u32::try_from(zero_based) {
            Ok(i) => Ok(i),
            Err(_) => out_of_range(format!("vertex index {index} is too large")),
        }
    }

    fn finish(self) -> Result<SurfaceMesh> {
        let count = self.positions.len();
        if count == 0 && self.triangles.is_empty() {
            return Err(Error::new(ErrorKind::Empty, "no vertices"));
        }
        if let Some(&(line, index)) = self.forward.iter().find(|(_, i)| *i as usize >= count) {
            return Err(Error::new(
                ErrorKind::IndexOutOfRange,
                format!(
                    "vertex index {} out of range ({count} vertices)",
                    u64::from(index) + 1
                ),
            )
            .at_line(line));
        }
        if self.triangles.is_empty() {
            return Err(Error::new(ErrorKind::Empty, "no faces"));
        }
        Ok(SurfaceMesh {
            positions: self.positions,
            triangles: self.triangles,
        })
    }
}

/// Write a mesh as OBJ.
pub(crate) fn write(mesh: &SurfaceMesh, out: &mut Vec<u8>) {
    // Writing into a Vec<u8> cannot fail, so the io::Results below are always Ok.
    let _ = writeln!(
        out,
        "# written by necklace: {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for [x, y, z] in &mesh.positions {
        let _ = writeln!(out, "v {x} {y} {z}");
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        let _ = writeln!(out, "f {a} {b} {c}");
    }
}
