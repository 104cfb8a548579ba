//! Gmsh `.msh` files, ascii versions 2.2 and 4.1.
//!
//! Reading: the file starts with `$MeshFormat`, whose `version file-type data-size` line
//! selects the layout: `2.2 0 8` or `4.1 0 8`. Binary files (file-type 1) and other
//! versions are [`ErrorKind::Unsupported`]. Records are lines; blank lines are ignored.
//! - `$Nodes`: 2.2 has `n` then `n` lines `tag x y z`; 4.1 has
//!   `blocks n min-tag max-tag`, then per entity block `dim entity parametric count`,
//!   `count` tag lines and `count` coordinate lines (parametric coordinates after `x y z`
//!   are ignored). Node tags are arbitrary distinct integers, mapped to 0-based indices
//!   in file order.
//! - `$Elements`: 2.2 has `n` then `n` lines `tag type ntags tag.. node..`; 4.1 has
//!   `blocks n min-tag max-tag`, then per block `dim entity type count` and `count` lines
//!   `tag node..`. Tets (type 4) are kept; 10-node tets (type 11) are reduced to their 4
//!   corners; every other element type (points, lines, triangles, hexahedra, ...) is
//!   skipped unchecked.
//! - Every other section (`$Entities`, `$PhysicalNames`, `$NodeData`, `$Comments`, ...)
//!   is skipped up to its `$End` line.
//!
//! Errors carry the line: a bad token or a missing `$End` line is [`ErrorKind::Syntax`],
//! a negative count or a section ending before its declared records
//! [`ErrorKind::CountMismatch`], the file ending early [`ErrorKind::Truncated`], a NaN or
//! infinite coordinate [`ErrorKind::NonFinite`], a tet naming an unknown node tag
//! [`ErrorKind::IndexOutOfRange`], and no tets [`ErrorKind::Empty`].
//!
//! Writing (4.1 ascii): `$MeshFormat`, `$Nodes` with one entity block (dimension 3, tag 1)
//! and node tags 1..n, `$Elements` with one block of type-4 tets tagged 1..t. There is no
//! `$Entities` section; Gmsh accepts files without it.

use std::collections::HashMap;
use std::io::Write;

use super::text;
use crate::error::{Error, ErrorKind, Result};
use crate::tet::TetMesh;

/// Node positions in file order and the index of each tag.
#[derive(Default)]
struct Nodes {
    positions: Vec<[f64; 3]>,
    index: HashMap<i64, u32>,
}

/// Read a Gmsh file.
pub(crate) fn read(data: &[u8]) -> Result<TetMesh> {
    let end = text::last_line(data);
    let mut lines = Lines {
        lines: text::raw_lines(data)
            .map(|(line, content)| (line, content.trim_ascii()))
            .filter(|(_, content)| !content.is_empty()),
        end,
    };
    let (line, first) = lines
        .next()
        .ok_or_else(|| Error::new(ErrorKind::Empty, "empty file"))?;
    if first != b"$MeshFormat" {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!("expected $MeshFormat, found {}", text::shown(first)),
        )
        .at_line(line));
    }
    let version4 = read_format(&mut lines)?;

    let mut nodes = Nodes::default();
    let mut tets = Vec::new();
    while let Some((line, content)) = lines.next() {
        match content {
            b"$Nodes" if version4 => read_nodes_v4(&mut lines, &mut nodes)?,
            b"$Nodes" => read_nodes_v2(&mut lines, &mut nodes)?,
            b"$Elements" if version4 => read_elements_v4(&mut lines, &nodes, &mut tets)?,
            b"$Elements" => read_elements_v2(&mut lines, &nodes, &mut tets)?,
            _ if content.starts_with(b"$") => lines.skip_section(content)?,
            _ => {
                return Err(Error::new(
                    ErrorKind::Syntax,
                    format!(
                        "expected a section such as $Nodes, found {}",
                        text::shown(content)
                    ),
                )
                .at_line(line))
            }
        }
    }
    if tets.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "no tetrahedra").at_line(end));
    }
    super::build_tet_mesh(nodes.positions, tets, None)
}

/// The `version file-type data-size` line and `$EndMeshFormat`; true for version 4.1.
fn read_format<'a>(lines: &mut Lines<impl Iterator<Item = (usize, &'a [u8])>>) -> Result<bool> {
    let (line, format) = lines.header("version line")?;
    let mut tokens = text::tokens(format);
    let version = tokens.next().unwrap_or_default();
    let version4 = match version {
        b"2.2" => false,
        b"4.1" => true,
        _ => {
            return Err(Error::new(
                ErrorKind::Unsupported,
                format!(
                    "Gmsh version {} is not supported (2.2 or 4.1 expected)",
                    text::shown(version)
                ),
            )
            .at_line(line))
        }
    };
    match tokens.next() {
        Some(b"0") => {}
        Some(b"1") => {
            return Err(Error::new(
                ErrorKind::Unsupported,
                "binary Gmsh files are not supported (ascii expected)",
            )
            .at_line(line))
        }
        _ => {
            return Err(Error::new(
                ErrorKind::Syntax,
                "expected the file type 0 (ascii) after the version",
            )
            .at_line(line))
        }
    }
    lines.end_of_section(b"$EndMeshFormat")?;
    Ok(version4)
}

fn read_nodes_v2<'a>(
    lines: &mut Lines<impl Iterator<Item = (usize, &'a [u8])>>,
    nodes: &mut Nodes,
) -> Result<()> {
    let (line, header) = lines.header("node count")?;
    let [count] = counts(header, line)?;
    for found in 0..count {
        let (line, record) = lines.record(count, "nodes", found)?;
        let tokens: Vec<&[u8]> = text::tokens(record).collect();
        if tokens.len() < 4 {
            return Err(Error::new(
                ErrorKind::Syntax,
                format!("node has {} values, expected 'tag x y z'", tokens.len()),
            )
            .at_line(line));
        }
        let tag = text::parse_int(tokens[0], "node tag", line)?;
        nodes.add(tag, coordinates(&tokens[1..], line)?, line)?;
    }
    lines.end_of_section(b"$EndNodes")
}

fn read_nodes_v4<'a>(
    lines: &mut Lines<impl Iterator<Item = (usize, &'a [u8])>>,
    nodes: &mut Nodes,
) -> Result<()> {
    let (header_line, header) = lines.header("node counts")?;
    let [blocks, total] = counts(header, header_line)?;
    let mut read = 0u64;
    let mut tags = Vec::new();
    for block in 0..blocks {
        let (line, block_header) = lines.record(blocks, "node blocks", block)?;
        let [_, _, _, count] = counts(block_header, line)?;
        tags.clear();
        for found in 0..count {
            let (line, record) = lines.record(count, "node tags in the block", found)?;
            let token = text::tokens(record).next().unwrap_or_default();
            tags.push(text::parse_int(token, "node tag", line)?);
        }
        for (found, &tag) in tags.iter().enumerate() {
            let (line, record) =
                lines.record(count, "node coordinates in the block", found as u64)?;
            let tokens: Vec<&[u8]> = text::tokens(record).collect();
            nodes.add(tag, coordinates(&tokens, line)?, line)?;
        }
        read += count;
    }
    if read != total {
        return Err(Error::new(
            ErrorKind::CountMismatch,
            format!("{total} nodes declared, the blocks hold {read}"),
        )
        .at_line(header_line));
    }
    lines.end_of_section(b"$EndNodes")
}

fn read_elements_v2<'a>(
    lines: &mut Lines<impl Iterator<Item = (usize, &'a [u8])>>,
    nodes: &Nodes,
    tets: &mut Vec<[u32; 4]>,
) -> Result<()> {
    let (line, header) = lines.header("element count")?;
    let [count] = counts(header, line)?;
    for found in 0..count {
        let (line, record) = lines.record(count, "elements", found)?;
        let tokens: Vec<&[u8]> = text::tokens(record).collect();
        if tokens.len() < 3 {
            return Err(Error::new(
                ErrorKind::Syntax,
                "expected an element 'tag type ntags tags.. nodes..'",
            )
            .at_line(line));
        }
        text::parse_int(tokens[0], "element tag", line)?;
        let element_type = text::parse_int(tokens[1], "element type", line)?;
        let tag_count = text::parse_int(tokens[2], "tag count", line)?;
        let node_tokens = usize::try_from(tag_count)
            .ok()
            .and_then(|n| tokens.get(3usize.saturating_add(n)..))
            .ok_or_else(|| {
                Error::new(
                    ErrorKind::Syntax,
                    format!("element declares {tag_count} tags, but has not that many values"),
                )
                .at_line(line)
            })?;
        if let Some(tet) = tet(element_type, node_tokens, nodes, line)? {
            tets.push(tet);
        }
    }
    lines.end_of_section(b"$EndElements")
}

fn read_elements_v4<'a>(
    lines: &mut Lines<impl Iterator<Item = (usize, &'a [u8])>>,
    nodes: &Nodes,
    tets: &mut Vec<[u32; 4]>,
) -> Result<()> {
    let (header_line, header) = lines.header("element counts")?;
    let [blocks, total] = counts(header, header_line)?;
    let mut read = 0u64;
    for block in 0..blocks {
        let (line, block_header) = lines.record(blocks, "element blocks", block)?;
        let [_, _, element_type, count] = counts(block_header, line)?;
        let element_type = i64::try_from(element_type).unwrap_or(i64::MAX);
        for found in 0..count {
            let (line, record) = lines.record(count, "elements in the block", found)?;
            let mut tokens = text::tokens(record);
            text::parse_int(tokens.next().unwrap_or_default(), "element tag", line)?;
            let node_tokens: Vec<&[u8]> = tokens.collect();
            if let Some(tet) = tet(element_type, &node_tokens, nodes, line)? {
                tets.push(tet);
            }
        }
        read += count;
    }
    if read != total {
        return Err(Error::new(
            ErrorKind::CountMismatch,
            format!("{total} elements declared, the blocks hold {read}"),
        )
        .at_line(header_line));
    }
    lines.end_of_section(b"$EndElements")
}

/// The tet of an element of `element_type` with node tags `tokens`: type 4 (tet) and
/// type 11 (10-node tet, reduced to its corners); `None` for other types.
fn tet(
    element_type: i64,
    tokens: &[&[u8]],
    nodes: &Nodes,
    line: usize,
) -> Result<Option<[u32; 4]>> {
    let needed = match element_type {
        4 => 4,
        11 => 10,
        _ => return Ok(None),
    };
    if tokens.len() < needed {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!(
                "element of type {element_type} has {} nodes, expected {needed}",
                tokens.len()
            ),
        )
        .at_line(line));
    }
    let mut tet = [0u32; 4];
    for (corner, token) in tet.iter_mut().zip(tokens) {
        let tag = text::parse_int(token, "node tag", line)?;
        *corner = *nodes.index.get(&tag).ok_or_else(|| {
            Error::new(
                ErrorKind::IndexOutOfRange,
                format!("unknown node tag {tag}"),
            )
            .at_line(line)
        })?;
    }
    Ok(Some(tet))
}

impl Nodes {
    fn add(&mut self, tag: i64, position: [f64; 3], line: usize) -> Result<()> {
        let index = self.positions.len() as u32;
        if self.index.insert(tag, index).is_some() {
            return Err(
                Error::new(ErrorKind::Syntax, format!("duplicate node tag {tag}")).at_line(line),
            );
        }
        self.positions.push(position);
        Ok(())
    }
}

/// The first three tokens as a finite position.
fn coordinates(tokens: &[&[u8]], line: usize) -> Result<[f64; 3]> {
    if tokens.len() < 3 {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!("node has {} coordinates, expected 3", tokens.len()),
        )
        .at_line(line));
    }
    let mut position = [0.0; 3];
    for (coordinate, token) in position.iter_mut().zip(tokens) {
        *coordinate = text::parse_coordinate(token, line)?;
    }
    Ok(position)
}

/// The first `N` values of a count line, non-negative integers (more may follow).
fn counts<const N: usize>(record: &[u8], line: usize) -> Result<[u64; N]> {
    let mut values = [0u64; N];
    let mut tokens = text::tokens(record);
    for (found, value) in values.iter_mut().enumerate() {
        let token = tokens.next().ok_or_else(|| {
            Error::new(
                ErrorKind::Syntax,
                format!("expected {N} integers, found {found}"),
            )
            .at_line(line)
        })?;
        let number = text::parse_int(token, "count", line)?;
        *value = u64::try_from(number).map_err(|_| {
            Error::new(ErrorKind::CountMismatch, format!("negative count {number}")).at_line(line)
        })?;
    }
    Ok(values)
}

/// Trimmed non-blank lines with the line where the file ends.
struct Lines<I> {
    lines: I,
    end: usize,
}

impl<'a, I: Iterator<Item = (usize, &'a [u8])>> Lines<I> {
    fn next(&mut self) -> Option<(usize, &'a [u8])> {
        self.lines.next()
    }

    /// The header line of a section (`what` names it): the file must not end there.
    fn header(&mut self, what: &str) -> Result<(usize, &'a [u8])> {
        match self.next() {
            Some((line, content)) if content.starts_with(b"$") => Err(Error::new(
                ErrorKind::Syntax,
                format!("expected the {what}, found {}", text::shown(content)),
            )
            .at_line(line)),
            Some(found) => Ok(found),
            None => Err(
                Error::new(ErrorKind::Truncated, format!("file ends before the {what}"))
                    .at_line(self.end),
            ),
        }
    }

    /// Record `found` of `expected` `what`: the file must not end, and a `$` line means
    /// the section holds fewer records than declared.
    fn record(&mut self, expected: u64, what: &str, found: u64) -> Result<(usize, &'a [u8])> {
        let message = || format!("expected {expected} {what}, found {found}");
        let (line, content) = self
            .next()
            .ok_or_else(|| Error::new(ErrorKind::Truncated, message()).at_line(self.end))?;
        if content.starts_with(b"$") {
            return Err(Error::new(
                ErrorKind::CountMismatch,
                format!("{} before {}", message(), text::shown(content)),
            )
            .at_line(line));
        }
        Ok((line, content))
    }

    /// The line that must close a section after its declared records.
    fn end_of_section(&mut self, marker: &[u8]) -> Result<()> {
        let name = String::from_utf8_lossy(marker);
        match self.next() {
            Some((_, content)) if content == marker => Ok(()),
            Some((line, content)) => Err(Error::new(
                ErrorKind::Syntax,
                format!("expected {name}, found {}", text::shown(content)),
            )
            .at_line(line)),
            None => Err(
                Error::new(ErrorKind::Truncated, format!("file ends before {name}"))
                    .at_line(self.end),
            ),
        }
    }

    /// Skip a section from its `$Name` line to its `$EndName` line.
    fn skip_section(&mut self, start: &[u8]) -> Result<()> {
        let name = &start[1..];
        let found = self.lines.any(|(_, content)| {
            content
                .strip_prefix(b"$End")
                .is_some_and(|rest| rest == name)
        });
        if found {
            Ok(())
        } else {
            Err(Error::new(
                ErrorKind::Truncated,
                format!("file ends before $End{}", String::from_utf8_lossy(name)),
            )
            .at_line(self.end))
        }
    }
}

/// Write a mesh as Gmsh 4.1 ascii.
pub(crate) fn write(mesh: &TetMesh, out: &mut Vec<u8>) {
    // Writing into a Vec<u8> cannot fail, so the io::Results below are always Ok.
    let (n, t) = (mesh.positions.len(), mesh.tets.len());
    let _ = writeln!(out, "$MeshFormat\n4.1 0 8\n$EndMeshFormat");
    let _ = writeln!(out, "$Nodes\n1 {n} {} {n}\n3 1 0 {n}", n.min(1));
    for tag in 1..=n {
        let _ = writeln!(out, "{tag}");
    }
    for [x, y, z] in &mesh.positions {
        let _ = writeln!(out, "{x} {y} {z}");
    }
    let _ = writeln!(out, "$EndNodes");
    let _ = writeln!(out, "$Elements\n1 {t} {} {t}\n3 1 4 {t}", t.min(1));
    for (i, tet) in mesh.tets.iter().enumerate() {
        let [a, b, c, d] = tet.map(|v| v + 1);
        let _ = writeln!(out, "{} {a} {b} {c} {d}", i + 1);
    }
    let _ = writeln!(out, "$EndElements");
}
