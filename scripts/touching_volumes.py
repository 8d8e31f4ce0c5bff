#!/usr/bin/env python3
"""Dev-only: 3D segmentation of touching objects at defaults (BENCHMARKS.md,
"Touching objects in volumes").

Volumes: generated ones of eight touching pairs of balls each (radii 5–9 voxels,
the pairs overlapping by 0–2 voxels along a random direction, Gaussian noise),
seeds 1–4 (seed 1 is the test's, the others held out), optionally single objects
(`--singles`) and densely packed ellipsoids (`--dense`), and stardist's synthetic
nuclei volume (57×61×31, 51 labels; the wheel downloaded into
target/compare-data). For each: the objects shapeflow reports, how many truth
objects are matched one to one (IoU > 0.5 with one reported object), and Dice.

    python3 scripts/touching_volumes.py [--bin target/release/shapeflow] [--seeds 1,2,3,4] [--dense 1,2]

Needs numpy, scipy, tifffile (and scikit-image for --peer-distance and --resplit).
"""

import argparse
import gzip
import io
import json
import pathlib
import re
import subprocess
import sys
import tempfile
import time
import zipfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent


def pairs_volume(seed, n=64, count=8):
    """`count` touching pairs of balls in an `n`³ volume: the image (uint8) and its
    truth labels (one per ball)."""
    rng = np.random.default_rng(seed)
    z, y, x = np.mgrid[0:n, 0:n, 0:n] + 0.5
    labels = np.zeros((n, n, n), np.uint16)
    cells = [(i, j, k) for i in range(2) for j in range(2) for k in range(2)][:count]
    cell = n / 2
    for c, (i, j, k) in enumerate(cells):
        r0, r1 = rng.uniform(5.5, 9.0), rng.uniform(5.0, 9.0)
        overlap = rng.uniform(0.0, 2.0)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        gap = r0 + r1 - overlap
        centre = np.array([(i + 0.5) * cell, (j + 0.5) * cell, (k + 0.5) * cell]) + rng.uniform(-1, 1, 3)
        # the pair's midpoint between the balls' outer ends at the cell's centre
        a = centre - d * (gap / 2 + (r0 - r1) / 2)
        b = a + d * gap
        da = np.sqrt((x - a[0]) ** 2 + (y - a[1]) ** 2 + (z - a[2]) ** 2)
        db = np.sqrt((x - b[0]) ** 2 + (y - b[1]) ** 2 + (z - b[2]) ** 2)
        ina, inb = da < r0, db < r1
        # the lens between them goes to the nearer surface
        labels[ina & (~inb | (da - r0 < db - r1))] = 2 * c + 1
        labels[inb & (~ina | (db - r1 <= da - r0))] = 2 * c + 2
    img = 60 + 110 * (labels > 0) + 30 * rng.standard_normal(labels.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8), labels


def singles_volume(seed, n=64, count=8):
    """`count` single objects in an `n`³ volume, none touching another: randomly
    turned ellipsoids (semi-axes 4.5–10 voxels, up to 2.2 to 1) and, for every
    third, a bean (an ellipsoid with a ball cut out of one side, 1.5–3 voxels
    deep), with the pairs' noise. Every object must stay one."""
    rng = np.random.default_rng(1000 + seed)
    z, y, x = np.mgrid[0:n, 0:n, 0:n] + 0.5
    labels = np.zeros((n, n, n), np.uint16)
    cells = [(i, j, k) for i in range(2) for j in range(2) for k in range(2)][:count]
    cell = n / 2
    for c, (i, j, k) in enumerate(cells):
        axes = np.sort(rng.uniform(4.5, 10.0, 3))
        axes[0] = max(axes[0], axes[2] / 2.2)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        centre = np.array([(i + 0.5) * cell, (j + 0.5) * cell, (k + 0.5) * cell]) + rng.uniform(-1, 1, 3)
        p = np.stack([x - centre[0], y - centre[1], z - centre[2]], -1) @ q
        inside = ((p / axes) ** 2).sum(-1) < 1
        if c % 3 == 2:
            depth = rng.uniform(1.5, 3.0)
            r = axes[2] * 0.6
            dent = np.array([0.0, axes[1] + r - depth, 0.0])
            inside &= ((p - dent) ** 2).sum(-1) > r * r
        labels[inside] = c + 1
    img = 60 + 110 * (labels > 0) + 30 * rng.standard_normal(labels.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8), labels


def dense_volume(seed, n=48, count=70, close=0.72):
    """Densely packed ellipsoids, nuclei-like, in an `n`³ volume: up to `count`
    randomly turned ellipsoids (semi-axes 4–7 voxels) placed where their centres
    are at least `close` times the sum of their mean radii apart, so that they
    touch and overlap without necks (each sample of an overlap goes to the
    ellipsoid it lies deeper in), blurred by σ 1, each at its own brightness
    (0.7–1.3), with noise 20 on a contrast of 100. About 40 % of the volume."""
    from scipy import ndimage as ndi
    rng = np.random.default_rng(500 + seed)
    z, y, x = np.mgrid[0:n, 0:n, 0:n] + 0.5
    labels = np.zeros((n, n, n), np.uint16)
    depth = np.full((n, n, n), np.inf)
    placed = []
    for _ in range(5000):
        if len(placed) == count:
            break
        axes = rng.uniform(4.0, 7.0, 3)
        c = rng.uniform(4, n - 4, 3)
        r = axes.mean()
        if any(np.linalg.norm(c - q) < close * (r + s) for q, s in placed):
            continue
        placed.append((c, r))
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        f = np.sqrt((((np.stack([x - c[0], y - c[1], z - c[2]], -1) @ q) / axes) ** 2).sum(-1))
        inside = (f < 1) & (f < depth)
        labels[inside] = len(placed)
        depth = np.where(inside, f, depth)
    bright = rng.uniform(0.7, 1.3, labels.max() + 1)[labels]
    img = 40 + 100 * ndi.gaussian_filter((labels > 0).astype(float), 1.0) * bright
    img = img + 20 * rng.standard_normal(labels.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8), labels


def nuclei_volume():
    data = ROOT / "target" / "compare-data"
    data.mkdir(parents=True, exist_ok=True)
    wheels = sorted(data.glob("stardist-*.whl"))
    if not wheels:
        subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "stardist==0.9.2", "-d", str(data)],
                       capture_output=True)
        wheels = sorted(data.glob("stardist-*.whl"))
        if not wheels:
            return None
    import tifffile
    with zipfile.ZipFile(wheels[-1]) as z:
        img = tifffile.imread(io.BytesIO(z.read("stardist/data/images/img3d.tif")))
        labels = tifffile.imread(io.BytesIO(z.read("stardist/data/images/mask3d.tif")))
    return img, labels


def write_nrrd(path, a):
    a = np.ascontiguousarray(a, np.float32)
    head = f"NRRD0004\ntype: float\ndimension: 3\nsizes: {a.shape[2]} {a.shape[1]} {a.shape[0]}\nencoding: raw\n" \
        f"endian: little\n\n"
    path.write_bytes(head.encode() + a.astype("<f4").tobytes())


def read_nrrd(path, shape):
    head, _, raw = path.read_bytes().partition(b"\n\n")
    kind = np.uint16 if b"uint16" in head or b"unsigned short" in head else np.uint8
    if b"gzip" in head:
        raw = gzip.decompress(raw)
    return np.frombuffer(raw, kind).reshape(shape)


def run(binary, img, extra):
    with tempfile.TemporaryDirectory() as d:
        d = pathlib.Path(d)
        write_nrrd(d / "image.nrrd", img)
        spec = {"problem": {"type": "segmentation", "image": "input:image"}}
        for k, v in extra.items():
            spec.setdefault(k, {}).update(v)
        (d / "spec.json").write_text(json.dumps(spec))
        t = time.perf_counter()
        r = subprocess.run([binary, "run", str(d / "spec.json"), "--input", f"image={d / 'image.nrrd'}",
                            "--out", str(d / "out")], capture_output=True, text=True)
        elapsed = time.perf_counter() - t
        if r.returncode != 0:
            raise SystemExit(r.stderr[-2000:])
        shape = json.loads((d / "out/shape.json").read_text())
        labels = read_nrrd(d / "out/labels.nrrd", img.shape)
        stop = re.search(r"stopped: (\w+) after (\d+)", r.stdout + r.stderr)
        return labels, elapsed, f"{stop[1]} ({stop[2]} it.)" if stop else "?"


def matched(truth, found):
    """Truth objects matched one to one by a found object with IoU > 0.5."""
    n = 0
    for t in np.unique(truth)[1:]:
        m = truth == t
        ids, counts = np.unique(found[m], return_counts=True)
        best = max(((c, i) for c, i in zip(counts, ids) if i != 0), default=None)
        if best is None:
            continue
        f = found == best[1]
        if (m & f).sum() / (m | f).sum() > 0.5:
            n += 1
    return n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=str(ROOT / "target" / "release" / "shapeflow"))
    ap.add_argument("--seeds", default="1,2,3,4")
    ap.add_argument("--spec", default="{}", help="extra spec sections, as JSON")
    ap.add_argument("--singles", default="", help="seeds of volumes of single objects, e.g. 1,2")
    ap.add_argument("--dense", default="", help="seeds of volumes of densely packed ellipsoids, e.g. 1,2")
    ap.add_argument("--no-nuclei", action="store_true")
    ap.add_argument("--peer-distance", type=float, default=0,
                    help="also run scikit-image's distance-transform watershed (Otsu's threshold of the image "
                         "smoothed with sigma 1.5, peak_local_max with this min_distance), in the same run")
    ap.add_argument("--resplit", action="store_true",
                    help="also count shapeflow's foreground split as the truth splits it (and as the peer does, "
                         "with --peer-distance): which of mask and split loses the matches")
    args = ap.parse_args()
    extra = json.loads(args.spec)
    cases = [(f"8 touching pairs, seed {s} (64³)", *pairs_volume(int(s))) for s in args.seeds.split(",") if s]
    cases += [(f"8 single objects, seed {s} (64³)", *singles_volume(int(s))) for s in args.singles.split(",") if s]
    cases += [(f"densely packed ellipsoids, seed {s} (48³)", *dense_volume(int(s))) for s in args.dense.split(",") if s]
    if not args.no_nuclei:
        n = nuclei_volume()
        if n is not None:
            cases.append(("stardist nuclei volume (57×61×31)", *n))
    print("| volume | truth objects | found | matched (IoU > 0.5) | Dice | time (s) | stop |")
    print("|---|---|---|---|---|---|---|")
    for name, img, truth in cases:
        labels, elapsed, stop = run(args.bin, img, extra)
        a, b = truth > 0, labels > 0
        dice = 2 * (a & b).sum() / (a.sum() + b.sum())
        found = len(np.unique(labels)) - 1
        print(f"| {name} | {len(np.unique(truth)) - 1} | {found} | {matched(truth, labels)} | {dice:.4f} | "
              f"{elapsed:.1f} | {stop} |", flush=True)
        ours = labels
        if args.resplit:
            print(f"| {name}, shapeflow's mask split as the truth | {len(np.unique(truth)) - 1} | "
                  f"{len(np.unique(resplit(truth, b))) - 1} | {matched(truth, resplit(truth, b))} | {dice:.4f} | — | — |")
        if args.peer_distance:
            labels, elapsed = peer_watershed(img, args.peer_distance)
            if args.resplit:
                again = resplit(labels, ours > 0)
                print(f"| {name}, shapeflow's mask split as the peer | {len(np.unique(truth)) - 1} | "
                      f"{len(np.unique(again)) - 1} | {matched(truth, again)} | {dice:.4f} | — | — |")
            dice = 2 * (a & (labels > 0)).sum() / (a.sum() + (labels > 0).sum())
            print(f"| {name}, scikit-image watershed | {len(np.unique(truth)) - 1} | {labels.max()} | "
                  f"{matched(truth, labels)} | {dice:.4f} | {elapsed:.2f} | — |", flush=True)


def resplit(labels, mask):
    """`mask` split as `labels` split theirs: `labels` inside `mask`, flooded over
    the rest of it on its distance transform."""
    from scipy import ndimage as ndi
    from skimage import segmentation
    markers = np.where(mask, labels, 0).astype(int)
    return segmentation.watershed(-ndi.distance_transform_edt(mask), markers, mask=mask)


def peer_watershed(img, min_distance):
    """The textbook split of touching objects: markers at the maxima of the
    distance transform of Otsu's threshold, flooded by a watershed."""
    from scipy import ndimage as ndi
    from skimage import feature, filters, measure, segmentation
    t = time.perf_counter()
    smooth = ndi.gaussian_filter(img.astype(float), 1.5)
    mask = smooth > filters.threshold_otsu(smooth)
    dist = ndi.distance_transform_edt(mask)
    peaks = feature.peak_local_max(dist, min_distance=int(min_distance), labels=measure.label(mask),
                                   exclude_border=False)
    markers = np.zeros(dist.shape, int)
    markers[tuple(peaks.T)] = np.arange(1, len(peaks) + 1)
    labels = segmentation.watershed(-dist, markers, mask=mask)
    return labels, time.perf_counter() - t


if __name__ == "__main__":
    main()
