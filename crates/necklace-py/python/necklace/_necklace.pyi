"""Type stubs of the extension module (conversion code; use the package's API)."""

from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str
JSON_VERSION: int

class NecklaceError(ValueError):
    """An input necklace cannot use, or a run that failed (one-line message)."""

def find_necks(
    vertices: npt.NDArray[np.float64],
    faces: npt.NDArray[np.uint32],
    options: Dict[str, Any],
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Tuple[str, List[Dict[str, Any]]]:
    """Run the method on C-contiguous float64 ``(n, 3)`` vertices and uint32 ``(m, 3)``
    faces; returns the report's JSON text and, per side, the critical points (and the
    volume with ``options["volume"]``) as arrays."""

def repair(
    vertices: npt.NDArray[np.float64],
    faces: npt.NDArray[np.uint32],
    options: Dict[str, Any],
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], str]:
    """Remove handles and tunnels; returns the repaired ``(V, F)`` and the report's
    JSON text."""

def load_mesh(path: str) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """``(V, F)`` of an OBJ, OFF, PLY or STL file: float64 ``(n, 3)``, int64 ``(m, 3)``."""

def defaults() -> Dict[str, Any]:
    """The library's default of every option of ``find_necks``."""

def batch_inputs(inputs: List[str]) -> List[str]:
    """The mesh files named by files, folders and ``@LIST`` files, sorted."""

def batch_options(options: Dict[str, Any]) -> Tuple[str, str]:
    """The options as the JSON a worker is given, and its hash."""

def batch_key(path: str, options_hash: str) -> Tuple[str, str, str, str]:
    """A row's key for this file: ``(path, sha256, options_hash, version)``."""

def batch_supervise(
    path: str,
    options_json: str,
    worker: List[str],
    timeout: Optional[float] = None,
    max_memory: Optional[int] = None,
    threads: int = 1,
    save: Optional[str] = None,
) -> Optional[str]:
    """One mesh in a worker process under the limits: its row as a JSON line, or
    ``None`` when the worker was interrupted."""

def batch_work(path: str, options_json: str, save: Optional[str] = None) -> str:
    """One mesh in this process: its row as a JSON line."""

def batch_read_rows(path: str) -> List[str]:
    """The rows of a runs file as JSON lines (a last line cut short is cut off)."""

def batch_write_rows(path: str, rows: List[str]) -> None:
    """Rows written to a runs file whole, in key order, through a rename."""
