//! The uploaded inputs a spec names as `"input:NAME"`: lookup and image decoding.

use crate::imaging::{
    decode_image_channel, decode_nifti_time_point, decode_slices, decode_tiff_stack_plane, decode_volume, is_nifti,
    is_tiff, tiff_pages, Grid, ImageError, ImageLimits, Plane, Subject,
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
/// or slice stack; of it, the channel and time point of `plane`
/// (`problem.channel`, `problem.time_point`).
pub(super) fn load_image(
    source: &ImageSource,
    plane: Plane,
    inputs: &HashMap<String, Vec<u8>>,
) -> Result<Grid, SpecError> {
    let limits = ImageLimits::default();
    let field = |e: ImageError| {
        let name = match e.subject {
            Subject::File => "problem.image",
            Subject::Channel => "problem.channel",
            Subject::TimePoint => "problem.time_point",
        };
        SpecError::new(name, e.to_string())
    };
    // a file of one time point: a broken file is named first, then the time point
    let one_time_point = |key: &str, decoded: Result<Grid, ImageError>, what: &str| {
        decoded.and_then(|grid| match plane.time_point {
            Some(t) if t > 0 => Err(ImageError::time_point(key, format!("{what}; time point {t} was asked for"))),
            _ => Ok(grid),
        })
    };
    match source {
        ImageSource::One(name) => {
            let (key, bytes) = input("problem.image", name, inputs)?;
            // NRRD and NIfTI volumes: a broken file is named first, then the channel
            let one_channel = |decoded: Result<Grid, ImageError>| {
                decoded.and_then(|grid| match plane.channel {
                    Some(c) if c > 0 => {
                        Err(ImageError::channel(key, format!("is a volume of one channel; channel {c} was asked for")))
                    }
                    _ => Ok(grid),
                })
            };
            let grid = if bytes.starts_with(b"NRRD") {
                let volume = one_channel(decode_volume(key, bytes, &limits));
                one_time_point(key, volume, "is a volume of one time point")
            } else if is_nifti(bytes) {
                one_channel(decode_nifti_time_point(key, bytes, &limits, plane.time_point))
            } else if is_tiff(bytes) && tiff_pages(bytes, 2) > 1 {
                decode_tiff_stack_plane(key, bytes, &limits, plane)
            } else {
                let mut image = decode_image_channel(key, bytes, &limits, plane.channel);
                if let (Err(first), true) = (&image, is_tiff(bytes)) {
                    // a TIFF of one page the 2D reader does not take (float samples)
                    image = decode_tiff_stack_plane(key, bytes, &limits, plane).map_err(|_| first.clone());
                }
                one_time_point(key, image, "is an image of one time point")
            };
            grid.map_err(field)
        }
        ImageSource::Slices(names) => {
            let slices = names
                .iter()
                .enumerate()
                .map(|(k, n)| input(&format!("problem.image[{k}]"), n, inputs))
                .collect::<Result<Vec<_>, _>>()?;
            let volume = decode_slices(&slices, &limits, plane.channel);
            let first = slices.first().map_or("(slices)", |s| s.0);
            one_time_point(first, volume, "is a stack of slices of one time point").map_err(field)
        }
    }
}
