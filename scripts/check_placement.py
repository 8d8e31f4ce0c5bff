#!/usr/bin/env python3
"""Dev-only: volume results lie where their input does, as SimpleITK reads them.

A ball of known centre and radius in physical space, sampled on a rotated,
anisotropic grid with an origin, is written as NIfTI-1 (qform and sform) and as
NRRD (left-posterior-superior); the CLI segments each at defaults, and
SimpleITK reads mask.nrrd and mask.nii.gz back. Checked: the mask's voxel size, the physical
centroid of its voxels against the ball's centre (within half a voxel), its
volume against the ball's (within 3 %), and the input's first voxel centre
against the mask's grid, half a new voxel in.

    cargo build --release
    python3 scripts/check_placement.py

Needs numpy and SimpleITK.
"""
import math
import pathlib
import subprocess
import sys
import tempfile

import numpy as np
import SimpleITK as sitk

ROOT = pathlib.Path(__file__).resolve().parent.parent
BINARY = ROOT / "target" / "release" / "shapeflow"
SPEC = '{"problem": {"type": "segmentation", "image": "input:image"}}'


def check(mask, what, centre, radius, spacing, origin):
    """Prints the checks of one mask read by SimpleITK; returns the failures."""
    m = sitk.GetArrayFromImage(mask) > 0
    voxel = mask.GetSpacing()
    centroid = np.array(mask.TransformContinuousIndexToPhysicalPoint(np.argwhere(m).mean(0)[::-1].tolist()))
    volume = m.sum() * np.prod(voxel)
    exact = 4 / 3 * math.pi * radius**3
    first = np.array(mask.TransformContinuousIndexToPhysicalPoint((0.0, 0.0, 0.5 * spacing[2] / voxel[2] - 0.5)))
    checks = {
        "voxel size": np.allclose(voxel, min(spacing)),
        "centroid": np.linalg.norm(centroid - centre) < 0.5 * min(spacing),
        "volume": abs(volume / exact - 1) < 0.03,
        "first voxel": np.allclose(first, origin, atol=1e-4),
    }
    print(f"{what}: voxel {np.round(voxel, 3)}, centroid off by {np.linalg.norm(centroid - centre):.3f}, "
          f"volume {volume:.0f} of {exact:.0f}, first voxel {np.round(first, 3)} (input {origin}): "
          + ", ".join(f"{k} {'ok' if v else 'FAILED'}" for k, v in checks.items()))
    return sum(not v for v in checks.values())


def main():
    size, spacing, origin = (48, 40, 20), (0.8, 0.8, 2.0), (12.5, -40.0, 7.0)
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    direction = (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
    ref = sitk.Image(size, sitk.sitkFloat32)
    ref.SetSpacing(spacing)
    ref.SetOrigin(origin)
    ref.SetDirection(direction)
    centre = np.array(ref.TransformContinuousIndexToPhysicalPoint((23.0, 19.0, 9.5)))
    radius = 9.0
    # physical position of every voxel centre (array order z, y, x)
    k, j, i = np.mgrid[0 : size[2], 0 : size[1], 0 : size[0]]
    idx = np.stack([i.ravel(), j.ravel(), k.ravel()], 1).astype(float)
    d = np.array(direction).reshape(3, 3)
    phys = np.array(origin) + (idx * np.array(spacing)) @ d.T
    inside = (np.linalg.norm(phys - centre, axis=1) < radius).reshape(size[::-1])
    rng = np.random.default_rng(1)
    values = (40 + 120 * inside + 10 * rng.standard_normal(inside.shape)).astype(np.float32)
    image = sitk.GetImageFromArray(values)
    image.CopyInformation(ref)
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        spec = pathlib.Path(tmp) / "spec.json"
        spec.write_text(SPEC)
        for ext in ["nii.gz", "nrrd"]:
            path = pathlib.Path(tmp) / f"ball.{ext}"
            sitk.WriteImage(image, str(path))
            out = pathlib.Path(tmp) / f"out_{ext.replace('.', '_')}"
            run = subprocess.run([BINARY, "run", spec, "--input", f"image={path}", "--out", out],
                                 capture_output=True, text=True)
            if run.returncode != 0:
                print(f"{ext}: exit {run.returncode}: {run.stderr.strip()}")
                failures += 1
                continue
            for result in ["mask.nrrd", "mask.nii.gz"]:
                failures += check(sitk.ReadImage(str(out / result)), f"{ext} -> {result}", centre, radius, spacing, origin)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
