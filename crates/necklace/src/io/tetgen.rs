//! TetGen meshes: a `.node` file (vertices) and an `.ele` file (tetrahedra).
//!
//! Reading, one record per non-empty line, `#` comments anywhere:
//! - `.node`: the header `n [dim [attributes [markers]]]` (dimension 3, attributes a count
//!   of extra columns, markers 0 or 1), then `n` records `index x y z [attributes]
//!   [marker]`. The first index sets the numbering base (usually 0 or 1); the following
//!   ones must count up from it, as TetGen requires. Attributes and markers are ignored.
//! - `.ele`: the header `t nodes_per_tet [region]` (4, or 10 for second-order tets, of
//!   which the first 4 nodes, the corners, are kept), then `t` records `index n1 .. nk
//!   [region attribute]`; tet indices and region attributes are ignored.
//!
//! Lines after the declared records are ignored. Vertex kinds are always classified
//! from the boundary: TetGen's boundary markers label facets, not our kinds.
//!
//! Errors carry the line: a bad header or record is [`ErrorKind::Syntax`], a dimension
//! other than 3 [`ErrorKind::Unsupported`], a negative count [`ErrorKind::CountMismatch`],
//! fewer records than declared [`ErrorKind::Truncated`], a NaN or infinite coordinate
//! [`ErrorKind::NonFinite`], a tet naming a missing node [`ErrorKind::IndexOutOfRange`],
//! and no tets [`ErrorKind::Empty`].
//!
//! Writing: `X.node` with header `n 3 0 1` and the vertex kind code (0 interior,
//! 1 surface, 2 outer) as boundary marker, `X.ele` with header `t 4 0`; both 0-based,
//! coordinates with Rust's shortest round-trip `{}` formatting.

use std::io::Write;

use super::text;
use crate::error::{Error, ErrorKind, Result};
use crate::tet::TetMesh;

/// The vertices of a `.node` file and the index of its first node.
struct Nodes {
    positions: Vec<[f64; 3]>,
    base: i64,
}

/// Read a mesh from the contents of its `.node` and `.ele` files; errors get the
/// source name of the part they were found in.
pub(crate) fn read(node: &[u8], ele: &[u8], node_name: &str, ele_name: &str) -> Result<TetMesh> {
    let nodes = read_nodes(node).map_err(|e| e.in_source(node_name))?;
    let tets = read_tets(ele, &nodes).map_err(|e| e.in_source(ele_name))?;
    super::build_tet_mesh(nodes.positions, tets, None).map_err(|e| e.in_source(ele_name))
}

fn read_nodes(data: &[u8]) -> Result<Nodes> {
    let end = text::last_line(data);
    let mut lines = text::content_lines(data);
    let (line, header) = lines
        .next()
        .ok_or_else(|| Error::new(ErrorKind::Empty, "empty file"))?;
    let header: Vec<&[u8]> = text::tokens(header).collect();
    let count = header_count(&header, 0, "node count", line)?.unwrap_or(0);
    let dimension = header_count(&header, 1, "dimension", line)?.unwrap_or(3);
    if dimension != 3 {
        return Err(Error::new(
            ErrorKind::Unsupported,
            format!("dimension {dimension} is not supported (3 expected)"),
        )
        .at_line(line));
    }
    let attributes = header_count(&header, 2, "attribute count", line)?.unwrap_or(0);
    let markers = header_count(&header, 3, "boundary marker flag", line)?.unwrap_or(0);
    if markers > 1 {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!("boundary marker flag is {markers}, expected 0 or 1"),
        )
        .at_line(line));
    }
    let columns = attributes.saturating_add(markers).saturating_add(4);

    let mut positions = Vec::new();
    let mut base = 0;
    for found in 0..count {
        let (line, record) = lines
            .next()
            .ok_or_else(|| truncated(count, "nodes", found, end))?;
        let tokens: Vec<&[u8]> = text::tokens(record).collect();
        if (tokens.len() as u64) < columns {
            return Err(Error::new(
                ErrorKind::Syntax,
                format!("node has {} values, expected {columns}", tokens.len()),
            )
            .at_line(line));
        }
        let index = text::parse_int(tokens[0], "node index", line)?;
        if found == 0 {
            base = index;
        } else if Some(index) != base.checked_add(found as i64) {
            return Err(Error::new(
                ErrorKind::Syntax,
                format!(
                    "node index {index} out of sequence (expected {}: nodes are numbered consecutively)",
                    base.saturating_add(found as i64)
                ),
            )
            .at_line(line));
        }
        let mut position = [0.0; 3];
        for (coordinate, token) in position.iter_mut().zip(&tokens[1..4]) {
            *coordinate = text::parse_coordinate(token, line)?;
        }
        positions.push(position);
    }
    Ok(Nodes { positions, base })
}

fn read_tets(data: &[u8], nodes: &Nodes) -> Result<Vec<[u32; 4]>> {
    let end = text::last_line(data);
    let mut lines = text::content_lines(data);
    let (line, header) = lines
        .next()
        .ok_or_else(|| Error::new(ErrorKind::Empty, "empty file"))?;
    let header: Vec<&[u8]> = text::tokens(header).collect();
    let count = header_count(&header, 0, "tet count", line)?.unwrap_or(0);
    let corners = header_count(&header, 1, "nodes per tet", line)?.unwrap_or(4);
    if corners != 4 && corners != 10 {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!("{corners} nodes per tet, expected 4 or 10"),
        )
        .at_line(line));
    }

    let n = nodes.positions.len();
    let mut tets = Vec::new();
    for found in 0..count {
        let (line, record) = lines
            .next()
            .ok_or_else(|| truncated(count, "tets", found, end))?;
        let tokens: Vec<&[u8]> = text::tokens(record).collect();
        if (tokens.len() as u64) < corners + 1 {
            return Err(Error::new(
                ErrorKind::Syntax,
                format!("tet has {} values, expected {}", tokens.len(), corners + 1),
            )
            .at_line(line));
        }
        text::parse_int(tokens[0], "tet index", line)?;
        let mut tet = [0u32; 4];
        for (corner, token) in tet.iter_mut().zip(&tokens[1..5]) {
            let index = text::parse_int(token, "node index", line)?;
            *corner = index
                .checked_sub(nodes.base)
                .and_then(|i| usize::try_from(i).ok())
                .filter(|&i| i < n)
                .and_then(|i| u32::try_from(i).ok())
                .ok_or_else(|| {
                    Error::new(
                        ErrorKind::IndexOutOfRange,
                        format!(
                            "node index {index} out of range ({n} nodes numbered from {})",
                            nodes.base
                        ),
                    )
                    .at_line(line)
                })?;
        }
        tets.push(tet);
    }
    if tets.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "no tetrahedra").at_line(end));
    }
    Ok(tets)
}

/// The header value at `position`, if present: a non-negative integer.
fn header_count(tokens: &[&[u8]], position: usize, what: &str, line: usize) -> Result<Option<u64>> {
    let Some(token) = tokens.get(position) else {
        return Ok(None);
    };
    let value = text::parse_int(token, what, line)?;
    u64::try_from(value).map(Some).map_err(|_| {
        Error::new(ErrorKind::CountMismatch, format!("negative {what} {value}")).at_line(line)
    })
}

fn truncated(expected: u64, what: &str, found: u64, line: usize) -> Error {
    Error::new(
        ErrorKind::Truncated,
        format!("expected {expected} {what}, found {found}"),
    )
    .at_line(line)
}

/// Write a mesh as the contents of `X.node` and `X.ele`.
pub(crate) fn write(mesh: &TetMesh) -> (Vec<u8>, Vec<u8>) {
    // Writing into a Vec<u8> cannot fail, so the io::Results below are always Ok.
    let mut node = Vec::new();
    let _ = writeln!(
        node,
        "# written by necklace; boundary marker = vertex kind (0 interior, 1 surface, 2 outer)"
    );
    let _ = writeln!(node, "{} 3 0 1", mesh.positions.len());
    for (i, ([x, y, z], &kind)) in mesh.positions.iter().zip(&mesh.kinds).enumerate() {
        let _ = writeln!(node, "{i} {x} {y} {z} {}", super::kind_code(kind));
    }
    let mut ele = Vec::new();
    let _ = writeln!(ele, "# written by necklace");
    let _ = writeln!(ele, "{} 4 0", mesh.tets.len());
    for (i, [a, b, c, d]) in mesh.tets.iter().enumerate() {
        let _ = writeln!(ele, "{i} {a} {b} {c} {d}");
    }
    (node, ele)
}
