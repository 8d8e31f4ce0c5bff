"""shapeflow.Client against a real `shapeflow serve` on loopback."""

import io
import zipfile

import numpy as np
import pytest
import tifffile

import shapeflow
from conftest import discs_image

SEGMENT = {"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"max_iterations": 300}}


def test_submit_wait_download(service):
    client = shapeflow.Client(service)
    img = discs_image(11, count=4)
    job = client.submit(SEGMENT, {"image": img})
    seen = []
    final = client.wait(job, progress=seen.append)
    assert final["status"] == "successful", final
    assert seen and all("iteration" in p and "energy" in p for p in seen)
    names = {f["name"] for f in client.results(job)["files"]}
    assert {"shape.json", "shape.vtp", "evolution_vtk.zip", "labels.tif", "rois.zip", "objects.csv"} <= names
    labels = tifffile.imread(io.BytesIO(client.download(job, "labels.tif")))
    # the service's labels are the library's
    assert np.array_equal(labels, shapeflow.run(SEGMENT, {"image": img}).labels)
    series = zipfile.ZipFile(io.BytesIO(client.download(job, "evolution_vtk.zip")))
    assert series.namelist()[0] == "evolution.pvd" and all(n.endswith(".vtp") for n in series.namelist()[1:])
    assert job in [j["id"] for j in client.jobs()]
    client.delete(job)
    with pytest.raises(shapeflow.JobError) as e:
        client.job(job)
    assert e.value.status == 404


def test_errors_and_cancel(service):
    client = shapeflow.Client(service)
    with pytest.raises(shapeflow.JobError) as e:
        client.submit({"problem": {"type": "curvature_flow", "gamma": -1, "lambda": 0}})
    assert e.value.status in (400, 422) and "problem.gamma" in e.value.detail
    long = {
        "problem": {"type": "curvature_flow", "gamma": 1.0, "lambda": 0.0},
        "initial": {"shape": "circle", "center": [0.0, 0.0], "radius": 1.0, "resolution": 1000},
        "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 10000000, "tolerance": 0},
    }
    job = client.submit(long)
    client.cancel(job)
    assert client.wait(job)["status"] in ("cancelled", "dismissed")
