"""Dataset runs from Python: :func:`batch` over a local process pool or a Dask cluster.

Each mesh runs in its own worker process (``python -m necklace._worker``), started and
watched by the library's ``necklace::batch::supervise`` with the time and memory limits:
the same supervision as ``necklace batch``, so a stuck mesh never stalls a Dask worker.
Rows are the CLI's (``docs/output.md``, "necklace batch").
"""

from __future__ import annotations

import inspect
import json
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from typing import Any, Dict, Iterable, List, Optional, Tuple

from . import _necklace

#: The command that runs one mesh: this Python, then the mesh's arguments.
WORKER = [sys.executable, "-m", "necklace._worker"]

#: Row fields, in the JSONL's order (the DataFrame's columns).
COLUMNS = [
    "path", "bytes", "sha256", "options_hash", "version", "status", "message", "signal",
    "components", "genus", "handles", "tunnels", "loops", "drops", "warnings", "timings",
    "seconds", "peak_memory",
]

#: Columns kept in Parquet as JSON text (maps whose keys differ from row to row).
_JSON_COLUMNS = ["drops", "timings"]

#: Parquet is rewritten whole: at most this often while rows come in, and at the end.
_PARQUET_EVERY = 5.0


def run_one(
    path: str,
    save: Optional[str] = None,
    *,
    options_json: str,
    timeout: Optional[float] = None,
    max_memory: Optional[int] = None,
    threads: int = 1,
) -> Optional[str]:
    """One mesh in a worker process under the limits: its row as a JSON line (``None``
    when the worker was interrupted). What a Dask task runs."""
    return _necklace.batch_supervise(
        path, options_json, WORKER, timeout, max_memory, threads, save
    )


def _option_names() -> List[str]:
    from . import find_necks

    return [p for p in inspect.signature(find_necks).parameters if p not in ("vertices", "faces", "progress")]


def _pandas():
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "necklace.batch returns a pandas.DataFrame: pip install 'necklace[dask]' "
            "(pandas, pyarrow and dask[distributed])"
        ) from e
    return pandas


def _read_rows(out: str) -> List[Dict[str, Any]]:
    """The rows already in ``out`` (JSONL or Parquet); none when it does not exist."""
    if not os.path.exists(out):
        return []
    if out.endswith(".parquet"):
        frame = _pandas().read_parquet(out)
        rows = []
        for record in frame.to_dict("records"):
            rows.append(_from_parquet(record))
        return rows
    return [json.loads(line) for line in _necklace.batch_read_rows(out)]


def _plain(value: Any) -> Any:
    """numpy arrays and scalars from Parquet as lists and Python numbers."""
    if hasattr(value, "tolist"):
        return _plain(value.tolist())
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _from_parquet(record: Dict[str, Any]) -> Dict[str, Any]:
    row = {}
    for key, value in record.items():
        value = _plain(value)
        if isinstance(value, float) and value != value:  # NaN: absent
            value = None
        if key in _JSON_COLUMNS and isinstance(value, str):
            value = json.loads(value)
        row[key] = value
    return row


def _write_parquet(out: str, rows: List[Dict[str, Any]]) -> None:
    frame = _frame(rows)
    for column in _JSON_COLUMNS:
        frame[column] = [json.dumps(v, sort_keys=True) for v in frame[column]]
    tmp = out + ".tmp"
    frame.to_parquet(tmp, index=False)
    os.replace(tmp, out)


def _frame(rows: List[Dict[str, Any]]):
    pandas = _pandas()
    ordered = sorted(rows, key=lambda r: (r["path"], r["sha256"], r["options_hash"], r["version"]))
    full = [{c: r.get(c) for c in COLUMNS} for r in ordered]
    return pandas.DataFrame(full, columns=COLUMNS)


def _key(row: Dict[str, Any]) -> Tuple[str, str, str, str]:
    return (row["path"], row["sha256"], row["options_hash"], row["version"])


def batch(
    paths: Iterable["str | os.PathLike[str]"],
    *,
    out: Optional["str | os.PathLike[str]"] = None,
    client: Any = None,
    timeout: Optional[float] = None,
    max_memory: Optional[int] = None,
    jobs: Optional[int] = None,
    retry_failed: bool = False,
    save_runs: Optional["str | os.PathLike[str]"] = None,
    **options: Any,
):
    """Find the neck loops of many meshes, each in its own worker process.

    Args:
        paths: mesh files, folders (searched recursively for .obj, .off, .ply, .stl)
            and ``@LIST`` files of paths.
        out: the runs file, ``.jsonl`` (rows appended as they come, as ``necklace
            batch`` writes it) or ``.parquet`` (rewritten whole every few seconds and at
            the end). An existing file is resumed: meshes whose row is there are not
            run again.
        client: a ``dask.distributed.Client``: one task per mesh (``client.map``,
            ``pure=False``), gathered as they complete. Without it, a local pool of
            ``jobs`` processes.
        timeout: seconds a mesh may take; its worker is then stopped (``timeout``).
        max_memory: bytes of resident memory a mesh may take (``memory``); also the
            method's budget, as ``--max-memory`` is for the CLI.
        jobs: local pool size (default: the cores); each worker then gets the cores
            over the jobs as threads (one on a Dask cluster).
        retry_failed: run again the meshes whose row is not ``ok``.
        save_runs: write each mesh's run folder (``loops.json``, ...) under this
            folder, named after the file.
        **options: the method's options, as :func:`necklace.find_necks` takes them.

    Returns:
        A ``pandas.DataFrame``, one row per mesh (the runs file's rows when ``out`` is
        given, else this call's), in path order; ``loops`` is a list column.
    """
    _pandas()
    known = _option_names()
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise TypeError(f"batch() got unknown options {unknown}; the method's are {known}")
    if max_memory is not None:
        options = dict(options, max_memory=int(max_memory))
    files = _necklace.batch_inputs([os.fspath(p) for p in paths])
    options_json, options_hash = _necklace.batch_options(options)
    out = os.fspath(out) if out is not None else None
    save_root = os.fspath(save_runs) if save_runs is not None else None
    cores = os.cpu_count() or 1
    jobs = max(1, int(jobs or cores))
    threads = 1 if client is not None else max(1, cores // jobs)

    # What is done already.
    rows = _read_rows(out) if out else []
    if retry_failed and any(r["status"] != "ok" for r in rows):
        rows = [r for r in rows if r["status"] == "ok"]
        _rewrite(out, rows)
    done = {_key(r) for r in rows}
    todo = [f for f in files if _necklace.batch_key(f, options_hash) not in done]

    names = _save_names(files)
    def save_of(path: str) -> Optional[str]:
        return os.path.join(save_root, names[path]) if save_root else None
    if save_root:
        os.makedirs(save_root, exist_ok=True)

    new_rows: List[Dict[str, Any]] = []
    last_write = time.monotonic()

    def take(line: Optional[str]) -> None:
        nonlocal last_write
        if line is None:
            return
        row = json.loads(line)
        new_rows.append(row)
        rows.append(row)
        if out is None:
            return
        if out.endswith(".parquet"):
            if time.monotonic() - last_write > _PARQUET_EVERY:
                _write_parquet(out, rows)
                last_write = time.monotonic()
        else:
            with open(out, "a", encoding="utf-8") as f:
                f.write(line)
                f.flush()

    limits = dict(options_json=options_json, timeout=timeout, max_memory=max_memory, threads=threads)
    saves = [save_of(p) for p in todo]
    if client is not None:
        from dask.distributed import as_completed as dask_completed

        futures = client.map(run_one, todo, saves, pure=False, **limits)
        for future in dask_completed(futures):
            take(future.result())
    else:
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [pool.submit(run_one, p, save, **limits) for p, save in zip(todo, saves)]
            for future in as_completed(futures):
                take(future.result())

    if out is not None:
        _rewrite(out, rows)
    wanted = {_necklace.batch_key(f, options_hash) for f in files}
    return _frame([r for r in rows if _key(r) in wanted])


def _rewrite(out: Optional[str], rows: List[Dict[str, Any]]) -> None:
    """The runs file whole, in path order (through a rename)."""
    if out is None:
        return
    if out.endswith(".parquet"):
        _write_parquet(out, rows)
        return
    _necklace.batch_write_rows(out, [json.dumps(r) for r in rows])


def _save_names(files: List[str]) -> Dict[str, str]:
    """Each file's run folder name: its file name, with as many parent folders before it
    as needed to tell the files apart (as ``necklace batch`` names them)."""
    parts = {f: [p for p in os.path.normpath(f).split(os.sep) if p not in ("", ".", "..")] for f in files}
    deepest = max((len(p) for p in parts.values()), default=1)
    depth = 1
    while True:
        names = {f: "-".join(p[-depth:]) for f, p in parts.items()}
        if len(set(names.values())) == len(names) or depth >= deepest:
            return names
        depth += 1
