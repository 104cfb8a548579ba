//! VTK XML UnstructuredGrid files (`.vtu`): tet meshes with per-vertex fields.
//!
//! Reading: the scanner of [`super::xml`] (no external parser) over the tags `<VTKFile
//! type="UnstructuredGrid">`, one `<Piece>`, and the `<DataArray>` elements of
//! `<Points>` (3 components), `<Cells>` (`connectivity`, `offsets`, `types`) and
//! `<PointData>`; other elements and attributes, `<?xml?>` declarations and `<!-- -->`
//! comments (outside data arrays) are ignored. Arrays are ascii, or raw appended data
//! (zlib-compressed or not, UInt32 or UInt64 headers; see [`super::vtk`]). Cells of
//! type 10 (tetra) are kept, type 24 (quadratic tetra, 10 points) is reduced to its 4
//! corners, all other cell types are skipped unchecked. A point data array named `kind`
//! (our writer's) restores the vertex kinds (0 interior, 1 surface, 2 outer); otherwise
//! kinds are classified from the boundary. Other point data is ignored.
//!
//! Inline `binary` (base64) arrays, base64-encoded appended data, several pieces and
//! other dataset types are [`ErrorKind::Unsupported`]. Errors carry the line: malformed
//! XML or a missing array is [`ErrorKind::Syntax`], the file ending inside an element or
//! appended data that ends early or does not inflate [`ErrorKind::Truncated`], counts
//! that disagree with `NumberOfPoints`/`NumberOfCells` or with each other
//! [`ErrorKind::CountMismatch`], a NaN or infinite coordinate [`ErrorKind::NonFinite`],
//! a point index or offset out of range [`ErrorKind::IndexOutOfRange`], and no tets
//! [`ErrorKind::Empty`].
//!
//! Writing: binary, all data in one raw appended section of zlib blocks
//! ([`super::vtk::Appended`]; the kitten's two volume meshes with their field: 4 MB
//! against 24.7 MB as ascii): Points (Float64), Cells (connectivity and offsets Int64,
//! types UInt8 = 10), and PointData: `kind` (Int32) and every field (Float64; a field
//! named `kind`, a repeated name or a non-finite value is rejected).

use std::io::Write;

use super::text;
use super::vtk::{self, Appended, Layout, Scalar, Values};
use super::xml::{Scanner, Tag};
use crate::error::{Error, ErrorKind, Result};
use crate::tet::TetMesh;

/// VTK cell types we read: tetra and quadratic tetra.
const VTK_TETRA: i64 = 10;
const VTK_QUADRATIC_TETRA: i64 = 24;

/// A data array: its text (ascii) or where its values are in the appended data.
struct Array<'a> {
    section: &'a [u8],
    name: String,
    components: i64,
    content: &'a [u8],
    /// Appended: the offset of its values and their type.
    appended: Option<(usize, Scalar)>,
    line: usize,
}

/// The raw appended data of a file and how it is laid out.
#[derive(Clone, Copy)]
struct Binary<'a> {
    blob: &'a [u8],
    layout: Layout,
}

/// Read a VTU file.
pub(crate) fn read(data: &[u8]) -> Result<TetMesh> {
    let mut scanner = Scanner {
        data,
        position: 0,
        line: 1,
    };
    let mut open: Vec<&[u8]> = Vec::new();
    let mut arrays = Vec::new();
    let mut piece = None;
    let mut root = false;
    let mut layout = None;
    let mut blob = None;
    while let Some(tag) = scanner.next_tag()? {
        if tag.closing {
            match open.pop() {
                Some(name) if name == tag.name => continue,
                _ => {
                    return Err(Error::new(
                        ErrorKind::Syntax,
                        format!("unexpected closing tag {}", text::shown(tag.name)),
                    )
                    .at_line(tag.line))
                }
            }
        }
        if open.is_empty() && tag.name != b"VTKFile" {
            return Err(Error::new(
                ErrorKind::Syntax,
                format!("expected <VTKFile>, found {}", text::shown(tag.name)),
            )
            .at_line(tag.line));
        }
        match tag.name {
            b"VTKFile" => {
                check_file_type(&tag, !root)?;
                root = true;
                layout = Some(
                    Layout::new(tag.attribute("header_type"), tag.attribute("compressor"))
                        .map_err(|e| e.at_line(tag.line))?,
                );
            }
            b"Piece" if piece.is_some() => {
                return Err(
                    Error::new(ErrorKind::Unsupported, "several pieces are not supported")
                        .at_line(tag.line),
                )
            }
            b"Piece" => {
                let points = tag.int_attribute("NumberOfPoints")?;
                let cells = tag.int_attribute("NumberOfCells")?;
                piece = Some((points, cells, tag.line));
            }
            b"AppendedData" if !tag.self_closing => blob = Some(scanner.appended(&tag)?),
            b"DataArray" => {
                let section = open.last().copied().unwrap_or_default();
                arrays.push(scanner.data_array(&tag, section)?);
                continue;
            }
            _ => {}
        }
        if !tag.self_closing {
            open.push(tag.name);
        }
    }
    let end = text::last_line(data);
    if !root {
        return Err(
            Error::new(ErrorKind::Syntax, "not a VTK XML file (no <VTKFile>)").at_line(end),
        );
    }
    if let Some(name) = open.last() {
        return Err(Error::new(
            ErrorKind::Truncated,
            format!("file ends before </{}>", String::from_utf8_lossy(name)),
        )
        .at_line(end));
    }
    let Some((point_count, cell_count, piece_line)) = piece else {
        return Err(Error::new(ErrorKind::Empty, "no <Piece>").at_line(end));
    };
    let binary = match (blob, layout) {
        (Some(blob), Some(layout)) => Some(Binary { blob, layout }),
        _ => None,
    };

    // Points.
    let points = find(&arrays, b"Points", None, end)?;
    if points.components != 3 {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!("points have {} components, expected 3", points.components),
        )
        .at_line(points.line));
    }
    let coordinates = floats(points, binary)?;
    if coordinates.len() % 3 != 0 {
        return Err(Error::new(
            ErrorKind::CountMismatch,
            format!(
                "{} point coordinates, not a multiple of 3",
                coordinates.len()
            ),
        )
        .at_line(points.line));
    }
    let positions: Vec<[f64; 3]> = coordinates
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let n = positions.len();
    check_count(point_count, n, "NumberOfPoints", "points", piece_line)?;

    // Cells.
    let connectivity = ints(find(&arrays, b"Cells", Some("connectivity"), end)?, binary)?;
    let offsets = ints(find(&arrays, b"Cells", Some("offsets"), end)?, binary)?;
    let types_array = find(&arrays, b"Cells", Some("types"), end)?;
    let types = ints(types_array, binary)?;
    if offsets.len() != types.len() {
        return Err(Error::new(
            ErrorKind::CountMismatch,
            format!(
                "{} cell offsets for {} cell types",
                offsets.len(),
                types.len()
            ),
        )
        .at_line(types_array.line));
    }
    check_count(
        cell_count,
        types.len(),
        "NumberOfCells",
        "cells",
        piece_line,
    )?;
    let mut tets = Vec::new();
    let mut start = 0;
    for (&(offset, offset_line), &(cell_type, type_line)) in offsets.iter().zip(&types) {
        let stop = usize::try_from(offset)
            .ok()
            .filter(|&stop| start <= stop && stop <= connectivity.len())
            .ok_or_else(|| {
                Error::new(
                    ErrorKind::IndexOutOfRange,
                    format!(
                        "cell offset {offset} out of range ({start} to {} expected)",
                        connectivity.len()
                    ),
                )
                .at_line(offset_line)
            })?;
        let cell = &connectivity[start..stop];
        start = stop;
        let size = match cell_type {
            VTK_TETRA => 4,
            VTK_QUADRATIC_TETRA => 10,
            _ => continue,
        };
        if cell.len() != size {
            return Err(Error::new(
                ErrorKind::Syntax,
                format!(
                    "cell of type {cell_type} has {} points, expected {size}",
                    cell.len()
                ),
            )
            .at_line(type_line));
        }
        let mut tet = [0u32; 4];
        for (corner, &(index, line)) in tet.iter_mut().zip(cell) {
            *corner = usize::try_from(index)
                .ok()
                .filter(|&i| i < n)
                .and_then(|i| u32::try_from(i).ok())
                .ok_or_else(|| {
                    Error::new(
                        ErrorKind::IndexOutOfRange,
                        format!("point index {index} out of range ({n} points)"),
                    )
                    .at_line(line)
                })?;
        }
        tets.push(tet);
    }
    if tets.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "no tetrahedra").at_line(end));
    }

    // Vertex kinds written by us.
    let kinds = match arrays
        .iter()
        .find(|a| a.section == b"PointData" && a.name == "kind")
    {
        None => None,
        Some(array) => {
            let codes = ints(array, binary)?;
            if codes.len() != n {
                return Err(Error::new(
                    ErrorKind::CountMismatch,
                    format!("{} kinds for {n} points", codes.len()),
                )
                .at_line(array.line));
            }
            let kinds = codes.iter().map(|&(code, line)| {
                super::kind_from_code(code).ok_or_else(|| {
                    Error::new(
                        ErrorKind::Syntax,
                        format!("kind {code} is not a kind code (0, 1 or 2)"),
                    )
                    .at_line(line)
                })
            });
            Some(kinds.collect::<Result<Vec<_>>>()?)
        }
    };
    super::build_tet_mesh(positions, tets, kinds)
}

/// `<VTKFile>` must be the one root and an UnstructuredGrid.
fn check_file_type(tag: &Tag, is_root: bool) -> Result<()> {
    if !is_root {
        return Err(Error::new(ErrorKind::Syntax, "a second <VTKFile>").at_line(tag.line));
    }
    match tag.attribute("type") {
        Some("UnstructuredGrid") => Ok(()),
        other => Err(Error::new(
            ErrorKind::Unsupported,
            format!(
                "VTK dataset type {} is not supported (UnstructuredGrid expected)",
                text::shown(other.unwrap_or_default().as_bytes())
            ),
        )
        .at_line(tag.line)),
    }
}

/// The first array in `section` (with `name`, if given).
fn find<'x, 'a>(
    arrays: &'x [Array<'a>],
    section: &[u8],
    name: Option<&str>,
    end: usize,
) -> Result<&'x Array<'a>> {
    arrays
        .iter()
        .find(|a| {
            a.section == section
                && match name {
                    Some(name) => a.name == name,
                    None => true,
                }
        })
        .ok_or_else(|| {
            let section = String::from_utf8_lossy(section);
            let message = match name {
                Some(name) => format!("no <{section}> data array named '{name}'"),
                None => format!("no <{section}> data array"),
            };
            Error::new(ErrorKind::Syntax, message).at_line(end)
        })
}

/// A declared count (if any) must match the actual one.
fn check_count(
    declared: Option<i64>,
    actual: usize,
    key: &str,
    what: &str,
    line: usize,
) -> Result<()> {
    match declared {
        Some(declared) if usize::try_from(declared).ok() != Some(actual) => Err(Error::new(
            ErrorKind::CountMismatch,
            format!("{key} is {declared}, but there are {actual} {what}"),
        )
        .at_line(line)),
        _ => Ok(()),
    }
}

/// The tokens of an array's text with their line numbers.
fn array_tokens<'a>(array: &Array<'a>) -> impl Iterator<Item = (usize, &'a [u8])> {
    let first = array.line;
    text::raw_lines(array.content)
        .flat_map(move |(i, line)| text::tokens(line).map(move |token| (first + i - 1, token)))
}

/// The values of an appended array.
fn appended_values(array: &Array, binary: Option<Binary>) -> Result<Option<Values>> {
    let Some((offset, scalar)) = array.appended else {
        return Ok(None);
    };
    let Some(binary) = binary else {
        return Err(Error::new(
            ErrorKind::Syntax,
            format!(
                "array '{}' is appended, but there is no <AppendedData>",
                array.name
            ),
        )
        .at_line(array.line));
    };
    vtk::decode(binary.blob, offset, scalar, binary.layout)
        .map(Some)
        .map_err(|e| e.at_line(array.line))
}

/// The values of an array as finite numbers.
fn floats(array: &Array, binary: Option<Binary>) -> Result<Vec<f64>> {
    match appended_values(array, binary)? {
        Some(values) => {
            let values = match values {
                Values::Floats(v) => v,
                Values::Ints(v) => v.into_iter().map(|x| x as f64).collect(),
            };
            if let Some(i) = values.iter().position(|x| !x.is_finite()) {
                return Err(Error::new(
                    ErrorKind::NonFinite,
                    format!("array '{}' has a non-finite value at {i}", array.name),
                )
                .at_line(array.line));
            }
            Ok(values)
        }
        None => array_tokens(array)
            .map(|(line, token)| text::parse_coordinate(token, line))
            .collect(),
    }
}

/// The values of an array as integers, each with its line (an appended array's values
/// all carry the line of its tag).
fn ints(array: &Array, binary: Option<Binary>) -> Result<Vec<(i64, usize)>> {
    match appended_values(array, binary)? {
        Some(Values::Ints(values)) => Ok(values.into_iter().map(|v| (v, array.line)).collect()),
        Some(Values::Floats(_)) => Err(Error::new(
            ErrorKind::Syntax,
            format!("array '{}' holds floats, integers expected", array.name),
        )
        .at_line(array.line)),
        None => array_tokens(array)
            .map(|(line, token)| Ok((text::parse_int(token, "value", line)?, line)))
            .collect(),
    }
}

/// The VTU-specific reads of the scanner: data arrays and the appended section.
impl<'a> Scanner<'a> {
    /// The `<DataArray>` just read: its text up to its end tag, or (appended) its
    /// offset and type.
    fn data_array(&mut self, tag: &Tag, section: &'a [u8]) -> Result<Array<'a>> {
        let components = tag.int_attribute("NumberOfComponents")?.unwrap_or(1);
        let name = tag.attribute("Name").unwrap_or_default().to_string();
        match tag.attribute("format").unwrap_or("ascii") {
            "ascii" if !tag.self_closing => {}
            "ascii" => {
                return Ok(Array {
                    section,
                    name,
                    components,
                    content: &[],
                    appended: None,
                    line: tag.line,
                })
            }
            "appended" => {
                let kind = tag.attribute("type").unwrap_or_default();
                let scalar = Scalar::parse(kind).ok_or_else(|| {
                    Error::new(
                        ErrorKind::Unsupported,
                        format!(
                            "data type {} is not supported",
                            text::shown(kind.as_bytes())
                        ),
                    )
                    .at_line(tag.line)
                })?;
                let offset = tag.int_attribute("offset")?.ok_or_else(|| {
                    Error::new(ErrorKind::Syntax, "an appended array without an offset")
                        .at_line(tag.line)
                })?;
                let offset = usize::try_from(offset).map_err(|_| {
                    Error::new(ErrorKind::Syntax, format!("offset {offset} is negative"))
                        .at_line(tag.line)
                })?;
                if !tag.self_closing {
                    self.skip_past(b"</DataArray>")?;
                }
                return Ok(Array {
                    section,
                    name,
                    components,
                    content: &[],
                    appended: Some((offset, scalar)),
                    line: tag.line,
                });
            }
            format => {
                return Err(Error::new(
                    ErrorKind::Unsupported,
                    format!(
                        "data array format {} is not supported (ascii or raw appended expected)",
                        text::shown(format.as_bytes())
                    ),
                )
                .at_line(tag.line))
            }
        }
        let (start, line) = (self.position, self.line);
        let stop = self.find(b"<").ok_or_else(|| {
            Error::new(ErrorKind::Truncated, "file ends inside a <DataArray>")
                .at_line(text::last_line(self.data))
        })?;
        let end_tag = self.next_tag()?;
        if !end_tag
            .as_ref()
            .is_some_and(|end| end.closing && end.name == b"DataArray")
        {
            return Err(Error::new(ErrorKind::Syntax, "expected </DataArray>").at_line(self.line));
        }
        Ok(Array {
            section,
            name,
            components,
            content: &self.data[start..stop],
            appended: None,
            line,
        })
    }

    /// The raw bytes of the `<AppendedData>` section just opened (after its `_`, up to
    /// its end tag, where the scanner goes next).
    fn appended(&mut self, tag: &Tag) -> Result<&'a [u8]> {
        match tag.attribute("encoding").unwrap_or("raw") {
            "raw" => {}
            other => {
                return Err(Error::new(
                    ErrorKind::Unsupported,
                    format!(
                        "appended data encoding {} is not supported (raw expected)",
                        text::shown(other.as_bytes())
                    ),
                )
                .at_line(tag.line))
            }
        }
        let truncated = || {
            Error::new(ErrorKind::Truncated, "file ends inside <AppendedData>")
                .at_line(text::last_line(self.data))
        };
        let start = self.find(b"_").ok_or_else(truncated)? + 1;
        let end_tag = b"</AppendedData>";
        let stop = self.data[start..]
            .windows(end_tag.len())
            .rposition(|w| w == end_tag)
            .map(|i| start + i)
            .ok_or_else(truncated)?;
        self.advance_to(stop);
        Ok(&self.data[start..stop])
    }
}

/// Write a mesh with per-vertex fields (lengths checked by the caller) as VTU.
pub(crate) fn write(mesh: &TetMesh, fields: &[(&str, &[f64])], out: &mut Vec<u8>) -> Result<()> {
    for (i, (name, values)) in fields.iter().enumerate() {
        if *name == "kind" || fields[..i].iter().any(|(other, _)| other == name) {
            return Err(Error::invalid_argument(format!(
                "field name '{name}' is taken ('kind' is the vertex kinds; names must differ)"
            )));
        }
        if let Some(v) = values.iter().position(|x| !x.is_finite()) {
            return Err(Error::new(
                ErrorKind::NonFinite,
                format!("field '{name}' has a non-finite value at vertex {v}"),
            ));
        }
    }
    // Writing into a Vec<u8> cannot fail, so the io::Results below are always Ok.
    let (n, t) = (mesh.positions.len(), mesh.tets.len());
    let mut data = Appended::default();
    let kinds: Vec<i32> = mesh
        .kinds
        .iter()
        .map(|&k| super::kind_code(k) as i32)
        .collect();
    let points: Vec<f64> = mesh.positions.iter().flatten().copied().collect();
    let connectivity: Vec<i64> = mesh.tets.iter().flatten().map(|&v| i64::from(v)).collect();
    let offsets: Vec<i64> = (1..=t as i64).map(|i| 4 * i).collect();
    let _ = writeln!(out, "<?xml version=\"1.0\"?>");
    let _ = writeln!(out, "{}", Appended::root("UnstructuredGrid"));
    let _ = writeln!(out, "  <UnstructuredGrid>");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{t}\">"
    );
    let _ = writeln!(out, "      <PointData Scalars=\"kind\">");
    let _ = writeln!(out, "        {}", data.ints("kind", &kinds));
    for (name, values) in fields {
        let _ = writeln!(out, "        {}", data.floats(name, 1, values));
    }
    let _ = writeln!(out, "      </PointData>");
    let _ = writeln!(out, "      <Points>");
    let _ = writeln!(out, "        {}", data.floats("Points", 3, &points));
    let _ = writeln!(out, "      </Points>");
    let _ = writeln!(out, "      <Cells>");
    let _ = writeln!(out, "        {}", data.longs("connectivity", &connectivity));
    let _ = writeln!(out, "        {}", data.longs("offsets", &offsets));
    let _ = writeln!(
        out,
        "        {}",
        data.bytes("types", &vec![VTK_TETRA as u8; t])
    );
    let _ = writeln!(out, "      </Cells>");
    let _ = writeln!(out, "    </Piece>");
    let _ = writeln!(out, "  </UnstructuredGrid>");
    data.finish(out);
    Ok(())
}
