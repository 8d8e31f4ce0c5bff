//! Images as sampled scalar fields: decoding (PNG, JPEG, TIFF; NRRD, NIfTI and
//! multi-page TIFF volumes, one channel and time point of them, slice stacks), Gaussian smoothing, the edge indicator `H = 1/(1 + |∇I|²)` of
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
pub mod signed_distance;
mod smooth;
mod threshold;
mod volumes;

pub use background::quadratic_background;
pub use contrast::{contrast_scale, noise_gradient};
pub use decode::{decode_image, decode_image_channel, decode_slices, decode_volume};
pub use edge::{EdgeField, EdgeSample};
pub use grid::{ArrayLayout, Grid, Placement, SampleKind};
pub use limits::ImageLimits;
pub use nrrd::{encode_nrrd_labels, encode_nrrd_mask, parse_nrrd};
pub use raster::{draw_overlay, rasterize_curve, rasterize_curve_window, rasterize_surface, rasterize_surface_window};
pub use smooth::gaussian_smooth;
pub use threshold::{
    background_spread, histogram_mode, noise_level, otsu, percentile, percentiles, smoothed_noise, smoothing_for_noise,
    Normalization, PERCENTILES,
};
pub use volumes::{
    decode_nifti, decode_nifti_time_point, decode_tiff_stack, decode_tiff_stack_plane, encode_nifti_labels,
    encode_nifti_mask, is_nifti, is_tiff, isotropic, tiff_pages,
};

/// The plane to read of a file that holds several channels or time points,
/// each 0-based. `None`: the file must hold only one (for the channel: or colour,
/// which is then taken to its luminance).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Plane {
    pub channel: Option<usize>,
    pub time_point: Option<usize>,
}

/// What an [`ImageError`] is about: the file, or the plane asked of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Subject {
    /// The file is broken or unsupported.
    #[default]
    File,
    /// The file is fine, but not the channel asked of it (or it needs one).
    Channel,
    /// The file is fine, but not the time point asked of it (or it needs one).
    TimePoint,
}

/// A bad or unsupported input file; `input` names it (the multipart part or file).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("input `{input}`: {message}")]
pub struct ImageError {
    pub input: String,
    pub message: String,
    pub subject: Subject,
}

impl ImageError {
    pub fn new(input: &str, message: impl Into<String>) -> Self {
        ImageError { input: input.to_string(), message: message.into(), subject: Subject::File }
    }

    /// An error of the channel asked of the file `input`.
    pub fn channel(input: &str, message: impl Into<String>) -> Self {
        ImageError { subject: Subject::Channel, ..ImageError::new(input, message) }
    }

    /// An error of the time point asked of the file `input`.
    pub fn time_point(input: &str, message: impl Into<String>) -> Self {
        ImageError { subject: Subject::TimePoint, ..ImageError::new(input, message) }
    }

    /// An error of `subject`.
    pub fn about(subject: Subject, input: &str, message: impl Into<String>) -> Self {
        ImageError { subject, ..ImageError::new(input, message) }
    }
}
