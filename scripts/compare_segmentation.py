#!/usr/bin/env python3
"""Dev-only: shapeflow segmentation at defaults beside established active-contour
tools with tuned parameters, measured in one run (BENCHMARKS.md, "Segmentation of
real images").

Needs: numpy, scipy, scikit-image, SimpleITK, tifffile, Pillow (pip), and a release
build (`cargo build --release`). Usage:

    python3 scripts/compare_segmentation.py [--quick] [--held-out | --volumes]

Images: tests/data/nuclei.png with its manual annotation (Dice and object count),
tests/data/coins.png (count only: 24 coins, no annotation), tests/data/cell.png (a
quantitative phase image; its truth is the disc through the cell's half-maximum
edge, as in tests/engine/real_images/), two synthetic pictures with known masks
generated here (the twelve discs of different contrast on an illumination
gradient, and the five-armed star at SNR 2), and a 3D brain MR: the ICBM152 2009a
T1 template (skull-stripped) that ships in the nilearn wheel, averaged over 4×4×4
voxels (47×58×49 at 4 mm), against its grey plus white matter (probability sum
> 0.5, from the same wheel). The wheel is downloaded with pip into
target/compare-data (its data's licence is not stated there, so it is not kept in
tests/data); without network the volume is left out. Then stardist's synthetic
nuclei volume (57×61×31) with its 51 labels, from the stardist wheel downloaded the
same way. `--volumes` runs these two alone.

Peers, each tuned over a small grid on each image (the best Dice is reported, with
the time of that run; the count of 4-connected components of its mask):
scikit-image morphological geodesic active contour (MGAC) and morphological
Chan-Vese (MCV), scikit-image Chan-Vese, SimpleITK geodesic active contour
(seeded by an Otsu mask, as its documentation does). shapeflow runs the CLI on the
file with the spec `{"problem": {"type": "segmentation", "image": "input:image"}}`;
its time is the whole process (decoding, preparation, run, writing all results),
and in brackets the segmentation alone as the CLI reports it (decoding and
preprocessing the image, the initial shape and the run: what the peers' times
hold, and more).

After the first table, a table of what the 5× speed target leaves shapeflow on
each image (a fifth of the fastest tuned peer's time) beside shapeflow's whole
process stopped after its first step (`flow.max_iterations` 1: decoding,
preprocessing, the initial shape, one step, every result file), measured in the
same run.

A second table repeats the star at SNR 2 over ten draws of its noise (seeds
2–11; seed 2 is the image of the first table): at this noise a single draw moves
Dice by ±0.002, more than the methods differ. Each peer is tuned on each draw
(its best Dice over the grid on that draw).

A third table holds synthetic pictures that neither the tests nor the defaults
were tuned on (`--held-out` runs it alone): shapes at SNR 2 (contrast 130, noise
65) and a few other kinds, each with its truth, shapeflow at defaults beside
each peer's best Dice over its grid (and that run's component count).
"""
import itertools
import json
import pathlib
import re
import subprocess
import sys
import tempfile
import time

import gzip
import zipfile

import numpy as np
import SimpleITK as sitk
from PIL import Image
from scipy import ndimage as ndi
from skimage import filters, measure, segmentation

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = ROOT / "target" / "release" / "shapeflow"
QUICK = "--quick" in sys.argv


def dice(a, b):
    return 2 * (a & b).sum() / (a.sum() + b.sum())


def hausdorff(a, b):
    """Symmetric Hausdorff distance (pixels) between the boundaries of two masks."""
    if not a.any() or not b.any():
        return float("inf")
    ba = a & ~ndi.binary_erosion(a)
    bb = b & ~ndi.binary_erosion(b)
    da = ndi.distance_transform_edt(~bb)
    db = ndi.distance_transform_edt(~ba)
    return max(da[ba].max(), db[bb].max())


def components(m):
    return measure.label(m, connectivity=1).max()


def discs():
    h = w = 192
    yy, xx = np.mgrid[0:h, 0:w] + 0.5
    rng = np.random.default_rng(1)
    v = 30 + 0.15 * xx
    truth = np.zeros((h, w), bool)
    spec = [(24 + 36 * (k % 5), 40 + 90 * (k // 5), 11, [40, 80, 140][k % 3]) for k in range(10)]
    spec += [(42, 86, 10, 60), (62, 86, 10, 130)]
    for cx, cy, r, a in spec:
        m = (np.hypot(xx - cx, yy - cy) < r) & ~truth
        v = v + a * m
        truth |= m
    img = np.clip(np.round(v + 6 * rng.standard_normal((h, w))), 0, 255).astype(np.uint8)
    return img, truth


def star_snr2(seed=2):
    yy, xx = np.mgrid[0:128, 0:128] + 0.5
    dx, dy = xx - 64, yy - 64
    truth = np.hypot(dx, dy) < 34 * (1 + 0.3 * np.cos(5 * np.arctan2(dy, dx)))
    rng = np.random.default_rng(seed)
    img = np.clip(np.round(60 + 130 * truth + 65 * rng.standard_normal(truth.shape)), 0, 255).astype(np.uint8)
    return img, truth


def cell():
    img = np.array(Image.open(ROOT / "tests/data/cell.png"))
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]] + 0.5
    return img, np.hypot(xx - 427.5, yy - 373.75) < 63.0


def brain():
    """The ICBM152 2009a T1 template at 4 mm and its grey + white matter, or None."""
    data = ROOT / "target" / "compare-data"
    data.mkdir(parents=True, exist_ok=True)
    wheels = sorted(data.glob("nilearn-*.whl"))
    if not wheels:
        r = subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "nilearn==0.14.1", "-d", str(data)],
                           capture_output=True)
        wheels = sorted(data.glob("nilearn-*.whl"))
        if r.returncode != 0 or not wheels:
            print("(the brain MR is left out: the nilearn wheel could not be downloaded)", file=sys.stderr)
            return None
    arrays = {}
    with zipfile.ZipFile(wheels[-1]) as z:
        for kind in ["t1", "gm", "wm"]:
            raw = z.read(f"nilearn/datasets/data/mni_icbm152_{kind}_tal_nlin_sym_09a_converted.nii.gz")
            path = data / f"{kind}.nii.gz"
            path.write_bytes(raw)
            arrays[kind] = sitk.GetArrayFromImage(sitk.ReadImage(str(path))).astype(float)

    def block(a, f=4):
        z, y, x = (n // f * f for n in a.shape)
        return a[:z, :y, :x].reshape(z // f, f, y // f, f, x // f, f).mean((1, 3, 5))

    t1 = np.round(block(arrays["t1"])).astype(np.uint8)
    return t1, block((arrays["gm"] + arrays["wm"]) / 255.0) > 0.5


def nuclei3d():
    """stardist's synthetic nuclei volume (57×61×31, 51 labelled nuclei) with its
    labels, from the stardist wheel (BSD-3-Clause) downloaded into
    target/compare-data, or None."""
    data = ROOT / "target" / "compare-data"
    data.mkdir(parents=True, exist_ok=True)
    wheels = sorted(data.glob("stardist-*.whl"))
    if not wheels:
        subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "stardist==0.9.2", "-d", str(data)],
                       capture_output=True)
        wheels = sorted(data.glob("stardist-*.whl"))
        if not wheels:
            print("(the nuclei volume is left out: the stardist wheel could not be downloaded)", file=sys.stderr)
            return None
    import io
    import tifffile
    with zipfile.ZipFile(wheels[-1]) as z:
        img = tifffile.imread(io.BytesIO(z.read("stardist/data/images/img3d.tif")))
        labels = tifffile.imread(io.BytesIO(z.read("stardist/data/images/mask3d.tif")))
    return img, labels > 0, len(np.unique(labels)) - 1


def volumes():
    b = brain()
    if b is not None:
        yield "brain MR, T1 (47×58×49, 4 mm)", b[0], b[1], 1
    n = nuclei3d()
    if n is not None:
        yield "nuclei volume (57×61×31, 51 labelled)", n[0], n[1], n[2]


def images():
    nuclei = np.array(Image.open(ROOT / "tests/data/nuclei.png"))
    labels = np.array(Image.open(ROOT / "tests/data/nuclei_labels.png"))
    yield "nuclei (512², 125 annotated)", nuclei, labels > 0, len(np.unique(labels)) - 1
    coins = np.array(Image.open(ROOT / "tests/data/coins.png"))
    yield "coins (384×303, 24 coins)", coins, None, 24
    img, truth = discs()
    yield "12 discs, contrast 40–140, gradient", img, truth, 12
    img, truth = star_snr2()
    yield "star at SNR 2 (128²)", img, truth, 1
    img, truth = cell()
    yield "cell, phase image (550×660)", img, truth, 1
    yield from volumes()


def shapeflow(img, flow=None):
    """shapeflow at defaults on `img` (with `flow` as the spec's `flow`, if given):
    its mask, (whole process, segmentation alone) in seconds, and its object count."""
    with tempfile.TemporaryDirectory() as d:
        d = pathlib.Path(d)
        if img.ndim == 2:
            path = d / "image.png"
            Image.fromarray(img).save(path)
        else:
            # NIfTI keeps the array's axis order (x fastest); the mask comes back
            # as NRRD in the same order
            path = d / "image.nii.gz"
            sitk.WriteImage(sitk.GetImageFromArray(img), str(path))
        spec = {"problem": {"type": "segmentation", "image": "input:image"}}
        if flow is not None:
            spec["flow"] = flow
        (d / "spec.json").write_text(json.dumps(spec))
        t = time.perf_counter()
        r = subprocess.run([str(BIN), "run", str(d / "spec.json"), "--input", f"image={path}", "--out", str(d / "out")],
                           check=True, capture_output=True, text=True)
        elapsed = time.perf_counter() - t
        # the CLI's last line: "took P s to prepare (...), R s to run, W s to write the results"
        took = re.search(r"took ([\d.]+) s to prepare .*?, ([\d.]+) s to run", r.stdout)
        if img.ndim == 2:
            mask = np.array(Image.open(d / "out/mask.png")) > 0
        else:
            raw = (d / "out/mask.nrrd").read_bytes().partition(b"\n\n")[2]
            mask = np.frombuffer(gzip.decompress(raw), np.uint8).reshape(img.shape) > 0
        objects = len(json.loads((d / "out/shape.json").read_text())["objects"])
    return mask, (elapsed, float(took[1]) + float(took[2])), objects


def normalized(img):
    lo, hi = np.percentile(img, [0.5, 99.5])
    return np.clip((img.astype(float) - lo) / (hi - lo), 0, 1)


def polarity_fix(mask):
    """Level-set peers do not know which phase is the object: take the phase that
    covers less of the border."""
    border = np.concatenate([np.moveaxis(mask, a, 0)[i].ravel() for a in range(mask.ndim) for i in (0, -1)])
    return ~mask if border.mean() > 0.5 else mask


def peers(img):
    u = normalized(img)
    iters = [100] if QUICK else [100, 300]
    for sigma, alpha, balloon, it in itertools.product([1, 2], [100, 400], [-1, 1], iters):
        gimage = segmentation.inverse_gaussian_gradient(u, alpha=alpha, sigma=sigma)
        init = np.zeros(u.shape, np.int8)
        if balloon < 0:
            init[(slice(2, -2),) * u.ndim] = 1
        else:
            init = segmentation.checkerboard_level_set(u.shape, 6).astype(np.int8)
        t = time.perf_counter()
        m = segmentation.morphological_geodesic_active_contour(gimage, it, init, smoothing=1, balloon=balloon) > 0
        yield "skimage MGAC", dict(sigma=sigma, alpha=alpha, balloon=balloon, iterations=it), polarity_fix(m), time.perf_counter() - t
    for smoothing, lam, it in itertools.product([0, 1, 2], [1, 2], iters):
        t = time.perf_counter()
        m = segmentation.morphological_chan_vese(u, it, init_level_set="checkerboard", smoothing=smoothing, lambda1=1, lambda2=lam) > 0
        yield "skimage MCV", dict(smoothing=smoothing, lambda2=lam, iterations=it), polarity_fix(m), time.perf_counter() - t
    for mu in ([] if u.ndim == 3 else [0.1] if QUICK else [0.05, 0.1, 0.25]):
        t = time.perf_counter()
        m = segmentation.chan_vese(u, mu=mu, max_num_iter=200, tol=1e-3)
        yield "skimage Chan-Vese", dict(mu=mu), polarity_fix(np.asarray(m, bool)), time.perf_counter() - t
    seed = filters.gaussian(u, 1) > filters.threshold_otsu(filters.gaussian(u, 1))
    levelset0 = sitk.SignedMaurerDistanceMap(sitk.GetImageFromArray(seed.astype(np.uint8)), insideIsPositive=False,
                                             useImageSpacing=True)
    for sigma, k, prop, curv in itertools.product([1.0, 2.0], [0.02, 0.05, 0.1], [-1.0, 1.0], [0.5, 2.0]):
        t = time.perf_counter()
        grad = np.sqrt(sum(g * g for g in np.gradient(filters.gaussian(u, sigma))))
        speed = sitk.GetImageFromArray((1.0 / (1.0 + (grad / k) ** 2)).astype(np.float32))
        gac = sitk.GeodesicActiveContourLevelSetImageFilter()
        gac.SetPropagationScaling(prop)
        gac.SetCurvatureScaling(curv)
        gac.SetAdvectionScaling(1.0)
        gac.SetMaximumRMSError(0.01)
        gac.SetNumberOfIterations(200 if QUICK else 400)
        out = gac.Execute(sitk.Cast(levelset0, sitk.sitkFloat32), speed)
        m = sitk.GetArrayFromImage(out) < 0
        yield "SimpleITK GAC", dict(sigma=sigma, k=k, propagation=prop, curvature=curv), polarity_fix(m), time.perf_counter() - t


def tuned_peers(img, truth, count):
    """Each peer's best run over its grid on `img`: method → (score, parameters,
    mask, time); the score is Dice against `truth`, or without one the closeness of
    its component count to `count`."""
    best = {}
    for method, params, m, t in peers(img):
        score = dice(m, truth) if truth is not None else -abs(components(m) - count)
        if method not in best or score > best[method][0]:
            best[method] = (score, params, m, t)
    return best


def main(only_volumes=False):
    print("| image | method | Dice | Hausdorff (px) | objects (truth) | time (s) | parameters |")
    print("|---|---|---|---|---|---|---|")
    floors = []
    for name, img, truth, count in (volumes() if only_volumes else images()):
        mask, elapsed, objects = shapeflow(img)
        # the same process stopped after its first step: decoding, preprocessing,
        # the initial shape, one step and every result file
        _, one_step, _ = shapeflow(img, {"max_iterations": 1})
        fmt = lambda m: ("%.4f" % dice(m, truth), "%.1f" % hausdorff(m, truth)) if truth is not None else ("—", "—")
        d, h = fmt(mask)
        print(f"| {name} | shapeflow, defaults | {d} | {h} | {objects} ({count}) | {elapsed[0]:.3f} ({elapsed[1]:.3f}) | — |")
        tuned = tuned_peers(img, truth, count)
        for method, (_, params, m, t) in tuned.items():
            d, h = fmt(m)
            p = ", ".join(f"{k} {v}" for k, v in params.items())
            print(f"| {name} | {method}, tuned | {d} | {h} | {components(m)} ({count}) | {t:.3f} | {p} |")
        fastest = min(tuned.items(), key=lambda kv: kv[1][3])
        floors.append((name, fastest[0], fastest[1][3], elapsed[0], one_step[0]))
        sys.stdout.flush()
    budget_table(floors)
    if only_volumes:
        return
    star_draws(3 if QUICK else 10)
    held_out()


def budget_table(floors):
    """What the 5× target leaves shapeflow on each image (a fifth of the fastest
    peer's segmentation), beside its whole process stopped after one step."""
    print()
    print("| image | fastest peer (s) | 5× budget (s) | shapeflow, one step (s) | shapeflow, defaults (s) | one step / budget |")
    print("|---|---|---|---|---|---|")
    for name, method, t, whole, one in floors:
        print(f"| {name} | {method} {t:.3f} | {t / 5:.3f} | {one:.3f} | {whole:.3f} | {one / (t / 5):.1f} |")
    sys.stdout.flush()


def held_out_pictures():
    """Synthetic pictures with known masks that the defaults were not tuned on:
    (name, image, truth, object count)."""
    n = 160
    yy, xx = np.mgrid[0:n, 0:n] + 0.5
    dx, dy = xx - n / 2, yy - n / 2
    r, th = np.hypot(dx, dy), np.arctan2(dy, dx)
    shapes = [
        ("seven-armed star", r < 0.3 * n * (1 + 0.25 * np.cos(7 * th)), 1),
        ("ellipse", (dx / (0.35 * n)) ** 2 + (dy / (0.18 * n)) ** 2 < 1, 1),
        ("square", (np.abs(dx) < 0.25 * n) & (np.abs(dy) < 0.25 * n), 1),
        ("ring (hole a fifth of the disc)", (r < 0.33 * n) & (r > 0.15 * n), 1),
        ("two discs", (np.hypot(dx - 0.2 * n, dy) < 0.14 * n) | (np.hypot(dx + 0.22 * n, dy + 0.1 * n) < 0.11 * n), 2),
    ]
    rng = np.random.default_rng(5)
    for name, truth, count in shapes:
        img = 60 + 130 * truth + 65 * rng.standard_normal(truth.shape)
        yield f"{name}, SNR 2 (160²)", np.clip(np.round(img), 0, 255).astype(np.uint8), truth, count
    truth = r < 0.3 * n * (1 + 0.3 * np.cos(5 * th))
    img = 190 - 130 * truth + 65 * rng.standard_normal(truth.shape)
    yield "dark five-armed star on a bright ground, SNR 2 (160²)", np.clip(np.round(img), 0, 255).astype(np.uint8), truth, 1
    m = 192
    yy, xx = np.mgrid[0:m, 0:m] + 0.5
    truth = (np.hypot(xx, yy - 96) < 50) | (np.hypot(xx - 150, yy - 192) < 40)
    img = 60 + 130 * truth + 50 * rng.standard_normal(truth.shape)
    yield "two discs cut by the image's edges, noise 50 (192²)", np.clip(np.round(img), 0, 255).astype(np.uint8), truth, 2
    a, b = np.hypot(xx - 60, yy - 96) < 30, np.hypot(xx - 135, yy - 96) < 30
    img = 60 + 160 * a + 50 * b + 12 * rng.standard_normal(a.shape)
    yield "two discs of contrast 160 and 50, noise 12 (192²)", np.clip(np.round(img), 0, 255).astype(np.uint8), a | b, 2
    truth = np.zeros((m, m), bool)
    for cy in range(20, m - 10, 34):
        for cx in range(20, m - 10, 34):
            c = np.hypot(xx - cx - rng.uniform(-4, 4), yy - cy - rng.uniform(-4, 4))
            truth |= c < 4 + (cx + cy) % 5
    img = 60 + 130 * truth + 40 * rng.standard_normal(truth.shape)
    yield "25 small discs (radius 4–8 px), noise 40 (192²)", np.clip(np.round(img), 0, 255).astype(np.uint8), truth, 25
    # the split of touching objects: one object with narrow parts, and touching
    # pairs of radii 15:15, 15:10 and 16:8
    k = 200
    yy, xx = np.mgrid[0:k, 0:k] + 0.5

    def capsule(x0, y0, x1, y1, radius):
        px, py, ex, ey = xx - x0, yy - y0, x1 - x0, y1 - y0
        t = np.clip((px * ex + py * ey) / (ex * ex + ey * ey), 0, 1)
        return np.hypot(px - t * ex, py - t * ey) < radius

    hand = np.hypot(xx - 100, yy - 120) < 40
    for angle, length, radius in [(-150, 55, 8), (-115, 65, 7), (-90, 70, 7), (-65, 65, 7), (-35, 50, 6)]:
        c, s_ = np.cos(np.radians(angle)), np.sin(np.radians(angle))
        hand |= capsule(100 + 30 * c, 120 + 30 * s_, 100 + (30 + length) * c, 120 + (30 + length) * s_, radius)
    cell = np.hypot(xx - 100, yy - 100) < 30
    for angle in [20, 140, 260]:
        c, s_ = np.cos(np.radians(angle)), np.sin(np.radians(angle))
        cell |= capsule(100, 100, 100 + 70 * c, 100 + 70 * s_, 2.5) | (np.hypot(xx - 100 - 70 * c, yy - 100 - 70 * s_) < 6)
    pairs = np.zeros((k, k), bool)
    for (x0, y0, r0), (x1, y1, r1) in [((60, 60, 15), (86, 60, 15)), ((130, 60, 15), (153, 60, 10)),
                                         ((80, 150, 16), (103, 150, 8))]:
        pairs |= (np.hypot(xx - x0, yy - y0) < r0) | (np.hypot(xx - x1, yy - y1) < r1)
    for name, truth, count in [("a hand (palm and five fingers)", hand, 1),
                               ("a cell with three thin processes ending in knobs", cell, 1),
                               ("three touching pairs, radii 15:15, 15:10, 16:8", pairs, 6)]:
        img = 60 + 110 * truth + 40 * rng.standard_normal(truth.shape)
        yield f"{name}, noise 40 (200²)", np.clip(np.round(img), 0, 255).astype(np.uint8), truth, count


def held_out():
    """shapeflow at defaults and each peer's best Dice on the held-out pictures."""
    print()
    print("Synthetic pictures held out from the tests and the defaults' tuning:")
    print()
    names = ["skimage MGAC", "skimage MCV", "skimage Chan-Vese", "SimpleITK GAC"]
    print("| picture | shapeflow, defaults | " + " | ".join(f"{k}, tuned" for k in names) + " |")
    print("|---|---|" + "---|" * len(names))
    for name, img, truth, count in held_out_pictures():
        mask, _, objects = shapeflow(img)
        best = tuned_peers(img, truth, count)
        cells = [f"{best[k][0]:.4f} ({components(best[k][2])})" for k in names]
        print(f"| {name}, {count} object{'s' if count > 1 else ''} | {dice(mask, truth):.4f} ({objects}) | "
              + " | ".join(cells) + " |")
        sys.stdout.flush()


def star_draws(n):
    """The star at SNR 2 over `n` draws of its noise: mean, lowest and highest Dice
    of shapeflow at defaults and of each peer tuned on each draw, and on how many
    draws shapeflow's Dice is at least the peer's."""
    scores = {}
    for seed in range(2, 2 + n):
        img, truth = star_snr2(seed)
        mask, _, _ = shapeflow(img)
        scores.setdefault("shapeflow, defaults", []).append(dice(mask, truth))
        for method, (d, _, _, _) in tuned_peers(img, truth, 1).items():
            scores.setdefault(method + ", tuned per draw", []).append(d)
    ours = np.array(scores["shapeflow, defaults"])
    print()
    print(f"Star at SNR 2 over {n} draws of the noise (seeds 2–{n + 1}):")
    print()
    print("| method | mean Dice | lowest | highest | draws where shapeflow's Dice ≥ this |")
    print("|---|---|---|---|---|")
    for method, v in scores.items():
        v = np.array(v)
        won = "—" if method.startswith("shapeflow") else f"{(ours >= v).sum()} of {n}"
        print(f"| {method} | {v.mean():.4f} | {v.min():.4f} | {v.max():.4f} | {won} |")


if __name__ == "__main__":
    if "--held-out" in sys.argv:
        held_out()
    else:
        main(only_volumes="--volumes" in sys.argv)
