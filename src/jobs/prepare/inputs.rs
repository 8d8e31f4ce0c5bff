//! The uploaded inputs a spec names as `"input:NAME"`: lookup and image decoding.

use crate::imaging::{
    decode_image_channel, decode_nifti, decode_slices, decode_tiff_stack_channel, decode_volume, is_nifti, is_tiff,
    tiff_pages, Grid, ImageError, ImageLimits,
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

/// Decode the image of a segmentation job: 2D raster, NRRD, NIfTI or TIFF volume,
/// or slice stack; `channel` as `problem.channel`.
pub(super) fn load_image(
    source: &ImageSource,
    channel: Option<u32>,
    inputs: &HashMap<String, Vec<u8>>,
) -> Result<Grid, SpecError> {
    let limits = ImageLimits::default();
    let channel = channel.map(|c| c as usize);
    let field =
        |e: ImageError| SpecError::new(if e.channel { "problem.channel" } else { "problem.image" }, e.to_string());
    match source {
        ImageSource::One(name) => {
            let (key, bytes) = input("problem.image", name, inputs)?;
            // NRRD and NIfTI volumes: a broken file is named first, then the channel
            let single = |decoded: Result<Grid, ImageError>| {
                decoded.and_then(|grid| match channel {
                    Some(c) if c > 0 => {
                        Err(ImageError::channel(key, format!("is a volume of one channel; channel {c} was asked for")))
                    }
                    _ => Ok(grid),
                })
            };
            let grid = if bytes.starts_with(b"NRRD") {
                single(decode_volume(key, bytes, &limits))
            } else if is_nifti(bytes) {
                single(decode_nifti(key, bytes, &limits))
            } else if is_tiff(bytes) && tiff_pages(bytes, 2) > 1 {
                decode_tiff_stack_channel(key, bytes, &limits, channel)
            } else {
                decode_image_channel(key, bytes, &limits, channel)
            };
            grid.map_err(field)
        }
        ImageSource::Slices(names) => {
            let slices = names
                .iter()
                .enumerate()
                .map(|(k, n)| input(&format!("problem.image[{k}]"), n, inputs))
                .collect::<Result<Vec<_>, _>>()?;
            decode_slices(&slices, &limits, channel).map_err(field)
        }
    }
}
