//! Reading and writing surface meshes.
//!
//! Readers: OBJ, OFF, PLY (ascii, binary little and big endian) and STL (ascii and
//! binary). Writers: OBJ, OFF and binary little-endian PLY. Entry points:
//! [`read_mesh`] (a path; format from the extension, else from the content),
//! [`read_mesh_bytes`] (bytes already in memory) and [`write_mesh`]; [`mesh_files`]
//! lists the meshes of a folder.
//!
//! The readers are our own rather than tobj / ply-rs / stl_io because every error must
//! name its line or byte offset, no input may panic, and a header's counts must never
//! be trusted for allocation: memory is reserved only as far as the remaining bytes can
//! hold the records a header announces (a hostile "4 billion faces" costs nothing).
//!
//! Conventions: polygons are split into triangles in linear time (a fan up to quads,
//! halving beyond: `text::triangulate`); vertex order and
//! face order are kept as in the file, so writing and reading back gives the same mesh
//! (STL has no shared vertices: coincident corners are welded exactly, in order of first
//! appearance).
//!
//! Tetrahedral meshes have their own entry points, [`read_tet_mesh`] and
//! [`write_tet_mesh`] (plus byte-level variants), for TetGen `.node`/`.ele`, Medit
//! `.mesh`, Gmsh `.msh` (2.2 and 4.1 ascii) and VTK XML `.vtu` (read ascii or raw
//! appended, written binary): vertex and tet order are kept, every tet is re-oriented to
//! positive volume, and vertex kinds come from [`TetMesh::classify_boundary`] unless the
//! file carries the kinds we wrote.
//!
//! Also written: point clouds ([`write_point_cloud`], PLY) and closed polylines as OBJ
//! ([`write_polylines`]), PLY (bare edges, the polyline's index on its vertices:
//! [`write_polylines_ply`]) and VTK ([`write_polylines_vtk`]: `.vtp` polylines, `.vtu`
//! line cells). Submodule `vtk` holds the VTK XML files' zlib-block encoding, the only
//! place `flate2` is named.

mod gmsh;
mod medit;
mod obj;
mod off;
mod ply;
mod stl;
mod tetgen;
mod text;
mod vtk;
mod vtu;
mod xml;

use std::path::Path;

use crate::error::{Error, ErrorKind, Result};
use crate::mesh::SurfaceMesh;
use crate::tet::{TetMesh, VertexKind};

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

    /// The format a file's content proves, whatever its name: PLY's `ply` magic line,
    /// an OFF header keyword on the first line, or a binary STL whose size matches its
    /// triangle count. `None` when the content proves nothing (OBJ and ascii STL have no
    /// signature).
    pub fn signature(data: &[u8]) -> Option<Format> {
        let data = skip_bom(data);
        let first = data
            .split(|&b| b == b'\n' || b == b'\r')
            .next()
            .unwrap_or(b"")
            .trim_ascii();
        let keyword = first.split(u8::is_ascii_whitespace).next().unwrap_or(b"");
        if first == b"ply" {
            Some(Format::Ply)
        } else if keyword.ends_with(b"OFF") && keyword.len() <= 6 {
            Some(Format::Off)
        } else if stl::looks_like_binary_stl(data) && !data.starts_with(b"solid") {
            Some(Format::Stl)
        } else {
            None
        }
    }

    /// Guess the format from the first bytes of a file.
    pub fn sniff(data: &[u8]) -> Option<Format> {
        let data = skip_bom(data);
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

/// The mesh files of a folder (extension .obj, .off, .ply or .stl, any case), sorted by
/// name; other files are skipped. Errors name the folder.
pub fn mesh_files(dir: impl AsRef<Path>) -> Result<Vec<std::path::PathBuf>> {
    let dir = dir.as_ref();
    let entries = std::fs::read_dir(dir).map_err(|e| {
        Error::new(ErrorKind::Io, format!("cannot list the folder: {e}")).in_file(dir)
    })?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| {
            Error::new(ErrorKind::Io, format!("cannot list the folder: {e}")).in_file(dir)
        })?;
        let path = entry.path();
        if path.is_file() && Format::from_extension(&path).is_some() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// Read a mesh file. The format comes from the extension, or from the content when the
/// extension is missing or unknown; a file whose content is unmistakably another format
/// (a PLY or OFF header, a binary STL's size) than its extension says is refused with
/// both named. Only regular files are read (not a FIFO, a device or a folder). Errors
/// name the file.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<SurfaceMesh> {
    let path = path.as_ref();
    let data = read_file(path)?;
    let format = match Format::from_extension(path) {
        Some(named) => {
            if let Some(actual) = Format::signature(&data).filter(|&f| f != named) {
                return Err(Error::new(
                    ErrorKind::UnknownFormat,
                    format!(
                        "the name says {} but the content is {}: rename the file to .{}",
                        named.name().to_uppercase(),
                        actual.name().to_uppercase(),
                        actual.name()
                    ),
                )
                .in_file(path));
            }
            named
        }
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

/// Read a mesh from bytes in a known format. A leading UTF-8 byte-order mark is
/// skipped.
pub fn read_mesh_bytes(data: &[u8], format: Format) -> Result<SurfaceMesh> {
    let data = skip_bom(data);
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

/// `data` without a leading UTF-8 byte-order mark (some editors write one; it is not
/// part of the first line).
fn skip_bom(data: &[u8]) -> &[u8] {
    data.strip_prefix(b"\xef\xbb\xbf").unwrap_or(data)
}

/// Points with per-point scalar fields and optional colours (critical points, saddles),
/// written as a binary PLY point cloud by [`write_point_cloud`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    /// Positions.
    pub positions: Vec<[f64; 3]>,
    /// Named per-point values (`name`, one value per point); names must be PLY words.
    pub scalars: Vec<(String, Vec<f64>)>,
    /// Optional RGB colour per point.
    pub colors: Option<Vec<[u8; 3]>>,
}

/// Check, before any work, that [`write_point_cloud`] takes this name (`.ply`).
pub fn check_point_cloud_name(path: &Path) -> Result<()> {
    if Format::from_extension(path) == Some(Format::Ply) {
        Ok(())
    } else {
        Err(Error::new(
            ErrorKind::UnknownFormat,
            "point clouds are written as PLY: use a .ply file name",
        )
        .in_file(path))
    }
}

/// Check, before any work, that [`write_mesh`] takes this name (`.obj`, `.off`,
/// `.ply`).
pub fn check_mesh_name(path: &Path) -> Result<()> {
    match Format::from_extension(path) {
        Some(Format::Obj | Format::Off | Format::Ply) => Ok(()),
        Some(Format::Stl) => Err(Error::new(
            ErrorKind::Unsupported,
            "writing STL is not supported (it has no shared vertices); use .obj, .off or .ply",
        )
        .in_file(path)),
        None => Err(Error::new(
            ErrorKind::UnknownFormat,
            "cannot tell the output format: use .obj, .off or .ply",
        )
        .in_file(path)),
    }
}

/// Check, before any work, that [`write_tet_mesh`] takes this name (`.vtu`, `.mesh`,
/// `.msh`, `.node`).
pub fn check_tet_mesh_name(path: &Path) -> Result<()> {
    match TetFormat::from_extension(path) {
        Some(_) => Ok(()),
        None => Err(Error::new(
            ErrorKind::UnknownFormat,
            "unknown tet mesh format (use .vtu, .mesh, .msh or .node)",
        )
        .in_file(path)),
    }
}

/// Write a point cloud as binary little-endian PLY (the extension must be `.ply`).
pub fn write_point_cloud(path: impl AsRef<Path>, points: &PointCloud) -> Result<()> {
    let path = path.as_ref();
    check_point_cloud_name(path)?;
    let n = points.positions.len();
    let bad_name = |name: &str| name.is_empty() || name.contains(char::is_whitespace);
    if let Some((name, values)) = points
        .scalars
        .iter()
        .find(|(name, values)| values.len() != n || bad_name(name))
    {
        return Err(Error::invalid_argument(format!(
            "point field '{name}' has {} values for {n} points (or is not a single word)",
            values.len()
        )));
    }
    if points.colors.as_ref().is_some_and(|c| c.len() != n) {
        return Err(Error::invalid_argument("one colour per point is needed"));
    }
    let mut out = Vec::new();
    ply::write_points(points, &mut out);
    crate::file::write_atomic(path, &out)
}

/// Write closed polylines as OBJ: their points as `v` lines and each polyline as one
/// `l` element that repeats its first point at the end; `names[i]`, when given, becomes an
/// `o` line before polyline `i`.
pub fn write_polylines(
    path: impl AsRef<Path>,
    polylines: &[Vec<[f64; 3]>],
    names: &[String],
) -> Result<()> {
    let path = path.as_ref();
    if Format::from_extension(path) != Some(Format::Obj) {
        return Err(Error::new(
            ErrorKind::UnknownFormat,
            "polylines are written as OBJ: use a .obj file name",
        )
        .in_file(path));
    }
    crate::file::write_atomic(path, polylines_obj(polylines, names).as_bytes())
}

/// Write closed polylines as binary PLY with an `edge` element of bare `vertex1`,
/// `vertex2` pairs (what trimesh and most readers expect of edges); every vertex carries
/// the index of its polyline (`loop`) and its polyline's colour (`colors[i]`, one per
/// polyline).
pub fn write_polylines_ply(
    path: impl AsRef<Path>,
    polylines: &[Vec<[f64; 3]>],
    colors: &[[u8; 3]],
) -> Result<()> {
    let path = path.as_ref();
    if Format::from_extension(path) != Some(Format::Ply) {
        return Err(Error::new(
            ErrorKind::UnknownFormat,
            "polylines are written as PLY here: use a .ply file name",
        )
        .in_file(path));
    }
    if colors.len() != polylines.len() {
        return Err(Error::invalid_argument(format!(
            "{} colours for {} polylines",
            colors.len(),
            polylines.len()
        )));
    }
    let mut out = Vec::new();
    ply::write_polylines(polylines, colors, &mut out);
    crate::file::write_atomic(path, &out)
}

/// Write closed polylines as VTK XML curves, by the file's extension: `.vtp`, PolyData
/// with one polyline cell each (ParaView, pyvista); `.vtu`, an UnstructuredGrid of
/// 2-point line cells (meshio, which reads neither PolyData nor polyline cells). Cells
/// carry `loop` (the polyline's index) and `kind` (`kinds[i]` for polyline `i`).
pub fn write_polylines_vtk(
    path: impl AsRef<Path>,
    polylines: &[Vec<[f64; 3]>],
    kinds: &[i32],
) -> Result<()> {
    let path = path.as_ref();
    if kinds.len() != polylines.len() {
        return Err(Error::invalid_argument(format!(
            "{} kinds for {} polylines",
            kinds.len(),
            polylines.len()
        )));
    }
    let data = match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("vtp") => vtk::polylines_vtp(polylines, kinds),
        Some(e) if e.eq_ignore_ascii_case("vtu") => vtk::segments_vtu(polylines, kinds),
        _ => {
            return Err(Error::new(
                ErrorKind::UnknownFormat,
                "VTK curves are written as .vtp (polylines) or .vtu (line segments)",
            )
            .in_file(path))
        }
    };
    crate::file::write_atomic(path, &data)
}

/// Write a triangle mesh as binary PLY whose faces carry the `int` property `name`
/// (`labels[f]` for face f), e.g. the index of the loop a membrane belongs to.
pub fn write_labelled_mesh_ply(
    path: impl AsRef<Path>,
    mesh: &SurfaceMesh,
    name: &str,
    labels: &[i32],
) -> Result<()> {
    let path = path.as_ref();
    if Format::from_extension(path) != Some(Format::Ply) {
        return Err(Error::new(
            ErrorKind::UnknownFormat,
            "a labelled mesh is written as PLY: use a .ply file name",
        )
        .in_file(path));
    }
    if labels.len() != mesh.triangles.len() {
        return Err(Error::invalid_argument(format!(
            "{} labels for {} triangles",
            labels.len(),
            mesh.triangles.len()
        )));
    }
    let mut out = Vec::new();
    ply::write_labelled(mesh, name, labels, &mut out);
    crate::file::write_atomic(path, &out)
}

/// The OBJ text of [`write_polylines`].
pub fn polylines_obj(polylines: &[Vec<[f64; 3]>], names: &[String]) -> String {
    use std::fmt::Write as _;
    let mut out = String::from("# closed polylines written by necklace\n");
    let mut next = 1usize;
    for (i, line) in polylines.iter().enumerate() {
        if let Some(name) = names.get(i) {
            let _ = writeln!(out, "o {}", name.replace(char::is_whitespace, "_"));
        }
        for p in line {
            let _ = writeln!(out, "v {} {} {}", p[0], p[1], p[2]);
        }
        if !line.is_empty() {
            out.push('l');
            for k in 0..line.len() {
                let _ = write!(out, " {}", next + k);
            }
            let _ = writeln!(out, " {next}");
        }
        next += line.len();
    }
    out
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
    crate::file::write_atomic(path, &bytes)
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

/// A tetrahedral-mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TetFormat {
    /// TetGen: a pair of files, `X.node` (vertices) and `X.ele` (tets).
    TetGen,
    /// Medit `.mesh` (ascii).
    Medit,
    /// Gmsh `.msh`: reads versions 2.2 and 4.1 ascii, writes 4.1 ascii.
    Gmsh,
    /// VTK XML UnstructuredGrid `.vtu` (ascii data arrays).
    Vtu,
}

impl TetFormat {
    /// The format named by a file extension (case-insensitive): `.node` or `.ele`,
    /// `.mesh`, `.msh`, `.vtu`.
    pub fn from_extension(path: &Path) -> Option<TetFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "node" | "ele" => Some(TetFormat::TetGen),
            "mesh" => Some(TetFormat::Medit),
            "msh" => Some(TetFormat::Gmsh),
            "vtu" => Some(TetFormat::Vtu),
            _ => None,
        }
    }
}

/// Read a tetrahedral mesh; the format comes from the extension (see [`TetFormat`]).
/// For TetGen the path may name either `X.node` or `X.ele`: both are read. Errors name
/// the file they were found in.
///
/// Vertex and tet order are kept; tets with negative volume get two vertices swapped.
/// Vertex kinds are restored from files we wrote (`.vtu` point data `kind`, `.mesh`
/// vertex references after the `# necklace kinds` comment), else computed with
/// [`TetMesh::classify_boundary`].
pub fn read_tet_mesh(path: impl AsRef<Path>) -> Result<TetMesh> {
    let path = path.as_ref();
    let format = TetFormat::from_extension(path).ok_or_else(|| {
        Error::new(
            ErrorKind::UnknownFormat,
            "unknown tet mesh format (expected .node, .ele, .mesh, .msh or .vtu)",
        )
        .in_file(path)
    })?;
    if format == TetFormat::TetGen {
        let node_path = path.with_extension("node");
        let ele_path = path.with_extension("ele");
        let node = read_file(&node_path)?;
        let ele = read_file(&ele_path)?;
        return tetgen::read(
            &node,
            &ele,
            &node_path.display().to_string(),
            &ele_path.display().to_string(),
        );
    }
    let data = read_file(path)?;
    read_tet_mesh_bytes(&data, format).map_err(|e| e.in_file(path))
}

/// Read a tetrahedral mesh from bytes in a single-file format (Medit, Gmsh or VTU).
/// TetGen needs two files: use [`read_tetgen_bytes`] ([`ErrorKind::InvalidArgument`]
/// here).
pub fn read_tet_mesh_bytes(data: &[u8], format: TetFormat) -> Result<TetMesh> {
    let data = skip_bom(data);
    if data.iter().all(u8::is_ascii_whitespace) {
        return Err(Error::new(ErrorKind::Empty, "empty file"));
    }
    match format {
        TetFormat::TetGen => Err(Error::invalid_argument(
            "TetGen meshes are two files: use read_tetgen_bytes",
        )),
        TetFormat::Medit => medit::read(data),
        TetFormat::Gmsh => gmsh::read(data),
        TetFormat::Vtu => vtu::read(data),
    }
}

/// Read a TetGen mesh from the contents of its `.node` and `.ele` files. Errors name
/// the part they were found in (`.node` or `.ele`).
pub fn read_tetgen_bytes(node: &[u8], ele: &[u8]) -> Result<TetMesh> {
    tetgen::read(node, ele, ".node", ".ele")
}

/// Write a tetrahedral mesh; the format comes from the extension: `.vtu`, `.mesh`,
/// `.msh` (Gmsh 4.1 ascii), or `.node` / `.ele` (writes both `X.node` and `X.ele`).
///
/// `fields` are per-vertex scalar fields `(name, values)`, one value per vertex
/// ([`ErrorKind::InvalidArgument`] otherwise), written as VTU point data (Float64);
/// the other formats check but ignore them.
pub fn write_tet_mesh(
    path: impl AsRef<Path>,
    mesh: &TetMesh,
    fields: &[(&str, &[f64])],
) -> Result<()> {
    let path = path.as_ref();
    let format = TetFormat::from_extension(path).ok_or_else(|| {
        Error::new(
            ErrorKind::UnknownFormat,
            "cannot tell the output format: use .vtu, .mesh, .msh or .node",
        )
        .in_file(path)
    })?;
    if format == TetFormat::TetGen {
        check_tet_mesh(mesh, fields).map_err(|e| e.in_file(path))?;
        let (node, ele) = tetgen::write(mesh);
        write_file(&path.with_extension("node"), &node)?;
        return write_file(&path.with_extension("ele"), &ele);
    }
    let bytes = write_tet_mesh_bytes(mesh, format, fields).map_err(|e| e.in_file(path))?;
    write_file(path, &bytes)
}

/// Encode a tetrahedral mesh in a single-file format (VTU, Medit or Gmsh 4.1); `fields`
/// as in [`write_tet_mesh`]. TetGen needs two files: use [`write_tetgen_bytes`]
/// ([`ErrorKind::InvalidArgument`] here).
pub fn write_tet_mesh_bytes(
    mesh: &TetMesh,
    format: TetFormat,
    fields: &[(&str, &[f64])],
) -> Result<Vec<u8>> {
    check_tet_mesh(mesh, fields)?;
    let mut out = Vec::new();
    match format {
        TetFormat::TetGen => {
            return Err(Error::invalid_argument(
                "TetGen meshes are two files: use write_tetgen_bytes",
            ))
        }
        TetFormat::Medit => medit::write(mesh, &mut out),
        TetFormat::Gmsh => gmsh::write(mesh, &mut out),
        TetFormat::Vtu => vtu::write(mesh, fields, &mut out)?,
    }
    Ok(out)
}

/// Encode a tetrahedral mesh as TetGen `(.node, .ele)` contents.
pub fn write_tetgen_bytes(mesh: &TetMesh) -> Result<(Vec<u8>, Vec<u8>)> {
    check_tet_mesh(mesh, &[])?;
    Ok(tetgen::write(mesh))
}

/// The bytes of a regular file. Anything else is refused before reading: a FIFO
/// would block forever and a device such as `/dev/zero` never ends.
fn read_file(path: &Path) -> Result<Vec<u8>> {
    let io_error =
        |e: std::io::Error| Error::new(ErrorKind::Io, format!("cannot read: {e}")).in_file(path);
    let metadata = std::fs::metadata(path).map_err(io_error)?;
    if !metadata.is_file() {
        let what = if metadata.is_dir() {
            "a folder"
        } else {
            "not a regular file (a pipe, socket or device)"
        };
        return Err(Error::new(
            ErrorKind::Io,
            format!("cannot read: {what}; give the path of a mesh file"),
        )
        .in_file(path));
    }
    std::fs::read(path).map_err(io_error)
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::file::write_atomic(path, bytes)
}

/// Check what the writers index by: one kind per vertex, tet corners in range (the
/// fields of a [`TetMesh`] are public), and one value per vertex in every field.
fn check_tet_mesh(mesh: &TetMesh, fields: &[(&str, &[f64])]) -> Result<()> {
    let n = mesh.positions.len();
    if mesh.kinds.len() != n {
        return Err(Error::invalid_argument(format!(
            "{} vertex kinds for {n} vertices",
            mesh.kinds.len()
        )));
    }
    if let Some(v) = mesh.tets.iter().flatten().find(|&&v| v as usize >= n) {
        return Err(Error::invalid_argument(format!(
            "a tet uses vertex {v}, but there are {n} vertices"
        )));
    }
    for (name, values) in fields {
        if values.len() != n {
            return Err(Error::invalid_argument(format!(
                "field '{name}' has {} values for {n} vertices",
                values.len()
            )));
        }
    }
    Ok(())
}

/// The last step of every tet reader: vertex kinds (the file's, or classified from the
/// boundary), then every negatively oriented tet gets its last two vertices swapped.
/// The readers have checked indices and coordinates already.
fn build_tet_mesh(
    positions: Vec<[f64; 3]>,
    tets: Vec<[u32; 4]>,
    kinds: Option<Vec<VertexKind>>,
) -> Result<TetMesh> {
    let kinds = kinds.unwrap_or_else(|| TetMesh::classify_boundary(&positions, &tets));
    let mut mesh = TetMesh::new(positions, tets, kinds)?;
    // Swapping within a tet leaves the vertex-to-tet adjacency unchanged.
    for t in 0..mesh.num_tets() {
        if mesh.tet_volume(t) < 0.0 {
            mesh.tets[t].swap(2, 3);
        }
    }
    Ok(mesh)
}

/// The code of a vertex kind in the files we write: 0 interior, 1 surface, 2 outer.
fn kind_code(kind: VertexKind) -> u8 {
    match kind {
        VertexKind::Interior => 0,
        VertexKind::Surface => 1,
        VertexKind::Outer => 2,
    }
}

/// The vertex kind of a code written by [`kind_code`].
fn kind_from_code(code: i64) -> Option<VertexKind> {
    match code {
        0 => Some(VertexKind::Interior),
        1 => Some(VertexKind::Surface),
        2 => Some(VertexKind::Outer),
        _ => None,
    }
}
