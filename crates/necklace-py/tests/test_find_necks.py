"""necklace.find_necks and load_mesh: the same loops as the CLI, analytic lengths,
input checks, array layouts and dtypes, the GIL, progress."""

import inspect
import json
import math
import threading

import numpy as np
import pytest

import necklace
from conftest import run, torus


def cli_report(cli, mesh, *flags):
    return json.loads(run(cli, "loops", mesh, "-q", "--json", *flags))


def same_loops(a, b):
    """The loops of two reports, every field but timings (there are none per loop)."""
    assert len(a["loops"]) == len(b["loops"])
    for x, y in zip(a["loops"], b["loops"]):
        assert x == y
    assert a["dropped"] == b["dropped"]


def test_dumbbell_same_loops_as_the_cli_and_its_neck_is_2_pi_r(cli, dumbbell):
    v, f = necklace.load_mesh(dumbbell)
    result = necklace.find_necks(v, f)
    same_loops(result.to_dict(), cli_report(cli, dumbbell))
    assert [l.kind for l in result.loops] == ["handle"]
    neck = result.loops[0]
    # The neck's cylinder has radius 0.15; the polygonal mesh's loop is a little shorter.
    assert neck.length == pytest.approx(2 * math.pi * 0.15, rel=0.02)
    assert neck.points.shape == (len(neck.edges), 3)
    # Its lasso is the neck's circle, across the axis (x).
    assert neck.lasso.radius == pytest.approx(0.15, rel=0.02)
    assert abs(neck.lasso.normal[0]) > 0.99
    assert neck.lasso.max_deviation < 0.02 * 0.15
    assert result.morse_ok


def test_both_preconditioners_give_the_dumbbells_neck(dumbbell):
    v, f = necklace.load_mesh(dumbbell)
    jacobi = necklace.find_necks(v, f, handles=True, tunnels=False, solver="jacobi")
    multigrid = necklace.find_necks(v, f, handles=True, tunnels=False, solver="multigrid")
    assert [l.kind for l in jacobi.loops] == [l.kind for l in multigrid.loops] == ["handle"]
    assert multigrid.loops[0].length == pytest.approx(jacobi.loops[0].length, rel=1e-6)


def test_a_surface_above_simplify_above_is_simplified_as_by_the_cli(cli, dumbbell):
    v, f = necklace.load_mesh(dumbbell)
    flags = dict(handles=True, tunnels=False, simplify_above=1000, simplify_to=2000)
    result = necklace.find_necks(v, f, **flags)
    report = result.to_dict()
    assert report["simplified"]["used"]
    assert any("simplified from" in n for n in result.notes)
    cli_flags = ("--handles", "--simplify-above", "1000", "--simplify-to", "2000")
    same_loops(report, cli_report(cli, dumbbell, *cli_flags))
    plain = necklace.find_necks(v, f, handles=True, tunnels=False)
    assert plain.to_dict()["simplified"] is None
    assert result.loops[0].length == pytest.approx(plain.loops[0].length, rel=0.005)


def test_kitten_same_loops_as_the_cli(cli, kitten):
    v, f = necklace.load_mesh(kitten)
    result = necklace.find_necks(v, f)
    cli_json = cli_report(cli, kitten)
    same_loops(result.to_dict(), cli_json)
    # Every label of the JSON is on the loop objects.
    for loop, d in zip(result.loops, cli_json["loops"]):
        assert loop.kind == d["kind"] and loop.role == d["role"]
        assert loop.homology == d["homology"] and loop.initial == d["initial"]
        assert (loop.birth_scale, loop.death_scale) == (d["birth_scale"], d["death_scale"])
        assert loop.data["reason"] == d["reason"]
        np.testing.assert_array_equal(loop.points, np.array(d["points"]))
    assert len(result.handles) == 2 and len(result.tunnels) == 1


def test_kitten_through_trimesh_gives_the_same_loops(cli, kitten):
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.load(kitten)
    result = necklace.find_necks(m.vertices, m.faces)
    cli_loops = cli_report(cli, kitten)["loops"]
    assert [l.kind for l in result.loops] == [d["kind"] for d in cli_loops]
    for loop, d in zip(result.loops, cli_loops):
        assert loop.length == pytest.approx(d["length"], rel=1e-9)


def on_surface(vertices, loop):
    """The loop's points rebuilt from its surface location."""
    a = vertices[loop.edges[:, 0]]
    b = vertices[loop.edges[:, 1]]
    return (1 - loop.t)[:, None] * a + loop.t[:, None] * b


def test_torus_loops_are_its_meridian_and_inner_equator():
    v, f = torus()
    result = necklace.find_necks(v, f)
    assert sorted(l.kind for l in result.loops) == ["handle", "tunnel"]
    (handle,) = result.handles
    (tunnel,) = result.tunnels
    # A polygon inscribed in each circle: a little shorter than 2πr.
    assert handle.length == pytest.approx(2 * math.pi * 0.3, rel=0.02)
    assert tunnel.length == pytest.approx(2 * math.pi * 0.7, rel=0.02)
    for loop in result.loops:
        np.testing.assert_allclose(on_surface(v, loop), loop.points, atol=1e-12)
        # Closed polyline: its length is the sum of its segments, the closing one included.
        segments = np.linalg.norm(np.roll(loop.points, -1, axis=0) - loop.points, axis=1)
        assert segments.sum() == pytest.approx(loop.length, rel=1e-9)
    # Critical points: arrays of one length per side, the selected ones 2-saddles.
    for c in result.critical:
        n = len(c.position)
        assert c.position.shape == (n, 3) and c.type.shape == (n,)
        assert c.selected.shape == (n,) and c.persistence.shape == (n,)
        # (A selected saddle may have merged into a degenerate point by the last level.)
        assert set(c.type[c.selected]) <= {"saddle2", "degenerate"}
    assert sum(c.selected.sum() for c in result.critical) >= 2


def test_face_dtypes_and_layouts_give_the_same_loops():
    v, f = torus(nu=32, nv=12)
    expected = necklace.find_necks(v, f, tunnels=False).to_dict()["loops"]
    fortran = np.asfortranarray(f)
    strided = np.zeros((len(f), 6), dtype=np.int64)
    strided[:, ::2] = f
    variants = [
        f.astype(np.int32),
        f.astype(np.uint32),
        f.astype(np.uint64),
        fortran,
        strided[:, ::2],
        f.tolist(),
    ]
    for faces in variants:
        got = necklace.find_necks(v, faces, tunnels=False).to_dict()["loops"]
        assert got == expected
    # Vertices: non-contiguous and float32 are converted.
    wide = np.zeros((len(v), 6))
    wide[:, ::2] = v
    got = necklace.find_necks(wide[:, ::2], f, tunnels=False).to_dict()["loops"]
    assert got == expected


@pytest.mark.parametrize(
    "vertices, faces, message",
    [
        (np.zeros((4, 2)), np.zeros((1, 3), int), "shape"),
        (np.zeros(12), np.zeros((1, 3), int), "shape"),
        (np.zeros((4, 3)), np.zeros((1, 4), int), "shape"),
        (np.zeros((4, 3)), np.zeros((1, 3)), "dtype"),
        (np.zeros((4, 3), dtype=complex), np.zeros((1, 3), int), "dtype"),
        (np.array([["a", "b", "c"]]), np.zeros((1, 3), int), "dtype"),
        (np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]]), [[0, 1, 2]], "not finite"),
        (np.array([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]]), [[0, 1, 2]], "not finite"),
        (np.eye(3), [[0, 1, 3]], "out of range"),
        (np.eye(3), [[0, 1, -1]], "out of range"),
        (np.zeros((0, 3)), np.zeros((0, 3), int), ""),
        (np.eye(3), [[0, 1, 2]], ""),  # one flat triangle
        ([[0, 0], [1]], [[0, 1, 2]], ""),  # ragged
    ],
)
def test_bad_input_raises_a_one_line_necklace_error(vertices, faces, message):
    with pytest.raises(necklace.NecklaceError) as info:
        necklace.find_necks(vertices, faces)
    text = str(info.value)
    assert message in text and "\n" not in text
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize(
    "options",
    [
        dict(h=-1.0),
        dict(h=float("nan")),
        dict(levels=0),
        dict(levels=-3),
        dict(tau=0.0),
        dict(max_flatness=-1.0),
        dict(schedule="weekly"),
        dict(solver="fast"),
        dict(handles=False, tunnels=False),
        dict(max_memory=4000),
        dict(unchecked_min_cell=-0.5),
        dict(unchecked_min_cell=float("nan")),
        dict(levels="many"),
    ],
)
def test_bad_options_raise_a_necklace_error(options):
    v, f = torus(nu=16, nv=8)
    with pytest.raises(necklace.NecklaceError) as info:
        necklace.find_necks(v, f, **options)
    assert "\n" not in str(info.value)


def test_keyword_defaults_are_the_cli_defaults():
    from necklace import _necklace

    signature = inspect.signature(necklace.find_necks)
    defaults = _necklace.defaults()
    for name, value in defaults.items():
        assert signature.parameters[name].default == value, name
    assert set(defaults) == {
        n for n, p in signature.parameters.items() if p.kind == p.KEYWORD_ONLY
    } - {"progress"}


def test_garbage_never_crashes_the_interpreter():
    rng = np.random.default_rng(7)
    for case in range(12):
        n = int(rng.integers(3, 12))
        v = rng.normal(size=(n, 3)) * 10.0 ** float(rng.integers(-3, 4))
        f = rng.integers(0, n, size=(int(rng.integers(1, 16)), 3))
        try:
            result = necklace.find_necks(v, f, max_memory=80_000_000)
        except necklace.NecklaceError as e:
            assert "\n" not in str(e)
        else:
            assert isinstance(result, necklace.NeckResult)


def test_the_gil_is_released_and_progress_reports_stages():
    v, f = torus()
    ticks = 0
    running = True

    def count():
        nonlocal ticks
        while running:
            ticks += 1

    stages = []
    counter = threading.Thread(target=count)
    counter.start()
    try:
        necklace.find_necks(v, f, progress=lambda s, done, total: stages.append((s, done, total)))
    finally:
        running = False
        counter.join()
    names = {s for s, _, _ in stages}
    assert any(s.startswith("volume mesh") for s in names), names
    assert any("inside" in s for s in names) and any("outside" in s for s in names)
    # A thread that needs the GIL ran all along.
    assert ticks > 1000


def test_an_exception_in_progress_is_raised():
    v, f = torus(nu=16, nv=8)

    def fail(stage, done, total):
        raise KeyError("stop")

    with pytest.raises(KeyError):
        necklace.find_necks(v, f, progress=fail)


def test_volume_gives_each_sides_tet_mesh_and_field():
    v, f = torus(nu=24, nv=10)
    result = necklace.find_necks(v, f, volume=True)
    assert [x.side for x in result.volume] == ["inside", "outside"]
    for side in result.volume:
        n = len(side.points)
        assert side.points.shape == (n, 3) and side.field.shape == (n,)
        assert side.tets.min() >= 0 and side.tets.max() < n and side.tets.shape[1] == 4
        # Positively oriented tets.
        p = side.points[side.tets]
        det = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
        assert (det > 0).all()
        assert set(side.kind) <= {"interior", "surface", "outer"}
    # The smoothed distance: 0 on the surface, positive off it, inside rescaled to a
    # maximum of 1.
    for side in result.volume:
        on_surface = side.kind == "surface"
        assert (side.field[on_surface] == 0).all() and (side.field[~on_surface] > 0).all()
    assert result.volume[0].field.max() == pytest.approx(1.0)


def test_load_mesh_reads_every_format_and_errors_name_the_file(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    v, f = torus(nu=16, nv=8)
    mesh = trimesh.Trimesh(v, f, process=False)
    for ext in ["obj", "off", "ply", "stl"]:
        path = tmp_path / f"t.{ext}"
        mesh.export(path)
        lv, lf = necklace.load_mesh(path)
        assert lv.dtype == np.float64 and lf.dtype == np.int64
        assert lf.shape == f.shape
        # The same triangles (STL's corners merged, so compare positions).
        np.testing.assert_allclose(lv[lf], v[f], atol=1e-6)
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    with pytest.raises(necklace.NecklaceError, match="bad.off"):
        necklace.load_mesh(bad)
    with pytest.raises(necklace.NecklaceError):
        necklace.load_mesh(tmp_path / "missing.obj")


def test_a_trimesh_round_trip_keeps_the_loops(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    v, f = torus(nu=32, nv=12)
    result = necklace.find_necks(v, f)
    # The loops as a trimesh path, written and read back.
    entities = []
    start = 0
    points = []
    for loop in result.loops:
        k = len(loop.points)
        entities.append(trimesh.path.entities.Line(np.r_[np.arange(start, start + k), start]))
        points.append(loop.points)
        start += k
    path = trimesh.path.Path3D(entities=entities, vertices=np.vstack(points))
    assert len(path.entities) == len(result.loops)
    for entity, loop in zip(path.entities, result.loops):
        assert entity.length(path.vertices) == pytest.approx(loop.length, rel=1e-12)
    # And the mesh itself: trimesh's export (float32 PLY) read back by necklace gives
    # the same loops, to float32's precision.
    file = tmp_path / "torus.ply"
    trimesh.Trimesh(v, f, process=False).export(file)
    again = necklace.find_necks(*necklace.load_mesh(file))
    assert [l.kind for l in again.loops] == [l.kind for l in result.loops]
    for a, b in zip(again.loops, result.loops):
        assert a.length == pytest.approx(b.length, rel=1e-6)
