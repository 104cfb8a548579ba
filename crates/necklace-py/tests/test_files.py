"""The files of `necklace loops -o DIR --volume`, read back by the tools people use:
trimesh, meshio and pyvista load the loops as curves and the field as a tet mesh
with its arrays."""

import json
import re

import numpy as np
import pytest

import necklace
from conftest import run, torus

trimesh = pytest.importorskip("trimesh")
meshio = pytest.importorskip("meshio")


@pytest.fixture(scope="module")
def run_dir(cli, tmp_path_factory):
    """A torus (one handle, one tunnel), run by the CLI into a folder."""
    folder = tmp_path_factory.mktemp("run")
    v, f = torus(nu=40, nv=16)
    mesh = folder / "torus.off"
    trimesh.Trimesh(v, f, process=False).export(mesh)
    out = folder / "out"
    run(cli, "loops", mesh, "-q", "-o", out, "--volume")
    report = json.loads((out / "loops.json").read_text())
    assert len(report["loops"]) == 2
    return out, report


def closed(points):
    return np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1).sum()


def test_loops_ply_is_a_trimesh_path_with_loop_ids(run_dir):
    out, report = run_dir
    path = trimesh.load(out / "loops.ply")
    assert isinstance(path, trimesh.path.Path3D)
    total = sum(len(l["points"]) for l in report["loops"])
    assert len(path.vertices) == total
    # Every edge of every loop, and the loop's length from them.
    length = sum(e.length(path.vertices) for e in path.entities)
    assert length == pytest.approx(sum(l["length"] for l in report["loops"]), rel=1e-9)
    # The loop id rides on the vertices.
    ids = path.metadata["_ply_raw"]["vertex"]["data"]["loop"]
    expected = np.concatenate([np.full(len(l["points"]), i) for i, l in enumerate(report["loops"])])
    np.testing.assert_array_equal(np.asarray(ids).ravel(), expected)


def test_loops_vtu_is_meshio_line_cells_with_loop_and_kind(run_dir):
    out, report = run_dir
    m = meshio.read(out / "loops.vtu")
    assert [c.type for c in m.cells] == ["line"]
    lines = m.cells[0].data
    loop = m.cell_data["loop"][0]
    kind = m.cell_data["kind"][0]
    for i, l in enumerate(report["loops"]):
        segments = lines[loop == i]
        assert len(segments) == len(l["points"])
        length = np.linalg.norm(m.points[segments[:, 1]] - m.points[segments[:, 0]], axis=1).sum()
        assert length == pytest.approx(l["length"], rel=1e-12)
        assert set(kind[loop == i]) == {0 if l["kind"] == "handle" else 1}


def test_loops_vtp_is_pyvista_polylines(run_dir):
    pv = pytest.importorskip("pyvista")
    out, report = run_dir
    poly = pv.read(out / "loops.vtp")
    assert poly.n_lines == len(report["loops"])
    np.testing.assert_array_equal(poly.cell_data["loop"], np.arange(len(report["loops"])))
    # Each polyline closes on itself: k + 1 ids, the first repeated.
    cells = poly.lines
    at = 0
    for l in report["loops"]:
        k = cells[at]
        ids = cells[at + 1 : at + 1 + k]
        assert k == len(l["points"]) + 1 and ids[0] == ids[-1]
        np.testing.assert_array_equal(poly.points[ids[:-1]], np.array(l["points"]))
        at += k + 1


def test_loops_obj_keeps_its_l_lines(run_dir):
    out, report = run_dir
    text = (out / "loops.obj").read_text()
    lines = [line for line in text.splitlines() if line.startswith("l ")]
    assert len(lines) == len(report["loops"])
    for line, l in zip(lines, report["loops"]):
        ids = line.split()[1:]
        assert len(ids) == len(l["points"]) + 1 and ids[0] == ids[-1]
    names = re.findall(r"^o (\w+)", text, flags=re.M)
    assert names == [f"{l['kind']}_{i}" for i, l in enumerate(report["loops"])]
    # trimesh reads the points (it ignores `l`; the PLY above is its curve file).
    points = trimesh.load(out / "loops.obj")
    assert len(points.vertices) == sum(len(l["points"]) for l in report["loops"])


def test_field_vtu_is_binary_and_read_by_meshio_and_pyvista(run_dir):
    out, report = run_dir
    data = (out / "field.vtu").read_bytes()
    assert b'<AppendedData encoding="raw">' in data
    m = meshio.read(out / "field.vtu")
    assert [c.type for c in m.cells] == ["tetra"]
    tets = m.cells[0].data
    vertices = sum(s["volume"]["vertices"] for s in report["sides"])
    assert len(m.points) == vertices
    assert len(tets) == sum(s["volume"]["tets"] for s in report["sides"])
    assert set(m.point_data) >= {"field", "side", "kind"}
    # The field: the smoothed distance, 0 on the surface (kind 1), positive off it;
    # inside rescaled to a maximum of 1.
    field, kind = m.point_data["field"], m.point_data["kind"]
    assert (field[kind == 1] == 0).all() and (field[kind != 1] > 0).all()
    assert field[m.point_data["side"] == 0].max() == pytest.approx(1.0)
    # At least 5x smaller than the ascii file the writer used to make (shortest
    # round-trip numbers, one value per token).
    ascii_size = sum(len(repr(float(x))) + 1 for x in m.points.ravel())
    ascii_size += sum(len(str(int(x))) + 1 for x in tets.ravel())
    ascii_size += len(tets) * (len(str(len(tets))) + 1 + 3)
    for name in ["field", "side"]:
        ascii_size += sum(len(repr(float(x))) + 1 for x in m.point_data[name])
    assert len(data) * 5 <= ascii_size, (len(data), ascii_size)
    pv = pytest.importorskip("pyvista")
    grid = pv.read(out / "field.vtu")
    assert grid.n_cells == len(tets)
    np.testing.assert_array_equal(grid.point_data["field"], m.point_data["field"])


def test_field_matches_the_python_volume(run_dir):
    """The field file holds the same values find_necks(volume=True) returns."""
    out, _ = run_dir
    mesh = necklace.load_mesh(out.parent / "torus.off")
    result = necklace.find_necks(*mesh, volume=True)
    m = meshio.read(out / "field.vtu")
    values = np.concatenate([side.field for side in result.volume])
    np.testing.assert_array_equal(m.point_data["field"], values)
