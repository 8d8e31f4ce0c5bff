//! The sizes of images and volumes that the decoders accept (defaults from
//! [`crate::limits`]).

use super::ImageError;
use crate::limits::{MAX_PIXELS, MAX_VOXELS, MIN_SIDE};

/// Size limits for decoded inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageLimits {
    /// Largest number of pixels of a 2D image.
    pub max_pixels: usize,
    /// Largest number of voxels of a 3D volume.
    pub max_voxels: usize,
    /// Smallest number of samples along any axis.
    pub min_side: usize,
}

impl Default for ImageLimits {
    fn default() -> Self {
        ImageLimits { max_pixels: MAX_PIXELS, max_voxels: MAX_VOXELS, min_side: MIN_SIDE }
    }
}

impl ImageLimits {
    pub(crate) fn check(&self, input: &str, dims: &[usize]) -> Result<(), ImageError> {
        let shape = dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("×");
        if let Some(d) = dims.iter().find(|&&d| d < self.min_side) {
            return Err(ImageError::new(
                input,
                format!("is {shape}: every side needs at least {} samples, one has {d}", self.min_side),
            ));
        }
        let total = dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d)).unwrap_or(usize::MAX);
        let limit = if dims.len() == 2 { self.max_pixels } else { self.max_voxels };
        if total > limit {
            return Err(ImageError::new(input, format!("is {shape} = {total} samples, more than the limit {limit}")));
        }
        Ok(())
    }
}
