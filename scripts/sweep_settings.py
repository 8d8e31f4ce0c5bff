#!/usr/bin/env python3
"""Dev-only: segmentation runs with random settings within the documented bounds
(the job spec's `problem` and `flow` sections, the initial shapes `seeds` and
`inscribed`), each run by the CLI on one of four images: a five-armed star at
SNR 2 and two balls in an anisotropic NIfTI volume (both generated into
target/sweep), the coins photograph and the horse silhouette (tests/data).

A run passes when it ends with exit 0 (any stop reason), or with exit 2 and an
error naming a spec field, or with exit 1 and a `failed:` message (a numeric
failure that ends the job with its checkpoint). Everything else is printed:
a panic, another exit code, a run over two minutes, and every exit 1 (so that
each numeric failure is looked at). At the end: the exit codes counted and the
most frequent spec errors.

    cargo build --release
    python3 scripts/sweep_settings.py [SEED] [RUNS]

Needs numpy, Pillow and SimpleITK.
"""
import collections
import json
import pathlib
import random
import subprocess
import sys

import numpy as np
import SimpleITK as sitk
from PIL import Image

ROOT = pathlib.Path(__file__).resolve().parent.parent
WORK = ROOT / "target" / "sweep"
BINARY = ROOT / "target" / "release" / "shapeflow"

PROBLEM = {
    "model": ["chan_vese", "geodesic", "both"],
    "mu": [0, 1e-4, 0.05, 1, 1000],
    "lambda_in": [0, 0.5, 1, 1000],
    "lambda_out": [0, 1, 1000],
    "means": ["per_object", "global"],
    "percentiles": [[0, 100], [0.5, 99.5], [10, 90], [50, 50]],
    "background": ["flat", "quadratic"],
    "polarity": ["bright", "dark"],
    "threshold": [0, 0.3, 1],
    "dim_threshold": [0, 0.1, 1],
    "min_size": [0, 1, 1e9],
    "split_touching": [True, False],
    "merge": [True, False],
    "sigma": [0, 0.5, 64],
    "data_sigma": [0, 3, 64],
    "lambda": [0, 1, 1000],
    "lambda_final": [0, 100],
    "epsilon": [1e-6, 10],
    "edge_contrast": [1e-6, 1, 1000],
}
FLOW = {
    "scalar_product": ["l2", "h1", "h1_newton", "h_minus_1"],
    "tau": [1e-8, 1e-3, 1, 100],
    "tolerance": [0, 1e-3],
    "backtracking": [True, False],
    "step_control": [0, 0.01, 10],
    "alpha": [0, 1000],
    "beta": [1e-6, 1000],
}


def images():
    """The four images, the generated ones written first."""
    WORK.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(1)
    y, x = np.mgrid[0:128, 0:128] + 0.5
    r, th = np.hypot(x - 64, y - 64), np.arctan2(y - 64, x - 64)
    star = r < 35 * (1 + 0.3 * np.cos(5 * th))
    img = np.clip(60 + 130 * star + 65 * rng.standard_normal(star.shape), 0, 255)
    Image.fromarray(img.astype(np.uint8)).save(WORK / "star.png")
    k, j, i = np.mgrid[0:24, 0:32, 0:32] + 0.5
    balls = (np.sqrt((i - 12) ** 2 + (j - 16) ** 2 + (k - 12) ** 2) < 7) | (
        np.sqrt((i - 22) ** 2 + (j - 16) ** 2 + (k - 12) ** 2) < 6)
    volume = sitk.GetImageFromArray((50 + 100 * balls + 10 * rng.standard_normal(balls.shape)).astype(np.float32))
    volume.SetSpacing((1, 1, 1.5))
    sitk.WriteImage(volume, str(WORK / "balls.nii.gz"))
    return [WORK / "star.png", ROOT / "tests/data/coins.png", WORK / "balls.nii.gz", ROOT / "tests/data/horse.png"]


def random_spec():
    problem = {"type": "segmentation", "image": "input:image"}
    problem.update({k: random.choice(v) for k, v in PROBLEM.items() if random.random() < 0.3})
    flow = {"max_iterations": 25}
    flow.update({k: random.choice(v) for k, v in FLOW.items() if random.random() < 0.25})
    spec = {"problem": problem, "flow": flow}
    r = random.random()
    if r < 0.15:
        spec["initial"] = {"shape": "seeds", "spacing": random.choice([3, 20, 1000]),
                           "radius": random.choice([0.5, 5, 100])}
    elif r < 0.25:
        spec["initial"] = {"shape": "inscribed"}
    return spec


def main():
    random.seed(int(sys.argv[1]) if len(sys.argv) > 1 else 0)
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    pictures = images()
    codes, errors, flagged = collections.Counter(), collections.Counter(), 0
    spec_path, out = WORK / "spec.json", WORK / "out"
    for _ in range(runs):
        picture, spec = random.choice(pictures), random_spec()
        spec_path.write_text(json.dumps(spec))
        command = [str(BINARY), "run", str(spec_path), "--input", f"image={picture}", "--out", str(out)]
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=120)
        except subprocess.TimeoutExpired:
            print("over two minutes:", picture.name, json.dumps(spec))
            flagged += 1
            continue
        text = done.stdout + done.stderr
        codes[done.returncode] += 1
        if done.returncode == 2 and "invalid spec" in text:
            errors[text.strip().splitlines()[-1].split(": ", 2)[-1][:120]] += 1
            continue
        clean = done.returncode == 0 or (done.returncode == 1 and "failed:" in text)
        if "panicked" in text or not clean or done.returncode == 1:
            last = " | ".join(line for line in text.splitlines() if line.strip())[-400:]
            print(f"exit {done.returncode}:", picture.name, json.dumps(spec))
            print("   ", last)
            flagged += 1
    print(f"{runs} runs, {flagged} printed above; exit codes {dict(codes)}")
    for message, count in errors.most_common(10):
        print(f"  {count} × {message}")


if __name__ == "__main__":
    main()
