//! Stereolithography (STL): reads ascii and binary STL (there is no STL writer).
//!
//! Which kind a file is: binary when its size is exactly `84 + 50 * n` for the count `n`
//! in bytes 80..84 (even if the 80-byte header begins with `solid`, as many binary files
//! do); otherwise ascii when it begins with `solid` and holds no NUL byte; otherwise an
//! error ([`ErrorKind::Truncated`], naming the declared count and the actual size).
//!
//! - Binary: 80-byte header, little-endian `u32` triangle count, then per triangle a
//!   normal and 3 corners as 3 `f32` each, and a `u16` attribute (normals and attributes
//!   are ignored).
//! - Ascii: `solid [name]`, then facets `facet normal nx ny nz` / `outer loop` /
//!   `vertex x y z` ... / `endloop` / `endfacet`, then `endsolid [name]`; several solids
//!   may follow each other. Keywords are case-insensitive, any whitespace and CRLF are
//!   accepted, names are optional, normals are not checked, and a loop of more than 3
//!   vertices is split into triangles.
//!
//! STL stores every triangle's corners separately: corners with exactly the same
//! coordinates (same `f64` bits, after turning -0.0 into 0.0) are welded into one vertex,
//! numbered in order of first appearance.
//!
//! Errors: binary ones carry the byte offset, ascii ones the 1-based line number.
//! Unexpected keywords, non-numbers and facets with fewer than 3 vertices are
//! [`ErrorKind::Syntax`], a file ending inside a solid is [`ErrorKind::Truncated`], NaN or
//! infinite corners are [`ErrorKind::NonFinite`], and a file without facets is
//! [`ErrorKind::Empty`].

use std::collections::hash_map::{Entry, HashMap};
use std::iter::Peekable;

use super::text;
use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;

const HEADER: usize = 80;
const RECORD: usize = 50;

/// Read an STL file, ascii or binary.
pub(crate) fn read(data: &[u8]) -> Result<SurfaceMesh> {
    if looks_like_binary_stl(data) {
        return read_binary(data);
    }
    let starts_with_solid = data
        .trim_ascii_start()
        .get(..5)
        .is_some_and(|word| word.eq_ignore_ascii_case(b"solid"));
    if starts_with_solid && !data.contains(&0) {
        return read_ascii(data);
    }
    let message = match declared_count(data) {
        Some(n) => format!(
            "binary STL header declares {n} triangles ({} bytes), but the file has {} bytes",
            HEADER as u64 + 4 + RECORD as u64 * u64::from(n),
            data.len()
        ),
        None => format!(
            "{} bytes: too short for a binary STL, and no ascii 'solid' keyword",
            data.len()
        ),
    };
    Err(Error::new(ErrorKind::Truncated, message).at_byte(HEADER as u64))
}

/// True when the size is exactly `84 + 50 * n` for the count `n` in bytes 80..84.
pub(crate) fn looks_like_binary_stl(data: &[u8]) -> bool {
    declared_count(data)
        .is_some_and(|n| data.len() as u64 == (HEADER + 4) as u64 + RECORD as u64 * u64::from(n))
}

/// The little-endian triangle count of a binary STL, if the file is long enough.
fn declared_count(data: &[u8]) -> Option<u32> {
    let bytes = data.get(HEADER..HEADER + 4)?;
    Some(u32::from_le_bytes(bytes.try_into().ok()?))
}

/// Numbers corners by exact position, in order of first appearance.
#[derive(Default)]
struct Welder {
    ids: HashMap<[u64; 3], u32>,
    positions: Vec<[f64; 3]>,
}

impl Welder {
    fn vertex(&mut self, position: [f64; 3]) -> Result<u32> {
        let position = position.map(|c| if c == 0.0 { 0.0 } else { c });
        match self.ids.entry(position.map(f64::to_bits)) {
            Entry::Occupied(entry) => Ok(*entry.get()),
            Entry::Vacant(entry) => {
                let id = u32::try_from(self.positions.len()).map_err(|_| {
                    Error::new(ErrorKind::Unsupported, "more than 2^32 distinct vertices")
                })?;
                self.positions.push(position);
                Ok(*entry.insert(id))
            }
        }
    }

    fn finish(self, triangles: Vec<[u32; 3]>) -> Result<SurfaceMesh> {
        if triangles.is_empty() {
            return Err(Error::new(ErrorKind::Empty, "no faces"));
        }
        Ok(SurfaceMesh {
            positions: self.positions,
            triangles,
        })
    }
}

fn read_binary(data: &[u8]) -> Result<SurfaceMesh> {
    let records = data
        .get(HEADER + 4..)
        .unwrap_or_default()
        .chunks_exact(RECORD);
    let mut welder = Welder::default();
    let mut triangles = Vec::with_capacity(records.len());
    for (i, record) in records.enumerate() {
        let offset = HEADER + 4 + i * RECORD;
        let mut triangle = [0; 3];
        for (corner, id) in triangle.iter_mut().enumerate() {
            let mut position = [0.0; 3];
            for (axis, c) in position.iter_mut().enumerate() {
                // After the 12-byte normal, the corners as 3 f32 each (always present in
                // a 50-byte record; a missing value would read as NaN and be rejected).
                let at = 12 + 12 * corner + 4 * axis;
                let value = record
                    .get(at..at + 4)
                    .and_then(|b| b.try_into().ok())
                    .map_or(f32::NAN, f32::from_le_bytes);
                if !value.is_finite() {
                    return Err(Error::new(
                        ErrorKind::NonFinite,
                        format!("non-finite coordinate {value} in triangle {i}"),
                    )
                    .at_byte((offset + at) as u64));
                }
                *c = f64::from(value);
            }
            *id = welder
                .vertex(position)
                .map_err(|e| e.at_byte(offset as u64))?;
        }
        triangles.push(triangle);
    }
    welder.finish(triangles)
}

fn read_ascii(data: &[u8]) -> Result<SurfaceMesh> {
    let end = text::last_line(data);
    let mut tokens = text::raw_lines(data)
        .flat_map(|(line, bytes)| text::tokens(bytes).map(move |t| (line, t)))
        .peekable();
    let mut welder = Welder::default();
    let mut triangles = Vec::new();
    let mut polygon = Vec::new();
    while let Some((line, word)) = tokens.next() {
        if !word.eq_ignore_ascii_case(b"solid") {
            return Err(unexpected("'solid'", word, line));
        }
        skip_rest_of_line(&mut tokens, line);
        loop {
            let (line, word) = next(&mut tokens, "'facet' or 'endsolid'", end)?;
            if word.eq_ignore_ascii_case(b"endsolid") {
                skip_rest_of_line(&mut tokens, line);
                break;
            }
            if !word.eq_ignore_ascii_case(b"facet") {
                return Err(unexpected("'facet' or 'endsolid'", word, line));
            }
            facet(&mut tokens, end, &mut welder, &mut polygon)?;
            text::triangulate(&polygon, &mut triangles);
        }
    }
    welder.finish(triangles)
}

/// Read a facet after its `facet` keyword, up to `endfacet`, into `polygon`.
fn facet<'a>(
    tokens: &mut impl Iterator<Item = (usize, &'a [u8])>,
    end: usize,
    welder: &mut Welder,
    polygon: &mut Vec<u32>,
) -> Result<()> {
    expect(tokens, "normal", end)?;
    for _ in 0..3 {
        let (line, value) = next(tokens, "a normal component", end)?;
        text::parse_number(value, line)?; // checked for syntax, not used
    }
    expect(tokens, "outer", end)?;
    expect(tokens, "loop", end)?;
    polygon.clear();
    loop {
        let (line, word) = next(tokens, "'vertex' or 'endloop'", end)?;
        if word.eq_ignore_ascii_case(b"endloop") {
            if polygon.len() < 3 {
                return Err(text::too_few_corners("facet", polygon.len()).at_line(line));
            }
            break;
        }
        if !word.eq_ignore_ascii_case(b"vertex") {
            return Err(unexpected("'vertex' or 'endloop'", word, line));
        }
        let mut position = [0.0; 3];
        for c in &mut position {
            let (line, value) = next(tokens, "a coordinate", end)?;
            *c = text::parse_coordinate(value, line)?;
        }
        polygon.push(welder.vertex(position).map_err(|e| e.at_line(line))?);
    }
    expect(tokens, "endfacet", end)
}

/// The next token, or a Truncated error naming what was expected.
fn next<'a>(
    tokens: &mut impl Iterator<Item = (usize, &'a [u8])>,
    expected: &str,
    end: usize,
) -> Result<(usize, &'a [u8])> {
    tokens.next().ok_or_else(|| {
        Error::new(
            ErrorKind::Truncated,
            format!("file ends where {expected} was expected"),
        )
        .at_line(end)
    })
}

/// The next token must be the keyword `word` (any case).
fn expect<'a>(
    tokens: &mut impl Iterator<Item = (usize, &'a [u8])>,
    word: &str,
    end: usize,
) -> Result<()> {
    let expected = format!("'{word}'");
    let (line, found) = next(tokens, &expected, end)?;
    if found.eq_ignore_ascii_case(word.as_bytes()) {
        Ok(())
    } else {
        Err(unexpected(&expected, found, line))
    }
}

fn unexpected(expected: &str, found: &[u8], line: usize) -> Error {
    Error::new(
        ErrorKind::Syntax,
        format!("expected {expected}, found {}", text::shown(found)),
    )
    .at_line(line)
}

/// Skip the name after `solid` or `endsolid`.
fn skip_rest_of_line<'a>(
    tokens: &mut Peekable<impl Iterator<Item = (usize, &'a [u8])>>,
    line: usize,
) {
    while tokens.next_if(|&(l, _)| l == line).is_some() {}
}
