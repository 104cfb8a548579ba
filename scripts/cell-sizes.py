#!/usr/bin/env python3
"""Where a volume mesh's unknowns are: its interior vertices binned by their longest edge.

Reads a Medit `.mesh` written by `necklace volume MESH -o OUT.mesh` (vertex kind 0 is an
interior vertex, the heat system's unknowns) and prints, per half-octave of the longest
incident edge relative to the lattice spacing h (the `h` of `necklace volume --json`),
how many interior vertices fall there. Standard library only.

    python3 scripts/cell-sizes.py OUT.mesh H
"""
import collections
import math
import sys


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: cell-sizes.py OUT.mesh H")
    path, h = sys.argv[1], float(sys.argv[2])
    with open(path) as f:
        lines = f.read().split("\n")
    start = lines.index("Vertices")
    count = int(lines[start + 1])
    positions, kinds = [], []
    for line in lines[start + 2 : start + 2 + count]:
        fields = line.split()
        positions.append(tuple(map(float, fields[:3])))
        kinds.append(int(fields[3]))
    start = lines.index("Tetrahedra")
    longest = [0.0] * count
    for line in lines[start + 2 : start + 2 + int(lines[start + 1])]:
        tet = [int(x) - 1 for x in line.split()[:4]]
        for a in range(4):
            for b in range(a + 1, 4):
                u, v = tet[a], tet[b]
                d = math.dist(positions[u], positions[v])
                longest[u] = max(longest[u], d)
                longest[v] = max(longest[v], d)
    bins = collections.Counter(
        round(2 * math.log2(longest[v] / h)) / 2 for v in range(count) if kinds[v] == 0
    )
    interior = sum(bins.values())
    print(f"{interior} interior vertices of {count}; longest edge / h:")
    for b in sorted(bins):
        print(f"  2^{b:+.1f}\t{bins[b]}")


if __name__ == "__main__":
    main()
