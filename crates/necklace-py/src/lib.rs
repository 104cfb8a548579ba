//! `necklace._necklace`: the Python extension module, conversion code only.
//!
//! numpy arrays in, the library's [`necklace::pipeline::find_necks_with_progress`] run
//! with the GIL released, and out: the report as its JSON text (what `loops.json`
//! holds, parsed by the Python package into its result classes), plus what the JSON
//! leaves out as numpy arrays (each side's critical points, and with `volume=True`
//! its tet mesh and smoothed field). Errors are `NecklaceError` (a `ValueError`) with
//! the library's one-line message; a panic becomes a `NecklaceError` too, never a crash.
//! The user-facing API, its documentation and its checks of array shapes and dtypes
//! live in `python/necklace/__init__.py`; this module trusts them and checks only what
//! it must to stay safe.
//!
//! Units: the input's; positions in its frame. Entry points: `find_necks`, `load_mesh`.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use necklace::loops::LoopOptions;
use necklace::morse::{MorseOptions, Preconditioner, Schedule, SolverOptions};
use necklace::pipeline::{
    InputOptions, NeckOptions, NeckReport, RepairOptions, RepairTarget, TrackedPoint,
};
use necklace::progress::Progress;
use necklace::simplify::SimplifyOptions;
use necklace::volume::VolumeOptions;
use necklace::{Side, SurfaceMesh};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

create_exception!(
    _necklace,
    NecklaceError,
    PyValueError,
    "An input necklace cannot use, or a run that failed: the message says why, in one line."
);

/// A library error as a `NecklaceError` with its one-line message.
fn error(e: impl std::fmt::Display) -> PyErr {
    NecklaceError::new_err(e.to_string())
}

/// Run `work`, turning a panic into a `NecklaceError` (the interpreter keeps running).
fn guarded<T>(work: impl FnOnce() -> necklace::Result<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(work)) {
        Ok(result) => result.map_err(error),
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("unknown");
            Err(NecklaceError::new_err(format!(
                "internal error (please report it): {what}"
            )))
        }
    }
}

/// The value of option `key` in `options`, or `default`; a wrong type is a
/// `NecklaceError` naming the option.
fn option<'py, T: FromPyObjectOwned<'py>>(
    options: &Bound<'py, PyDict>,
    key: &str,
    default: T,
) -> PyResult<T> {
    match options.get_item(key)? {
        None => Ok(default),
        Some(value) if value.is_none() => Ok(default),
        Some(value) => value.extract::<T>().map_err(|e| {
            let e: PyErr = e.into();
            NecklaceError::new_err(format!(
                "option {key} = {}: {}",
                value.repr().map(|r| r.to_string()).unwrap_or_default(),
                e.value(options.py())
            ))
        }),
    }
}

/// A keyword argument naming one of `choices` (the first is the default).
fn choice<T: Copy>(options: &Bound<'_, PyDict>, key: &str, choices: &[(&str, T)]) -> PyResult<T> {
    let name = option::<String>(options, key, choices[0].0.into())?;
    match choices.iter().find(|(n, _)| *n == name) {
        Some(&(_, value)) => Ok(value),
        None => {
            let names: Vec<String> = choices.iter().map(|(n, _)| format!("'{n}'")).collect();
            Err(NecklaceError::new_err(format!(
                "option {key} = '{name}': expected {}",
                names.join(" or ")
            )))
        }
    }
}

/// The library's options from the keyword arguments (names as the CLI's flags).
fn neck_options(options: &Bound<'_, PyDict>) -> PyResult<NeckOptions> {
    let loops = LoopOptions::default();
    let morse = MorseOptions::default();
    let volume = VolumeOptions::default();
    let schedule = choice(
        options,
        "schedule",
        &[("scales", Schedule::ScaleSpace), ("paper", Schedule::Paper)],
    )?;
    let preconditioner = choice(
        options,
        "solver",
        &[
            ("auto", Preconditioner::Auto),
            ("jacobi", Preconditioner::Jacobi),
            ("multigrid", Preconditioner::Multigrid),
        ],
    )?;
    let h = match options.get_item("h")? {
        Some(value) if !value.is_none() => Some(option::<f64>(options, "h", 0.0)?),
        _ => None,
    };
    let simplify = SimplifyOptions::default();
    Ok(NeckOptions {
        handles: option(options, "handles", true)?,
        simplify: SimplifyOptions {
            above: option(options, "simplify_above", simplify.above)?,
            target: option(options, "simplify_to", simplify.target)?,
            ..simplify
        },
        tunnels: option(options, "tunnels", true)?,
        volume: VolumeOptions {
            h,
            max_memory: option(options, "max_memory", volume.max_memory)?,
            unchecked_min_cell: option(options, "unchecked_min_cell", volume.unchecked_min_cell)?,
            ..volume
        },
        morse: MorseOptions {
            schedule,
            levels: option(options, "levels", morse.levels)?,
            min_bulge: option(options, "min_bulge", morse.min_bulge)?,
            min_levels: option(options, "min_levels", morse.min_levels)?,
            steps: option(options, "steps", morse.steps)?,
            tau: option(options, "tau", morse.tau)?,
            max_steps: option(options, "max_steps", morse.max_steps)?,
            solver: SolverOptions {
                preconditioner,
                ..morse.solver
            },
            ..morse
        },
        loops: LoopOptions {
            plane_offsets: option(options, "plane_offsets", loops.plane_offsets)?,
            slide_steps: option(options, "slide_steps", loops.slide_steps)?,
            min_opening: option(options, "min_opening", loops.min_opening)?,
            max_flatness: option(options, "max_flatness", loops.max_flatness)?,
            ..loops
        },
        keep_volume: option(options, "volume", false)?,
        input: InputOptions {
            weld: (!option(options, "no_weld", false)?).then_some(option(
                options,
                "weld",
                necklace::pipeline::DEFAULT_WELD,
            )?),
        },
        sides_at_once: !option(
            options,
            "one_side_at_a_time",
            !NeckOptions::default().sides_at_once,
        )?,
        budget_steps: option(options, "budget_steps", NeckOptions::default().budget_steps)?,
        at_once_max_tets: NeckOptions::default().at_once_max_tets,
    })
}

/// Progress reports to a Python callable `progress(stage, done, total)`: at each
/// stage's start and end, and in between at most every 0.2 s. The first exception it
/// raises stops further calls and is raised when the run ends.
struct PyProgress {
    callback: Py<PyAny>,
    state: Mutex<ProgressState>,
}

struct ProgressState {
    /// Per lane (the two sides run at the same time): its stage, done, total.
    lanes: BTreeMap<usize, (String, u64, u64)>,
    last_call: Instant,
    error: Option<PyErr>,
}

impl PyProgress {
    /// Call back with `lane`'s stage.
    fn call(&self, state: &mut ProgressState, lane: usize) {
        if state.error.is_some() {
            return;
        }
        let Some((stage, done, total)) = state.lanes.get(&lane).cloned() else {
            return;
        };
        state.last_call = Instant::now();
        let result = Python::attach(|py| {
            self.callback
                .call1(py, (stage.as_str(), done, total))
                .map(drop)
        });
        if let Err(e) = result {
            state.error = Some(e);
        }
    }
}

impl Progress for PyProgress {
    fn start_lane(&self, lane: usize, stage: &str, total: u64) {
        if let Ok(mut state) = self.state.lock() {
            state.lanes.insert(lane, (stage.to_string(), 0, total));
            self.call(&mut state, lane);
        }
    }

    fn advance_lane(&self, lane: usize, units: u64) {
        if let Ok(mut state) = self.state.lock() {
            if let Some(entry) = state.lanes.get_mut(&lane) {
                entry.1 += units;
            }
            if state.last_call.elapsed() >= Duration::from_millis(200) {
                self.call(&mut state, lane);
            }
        }
    }

    fn finish_lane(&self, lane: usize) {
        if let Ok(mut state) = self.state.lock() {
            if let Some(entry) = state.lanes.get_mut(&lane) {
                entry.1 = entry.1.max(entry.2);
            }
            self.call(&mut state, lane);
        }
    }
}

/// A flat `Vec` as a numpy array of shape `(len / columns, columns)`.
fn matrix<'py, T: numpy::Element>(
    py: Python<'py>,
    values: Vec<T>,
    columns: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let rows = values.len() / columns;
    Ok(PyArray1::from_vec(py, values)
        .reshape([rows, columns])?
        .into_any())
}

/// The serde name of a value (`"saddle2"`, `"surface"`, ...).
fn name<T: serde::Serialize>(value: T) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(s)) => s,
        _ => String::new(),
    }
}

/// One side's critical points as arrays: `position (n, 3)`, `type` (a list of names as
/// the JSON spells them: `minimum`, `saddle1`, `saddle2`, `maximum`, ...),
/// `selected (n,)`, `persistence (n,)`.
fn critical_arrays<'py>(py: Python<'py>, points: &[TrackedPoint]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let positions: Vec<f64> = points.iter().flat_map(|p| p.position).collect();
    out.set_item("position", matrix(py, positions, 3)?)?;
    let types: Vec<String> = points.iter().map(|p| name(p.kind)).collect();
    out.set_item("type", types)?;
    let selected: Vec<bool> = points.iter().map(|p| p.selected).collect();
    out.set_item("selected", PyArray1::from_vec(py, selected))?;
    let persistence: Vec<u64> = points.iter().map(|p| p.persistence as u64).collect();
    out.set_item("persistence", PyArray1::from_vec(py, persistence))?;
    Ok(out)
}

/// What the JSON leaves out, per side: `side`, `critical` (see [`critical_arrays`]) and,
/// when the volume was kept, `volume`: `points (n, 3)`, `tets (t, 4)`, `field (n,)`,
/// `kind` (a list of names: `interior`, `surface`, `outer`).
fn side_arrays<'py>(py: Python<'py>, report: &NeckReport) -> PyResult<Bound<'py, PyList>> {
    let sides = PyList::empty(py);
    for side in &report.sides {
        let entry = PyDict::new(py);
        entry.set_item("side", side.side.name())?;
        entry.set_item("critical", critical_arrays(py, &side.critical)?)?;
        if let Some(field) = &side.field {
            let volume = PyDict::new(py);
            let points: Vec<f64> = field.mesh.positions.iter().flatten().copied().collect();
            volume.set_item("points", matrix(py, points, 3)?)?;
            let tets: Vec<i64> = field
                .mesh
                .tets
                .iter()
                .flatten()
                .map(|&v| v as i64)
                .collect();
            volume.set_item("tets", matrix(py, tets, 4)?)?;
            volume.set_item("field", PyArray1::from_vec(py, field.values.clone()))?;
            let kinds: Vec<String> = field.mesh.kinds.iter().map(|&k| name(k)).collect();
            volume.set_item("kind", kinds)?;
            entry.set_item("volume", volume)?;
        }
        sides.append(entry)?;
    }
    Ok(sides)
}

/// The surface of `vertices (n, 3)` and `faces (m, 3)`.
fn surface_of(
    vertices: &PyReadonlyArray2<'_, f64>,
    faces: &PyReadonlyArray2<'_, u32>,
) -> PyResult<SurfaceMesh> {
    let (vertices, faces) = (vertices.as_array(), faces.as_array());
    if vertices.ncols() != 3 || faces.ncols() != 3 {
        return Err(NecklaceError::new_err(
            "vertices and faces must have 3 columns",
        ));
    }
    Ok(SurfaceMesh {
        positions: vertices
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect(),
        triangles: faces
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect(),
    })
}

/// Run `work` with the GIL released, its progress going to `progress` (a Python
/// callable) or nowhere; an exception the callable raised is raised after it.
fn with_progress<T: Send>(
    py: Python<'_>,
    progress: Option<Py<PyAny>>,
    work: impl FnOnce(&dyn Progress) -> necklace::Result<T> + Send,
) -> PyResult<T> {
    let reporter = progress.map(|callback| PyProgress {
        callback,
        state: Mutex::new(ProgressState {
            lanes: BTreeMap::new(),
            last_call: Instant::now(),
            error: None,
        }),
    });
    let result = py.detach(|| {
        guarded(|| {
            let silent = necklace::progress::Silent;
            let progress: &dyn Progress = match &reporter {
                Some(p) => p,
                None => &silent,
            };
            work(progress)
        })
    });
    if let Some(error) = reporter
        .and_then(|r| r.state.into_inner().ok())
        .and_then(|s| s.error)
    {
        return Err(error);
    }
    result
}

/// `find_necks(vertices, faces, options, progress)`: `vertices` float64 `(n, 3)`, `faces`
/// uint32 `(m, 3)` (both C-contiguous; the Python wrapper converts), `options` a dict of
/// the CLI's option names. Returns `(report_json, sides)`.
#[pyfunction]
#[pyo3(signature = (vertices, faces, options, progress=None))]
fn find_necks<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, u32>,
    options: &Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, Bound<'py, PyList>)> {
    let options = neck_options(options)?;
    let surface = surface_of(&vertices, &faces)?;
    let report = with_progress(py, progress, |progress| {
        necklace::pipeline::find_necks_with_progress(&surface, &options, progress)
    })?;
    let json = guarded(|| {
        let value = necklace::output::report_json(&report, None)?;
        serde_json::to_string(&value).map_err(|e| {
            necklace::Error::new(
                necklace::ErrorKind::Internal,
                format!("cannot encode the report: {e}"),
            )
        })
    })?;
    Ok((json, side_arrays(py, &report)?))
}

/// `repair(vertices, faces, options, progress)`: `options` holds `find_necks`'s keys
/// and `genus`, `max_length`, `only` (`"handles"` / `"tunnels"`), `band`. Returns the
/// repaired `(V float64 (n, 3), F int64 (m, 3), report_json)`.
#[pyfunction]
#[pyo3(signature = (vertices, faces, options, progress=None))]
fn repair<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, u32>,
    options: &Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, String)> {
    let defaults = RepairOptions::default();
    let genus = option::<Option<usize>>(options, "genus", None)?;
    let max_length = option::<Option<f64>>(options, "max_length", None)?;
    if genus.is_some() && max_length.is_some() {
        return Err(NecklaceError::new_err(
            "genus and max_length exclude each other: give one",
        ));
    }
    let only = match option::<Option<String>>(options, "only", None)?.as_deref() {
        None => None,
        Some("handles") => Some(Side::Inside),
        Some("tunnels") => Some(Side::Outside),
        Some(other) => {
            return Err(NecklaceError::new_err(format!(
                "option only = '{other}': expected 'handles' or 'tunnels'"
            )))
        }
    };
    let options = RepairOptions {
        target: match max_length {
            Some(l) => RepairTarget::MaxLength(l),
            None => RepairTarget::Genus(genus.unwrap_or(0)),
        },
        only,
        band: option(options, "band", defaults.band)?,
        necks: neck_options(options)?,
        ..defaults
    };
    let surface = surface_of(&vertices, &faces)?;
    let (repaired, report) = with_progress(py, progress, |progress| {
        necklace::pipeline::repair_with_progress(&surface, &options, progress)
    })?;
    let json = serde_json::to_string(&report).map_err(error)?;
    let positions: Vec<f64> = repaired.positions.iter().flatten().copied().collect();
    let faces: Vec<i64> = repaired
        .triangles
        .iter()
        .flatten()
        .map(|&v| i64::from(v))
        .collect();
    Ok((matrix(py, positions, 3)?, matrix(py, faces, 3)?, json))
}

/// `load_mesh(path)`: the vertices `(n, 3)` float64 and faces `(m, 3)` int64 of an OBJ,
/// OFF, PLY or STL file (STL's corners merged).
#[pyfunction]
fn load_mesh(py: Python<'_>, path: PathBuf) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>)> {
    let mesh = py.detach(|| guarded(|| necklace::io::read_mesh(&path)))?;
    let positions: Vec<f64> = mesh.positions.iter().flatten().copied().collect();
    let faces: Vec<i64> = mesh
        .triangles
        .iter()
        .flatten()
        .map(|&v| i64::from(v))
        .collect();
    Ok((matrix(py, positions, 3)?, matrix(py, faces, 3)?))
}

/// `defaults()`: the library's default of every option `find_necks` takes (the Python
/// signature's defaults are checked against these in the tests).
#[pyfunction]
fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let options = NeckOptions::default();
    let out = PyDict::new(py);
    out.set_item("handles", options.handles)?;
    out.set_item("tunnels", options.tunnels)?;
    out.set_item(
        "schedule",
        match options.morse.schedule {
            Schedule::ScaleSpace => "scales",
            Schedule::Paper => "paper",
        },
    )?;
    out.set_item("levels", options.morse.levels)?;
    out.set_item("min_bulge", options.morse.min_bulge)?;
    out.set_item("min_levels", options.morse.min_levels)?;
    out.set_item("steps", options.morse.steps)?;
    out.set_item("tau", options.morse.tau)?;
    out.set_item("h", options.volume.h)?;
    out.set_item("max_memory", options.volume.max_memory)?;
    out.set_item("unchecked_min_cell", options.volume.unchecked_min_cell)?;
    out.set_item("max_steps", options.morse.max_steps)?;
    out.set_item(
        "solver",
        match options.morse.solver.preconditioner {
            Preconditioner::Multigrid => "multigrid",
            Preconditioner::Jacobi => "jacobi",
            Preconditioner::Auto => "auto",
        },
    )?;
    out.set_item("plane_offsets", options.loops.plane_offsets)?;
    out.set_item("slide_steps", options.loops.slide_steps)?;
    out.set_item("min_opening", options.loops.min_opening)?;
    out.set_item("max_flatness", options.loops.max_flatness)?;
    out.set_item("volume", options.keep_volume)?;
    out.set_item("one_side_at_a_time", !options.sides_at_once)?;
    out.set_item("budget_steps", options.budget_steps)?;
    out.set_item("simplify_above", options.simplify.above)?;
    out.set_item("simplify_to", options.simplify.target)?;
    out.set_item("weld", options.input.weld.unwrap_or(0.0))?;
    out.set_item("no_weld", options.input.weld.is_none())?;
    Ok(out)
}

/// `batch_inputs(inputs)`: the mesh files named by files, folders and `@LIST`s
/// (`necklace::batch::collect_inputs`), sorted.
#[pyfunction]
fn batch_inputs(inputs: Vec<String>) -> PyResult<Vec<String>> {
    let files = guarded(|| necklace::batch::collect_inputs(&inputs))?;
    Ok(files.iter().map(|p| p.display().to_string()).collect())
}

/// `batch_options(options)`: the options (a dict of the CLI's option names) as the JSON a
/// worker is given, and its hash (a row's `options_hash`).
#[pyfunction]
fn batch_options(options: &Bound<'_, PyDict>) -> PyResult<(String, String)> {
    let options = neck_options(options)?;
    guarded(|| {
        Ok((
            necklace::batch::options_json(&options)?,
            necklace::batch::options_hash(&options)?,
        ))
    })
}

/// `batch_key(path, options_hash)`: a row's key for this file: `(path, sha256,
/// options_hash, version)` (`sha256` empty when the file cannot be read).
#[pyfunction]
fn batch_key(path: PathBuf, options_hash: &str) -> (String, String, String, String) {
    let (key, _) = necklace::batch::file_key(&path, options_hash);
    (key.path, key.sha256, key.options_hash, key.version)
}

/// `batch_supervise(path, options_json, worker, timeout, max_memory, threads, save)`: one
/// mesh in a worker process (`worker`: the command before the mesh's arguments) under the
/// limits; its row as a JSON line, or `None` when the worker was interrupted. The GIL is
/// released while it runs.
#[pyfunction]
#[pyo3(signature = (path, options_json, worker, timeout=None, max_memory=None, threads=1, save=None))]
#[allow(clippy::too_many_arguments)]
fn batch_supervise(
    py: Python<'_>,
    path: PathBuf,
    options_json: String,
    worker: Vec<String>,
    timeout: Option<f64>,
    max_memory: Option<u64>,
    threads: usize,
    save: Option<PathBuf>,
) -> PyResult<Option<String>> {
    let Some((program, args)) = worker.split_first() else {
        return Err(NecklaceError::new_err("the worker command is empty"));
    };
    let worker = necklace::batch::Worker {
        program: PathBuf::from(program),
        args: args.to_vec(),
    };
    let limits = necklace::batch::Limits {
        timeout,
        max_memory,
        threads,
    };
    let row = py.detach(|| {
        necklace::batch::supervise(&path, &options_json, &limits, &worker, save.as_deref())
    });
    row.map(|r| guarded(|| necklace::batch::row_line(&r)))
        .transpose()
}

/// `batch_work(path, options_json, save=None)`: the worker's body, one mesh in this
/// process; its row as a JSON line.
#[pyfunction]
#[pyo3(signature = (path, options_json, save=None))]
fn batch_work(
    py: Python<'_>,
    path: PathBuf,
    options_json: String,
    save: Option<PathBuf>,
) -> PyResult<String> {
    let row = py.detach(|| necklace::batch::work(&path, &options_json, save.as_deref()));
    guarded(|| necklace::batch::row_line(&row))
}

/// `batch_read_rows(path)`: the rows of a runs file as JSON lines (a last line cut short
/// is cut off the file).
#[pyfunction]
fn batch_read_rows(path: PathBuf) -> PyResult<Vec<String>> {
    let rows = guarded(|| necklace::batch::read_rows(&path))?;
    rows.iter()
        .map(|r| guarded(|| necklace::batch::row_line(r)))
        .collect()
}

/// `batch_write_rows(path, rows)`: rows (JSON text each) written to a runs file whole, in
/// key order, through a rename.
#[pyfunction]
fn batch_write_rows(path: PathBuf, rows: Vec<String>) -> PyResult<()> {
    let mut parsed: Vec<necklace::batch::Row> = rows
        .iter()
        .map(|r| {
            serde_json::from_str(r)
                .map_err(|e| NecklaceError::new_err(format!("not a batch row: {e}")))
        })
        .collect::<PyResult<_>>()?;
    parsed.sort_by_key(necklace::batch::Row::key);
    guarded(|| necklace::batch::write_rows(&path, &parsed))
}

#[pymodule]
fn _necklace(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("NecklaceError", m.py().get_type::<NecklaceError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("JSON_VERSION", necklace::output::JSON_VERSION)?;
    m.add_function(wrap_pyfunction!(find_necks, m)?)?;
    m.add_function(wrap_pyfunction!(load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(repair, m)?)?;
    m.add_function(wrap_pyfunction!(defaults, m)?)?;
    m.add_function(wrap_pyfunction!(batch_inputs, m)?)?;
    m.add_function(wrap_pyfunction!(batch_options, m)?)?;
    m.add_function(wrap_pyfunction!(batch_key, m)?)?;
    m.add_function(wrap_pyfunction!(batch_supervise, m)?)?;
    m.add_function(wrap_pyfunction!(batch_work, m)?)?;
    m.add_function(wrap_pyfunction!(batch_read_rows, m)?)?;
    m.add_function(wrap_pyfunction!(batch_write_rows, m)?)?;
    Ok(())
}
