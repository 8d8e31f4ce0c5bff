//! `problem` of type `segmentation`: the image, the model and the automatic
//! choices a user may override, with their documented defaults.

use super::bounds::{CHANNEL, LEVEL, MIN_SEPARATION, MIN_SIZE, PERCENTILE, SIGMA, TIME_POINT, WEIGHT};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// One input file, or a stack of 2D slices.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum ImageSource {
    One(#[schemars(regex(pattern = "^input:"))] String),
    Slices(#[schemars(length(min = 1), inner(regex(pattern = "^input:")))] Vec<String>),
}

/// `problem` of `segmentation` (without its `type`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SegmentationSpec {
    /// `"input:NAME"` (PNG/JPEG/TIFF → 2D, NRRD → 3D) or a list of them (a stack
    /// of 2D slices → 3D, first slice at the bottom).
    pub image: ImageSource,
    /// (Addition) the channel to segment, from 0: that component of a colour
    /// image (red, green, blue, alpha; or gray, alpha) instead of its luminance,
    /// or that channel of a TIFF stack of several (OME-TIFF, ImageJ hyperstack);
    /// NRRD and NIfTI volumes have channel 0 only. Default: the luminance, and a
    /// stack of several channels is refused.
    #[serde(default)]
    #[schemars(range(min = CHANNEL.min, max = CHANNEL.max))]
    pub channel: Option<u32>,
    /// (Addition) the time point to segment, from 0, of a time series: a 4D
    /// NIfTI file, or a TIFF stack of several time points (OME-TIFF, ImageJ
    /// hyperstack); a time point of one page is a 2D image. Other inputs have
    /// time point 0 only. Default: none, and a series of several time points is
    /// refused.
    #[serde(default)]
    #[schemars(range(min = TIME_POINT.min, max = TIME_POINT.max))]
    pub time_point: Option<u32>,
    /// Gaussian smoothing in pixels of the image the threshold and the edge
    /// indicator see; default from the image's noise level (1–4 pixels; at least
    /// 1.5 for the geodesic model).
    #[serde(default)]
    #[schemars(range(min = SIGMA.min, max = SIGMA.max))]
    pub sigma: Option<f64>,
    /// (Addition, Chan–Vese) Gaussian smoothing in pixels of the image the fit
    /// sees; default 0 (the fit averages the noise over regions).
    #[serde(default)]
    #[schemars(range(min = SIGMA.min, max = SIGMA.max))]
    pub data_sigma: Option<f64>,
    /// Weight of the region term (balloon force); default `0.3 L` (2D) or `0.15 L`
    /// (3D), `L` the number of samples along the image's longest side.
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub lambda: Option<f64>,
    /// (Addition) once the flow has converged with `lambda`, it continues with
    /// this weight until it converges again (default 0 in 2D, `lambda` in 3D).
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub lambda_final: Option<f64>,
    /// (Addition) the results show the contour moved onto the image's edges to
    /// sub-pixel accuracy; default true.
    #[serde(default)]
    pub edge_refinement: Option<bool>,
    /// (Addition, geodesic model) contrast scale `k` of the edge indicator
    /// `H = 1/(1 + |∇I_σ|²/k²)`, the image mapped to [0, 100]; default from the
    /// image's gradients: `max(p99, max/4)/20` of `|∇I_σ|`, but at least twice the
    /// noise's gradient (about 1 on the paper's images, lower where the objects
    /// are dim and the noise is low).
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0), range(max = WEIGHT.max))]
    pub edge_contrast: Option<f64>,
    /// Threshold ε of the Newton weight β (paper §4.2.1); default `0.1 L²`.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub epsilon: Option<f64>,
    /// (Addition) the functional: `chan_vese` (region-based, one mean intensity
    /// per object; the default), `geodesic` (geodesic active contours, the
    /// paper's) or `both` (their sum).
    #[serde(default)]
    pub model: Option<SegmentationModel>,
    /// (Addition, Chan–Vese) weight of the contour's length, in intensity² ×
    /// pixels (the image normalized to [0, 1]); default `max(0.05, noise/2)` with
    /// the noise's standard deviation on that scale, halved in 3D (a surface's
    /// mean curvature is the sum of two principal curvatures, so that objects of
    /// one radius are pulled in alike).
    #[serde(default)]
    #[schemars(range(min = WEIGHT.min, max = WEIGHT.max))]
    pub mu: Option<f64>,
    /// (Addition, Chan–Vese) weight of the fit inside the objects; default 1.
    #[serde(default)]
    #[schemars(range(min = WEIGHT.min, max = WEIGHT.max))]
    pub lambda_in: Option<f64>,
    /// (Addition, Chan–Vese) weight of the fit outside the objects; default 1.
    #[serde(default)]
    #[schemars(range(min = WEIGHT.min, max = WEIGHT.max))]
    pub lambda_out: Option<f64>,
    /// (Addition, Chan–Vese) `per_object` (default: each object has its own mean
    /// intensity, so that dim and bright objects are both fitted) or `global` (one
    /// mean for all objects: the two-phase model).
    #[serde(default)]
    pub means: Option<MeansKind>,
    /// (Addition) intensity normalization: the percentiles of the image mapped to
    /// 0 and 1 (values beyond are clipped); default [0.5, 99.5].
    #[serde(default)]
    #[schemars(extend("items" = {"type": "number", "format": "double", "minimum": PERCENTILE.min, "maximum": PERCENTILE.max}))]
    pub percentiles: Option<[f64; 2]>,
    /// (Addition) the background model removed before thresholding and fitting:
    /// `quadratic` (default: a quadratic illumination fitted to the background) or
    /// `flat` (none).
    #[serde(default)]
    pub background: Option<BackgroundModel>,
    /// (Addition) whether the objects are `bright` or `dark`; default: the class
    /// of the threshold that covers less of the image's border.
    #[serde(default)]
    pub polarity: Option<Polarity>,
    /// (Addition) the threshold of the automatic initial shape on the normalized
    /// scale [0, 1]; default Otsu's.
    #[serde(default)]
    #[schemars(range(min = LEVEL.min, max = LEVEL.max))]
    pub threshold: Option<f64>,
    /// (Addition) the threshold (normalized scale) at which dim objects that the
    /// main threshold misses entirely are found; default: the background level
    /// (the histogram's mode) plus 6 times its fluctuation at the smoothing scale
    /// (the larger of the smoothed noise and the spread of the background's samples
    /// on the side away from the objects, which includes its texture).
    #[serde(default)]
    #[schemars(range(min = LEVEL.min, max = LEVEL.max))]
    pub dim_threshold: Option<f64>,
    /// (Addition) objects of fewer pixels (voxels) are dropped from the automatic
    /// initial shape, and holes of fewer are filled; default 16 (2D), 64 (3D).
    #[serde(default)]
    #[schemars(range(min = MIN_SIZE.min, max = MIN_SIZE.max))]
    pub min_size: Option<f64>,
    /// (Addition) the automatic initial shape splits objects that touch, where a
    /// neck is clearly narrower than both sides and the sides are of comparable
    /// size (a watershed of the distance transform); they then stay separate
    /// objects. With separate objects (Chan–Vese with per-object means, `merge`
    /// false), the converged contours (surfaces) are split by the same rule where
    /// the cut is a notch at both ends (all around its rim, in 3D), and the run
    /// goes on from the parts. Default true.
    #[serde(default)]
    pub split_touching: Option<bool>,
    /// (Addition) the least distance, in pixels (voxels), between the centres of
    /// two touching objects, for objects that touch without a clear neck (densely
    /// packed nuclei): the automatic initial shape then puts one object at every
    /// maximum of the thresholded image's distance transform that no higher one
    /// of its component comes nearer than this, whatever the neck between them (a
    /// marker watershed, as scikit-image's `peak_local_max(min_distance=…)` with
    /// `watershed`), instead of splitting at necks; after the flow converges,
    /// each object of the converged surfaces is split again by the same rule on
    /// its own distance transform (at necks where its maxima are closer), and the
    /// flow goes on with the parts (in 2D, on the nuclei image at 4, 6 and 8, it
    /// split no more objects than the initial shape had). About the radius of the
    /// smallest objects; an elongated object is cut where its ridge has a second
    /// maximum farther than this (a voxel ellipsoid of aspect 2.2 stayed one from
    /// its smaller radius on). Default: none (split at necks). With
    /// `split_touching` false it is not used.
    #[serde(default)]
    #[schemars(range(min = MIN_SEPARATION.min, max = MIN_SEPARATION.max))]
    pub min_separation: Option<f64>,
    /// (Addition, Chan–Vese with per-object means) whether objects merge where
    /// their contours meet; default false: objects that start separate stay the
    /// objects they are (curves: a trial step that would make them overlap is
    /// shortened; surfaces: each keeps to its territory, the voxels nearer to it
    /// than to any other initial object).
    #[serde(default)]
    pub merge: Option<bool>,
}

/// `problem.model` of segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SegmentationModel {
    Geodesic,
    ChanVese,
    Both,
}

/// `problem.means` of Chan–Vese segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MeansKind {
    PerObject,
    Global,
}

/// `problem.background` of segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BackgroundModel {
    Flat,
    Quadratic,
}

/// `problem.polarity` of segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Polarity {
    Bright,
    Dark,
}

/// Prefix of the message of a malformed `problem.image` (see [`parse_spec`]).
pub(super) const IMAGE_MESSAGE: &str = "`image` must be \"input:NAME\" or a list of them";

impl<'de> Deserialize<'de> for ImageSource {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(s) => Ok(ImageSource::One(s)),
            serde_json::Value::Array(items) if !items.is_empty() => items
                .into_iter()
                .map(|v| match v {
                    serde_json::Value::String(s) => Ok(s),
                    other => Err(serde::de::Error::custom(format!("{IMAGE_MESSAGE}, found {other} in the list"))),
                })
                .collect::<Result<_, _>>()
                .map(ImageSource::Slices),
            other => Err(serde::de::Error::custom(format!("{IMAGE_MESSAGE}, got {other}"))),
        }
    }
}

/// Default `problem.sigma` (pixels), 1.5 in 2D and 3D. The smoothing moves the
/// minimizer inside the edges by `O(σ²κ)`, which the results' edge refinement
/// (`problem.edge_refinement`) removes; more smoothing means a quieter `H` and fewer
/// iterations (two noisy balls in 64³: 31 iterations at σ = 1, 18 at σ = 1.5).
pub fn default_sigma(_d: usize) -> f64 {
    1.5
}
/// Default `problem.lambda` of segmentation for an image of `L` samples along its
/// longest side, in dimension `d`: `0.3 L` (2D) and `0.15 L` (3D). The paper's
/// λ = 30 on 100×100 images is 0.3 per pixel; keeping λ/L fixed makes the balance
/// of balloon force, edge attraction and pixel noise the same at every resolution.
/// The balloon force shifts the contour inwards by about `(λ + κ) s² / 2L` pixels
/// (`s²` the variance of the edge profile), and `κ` of a surface is twice that of a
/// curve of the same radius: volumes get the smaller factor.
pub fn default_lambda(d: usize, l: f64) -> f64 {
    if d == 2 {
        0.3 * l
    } else {
        0.15 * l
    }
}
/// Default `problem.lambda_final` of segmentation: 0 for 2D images, `lambda` (no
/// second stage) for volumes. The balloon force that carries the contour to the
/// object's edges also holds it about `λ s²/2L` pixels inside them (see
/// [`default_lambda`]): half a pixel with the 2D defaults, which costs 1 % of Dice
/// on a 128² image. Started at the edges, the flow without it moves out to where
/// `κH + ∂_ν H = 0` in a few iterations. In 3D the shift is a quarter as large
/// and the second stage measured to gain 0.1 % of Dice for 60 % more time.
pub fn default_lambda_final(d: usize, lambda: f64) -> f64 {
    if d == 2 {
        0.0
    } else {
        lambda
    }
}
/// Default `problem.epsilon` of segmentation: `0.1 L²`, the paper's ε = 0.1 per
/// squared pixel (1e3 on its 100×100 images in the unit box).
pub fn default_beta_epsilon(l: f64) -> f64 {
    0.1 * l * l
}
