"""necklace.batch: the same rows as `necklace batch`, on a Dask LocalCluster and on the
local pool, with a failing and a timing-out mesh; Parquet written, read back and
resumed."""

import json
import pathlib

import pytest

import necklace

from conftest import MESHES, ROOT, run

REALWORLD = ROOT.parent / "shared" / "data" / "realworld"
TIMEOUT = 8.0


@pytest.fixture(scope="module")
def meshes(cli, tmp_path_factory):
    """About ten meshes: small analytic shapes and shared models, a triangle soup (an
    error row) and the bed (over the time limit)."""
    for path in (MESHES / "eight.off", REALWORLD / "tm_soup.stl", REALWORLD / "ps_mk3_bed.stl"):
        if not path.exists():
            pytest.skip(f"{path} is absent")
    folder = tmp_path_factory.mktemp("batch")
    shapes = []
    for name, param in [
        ("torus", "res=16"),
        ("dumbbell", "res=24"),
        ("sphere", "res=8"),
        ("eight", "res=24"),
        ("capsule", "res=16"),
        ("varying-torus", "res=20"),
    ]:
        path = folder / f"{name}.obj"
        run(cli, "shape", name, "--param", param, "-o", path)
        shapes.append(path)
    return shapes + [
        MESHES / "eight.off",
        MESHES / "torus.obj",
        REALWORLD / "tm_soup.stl",
        REALWORLD / "ps_mk3_bed.stl",
    ]


def comparable(row):
    """A row without what the clock and memory say, with absent fields as None."""
    out = {k: row.get(k) for k in necklace._batch.COLUMNS}
    for key in ("seconds", "timings", "peak_memory"):
        out.pop(key)
    if out["loops"] is not None:
        out["loops"] = [
            {k: (list(v) if not isinstance(v, (str, float, int)) else v) for k, v in loop.items()}
            for loop in out["loops"]
        ]
    return out


def frame_rows(frame):
    return [necklace._batch._from_parquet(r) for r in frame.to_dict("records")]


@pytest.fixture(scope="module")
def cli_rows(cli, meshes, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "runs.jsonl"
    run(cli, "batch", "-q", *meshes, "-o", out, "--jobs", "2", "--timeout", TIMEOUT)
    return [json.loads(line) for line in out.read_text().splitlines()]


def check_statuses(rows):
    status = {pathlib.Path(r["path"]).name: r["status"] for r in rows}
    assert status["tm_soup.stl"] == "error"
    assert status["ps_mk3_bed.stl"] == "timeout"
    assert sum(s == "ok" for s in status.values()) == len(status) - 2, status


def test_batch_on_a_dask_local_cluster_gives_the_cli_rows(meshes, cli_rows, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        out = tmp_path / "runs.parquet"
        frame = necklace.batch(meshes, out=out, client=client, timeout=TIMEOUT)
    rows = frame_rows(frame)
    assert len(rows) == len(meshes)
    check_statuses(rows)
    assert [comparable(r) for r in rows] == [comparable(r) for r in cli_rows]
    assert isinstance(frame["loops"].iloc[0], list)

    # The Parquet file reads back with pandas, with the same rows.
    import pandas

    back = pandas.read_parquet(out)
    assert len(back) == len(meshes)
    assert [comparable(r) for r in frame_rows(back)] == [comparable(r) for r in cli_rows]

    # Resumed from it: nothing runs again (the soup's row is kept, the bed's too).
    again = necklace.batch(meshes, out=out, timeout=TIMEOUT)
    assert [comparable(r) for r in frame_rows(again)] == [comparable(r) for r in rows]


def test_batch_without_a_client_gives_the_cli_rows_and_resumes_from_jsonl(
    meshes, cli_rows, tmp_path
):
    out = tmp_path / "runs.jsonl"
    frame = necklace.batch(meshes[:-1], out=out, jobs=2, timeout=TIMEOUT)
    assert len(frame) == len(meshes) - 1
    frame = necklace.batch(meshes, out=out, jobs=2, timeout=TIMEOUT)
    rows = frame_rows(frame)
    check_statuses(rows)
    assert [comparable(r) for r in rows] == [comparable(r) for r in cli_rows]
    # The file is the CLI's format: one row per mesh, in path order.
    lines = out.read_text().splitlines()
    assert [json.loads(line)["path"] for line in lines] == [r["path"] for r in cli_rows]


def test_batch_refuses_unknown_options_and_missing_files(tmp_path):
    with pytest.raises(TypeError, match="unknown options"):
        necklace.batch([tmp_path], colour="red")
    with pytest.raises(necklace.NecklaceError, match="does not exist"):
        necklace.batch([tmp_path / "nothing.obj"])
