"""Find the neck loops of a mesh loaded with trimesh and draw them with matplotlib.

    python examples/python/draw_necks.py MESH [OUT.png]

Handles are drawn in vermilion, tunnels in blue, over the surface's triangles.
Needs: pip install ./crates/necklace-py trimesh matplotlib
"""

import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np
import trimesh
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import necklace

COLORS = {"handle": "#d53e1e", "tunnel": "#1e64c8"}


def main(path, out="necks.png"):
    mesh = trimesh.load(path, force="mesh")
    result = necklace.find_necks(mesh.vertices, mesh.faces)
    print(result)

    fig = plt.figure(figsize=(8, 8))
    ax = fig.add_subplot(projection="3d")
    ax.computed_zorder = False  # loops on top of the see-through surface
    surface = Poly3DCollection(
        mesh.vertices[mesh.faces], facecolor="0.85", edgecolor="none", alpha=0.25
    )
    ax.add_collection3d(surface)
    for i, loop in enumerate(result.loops):
        closed = np.vstack([loop.points, loop.points[:1]])
        ax.plot(*closed.T, color=COLORS[loop.kind], linewidth=2.5, zorder=10)
        ax.text(*loop.center, str(i), color=COLORS[loop.kind], zorder=11)
    lo, hi = mesh.bounds
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    for set_limits, c in zip([ax.set_xlim, ax.set_ylim, ax.set_zlim], centre):
        set_limits(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_axis_off()
    ax.set_title(f"{len(result.handles)} handles, {len(result.tunnels)} tunnels")
    fig.savefig(out, dpi=100, bbox_inches="tight")
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(*sys.argv[1:3])
