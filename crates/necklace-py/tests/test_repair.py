"""necklace.repair: a numpy torus to genus 0 both ways, read back by trimesh as a
watertight sphere-like solid; the CLI's report; input refused in one line."""

import json
import math

import numpy as np
import pytest

import necklace
from conftest import run, torus

trimesh = pytest.importorskip("trimesh")

MAJOR, MINOR = 1.0, 0.3
# Fine enough that the band (at least a tenth of an edge each side) stays thin.
NU, NV = 96, 40


@pytest.fixture(scope="module")
def tori():
    """The torus repaired each way: {only: (V, F, report)}."""
    v, f = torus(MAJOR, MINOR, NU, NV)
    return {only: necklace.repair(v, f, only=only) for only in ("handles", "tunnels")}


@pytest.mark.parametrize("only", ["handles", "tunnels"])
def test_a_numpy_torus_becomes_a_watertight_genus_0_solid(tori, only):
    v, f, report = tori[only]
    assert v.dtype == np.float64 and v.shape[1] == 3
    assert f.dtype == np.int64 and f.shape[1] == 3
    assert report["genus"] == [1, 0]
    assert len(report["operations"]) == 1 and report["skipped"] == []
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.euler_number == 2  # genus 0
    assert mesh.volume > 0  # outward
    assert math.isclose(mesh.volume, report["volume"][1], rel_tol=1e-9)
    # The loop removed is the torus's: a meridian (2πr) or the inner equator (2π(R − r)).
    op = report["operations"][0]
    expected = 2 * math.pi * (MINOR if only == "handles" else MAJOR - MINOR)
    assert op["kind"] == ("handle" if only == "handles" else "tunnel")
    assert abs(op["loop_length"] - expected) < 0.05 * expected
    assert len(op["points"]) >= 3


def test_a_cut_lowers_the_volume_and_a_plug_raises_it(tori):
    v, f = torus(MAJOR, MINOR, NU, NV)
    before = trimesh.Trimesh(v, f, process=False).volume
    cut = trimesh.Trimesh(*tori["handles"][:2], process=False).volume
    plug = trimesh.Trimesh(*tori["tunnels"][:2], process=False).volume
    assert cut < before < plug
    # The cut removes a slab of the tube as thick as the band: 2δ·πr², under 2 %.
    op = tori["handles"][2]["operations"][0]
    slab = op["band_width"] * math.pi * MINOR**2
    assert abs((before - cut) - slab) < 0.05 * slab
    assert before - cut < 0.02 * before
    # The caps are flat disks of the tube's section; the farthest cap point, the
    # centre, lies r from the tube's wall.
    assert op["cap_area"] == pytest.approx(2 * math.pi * MINOR**2, rel=0.02)
    assert op["max_displacement"] == pytest.approx(MINOR, rel=0.02)


def test_the_default_is_the_cli_repair(cli, tmp_path, tori):
    """`necklace repair --json` on the same torus gives the same operations."""
    v, f = torus(MAJOR, MINOR, NU, NV)
    mesh = tmp_path / "torus.obj"
    trimesh.Trimesh(v, f, process=False).export(mesh)
    out = tmp_path / "out.obj"
    cli_report = json.loads(run(cli, "repair", mesh, "-o", out, "-q", "--json"))
    _, _, report = necklace.repair(v, f)
    assert report["genus"] == cli_report["genus"] == [1, 0]
    assert [o["kind"] for o in report["operations"]] == ["handle"]  # the cheaper cap
    for a, b in zip(report["operations"], cli_report["operations"]):
        assert a["loop_length"] == pytest.approx(b["loop_length"], rel=1e-6)
        assert a["cap_area"] == pytest.approx(b["cap_area"], rel=1e-6)


@pytest.mark.parametrize(
    "mesh, options, message",
    [
        ("open", {}, "closed"),
        ("torus", dict(genus=2), "genus 1"),
        ("torus", dict(genus=0, max_length=1.0), "exclude"),
        ("torus", dict(genus=-1), "genus"),
        ("torus", dict(max_length=-1.0), "max-length"),
        ("torus", dict(only="both"), "only"),
        ("torus", dict(band=0.0), "band"),
        ("torus", dict(colour="red"), "unknown option"),
    ],
)
def test_bad_input_raises_a_one_line_necklace_error(mesh, options, message):
    v, f = torus(nu=16, nv=8)
    if mesh == "open":
        f = f[1:]
    with pytest.raises(necklace.NecklaceError) as info:
        necklace.repair(v, f, **options)
    text = str(info.value)
    assert message in text and "\n" not in text, text
