"""Neck loops (handles and tunnels) of closed triangle meshes.

necklace finds the loops that lasso the narrow parts of a solid (*handles*: a finger,
a tail, the thin side of a ring) and of the space around it (*tunnels*: around a
hole), after "Fast Computation of Neck-like Features". numpy in, numpy out::

    import necklace, trimesh
    mesh = trimesh.load("kitten.off")
    result = necklace.find_necks(mesh.vertices, mesh.faces)
    for loop in result.loops:
        print(loop.kind, loop.length, loop.points.shape)

Units are the input's; positions are in the input's frame. Errors raise
:class:`NecklaceError` (a ``ValueError``) with a one-line message.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np

from ._necklace import JSON_VERSION, NecklaceError, __version__
from ._necklace import find_necks as _find_necks
from ._necklace import load_mesh as _load_mesh
from ._necklace import repair as _repair
from ._batch import batch

__all__ = [
    "find_necks",
    "repair",
    "batch",
    "load_mesh",
    "NecklaceError",
    "NeckResult",
    "Loop",
    "Lasso",
    "DroppedSaddle",
    "CriticalPoints",
    "VolumeField",
    "JSON_VERSION",
    "__version__",
]

_MAX_INDEX = 2**32 - 1


@dataclass(frozen=True)
class Lasso:
    """The circle that fits a loop best: what a gripper or a rope lassoes.

    Attributes:
        center: ``(3,)`` the circle's centre.
        normal: ``(3,)`` unit normal of its plane (the loop's own best-fit plane,
            oriented like the loop).
        radius: the circle's radius.
        max_deviation: the largest distance from the loop to the circle.
        rms_deviation: the root-mean-square distance (weighted by length).
    """

    center: np.ndarray
    normal: np.ndarray
    radius: float
    max_deviation: float
    rms_deviation: float


@dataclass(frozen=True)
class Loop:
    """A neck loop: a closed polyline on the surface.

    Attributes:
        kind: ``"handle"`` (around a narrow part of the solid) or ``"tunnel"``
            (around a narrow part of the space around it).
        points: ``(k, 3)`` float64, the closed polyline (first point not repeated),
            in input units.
        edges: ``(k, 2)`` int64, where each point lies on the surface: on the input
            edge ``edges[i]`` at ``(1 - t[i]) * V[edges[i, 0]] + t[i] * V[edges[i, 1]]``;
            a point at a vertex ``v`` has ``edges[i] == (v, v)`` and ``t[i] == 0``.
            Indices are the input's vertex indices.
        t: ``(k,)`` float64, the parameter along ``edges``.
        length: length of the loop (input units).
        radius: ``length / 2π``.
        center: ``(3,)`` length-weighted centroid.
        normal: ``(3,)`` unit normal of the best-fit plane (the loop turns
            counter-clockwise around it).
        saddle: ``(3,)`` the 2-saddle it came from.
        persistence: smoothing levels the saddle lived.
        role: ``"cycle_closing"``, ``"separating"`` or ``None``.
        birth_scale, death_scale: the scale (a length) at which its saddle appeared
            and vanished under smoothing (``death_scale`` ``None``: alive at the
            largest scale).
        homology: its Z2 homology class, one ``"0"``/``"1"`` per basis cycle.
        separating: whether it cuts the surface in two (class 0).
        initial: how the initial loop was built (``"plane"``, ``"membrane"``, ``"turned_plane"`` or ``"linked"``: no saddle, a class that bounds no disk on its side).
        lasso: its best-fit circle (:class:`Lasso`).
        data: every field of the loop as ``loops.json`` has it (``bulge``,
            ``areas``, ``opening``, ``flatness``, ``reason``, ``tightening``, ...).
    """

    kind: str
    points: np.ndarray
    edges: np.ndarray
    t: np.ndarray
    length: float
    radius: float
    center: np.ndarray
    normal: np.ndarray
    saddle: np.ndarray
    persistence: int
    role: Optional[str]
    birth_scale: float
    death_scale: Optional[float]
    homology: str
    separating: bool
    initial: str
    lasso: Lasso
    data: Dict[str, Any] = field(repr=False)

    def __repr__(self) -> str:
        return (
            f"Loop({self.kind}, length={self.length:.6g}, points={len(self.points)}, "
            f"persistence={self.persistence}, role={self.role})"
        )


@dataclass(frozen=True)
class DroppedSaddle:
    """A selected 2-saddle that gave no kept loop, and why.

    Attributes:
        kind: ``"handle"`` or ``"tunnel"``.
        saddle: ``(3,)`` its position.
        persistence: smoothing levels it lived.
        reason: the reason's name (``"duplicate"``, ``"not_a_neck"``, ...).
        data: every field as ``loops.json`` has it (the reason's figures).
    """

    kind: str
    saddle: np.ndarray
    persistence: int
    reason: str
    data: Dict[str, Any] = field(repr=False)


@dataclass(frozen=True)
class CriticalPoints:
    """The critical points of one side's smoothed distance at the last level.

    Attributes:
        side: ``"inside"`` (handles) or ``"outside"`` (tunnels).
        position: ``(n, 3)`` float64.
        type: ``(n,)`` str: ``"minimum"``, ``"saddle1"``, ``"saddle2"``,
            ``"maximum"``, ``"degenerate"``.
        selected: ``(n,)`` bool, the neck 2-saddles.
        persistence: ``(n,)`` uint64, levels lived.
    """

    side: str
    position: np.ndarray
    type: np.ndarray
    selected: np.ndarray
    persistence: np.ndarray


@dataclass(frozen=True)
class VolumeField:
    """One side's tet mesh and smoothed distance field (``find_necks(volume=True)``).

    Attributes:
        side: ``"inside"`` or ``"outside"``.
        points: ``(n, 3)`` float64 vertex positions.
        tets: ``(t, 4)`` int64 vertex indices, positively oriented.
        field: ``(n,)`` float64, the distance to the surface after the last smoothing
            step: 0 on the surface; outside in input units, inside rescaled after
            each step to a maximum of 1 (its boundary values are all 0, so heat would
            otherwise drain it).
        kind: ``(n,)`` str: ``"interior"``, ``"surface"`` or ``"outer"`` (the
            bounding sphere of the outside shell).
    """

    side: str
    points: np.ndarray
    tets: np.ndarray
    field: np.ndarray
    kind: np.ndarray


@dataclass(frozen=True, repr=False)
class NeckResult:
    """What :func:`find_necks` found.

    Attributes:
        loops: the neck loops, handles then tunnels.
        dropped: the saddles that gave no loop, with reasons.
        critical: per side run, the critical points at the last level.
        volume: per side run, the tet mesh and field (only with ``volume=True``).
        morse: per side, the Morse check (``ok``, per-level counts), as in the JSON.
        saddles: per side, the selected 2-saddles (dicts, as in the JSON).
        rejected: per side, the 2-saddles not selected, with reasons.
        warnings: what is unusual about the input or the run, one line each.
        notes: what was repaired in the input, one line each.
        timings: seconds per stage and side.
    """

    loops: List[Loop]
    dropped: List[DroppedSaddle]
    critical: List[CriticalPoints]
    volume: List[VolumeField]
    morse: List[Dict[str, Any]]
    saddles: Dict[str, List[Dict[str, Any]]]
    rejected: Dict[str, List[Dict[str, Any]]]
    warnings: List[str]
    notes: List[str]
    timings: Dict[str, Any]
    _report: Dict[str, Any] = field(repr=False)

    @property
    def handles(self) -> List[Loop]:
        """The handle loops."""
        return [l for l in self.loops if l.kind == "handle"]

    @property
    def tunnels(self) -> List[Loop]:
        """The tunnel loops."""
        return [l for l in self.loops if l.kind == "tunnel"]

    @property
    def morse_ok(self) -> bool:
        """Whether every side's Morse sum matched at every level."""
        return all(m["ok"] for m in self.morse)

    def to_dict(self) -> Dict[str, Any]:
        """The report as ``loops.json`` holds it (``json.dump`` writes the same file)."""
        return json.loads(json.dumps(self._report))

    def __repr__(self) -> str:
        lines = [
            f"NeckResult: {len(self.handles)} handles, {len(self.tunnels)} tunnels, "
            f"{len(self.dropped)} dropped"
        ]
        for i, l in enumerate(self.loops):
            c = ", ".join(f"{x:.4g}" for x in l.center)
            lines.append(
                f"  {i:2} {l.kind:6} length {l.length:.6g} radius {l.radius:.4g} "
                f"centre ({c}) persistence {l.persistence}"
            )
        for d in self.dropped:
            lines.append(f"  dropped {d.kind} saddle (persistence {d.persistence}): {d.reason}")
        for w in self.warnings:
            lines.append(f"  warning: {w}")
        return "\n".join(lines)


def _as_vertices(vertices: Any) -> np.ndarray:
    try:
        v = np.asarray(vertices)
    except Exception as e:  # e.g. ragged lists
        raise NecklaceError(f"vertices: not an array ({e})") from None
    if v.dtype.kind not in "fiu":
        raise NecklaceError(f"vertices: dtype {v.dtype} is not a real number type")
    if v.ndim != 2 or v.shape[1] != 3:
        raise NecklaceError(f"vertices: shape {v.shape}, expected (n, 3)")
    v = np.ascontiguousarray(v, dtype=np.float64)
    bad = ~np.isfinite(v)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise NecklaceError(f"vertices: vertex {row} is not finite ({v[row].tolist()})")
    return v


def _as_faces(faces: Any, vertex_count: int) -> np.ndarray:
    try:
        f = np.asarray(faces)
    except Exception as e:
        raise NecklaceError(f"faces: not an array ({e})") from None
    if f.dtype.kind not in "iu":
        raise NecklaceError(f"faces: dtype {f.dtype} is not an integer type")
    if f.ndim != 2 or f.shape[1] != 3:
        raise NecklaceError(f"faces: shape {f.shape}, expected (m, 3) triangles")
    if f.size:
        low, high = int(f.min()), int(f.max())
        if low < 0 or high >= vertex_count:
            bad = low if low < 0 else high
            raise NecklaceError(
                f"faces: vertex index {bad} out of range ({vertex_count} vertices)"
            )
        if high > _MAX_INDEX:
            raise NecklaceError(f"faces: vertex index {high} above 2^32 - 1")
    return np.ascontiguousarray(f, dtype=np.uint32)


def _vec(x: Any) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def _location(points: List[Dict[str, Any]]) -> Tuple[np.ndarray, np.ndarray]:
    edges = np.empty((len(points), 2), dtype=np.int64)
    t = np.zeros(len(points), dtype=np.float64)
    for i, p in enumerate(points):
        if "edge" in p:
            edges[i] = p["edge"]["edge"]
            t[i] = p["edge"]["t"]
        else:
            edges[i] = p["vertex"]["vertex"]
    return edges, t


def _loop(d: Dict[str, Any]) -> Loop:
    edges, t = _location(d["surface_points"])
    return Loop(
        kind=d["kind"],
        points=_vec(d["points"]).reshape(-1, 3),
        edges=edges,
        t=t,
        length=d["length"],
        radius=d["radius"],
        center=_vec(d["center"]),
        normal=_vec(d["normal"]),
        saddle=_vec(d["saddle"]),
        persistence=d["persistence"],
        role=d["role"],
        birth_scale=d["birth_scale"],
        death_scale=d["death_scale"],
        homology=d["homology"],
        separating=d["separating"],
        initial=d["initial"],
        lasso=Lasso(
            center=_vec(d["lasso"]["center"]),
            normal=_vec(d["lasso"]["normal"]),
            radius=d["lasso"]["radius"],
            max_deviation=d["lasso"]["max_deviation"],
            rms_deviation=d["lasso"]["rms_deviation"],
        ),
        data=d,
    )


def _result(report: Dict[str, Any], sides: List[Dict[str, Any]]) -> NeckResult:
    critical = [
        CriticalPoints(
            side=s["side"],
            position=s["critical"]["position"],
            type=np.asarray(s["critical"]["type"], dtype=str),
            selected=s["critical"]["selected"],
            persistence=s["critical"]["persistence"],
        )
        for s in sides
    ]
    volume = [
        VolumeField(
            side=s["side"],
            points=s["volume"]["points"],
            tets=s["volume"]["tets"],
            field=s["volume"]["field"],
            kind=np.asarray(s["volume"]["kind"], dtype=str),
        )
        for s in sides
        if "volume" in s
    ]
    dropped = [
        DroppedSaddle(
            kind=d["kind"],
            saddle=_vec(d["saddle"]),
            persistence=d["persistence"],
            reason=d["reason"],
            data=d,
        )
        for d in report["dropped"]
    ]
    return NeckResult(
        loops=[_loop(l) for l in report["loops"]],
        dropped=dropped,
        critical=critical,
        volume=volume,
        morse=report["morse"],
        saddles={s["side"]: s["saddles"] for s in report["sides"]},
        rejected={s["side"]: s["rejected"] for s in report["sides"]},
        warnings=report["warnings"],
        notes=report["notes"],
        timings=report["timings"],
        _report=report,
    )


def find_necks(
    vertices: Any,
    faces: Any,
    *,
    handles: bool = True,
    tunnels: bool = True,
    schedule: str = "scales",
    levels: int = 32,
    min_bulge: float = 1.5,
    min_levels: int = 3,
    steps: int = 20,
    tau: float = 0.01,
    h: Optional[float] = None,
    max_memory: int = 8_000_000_000,
    unchecked_min_cell: float = 0.25,
    max_steps: int = 1000,
    solver: str = "auto",
    plane_offsets: int = 16,
    slide_steps: int = 8,
    min_opening: float = 0.1,
    max_flatness: float = 3.0,
    volume: bool = False,
    one_side_at_a_time: bool = False,
    budget_steps: bool = False,
    simplify_above: int = 200_000,
    simplify_to: int = 30_000,
    weld: float = 1e-08,
    no_weld: bool = False,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> NeckResult:
    """Find the neck loops of a closed triangle mesh.

    Args:
        vertices: ``(n, 3)`` real numbers (any float or integer dtype), input units.
        faces: ``(m, 3)`` integer vertex indices (any integer dtype, any memory
            layout), each triangle counter-clockwise seen from outside (inverted
            meshes and components are turned round, and said so in ``notes``).
        handles: look for handle loops (inside the solid).
        tunnels: look for tunnel loops (outside it).
        schedule: ``"scales"`` (32 levels over a geometric range of scales) or
            ``"paper"`` (the paper's ``steps`` steps of ``tau``).
        levels: scale space: classified levels.
        min_bulge: scale space: smallest ratio of a lobe's inscribed radius to the
            neck's for a separating saddle to be a neck by its lobe alone.
        min_levels: scale space: levels a saddle must live to be a neck.
        steps: paper schedule: last smoothing step.
        tau: paper schedule: heat time step, in units where the bounding box's
            longest side is 1.
        h: lattice spacing of the volume mesh, input units (default: the bounding
            box diagonal / 64).
        max_memory: memory budget of the run in bytes, shared by the two volume
            meshes (400 bytes a tet): thin parts are not refined past it, and a mesh
            estimated over it is refused before it is built.
        unchecked_min_cell: on a side whose topology the surface does not predict
            (it crosses itself, or a component has no genus), no cell finer than this
            fraction of ``h`` is asked for (0 turns the bound off); a warning says
            when it binds.
        max_steps: the most heat steps a run may take.
        solver: preconditioner of the heat steps' conjugate gradients: ``"jacobi"``
            (the diagonal), ``"multigrid"`` (a smoothed-aggregation V-cycle: fewer,
            dearer iterations, more memory), or ``"auto"`` (multigrid from 300 000
            to 1 000 000 unknowns, jacobi outside); the fields agree to the solver's
            tolerance.
        plane_offsets: parallel planes tried each way where the plane through a
            saddle has no curve around it (0.125 % of the diagonal apart).
        slide_steps: parallel planes (0.5 % of the diagonal apart) each way a
            cycle-closing loop is slid along to its narrowest place.
        min_opening: how much longer than the loop the curve one loop radius away
            must be, on both sides, for a gently bulging separating saddle to be a neck.
        max_flatness: the longest loop, in circumferences of the inscribed ball at its
            saddle, such a saddle may have.
        volume: also return each side's tet mesh and smoothed field
            (:attr:`NeckResult.volume`).
        one_side_at_a_time: run the two sides one after the other instead of at
            the same time: slower, with the larger side's peak memory instead of
            both sides'; the same results.
        budget_steps: mesh each side of a surface whose genus is known within a
            sixteenth, then a quarter of its budget first, and keep the first mesh
            whose budget did not bind or whose topology and loop rank match the
            surface's (``notes`` says which): faster where slivers make the budget
            bind, but such a mesh can miss necks that do not change the ranks.
        simplify_above: a closed surface with more triangles than this (0: never)
            is simplified for the volume mesh, field and saddles, and each loop is cut
            again and tightened on the input (``to_dict()["simplified"]`` says what
            was done; ``notes`` too).
        simplify_to: how many triangles the simplified copy keeps.
        weld: corners closer than this fraction of the bounding-box diagonal are
            welded into one vertex (repeated positions, an exporter's rounding);
            ``notes`` says how many.
        no_weld: keep the vertices as given (no welding).
        progress: called as ``progress(stage, done, total)`` at each stage's start
            and end and at most every 0.2 s in between (``total`` 0 when unknown). The
            two sides run at the same time, so their calls interleave; each stage's
            name ends with its side, e.g. ``"volume mesh (outside)"``. An exception it
            raises is raised when the run ends.

    Returns:
        A :class:`NeckResult`.

    Raises:
        NecklaceError: arrays of the wrong shape or dtype, NaN or infinite
            coordinates, indices out of range, a mesh no stage can use, options out of
            range, a run over budget. The message is one line.

    The defaults are those of ``necklace loops``; the GIL is released while it runs.
    """
    v = _as_vertices(vertices)
    f = _as_faces(faces, len(v))
    options = dict(
        handles=handles,
        tunnels=tunnels,
        schedule=schedule,
        levels=levels,
        min_bulge=min_bulge,
        min_levels=min_levels,
        steps=steps,
        tau=tau,
        h=h,
        max_memory=max_memory,
        unchecked_min_cell=unchecked_min_cell,
        max_steps=max_steps,
        solver=solver,
        plane_offsets=plane_offsets,
        slide_steps=slide_steps,
        min_opening=min_opening,
        max_flatness=max_flatness,
        volume=volume,
        one_side_at_a_time=one_side_at_a_time,
        budget_steps=budget_steps,
        simplify_above=simplify_above,
        simplify_to=simplify_to,
        weld=weld,
        no_weld=no_weld,
    )
    if progress is not None and not callable(progress):
        raise NecklaceError("progress: not callable")
    text, sides = _find_necks(v, f, options, progress)
    return _result(json.loads(text), sides)


# find_necks's keyword arguments that reach the library (repair takes them too).
_FIND_NECKS_OPTIONS = [
    name
    for name in find_necks.__code__.co_varnames[
        2 : 2 + find_necks.__code__.co_kwonlyargcount
    ]
    if name != "progress"
]


def repair(
    vertices: Any,
    faces: Any,
    *,
    genus: Optional[int] = None,
    max_length: Optional[float] = None,
    only: Optional[str] = None,
    band: float = 0.15,
    progress: Optional[Callable[[str, int, int], Any]] = None,
    **options: Any,
) -> Tuple[np.ndarray, np.ndarray, Dict[str, Any]]:
    """Remove handles and tunnels along their neck loops (``necklace repair``).

    A handle is cut through along a thin band round its loop and a tunnel's hole is
    plugged; each opening is closed by a faired cap. Loops go shortest first, and each
    operation is checked (a closed solid, the genus one lower, no crossings) or skipped
    with its reason.

    Args:
        vertices, faces: the closed surface, as for :func:`find_necks`.
        genus: remove classes until the surface has this genus (default 0).
        max_length: instead, remove every loop shorter than this (noise), whatever
            genus results. Excludes ``genus``.
        only: ``"handles"`` (only cuts) or ``"tunnels"`` (only plugs); default both.
        band: each side of the band a cut removes lies this fraction of the loop's
            radius from it (at least a tenth of the edges it crosses), in (0, 0.5].
        progress: as for :func:`find_necks`, called through each loop run.
        **options: :func:`find_necks`'s keyword arguments (``h``, ``levels``, ...),
            for the loop runs.

    Returns:
        ``(V, F, report)``: the repaired surface, ``(n, 3)`` float64 and ``(m, 3)``
        int64, and the report as ``necklace repair --json`` prints it: ``genus``
        (before, after), ``volume`` (before, after), ``operations`` (``kind``,
        ``loop_length``, ``center``, ``band_width``, ``cap_area``, ``volume_change``,
        ``max_displacement``, ``run``, ``points``), ``skipped`` (with ``reason``),
        ``loop_runs``, ``hausdorff``, ``warnings``, ``seconds``.

    Raises:
        NecklaceError: what :func:`find_necks` refuses, and an open or self-crossing
            surface, a ``genus`` above the surface's, ``genus`` with ``max_length``. The
            message is one line.
    """
    v = _as_vertices(vertices)
    f = _as_faces(faces, len(v))
    unknown = sorted(set(options) - set(_FIND_NECKS_OPTIONS))
    if unknown:
        raise NecklaceError(f"repair: unknown option {unknown[0]!r}")
    if genus is not None and max_length is not None:
        raise NecklaceError("repair: genus and max_length exclude each other: give one")
    if genus is not None and (isinstance(genus, bool) or not isinstance(genus, int) or genus < 0):
        raise NecklaceError(f"repair: genus = {genus!r}: expected an integer >= 0")
    if progress is not None and not callable(progress):
        raise NecklaceError("progress: not callable")
    options.update(genus=genus, max_length=max_length, only=only, band=band)
    vertices_out, faces_out, text = _repair(v, f, options, progress)
    return vertices_out, faces_out, json.loads(text)


def load_mesh(path: "str | os.PathLike[str]") -> Tuple[np.ndarray, np.ndarray]:
    """Read a triangle mesh (OBJ, OFF, PLY ascii or binary, STL ascii or binary).

    Returns:
        ``(V, F)``: ``(n, 3)`` float64 vertices and ``(m, 3)`` int64 faces (polygons
        fanned into triangles; STL corners merged).

    Raises:
        NecklaceError: an unreadable or malformed file (the message names the file
            and the line or byte).
    """
    return _load_mesh(os.fspath(path))
