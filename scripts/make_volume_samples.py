#!/usr/bin/env python3
"""Dev-only: writes the small volumes of tests/data that the readers are checked
against, with nibabel and tifffile (implementations of NIfTI and OME-TIFF / ImageJ
TIFF independent of ours). Usage: python3 scripts/make_volume_samples.py

- ramp_nifti1.nii, ramp_nifti2.nii.gz and ramp_nifti2_be.nii: one volume of 7×5×4
  voxels, value i + 10 j + 100 k at voxel (i, j, k), voxels 2 × 3 × 4 apart, turned
  a quarter turn about z and shifted (sform and qform both set, codes 1), as
  NIfTI-1, gzip NIfTI-2 (int16) and big-endian NIfTI-2 (whose header's default
  type stores the samples as float32). The reader must give the same grid and
  placement for all three.
- ome_stack.ome.tif: 4 slices of 5×6 uint8, value 10 z + x, OME-XML with
  PhysicalSizeX/Y 0.5 µm and PhysicalSizeZ 1500 nm (1.5 µm).
- ome_channels.ome.tif and imagej_channels.tif: 4 slices of 5×6 in 2 channels
  (the second 255 − v of the first; OME-XML SizeC 2, ImageJ hyperstack
  channels=2): without a channel chosen each must be refused, never
  read as 8 slices; with `problem.channel` the chosen channel is read.
- ome_series.ome.tif and imagej_series.tif: the same 4 slices at 3 time points,
  value 10 z + x + 60 t in channel 0 and 255 minus that in channel 1 (axes TZCYX):
  without a channel and a time point each must be refused; with both, that
  channel's 4 slices of that time point are read.
- series_nifti1.nii.gz: the ramp of ramp_nifti1.nii at 3 time points, plus
  1000 t at time point t (4D, int16): refused without `problem.time_point`, read
  at the one chosen.
"""
import pathlib

import nibabel as nib
import numpy as np
import tifffile

OUT = pathlib.Path(__file__).resolve().parent.parent / "tests/data"

i, j, k = np.meshgrid(np.arange(7), np.arange(5), np.arange(4), indexing="ij")
data = (i + 10 * j + 100 * k).astype(np.int16)
affine = np.array([[0.0, -3.0, 0.0, 10.0], [2.0, 0.0, 0.0, -20.0], [0.0, 0.0, 4.0, 30.0], [0, 0, 0, 1]])
for name, image in [
    ("ramp_nifti1.nii", nib.Nifti1Image(data, affine)),
    ("ramp_nifti2.nii.gz", nib.Nifti2Image(data, affine)),
    ("ramp_nifti2_be.nii", nib.Nifti2Image(data, affine, header=nib.Nifti2Header(endianness=">"))),
]:
    image.header.set_qform(affine, code=1)
    image.header.set_sform(affine, code=1)
    image.to_filename(OUT / name)
    back = nib.load(OUT / name)
    assert np.array_equal(back.get_fdata(), data) and np.allclose(back.affine, affine), name

z, y, x = np.meshgrid(np.arange(4), np.arange(5), np.arange(6), indexing="ij")
stack = (10 * z + x).astype(np.uint8)
tifffile.imwrite(OUT / "ome_stack.ome.tif", stack, ome=True, metadata={
    "axes": "ZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 1500.0, "PhysicalSizeZUnit": "nm"})
two = np.stack([stack, 255 - stack], axis=1)  # Z, C, Y, X
tifffile.imwrite(OUT / "ome_channels.ome.tif", two, ome=True, metadata={"axes": "ZCYX"})
tifffile.imwrite(OUT / "imagej_channels.tif", two, imagej=True, metadata={"axes": "ZCYX"})
series = np.stack([stack + 60 * t for t in range(3)])  # T, Z, Y, X
series = np.stack([series, 255 - series], axis=2)  # T, Z, C, Y, X
tifffile.imwrite(OUT / "ome_series.ome.tif", series, ome=True, metadata={"axes": "TZCYX"})
tifffile.imwrite(OUT / "imagej_series.tif", series, imagej=True, metadata={"axes": "TZCYX"})
frames = np.stack([data + 1000 * t for t in range(3)], axis=-1).astype(np.int16)
image = nib.Nifti1Image(frames, affine)
image.header.set_qform(affine, code=1)
image.header.set_sform(affine, code=1)
image.to_filename(OUT / "series_nifti1.nii.gz")
assert np.array_equal(nib.load(OUT / "series_nifti1.nii.gz").get_fdata()[..., 2], data + 2000)
for name in ["ome_stack.ome.tif", "ome_channels.ome.tif", "imagej_channels.tif", "ome_series.ome.tif",
             "imagej_series.tif"]:
    with tifffile.TiffFile(OUT / name) as t:
        print(name, len(t.pages), t.pages[0].description[:200].replace("\n", " "))
