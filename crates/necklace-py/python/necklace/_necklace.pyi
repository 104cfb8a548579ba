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

def load_mesh(path: str) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """``(V, F)`` of an OBJ, OFF, PLY or STL file: float64 ``(n, 3)``, int64 ``(m, 3)``."""

def defaults() -> Dict[str, Any]:
    """The library's default of every option of ``find_necks``."""
