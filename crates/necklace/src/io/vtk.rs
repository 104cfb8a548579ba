//! Binary data of VTK XML files, and the loops as VTK XML curves.
//!
//! Our VTK XML files (`.vtu`, `.vtp`) keep their data after the XML in one
//! `<AppendedData encoding="raw">` section: each array is a `UInt64` block header
//! (`[blocks, block size, last block size, compressed size of each block]`) followed by
//! its zlib-compressed blocks of at most [`BLOCK`] bytes, little-endian
//! (`header_type="UInt64"`, `compressor="vtkZLibDataCompressor"` on `<VTKFile>`). This is
//! VTK's own default layout: ParaView, pyvista, VTK and meshio read it. [`Appended`]
//! builds it; [`decode`] reads one array back from raw appended data, compressed or not,
//! with `UInt32` or `UInt64` headers (what VTK writers produce).
//!
//! Curves ([`polylines_vtp`], [`segments_vtu`]): closed polylines as PolyData `<Lines>`
//! (one polyline cell each, first point repeated at the end; for ParaView and pyvista),
//! and as an UnstructuredGrid of 2-point line cells (VTK type 3; for meshio, which reads
//! no PolyData and no polyline cells). Both carry the cell data `loop` (the polyline's
//! index) and `kind` (a code per polyline given by the caller).
//!
//! Entry points: [`Appended`], [`decode`], [`polylines_vtp`], [`segments_vtu`].

use std::io::{Read, Write};

use flate2::write::ZlibEncoder;
use flate2::Compression;

use crate::error::{Error, ErrorKind, Result};

/// Uncompressed bytes per compressed block.
pub(crate) const BLOCK: usize = 1 << 20;

/// VTK cell types written here.
const VTK_LINE: u8 = 3;

/// A value type of a data array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scalar {
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Float32,
    Float64,
}

impl Scalar {
    /// The `type` attribute's name, as VTK spells it.
    pub(crate) fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "Int8" => Scalar::Int8,
            "UInt8" => Scalar::UInt8,
            "Int16" => Scalar::Int16,
            "UInt16" => Scalar::UInt16,
            "Int32" => Scalar::Int32,
            "UInt32" => Scalar::UInt32,
            "Int64" => Scalar::Int64,
            "UInt64" => Scalar::UInt64,
            "Float32" => Scalar::Float32,
            "Float64" => Scalar::Float64,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::Int8 => "Int8",
            Scalar::UInt8 => "UInt8",
            Scalar::Int16 => "Int16",
            Scalar::UInt16 => "UInt16",
            Scalar::Int32 => "Int32",
            Scalar::UInt32 => "UInt32",
            Scalar::Int64 => "Int64",
            Scalar::UInt64 => "UInt64",
            Scalar::Float32 => "Float32",
            Scalar::Float64 => "Float64",
        }
    }

    fn size(self) -> usize {
        match self {
            Scalar::Int8 | Scalar::UInt8 => 1,
            Scalar::Int16 | Scalar::UInt16 => 2,
            Scalar::Int32 | Scalar::UInt32 | Scalar::Float32 => 4,
            Scalar::Int64 | Scalar::UInt64 | Scalar::Float64 => 8,
        }
    }
}

/// The values of an array read from binary data.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Values {
    /// Integer types (UInt64 above `i64::MAX` is an error).
    Ints(Vec<i64>),
    /// Float types.
    Floats(Vec<f64>),
}

/// The appended section of a VTK XML file being written: arrays are added in order and
/// each returns its `<DataArray>` tag (with its `offset`).
#[derive(Debug, Default)]
pub(crate) struct Appended {
    data: Vec<u8>,
}

impl Appended {
    /// Add an array of `values` (little-endian bytes of `scalar`s) and return its
    /// self-closing `<DataArray>` tag.
    fn add(&mut self, scalar: Scalar, name: &str, components: usize, bytes: &[u8]) -> String {
        let offset = self.data.len();
        let blocks: Vec<&[u8]> = bytes.chunks(BLOCK).collect();
        let compressed: Vec<Vec<u8>> = blocks.iter().map(|b| zlib(b)).collect();
        let last = blocks.last().map_or(0, |b| b.len());
        let mut header = vec![blocks.len() as u64, BLOCK as u64, last as u64];
        header.extend(compressed.iter().map(|c| c.len() as u64));
        for h in header {
            self.data.extend_from_slice(&h.to_le_bytes());
        }
        for c in compressed {
            self.data.extend_from_slice(&c);
        }
        let components = if components > 1 {
            format!(" NumberOfComponents=\"{components}\"")
        } else {
            String::new()
        };
        format!(
            "<DataArray type=\"{}\" Name=\"{}\"{components} format=\"appended\" offset=\"{offset}\"/>",
            scalar.name(),
            escape(name)
        )
    }

    /// Add `f64` values.
    pub(crate) fn floats(&mut self, name: &str, components: usize, values: &[f64]) -> String {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.add(Scalar::Float64, name, components, &bytes)
    }

    /// Add `i32` values.
    pub(crate) fn ints(&mut self, name: &str, values: &[i32]) -> String {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.add(Scalar::Int32, name, 1, &bytes)
    }

    /// Add `i64` values.
    pub(crate) fn longs(&mut self, name: &str, values: &[i64]) -> String {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.add(Scalar::Int64, name, 1, &bytes)
    }

    /// Add `u8` values.
    pub(crate) fn bytes(&mut self, name: &str, values: &[u8]) -> String {
        self.add(Scalar::UInt8, name, 1, values)
    }

    /// The `<VTKFile>` start tag of a file of `kind` (`UnstructuredGrid`, `PolyData`)
    /// whose data this holds.
    pub(crate) fn root(kind: &str) -> String {
        format!(
            "<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"
        )
    }

    /// Append the section and the file's end to `out`.
    pub(crate) fn finish(self, out: &mut Vec<u8>) {
        out.extend_from_slice(b"  <AppendedData encoding=\"raw\">\n   _");
        out.extend_from_slice(&self.data);
        out.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
    }
}

fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = ZlibEncoder::new(Vec::new(), Compression::fast());
    // Writing into a Vec<u8> cannot fail.
    let _ = encoder.write_all(bytes);
    encoder.finish().unwrap_or_default()
}

/// Escape text for an attribute value.
pub(crate) fn escape(value: &str) -> String {
    value
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// How a file's appended data is laid out (attributes of `<VTKFile>`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Layout {
    /// Header words are UInt64 (else UInt32, VTK's default).
    pub wide_header: bool,
    /// Blocks are zlib-compressed (else one uncompressed block).
    pub compressed: bool,
}

impl Layout {
    /// From the `header_type` and `compressor` attributes.
    pub(crate) fn new(header_type: Option<&str>, compressor: Option<&str>) -> Result<Layout> {
        let wide_header = match header_type.unwrap_or("UInt32") {
            "UInt32" => false,
            "UInt64" => true,
            other => {
                return Err(Error::new(
                    ErrorKind::Unsupported,
                    format!("header_type '{other}' is not supported (UInt32 or UInt64)"),
                ))
            }
        };
        let compressed = match compressor {
            None | Some("") => false,
            Some("vtkZLibDataCompressor") => true,
            Some(other) => {
                return Err(Error::new(
                    ErrorKind::Unsupported,
                    format!("compressor '{other}' is not supported (zlib only)"),
                ))
            }
        };
        Ok(Layout {
            wide_header,
            compressed,
        })
    }
}

/// Read the array of `scalar`s at `offset` in raw appended data `blob`.
pub(crate) fn decode(blob: &[u8], offset: usize, scalar: Scalar, layout: Layout) -> Result<Values> {
    let corrupt = |what: &str| {
        Error::new(
            ErrorKind::Truncated,
            format!("appended data at offset {offset}: {what}"),
        )
    };
    let word = if layout.wide_header { 8 } else { 4 };
    let take = |at: usize, length: usize| at.checked_add(length).and_then(|end| blob.get(at..end));
    let mut at = offset;
    let next_word = |at: &mut usize| -> Result<usize> {
        let bytes = take(*at, word).ok_or_else(|| corrupt("ends inside a block header"))?;
        *at += word;
        let value = if word == 8 {
            u64::from_le_bytes(bytes.try_into().unwrap_or_default())
        } else {
            u64::from(u32::from_le_bytes(bytes.try_into().unwrap_or_default()))
        };
        usize::try_from(value).map_err(|_| corrupt("a size beyond this machine"))
    };
    let bytes = if layout.compressed {
        let blocks = next_word(&mut at)?;
        let block_size = next_word(&mut at)?;
        let last = next_word(&mut at)?;
        let sizes = (0..blocks)
            .map(|_| next_word(&mut at))
            .collect::<Result<Vec<_>>>()?;
        let mut out = Vec::new();
        for (i, &size) in sizes.iter().enumerate() {
            let expected = if i + 1 == blocks && last != 0 {
                last
            } else {
                block_size
            };
            let compressed =
                take(at, size).ok_or_else(|| corrupt("ends inside a compressed block"))?;
            at += size;
            let start = out.len();
            flate2::read::ZlibDecoder::new(compressed)
                .take(expected as u64)
                .read_to_end(&mut out)
                .map_err(|e| corrupt(&format!("block {i} is not zlib data ({e})")))?;
            if out.len() - start != expected {
                return Err(corrupt(&format!(
                    "block {i} holds {} bytes, its header says {expected}",
                    out.len() - start
                )));
            }
        }
        out
    } else {
        let length = next_word(&mut at)?;
        take(at, length)
            .ok_or_else(|| corrupt("ends inside the data"))?
            .to_vec()
    };
    let size = scalar.size();
    if bytes.len() % size != 0 {
        return Err(corrupt(&format!(
            "{} bytes are not a whole number of {}",
            bytes.len(),
            scalar.name()
        )));
    }
    let chunks = bytes.chunks_exact(size);
    let array = |c: &[u8]| -> [u8; 8] {
        let mut a = [0u8; 8];
        a[..c.len()].copy_from_slice(c);
        a
    };
    Ok(match scalar {
        Scalar::Float32 => Values::Floats(
            chunks
                .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
                .collect(),
        ),
        Scalar::Float64 => Values::Floats(chunks.map(|c| f64::from_le_bytes(array(c))).collect()),
        Scalar::Int8 => Values::Ints(chunks.map(|c| i64::from(c[0] as i8)).collect()),
        Scalar::UInt8 => Values::Ints(chunks.map(|c| i64::from(c[0])).collect()),
        Scalar::Int16 => Values::Ints(
            chunks
                .map(|c| i64::from(i16::from_le_bytes([c[0], c[1]])))
                .collect(),
        ),
        Scalar::UInt16 => Values::Ints(
            chunks
                .map(|c| i64::from(u16::from_le_bytes([c[0], c[1]])))
                .collect(),
        ),
        Scalar::Int32 => Values::Ints(
            chunks
                .map(|c| i64::from(i32::from_le_bytes([c[0], c[1], c[2], c[3]])))
                .collect(),
        ),
        Scalar::UInt32 => Values::Ints(
            chunks
                .map(|c| i64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])))
                .collect(),
        ),
        Scalar::Int64 => Values::Ints(chunks.map(|c| i64::from_le_bytes(array(c))).collect()),
        Scalar::UInt64 => Values::Ints(
            chunks
                .map(|c| {
                    i64::try_from(u64::from_le_bytes(array(c)))
                        .map_err(|_| corrupt("a UInt64 value above the Int64 range"))
                })
                .collect::<Result<Vec<_>>>()?,
        ),
    })
}

/// Closed polylines (`kinds[i]` per polyline) as a VTK XML PolyData file: one polyline
/// cell each, its first point repeated at the end, with cell data `loop` and `kind`.
pub(crate) fn polylines_vtp(polylines: &[Vec<[f64; 3]>], kinds: &[i32]) -> Vec<u8> {
    let points: Vec<f64> = polylines.iter().flatten().flatten().copied().collect();
    let mut connectivity = Vec::new();
    let mut offsets = Vec::new();
    let mut base = 0;
    for line in polylines {
        let n = line.len() as i32;
        connectivity.extend(base..base + n);
        if n > 0 {
            connectivity.push(base);
        }
        offsets.push(connectivity.len() as i32);
        base += n;
    }
    let loops: Vec<i32> = (0..polylines.len() as i32).collect();
    let mut data = Appended::default();
    let mut out = Vec::new();
    let _ = writeln!(out, "<?xml version=\"1.0\"?>");
    let _ = writeln!(out, "{}", Appended::root("PolyData"));
    let _ = writeln!(out, "  <PolyData>");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">",
        points.len() / 3,
        polylines.len()
    );
    let _ = writeln!(out, "      <CellData Scalars=\"loop\">");
    let _ = writeln!(out, "        {}", data.ints("loop", &loops));
    let _ = writeln!(out, "        {}", data.ints("kind", kinds));
    let _ = writeln!(out, "      </CellData>");
    let _ = writeln!(
        out,
        "      <Points>\n        {}\n      </Points>",
        data.floats("Points", 3, &points)
    );
    let _ = writeln!(out, "      <Lines>");
    let _ = writeln!(out, "        {}", data.ints("connectivity", &connectivity));
    let _ = writeln!(out, "        {}", data.ints("offsets", &offsets));
    let _ = writeln!(out, "      </Lines>");
    let _ = writeln!(out, "    </Piece>");
    let _ = writeln!(out, "  </PolyData>");
    data.finish(&mut out);
    out
}

/// Closed polylines as a VTK XML UnstructuredGrid of 2-point line cells (one per
/// segment, the closing one included), with cell data `loop` and `kind` per segment.
pub(crate) fn segments_vtu(polylines: &[Vec<[f64; 3]>], kinds: &[i32]) -> Vec<u8> {
    let points: Vec<f64> = polylines.iter().flatten().flatten().copied().collect();
    let mut connectivity = Vec::new();
    let mut loops = Vec::new();
    let mut segment_kinds = Vec::new();
    let mut base = 0;
    for (i, line) in polylines.iter().enumerate() {
        let n = line.len() as i32;
        for k in 0..n {
            connectivity.extend([base + k, base + (k + 1) % n]);
            loops.push(i as i32);
            segment_kinds.push(kinds[i]);
        }
        base += n;
    }
    let cells = loops.len();
    let offsets: Vec<i32> = (1..=cells as i32).map(|c| 2 * c).collect();
    let mut data = Appended::default();
    let mut out = Vec::new();
    let _ = writeln!(out, "<?xml version=\"1.0\"?>");
    let _ = writeln!(out, "{}", Appended::root("UnstructuredGrid"));
    let _ = writeln!(out, "  <UnstructuredGrid>");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{cells}\">",
        points.len() / 3
    );
    let _ = writeln!(out, "      <CellData Scalars=\"loop\">");
    let _ = writeln!(out, "        {}", data.ints("loop", &loops));
    let _ = writeln!(out, "        {}", data.ints("kind", &segment_kinds));
    let _ = writeln!(out, "      </CellData>");
    let _ = writeln!(
        out,
        "      <Points>\n        {}\n      </Points>",
        data.floats("Points", 3, &points)
    );
    let _ = writeln!(out, "      <Cells>");
    let _ = writeln!(out, "        {}", data.ints("connectivity", &connectivity));
    let _ = writeln!(out, "        {}", data.ints("offsets", &offsets));
    let _ = writeln!(
        out,
        "        {}",
        data.bytes("types", &vec![VTK_LINE; cells])
    );
    let _ = writeln!(out, "      </Cells>");
    let _ = writeln!(out, "    </Piece>");
    let _ = writeln!(out, "  </UnstructuredGrid>");
    data.finish(&mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> Layout {
        Layout {
            wide_header: true,
            compressed: true,
        }
    }

    #[test]
    fn arrays_round_trip_across_blocks() {
        let mut appended = Appended::default();
        // More than one block, and an empty array.
        let values: Vec<f64> = (0..(BLOCK / 8 + 1000)).map(|i| i as f64 * 0.5).collect();
        appended.floats("a", 1, &values);
        let second = appended.data.len();
        appended.ints("b", &[]);
        let third = appended.data.len();
        appended.ints("c", &[-3, 7]);
        let blob = appended.data;
        assert_eq!(
            decode(&blob, 0, Scalar::Float64, layout()).unwrap(),
            Values::Floats(values)
        );
        assert_eq!(
            decode(&blob, second, Scalar::Int32, layout()).unwrap(),
            Values::Ints(vec![])
        );
        assert_eq!(
            decode(&blob, third, Scalar::Int32, layout()).unwrap(),
            Values::Ints(vec![-3, 7])
        );
    }

    #[test]
    fn uncompressed_narrow_headers_are_read() {
        let mut blob = 12u32.to_le_bytes().to_vec();
        for v in [1i32, -2, 3] {
            blob.extend_from_slice(&v.to_le_bytes());
        }
        let plain = Layout {
            wide_header: false,
            compressed: false,
        };
        assert_eq!(
            decode(&blob, 0, Scalar::Int32, plain).unwrap(),
            Values::Ints(vec![1, -2, 3])
        );
        // Cut short: an error, not a panic.
        assert!(decode(&blob[..10], 0, Scalar::Int32, plain).is_err());
    }

    #[test]
    fn damaged_blocks_are_errors() {
        let mut appended = Appended::default();
        appended.floats("a", 1, &[1.0, 2.0, 3.0]);
        let mut blob = appended.data;
        let n = blob.len();
        blob[n - 3] ^= 0xff;
        assert!(decode(&blob, 0, Scalar::Float64, layout()).is_err());
        assert!(decode(&blob[..n - 2], 0, Scalar::Float64, layout()).is_err());
    }
}
