"""Shared fixtures: the repository's paths, the CLI binary, analytic meshes."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
MESHES = pathlib.Path(os.environ.get("NECKLACE_MESHES", ROOT.parent / "shared" / "data" / "meshes"))


@pytest.fixture(scope="session")
def cli():
    """The `necklace` binary of this checkout (built by the test command)."""
    path = pathlib.Path(os.environ.get("NECKLACE_CLI", ROOT / "target" / "release" / "necklace"))
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo build --release` (the test command does)")
    return path


def run(cli, *args):
    done = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.fixture(scope="session")
def dumbbell(cli, tmp_path_factory):
    """The CLI's analytic dumbbell (neck radius 0.15) as an OFF file."""
    path = tmp_path_factory.mktemp("shapes") / "dumbbell.off"
    run(cli, "shape", "dumbbell", "-o", path)
    return path


@pytest.fixture(scope="session")
def kitten():
    path = MESHES / "kitten.off"
    if not path.exists():
        pytest.skip(f"{path} is absent (set NECKLACE_MESHES)")
    return path


def torus(major=1.0, minor=0.3, nu=48, nv=20):
    """A torus around z: its tunnel loop is the inner equator (2π(R − r)), its handle
    loop a meridian (2πr). Faces counter-clockwise seen from outside."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.arange(nv) * 2 * np.pi / nv
    uu, vv = np.meshgrid(u, v, indexing="ij")
    ring = major + minor * np.cos(vv)
    vertices = np.stack(
        [ring * np.cos(uu), ring * np.sin(uu), minor * np.sin(vv)], axis=-1
    ).reshape(-1, 3)
    faces = []
    for i in range(nu):
        for j in range(nv):
            a = i * nv + j
            b = ((i + 1) % nu) * nv + j
            c = ((i + 1) % nu) * nv + (j + 1) % nv
            d = i * nv + (j + 1) % nv
            faces += [(a, b, c), (a, c, d)]
    return vertices, np.array(faces, dtype=np.int64)
