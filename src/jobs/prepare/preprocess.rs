//! A segmentation's image as the functional and the initial shape see it: the
//! percentile normalization, the noise level, the smoothing, the polarity, the
//! illumination removed and the thresholds, each automatic unless the spec gives
//! it ([`preprocess`]).

use super::background::{border_polarity, flatten, minus};
use super::image_shapes::Levels;
use crate::imaging::{
    background_spread, gaussian_smooth, histogram_mode, noise_level, otsu, smoothed_noise, smoothing_for_noise, Grid,
    Normalization, PERCENTILES,
};
use crate::jobs::spec::bounds::{LEVEL, PERCENTILE, SIGMA};
use crate::jobs::spec::{BackgroundModel, ImageSource, Polarity, SegmentationModel, SegmentationSpec, SpecError};

/// Dim objects are detected this many times the background's fluctuation at the
/// smoothing scale away from the background level (for Gaussian fluctuations a
/// false detection per independent sample has a probability of about 1e-9).
const DIM_OBJECT_SNR: f64 = 6.0;

/// The image as the segmentation sees it, and the automatic choices made on it.
pub(super) struct Preprocessed {
    pub(super) percentiles: [f64; 2],
    pub(super) normalization: Normalization,
    pub(super) noise: f64,
    pub(super) sigma: f64,
    pub(super) data_sigma: f64,
    pub(super) background: BackgroundModel,
    pub(super) illumination: f64,
    /// Normalized, corrected, smoothed by `sigma` (threshold, initial shape).
    pub(super) smoothed: Grid,
    /// Normalized, corrected, smoothed by `data_sigma` (the Chan–Vese fit).
    pub(super) data: Grid,
    pub(super) levels: Levels,
}

/// The error of an image with nothing to segment.
fn constant_image(source: &ImageSource) -> SpecError {
    let names = match source {
        ImageSource::One(s) => s.clone(),
        ImageSource::Slices(v) => v.join(", "),
    };
    SpecError::new("problem.image", format!("the image {names} is constant: there is nothing to segment"))
}

/// The error of an image that is not constant but that the smoothing by `sigma`
/// pixels made so (a `sigma` far above the image's size).
pub(super) fn smoothed_away(sigma: f64, grid: &Grid) -> SpecError {
    let sides = grid.dims[..grid.dimension].iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" × ");
    SpecError::new(
        "problem.sigma",
        format!("smoothing by {sigma} pixels leaves the image ({sides} samples) constant: give a smaller sigma"),
    )
}

/// Normalization, noise, smoothing, polarity, illumination and thresholds.
pub(super) fn preprocess(
    spec: &SegmentationSpec,
    grid: &Grid,
    model: SegmentationModel,
) -> Result<Preprocessed, SpecError> {
    let d = grid.dimension;
    let percentiles = spec.percentiles.unwrap_or([PERCENTILES.0, PERCENTILES.1]);
    PERCENTILE.check("problem.percentiles[0]", percentiles[0])?;
    PERCENTILE.check("problem.percentiles[1]", percentiles[1])?;
    if percentiles[0] >= percentiles[1] {
        return Err(SpecError::new("problem.percentiles", "the first must be below the second"));
    }
    let constant = || constant_image(&spec.image);
    let normalization = Normalization::of(grid, (percentiles[0], percentiles[1])).ok_or_else(constant)?;
    let unit = normalization.apply(grid);
    let noise = noise_level(&unit);
    let sigma = match spec.sigma {
        Some(s) => {
            if !(s.is_finite() && (SIGMA.min..=SIGMA.max).contains(&s)) {
                let (lo, hi) = (SIGMA.min, SIGMA.max);
                return Err(SpecError::new("problem.sigma", format!("must be between {lo} and {hi} pixels, got {s}")));
            }
            s
        }
        None if model == SegmentationModel::ChanVese => smoothing_for_noise(noise, d),
        // the edge indicator's own default, raised for noisy images
        None => smoothing_for_noise(noise, d).max(crate::jobs::spec::default_sigma(d)),
    };
    let smoothed = gaussian_smooth(&unit, sigma);
    // the image is not constant (it has a normalization): the smoothing made it so
    let first = otsu(&smoothed.values).ok_or_else(|| smoothed_away(sigma, grid))?;
    let polarity = spec.polarity.unwrap_or_else(|| border_polarity(&smoothed, first));
    let background = spec.background.unwrap_or(BackgroundModel::Quadratic);
    let offset = match background {
        BackgroundModel::Flat => None,
        BackgroundModel::Quadratic => flatten(&smoothed, first, polarity),
    };
    let illumination = offset.as_ref().map_or(0.0, |o| {
        let (lo, hi) = o.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), &v| (a.min(v), c.max(v)));
        hi - lo
    });
    // the Chan–Vese fit averages the noise over regions itself: it sees the image
    // smoothed by data_sigma only
    let data_sigma = match spec.data_sigma {
        Some(s) => SIGMA.check("problem.data_sigma", s)?,
        None => 0.0,
    };
    let data = gaussian_smooth(&unit, data_sigma);
    let (smoothed, data) = match &offset {
        Some(o) => (minus(&smoothed, o), minus(&data, o)),
        None => (smoothed, data),
    };
    let threshold = match spec.threshold {
        Some(t) => LEVEL.check("problem.threshold", t)?,
        None => otsu(&smoothed.values).ok_or_else(|| match spec.sigma {
            Some(_) => smoothed_away(sigma, grid),
            None => SpecError::new(
                "problem.background",
                "the image is its quadratic background alone: there is nothing to segment (`flat` keeps it)",
            ),
        })?,
    };
    // dim objects: above the background level by DIM_OBJECT_SNR times the
    // background's fluctuation at the smoothing scale, the larger of the smoothed
    // white noise and the spread measured on the background (its texture) (a
    // threshold only where it is more permissive than the main one)
    let sign = if polarity == Polarity::Bright { 1.0 } else { -1.0 };
    let dim = match spec.dim_threshold {
        Some(t) => LEVEL.check("problem.dim_threshold", t)?,
        None => {
            let level = histogram_mode(&smoothed.values);
            let spread = background_spread(&smoothed.values, level, sign).max(smoothed_noise(noise, sigma, d));
            (level + sign * DIM_OBJECT_SNR * spread).clamp(0.0, 1.0)
        }
    };
    let dim = (sign * (threshold - dim) > 0.0).then_some(dim);
    let levels = Levels { main: threshold, dim, sign };
    Ok(Preprocessed {
        percentiles,
        normalization,
        noise,
        sigma,
        data_sigma,
        background,
        illumination,
        smoothed,
        data,
        levels,
    })
}
