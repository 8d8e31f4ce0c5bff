//! 2D image uploads (segmentation): PNG, JPEG and TIFF, decoded by the image crate
//! after our own size check.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let limits = shapeflow::imaging::ImageLimits::default();
    let _ = shapeflow::imaging::decode_image("in", data, &limits);
    let _ = shapeflow::imaging::decode_image_channel("in", data, &limits, Some(2));
});
