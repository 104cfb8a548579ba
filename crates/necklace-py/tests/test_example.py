"""examples/python/draw_necks.py runs and writes a picture with the loops drawn."""

import subprocess
import sys

import pytest

from conftest import ROOT

pytest.importorskip("matplotlib")
pytest.importorskip("trimesh")


def test_the_example_draws_the_dumbbells_neck(dumbbell, tmp_path):
    out = tmp_path / "necks.png"
    script = ROOT / "examples" / "python" / "draw_necks.py"
    done = subprocess.run(
        [sys.executable, str(script), str(dumbbell), str(out)], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert "1 handles, 0 tunnels" in done.stdout or "NeckResult: 1 handles" in done.stdout
    png = out.read_bytes()
    assert png.startswith(b"\x89PNG")
    # The handle's vermilion is in the picture.
    matplotlib_image = pytest.importorskip("matplotlib.image")
    pixels = matplotlib_image.imread(out)[..., :3]
    vermilion = (abs(pixels[..., 0] - 0xD5 / 255) < 0.08) & (abs(pixels[..., 1] - 0x3E / 255) < 0.08)
    assert vermilion.sum() > 50
