"""The files a run writes, read by the tools their users have: PyVista (VTK's own
readers), tifffile and roifile."""

import json

import numpy as np
import pytest
import pyvista as pv
import roifile
import skimage.measure
import tifffile
from skimage.draw import polygon2mask

import shapeflow
from conftest import discs_image


def test_pvd_has_every_checkpoint_and_ends_at_shape_json(workdir):
    spec = {
        "problem": {"type": "surface_diffusion", "gamma": 1.0},
        "initial": {"shape": "ellipse", "center": [0.1, -0.2], "semi_axes": [1.0, 0.5], "resolution": 96},
        "flow": {"scalar_product": "h_minus_1", "tau": 1e-4, "end_time": 0.02, "max_iterations": 10000, "tolerance": 0},
        "output": {"checkpoint_every": 40},
    }
    seen = []
    r = shapeflow.run(spec, progress=seen.append)
    r.save(workdir)
    reader = pv.get_reader(str(workdir / "evolution.pvd"))
    times = np.array(reader.time_values)
    assert len(times) == len(seen) and np.allclose(times, [p["time"] for p in seen])
    reader.set_active_time_value(times[-1])
    last = reader.read()[0]
    shape = json.loads((workdir / "shape.json").read_text())
    # shape.json lists each closed curve's vertices in order
    points = np.vstack([np.asarray(c["vertices"], float) for c in shape["components"]])
    order = lambda p: p[np.lexsort(p.T[::-1])]
    assert np.allclose(order(last.points[:, :2]), order(points)) and np.all(last.points[:, 2] == 0)
    assert last.n_lines == len(points)
    for field in ("curvature", "normal_velocity"):
        assert last.point_data[field].shape == (len(points),)
    # the curvature of an ellipse lies between b/a² and a/b²
    k = np.abs(last.point_data["curvature"])
    assert 0.4 < k.min() and k.max() < 4.2
    single = pv.read(str(workdir / "shape.vtp"))
    assert np.allclose(single.points, last.points)
    # the area surface diffusion keeps, measured on the file
    x, y = r.vertices[:, 0], r.vertices[:, 1]
    seg = r.segments
    area = 0.5 * np.sum(x[seg[:, 0]] * y[seg[:, 1]] - x[seg[:, 1]] * y[seg[:, 0]])
    assert abs(abs(area) - np.pi * 0.5) < 2e-3


def test_anisotropic_volume_lies_in_its_physical_extent(workdir):
    n = (24, 48, 40)  # (z, y, x)
    spacing = (2.0, 0.5, 1.0)
    z, y, x = np.meshgrid(*[np.arange(k) * s for k, s in zip(n, spacing)], indexing="ij")
    centre, radius = (22.0, 12.0, 20.0), 8.0
    vol = np.where((z - centre[0]) ** 2 + (y - centre[1]) ** 2 + (x - centre[2]) ** 2 <= radius**2, 200, 30)
    r = shapeflow.run(
        {"problem": {"type": "segmentation", "image": "input:volume"}, "flow": {"max_iterations": 200}},
        {"volume": (vol.astype(np.uint8), spacing)},
    )
    v = r.vertices
    assert v.shape[1] == 3 and r.triangles.shape[1] == 3
    extent = [(k - 1) * s for k, s in zip(n, spacing)]
    assert np.all(v >= -1e-9) and np.all(v <= np.array(extent) + 1e-9)
    # the ball found where it is, in (z, y, x) physical units
    assert np.allclose(v.mean(axis=0), centre, atol=0.6)
    assert abs(np.linalg.norm(v - centre, axis=1).mean() - radius) < 0.7
    r.save(workdir)
    mesh = pv.read(str(workdir / "shape.vtp"))
    assert np.allclose(mesh.points, v[:, ::-1])  # VTK's (x, y, z)
    # the labels on the input's own voxels, where the ball is
    assert r.labels.shape == vol.shape and r.mask.shape == vol.shape
    assert dice(r.labels > 0, vol > 100) > 0.9
    assert np.array_equal(r.mask, r.labels > 0)
    ome = tifffile.TiffFile(workdir / "labels.ome.tif")
    assert ome.is_ome and ome.series[0].axes == "ZYX"
    assert np.array_equal(ome.asarray(), r.labels)
    pixels = ome_pixels(ome)
    assert [float(pixels.get(f"PhysicalSize{a}")) for a in "ZYX"] == list(spacing)
    props = skimage.measure.regionprops_table(r.labels, properties=("label", "area", "centroid", "bbox"))
    for name, column in props.items():
        assert np.allclose(r.objects[name], column), name


def test_tiff_stack_labels_are_in_the_files_order(workdir):
    # a ball near the first rows and planes of an anisotropic ImageJ stack: any
    # flip or resampling left in the labels moves it
    n, spacing = (20, 44, 36), (1.5, 0.75, 0.75)  # (z, y, x)
    z, y, x = np.meshgrid(*[np.arange(k) * s for k, s in zip(n, spacing)], indexing="ij")
    centre, radius = (11.0, 10.0, 15.0), 6.0
    vol = np.where((z - centre[0]) ** 2 + (y - centre[1]) ** 2 + (x - centre[2]) ** 2 <= radius**2, 220, 25)
    path = workdir / "stack.tif"
    tifffile.imwrite(path, vol.astype(np.uint8), imagej=True, resolution=(1 / spacing[2], 1 / spacing[1]),
                     metadata={"spacing": spacing[0], "unit": "um", "axes": "ZYX"})
    r = shapeflow.run({"problem": {"type": "segmentation", "image": "input:volume"}, "flow": {"max_iterations": 200}},
                      {"volume": path})
    assert r.labels.shape == vol.shape
    assert dice(r.labels > 0, vol > 100) > 0.9
    # the surface over the array as tifffile reads it, in (z, y, x) physical units
    v = r.vertices
    assert np.allclose(v.mean(axis=0), centre, atol=0.6)
    assert abs(np.linalg.norm(v - centre, axis=1).mean() - radius) < 0.6
    r.save(workdir / "out")
    assert np.array_equal(tifffile.imread(workdir / "out/labels.ome.tif"), r.labels)


def dice(a, b):
    return 2 * (a & b).sum() / (a.sum() + b.sum())


def ome_pixels(ome):
    import xml.etree.ElementTree as ET

    root = ET.fromstring(ome.ome_metadata)
    return next(e for e in root.iter() if e.tag.endswith("Pixels"))


def test_tiff_and_rois_agree_with_the_labels(workdir):
    r = shapeflow.run(
        {"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"max_iterations": 300}},
        {"image": discs_image(7, count=4)},
    )
    r.save(workdir)
    assert np.array_equal(tifffile.imread(workdir / "labels.tif"), r.labels)
    rois = roifile.roiread(workdir / "rois.zip")
    assert sorted({int(roi.name.split("-")[0]) for roi in rois}) == list(range(1, r.labels.max() + 1))
    for roi in rois:
        xy = roi.coordinates()
        label = int(roi.name.split("-")[0])
        # ImageJ's pixel (c, r) covers [c, c + 1) × [r, r + 1): its centre is at (c + ½, r + ½)
        inside = polygon2mask(r.labels.shape, np.c_[xy[:, 1] - 0.5, xy[:, 0] - 0.5])
        obj = r.labels == label
        assert (inside & obj).sum() / (inside | obj).sum() > 0.97, roi.name


@pytest.mark.parametrize("dtype", [np.uint16, np.float32, np.float64, bool])
def test_array_types(dtype):
    img = discs_image(4, count=3).astype(np.float64) / 255.0
    if dtype is np.uint16:
        a = (img * 65535).astype(np.uint16)
    elif dtype is bool:
        a = img > 0.45
    else:
        a = img.astype(dtype)
    r = shapeflow.run({"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"max_iterations": 300}},
                      {"image": a})
    assert r.labels.max() == 3, dtype
