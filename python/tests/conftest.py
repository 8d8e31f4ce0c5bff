"""Shared pieces of the Python package's tests: synthetic images (made here, with
a seed, not read from the repository), the CLI binary and a live service."""

import contextlib
import os
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def discs_image(seed=0, size=(150, 190), count=5, noise=12.0):
    """A uint8 image of `count` bright discs of random centres and radii on a dark, noisy background."""
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[0 : size[0], 0 : size[1]]
    img = np.full(size, 40.0)
    placed = []
    while len(placed) < count:
        r = rng.uniform(9, 22)
        c = rng.uniform([r + 4, r + 4], [size[0] - r - 4, size[1] - r - 4])
        if all(np.hypot(*(c - p)) > r + q + 6 for p, q in placed):
            placed.append((c, r))
            img[(rows - c[0]) ** 2 + (cols - c[1]) ** 2 <= r * r] = 190.0
    img += rng.normal(0, noise, size)
    return np.clip(img, 0, 255).astype(np.uint8)


@pytest.fixture(scope="session")
def cli():
    """The shapeflow binary: $SHAPEFLOW_BIN, else the repository's debug or release build."""
    for p in [os.environ.get("SHAPEFLOW_BIN"), REPO / "target/debug/shapeflow", REPO / "target/release/shapeflow"]:
        if p and Path(p).is_file():
            return str(p)
    pytest.skip("no shapeflow binary: run `cargo build` or set SHAPEFLOW_BIN")


@pytest.fixture()
def workdir():
    d = tempfile.mkdtemp(prefix="shapeflow-py-")
    yield Path(d)
    shutil.rmtree(d, ignore_errors=True)


@contextlib.contextmanager
def serving(cli):
    """A real `shapeflow serve` on a free loopback port with its own data directory; its URL."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    data = tempfile.mkdtemp(prefix="shapeflow-serve-")
    proc = subprocess.Popen(
        [cli, "serve", "--bind", f"127.0.0.1:{port}", "--data-dir", data],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        for _ in range(200):
            try:
                urllib.request.urlopen(url + "/readyz", timeout=1).close()
                break
            except OSError:
                time.sleep(0.05)
        else:
            pytest.fail("shapeflow serve did not become ready")
        yield url
    finally:
        proc.terminate()
        proc.wait(timeout=20)
        shutil.rmtree(data, ignore_errors=True)


@pytest.fixture(scope="session")
def service(cli):
    """A service shared by the client's tests."""
    with serving(cli) as url:
        yield url
