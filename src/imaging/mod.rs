//! Images as sampled scalar fields: decoding (PNG, JPEG, TIFF; NRRD, NIfTI-1 and
//! multi-page TIFF volumes, slice stacks), Gaussian smoothing, the edge indicator `H = 1/(1 + |∇I|²)` of
//! geodesic active contours with a C² interpolant, and rasterization of shapes into
//! masks. Pure functions over bytes and arrays; nothing here touches files.
//!
//! Coordinates (docs/problems/segmentation.md): a grid of `n_x × n_y (× n_z)` samples lives in the
//! unit box, `L = max(n_x, n_y, n_z)`; sample `(i, j, k)` has its centre at
//! `((i+½)/L, (j+½)/L, (k+½)/L)`. 2D images are stored with their rows flipped
//! (`j = 0` is the bottom row of the picture), so that y points up.

mod background;
mod bspline;
pub mod contours;
mod contrast;
mod decode;
mod edge;
mod grid;
pub mod isosurface;
pub mod labels;
mod limits;
mod nrrd;
mod raster;
mod smooth;
mod threshold;
mod volumes;

pub use background::quadratic_background;
pub use contrast::{contrast_scale, noise_gradient};
pub use decode::{decode_image, decode_image_channel, decode_slices, decode_volume};
pub use edge::{EdgeField, EdgeSample};
pub use grid::{Grid, Placement, SampleKind};
pub use limits::ImageLimits;
pub use nrrd::{encode_nrrd_labels, encode_nrrd_mask, parse_nrrd};
pub use raster::{draw_overlay, rasterize_curve, rasterize_curve_window, rasterize_surface, rasterize_surface_window};
pub use smooth::gaussian_smooth;
pub use threshold::{
    background_spread, histogram_mode, noise_level, otsu, percentile, percentiles, smoothed_noise, smoothing_for_noise,
    Normalization, PERCENTILES,
};
pub use volumes::{
    decode_nifti, decode_tiff_stack, decode_tiff_stack_channel, encode_nifti_labels, encode_nifti_mask, is_nifti,
    is_tiff, isotropic, tiff_pages,
};

/// A bad or unsupported input file; `input` names it (the multipart part or file).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("input `{input}`: {message}")]
pub struct ImageError {
    pub input: String,
    pub message: String,
    /// The file is fine, but not the channel asked of it (or it needs one).
    pub channel: bool,
}

impl ImageError {
    pub fn new(input: &str, message: impl Into<String>) -> Self {
        ImageError { input: input.to_string(), message: message.into(), channel: false }
    }

    /// An error of the channel asked of the file `input`.
    pub fn channel(input: &str, message: impl Into<String>) -> Self {
        ImageError { channel: true, ..ImageError::new(input, message) }
    }
}
