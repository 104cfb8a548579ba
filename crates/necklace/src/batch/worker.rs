//! One mesh of a batch: [`work`] runs it in this process (the worker's body), and
//! [`supervise`] runs it in a worker process under a time and a memory limit, turning
//! whatever ends the process into a [`Row`].

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use super::row::{options_from_json, sha256_hex, version, Row, RowKey, Status};
use crate::error::{printable, ErrorKind};
use crate::pipeline::{find_necks, NeckOptions};

/// A test-only trigger: a worker whose mesh's file name contains this variable's value
/// aborts (as a crash would) before any work. Unset, it does nothing.
pub const CRASH_VARIABLE: &str = "NECKLACE_BATCH_CRASH";

/// A test-only trigger: a worker whose mesh's file name contains this variable's value
/// takes memory, 16 MB every 10 ms, until it is stopped. Unset, it does nothing.
pub const HOG_VARIABLE: &str = "NECKLACE_BATCH_HOG";

/// How often a worker is looked at (exit, time, memory).
const POLL: Duration = Duration::from_millis(20);

/// The command that runs one mesh in a worker process: `program`, then `args`, then the
/// mesh's path, `--options JSON` and, to save the run's folder, `--save-run DIR`. The
/// worker prints the mesh's row as one JSON line on stdout ([`work`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Worker {
    /// The program (the `necklace` binary, or Python).
    pub program: PathBuf,
    /// Its arguments before the mesh's (`batch-worker`, or `-m necklace._worker`).
    pub args: Vec<String>,
}

/// The limits of one mesh's worker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Wall-clock seconds (`None`: no limit).
    pub timeout: Option<f64>,
    /// Resident memory, bytes (`None`: no limit); read from `/proc` (Linux).
    pub max_memory: Option<u64>,
    /// Threads the worker may use (`RAYON_NUM_THREADS`).
    pub threads: usize,
}

/// A mesh file's key fields: its size and content hash (`None` when unreadable, with
/// the reason).
pub fn file_key(path: &Path, options_hash: &str) -> (RowKey, std::result::Result<u64, String>) {
    let (sha256, bytes) = match std::fs::read(path) {
        Ok(data) => (sha256_hex(&data), Ok(data.len() as u64)),
        Err(e) => (String::new(), Err(format!("cannot read the file: {e}"))),
    };
    let key = RowKey {
        path: path.display().to_string(),
        sha256,
        options_hash: options_hash.to_string(),
        version: version(),
    };
    (key, bytes)
}

/// Run the method on one mesh in this process and return its row (`ok`, or `error` /
/// `memory` with the one-line message). With `save`, the run's usual folder
/// (`loops.json`, `loops.ply`, ...) is written there.
pub fn work(path: &Path, options_json: &str, save: Option<&Path>) -> Row {
    let started = Instant::now();
    let options = options_from_json(options_json);
    let hash = super::row::sha256_hex(options_json.as_bytes());
    let (key, bytes) = file_key(path, &hash);
    let mut row = Row::new(&key, *bytes.as_ref().unwrap_or(&0), Status::Ok);
    if triggered(CRASH_VARIABLE, path) {
        std::process::abort();
    }
    if triggered(HOG_VARIABLE, path) {
        let mut taken: Vec<Vec<u8>> = Vec::new();
        loop {
            taken.push(vec![1; 16 << 20]);
            std::thread::sleep(Duration::from_millis(10));
        }
    }
    let outcome = match (options, bytes) {
        (Err(e), _) => Err(e),
        (_, Err(message)) => Err(crate::error::Error::new(ErrorKind::Io, message)),
        (Ok(options), Ok(_)) => run(path, &options, save),
    };
    match outcome {
        Ok(report) => row.fill(&report),
        Err(e) => {
            row.status = if e.kind() == ErrorKind::OverBudget {
                Status::Memory
            } else {
                Status::Error
            };
            row.message = Some(printable(&e.to_string()));
        }
    }
    row.seconds = started.elapsed().as_secs_f64();
    row.peak_memory = peak_memory();
    row
}

/// Whether the test-only trigger `variable` names `path`'s file.
fn triggered(variable: &str, path: &Path) -> bool {
    let file = path.file_name().unwrap_or_default().to_string_lossy();
    std::env::var(variable).is_ok_and(|name| !name.is_empty() && file.contains(&name))
}

fn run(
    path: &Path,
    options: &NeckOptions,
    save: Option<&Path>,
) -> crate::error::Result<crate::pipeline::NeckReport> {
    let surface = crate::io::read_mesh(path)?;
    let report = find_necks(&surface, options).map_err(|e| e.in_file(path))?;
    if let Some(dir) = save {
        let files = crate::output::OutputOptions::default();
        crate::output::write_run(dir, &report.surface, &report, &files, Some(path))?;
    }
    Ok(report)
}

/// This process's peak resident memory in bytes (`VmHWM`; Linux only).
fn peak_memory() -> Option<u64> {
    status_field(Path::new("/proc/self/status"), "VmHWM:")
}

/// A `kB` field of a `/proc/.../status` file, in bytes.
fn status_field(file: &Path, field: &str) -> Option<u64> {
    let text = std::fs::read_to_string(file).ok()?;
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line[field.len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// Run one mesh in a worker process under `limits` and return its row: the worker's
/// own (`ok`, `error`, `memory` refused by the estimate), or `timeout` / `memory` when
/// the limit stopped it, or `crashed` with the signal or exit status and the last line
/// it wrote to stderr. `None` when the worker was interrupted (SIGINT, SIGTERM or
/// SIGHUP: the batch itself is being stopped, and the mesh runs again next time).
pub fn supervise(
    path: &Path,
    options_json: &str,
    limits: &Limits,
    worker: &Worker,
    save: Option<&Path>,
) -> Option<Row> {
    let hash = sha256_hex(options_json.as_bytes());
    let (key, bytes) = file_key(path, &hash);
    let bytes = match bytes {
        Ok(bytes) => bytes,
        Err(message) => {
            let mut row = Row::new(&key, 0, Status::Error);
            row.message = Some(printable(&format!("{}: {message}", path.display())));
            return Some(row);
        }
    };
    let started = Instant::now();
    let mut command = Command::new(&worker.program);
    command
        .args(&worker.args)
        .arg(path)
        .arg("--options")
        .arg(options_json)
        .env("RAYON_NUM_THREADS", limits.threads.max(1).to_string())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(dir) = save {
        command.arg("--save-run").arg(dir);
    }
    let mut child = match command.spawn() {
        Ok(child) => child,
        Err(e) => {
            let mut row = Row::new(&key, bytes, Status::Crashed);
            row.message = Some(printable(&format!(
                "cannot start the worker {}: {e}",
                worker.program.display()
            )));
            return Some(row);
        }
    };
    let stdout = drain(child.stdout.take());
    let stderr = drain(child.stderr.take());
    let (ended, peak) = watch(&mut child, limits, started);
    let out = stdout.join().unwrap_or_default();
    let err = stderr.join().unwrap_or_default();
    let seconds = started.elapsed().as_secs_f64();
    let mut row = match ended {
        Ended::Exited(status) => {
            let parsed = out
                .lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .and_then(|l| serde_json::from_str::<Row>(l).ok());
            match parsed {
                Some(row) => row,
                None => {
                    let signal = signal_of(status);
                    if matches!(signal, Some(1 | 2 | 15)) {
                        return None;
                    }
                    let mut row = Row::new(&key, bytes, Status::Crashed);
                    row.signal = signal;
                    let last = err.lines().rev().find(|l| !l.trim().is_empty());
                    let what = match signal {
                        Some(s) => format!("the worker was killed by signal {s}"),
                        None => format!("the worker exited with {status}"),
                    };
                    row.message = Some(printable(&match last {
                        Some(line) => format!("{what}: {line}"),
                        None => what,
                    }));
                    row
                }
            }
        }
        Ended::Timeout(limit) => {
            let mut row = Row::new(&key, bytes, Status::Timeout);
            row.message = Some(format!("stopped after the time limit of {limit} s"));
            row
        }
        Ended::Memory(resident, limit) => {
            let mut row = Row::new(&key, bytes, Status::Memory);
            row.message = Some(format!(
                "stopped at {resident} bytes resident, over the memory limit of {limit} bytes"
            ));
            row
        }
    };
    // The batch's figures win over the worker's own: the same file, measured the same
    // way for every status.
    row.path = key.path;
    row.bytes = bytes;
    row.sha256 = key.sha256;
    row.options_hash = key.options_hash;
    row.version = key.version;
    row.seconds = seconds;
    row.peak_memory = match (row.peak_memory, peak) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    };
    Some(row)
}

/// How a watched worker ended.
enum Ended {
    Exited(std::process::ExitStatus),
    /// Stopped at the time limit (seconds).
    Timeout(f64),
    /// Stopped over the memory limit: resident bytes, limit.
    Memory(u64, u64),
}

/// Wait for `child`, stopping it at the limits; also the peak resident memory seen.
fn watch(child: &mut Child, limits: &Limits, started: Instant) -> (Ended, Option<u64>) {
    let status_file = PathBuf::from(format!("/proc/{}/status", child.id()));
    let mut peak: Option<u64> = None;
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return (Ended::Exited(status), peak),
            Ok(None) => {}
            Err(_) => {
                let _ = child.kill();
                let status = child.wait().ok();
                if let Some(status) = status {
                    return (Ended::Exited(status), peak);
                }
            }
        }
        if let Some(resident) = status_field(&status_file, "VmRSS:") {
            peak = Some(peak.unwrap_or(0).max(resident));
            if let Some(limit) = limits.max_memory {
                if resident > limit {
                    stop(child);
                    return (Ended::Memory(resident, limit), peak);
                }
            }
        }
        if let Some(limit) = limits.timeout {
            if started.elapsed().as_secs_f64() > limit {
                stop(child);
                return (Ended::Timeout(limit), peak);
            }
        }
        std::thread::sleep(POLL);
    }
}

/// The signal that ended a process, where there are signals.
#[cfg(unix)]
fn signal_of(status: std::process::ExitStatus) -> Option<i32> {
    use std::os::unix::process::ExitStatusExt;
    status.signal()
}

#[cfg(not(unix))]
fn signal_of(_: std::process::ExitStatus) -> Option<i32> {
    None
}

fn stop(child: &mut Child) {
    let _ = child.kill();
    let _ = child.wait();
}

/// Read a pipe to its end on a thread (a worker that fills a pipe nobody reads would
/// block).
fn drain<R: Read + Send + 'static>(pipe: Option<R>) -> std::thread::JoinHandle<String> {
    std::thread::spawn(move || {
        let mut text = String::new();
        if let Some(mut pipe) = pipe {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            text = String::from_utf8_lossy(&bytes).into_owned();
        }
        text
    })
}
