#!/usr/bin/env python3
"""Dev-only: writes tests/data/ramp_nifti1.nii and tests/data/ramp_nifti2.nii.gz
(and a big-endian NIfTI-2, ramp_nifti2_be.nii, whose header's default type stores
the samples as float32) with nibabel, an implementation of
NIfTI independent of ours: one int16 volume of 7×5×4 voxels, value
i + 10 j + 100 k at voxel (i, j, k), voxels 2 × 3 × 4 apart, turned a quarter
turn about z and shifted (sform and qform both set, codes 1). The reader must give
the same grid and placement for all three. Usage: python3 scripts/make_nifti_samples.py
"""
import pathlib

import nibabel as nib
import numpy as np

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
    print(name, back.header.endianness, back.header["sizeof_hdr"], back.header["vox_offset"])
