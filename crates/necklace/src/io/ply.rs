//! Stanford PLY: reads ascii, binary little-endian and binary big-endian PLY; writes
//! binary little-endian PLY.
//!
//! Reading:
//! - The header: `ply`, `format ascii|binary_little_endian|binary_big_endian 1.0`,
//!   `comment` and `obj_info` lines, `element NAME COUNT`, `property TYPE NAME`,
//!   `property list COUNTTYPE ITEMTYPE NAME`, `end_header`. Lines may end in CRLF; binary
//!   data starts right after the `\n` of `end_header`. Types: `char`/`int8`,
//!   `uchar`/`uint8`, `short`/`int16`, `ushort`/`uint16`, `int`/`int32`, `uint`/`uint32`,
//!   `float`/`float32`, `double`/`float64`.
//! - Element `vertex` needs scalar properties `x`, `y`, `z` of any type; element `face`
//!   needs an integer list property `vertex_indices` (or `vertex_index`). Every other
//!   property (scalar or list, in any order) and every other element (before, between or
//!   after these two) is read and skipped. Faces are split into triangles (fans up to quads).
//! - Ascii data is one record per non-blank line; a record with too few or too many
//!   values is an error.
//!
//! Errors: header problems carry the header line number, ascii data problems the line
//! number, binary data problems the byte offset. Malformed header lines, unknown formats
//! or types, a missing `end_header`, a missing `vertex`/`face` element or property, a
//! negative list count or a face with fewer than 3 vertices are [`ErrorKind::Syntax`];
//! data that ends early is [`ErrorKind::Truncated`]; NaN or infinite coordinates are
//! [`ErrorKind::NonFinite`]; negative or too large face indices
//! [`ErrorKind::IndexOutOfRange`]; zero faces [`ErrorKind::Empty`]. Before reserving
//! memory for binary records, the reader checks that the remaining bytes can hold the
//! announced count at the smallest possible record size, so a hostile header fails fast.
//!
//! Writing: binary little-endian, `double` x/y/z and `list uchar uint vertex_indices`.

use super::text;
use super::PointCloud;
use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;

/// Read a PLY file.
pub(crate) fn read(data: &[u8]) -> Result<SurfaceMesh> {
    let header = parse_header(data)?;
    let layout = Layout::new(&header)?;
    let body = data.get(header.data_start..).unwrap_or_default();
    match header.format {
        Format::Ascii => {
            let mut source = AsciiSource::new(body, header.end_line);
            read_elements(&mut source, &header, &layout)
        }
        Format::Binary { big_endian } => {
            let mut source = BinarySource {
                data,
                pos: header.data_start,
                last: header.data_start,
                big_endian,
            };
            read_elements(&mut source, &header, &layout)
        }
    }
}

// ---------------------------------------------------------------------------------------
// Header

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> u64 {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The value range of an integer type; `None` for floating-point types.
    fn int_range(self) -> Option<(i64, i64)> {
        match self {
            Scalar::I8 => Some((i8::MIN.into(), i8::MAX.into())),
            Scalar::U8 => Some((0, u8::MAX.into())),
            Scalar::I16 => Some((i16::MIN.into(), i16::MAX.into())),
            Scalar::U16 => Some((0, u16::MAX.into())),
            Scalar::I32 => Some((i32::MIN.into(), i32::MAX.into())),
            Scalar::U32 => Some((0, u32::MAX.into())),
            Scalar::F32 | Scalar::F64 => None,
        }
    }

    fn is_integer(self) -> bool {
        self.int_range().is_some()
    }
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    /// Header line of the `element` statement.
    line: usize,
    properties: Vec<Property>,
}

impl Element {
    /// The smallest possible size of one binary record (lists empty).
    fn min_record_size(&self) -> u64 {
        self.properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(t) => t.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }
}

#[derive(Debug, Clone, Copy)]
enum Format {
    Ascii,
    Binary { big_endian: bool },
}

#[derive(Debug)]
struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// Line number of `end_header`.
    end_line: usize,
}

fn syntax(message: impl Into<String>, line: usize) -> Error {
    Error::new(ErrorKind::Syntax, message).at_line(line)
}

/// The byte offset just after the `end_header` line.
fn find_end_header(data: &[u8]) -> Result<usize> {
    let mut pos = 0;
    for line in data.split_inclusive(|&b| b == b'\n') {
        pos += line.len();
        if line.trim_ascii() == b"end_header" {
            return Ok(pos);
        }
    }
    Err(Error::new(
        ErrorKind::Syntax,
        "header has no end_header line",
    ))
}

fn parse_header(data: &[u8]) -> Result<Header> {
    let data_start = find_end_header(data)?;
    let header = data.get(..data_start).unwrap_or_default();
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut end_line = 0;
    for (number, raw) in text::raw_lines(header) {
        end_line = number;
        let line = String::from_utf8_lossy(raw);
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        if number == 1 {
            if words != ["ply"] {
                return Err(syntax("missing ply header", 1));
            }
            continue;
        }
        match words.as_slice() {
            [] | ["comment" | "obj_info", ..] | ["end_header"] => {}
            ["format", name, _version] => {
                format = Some(match *name {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Binary { big_endian: false },
                    "binary_big_endian" => Format::Binary { big_endian: true },
                    _ => {
                        let name = text::shown(name.as_bytes());
                        return Err(syntax(format!("unknown PLY format {name}"), number));
                    }
                });
            }
            ["element", name, count] => {
                let count = count.parse::<u64>().map_err(|_| {
                    let count = text::shown(count.as_bytes());
                    syntax(format!("bad element count {count}"), number)
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    line: number,
                    properties: Vec::new(),
                });
            }
            ["property", rest @ ..] => {
                let property = parse_property(rest, number)?;
                let element = elements
                    .last_mut()
                    .ok_or_else(|| syntax("property before any element", number))?;
                element.properties.push(property);
            }
            _ => {
                let shown = text::shown(raw);
                return Err(syntax(format!("unexpected header line {shown}"), number));
            }
        }
    }
    let format = format.ok_or_else(|| syntax("header has no format line", end_line))?;
    Ok(Header {
        format,
        elements,
        data_start,
        end_line,
    })
}

/// The words after `property`: `TYPE NAME` or `list COUNTTYPE ITEMTYPE NAME`.
fn parse_property(words: &[&str], line: usize) -> Result<Property> {
    let scalar = |name: &str| {
        Scalar::from_name(name).ok_or_else(|| {
            let name = text::shown(name.as_bytes());
            syntax(format!("unknown property type {name}"), line)
        })
    };
    let (kind, name) = match words {
        ["list", count, item, name] => {
            let count = scalar(count)?;
            if !count.is_integer() {
                return Err(syntax("list count type must be an integer type", line));
            }
            let item = scalar(item)?;
            (Kind::List { count, item }, name)
        }
        [ty, name] => (Kind::Scalar(scalar(ty)?), name),
        _ => return Err(syntax("malformed property line", line)),
    };
    Ok(Property {
        name: name.to_string(),
        kind,
    })
}

/// Where the mesh data sits: which element holds the vertices and which the faces.
struct Layout {
    vertex_element: usize,
    /// Property indices of x, y and z in the vertex element.
    xyz: [usize; 3],
    face_element: usize,
    /// Property index of the vertex index list in the face element.
    face_list: usize,
    vertex_count: u64,
}

impl Layout {
    fn new(header: &Header) -> Result<Layout> {
        let find = |name: &str| {
            header
                .elements
                .iter()
                .position(|e| e.name == name)
                .ok_or_else(|| syntax(format!("no '{name}' element"), header.end_line))
        };
        let vertex_element = find("vertex")?;
        let face_element = find("face")?;
        let vertex = &header.elements[vertex_element];
        let face = &header.elements[face_element];

        let mut xyz = [0; 3];
        for (slot, axis) in xyz.iter_mut().zip(["x", "y", "z"]) {
            *slot = match vertex.properties.iter().position(|p| p.name == axis) {
                None => {
                    let message = format!("vertex element has no property '{axis}'");
                    return Err(syntax(message, vertex.line));
                }
                Some(i) => match vertex.properties[i].kind {
                    Kind::Scalar(_) => i,
                    Kind::List { .. } => {
                        let message = format!("vertex property '{axis}' is a list");
                        return Err(syntax(message, vertex.line));
                    }
                },
            };
        }

        let face_list = face
            .properties
            .iter()
            .position(|p| p.name == "vertex_indices" || p.name == "vertex_index")
            .ok_or_else(|| syntax("face element has no 'vertex_indices' list", face.line))?;
        match face.properties[face_list].kind {
            Kind::List { item, .. } if item.is_integer() => {}
            Kind::List { .. } => {
                return Err(syntax("face vertex indices must be integers", face.line))
            }
            Kind::Scalar(_) => {
                return Err(syntax("face 'vertex_indices' is not a list", face.line))
            }
        }
        Ok(Layout {
            vertex_element,
            xyz,
            face_element,
            face_list,
            vertex_count: vertex.count,
        })
    }
}

// ---------------------------------------------------------------------------------------
// Data

/// Where element records come from: ascii lines or binary bytes.
trait Source {
    /// Start the next record of `element`; `index` records were read before.
    fn begin_record(&mut self, element: &Element, index: u64) -> Result<()>;
    /// Finish a record.
    fn end_record(&mut self, element: &Element) -> Result<()>;
    /// Read one value (integer types are exact in f64).
    fn scalar(&mut self, ty: Scalar) -> Result<f64>;
    /// Skip `n` values of a type.
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<()>;
    /// Before reading `element`: check that the data can hold it, and return how many
    /// records it is safe to reserve memory for.
    fn room_for(&self, element: &Element) -> Result<usize>;
    /// An error at the location of the last value read.
    fn error(&self, kind: ErrorKind, message: String) -> Error;
}

fn read_elements(
    source: &mut impl Source,
    header: &Header,
    layout: &Layout,
) -> Result<SurfaceMesh> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut polygon = Vec::new();
    for (e, element) in header.elements.iter().enumerate() {
        if element.properties.is_empty() {
            continue; // records without properties take no data
        }
        let reserve = source.room_for(element)?;
        if e == layout.vertex_element {
            positions.reserve(reserve);
        } else if e == layout.face_element {
            triangles.reserve(reserve);
        }
        for index in 0..element.count {
            source.begin_record(element, index)?;
            let mut position = [0.0; 3];
            for (p, property) in element.properties.iter().enumerate() {
                match property.kind {
                    Kind::Scalar(ty) => {
                        let value = source.scalar(ty)?;
                        if e == layout.vertex_element {
                            if let Some(axis) = layout.xyz.iter().position(|&i| i == p) {
                                if !value.is_finite() {
                                    let message = format!("non-finite coordinate {value}");
                                    return Err(source.error(ErrorKind::NonFinite, message));
                                }
                                position[axis] = value;
                            }
                        }
                    }
                    Kind::List { count, item } => {
                        let n = list_length(source, count)?;
                        if e == layout.face_element && p == layout.face_list {
                            read_face(source, item, n, layout.vertex_count, &mut polygon)?;
                            text::triangulate(&polygon, &mut triangles);
                        } else {
                            source.skip(item, n)?;
                        }
                    }
                }
            }
            source.end_record(element)?;
            if e == layout.vertex_element {
                positions.push(position);
            }
        }
    }
    if triangles.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "no faces"));
    }
    Ok(SurfaceMesh {
        positions,
        triangles,
    })
}

fn list_length(source: &mut impl Source, ty: Scalar) -> Result<u64> {
    let n = source.scalar(ty)?;
    if n < 0.0 {
        return Err(source.error(ErrorKind::Syntax, format!("negative list count {n}")));
    }
    // An integer type (checked in the header) of at most 32 bits: exact.
    Ok(n as u64)
}

fn read_face(
    source: &mut impl Source,
    item: Scalar,
    n: u64,
    vertex_count: u64,
    polygon: &mut Vec<u32>,
) -> Result<()> {
    if n < 3 {
        return Err(source.error(
            ErrorKind::Syntax,
            format!("face has {n} vertices, at least 3 needed"),
        ));
    }
    polygon.clear();
    for _ in 0..n {
        let index = source.scalar(item)?;
        // An integer type of at most 32 bits: exact in f64 and in i64.
        let index = index as i64;
        let valid = u64::try_from(index)
            .ok()
            .filter(|&i| i < vertex_count)
            .and_then(|i| u32::try_from(i).ok());
        let index = valid.ok_or_else(|| {
            let message = format!("vertex index {index} out of range ({vertex_count} vertices)");
            source.error(ErrorKind::IndexOutOfRange, message)
        })?;
        polygon.push(index);
    }
    Ok(())
}

/// Ascii data: one record per non-blank line.
struct AsciiSource<'a> {
    lines: Box<dyn Iterator<Item = (usize, &'a [u8])> + 'a>,
    /// Line number of the current record.
    line: usize,
    /// Last line of the file, for "ends early" errors.
    end: usize,
    tokens: Vec<&'a [u8]>,
    next: usize,
}

impl<'a> AsciiSource<'a> {
    /// Records from `body`, which follows `offset` header lines.
    fn new(body: &'a [u8], offset: usize) -> Self {
        let lines = text::raw_lines(body)
            .map(move |(n, line)| (n + offset, line.trim_ascii()))
            .filter(|(_, line)| !line.is_empty());
        AsciiSource {
            lines: Box::new(lines),
            line: offset,
            end: offset + text::last_line(body),
            tokens: Vec::new(),
            next: 0,
        }
    }

    fn token(&mut self) -> Result<&'a [u8]> {
        let token = self.tokens.get(self.next).copied().ok_or_else(|| {
            syntax(
                "record has fewer values than the header declares",
                self.line,
            )
        })?;
        self.next += 1;
        Ok(token)
    }
}

impl Source for AsciiSource<'_> {
    fn begin_record(&mut self, element: &Element, index: u64) -> Result<()> {
        let (line, record) = self.lines.next().ok_or_else(|| {
            let message = format!(
                "expected {} '{}' records, found {index}",
                element.count, element.name
            );
            Error::new(ErrorKind::Truncated, message).at_line(self.end)
        })?;
        self.line = line;
        self.tokens.clear();
        self.tokens.extend(text::tokens(record));
        self.next = 0;
        Ok(())
    }

    fn end_record(&mut self, element: &Element) -> Result<()> {
        let extra = self.tokens.len().saturating_sub(self.next);
        if extra > 0 {
            let message = format!("'{}' record has {extra} extra value(s)", element.name);
            return Err(syntax(message, self.line));
        }
        Ok(())
    }

    fn scalar(&mut self, ty: Scalar) -> Result<f64> {
        let token = self.token()?;
        match ty.int_range() {
            None => text::parse_number(token, self.line),
            Some((min, max)) => {
                let value = text::parse_int(token, "value", self.line)?;
                if value < min || value > max {
                    let message = format!("value {value} out of range for its type {ty:?}");
                    return Err(syntax(message, self.line));
                }
                Ok(value as f64)
            }
        }
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> Result<()> {
        for _ in 0..n {
            self.scalar(ty)?;
        }
        Ok(())
    }

    fn room_for(&self, _element: &Element) -> Result<usize> {
        Ok(0) // text: records are pushed as they come
    }

    fn error(&self, kind: ErrorKind, message: String) -> Error {
        Error::new(kind, message).at_line(self.line)
    }
}

/// Binary data, little or big endian.
struct BinarySource<'a> {
    /// The whole file, so that offsets count from its start.
    data: &'a [u8],
    pos: usize,
    /// Offset of the last value read.
    last: usize,
    big_endian: bool,
}

impl BinarySource<'_> {
    fn remaining(&self) -> u64 {
        self.data.len().saturating_sub(self.pos) as u64
    }

    fn truncated(&self, message: String) -> Error {
        Error::new(ErrorKind::Truncated, message).at_byte(self.pos as u64)
    }

    /// The next `N` bytes, in big-endian order.
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut bytes: [u8; N] = self
            .data
            .get(self.pos..)
            .and_then(|rest| rest.get(..N))
            .and_then(|b| b.try_into().ok())
            .ok_or_else(|| self.truncated(format!("data ends inside a {N}-byte value")))?;
        self.last = self.pos;
        self.pos += N;
        if !self.big_endian {
            bytes.reverse();
        }
        Ok(bytes)
    }
}

impl Source for BinarySource<'_> {
    fn begin_record(&mut self, _element: &Element, _index: u64) -> Result<()> {
        Ok(())
    }

    fn end_record(&mut self, _element: &Element) -> Result<()> {
        Ok(())
    }

    fn scalar(&mut self, ty: Scalar) -> Result<f64> {
        Ok(match ty {
            Scalar::I8 => i8::from_be_bytes(self.bytes()?).into(),
            Scalar::U8 => u8::from_be_bytes(self.bytes()?).into(),
            Scalar::I16 => i16::from_be_bytes(self.bytes()?).into(),
            Scalar::U16 => u16::from_be_bytes(self.bytes()?).into(),
            Scalar::I32 => i32::from_be_bytes(self.bytes()?).into(),
            Scalar::U32 => u32::from_be_bytes(self.bytes()?).into(),
            Scalar::F32 => f32::from_be_bytes(self.bytes()?).into(),
            Scalar::F64 => f64::from_be_bytes(self.bytes()?),
        })
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> Result<()> {
        let size = n.checked_mul(ty.size()).filter(|&s| s <= self.remaining());
        let size = size.ok_or_else(|| {
            self.truncated(format!("list of {n} values runs past the end of the data"))
        })?;
        // size <= remaining, so it fits in usize.
        self.pos += size as usize;
        Ok(())
    }

    fn room_for(&self, element: &Element) -> Result<usize> {
        let min_record = element.min_record_size();
        let fits = element
            .count
            .checked_mul(min_record)
            .is_some_and(|needed| needed <= self.remaining());
        if !fits {
            let message = format!(
                "{} '{}' records need at least {} bytes each, only {} bytes remain",
                element.count,
                element.name,
                min_record,
                self.remaining()
            );
            return Err(self.truncated(message));
        }
        // count <= remaining bytes, so it fits in usize.
        Ok(element.count as usize)
    }

    fn error(&self, kind: ErrorKind, message: String) -> Error {
        Error::new(kind, message).at_byte(self.last as u64)
    }
}

// ---------------------------------------------------------------------------------------
// Writing

/// Write a mesh as binary little-endian PLY.
pub(crate) fn write(mesh: &SurfaceMesh, out: &mut Vec<u8>) {
    write_with_labels(mesh, None, out);
}

/// Binary PLY mesh whose faces carry one `int` property `name` (`labels[f]` for face f).
pub(crate) fn write_labelled(mesh: &SurfaceMesh, name: &str, labels: &[i32], out: &mut Vec<u8>) {
    write_with_labels(mesh, Some((name, labels)), out);
}

fn write_with_labels(mesh: &SurfaceMesh, labels: Option<(&str, &[i32])>, out: &mut Vec<u8>) {
    let label_property = labels.map_or(String::new(), |(name, _)| format!("property int {name}\n"));
    let header = format!(
        "ply\n\
         format binary_little_endian 1.0\n\
         comment written by necklace\n\
         element vertex {}\n\
         property double x\n\
         property double y\n\
         property double z\n\
         element face {}\n\
         property list uchar uint vertex_indices\n\
         {label_property}\
         end_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    out.reserve(header.len() + mesh.positions.len() * 24 + mesh.triangles.len() * 17);
    out.extend_from_slice(header.as_bytes());
    for position in &mesh.positions {
        for c in position {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for (f, triangle) in mesh.triangles.iter().enumerate() {
        out.push(3);
        for i in triangle {
            out.extend_from_slice(&i.to_le_bytes());
        }
        if let Some((_, labels)) = labels {
            out.extend_from_slice(&labels[f].to_le_bytes());
        }
    }
}

/// Binary PLY point cloud: `x y z` (double), one double property per named scalar
/// field, and `red green blue` (uchar) when colours are given.
pub(crate) fn write_points(points: &PointCloud, out: &mut Vec<u8>) {
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by necklace\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n",
        points.positions.len()
    );
    for (name, _) in &points.scalars {
        header.push_str(&format!("property double {name}\n"));
    }
    if points.colors.is_some() {
        header.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    header.push_str("end_header\n");
    out.extend_from_slice(header.as_bytes());
    for (i, position) in points.positions.iter().enumerate() {
        for c in position {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for (_, values) in &points.scalars {
            out.extend_from_slice(&values[i].to_le_bytes());
        }
        if let Some(colors) = &points.colors {
            out.extend_from_slice(&colors[i]);
        }
    }
}

/// Binary PLY of closed polylines: vertices `x y z` (double), `loop` (int: the
/// polyline's index) and `red green blue` (uchar, the polyline's colour); edges
/// `vertex1 vertex2 loop` (int), the last joining a polyline's end to its start.
pub(crate) fn write_polylines(polylines: &[Vec<[f64; 3]>], colors: &[[u8; 3]], out: &mut Vec<u8>) {
    let vertices: usize = polylines.iter().map(Vec::len).sum();
    let edges: usize = polylines
        .iter()
        .filter(|p| p.len() >= 2)
        .map(Vec::len)
        .sum();
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment closed polylines written by necklace\n\
         element vertex {vertices}\nproperty double x\nproperty double y\nproperty double z\n\
         property int loop\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element edge {edges}\nproperty int vertex1\nproperty int vertex2\n\
         end_header\n"
    );
    out.extend_from_slice(header.as_bytes());
    for (i, line) in polylines.iter().enumerate() {
        for p in line {
            for c in p {
                out.extend_from_slice(&c.to_le_bytes());
            }
            out.extend_from_slice(&(i as i32).to_le_bytes());
            out.extend_from_slice(&colors[i]);
        }
    }
    let mut first = 0usize;
    for line in polylines {
        let n = line.len();
        if n >= 2 {
            for k in 0..n {
                out.extend_from_slice(&((first + k) as i32).to_le_bytes());
                out.extend_from_slice(&((first + (k + 1) % n) as i32).to_le_bytes());
            }
        }
        first += n;
    }
}
