//! Dataset runs: the whole method on many meshes, each in its own worker process, one
//! JSON row per mesh appended to a runs file, resumable.
//!
//! This is not a stage of the method. It sits above [`pipeline`](crate::pipeline) and
//! [`output`](crate::output), which it calls once per mesh, in a worker process (the
//! caller's program re-executed: the `necklace` binary's hidden `batch-worker`, or
//! Python's `necklace._worker`), so that a panic, an abort, running out of memory or
//! time ends that mesh alone. The batch watches each worker, stops it at the time and
//! memory limits (no task scheduler does that: Dask and Ray leave it to the task), and
//! writes what ended it as the row's [`Status`].
//!
//! [`collect_inputs`] turns files, folders (searched recursively) and `@LIST` files into
//! the meshes to run. [`supervise`] spawns the caller's worker command, polls it for its
//! exit, its time and its resident memory (`/proc`), kills it at the limits and turns
//! what ended it into a [`Row`]; [`work`] is the worker's body (read the mesh,
//! `find_necks`, optionally `write_run`) and returns its row. Rows ([`Row`], [`Status`],
//! [`RowKey`], [`RowFile`]): the options travel to the worker and into the key as JSON
//! ([`options_json`], [`options_hash`]; the only place `sha2` is named).
//! [`CRASH_VARIABLE`] and [`HOG_VARIABLE`] are test-only triggers (a crash, a memory
//! hog).
//!
//! Steps of [`run`]:
//! 1. The runs file's rows are read ([`read_rows`]; a line a kill cut short is cut off).
//! 2. Each input's key (path, content hash, options hash, version): those with a row
//!    are skipped; with `retry_failed`, rows whose status is not `ok` are taken out of
//!    the file and their meshes run again.
//! 3. The rest run on `jobs` threads, each supervising one worker at a time
//!    ([`supervise`]); every row is appended and flushed as it comes, so a kill loses
//!    only the meshes that were running.
//! 4. The file is rewritten in path order (through a rename), so that the same inputs
//!    give the same file whatever `jobs` is.
//!
//! Conventions: seconds of wall clock; memory in bytes, resident (Linux `/proc`).
//! Results do not depend on `jobs` or on the threads per job.

mod row;
mod worker;

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

pub use row::{
    options_from_json, options_hash, options_json, read_rows, row_line, sha256_hex, version,
    write_rows, LoopRow, Row, RowFile, RowKey, Status,
};
pub use worker::{file_key, supervise, work, Limits, Worker, CRASH_VARIABLE, HOG_VARIABLE};

use crate::error::{Error, Result};
use crate::io::Format;
use crate::pipeline::NeckOptions;

/// Options of [`run`].
#[derive(Debug, Clone, PartialEq)]
pub struct BatchOptions {
    /// Meshes run at the same time (default: the cores).
    pub jobs: usize,
    /// Threads each worker may use (default: the cores over `jobs`, at least 1).
    pub threads_per_job: Option<usize>,
    /// Wall-clock seconds per mesh (default `None`: no limit).
    pub timeout: Option<f64>,
    /// Resident memory per mesh, bytes (default `None`: no limit besides the method's
    /// own budget, `NeckOptions::volume.max_memory`).
    pub max_memory: Option<u64>,
    /// Run again the meshes whose row is not `ok` (default false: every row counts as
    /// done).
    pub retry_failed: bool,
    /// Write each mesh's usual run folder (`loops.json`, `loops.ply`, ...) under this
    /// folder, named after the file (default none).
    pub save_runs: Option<PathBuf>,
}

impl Default for BatchOptions {
    fn default() -> Self {
        BatchOptions {
            jobs: cores(),
            threads_per_job: None,
            timeout: None,
            max_memory: None,
            retry_failed: false,
            save_runs: None,
        }
    }
}

impl BatchOptions {
    /// Threads per worker: as given, else the cores over the jobs (at least 1), so that
    /// jobs × threads do not exceed the cores.
    pub fn threads(&self) -> usize {
        self.threads_per_job
            .unwrap_or(cores() / self.jobs.max(1))
            .max(1)
    }

    fn check(&self) -> Result<()> {
        if self.jobs == 0 {
            return Err(Error::invalid_argument("--jobs must be at least 1"));
        }
        if let Some(t) = self.timeout {
            if !(t > 0.0 && t.is_finite()) {
                return Err(Error::invalid_argument(format!(
                    "--timeout must be a positive number of seconds, not {t}"
                )));
            }
        }
        Ok(())
    }
}

/// The cores this process may use.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What [`run`] did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BatchSummary {
    /// Meshes among the inputs.
    pub meshes: usize,
    /// Meshes skipped: their row was already in the file.
    pub skipped: usize,
    /// Rows written by this run, by status.
    pub counts: BTreeMap<Status, usize>,
    /// The slowest five meshes of this run: path, seconds, status.
    pub slowest: Vec<(String, f64, Status)>,
    /// Meshes not run because the batch was interrupted.
    pub interrupted: usize,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
}

/// Progress of a batch, for a bar: after each row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BatchProgress {
    /// Meshes this run has to do.
    pub total: usize,
    /// Rows written so far.
    pub done: usize,
    /// Of them, not `ok`.
    pub failed: usize,
}

/// The mesh files named by `inputs`: files as given, folders searched recursively for
/// files we read (`.obj`, `.off`, `.ply`, `.stl`, any case), and `@LIST` files of paths
/// (one per line; blank lines and `#` comments skipped; relative paths from the list's
/// folder). Sorted and without repeats; an input that does not exist is an error.
pub fn collect_inputs(inputs: &[String]) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for input in inputs {
        if let Some(list) = input.strip_prefix('@') {
            let list = Path::new(list);
            let text = std::fs::read_to_string(list).map_err(|e| row::io_error(e, list))?;
            let base = list.parent().unwrap_or(Path::new(""));
            for (i, line) in text.lines().enumerate() {
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                let path = base.join(line);
                if !path.exists() {
                    return Err(Error::invalid_argument(format!(
                        "{}: line {}: {} does not exist",
                        list.display(),
                        i + 1,
                        path.display()
                    )));
                }
                add(&path, &mut found)?;
            }
        } else {
            let path = Path::new(input);
            if !path.exists() {
                return Err(Error::invalid_argument(format!("{input} does not exist")));
            }
            add(path, &mut found)?;
        }
    }
    found.sort();
    found.dedup();
    Ok(found)
}

/// A file, or a folder's mesh files, recursively.
fn add(path: &Path, found: &mut Vec<PathBuf>) -> Result<()> {
    if !path.is_dir() {
        found.push(path.to_path_buf());
        return Ok(());
    }
    let entries = std::fs::read_dir(path).map_err(|e| row::io_error(e, path))?;
    let mut children: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    children.sort();
    for child in children {
        if child.is_dir() {
            add(&child, found)?;
        } else if Format::from_extension(&child).is_some() {
            found.push(child);
        }
    }
    Ok(())
}

/// Run `options` on every mesh of `inputs` (from [`collect_inputs`]), each in a
/// `worker` process, appending one row per mesh to `out` (see the module doc). Calls
/// `on_row` after each row. `stop`, when set (e.g. by Ctrl-C), starts no new mesh.
pub fn run(
    inputs: &[PathBuf],
    options: &NeckOptions,
    batch: &BatchOptions,
    worker: &Worker,
    out: &Path,
    stop: &AtomicBool,
    on_row: &mut dyn FnMut(&Row, BatchProgress),
) -> Result<BatchSummary> {
    batch.check()?;
    let started = Instant::now();
    let json = options_json(options)?;
    let hash = options_hash(options)?;

    // 1–2. What is done, what is to do.
    let mut rows = read_rows(out)?;
    if batch.retry_failed {
        let before = rows.len();
        rows.retain(|r| r.status == Status::Ok);
        if rows.len() < before {
            write_rows(out, &rows)?;
        }
    }
    let done: HashSet<RowKey> = rows.iter().map(Row::key).collect();
    let keys: Vec<RowKey> = {
        use rayon::prelude::*;
        inputs.par_iter().map(|p| file_key(p, &hash).0).collect()
    };
    let todo: Vec<&PathBuf> = inputs
        .iter()
        .zip(&keys)
        .filter(|(_, k)| !done.contains(k))
        .map(|(p, _)| p)
        .collect();
    let names = save_names(inputs);
    let mut summary = BatchSummary {
        meshes: inputs.len(),
        skipped: inputs.len() - todo.len(),
        ..BatchSummary::default()
    };
    if let Some(dir) = &batch.save_runs {
        std::fs::create_dir_all(dir).map_err(|e| row::io_error(e, dir))?;
    }

    // 3. The meshes, `jobs` at a time; rows appended as they come.
    let limits = Limits {
        timeout: batch.timeout,
        max_memory: batch.max_memory,
        threads: batch.threads(),
    };
    let mut file = RowFile::append(out)?;
    let mut progress = BatchProgress {
        total: todo.len(),
        ..BatchProgress::default()
    };
    let mut ran: Vec<Row> = Vec::new();
    let next = AtomicUsize::new(0);
    let (send, receive) = mpsc::channel::<Option<Row>>();
    let mut failure: Option<Error> = None;
    std::thread::scope(|scope| {
        for _ in 0..batch.jobs.min(todo.len()) {
            let send = send.clone();
            let (todo, next, names, json) = (&todo, &next, &names, &json);
            let (limits, worker) = (&limits, worker);
            scope.spawn(move || loop {
                if stop.load(Ordering::SeqCst) {
                    break;
                }
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(path) = todo.get(i) else { break };
                let save = batch.save_runs.as_ref().map(|d| d.join(&names[*path]));
                let row = supervise(path, json, limits, worker, save.as_deref());
                if send.send(row).is_err() {
                    break;
                }
            });
        }
        drop(send);
        for row in receive {
            let Some(row) = row else {
                // Interrupted: the batch is being stopped.
                stop.store(true, Ordering::SeqCst);
                continue;
            };
            if failure.is_none() {
                if let Err(e) = file.push(&row) {
                    failure = Some(e);
                    stop.store(true, Ordering::SeqCst);
                }
            }
            progress.done += 1;
            progress.failed += usize::from(row.status != Status::Ok);
            on_row(&row, progress);
            ran.push(row);
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    summary.interrupted = todo.len() - ran.len();

    // 4. The file in path order.
    let mut all = read_rows(out)?;
    all.sort_by_key(Row::key);
    write_rows(out, &all)?;

    for r in &ran {
        *summary.counts.entry(r.status).or_default() += 1;
    }
    ran.sort_by(|a, b| b.seconds.total_cmp(&a.seconds).then(a.path.cmp(&b.path)));
    summary.slowest = ran
        .iter()
        .take(5)
        .map(|r| (r.path.clone(), r.seconds, r.status))
        .collect();
    summary.seconds = started.elapsed().as_secs_f64();
    Ok(summary)
}

/// The folder name of each input's saved run: its file name, with its parent folders'
/// names before it (`a/b/mesh.stl` → `a-b-mesh.stl`) as far as needed to tell the
/// inputs apart.
fn save_names(inputs: &[PathBuf]) -> BTreeMap<PathBuf, String> {
    let parts = |p: &Path| -> Vec<String> {
        p.components()
            .filter_map(|c| match c {
                std::path::Component::Normal(s) => Some(s.to_string_lossy().into_owned()),
                _ => None,
            })
            .collect()
    };
    let mut depth = 1;
    loop {
        let names: Vec<String> = inputs
            .iter()
            .map(|p| {
                let parts = parts(p);
                parts[parts.len().saturating_sub(depth)..].join("-")
            })
            .collect();
        let unique: HashSet<&String> = names.iter().collect();
        let deepest = inputs.iter().map(|p| parts(p).len()).max().unwrap_or(1);
        if unique.len() == names.len() || depth >= deepest {
            return inputs.iter().cloned().zip(names).collect();
        }
        depth += 1;
    }
}
