//! NRRD volumes (3D segmentation inputs).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = shapeflow::imaging::parse_nrrd("in", data, &shapeflow::imaging::ImageLimits::default());
});
