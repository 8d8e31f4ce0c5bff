//! The uploaded inputs a spec names as `"input:NAME"`: lookup and image decoding.

use crate::imaging::{
    decode_image, decode_nifti, decode_slices, decode_tiff_stack, decode_volume, is_nifti, is_tiff, tiff_pages, Grid,
    ImageLimits,
};
use crate::jobs::spec::{ImageSource, SpecError};
use std::collections::HashMap;

pub(super) fn input<'a>(
    field: &str,
    name: &str,
    inputs: &'a HashMap<String, Vec<u8>>,
) -> Result<(&'a str, &'a [u8]), SpecError> {
    let key = name
        .strip_prefix("input:")
        .ok_or_else(|| SpecError::new(field, format!("must name an uploaded input as \"input:NAME\", got {name:?}")))?;
    inputs
        .get_key_value(key)
        .map(|(k, v)| (k.as_str(), v.as_slice()))
        .ok_or_else(|| SpecError::new(field, format!("no input named {key:?} was supplied")))
}

/// Decode the image of a segmentation job: 2D raster, NRRD volume or slice stack.
pub(super) fn load_image(source: &ImageSource, inputs: &HashMap<String, Vec<u8>>) -> Result<Grid, SpecError> {
    let limits = ImageLimits::default();
    match source {
        ImageSource::One(name) => {
            let (key, bytes) = input("problem.image", name, inputs)?;
            let grid = if bytes.starts_with(b"NRRD") {
                decode_volume(key, bytes, &limits)
            } else if is_nifti(bytes) {
                decode_nifti(key, bytes, &limits)
            } else if is_tiff(bytes) && tiff_pages(bytes, 2) > 1 {
                decode_tiff_stack(key, bytes, &limits)
            } else {
                decode_image(key, bytes, &limits)
            };
            grid.map_err(|e| SpecError::new("problem.image", e.to_string()))
        }
        ImageSource::Slices(names) => {
            let slices = names
                .iter()
                .enumerate()
                .map(|(k, n)| input(&format!("problem.image[{k}]"), n, inputs))
                .collect::<Result<Vec<_>, _>>()?;
            decode_slices(&slices, &limits).map_err(|e| SpecError::new("problem.image", e.to_string()))
        }
    }
}
