//! NIfTI-1, NIfTI-2 and multi-page TIFF volumes (3D segmentation inputs; OME and
//! ImageJ descriptions, a channel and a time point chosen), small limits.
#![no_main]
use libfuzzer_sys::fuzz_target;
use shapeflow::imaging::{decode_nifti, decode_nifti_time_point, decode_tiff_stack, decode_tiff_stack_plane, ImageLimits, Plane};

fuzz_target!(|data: &[u8]| {
    let limits = ImageLimits { max_pixels: 1 << 16, max_voxels: 1 << 18, min_side: 2 };
    let _ = decode_nifti("in", data, &limits);
    let _ = decode_tiff_stack("in", data, &limits);
    let _ = decode_tiff_stack_plane("in", data, &limits, Plane { channel: Some(1), time_point: Some(1) });
    let _ = decode_nifti_time_point("in", data, &limits, Some(1));
});
