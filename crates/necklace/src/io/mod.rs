//! Reading and writing surface meshes.
//!
//! Readers: OBJ, OFF, PLY (ascii, binary little and big endian) and STL (ascii and
//! binary). Writers: OBJ, OFF and binary little-endian PLY. Entry points:
//! [`read_mesh`] (a path; format from the extension, else from the content),
//! [`read_mesh_bytes`] (bytes already in memory) and [`write_mesh`].
//!
//! The readers are our own rather than tobj / ply-rs / stl_io because every error must
//! name its line or byte offset, no input may panic, and a header's counts must never
//! be trusted for allocation: memory is reserved only as far as the remaining bytes can
//! hold the records a header announces (a hostile "4 billion faces" costs nothing).
//!
//! Conventions: polygons are fan-split into triangles (v0, vi, vi+1); vertex order and
//! face order are kept as in the file, so writing and reading back gives the same mesh
//! (STL has no shared vertices: coincident corners are welded exactly, in order of first
//! appearance).

mod obj;
mod off;
mod ply;
mod stl;
mod text;

use std::path::Path;

use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Wavefront OBJ.
    Obj,
    /// Object File Format.
    Off,
    /// Stanford PLY.
    Ply,
    /// Stereolithography (ascii or binary).
    Stl,
}

impl Format {
    /// The format named by a file extension (case-insensitive), if any.
    pub fn from_extension(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(Format::Obj),
            "off" => Some(Format::Off),
            "ply" => Some(Format::Ply),
            "stl" => Some(Format::Stl),
            _ => None,
        }
    }

    /// Guess the format from the first bytes of a file.
    pub fn sniff(data: &[u8]) -> Option<Format> {
        let head = &data[..data.len().min(512)];
        let text = String::from_utf8_lossy(head);
        let first = text
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'))
            .unwrap_or("");
        if head.starts_with(b"ply") {
            Some(Format::Ply)
        } else if first.starts_with("OFF") || first.starts_with("COFF") || first.starts_with("NOFF")
        {
            Some(Format::Off)
        } else if stl::looks_like_binary_stl(data) || head.starts_with(b"solid") {
            Some(Format::Stl)
        } else if text.lines().any(|l| {
            let l = l.trim_start();
            l.starts_with("v ") || l.starts_with("f ") || l.starts_with("v\t")
        }) {
            Some(Format::Obj)
        } else {
            None
        }
    }

    /// Lower-case name, as used in messages.
    pub fn name(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Off => "off",
            Format::Ply => "ply",
            Format::Stl => "stl",
        }
    }
}

/// Read a mesh file. The format comes from the extension, or from the content when the
/// extension is missing or unknown. Errors name the file.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<SurfaceMesh> {
    let path = path.as_ref();
    let data = std::fs::read(path)
        .map_err(|e| Error::new(ErrorKind::Io, format!("cannot read: {e}")).in_file(path))?;
    let format = match Format::from_extension(path) {
        Some(f) => f,
        None => Format::sniff(&data).ok_or_else(|| {
            Error::new(
                ErrorKind::UnknownFormat,
                "unknown mesh format (expected .obj, .off, .ply or .stl)",
            )
            .in_file(path)
        })?,
    };
    read_mesh_bytes(&data, format).map_err(|e| e.in_file(path))
}

/// Read a mesh from bytes in a known format.
pub fn read_mesh_bytes(data: &[u8], format: Format) -> Result<SurfaceMesh> {
    if data.iter().all(u8::is_ascii_whitespace) {
        return Err(Error::new(ErrorKind::Empty, "empty file"));
    }
    match format {
        Format::Obj => obj::read(data),
        Format::Off => off::read(data),
        Format::Ply => ply::read(data),
        Format::Stl => stl::read(data),
    }
}

/// Write a mesh; the format comes from the extension (OBJ, OFF or PLY).
pub fn write_mesh(path: impl AsRef<Path>, mesh: &SurfaceMesh) -> Result<()> {
    let path = path.as_ref();
    let format = Format::from_extension(path).ok_or_else(|| {
        Error::new(
            ErrorKind::UnknownFormat,
            "cannot tell the output format: use .obj, .off or .ply",
        )
        .in_file(path)
    })?;
    let bytes = write_mesh_bytes(mesh, format).map_err(|e| e.in_file(path))?;
    std::fs::write(path, bytes)
        .map_err(|e| Error::new(ErrorKind::Io, format!("cannot write: {e}")).in_file(path))
}

/// Encode a mesh in a format (OBJ, OFF or binary little-endian PLY).
pub fn write_mesh_bytes(mesh: &SurfaceMesh, format: Format) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    match format {
        Format::Obj => obj::write(mesh, &mut out),
        Format::Off => off::write(mesh, &mut out),
        Format::Ply => ply::write(mesh, &mut out),
        Format::Stl => {
            return Err(Error::new(
                ErrorKind::Unsupported,
                "writing STL is not supported (it has no shared vertices); use .obj, .off or .ply",
            ))
        }
    }
    Ok(out)
}
