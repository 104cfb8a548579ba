//! Object File Format (OFF): reads and writes ascii OFF.
//!
//! Reading, one record per non-empty line:
//! - the header keyword `OFF`, or `COFF`, `NOFF`, `CNOFF` (colours and normals), `STOFF`
//!   (texture coordinates) and their combinations; the counts may follow on the same line
//!   (`OFF 4 4 6`);
//! - the counts `nv nf [ne]` (the edge count is optional and ignored);
//! - `nv` vertex records: at least 3 numbers, further columns (colours, normals,
//!   texture coordinates) are ignored;
//! - `nf` face records `n i1 .. in [colour ...]` with 0-based indices; polygons are
//!   split into triangles (fans up to quads), trailing colour values are ignored.
//!
//! `#` comments (to the end of a line), blank lines, CRLF endings and a last line without
//! a newline are accepted anywhere; non-empty lines after the declared records are
//! ignored. Binary OFF and 4-dimensional `4OFF`/`nOFF` are [`ErrorKind::Unsupported`].
//!
//! Errors carry the 1-based line number: a missing header, a non-numeric count, a short
//! record or a face with fewer than 3 vertices is [`ErrorKind::Syntax`], a negative count
//! [`ErrorKind::CountMismatch`], fewer records than declared [`ErrorKind::Truncated`]
//! ("expected N faces, found M"), a NaN or infinite coordinate [`ErrorKind::NonFinite`], a
//! bad face index [`ErrorKind::IndexOutOfRange`], and zero faces [`ErrorKind::Empty`].
//!
//! Writing: `OFF`, `nv nf 0`, the vertices with Rust's shortest round-trip `{}`
//! formatting, then `3 a b c` per triangle.

use std::io::Write;

use super::text;
use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;

/// Read an OFF file.
pub(crate) fn read(data: &[u8]) -> Result<SurfaceMesh> {
    let end = text::last_line(data);
    let mut lines = text::content_lines(data);

    let (header_line, header) = lines
        .next()
        .ok_or_else(|| Error::new(ErrorKind::Empty, "empty file"))?;
    let mut header_tokens = text::tokens(header);
    check_keyword(header_tokens.next().unwrap_or_default(), header_line)?;
    let inline_counts: Vec<&[u8]> = header_tokens.collect();
    let (vertex_count, face_count) = if inline_counts.is_empty() {
        let (line, counts) = lines.next().ok_or_else(|| {
            Error::new(ErrorKind::Truncated, "file ends before the counts line").at_line(end)
        })?;
        parse_counts(&text::tokens(counts).collect::<Vec<_>>(), line)?
    } else {
        parse_counts(&inline_counts, header_line)?
    };

    let mut positions = Vec::new();
    for found in 0..vertex_count {
        let (line, record) = lines
            .next()
            .ok_or_else(|| truncated(vertex_count, "vertices", found, end))?;
        positions.push(parse_vertex(record, line)?);
    }

    let mut triangles = Vec::new();
    let mut polygon = Vec::new();
    for found in 0..face_count {
        let (line, record) = lines
            .next()
            .ok_or_else(|| truncated(face_count, "faces", found, end))?;
        parse_face(record, line, vertex_count, &mut polygon)?;
        text::triangulate(&polygon, &mut triangles);
    }
    if triangles.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "no faces").at_line(end));
    }
    Ok(SurfaceMesh {
        positions,
        triangles,
    })
}

/// Accept `[ST][C][N]OFF`; reject 4D and binary variants as unsupported.
fn check_keyword(keyword: &[u8], line: usize) -> Result<()> {
    let Some(prefix) = keyword.strip_suffix(b"OFF") else {
        return Err(Error::new(ErrorKind::Syntax, "missing OFF header").at_line(line));
    };
    let prefix = prefix.strip_prefix(b"ST").unwrap_or(prefix);
    let prefix = prefix.strip_prefix(b"C").unwrap_or(prefix);
    let prefix = prefix.strip_prefix(b"N").unwrap_or(prefix);
    if prefix.is_empty() {
        Ok(())
    } else if prefix.contains(&b'4') || prefix.contains(&b'n') {
        Err(Error::new(
            ErrorKind::Unsupported,
            format!(
                "{} (not 3-dimensional) is not supported",
                text::shown(keyword)
            ),
        )
        .at_line(line))
    } else {
        Err(Error::new(
            ErrorKind::Syntax,
            format!("missing OFF header (found {})", text::shown(keyword)),
        )
        .at_line(line))
    }
}

/// `nv nf [ne]`, as (nv, nf).
fn parse_counts(tokens: &[&[u8]], line: usize) -> Result<(u64, u64)> {
    if tokens.first().is_some_and(|t| *t == b"BINARY") {
        return Err(
            Error::new(ErrorKind::Unsupported, "binary OFF is not supported").at_line(line),
        );
    }
    let count = |position: usize, what: &str| -> Result<u64> {
        let token = tokens.get(position).ok_or_else(|| {
            Error::new(
                ErrorKind::Syntax,
                "expected the counts 'vertices faces [edges]'",
            )
            .at_line(line)
        })?;
        let value = text::parse_int(token, what, line)?;
        u64::try_from(value).map_err(|_| {
            Error::new(ErrorKind::CountMismatch, format!("negative {what} {value}")).at_line(line)
        })
    };
    Ok((count(0, "vertex count")?, count(1, "face count")?))
}

fn parse_vertex(record: &[u8], line: usize) -> Result<[f64; 3]> {
    text::parse_position(text::tokens(record), line)
}

/// Parse `n i1 .. in [colour]` into `polygon` (0-based indices, checked).
fn parse_face(record: &[u8], line: usize, vertex_count: u64, polygon: &mut Vec<u32>) -> Result<()> {
    let mut tokens = text::tokens(record);
    let n = text::parse_int(tokens.next().unwrap_or_default(), "vertex count", line)?;
    if n < 3 {
        return Err(text::too_few_corners("face", n).at_line(line));
    }
    polygon.clear();
    for listed in 0..n {
        let token = tokens.next().ok_or_else(|| {
            Error::new(
                ErrorKind::Syntax,
                format!("face declares {n} vertices but lists {listed}"),
            )
            .at_line(line)
        })?;
        let index = text::parse_int(token, "vertex index", line)?;
        let valid = u64::try_from(index)
            .ok()
            .filter(|&i| i < vertex_count)
            .and_then(|i| u32::try_from(i).ok());
        let index = valid.ok_or_else(|| {
            Error::new(
                ErrorKind::IndexOutOfRange,
                format!("vertex index {index} out of range ({vertex_count} vertices)"),
            )
            .at_line(line)
        })?;
        polygon.push(index);
    }
    Ok(())
}

fn truncated(expected: u64, what: &str, found: u64, line: usize) -> Error {
    Error::new(
        ErrorKind::Truncated,
        format!("expected {expected} {what}, found {found}"),
    )
    .at_line(line)
}

/// Write a mesh as OFF.
pub(crate) fn write(mesh: &SurfaceMesh, out: &mut Vec<u8>) {
    // Writing into a Vec<u8> cannot fail, so the io::Results below are always Ok.
    let _ = writeln!(out, "OFF");
    let _ = writeln!(out, "{} {} 0", mesh.positions.len(), mesh.triangles.len());
    for [x, y, z] in &mesh.positions {
        let _ = writeln!(out, "{x} {y} {z}");
    }
    for [a, b, c] in &mesh.triangles {
        let _ = writeln!(out, "3 {a} {b} {c}");
    }
}
