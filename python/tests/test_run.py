"""shapeflow.run: arrays in and out, the CLI's files, progress, Ctrl-C and errors."""

import _thread
import json
import signal
import subprocess
import threading
import time

import numpy as np
import pytest
import skimage.io
import skimage.measure

import shapeflow
from conftest import discs_image

SEGMENT = {"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"max_iterations": 300}}


@pytest.mark.parametrize("seed", [1, 2])
def test_labels_equal_the_clis(cli, workdir, seed):
    img = discs_image(seed)
    png = workdir / "image.png"
    skimage.io.imsave(png, img, check_contrast=False)
    spec = workdir / "spec.json"
    spec.write_text(json.dumps(SEGMENT))
    subprocess.run([cli, "run", str(spec), "--out", str(workdir / "cli"), "--input", f"image={png}"], check=True,
                   stdout=subprocess.DEVNULL)
    r = shapeflow.run(SEGMENT, {"image": img})
    cli_labels = skimage.io.imread(workdir / "cli/labels.png")
    assert r.labels.dtype == np.uint16 and r.labels.shape == img.shape
    assert np.array_equal(r.labels, cli_labels)
    assert r.labels.max() == 5, "the five discs"
    # the same from the file's bytes and from its path
    assert np.array_equal(shapeflow.run(SEGMENT, {"image": str(png)}).labels, cli_labels)


def test_objects_are_regionprops_of_the_labels():
    r = shapeflow.run(SEGMENT, {"image": discs_image(3)})
    props = skimage.measure.regionprops_table(r.labels, properties=("label", "area", "centroid", "bbox"))
    for name, column in props.items():
        assert np.allclose(r.objects[name], column), name
    # shapeflow's own sub-pixel measures, beside them: close to the pixel counts
    assert np.allclose(r.objects["area_subpixel"], r.objects["area"], rtol=0.08)
    assert np.allclose(r.objects["centroid_subpixel-0"], r.objects["centroid-0"], atol=0.6)
    # vertices in (row, column) pixels: each object's contour surrounds its centroid
    assert r.vertices.shape[1] == 2 and r.segments.shape[1] == 2
    assert r.mask.shape == r.labels.shape and r.mask.dtype == bool
    assert (r.mask == (r.labels > 0)).mean() > 0.995


def test_progress_rises_while_another_thread_runs():
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    seen = []
    spec = {
        "problem": {"type": "curvature_flow", "gamma": 1.0, "lambda": 0.0},
        "initial": {"shape": "circle", "center": [0.0, 0.0], "radius": 1.0, "resolution": 512},
        "flow": {"tau": 1e-5, "end_time": 0.05, "max_iterations": 100000, "tolerance": 0},
        "output": {"checkpoint_every": 500},
    }
    t = threading.Thread(target=ticker)
    t.start()
    r = shapeflow.run(spec, progress=lambda p: seen.append((p["iteration"], p["time"], p["energy"], len(ticks))))
    stop.set()
    t.join()
    assert r.stop_reason == "end_time"
    assert len(seen) >= 5
    iterations = [s[0] for s in seen]
    assert iterations == sorted(iterations) and len(set(iterations)) == len(iterations)
    # the other thread ran between the callbacks: the GIL was released during the run
    assert seen[-1][3] - seen[0][3] > 10
    # the history: energy of a shrinking circle decreases, time rises to end_time
    assert np.all(np.diff(r.energy["energy"]) <= 0)
    assert abs(r.energy["time"][-1] - 0.05) < 1e-9


def test_ctrl_c_stops_a_long_run():
    spec = {
        "problem": {"type": "curvature_flow", "gamma": 1.0, "lambda": 0.0},
        "initial": {"shape": "circle", "center": [0.0, 0.0], "radius": 1.0, "resolution": 2000},
        "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 10000000, "tolerance": 0},
        "output": {"checkpoint_every": 100},
    }
    started = time.perf_counter()

    def not_stopped(_):
        # a run that Ctrl-C did not stop ends here, not hours later
        if time.perf_counter() - started > 30:
            raise RuntimeError("Ctrl-C did not stop the run within 30 s")

    # Ctrl-C as an interactive Python has it: a process started in the background
    # by a shell inherits SIGINT ignored, and then Python installs no handler
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Timer(0.5, _thread.interrupt_main).start()
        with pytest.raises(KeyboardInterrupt):
            shapeflow.run(spec, progress=not_stopped)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert time.perf_counter() - started < 10


def test_bad_specs_name_the_field():
    with pytest.raises(shapeflow.SpecError) as e:
        shapeflow.run({"problem": {"type": "curvature_flow", "gamma": -1, "lambda": 0}})
    assert e.value.field == "problem.gamma"
    with pytest.raises(shapeflow.SpecError) as e:
        shapeflow.run('{"problem": {"type": "curvature_flow", "gamma": 1, "lambda": 0}, "flow": {"tau": "x"}}')
    assert e.value.field.startswith("flow.tau")
    with pytest.raises(shapeflow.SpecError) as e:
        shapeflow.run(SEGMENT, {"image": np.zeros((4, 4, 4, 4), np.uint8)})
    assert e.value.field == "inputs['image']"
    with pytest.raises(shapeflow.SpecError) as e:
        shapeflow.run(SEGMENT, {"picture": discs_image(0)})
    assert e.value.field == "problem.image"
    with pytest.raises(shapeflow.SpecError) as e:
        shapeflow.run(SEGMENT, {"image": "/no/such/file.png"})
    assert "cannot read" in e.value.message
