#!/usr/bin/env python3
"""Dev-only: a worst case for the curve intersection check (BENCHMARKS.md, "Mesh
management per step", dense cells). A polygon whose comb of 2·T tiny teeth (each
going back before it goes on, so no run of segments is monotone) lies beside two
edges of length 1e4 that set the mean segment length, hence the cell size: the
whole comb falls in one cell. Writes a curvature_flow spec of one tiny step.

    scripts/comb_polygon.py 30000 > comb.json
    time target/release/shapeflow run comb.json --out out/comb
"""
import json
import sys

teeth = int(sys.argv[1]) if len(sys.argv) > 1 else 30000
s = 1.0 / teeth
points = []
for j in range(teeth):
    x = 1.0 - j * s
    points += [[round(x, 9), 0.0], [round(x + 0.3 * s, 9), 1e-4]]
points += [[0.0, -1e-4], [0.0, -1e4], [1.0, -1e4]]
spec = {
    "problem": {"type": "curvature_flow"},
    "initial": {"shape": "polygon", "points": points[::-1]},
    "flow": {"max_iterations": 1, "tau": 1e-12},
    "mesh": {"regularize": False, "adapt": False, "topology_changes": False},
}
json.dump(spec, sys.stdout)
