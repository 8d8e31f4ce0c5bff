//! 2D image uploads (segmentation): PNG, JPEG and TIFF, decoded by the image crate
//! after our own size check.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = shapeflow::imaging::decode_image("in", data, &shapeflow::imaging::ImageLimits::default());
});
