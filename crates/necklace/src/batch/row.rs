//! One mesh's line of a batch: [`Row`], its key, and the JSON-lines file of rows
//! ([`read_rows`], [`RowFile`]) with the repair of a line a kill cut short.

use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{Error, ErrorKind, Result};
use crate::mesh::Side;
use crate::pipeline::{NeckOptions, NeckReport};

/// How a mesh's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// The loops were found.
    Ok,
    /// The mesh was refused or could not be read: `message` says why.
    Error,
    /// The run went over the time limit and was stopped.
    Timeout,
    /// The run went over the memory limit (stopped, or refused by its estimate).
    Memory,
    /// The worker process died (a panic, an abort, a signal): `message` and `signal`.
    Crashed,
}

impl Status {
    /// Every status, in the order summaries list them.
    pub const ALL: [Status; 5] = [
        Status::Ok,
        Status::Error,
        Status::Timeout,
        Status::Memory,
        Status::Crashed,
    ];

    /// The name used in rows and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Error => "error",
            Status::Timeout => "timeout",
            Status::Memory => "memory",
            Status::Crashed => "crashed",
        }
    }
}

/// One loop of a row: what a dataset table needs of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopRow {
    /// `"handle"` or `"tunnel"`.
    pub kind: String,
    /// Length, in the mesh's units.
    pub length: f64,
    /// Centre of the loop's best-fit circle.
    pub center: [f64; 3],
    /// Normal of that circle's plane.
    pub normal: [f64; 3],
    /// Its radius.
    pub radius: f64,
}

/// One mesh's result in a batch: one JSON line of the runs file (`docs/output.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The mesh file, as given (or found in a folder).
    pub path: String,
    /// Its size in bytes (0 when it could not be read).
    pub bytes: u64,
    /// SHA-256 of its content, hex (empty when it could not be read).
    pub sha256: String,
    /// SHA-256 of the options, hex ([`options_hash`]).
    pub options_hash: String,
    /// necklace's version.
    pub version: String,
    /// How the run ended.
    pub status: Status,
    /// Why it did not end `ok`: the one-line error, or what stopped it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// The signal that ended a crashed worker.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<i32>,
    /// Connected components of the surface the method worked on.
    #[serde(default)]
    pub components: Option<usize>,
    /// Genus of each component (`null` where it has none: open or not manifold).
    #[serde(default)]
    pub genus: Option<Vec<Option<i64>>>,
    /// Handle loops found.
    #[serde(default)]
    pub handles: Option<usize>,
    /// Tunnel loops found.
    #[serde(default)]
    pub tunnels: Option<usize>,
    /// The loops, handles first.
    #[serde(default)]
    pub loops: Vec<LoopRow>,
    /// Saddles that gave no loop, counted by reason.
    #[serde(default)]
    pub drops: BTreeMap<String, usize>,
    /// The run's warnings and notes, one line each.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Seconds per stage (summed over the sides) and the run's own wall clock.
    #[serde(default)]
    pub timings: BTreeMap<String, f64>,
    /// Wall-clock seconds of the mesh's worker, start to end, as the batch measured it.
    pub seconds: f64,
    /// Peak resident memory of the worker, bytes (where the system tells it).
    #[serde(default)]
    pub peak_memory: Option<u64>,
}

/// What identifies a row for resuming: the mesh file and its content, the options and
/// necklace's version.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RowKey {
    /// The file, as given.
    pub path: String,
    /// SHA-256 of its content.
    pub sha256: String,
    /// SHA-256 of the options.
    pub options_hash: String,
    /// necklace's version.
    pub version: String,
}

impl Row {
    /// A row with the key's fields and nothing else yet.
    pub fn new(key: &RowKey, bytes: u64, status: Status) -> Row {
        Row {
            path: key.path.clone(),
            bytes,
            sha256: key.sha256.clone(),
            options_hash: key.options_hash.clone(),
            version: key.version.clone(),
            status,
            message: None,
            signal: None,
            components: None,
            genus: None,
            handles: None,
            tunnels: None,
            loops: Vec::new(),
            drops: BTreeMap::new(),
            warnings: Vec::new(),
            timings: BTreeMap::new(),
            seconds: 0.0,
            peak_memory: None,
        }
    }

    /// The row's key.
    pub fn key(&self) -> RowKey {
        RowKey {
            path: self.path.clone(),
            sha256: self.sha256.clone(),
            options_hash: self.options_hash.clone(),
            version: self.version.clone(),
        }
    }

    /// Fill the result fields from a finished run's report.
    pub fn fill(&mut self, report: &NeckReport) {
        let surface = crate::mesh::MeshReport::new(&report.surface);
        self.components = Some(surface.components);
        self.genus = Some(surface.genus.clone());
        let count = |side: Side| report.loops.iter().filter(|l| l.kind == side).count();
        self.handles = Some(count(Side::Inside));
        self.tunnels = Some(count(Side::Outside));
        self.loops = report
            .loops
            .iter()
            .map(|l| LoopRow {
                kind: neck_name(l.kind).to_string(),
                length: l.length,
                center: l.center,
                normal: l.normal,
                radius: l.radius,
            })
            .collect();
        self.drops = BTreeMap::new();
        for d in &report.dropped {
            let reason = serde_json::to_value(d.reason)
                .ok()
                .and_then(|v| v.get("reason").and_then(|r| r.as_str().map(str::to_string)))
                .unwrap_or_else(|| "unknown".to_string());
            *self.drops.entry(reason).or_default() += 1;
        }
        self.warnings = report
            .notes
            .iter()
            .chain(&report.warnings)
            .cloned()
            .collect();
        let t = &report.timings;
        self.timings = [
            ("input", t.input),
            ("survey", t.survey),
            ("volume_mesh", t.total.volume_mesh),
            ("distance", t.total.distance),
            ("smoothing", t.total.smoothing),
            ("critical_points", t.total.critical_points),
            ("loops", t.total.loops),
            ("total", t.seconds),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    }
}

/// `"handle"` for the inside, `"tunnel"` for the outside.
fn neck_name(side: Side) -> &'static str {
    match side {
        Side::Inside => "handle",
        Side::Outside => "tunnel",
    }
}

/// SHA-256 of bytes, as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The options as JSON: what a worker process is given, and what [`options_hash`]
/// hashes.
pub fn options_json(options: &NeckOptions) -> Result<String> {
    serde_json::to_string(options).map_err(|e| {
        Error::new(
            ErrorKind::Internal,
            format!("cannot encode the options: {e}"),
        )
    })
}

/// The options read back from [`options_json`].
pub fn options_from_json(text: &str) -> Result<NeckOptions> {
    serde_json::from_str(text)
        .map_err(|e| Error::invalid_argument(format!("not necklace options: {e}")))
}

/// SHA-256 of the options' JSON: rows made with other options are other rows.
pub fn options_hash(options: &NeckOptions) -> Result<String> {
    Ok(sha256_hex(options_json(options)?.as_bytes()))
}

/// necklace's version, as rows record it.
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// The rows of a runs file (none when it does not exist). A last line a kill cut short
/// (not JSON, or no newline at its end) is cut off the file; any other line that is not
/// a row is an error naming it.
pub fn read_rows(path: &Path) -> Result<Vec<Row>> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(io_error(e, path)),
    };
    let mut rows = Vec::new();
    let mut good = 0;
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    for (i, line) in lines.iter().enumerate() {
        let complete = line.ends_with('\n');
        match serde_json::from_str::<Row>(line.trim_end()) {
            Ok(row) if complete => {
                rows.push(row);
                good += line.len();
            }
            _ if line.trim().is_empty() => good += line.len(),
            _ if i + 1 == lines.len() => {
                // Cut short by a kill: drop it, the mesh runs again.
                let file = OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(|e| io_error(e, path))?;
                file.set_len(good as u64).map_err(|e| io_error(e, path))?;
            }
            Err(e) => {
                return Err(Error::new(
                    ErrorKind::Syntax,
                    format!("line {} is not a batch row: {e}", i + 1),
                )
                .in_file(path))
            }
            Ok(_) => unreachable!("a complete line is handled above"),
        }
    }
    Ok(rows)
}

/// Write `rows` to `path` whole, through a temporary file renamed over it (a kill
/// leaves the old file or the new one).
pub fn write_rows(path: &Path, rows: &[Row]) -> Result<()> {
    let tmp = temporary(path);
    let mut text = String::new();
    for row in rows {
        text.push_str(&row_line(row)?);
    }
    std::fs::write(&tmp, text).map_err(|e| io_error(e, &tmp))?;
    std::fs::rename(&tmp, path).map_err(|e| io_error(e, path))
}

/// An operating-system error on `path`.
pub(super) fn io_error(e: std::io::Error, path: &Path) -> Error {
    Error::new(ErrorKind::Io, e.to_string()).in_file(path)
}

fn temporary(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// A row as one line of JSON, with its newline.
pub fn row_line(row: &Row) -> Result<String> {
    serde_json::to_string(row)
        .map(|s| s + "\n")
        .map_err(|e| Error::new(ErrorKind::Internal, format!("cannot encode a row: {e}")))
}

/// A runs file open for appending, a row at a time, each flushed to the disk.
pub struct RowFile {
    file: File,
    path: PathBuf,
}

impl RowFile {
    /// Open (or create) `path` for appending.
    pub fn append(path: &Path) -> Result<RowFile> {
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| io_error(e, path))?;
        Ok(RowFile {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Append one row and flush it.
    pub fn push(&mut self, row: &Row) -> Result<()> {
        let line = row_line(row)?;
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| io_error(e, &self.path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_survive_their_json_and_other_options_hash_apart() {
        let defaults = NeckOptions::default();
        let json = options_json(&defaults).unwrap();
        assert_eq!(options_from_json(&json).unwrap(), defaults);
        let mut other = defaults;
        other.volume.h = Some(0.5);
        assert_eq!(
            options_from_json(&options_json(&other).unwrap()).unwrap(),
            other
        );
        assert_ne!(
            options_hash(&other).unwrap(),
            options_hash(&defaults).unwrap()
        );
        assert!(options_from_json("{\"handles\": 3}").is_err());
    }

    #[test]
    fn a_last_line_cut_short_is_cut_off_and_other_bad_lines_are_errors() {
        let dir = std::env::temp_dir().join(format!("necklace-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("runs.jsonl");
        let key = RowKey {
            path: "a.obj".into(),
            sha256: sha256_hex(b"a"),
            options_hash: "h".into(),
            version: version(),
        };
        let row = Row::new(&key, 1, Status::Ok);
        let line = row_line(&row).unwrap();
        std::fs::write(&path, format!("{line}{line}{{\"path\":\"b.o")).unwrap();
        assert_eq!(read_rows(&path).unwrap(), vec![row.clone(), row.clone()]);
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            format!("{line}{line}")
        );
        // A whole last line without its newline is cut off too: its flush may not
        // have finished.
        std::fs::write(&path, format!("{line}{}", line.trim_end())).unwrap();
        assert_eq!(read_rows(&path).unwrap().len(), 1);
        std::fs::write(&path, format!("not a row\n{line}")).unwrap();
        let err = read_rows(&path).unwrap_err().to_string();
        assert!(err.contains("line 1 is not a batch row"), "{err}");
        assert_eq!(read_rows(&dir.join("none.jsonl")).unwrap(), Vec::new());
        let _ = std::fs::remove_dir_all(dir);
    }
}
