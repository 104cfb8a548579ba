//! Writing output files so that a failure never leaves a partial one, and checking
//! that an output place is writable before the work that fills it.
//!
//! [`write_atomic`] writes the bytes to a hidden temporary file beside the target and
//! renames it over the target once every byte is written: a full disk or a killed run
//! leaves the old file (or none), never a truncated one. [`check_output_file`] and
//! [`check_output_folder`] are for callers that compute for minutes before writing: they
//! try the place first (creating a probe file and removing it), so a typo in `-o`
//! costs nothing. Errors are [`ErrorKind::Io`] and name the path.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, ErrorKind, Result};

/// Write `bytes` to `path` through a temporary file in the same folder and a rename.
/// A target that exists and is not a regular file (`/dev/null`, a pipe) is written
/// directly.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let fail =
        |e: std::io::Error| Error::new(ErrorKind::Io, format!("cannot write: {e}")).in_file(path);
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(fail)?;
        return file.write_all(bytes).map_err(fail);
    }
    let temporary = temporary_beside(path);
    let written = std::fs::File::create(&temporary).and_then(|mut file| {
        file.write_all(bytes)?;
        file.flush()
    });
    let renamed = written.and_then(|()| std::fs::rename(&temporary, path));
    if let Err(e) = renamed {
        let _ = std::fs::remove_file(&temporary);
        return Err(fail(e));
    }
    Ok(())
}

/// Check that a file can be written at `path`: its folder exists and takes a new file,
/// and `path` is not a folder.
pub fn check_output_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::new(
            ErrorKind::Io,
            "cannot write: this is a folder; give a file name",
        )
        .in_file(path));
    }
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        // A device or a pipe: nothing to probe.
        return Ok(());
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(Error::new(
            ErrorKind::Io,
            format!(
                "cannot write: the folder {} does not exist",
                folder.display()
            ),
        )
        .in_file(path));
    }
    probe(folder).map_err(|e| e.in_file(path))
}

/// Check that files can be written into `dir`, creating it (and its parents) if
/// missing.
pub fn check_output_folder(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::new(ErrorKind::Io, format!("cannot create the folder: {e}")).in_file(dir)
    })?;
    probe(dir).map_err(|e| e.in_file(dir))
}

/// Create and remove a probe file in `folder`.
fn probe(folder: &Path) -> Result<()> {
    let probe = folder.join(format!(".necklace-probe-{}", std::process::id()));
    std::fs::File::create(&probe)
        .map_err(|e| Error::new(ErrorKind::Io, format!("cannot write here: {e}")))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// A hidden name beside `path`, unique to this process.
fn temporary_beside(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("necklace-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("a.txt");
        write_atomic(&target, b"old").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        write_atomic(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // Into a folder that does not exist: an error, nothing left behind.
        let err = write_atomic(&dir.join("missing/a.txt"), b"x").unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Io);
        assert!(check_output_file(&dir.join("missing/a.txt")).is_err());
        assert!(check_output_file(&dir).is_err());
        assert!(check_output_file(&target).is_ok());
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
