"""Dev-only benchmark: shapeflow.run from Python beside the CLI on the same jobs
(the same build profile for both), and the time of writing the VTK files.
Usage: python scripts/bench_python.py [path/to/shapeflow]   (results: BENCHMARKS.md)"""
import json, re, subprocess, sys, tempfile, time, pathlib
import numpy as np, skimage.io
import shapeflow

repo = pathlib.Path(__file__).resolve().parents[1]
cli = sys.argv[1] if len(sys.argv) > 1 else str(repo / "target/debug/shapeflow")
jobs = [
    ("circle (curvature flow, 2500 steps)", "examples/circle.json", {}),
    ("segment_four (2D image)", "examples/segment_four.json", {"image": "examples/data/four.png"}),
    ("segment_balls (3D volume)", "examples/segment_balls.json", {"volume": "examples/data/balls.nrrd"}),
]
print("| job | CLI prepare + run (s) | Python run (s) | ratio | all result files from Python (s) |\n|---|---|---|---|---|")
for name, spec, inputs in jobs:
    best_cli, best_py, best_vtk = 1e9, 1e9, 1e9
    for _ in range(3):
        with tempfile.TemporaryDirectory() as out:
            args = [cli, "run", str(repo / spec), "--out", out]
            for k, v in inputs.items():
                args += ["--input", f"{k}={repo / v}"]
            text = subprocess.run(args, check=True, capture_output=True, text=True).stdout
            m = re.search(r"took ([0-9.]+) s to prepare .*?, ([0-9.]+) s to run", text)
            ran = float(m.group(1)) + float(m.group(2))
            best_cli = min(best_cli, ran)
        arrays = {k: (skimage.io.imread(repo / v) if v.endswith(".png") else str(repo / v)) for k, v in inputs.items()}
        t = time.perf_counter()
        r = shapeflow.run(json.loads((repo / spec).read_text()), arrays)
        best_py = min(best_py, time.perf_counter() - t)
        t = time.perf_counter()
        files = r._run.files("bench")
        vtk = [f for f in files if f[0].endswith((".vtp", ".pvd", "vtk.zip"))]
        best_vtk = min(best_vtk, time.perf_counter() - t)
    print(f"| {name} | {best_cli:.3f} | {best_py:.3f} | {best_py / best_cli:.3f} | {best_vtk:.3f} (of them {len(vtk)} VTK) |")
