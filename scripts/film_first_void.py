#!/usr/bin/env python3
"""Refinement study of the stressed film's first void (dev-only; stdlib only).

For each resolution, runs the paper's scenario (L = 1, H = 0.5, g = x, a cos 2πx
perturbation of amplitude 0.02) with `shapeflow run` up to END, finds the first
iteration with a closed void in energy.csv, re-runs exactly that many iterations
(the run is deterministic) and reports the void's time, area, height and the rise
of J at the reconnection.

    cargo build --release
    python3 scripts/film_first_void.py --gamma 0.24 --end 0.0132 64 96 128 192

Measured (docs/problems/stressed-film.md), gamma 0.24, 64/96/128/192 vertices:
  t      0.013152  0.012715  0.012544  0.012412
  area   2.06e-3   1.01e-3   6.71e-4   4.11e-4
  height 0.132     0.104     0.087     0.080
The height converges, the mean width (area / height) is about 1/n, the initial
segment length: the void is the bottom of a crack, one segment wide.
gamma 0.2 (--end 0.0072), 64/96/128: t 0.007003, 0.006766, 0.006665; area 9.74e-4,
5.68e-4, 3.76e-4; height 0.110, 0.086, 0.071.
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def spec(gamma, n, end, max_iterations=None, bending=0.0):
    flow = {"tau": 1e-5, "end_time": end, "max_iterations": max_iterations or 1_000_000, "tolerance": 0}
    problem = {"type": "stressed_film", "length": 1.0, "gamma": gamma, "boundary": {"type": "x"}}
    if bending:
        problem["bending"] = bending
    return {
        "problem": problem,
        "initial": {"shape": "film", "height": 0.5, "amplitude": 0.02, "mode": 1, "resolution": n},
        "flow": flow,
        "output": {"checkpoint_every": 1_000_000},
    }


def run(binary, s, out):
    path = out + ".json"
    with open(path, "w") as f:
        json.dump(s, f)
    subprocess.run([binary, "run", path, "--out", out], check=True, stdout=subprocess.DEVNULL)


def area(v):
    return 0.5 * sum(v[k][0] * v[(k + 1) % len(v)][1] - v[(k + 1) % len(v)][0] * v[k][1] for k in range(len(v)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gamma", type=float, default=0.2)
    ap.add_argument("--bending", type=float, default=0.0, help="epsilon of the bending energy (an addition)")
    ap.add_argument("--end", type=float, default=0.0072, help="end time, a little past the first void")
    ap.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "shapeflow"))
    ap.add_argument("resolutions", type=int, nargs="+")
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="film_first_void_")
    print(f"# gamma {a.gamma}, bending {a.bending}; runs in {work}")
    print("vertices  iteration  time        area        y_min   y_max   J rise")
    for n in a.resolutions:
        out = os.path.join(work, f"n{n}")
        run(a.binary, spec(a.gamma, n, a.end, bending=a.bending), out)
        rows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
        k = next((i for i, r in enumerate(rows) if int(r["components"]) >= 2), None)
        if k is None:
            print(f"{n:8d}  no void before t = {a.end}")
            continue
        it = int(rows[k]["iteration"])
        rise = float(rows[k]["energy"]) - float(rows[k - 1]["energy"])
        run(a.binary, spec(a.gamma, n, a.end, it, a.bending), out + "_void")
        shape = json.load(open(os.path.join(out + "_void", "shape.json")))
        for c in shape["components"][1:]:
            ys = [p[1] for p in c["vertices"]]
            print(f"{n:8d}  {it:9d}  {float(rows[k]['time']):.6f}  {area(c['vertices']):.4e}  "
                  f"{min(ys):.4f}  {max(ys):.4f}  {rise:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
